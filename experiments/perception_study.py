#!/usr/bin/env python3
"""The paper's §4.1 perception studies with one command: the data sets (`paracosm-fuzz
dataset` at 160 × 120), the two networks (`perception train`: road segmentation on the
renderer's masks, a centre-point vehicle detector on the COCO boxes), and the two studies
(`perception road-study`: road true/false positive rates against the focal length, Figures
5-6; `perception drive-study`: cars visible, found and falsely found along a drive into a
crossing with an occluding truck, Figures 7-8). Deterministic for a seed.

    python3 experiments/perception_study.py                 # seed 0, the shipped networks
    python3 experiments/perception_study.py --seed 1 --out experiments/out/perception-s1

With the shipped networks' seed it says whether the ONNX files it trained are the shipped ones
byte for byte, and it runs the studies on the shipped files (experiments/models/road_seg.onnx,
vehicle_det.onnx). Builds the release binaries first (the shared profile).
"""

import argparse
import hashlib
import os
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SIZE = ["--width", "160", "--height", "120"]
FOCALS = [10, 15, 20, 24, 30, 35, 40, 45, 50]
DATA = {
    "road-train": ["experiments/scenarios/perception_road.star", "--strategy", "halton",
                   "--budget", "200", "--rate", "2"],
    "veh-train": ["experiments/scenarios/perception_vehicles_train.star", "--strategy", "halton",
                  "--budget", "300", "--rate", "2"],
    "drive": ["experiments/scenarios/perception_vehicles_drive.star", "--strategy", "halton",
              "--budget", "1", "--rate", "1"],
    **{f"road-f{f}": ["experiments/scenarios/perception_road.star", "--strategy", "random",
                      "--seed", "7", "--budget", "40", "--rate", "1", "--focal-mm", str(f)]
       for f in FOCALS},
}
TRAIN = {
    "road_seg": ["--task", "road", "--data", "road-train"],
    "vehicle_det": ["--task", "vehicles", "--data", "veh-train", "--positive-weight", "20"],
}


def run(cmd):
    """Runs `cmd` in the repository, echoing it; exits when it fails."""
    print("$ " + " ".join(cmd), flush=True)
    env = dict(os.environ)
    env.setdefault("XDG_RUNTIME_DIR", "/tmp")
    started = time.monotonic()
    p = subprocess.run(cmd, cwd=ROOT, env=env)
    if p.returncode != 0:
        sys.exit(f"perception_study: `{' '.join(cmd)}` exited with {p.returncode}")
    return time.monotonic() - started


def sha256(path):
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seed", type=int, default=0, help="training seed (default 0, as shipped)")
    ap.add_argument("--out", default="experiments/out/perception",
                    help="folder for the data, the networks and the studies")
    args = ap.parse_args()
    out = Path(args.out)
    subprocess.run(["cargo", "build", "--release", "--locked", "-q", "-p", "paracosm", "--bin",
                    "paracosm-fuzz", "-p", "paracosm-experiments", "--bin", "perception"],
                   cwd=ROOT, check=True)
    fuzz = str(ROOT / "target/release/paracosm-fuzz")
    perception = str(ROOT / "target/release/perception")
    t_data = sum(run([fuzz, "dataset", *a, *SIZE, "--out", str(out / name), "--force"])
                 for name, a in DATA.items())
    times = {}
    models = {}
    for name, a in TRAIN.items():
        a = [str(out / x) if i > 0 and a[i - 1] == "--data" else x for i, x in enumerate(a)]
        prefix = out / f"{name}-s{args.seed}"
        times[name] = run([perception, "train", *a, "--seed", str(args.seed), "--out",
                           str(prefix)])
        shipped = ROOT / "experiments/models" / f"{name}.onnx"
        same = shipped.exists() and sha256(ROOT / f"{prefix}.onnx") == sha256(shipped)
        print(f"{prefix}.onnx is {'identical to' if same else 'not'} the shipped {shipped.name}")
        models[name] = shipped if args.seed == 0 and shipped.exists() else ROOT / f"{prefix}.onnx"
    run([perception, "road-study", "--model", str(models["road_seg"]),
         *[x for f in FOCALS for x in ("--data", f"{f}={out / f'road-f{f}'}")],
         "--out", str(out / "road_focal")])
    run([perception, "drive-study", "--model", str(models["vehicle_det"]), "--data",
         str(out / "drive"), "--out", str(out / "vehicle_drive")])
    print(f"\ndata {t_data:.0f} s, training: road_seg {times['road_seg']:.0f} s, vehicle_det "
          f"{times['vehicle_det']:.0f} s (wall); studies in {out}/road_focal.* and "
          f"{out}/vehicle_drive.*")


if __name__ == "__main__":
    main()
