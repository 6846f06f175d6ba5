#!/usr/bin/env python3
"""CPU per test of the pedestrian study for each system under test that sees through the
camera, against `aeb` (lidar), and between binaries (the camera-loop issue, requirements 2
and 5).

For each system under test (`aeb`, `vision`, `pilotnet`, and an external process,
`python3 scenarios/benches/camera_sut.py` through `--sut-cmd`) and each binary, runs
`paracosm-fuzz scenarios/pedestrian_crossing.star --strategy halton --jobs 1` with a budget
of 1 test and of --budget tests (`aeb`: 10 × --budget, its tests being cheap). A run's CPU time is the user + system time of the whole
process and the processes it waited for (os.wait4: the external system's Python included).
Two figures per test come out of the medians of --runs runs:

- *whole*: CPU(budget) / budget, what the issue's table measured (loading, the renderer's
  device, the model and the report included);
- *marginal*: (CPU(budget) − CPU(1)) / (budget − 1), a test's own cost with the campaign's
  fixed costs taken out.

Prints, per binary, both figures for each system and the marginal one's ratio to `aeb`; with
two binaries (--bin BASE --bin NEW, alternating within each round so both see the same
machine), each system's ratio NEW / BASE; the load average before and after
(/proc/loadavg), so a reader on a busy machine can compare. The binaries' results.jsonl must
agree but for wall_ms: the script says which systems' verdicts differ and exits 1 when any do.

Wall time is printed beside CPU time (tests per second of the whole campaign, and a test's
marginal wall seconds), which is what a GPU changes. `--jobs N` runs the campaigns on N
workers. `--save DIR` writes the first binary's full campaigns' results (`DIR/SUT.jsonl`,
wall_ms left out); `--compare DIR` reads such a folder, written on another machine or with
another renderer, and says per system how many records and verdicts differ (exit status 1
when any verdict does).

    python3 experiments/bench/camera_loop.py --bin BASE --bin target/release/paracosm-fuzz
"""

import argparse
import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO_ROOT = Path(__file__).resolve().parents[2]
SCENARIO = "scenarios/pedestrian_crossing.star"
SUTS = {
    "aeb": ["--sut", "aeb"],
    "vision": ["--sut", "vision"],
    "pilotnet": ["--sut", "pilotnet"],
    "external": ["--sut-cmd", "python3 scenarios/benches/camera_sut.py"],
}


def budget_of(sut, budget):
    """`aeb` runs 10 times the budget: its tests cost too little for the fixed costs' noise."""
    return budget * 10 if sut == "aeb" else budget


def run(binary, sut, budget, out, jobs=1):
    """CPU seconds, wall seconds and stderr of one campaign, and its results as comparable
    lines."""
    cmd = [binary, SCENARIO, "--strategy", "halton", "--budget", str(budget), "--jobs",
           str(jobs), "--out", out, "--force", *SUTS[sut]]
    start = time.perf_counter()
    proc = subprocess.Popen(cmd, cwd=REPO_ROOT, stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE)
    err = proc.stderr.read().decode(errors="replace")
    _, status, usage = os.wait4(proc.pid, 0)
    wall = time.perf_counter() - start
    code = os.waitstatus_to_exitcode(status)
    if code not in (0, 1):
        sys.exit(f"{' '.join(cmd)} exited with {code}: {err[-2000:]}")
    records = []
    with open(Path(out) / "results.jsonl") as f:
        for line in f:
            r = json.loads(line)
            r.pop("wall_ms", None)
            records.append(json.dumps(r, sort_keys=True))
    return usage.ru_utime + usage.ru_stime, wall, err, records


def compare(records, folder, sut):
    """(records that differ, verdicts that differ, tests) against `folder/SUT.jsonl`."""
    theirs = Path(folder, f"{sut}.jsonl").read_text().splitlines()
    if len(theirs) != len(records):
        return len(records), len(records), len(records)
    verdict = lambda line: json.loads(line)["status"]  # noqa: E731
    return (sum(a != b for a, b in zip(records, theirs)),
            sum(verdict(a) != verdict(b) for a, b in zip(records, theirs)), len(records))


