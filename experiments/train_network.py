#!/usr/bin/env python3
"""Trains one of the shipped networks from its scenario with one command: the training data
(`paracosm-fuzz dataset`), the training (`train_pilotnet`, which writes the ONNX file, its
manifest and its model card), DAgger rounds where the recipe has them (the network drives,
the teacher labels its states: `dataset --learner-onnx`, and a fresh network trains on all the
data), and a closed-loop evaluation on held-out tests (`paracosm-fuzz ... --sut-onnx`). Deterministic for a seed: with the seed a network was
shipped with, the ONNX file it writes is the shipped one byte for byte, and the script says
whether it is.

    python3 experiments/train_network.py follow                # seed 0
    python3 experiments/train_network.py pilotnet --seed 1 --out experiments/out/pilotnet-s1

The recipes (scenario, budget, noise, training options, evaluation) are the ones
docs/experiments.md gives for each network. Builds the release binaries first (the shared
profile: a no-op when they are up to date).
"""

import argparse
import hashlib
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

RECIPES = {
    "pilotnet": {
        "shipped": "assets/models/pilotnet.onnx",
        "data": ["experiments/scenarios/pilotnet_train.star", "--budget", "96", "--rate", "10",
                 "--steer-noise", "0.08", "--noise-hold", "0.5"],
        "train": ["--epochs", "8", "--steering-weight", "10", "--closed-loop",
                  "pedestrian-crossing"],
        "evaluate": [["pedestrian-crossing", "--budget", "400"],
                     ["experiments/scenarios/pilotnet_bends_check.star", "--budget", "40"]],
    },
    "follow": {
        "shipped": "experiments/models/follow.onnx",
        "data": ["experiments/scenarios/follow_red_train.star", "--budget", "64", "--rate", "10",
                 "--steer-noise", "0.08", "--noise-hold", "0.5"],
        "train": ["--epochs", "8", "--smooth-s", "1", "--steering-weight", "10",
                  "--brake-weight", "6", "--closed-loop",
                  "experiments/scenarios/follow_red_check.star"],
        "evaluate": [["experiments/scenarios/follow_red_check.star", "--budget", "40"]],
    },
    "loop": {
        "shipped": "experiments/models/loop.onnx",
        "data": ["experiments/scenarios/loop_train.star", "--budget", "48", "--rate", "10",
                 "--steer-noise", "0.1", "--noise-hold", "0.5"],
        "train": ["--epochs", "8", "--steering-weight", "10", "--closed-loop",
                  "experiments/scenarios/loop_check.star"],
        # One DAgger round: the network of the round before drives the same tests while the
        # teacher labels its states; the next network trains on all the data so far.
        "dagger": [["experiments/scenarios/loop_train.star", "--budget", "48", "--rate", "10"]],
        "evaluate": [["experiments/scenarios/loop_check.star", "--strategy", "random",
                      "--seed", "1", "--budget", "100"]],
    },
}


def run(cmd):
    """Runs `cmd` in the repository, echoing it; exits with its status when it is not 0 (or
    1 for a campaign, whose failed tests are what an evaluation reports)."""
    print("$ " + " ".join(cmd), flush=True)
    env = dict(os.environ)
    env.setdefault("XDG_RUNTIME_DIR", "/tmp")
    started = time.monotonic()
    p = subprocess.run(cmd, cwd=ROOT, env=env)
    if p.returncode not in (0, 1):
        sys.exit(f"train_network: `{' '.join(cmd)}` exited with {p.returncode}")
    return time.monotonic() - started


def sha256(path):
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("network", choices=sorted(RECIPES))
    ap.add_argument("--seed", type=int, default=0, help="training seed (default 0, as shipped)")
    ap.add_argument("--out", help="output prefix (default experiments/out/NETWORK-sSEED)")
    ap.add_argument("--delete-data", action="store_true",
                    help="delete the data sets once the last network is trained (several GB "
                         "each; the same command writes them again, bit for bit)")
    args = ap.parse_args()
    recipe = RECIPES[args.network]
    out = args.out or f"experiments/out/{args.network}-s{args.seed}"
    data = f"{out}-data"
    subprocess.run(["cargo", "build", "--release", "--locked", "-q", "-p", "paracosm", "--bin",
                    "paracosm-fuzz", "-p", "paracosm-experiments", "--bin", "train_pilotnet"],
                   cwd=ROOT, check=True)
    fuzz = str(ROOT / "target/release/paracosm-fuzz")
    trainer = str(ROOT / "target/release/train_pilotnet")
    rounds = recipe.get("dagger", [])
    # Round 0 trains on the teacher's drives; each DAgger round adds the drives of the
    # network before it, labelled by the teacher (`dataset --learner-onnx`), and trains a
    # fresh network on everything. The last round's network is OUT.onnx.
    outs = [f"{out}-round{k}" for k in range(len(rounds))] + [out]
    datas = [data] + [f"{out}-data{k + 1}" for k in range(len(rounds))]
    t_data = run([fuzz, "dataset", *recipe["data"], "--out", data, "--force"])
    t_train = run([trainer, *[a for d in datas[:1] for a in ("--data", d)], "--out", outs[0],
                   "--seed", str(args.seed), *recipe["train"]])
    for k, more in enumerate(rounds, start=1):
        t_data += run([fuzz, "dataset", *more, "--learner-onnx", f"{outs[k - 1]}.onnx",
                       "--out", datas[k], "--force"])
        t_train += run([trainer, *[a for d in datas[:k + 1] for a in ("--data", d)],
                        "--out", outs[k], "--seed", str(args.seed), *recipe["train"]])
    if args.delete_data:
        for d in datas:
            shutil.rmtree(ROOT / d, ignore_errors=True)
    # Each evaluation (held-out tests in closed loop) in its own folder.
    t_eval = sum(run([fuzz, *e, "--sut-onnx", f"{out}.onnx", "--out",
                      f"{out}-evaluation" + (f"-{k}" if k else ""), "--force"])
                 for k, e in enumerate(recipe["evaluate"]))
    shipped = ROOT / recipe["shipped"]
    same = shipped.exists() and sha256(ROOT / f"{out}.onnx") == sha256(shipped)
    print(f"\n{args.network}, seed {args.seed}: data {t_data:.0f} s, training {t_train:.0f} s, "
          f"evaluation {t_eval:.0f} s (wall); wrote {out}.onnx, {out}.toml, {out}.md; "
          f"evaluations in {out}-evaluation*/")
    print(f"{out}.onnx is {'identical to' if same else 'not'} the shipped {recipe['shipped']}"
          + ("" if same else " (another seed, or the data or the code changed)"))


if __name__ == "__main__":
    main()
