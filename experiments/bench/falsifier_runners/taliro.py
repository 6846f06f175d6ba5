"""Run PSY-TaLiRo's optimizers on a black-box objective over [0,1]^d (experiments/bench/falsifiers.py's
`psy-taliro` family; `python taliro.py` runs a self-test in the family's environment).

Installed version (``/tmp/taliro-venv/bin/pip show psy-taliro``)::

    Name: psy-taliro
    Version: 3.2.0
    (with scipy 1.17.1, numpy 2.4.6, pathos 0.3.5, attrs 26.1.0)

Optimizers shipped by psy-taliro 3.2 (``staliro/optimizers.py``):

* ``uniform-random`` -> ``staliro.optimizers.UniformRandom``: pure random search. It makes
  ``numpy.random.default_rng(params.seed)``, draws *all* ``params.budget`` samples up front
  (``rng.uniform(lo, hi)`` per coordinate) and then evaluates them in order; with no
  ``min_cost`` it evaluates every sample (``eval_samples``), with ``min_cost`` it stops at the
  first cost strictly ``< min_cost``. It learns nothing from the costs.
* ``dual-annealing`` -> ``staliro.optimizers.DualAnnealing``: a thin wrapper around
  ``scipy.optimize.dual_annealing(func, bounds, rng=params.seed, maxfun=params.budget,
  no_local_search=True, callback=...)``, i.e. generalised simulated annealing (Tsallis/Stariolo
  visiting distribution, with re-annealing restarts) with SciPy's local-search phase turned off.
  It starts from one uniform random point, then each annealing iteration is a Markov chain of
  ``2*d`` visits; it stops when SciPy's ``maxfun`` (= budget) is reached, after ``maxiter=1000``
  iterations (``1 + 2000*d`` evaluations, e.g. 2001 measured for d=1, cap=5000 - so a
  ``cap`` above that is never reached), or when the callback (``cost < min_cost``,
  strict, and only called on a *new best found inside a chain*, not for the initial point)
  asks it to.

How :func:`run` uses the API: a ``@staliro.costfunc`` cost function, a ``staliro.TestOptions``
with one static input per dimension, ``x0..x{d-1}``, each bounded by ``(0.0, 1.0)``, ``iterations=cap``
(this *is* the optimizer's budget: ``Optimizer.Params.budget = options.iterations``),
``runs=1``, ``seed=seed + 1`` (TestOptions requires ``seed > 0``; the optimizer's real seed is
``default_rng(options.seed).integers(0, 2**32 - 1)``), no ``processes``/``threads``, and
``staliro.staliro(costfn, optimizer, options, processes=None)`` - so everything is evaluated
sequentially in this process. Neither optimizer can stop at a cost ``<= 0`` (``min_cost`` is a
strict ``<`` test, and DualAnnealing's callback never sees the initial point), so the cost
function raises a private exception right after recording the first value ``<= 0`` (or the
``cap``-th value) and :func:`run` catches it; psy-taliro 3.2 has no ``try/except`` on this path,
so the exception propagates out of ``staliro()`` untouched.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import staliro
from staliro.optimizers import DualAnnealing, UniformRandom

OPTIMIZERS: list[str] = ["uniform-random", "dual-annealing"]


class _Stop(Exception):
    """Raised inside the cost function to end a search early (never escapes :func:`run`)."""


def _make_optimizer(name: str):
    # min_cost is left unset on purpose: the cost function below stops the run itself on the
    # first value <= 0, which always happens before a strict `< min_cost` test could fire.
    if name == "uniform-random":
        return UniformRandom()
    if name == "dual-annealing":
        return DualAnnealing()
    raise ValueError(f"unknown optimizer {name!r}; expected one of {OPTIMIZERS}")


def run(fun: Callable[[np.ndarray], float], d: int, seed: int, cap: int, optimizer: str) -> list[float]:
    """Minimise fun (a callable taking a numpy array of length d in [0,1]^d, returning a float
    'robustness'; <= 0 means falsified) with PSY-TaLiRo's optimizer `optimizer`, at most `cap`
    evaluations, stopping right after the first evaluation whose value is <= 0.
    Returns the list of values in evaluation order (so len(list) is the number of evaluations,
    and the index of the first value <= 0 gives tests-to-first-failure)."""
    if optimizer not in OPTIMIZERS:
        raise ValueError(f"unknown optimizer {optimizer!r}; expected one of {OPTIMIZERS}")
    d, seed, cap = int(d), int(seed), int(cap)
    if d < 1:
        raise ValueError("d must be >= 1")
    if seed < 0:
        raise ValueError("seed must be >= 0")
    if cap <= 0:
        return []

    values: list[float] = []

    @staliro.costfunc
    def cost(inputs: staliro.Inputs) -> float:
        x = np.array(inputs.sample.values, dtype=float, copy=True)
        v = float(fun(x))
        values.append(v)
        if v <= 0.0 or len(values) >= cap:
            raise _Stop
        return v

    options = staliro.TestOptions(
        static_inputs={f"x{i}": (0.0, 1.0) for i in range(d)},
        iterations=cap,
        runs=1,
        seed=seed + 1,  # TestOptions validates seed > 0
        processes=None,
        threads=None,
    )
    try:
        staliro.staliro(cost, _make_optimizer(optimizer), options, processes=None)
    except _Stop:
        pass
    return values


TOOLS = [f"psy-taliro:{o}" for o in OPTIMIZERS]


def runner(tool: str):
    """The bench's runner for `psy-taliro:<optimizer>` (falsifiers.py stops it by exception)."""
    optimizer = tool.split(":", 1)[1]
    return lambda fun, d, seed, cap: run(fun, d, seed, cap, optimizer)


