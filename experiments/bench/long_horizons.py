#!/usr/bin/env python3
"""CPU per simulated second of the long-horizon scenarios against the pedestrian study
(issue 23, requirement 3).

Runs `paracosm-fuzz SCENARIO --strategy halton --budget B --jobs 1` for the pedestrian
study, `t-loop` and `grid-world`, with budgets that give each campaign about the same
simulated time (26,000 to 29,000 s), so the campaign's fixed costs (loading, the report)
weigh alike. Each run's CPU time is the user + system time of the whole process
(os.wait4), its simulated time the sum of `metrics.simulated_s` over results.jsonl.
Prints, per binary, the median of --runs runs of each scenario in ms of CPU per simulated
second, and each scenario's ratio to the pedestrian study; and the same for the tests alone
(the sum of the tests' wall_ms, which at --jobs 1 leaves out loading and the report). Exits 1 when a ratio is above
--limit (default 1.2) for the last binary given.

With several binaries (--bin A --bin B), the runs alternate binary by binary within each
round, so both see the same machine; their results.jsonl must agree but for wall_ms (the
script checks it and exits 1 when they do not).

    python3 experiments/bench/long_horizons.py --bin target/release/paracosm-fuzz [--bin OTHER]
"""

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

REPO_ROOT = Path(__file__).resolve().parents[2]
# (scenario, budget): about 28,000, 26,000 and 29,000 simulated seconds.
CAMPAIGNS = [("pedestrian-crossing", 2000), ("t-loop", 150), ("grid-world", 750)]


def run(binary, scenario, budget, out):
    """CPU seconds (user + sys) of one campaign, and its results as comparable lines."""
    cmd = [binary, scenario, "--strategy", "halton", "--budget", str(budget),
           "--jobs", "1", "--out", out, "--force"]
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    _, status, usage = os.wait4(proc.pid, 0)
    code = os.waitstatus_to_exitcode(status)
    if code not in (0, 1):
        sys.exit(f"{' '.join(cmd)} exited with {code}")
    records = []
    simulated = 0.0
    tests_s = 0.0
    with open(Path(out) / "results.jsonl") as f:
        for line in f:
            r = json.loads(line)
            simulated += r["metrics"]["simulated_s"]
            tests_s += r.pop("wall_ms", 0.0) / 1e3
            records.append(json.dumps(r, sort_keys=True))
    return usage.ru_utime + usage.ru_stime, tests_s, simulated, records


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--bin", action="append", required=True,
                    help="a paracosm-fuzz binary (give twice to compare)")
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--limit", type=float, default=1.2)
    args = ap.parse_args()
    cpu = {b: {s: [] for s, _ in CAMPAIGNS} for b in args.bin}
    tests = {b: {s: [] for s, _ in CAMPAIGNS} for b in args.bin}
    sim = {}
    results = {}
    with tempfile.TemporaryDirectory() as tmp:
        for r in range(args.runs):
            for scenario, budget in CAMPAIGNS:
                for i, b in enumerate(args.bin):
                    out = os.path.join(tmp, f"{i}-{scenario}")
                    seconds, tests_s, simulated, records = run(b, scenario, budget, out)
                    cpu[b][scenario].append(seconds)
                    tests[b][scenario].append(tests_s)
                    sim[scenario] = simulated
                    key = (scenario, r)
                    if key in results and results[key] != records:
                        sys.exit(f"{scenario}: {b} gives other results than {args.bin[0]}")
                    results[key] = records
                    print(f"round {r + 1}: {scenario} {b}: {seconds:.2f} CPU-s",
                          file=sys.stderr, flush=True)
    print("| binary | scenario (budget) | simulated s | CPU-s (median) | ms per simulated s "
          "| × pedestrian | tests only: ms per simulated s | × pedestrian |")
    print("|---|---|---:|---:|---:|---:|---:|---:|")
    worst = 0.0
    for b in args.bin:
        base = statistics.median(cpu[b]["pedestrian-crossing"]) / sim["pedestrian-crossing"]
        base_tests = (statistics.median(tests[b]["pedestrian-crossing"])
                      / sim["pedestrian-crossing"])
        for scenario, budget in CAMPAIGNS:
            med = statistics.median(cpu[b][scenario])
            rate = med / sim[scenario]
            ratio = rate / base
            rate_tests = statistics.median(tests[b][scenario]) / sim[scenario]
            if b == args.bin[-1]:
                worst = max(worst, ratio)
            print(f"| {b} | {scenario} ({budget}) | {sim[scenario]:,.0f} | {med:.2f} "
                  f"| {rate * 1e3:.4f} | {ratio:.2f} | {rate_tests * 1e3:.4f} "
                  f"| {rate_tests / base_tests:.2f} |")
    print(f"\nruns: {args.runs}, --jobs 1, medians of user + sys CPU of the whole process; "
          "'tests only' sums the tests' wall_ms (at --jobs 1 one test runs at a time: the "
          "closed loop and each test's program and world, without loading and the report); "
          f"nproc {os.cpu_count()}")
    if worst > args.limit:
        print(f"a ratio is above {args.limit}: {worst:.2f}")
        sys.exit(1)


if __name__ == "__main__":
    main()
