#!/usr/bin/env python3
"""Falsify a driving scenario with scipy's differential evolution.

The ego vehicle (built-in `aeb` system under test) follows a lead car that brakes
(`follow-lead-car`, PARACOSM section 4.2.2). Each evaluation is one closed-loop test;
its robustness (metres; <= 0 means a monitor failed) is what the optimiser minimises over
the unit cube of the scenario's 6 parameters (two of them levels, read as
floor(u * levels)). The search stops at the first failure.

    pip install ./python scipy && python examples/python/falsify_with_scipy.py
"""

import time

import numpy as np
from scipy.optimize import differential_evolution

import paracosm

scenario = paracosm.Scenario("follow-lead-car")
d = len(scenario.space)
evaluations = []


def robustness(x):
    r = scenario.robustness(x)
    evaluations.append((x.copy(), r))
    return r


def stop_at_failure(intermediate_result):
    return intermediate_result.fun <= 0.0


t0 = time.perf_counter()
result = differential_evolution(
    robustness,
    bounds=[(0.0, 1.0)] * d,
    popsize=10,
    maxiter=40,
    tol=0.0,  # the collision margin has plateaus (the AEB stops 1.7 m short): never "converged"
    init="sobol",
    seed=1,
    polish=False,
    callback=stop_at_failure,
)
elapsed = time.perf_counter() - t0

first = next((i for i, (_, r) in enumerate(evaluations) if r <= 0.0), None)
print(f"scenario {scenario.name}: {d} parameters {scenario.space.names}")
print(f"differential evolution: {len(evaluations)} tests in {elapsed:.1f} s, best robustness {result.fun:.3f} m")
print(f"  (tests 1-{10 * d} are its initial population, a scrambled Sobol design)")
if first is None:
    print("no failure found")
else:
    x, r = evaluations[first]
    print(f"first failure at test {first + 1}: robustness {r:.3f} m")
    (point,) = scenario.space.to_units(np.array([x]))
    for p in scenario.space:
        v = point[p.name]
        unit = f" {p.unit}" if p.unit else ""
        print(f"  {p.name:<11} = {v:.3f}{unit}" if isinstance(v, float) else f"  {p.name:<11} = {v}")
    record = scenario.run([point], output="records")[0]
    print(f"  status {record['status']}; monitors: " + ", ".join(
        f"{name} {'passed' if m['passed'] else 'FAILED'} ({m['robustness']:.3f})" for name, m in record["monitors"].items()
    ))
