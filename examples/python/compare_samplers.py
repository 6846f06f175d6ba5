#!/usr/bin/env python3
"""Compare samplers on the pedestrian study: scipy's Halton, Sobol and Latin hypercube
against paracosm's Halton and Sobol, with the same budget.

For each sampler: the failures it finds on `pedestrian-crossing` (built-in `aeb` system
under test), and the coverage of its points: dispersion (largest empty box; exact here),
star discrepancy (exact or bracketed) and scipy's centered L2 discrepancy (CD).

    pip install ./python scipy && python examples/python/compare_samplers.py [N]
"""

import sys

import numpy as np
from scipy.stats import qmc as sqmc

import paracosm
from paracosm import qmc

n = int(sys.argv[1]) if len(sys.argv) > 1 else 256
scenario = paracosm.Scenario("pedestrian-crossing")
d = len(scenario.space)
samplers = {
    "scipy Halton (scrambled, rng=0)": sqmc.Halton(d, rng=0),
    "scipy Sobol (scrambled, rng=0)": sqmc.Sobol(d, rng=0),
    "scipy LatinHypercube (rng=0)": sqmc.LatinHypercube(d, rng=0),
    "paracosm Halton (paper, unscrambled)": qmc.Halton(d),
    "paracosm Halton (scrambled, rng=0)": qmc.Halton(d, scramble=True, rng=0),
    "paracosm Sobol (Owen-scrambled, rng=0)": qmc.Sobol(d, rng=0),
    "numpy uniform random (seed 0)": None,
}

print(f"{scenario.name}: {d} parameters ({', '.join(scenario.space.names)}), {n} tests each\n")
print(f"| sampler | failures | dispersion | star discrepancy | CD |")
print(f"|---|---:|---:|---:|---:|")
for name, engine in samplers.items():
    x = np.random.default_rng(0).random((n, d)) if engine is None else engine.random(n)
    records = scenario.run(x, seed=0, output="records")  # no pandas needed
    failures = sum(r["status"] == "fail" for r in records)
    disp = qmc.dispersion(x)
    star = qmc.star_discrepancy(x)
    show = lambda b: f"{b.lower:.4f}" if b.exact else f"[{b.lower:.4f}, {b.upper:.4f}]"
    print(f"| {name} | {failures} | {show(disp)} | {show(star)} | {qmc.discrepancy(x):.2e} |")
