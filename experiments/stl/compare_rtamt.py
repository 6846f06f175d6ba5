#!/usr/bin/env python3
"""Correctness and speed of paracosm's STL robustness against RTAMT (PyPI `rtamt`).

    python3 experiments/stl/compare_rtamt.py fixtures   # writes oracles/tests/fixtures/rtamt.json
    python3 experiments/stl/compare_rtamt.py speed      # RTAMT vs paracosm on 10^5 samples

Installs rtamt into its own virtualenv (experiments/stl/.venv) on first use. Both use
discrete-time semantics: time is the sample index (dt = 1), bounds count samples.

`fixtures`: random traces (seeded) and formulas covering predicates, the connectives and the
bounded G, F and U; RTAMT's robustness at every sample is written with the inputs, and
`cargo test -p paracosm-oracles --test rtamt` checks that paracosm computes the same values.
"""
import json
import os
import random
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
VENV = os.path.join(HERE, ".venv")


def ensure_rtamt():
    python = os.path.join(VENV, "bin", "python")
    if not os.path.exists(python):
        subprocess.check_call([sys.executable, "-m", "venv", VENV])
        subprocess.check_call([python, "-m", "pip", "install", "-q", "rtamt"])
    if os.path.realpath(sys.prefix) != os.path.realpath(VENV):
        os.execv(python, [python] + sys.argv)


# Formulas in both syntaxes: (paracosm, RTAMT).
TEMPLATES = [
    ("a > {c}", "a > {c}"),
    ("b <= {c}", "b <= {c}"),
    ("!(a > {c})", "not (a > {c})"),
    ("a > {c} & b < {d}", "(a > {c}) and (b < {d})"),
    ("a > {c} | b < {d}", "(a > {c}) or (b < {d})"),
    ("a > {c} -> b < {d}", "(a > {c}) implies (b < {d})"),
    ("G[{lo},{hi}] a > {c}", "always[{lo},{hi}](a > {c})"),
    ("F[{lo},{hi}] b < {d}", "eventually[{lo},{hi}](b < {d})"),
    ("a > {c} U[{lo},{hi}] b > {d}", "(a > {c}) until[{lo},{hi}] (b > {d})"),
    ("G[{lo},{hi}](a > {c} -> F[0,{w}](b < {d}))",
     "always[{lo},{hi}]((a > {c}) implies (eventually[0,{w}](b < {d})))"),
    ("F[{lo},{hi}](G[0,{w}] a >= {c})", "eventually[{lo},{hi}](always[0,{w}](a >= {c}))"),
    ("!(a > {c} U[{lo},{hi}] (b > {d} & a < {c}))",
     "not ((a > {c}) until[{lo},{hi}] ((b > {d}) and (a < {c})))"),
]


def rtamt_robustness(formula, trace):
    import rtamt
    spec = rtamt.StlDiscreteTimeSpecification()
    for name in trace:
        if name != "time":
            spec.declare_var(name, "float")
    spec.spec = formula
    spec.parse()
    return [r for _, r in spec.evaluate(trace)]


def fixtures():
    rng = random.Random(20261121)
    cases = []
    for k in range(60):
        n = rng.randint(2, 40)  # RTAMT fails on one-sample traces
        a = [round(rng.uniform(-3, 3), 3) for _ in range(n)]
        b = [round(rng.uniform(-3, 3), 3) for _ in range(n)]
        ours, theirs = TEMPLATES[k % len(TEMPLATES)]
        lo = rng.randint(0, 4)
        values = dict(c=round(rng.uniform(-1, 1), 2), d=round(rng.uniform(-1, 1), 2),
                      lo=lo, hi=lo + rng.randint(0, 6), w=rng.randint(0, 3))
        trace = {"time": list(range(n)), "a": a, "b": b}
        rob = rtamt_robustness(theirs.format(**values), trace)
        cases.append({
            "formula": ours.format(**values),
            "rtamt_formula": theirs.format(**values),
            "a": a,
            "b": b,
            # JSON has no infinity: write it as a string.
            "robustness": [r if abs(r) != float("inf") else ("inf" if r > 0 else "-inf")
                           for r in rob],
        })
    path = os.path.join(ROOT, "oracles", "tests", "fixtures", "rtamt.json")
    import rtamt  # noqa: F401  (version)
    from importlib.metadata import version
    with open(path, "w") as f:
        json.dump({"rtamt": version("rtamt"), "cases": cases}, f, indent=1)
        f.write("\n")
    print(f"wrote {len(cases)} cases to {path}")


def speed():
    n = 100_000
    rng = random.Random(1)
    a = [rng.uniform(-1, 2) for _ in range(n)]
    b = [rng.uniform(-1, 2) for _ in range(n)]
    trace = {"time": list(range(n)), "a": a, "b": b}
    csv = os.path.join(HERE, ".trace.csv")
    with open(csv, "w") as f:
        f.write("a,b\n")
        for x, y in zip(a, b):
            f.write(f"{x!r},{y!r}\n")
    cover = os.path.join(ROOT, "target", "release", "paracosm-cover")
    cases = [
        ("G[0,10](a > 0 -> F[0,2](b < 1))",
         "always[0,10]((a > 0) implies (eventually[0,2](b < 1)))"),
        ("G[0,1000](a > 0 -> F[0,200](b < 1))",
         "always[0,1000]((a > 0) implies (eventually[0,200](b < 1)))"),
        ("a > 0 U[0,100] b > 1.5", "(a > 0) until[0,100] (b > 1.5)"),
    ]
    print(f"| formula (n = {n}) | RTAMT (s) | paracosm (s) | speed-up |")
    print("|---|---:|---:|---:|")
    for ours, theirs in cases:
        t0 = time.perf_counter()
        rtamt_robustness(theirs, trace)
        rt = time.perf_counter() - t0
        out = subprocess.run([cover, "stl", ours, csv, "--dt", "1", "--json"],
                             check=True, capture_output=True, text=True).stdout
        pc = json.loads(out)["eval_s"]
        print(f"| `{ours}` | {rt:.3f} | {pc:.4f} | {rt / pc:.0f}x |")


if __name__ == "__main__":
    ensure_rtamt()
    {"fixtures": fixtures, "speed": speed}[sys.argv[1] if len(sys.argv) > 1 else "fixtures"]()
