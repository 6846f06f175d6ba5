"""paracosm's falsifiers on any objective over the unit cube, from Python.

- `Falsifier(strategy, d, *, seed=0)`: one of `paracosm-fuzz`'s strategies in ask/tell form:
  the adaptive ones (`falsify-bo`, `falsify-bo-lcb`, `falsify-nm`, `falsify-pso`,
  `falsify-sa`, `falsify-ce`) and the samplers (`random`, `halton`, `halton-scrambled`,
  `sobol`). The same generator as a campaign over `d` continuous parameters, so the same points
  for the same seed and robustness values.
- `falsify(fun, d, ...)`: the loop around it: asks a batch, evaluates `fun` (robustness, `<= 0`
  a failure) at each point, tells the values back, until the budget is spent or, by default,
  the first failure.

A scenario's robustness is `paracosm.Scenario(name).robustness`, so

    falsify(paracosm.Scenario("follow-lead-car").robustness, 6, strategy="falsify-bo")

searches a driving scenario the way `paracosm-fuzz --strategy falsify-bo` does, through the
same entry point as scipy's or any other Python optimiser (`experiments/bench/falsifiers.py`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from . import _native

__all__ = ["Falsifier", "FalsifyResult", "falsify"]


class Falsifier:
    """A paracosm strategy over `[0, 1)^d` in ask/tell form (see the module docs).

    Raises `ValueError` for an unknown strategy, one that needs a budget or a list of
    points (`ipog`, `kwise`, `points`), or `d < 1`.
    """

    def __init__(self, strategy: str, d: int, *, seed: int = 0):
        if int(d) != d or d < 1:
            raise ValueError(f"d must be a positive integer, got {d!r}")
        if int(seed) != seed or seed < 0:
            raise ValueError(f"seed must be a non-negative integer, got {seed!r}")
        self._engine = _native.FalsifierEngine(str(strategy), int(d), int(seed))
        self.strategy = str(strategy)
        self.d = int(d)

    @property
    def batch(self) -> int | None:
        """Points per batch of an adaptive strategy; None for a sampler."""
        return self._engine.batch

    @property
    def pending(self) -> int:
        """Points asked for and not yet told."""
        return self._engine.pending

    def ask(self, n: int | None = None) -> np.ndarray:
        """Up to `n` points (default: one batch, or 1 for a sampler) as a `(k, d)` array in
        [0, 1); fewer, possibly none, while an adaptive strategy waits for `tell`."""
        if n is None:
            n = self.batch or 1
        if int(n) != n or n < 0:
            raise ValueError(f"n must be a non-negative integer, got {n!r}")
        return self._engine.ask(int(n))

    def tell(self, robustness) -> None:
        """Robustness of the oldest points asked for and not yet told, in that order (NaN for
        a test that errored)."""
        r = np.ascontiguousarray(np.atleast_1d(np.asarray(robustness, dtype=np.float64)))
        if r.ndim != 1:
            raise ValueError(f"robustness must be one value per point, got shape {r.shape}")
        self._engine.tell(r)


@dataclass
class FalsifyResult:
    """What `falsify` found: the point of lowest robustness and the whole history."""

    x: np.ndarray
    """The point of lowest robustness, in [0, 1)^d."""
    fun: float
    """Its robustness (<= 0: a failure)."""
    nfev: int
    """Evaluations made."""
    first_failure: int | None
    """1-based index of the first evaluation with robustness <= 0, None if there was none."""
    xs: np.ndarray = field(repr=False)
    """Every point evaluated, `(nfev, d)`, in order."""
    values: np.ndarray = field(repr=False)
    """Their robustness, `(nfev,)`."""


def falsify(fun, d: int, *, strategy: str = "falsify-bo", budget: int = 100, seed: int = 0,
            stop_at_first_failure: bool = True) -> FalsifyResult:
    """Minimises `fun` (a point of [0, 1)^d to its robustness) with a paracosm strategy: at most
    `budget` evaluations, stopping after the first with robustness <= 0 unless
    `stop_at_first_failure` is False. A NaN from `fun` counts as a test that errored.

    Raises `ValueError` for a budget below 1, as `Falsifier` for the others."""
    if int(budget) != budget or budget < 1:
        raise ValueError(f"budget must be a positive integer, got {budget!r}")
    f = Falsifier(strategy, d, seed=seed)
    xs, values = [], []
    first = None
    while len(values) < budget:
        batch = f.ask(min(f.batch or 1, budget - len(values)))
        if len(batch) == 0:
            raise RuntimeError(f"{strategy} asked for nothing with no point pending (a defect)")
        told = []
        for x in batch:
            r = float(fun(x))
            xs.append(x)
            values.append(r)
            told.append(r)
            if first is None and r <= 0.0:
                first = len(values)
                if stop_at_first_failure:
                    break
        f.tell(told)
        if first is not None and stop_at_first_failure:
            break
    v = np.asarray(values)
    finite = np.where(np.isnan(v), math.inf, v)
    best = int(np.argmin(finite))
    return FalsifyResult(x=np.asarray(xs[best]), fun=float(v[best]), nfev=len(values),
                         first_failure=first, xs=np.asarray(xs), values=v)