def loadavg():
    try:
        return Path("/proc/loadavg").read_text().split()[:3]
    except OSError:
        return ["?"] * 3


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--bin", action="append", required=True,
                    help="a paracosm-fuzz binary (give twice to compare: BASE then NEW)")
    ap.add_argument("--budget", type=int, default=20, help="tests per campaign (default 20)")
    ap.add_argument("--runs", type=int, default=3, help="runs of each campaign (default 3)")
    ap.add_argument("--sut", action="append", choices=list(SUTS),
                    help="systems under test to measure (default: all four)")
    ap.add_argument("--jobs", type=int, default=1, help="workers per campaign (default 1)")
    ap.add_argument("--save", help="write the first binary's results to DIR/SUT.jsonl")
    ap.add_argument("--compare", help="compare the first binary's results with DIR/SUT.jsonl")
    args = ap.parse_args()
    suts = args.sut or list(SUTS)
    if "aeb" not in suts:
        suts.insert(0, "aeb")
    bins = [str(Path(b).resolve()) for b in args.bin]
    before = loadavg()
    started = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())
    cpu = {}  # (bin, sut, budget) -> [seconds]
    wall = {}  # likewise, wall seconds
    renderer = set()
    records = {}  # (bin, sut) -> lines of the full campaign
    with tempfile.TemporaryDirectory() as tmp:
        for r in range(args.runs):
            for sut in suts:
                for b, binary in enumerate(bins):
                    for budget in (1, budget_of(sut, args.budget)):
                        out = os.path.join(tmp, f"{b}-{sut}-{budget}")
                        seconds, w, err, lines = run(binary, sut, budget, out, args.jobs)
                        cpu.setdefault((b, sut, budget > 1), []).append(seconds)
                        wall.setdefault((b, sut, budget > 1), []).append(w)
                        renderer.update(line.split("camera renderer: ", 1)[1]
                                        for line in err.splitlines()
                                        if "camera renderer: " in line)
                        if budget > 1:
                            records[(b, sut)] = lines
            print(f"round {r + 1} of {args.runs} done", file=sys.stderr)
    after = loadavg()
    print(f"pedestrian study, {args.budget} Halton tests ({budget_of('aeb', args.budget)} "
          f"for aeb), --jobs {args.jobs}, medians of {args.runs} "
          f"runs; {started}; {platform.machine()}, {os.cpu_count()} cores; "
          f"load average before {' '.join(before)}, after {' '.join(after)}; camera renderer: "
          f"{', '.join(sorted(renderer)) or 'none reported'}")
    marginal = {}
    for b, binary in enumerate(bins):
        print(f"\n{binary}")
        print("| system under test | CPU-s, 1 test | CPU-s, whole campaign | whole, per test "
              "| marginal, per test | marginal against aeb | wall s, whole campaign "
              "| tests/s | marginal wall s per test |")
        print("|---|---:|---:|---:|---:|---:|---:|---:|---:|")
        for sut in suts:
            n = budget_of(sut, args.budget)
            one = statistics.median(cpu[(b, sut, False)])
            whole = statistics.median(cpu[(b, sut, True)])
            m = (whole - one) / (n - 1)
            marginal[(b, sut)] = m
            ratio = m / marginal[(b, "aeb")] if marginal[(b, "aeb")] > 0 else float("nan")
            w_one = statistics.median(wall[(b, sut, False)])
            w_whole = statistics.median(wall[(b, sut, True)])
            print(f"| {sut} | {one:.2f} | {whole:.2f} ({n} tests) | {whole / n:.4f} | {m:.4f} "
                  f"| {ratio:.1f}× | {w_whole:.2f} | {n / w_whole:.1f} "
                  f"| {(w_whole - w_one) / (n - 1):.4f} |")
    failed = False
    if args.save:
        os.makedirs(args.save, exist_ok=True)
        for sut in suts:
            Path(args.save, f"{sut}.jsonl").write_text("\n".join(records[(0, sut)]) + "\n")
    if args.compare:
        print(f"\nagainst {args.compare} (the first binary's full campaigns)")
        print("| system under test | records that differ | verdicts that differ |")
        print("|---|---:|---:|")
        for sut in suts:
            rec, ver, n = compare(records[(0, sut)], args.compare, sut)
            failed |= ver > 0
            print(f"| {sut} | {rec} of {n} | {ver} of {n} |")
    if len(bins) == 2:
        print(f"\nNEW / BASE (below 1 is faster): NEW {bins[1]}, BASE {bins[0]}")
        print("| system under test | whole campaign | marginal per test | verdicts |")
        print("|---|---:|---:|---|")
        for sut in suts:
            w0 = statistics.median(cpu[(0, sut, True)])
            w1 = statistics.median(cpu[(1, sut, True)])
            same = records[(0, sut)] == records[(1, sut)]
            failed |= not same
            print(f"| {sut} | {w1 / w0:.3f} | {marginal[(1, sut)] / marginal[(0, sut)]:.3f} "
                  f"| {'identical results' if same else 'RESULTS DIFFER'} |")
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
