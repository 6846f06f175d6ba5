#!/usr/bin/env python3
"""Writes the scikit-learn reference that paracosm's Gaussian process is tested against
(generators/src/falsify/gp/tests.rs, `matches_scikit_learn`).

    target/py-venv/bin/pip install scikit-learn==1.9.1
    target/py-venv/bin/python experiments/bench/gp_reference.py > generators/tests/data/gp_sklearn.json

The data: 14 inputs in the unit square from a fixed formula, targets from a smooth function
with a step. The kernel is scikit-learn's `ConstantKernel * Matern(nu=2.5, ARD) + WhiteKernel`
with `normalize_y=True`; paracosm's `Hyper` orders the same parameters as
`(ln l_1, ln l_2, ln sf2, ln sn2)` where scikit-learn's theta is `(ln sf2, ln l_1, ln l_2, ln sn2)`.
"""

import json
import math

import numpy as np
import sklearn
from sklearn.gaussian_process import GaussianProcessRegressor
from sklearn.gaussian_process.kernels import ConstantKernel, Matern, WhiteKernel

x = np.array([[(0.37 * i + 0.11) % 1.0, (0.61 * i * i + 0.05) % 1.0] for i in range(14)])
y = np.array([math.sin(6.0 * a) + 0.5 * b * b + (1.0 if a > 0.6 else 0.0) for a, b in x])
queries = np.array([[0.1, 0.2], [0.5, 0.5], [0.93, 0.07], [0.33, 0.81], [0.7, 0.4]])

out = {"sklearn": sklearn.__version__, "x": x.tolist(), "y": y.tolist(), "queries": queries.tolist(),
       "fixed": [], "optimised": None}
for sf2, l1, l2, sn2 in [(1.0, 0.3, 0.5, 1e-4), (2.5, 0.12, 1.7, 0.03)]:
    kernel = (ConstantKernel(sf2, "fixed") * Matern([l1, l2], "fixed", nu=2.5)
              + WhiteKernel(sn2, "fixed"))
    gp = GaussianProcessRegressor(kernel, optimizer=None, normalize_y=True, alpha=0.0).fit(x, y)
    mean, std = gp.predict(queries, return_std=True)
    free = (ConstantKernel(sf2) * Matern([l1, l2], nu=2.5) + WhiteKernel(sn2))
    theta = np.log([sf2, l1, l2, sn2])
    gpf = GaussianProcessRegressor(free, optimizer=None, normalize_y=True, alpha=0.0).fit(x, y)
    lml, grad = gpf.log_marginal_likelihood(theta, eval_gradient=True)
    out["fixed"].append({
        "hyper": {"length": [l1, l2], "signal": sf2, "noise": sn2},
        "mean": mean.tolist(),
        # predict's std includes the WhiteKernel's noise; paracosm's is the latent f's.
        "std_with_noise": std.tolist(),
        "lml": float(lml),
        # reordered to paracosm's (ln l_1, ln l_2, ln sf2, ln sn2)
        "lml_gradient": [float(grad[1]), float(grad[2]), float(grad[0]), float(grad[3])],
    })
bounds = {"length": (0.01, 10.0), "signal": (0.01, 100.0), "noise": (1e-8, 1.0)}
kernel = (ConstantKernel(1.0, bounds["signal"]) * Matern([0.5, 0.5], bounds["length"], nu=2.5)
          + WhiteKernel(1e-3, bounds["noise"]))
gp = GaussianProcessRegressor(kernel, normalize_y=True, alpha=0.0, n_restarts_optimizer=8,
                              random_state=0).fit(x, y)
out["optimised"] = {"lml": float(gp.log_marginal_likelihood_value_),
                    "theta": gp.kernel_.theta.tolist()}
print(json.dumps(out, indent=1))