def _selftest() -> None:
    def f(x: np.ndarray) -> float:
        return math.hypot(x[0] - 0.83, x[1] - 0.21) - 0.03

    cap = 300
    for name in OPTIMIZERS:
        for seed in (0, 1):
            a = run(f, 2, seed, cap, name)
            b = run(f, 2, seed, cap, name)
            assert a == b, f"{name} seed {seed}: not deterministic"
            assert 1 <= len(a) <= cap
            first = next((i for i, v in enumerate(a) if v <= 0), None)
            if first is not None:
                assert first == len(a) - 1, "must stop right after the first failure"
            else:
                assert len(a) == cap and all(v > 0 for v in a)
            print(f"{name:15s} seed={seed} evals={len(a):3d} falsified={first is not None}"
                  f" min={min(a):+.4f} deterministic=True")
    # different seeds give different searches
    for name in OPTIMIZERS:
        assert run(f, 2, 0, 20, name) != run(f, 2, 1, 20, name)
    # cap is respected on an unfalsifiable function, and a run is not cut short
    for name in OPTIMIZERS:
        vals = run(lambda x: 1.0 + float(np.sum(x)), 3, 0, 50, name)
        assert len(vals) == 50 and all(v > 0 for v in vals), (name, len(vals))
    # immediate failure: stops after exactly one evaluation (DualAnnealing's initial point)
    for name in OPTIMIZERS:
        assert run(lambda x: -1.0, 4, 0, 50, name) == [-1.0]
    # inputs are length-d arrays inside [0,1]
    seen: list[np.ndarray] = []

    def g(x: np.ndarray) -> float:
        seen.append(x)
        return 1.0

    for name in OPTIMIZERS:
        seen.clear()
        run(g, 5, 3, 30, name)
        assert len(seen) == 30 and all(x.shape == (5,) and np.all((x >= 0) & (x <= 1)) for x in seen)
    try:
        run(f, 2, 0, 10, "nope")
    except ValueError:
        pass
    else:
        raise AssertionError("unknown optimizer accepted")
    print("self-test OK")


if __name__ == "__main__":
    _selftest()
