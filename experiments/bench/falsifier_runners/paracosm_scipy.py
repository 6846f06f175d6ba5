"""Runners of paracosm's own strategies (through `paracosm.falsify`, the same generators as
`paracosm-fuzz --strategy`) and of scipy's global optimisers."""

from scipy.optimize import differential_evolution, dual_annealing

from paracosm.falsify import Falsifier

PARACOSM = ["random", "halton-scrambled", "sobol", "falsify-nm", "falsify-pso", "falsify-sa",
            "falsify-ce", "falsify-bo", "falsify-bo-lcb"]
SCIPY = ["scipy-dual-annealing", "scipy-differential-evolution"]
TOOLS = [f"paracosm:{s}" for s in PARACOSM] + SCIPY


def _paracosm(strategy):
    def run(fun, d, seed, cap):
        f = Falsifier(strategy, d, seed=seed)
        while True:
            batch = f.ask(f.batch or 16)
            values = []
            try:
                for x in batch:
                    values.append(fun(x))
            finally:
                f.tell(values)
    return run


def _dual_annealing(fun, d, seed, cap):
    dual_annealing(fun, [(0.0, 1.0)] * d, maxfun=10 * cap, seed=seed)


def _differential_evolution(fun, d, seed, cap):
    # polish=False: the L-BFGS-B polish spends evaluations on finite differences.
    differential_evolution(fun, [(0.0, 1.0)] * d, popsize=10, maxiter=10 * cap, tol=0.0,
                           init="sobol", seed=seed, polish=False)


def runner(tool: str):
    if tool.startswith("paracosm:"):
        return _paracosm(tool.split(":", 1)[1])
    return {"scipy-dual-annealing": _dual_annealing,
            "scipy-differential-evolution": _differential_evolution}[tool]
