#!/usr/bin/env python3
"""paracosm's Python package beside scipy.stats.qmc and beside its own CLI, in one run.

1. `paracosm.qmc.discrepancy` against `scipy.stats.qmc.discrepancy`, CD, n = 4,000, d = 8
   (a fixed random array); the values are checked equal to 1e-10 relative.
2. `paracosm.qmc.Halton(8).random(65536)` against `scipy.stats.qmc.Halton(8,
   scramble=False).random(65536)` (the same points), and both scrambled.
3. `Scenario("pedestrian-crossing").run(X)` against `paracosm-fuzz pedestrian-crossing
   --points X.csv` (the whole process, which also writes its summary, plots and report
   page) on the same N Halton points: wall time per test, and the difference.

Times: best of 7 after a warm-up (1, 2), median of 3 (3); time.perf_counter. Needs the
package installed (`pip install ./python`), scipy, and `target/release/paracosm-fuzz`.

    python experiments/bench/python_vs_scipy.py [--tests N] [--jobs J]
"""

import argparse
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from scipy.stats import qmc as sqmc

import paracosm
from paracosm.scenario import points_csv

REPO = Path(__file__).resolve().parents[2]


def best_ms(fn, repeats=7):
    fn()
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times) * 1e3


def median_s(fn, repeats=3):
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tests", type=int, default=500, help="tests of the scenario comparison")
    ap.add_argument("--jobs", type=int, default=None, help="worker threads (default: all cores)")
    ap.add_argument("--fuzz", default=str(REPO / "target" / "release" / "paracosm-fuzz"))
    args = ap.parse_args()

    rows = []
    sample = np.random.default_rng(0).random((4000, 8))
    ours = paracosm.qmc.discrepancy(sample, method="CD")
    theirs = sqmc.discrepancy(sample, method="CD")
    assert abs(ours - theirs) <= 1e-10 * abs(theirs), (ours, theirs)
    t_s = best_ms(lambda: sqmc.discrepancy(sample, method="CD"))
    t_p = best_ms(lambda: paracosm.qmc.discrepancy(sample, method="CD"))
    rows.append(("CD discrepancy, n = 4,000, d = 8", t_s, t_p))

    a = paracosm.qmc.Halton(8).random(65536)
    b = sqmc.Halton(8, scramble=False).random(65536)
    assert np.abs(a - b).max() <= 1e-15
    t_s = best_ms(lambda: sqmc.Halton(8, scramble=False).random(65536))
    t_p = best_ms(lambda: paracosm.qmc.Halton(8).random(65536))
    rows.append(("Halton(8).random(65536), unscrambled", t_s, t_p))
    t_s = best_ms(lambda: sqmc.Halton(8, scramble=True, rng=1).random(65536))
    t_p = best_ms(lambda: paracosm.qmc.Halton(8, scramble=True, rng=1).random(65536))
    rows.append(("Halton(8).random(65536), scrambled", t_s, t_p))

    print("| task | scipy (ms) | paracosm (ms) | speed-up |")
    print("|---|---:|---:|---:|")
    for name, s, p in rows:
        print(f"| {name} | {s:.2f} | {p:.2f} | {s / p:.1f}x |")

    scenario = paracosm.Scenario("pedestrian-crossing")
    x = paracosm.qmc.Halton(len(scenario.space)).random(args.tests)
    points = scenario.space.to_units(x)
    jobs = [] if args.jobs is None else ["--jobs", str(args.jobs)]
    with tempfile.TemporaryDirectory() as tmp:
        csv_path = Path(tmp) / "points.csv"
        csv_path.write_text(points_csv(points, scenario.space))

        def cli():
            subprocess.run(
                [args.fuzz, "pedestrian-crossing", "--points", csv_path, "--out", Path(tmp) / "out", "--force", *jobs],
                check=False,
                capture_output=True,
            )

        t_cli = median_s(cli)
        t_py = median_s(lambda: scenario.run(points, jobs=args.jobs, output="jsonl"))
    n = args.tests
    print()
    print(f"| pedestrian-crossing, {n} tests | wall (s) | per test (ms) |")
    print("|---|---:|---:|")
    print(f"| paracosm-fuzz --points (whole process) | {t_cli:.2f} | {1e3 * t_cli / n:.2f} |")
    print(f"| Scenario.run | {t_py:.2f} | {1e3 * t_py / n:.2f} |")
    print(f"| Scenario.run over the CLI | {t_py / t_cli:.2f}x | {1e3 * (t_py - t_cli) / n:+.3f} |")
    print(f"\npython {sys.version.split()[0]}, numpy {np.__version__}, scipy {__import__('scipy').__version__}, paracosm {paracosm.__version__}")


if __name__ == "__main__":
    main()
