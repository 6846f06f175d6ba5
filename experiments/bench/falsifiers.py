#!/usr/bin/env python3
"""The falsifier bench: paracosm's strategies beside PSY-TaLiRo's optimisers, VerifAI's
samplers and scipy's global optimisers, on the same objectives and budgets, many seeds each.

    python3 experiments/bench/falsifiers.py [--seeds 30] [--cap 300] [--jobs 2]

Every tool drives the same callable, a point of [0, 1]^d to its robustness (`<= 0`: falsified):
paracosm's scenarios through `paracosm.Scenario(name).robustness` (one closed-loop test per
call) and two analytic functions (falsifier_runners/common.py). A search stops right after
its first falsifying evaluation or at `--cap` evaluations (then "not found", counted as
cap + 1 in the medians). Reported per tool and objective: the falsification rate, the median
and quartiles of the evaluations to the first failure, and the process CPU seconds per
evaluation (the tool's own work plus the simulation).

PSY-TaLiRo and VerifAI cannot share one environment (their pins conflict), so each family of
tools runs in its own virtual environment under target/bench-venvs/, made on first use from the
pinned requirements-falsifiers-*.txt beside this script plus the paracosm wheel (build it first:
`maturin build --release -m python/Cargo.toml --out target/wheels`, as scripts/test does).
Outputs: experiments/out/bench/falsifiers/{trials.csv,table.md,cpu.md,first_failure.png}, and one file
per finished job in jobs/ (a rerun with the same settings reuses them; delete it to rerun).
"""

import argparse
import csv
import glob
import hashlib
import json
import os
import statistics
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent.parent
sys.path.insert(0, str(HERE / "falsifier_runners"))

FAMILIES = {
    # family: (requirements file, runner module)
    "paracosm-scipy": ("requirements-falsifiers-scipy.txt", "paracosm_scipy"),
    "psy-taliro": ("requirements-falsifiers-taliro.txt", "taliro"),
    "verifai": ("requirements-falsifiers-verifai.txt", "verifai_runner"),
}


def worker(args):
    """Runs in a family's environment: every seed of one tool on one objective, one JSON line
    per trial on stdout."""
    import importlib

    from common import trial

    module = importlib.import_module(FAMILIES[args.family][1])
    run = module.runner(args.tool)
    for seed in range(args.seeds):
        print(json.dumps(trial(args.tool, run, args.objective, seed, args.cap)), flush=True)


def venv(family: str, wheel: str) -> Path:
    """The family's environment, made and filled on first use."""
    path = ROOT / "target" / "bench-venvs" / family
    python = path / "bin" / "python"
    stamp = path / "installed.txt"
    requirements = HERE / FAMILIES[family][0]
    # The wheel's digest, not its name: a rebuilt wheel keeps its file name.
    want = requirements.read_text() + wheel + hashlib.sha256(Path(wheel).read_bytes()).hexdigest()
    if not python.exists():
        subprocess.run([sys.executable, "-m", "venv", str(path)], check=True)
    if not stamp.exists() or stamp.read_text() != want:
        subprocess.run([str(python), "-m", "pip", "install", "-q", "-r", str(requirements)], check=True)
        subprocess.run([str(python), "-m", "pip", "install", "-q", "--force-reinstall", "--no-deps", wheel],
                       check=True)
        stamp.write_text(want)
    return python


def tools_of(family: str) -> list[str]:
    import importlib

    return importlib.import_module(FAMILIES[family][1]).TOOLS if family == "paracosm-scipy" else {
        "psy-taliro": lambda: [f"psy-taliro:{o}" for o in _listed("taliro", "OPTIMIZERS")],
        "verifai": lambda: [f"verifai:{s}" for s in _listed("verifai_runner", "SAMPLERS")],
    }[family]()


def _listed(module: str, name: str) -> list[str]:
    """A runner module's list of names, read without importing its tool (which lives in
    another environment)."""
    import ast

    tree = ast.parse((HERE / "falsifier_runners" / f"{module}.py").read_text())
    for node in tree.body:
        targets = node.targets if isinstance(node, ast.Assign) else [node.target] if isinstance(
            node, ast.AnnAssign) else []
        if any(getattr(t, "id", None) == name for t in targets):
            return ast.literal_eval(node.value)
    raise SystemExit(f"falsifiers.py: {module}.py has no {name}")


def quartiles(v):
    q = statistics.quantiles(v, n=4, method="inclusive") if len(v) > 1 else [v[0]] * 3
    return q[0], statistics.median(v), q[2]


