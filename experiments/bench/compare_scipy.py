#!/usr/bin/env python3
"""Time SciPy and paracosm side by side on the same QMC tasks.

Tasks: scrambled Halton, 2^16 points in d=8; and the CD, WD, MD and L2-star
discrepancies of a fixed random 4000x8 array. Each SciPy time is the best of
7 repetitions after one warm-up (time.perf_counter, milliseconds, SciPy's
default workers=1). Paracosm's numbers come from
`target/release/paracosm-cover bench --json` (build it first with
`cargo build --release --bin paracosm-cover`), or from a file given with
--paracosm-json. Prints a markdown table, then checks that paracosm's four discrepancies of
the same array equal scipy's to 1e-12 relative (`paracosm-cover estimate` on the array
written as CSV; skipped with --paracosm-json) and exits 1 when one does not.

Run from anywhere:

    python3 experiments/bench/compare_scipy.py [--paracosm-json FILE]

On first run it creates a virtualenv at ${VENV:-/tmp/paracosm-scipy-venv},
installs scipy and numpy there, and re-executes itself inside it.
"""

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "scripts"))
from scipy_venv import ensure_venv  # noqa: E402

REPO_ROOT = Path(__file__).resolve().parents[2]
PARACOSM_BIN = REPO_ROOT / "target" / "release" / "paracosm-cover"

REPEATS = 7
# Largest relative difference allowed between paracosm's and scipy's values (issue 23).
VALUE_TOLERANCE = 1e-12
DISC_N, DISC_D = 4000, 8

# (label, key in paracosm's JSON)
TASKS = [
    ("Halton 2^16 points, d=8, scrambled", "halton_scrambled_65536x8_ms"),
    ("CD discrepancy, n=4000, d=8", "cd_4000x8_ms"),
    ("WD discrepancy, n=4000, d=8", "wd_4000x8_ms"),
    ("MD discrepancy, n=4000, d=8", "md_4000x8_ms"),
    ("L2-star discrepancy, n=4000, d=8", "l2star_4000x8_ms"),
]


def best_ms(fn):
    """Minimum wall time of REPEATS calls after one warm-up, in ms."""
    fn()
    times = []
    for _ in range(REPEATS):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times) * 1e3


def scipy_times():
    import numpy as np
    from scipy.stats import qmc

    x = np.random.default_rng(0).random((DISC_N, DISC_D))
    disc = lambda method: (lambda: qmc.discrepancy(x, method=method))
    fns = {
        "halton_scrambled_65536x8_ms":
            lambda: qmc.Halton(8, scramble=True, seed=0).random(65536),
        "cd_4000x8_ms": disc("CD"),
        "wd_4000x8_ms": disc("WD"),
        "md_4000x8_ms": disc("MD"),
        "l2star_4000x8_ms": disc("L2-star"),
    }
    return {key: best_ms(fn) for key, fn in fns.items()}


def paracosm_times(json_file):
    if json_file is not None:
        text = Path(json_file).read_text()
        source = str(json_file)
    else:
        if not PARACOSM_BIN.is_file():
            print(f"error: {PARACOSM_BIN} not found.\n"
                  "Build it first:  cargo build --release --bin paracosm-cover\n"
                  "(or pass --paracosm-json FILE)", file=sys.stderr)
            sys.exit(2)
        cmd = [str(PARACOSM_BIN), "bench", "--json"]
        proc = subprocess.run(cmd, cwd=REPO_ROOT, capture_output=True, text=True)
        if proc.returncode != 0:
            sys.stderr.write(proc.stderr)
            print(f"error: `{' '.join(cmd)}` exited with {proc.returncode}", file=sys.stderr)
            sys.exit(1)
        text = proc.stdout
        source = " ".join(cmd)
    try:
        data = json.loads(text)
    except json.JSONDecodeError as e:
        print(f"error: output of {source} is not JSON: {e}", file=sys.stderr)
        sys.exit(1)
    missing = [k for _, k in TASKS if k not in data] + (["threads"] if "threads" not in data else [])
    if missing:
        print(f"error: {source} lacks keys: {', '.join(missing)}", file=sys.stderr)
        sys.exit(1)
    return data


def value_check(skip):
    """Compare paracosm's CD, WD, MD and L2-star with scipy's on the timed 4000x8 array.

    Writes the array to a CSV (Python's repr round-trips every float), runs
    `paracosm-cover estimate FILE --metrics cd,wd,md,l2star --json` and returns rows
    (method, scipy, paracosm, relative difference). Empty when `skip`.
    """
    if skip:
        return []
    import tempfile
    import numpy as np
    from scipy.stats import qmc

    x = np.random.default_rng(0).random((DISC_N, DISC_D))
    with tempfile.NamedTemporaryFile("w", suffix=".csv", delete=False) as f:
        f.write(",".join(f"x{k}" for k in range(DISC_D)) + "\n")
        for row in x:
            f.write(",".join(repr(float(v)) for v in row) + "\n")
        path = f.name
    cmd = [str(PARACOSM_BIN), "estimate", path, "--metrics", "cd,wd,md,l2star", "--json"]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    os.unlink(path)
    if proc.returncode != 0:
        sys.stderr.write(proc.stderr)
        print(f"error: `{' '.join(cmd)}` exited with {proc.returncode}", file=sys.stderr)
        sys.exit(1)
    ours = dict(json.loads(proc.stdout)["discrepancy"])
    rows = []
    for name, method in (("cd", "CD"), ("wd", "WD"), ("md", "MD"), ("l2star", "L2-star")):
        theirs = float(qmc.discrepancy(x, method=method))
        rows.append((method, theirs, ours[name], abs(ours[name] - theirs) / abs(theirs)))
    return rows


def nproc():
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:
        return os.cpu_count()


def main():
    parser = argparse.ArgumentParser(
        description="Compare SciPy and paracosm timings on QMC tasks.")
    parser.add_argument("--paracosm-json", metavar="FILE",
                        help="read paracosm's timings from FILE instead of running "
                             "target/release/paracosm-cover bench --json")
    args = parser.parse_args()

    # Get paracosm's numbers first so a missing binary fails fast.
    ours = paracosm_times(args.paracosm_json)

    import numpy as np
    import scipy

    theirs = scipy_times()

    print("| task | scipy (ms) | paracosm (ms) | speed-up |")
    print("|---|---:|---:|---:|")
    for label, key in TASKS:
        s, p = theirs[key], float(ours[key])
        ratio = f"{s / p:.1f}×" if p > 0 else "n/a"
        print(f"| {label} | {s:.2f} | {p:.2f} | {ratio} |")
    print()
    print(f"scipy {scipy.__version__}, numpy {np.__version__} (scipy workers=1); "
          f"paracosm threads: {ours['threads']}; nproc: {nproc()}; "
          f"best of {REPEATS} after 1 warm-up; speed-up = scipy / paracosm.")

    rows = value_check(args.paracosm_json is not None)
    if rows:
        print()
        print("| value | scipy | paracosm | relative difference |")
        print("|---|---:|---:|---:|")
        for method, theirs, mine, rel in rows:
            print(f"| {method} | {theirs!r} | {mine!r} | {rel:.1e} |")
        worst = max(r[3] for r in rows)
        if worst > VALUE_TOLERANCE:
            print(f"error: a value differs from scipy's by {worst:.1e} relative "
                  f"(more than {VALUE_TOLERANCE:g})", file=sys.stderr)
            sys.exit(1)


if __name__ == "__main__":
    ensure_venv(__file__)
    main()