def main():
    from common import OBJECTIVES

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seeds", type=int, default=30)
    ap.add_argument("--cap", type=int, default=300)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--objectives", default=",".join(OBJECTIVES))
    ap.add_argument("--families", default=",".join(FAMILIES))
    ap.add_argument("--wheel", help="the paracosm wheel (default: the newest in target/wheels)")
    ap.add_argument("--out", default=str(ROOT / "experiments/out/bench/falsifiers"))
    ap.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--family", help=argparse.SUPPRESS)
    ap.add_argument("--tool", help=argparse.SUPPRESS)
    ap.add_argument("--objective", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.worker:
        return worker(args)
    wheel = args.wheel or max(glob.glob(str(ROOT / "target/wheels/paracosm-*.whl")), key=os.path.getmtime,
                              default=None)
    if not wheel:
        sys.exit("falsifiers.py: no paracosm wheel in target/wheels: build it with maturin first")
    # The driver itself runs in the paracosm-scipy environment (it plots with matplotlib).
    main_python = venv("paracosm-scipy", wheel)
    if Path(sys.prefix).resolve() != main_python.parent.parent.resolve():
        os.execv(str(main_python), [str(main_python), str(Path(__file__).resolve()), *sys.argv[1:],
                                    "--wheel", wheel])
    objectives = args.objectives.split(",")
    jobs = []
    for family in args.families.split(","):
        python = venv(family, wheel)
        for tool in tools_of(family):
            for objective in objectives:
                jobs.append([str(python), str(Path(__file__).resolve()), "--worker", "--family", family,
                             "--tool", tool, "--objective", objective, "--seeds", str(args.seeds),
                             "--cap", str(args.cap)])

    out = Path(args.out)
    cache = out / "jobs"
    cache.mkdir(parents=True, exist_ok=True)

    def go(cmd):
        """One job's trials: from its cache file when a run with the same settings finished it
        (so an interrupted bench resumes), else by running it in its environment."""
        key = "_".join(c.replace("/", "-").replace(":", "-") for c in cmd[4:])
        done = cache / f"{key}.jsonl"
        if done.exists():
            return [json.loads(line) for line in done.read_text().splitlines()]
        env = dict(os.environ, PYTHONHASHSEED="0", OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1",
                   MKL_NUM_THREADS="1")
        p = subprocess.run(cmd, capture_output=True, text=True, env=env)
        if p.returncode != 0:
            print(f"falsifiers.py: {' '.join(cmd[3:])} failed; its trials are left out:\n"
                  f"{p.stderr[-2000:]}", file=sys.stderr)
            return []
        lines = [line for line in p.stdout.splitlines() if line.startswith("{")]
        done.write_text("".join(line + "\n" for line in lines))
        return [json.loads(line) for line in lines]

    with ThreadPoolExecutor(args.jobs) as pool:
        trials = [t for batch in pool.map(go, jobs) for t in batch]
    if not trials:
        sys.exit("falsifiers.py: no trial finished")
    with open(out / "trials.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(trials[0]))
        w.writeheader()
        w.writerows(trials)
    tools = list(dict.fromkeys(t["tool"] for t in trials))
    # Two tables: what was found (deterministic: the same for every run with these settings)
    # and the CPU it took (a measurement, which varies with the machine and its load).
    found_lines = ["| tool | " + " | ".join(f"{o}: found, median [quartiles]" for o in objectives) + " |",
                   "|---|" + "---|" * len(objectives)]
    cpu_lines = ["| tool | " + " | ".join(f"{o}: CPU ms/test" for o in objectives) + " |",
                 "|---|" + "---:|" * len(objectives)]
    for tool in tools:
        found_cells, cpu_cells = [], []
        for o in objectives:
            ts = [t for t in trials if t["tool"] == tool and t["objective"] == o]
            if not ts:
                found_cells.append("–")
                cpu_cells.append("–")
                continue
            firsts = [t["first_failure"] or t["cap"] + 1 for t in ts]
            found = sum(t["first_failure"] is not None for t in ts)
            q1, med, q3 = quartiles(firsts)
            ms = 1000 * sum(t["cpu_s"] for t in ts) / max(1, sum(t["evaluations"] for t in ts))
            found_cells.append(f"{found}/{len(ts)}, {med:g} [{q1:g}, {q3:g}]")
            cpu_cells.append(f"{ms:.2f}")
        found_lines.append(f"| {tool} | " + " | ".join(found_cells) + " |")
        cpu_lines.append(f"| {tool} | " + " | ".join(cpu_cells) + " |")
    table = "\n".join(found_lines)
    cpu = "\n".join(cpu_lines)
    (out / "table.md").write_text(table + "\n")
    (out / "cpu.md").write_text(cpu + "\n")
    print(table)
    print()
    print(cpu)
    plot(trials, tools, objectives, out / "first_failure.png")
    print(f"wrote {out}/trials.csv, table.md, cpu.md, first_failure.png")


def plot(trials, tools, objectives, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(objectives), figsize=(4.2 * len(objectives), 0.32 * len(tools) + 1.6),
                             sharey=True)
    for ax, o in zip(axes if len(objectives) > 1 else [axes], objectives):
        data = [[t["first_failure"] or t["cap"] + 1 for t in trials if t["tool"] == tool and t["objective"] == o]
                or [float("nan")] for tool in tools]
        ax.boxplot(data, orientation="horizontal", tick_labels=tools, showfliers=True)
        ax.set_xscale("log")
        ax.set_title(o, fontsize=10)
        ax.set_xlabel("evaluations to the first failure")
    fig.tight_layout()
    fig.savefig(path, dpi=110)


if __name__ == "__main__":
    main()
