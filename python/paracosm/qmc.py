"""Samplers and coverage estimators of the unit cube, with the names and conventions of
`scipy.stats.qmc`.

- `Halton(d, *, scramble=False, rng=None)` and `Sobol(d, *, scramble=True, rng=None)`:
  `.random(n)` returns an `(n, d)` float64 array in [0, 1), continuing the sequence.
- `discrepancy(sample, *, method="CD")`: equal to `scipy.stats.qmc.discrepancy` (CD, WD and
  MD squared, L2-star square-rooted, as scipy returns them).
- `star_discrepancy(sample)` and `dispersion(sample)`: the L-infinity star discrepancy and
  the largest empty box (PARACOSM paper, section 3.1), exact where the algorithms allow
  and otherwise a certified bracket: a `Bracket` with `lower`, `upper`, `exact`, `box`.

Where the defaults differ from scipy's:

- `Halton` is unscrambled by default (scipy: `scramble=True`): the sequence of the
  PARACOSM paper and of `paracosm-fuzz --strategy halton`, equal to
  `scipy.stats.qmc.Halton(d, scramble=False)` point for point, to 4.4e-16: paracosm's
  values are the correctly rounded radical inverses while `q^k < 2**53` (for the first 8
  bases, every index below 2e15), scipy adds digit terms in floats (up to 3 ulp off, 3.3e-16,
  on 20,000 points in d = 8). At most
  `HALTON_MAX_DIMENSIONS` (65,536) dimensions and `HALTON_MAX_INDEX` (2**53) points: past
  that index a radical inverse has more bits than a float64. `scramble=True` permutes
  every base digit (Owen, "A randomized Halton algorithm in R", 2017), not scipy's
  permutations, so scrambled values differ from scipy's.
- `Sobol` is always Owen-scrambled (hash-based, Burley, "Practical Hash-based Owen
  Scrambling", JCGT 2020, via the `sobol_burley` crate; scipy uses a linear matrix scramble
  with a digital shift). Its values have 24 bits (float32 precision) and it holds at most
  65,536 points in at most 256 dimensions. `scramble=False` is refused.

Every computation runs in Rust with the GIL released, on all cores (rayon); results do not
depend on the number of threads.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from . import _native
from ._check import positive_int, seed_of, unit_matrix

__all__ = ["Bracket", "Halton", "Sobol", "discrepancy", "dispersion", "star_discrepancy"]

SOBOL_MAX_POINTS: int = _native.SOBOL_MAX_POINTS
"""Points a `Sobol` sequence holds: 2**16."""
SOBOL_MAX_DIMENSIONS: int = _native.SOBOL_MAX_DIMENSIONS
"""Dimensions a `Sobol` sequence supports."""
HALTON_MAX_DIMENSIONS: int = _native.HALTON_MAX_DIMENSIONS
"""Dimensions a `Halton` sequence supports: 2**16."""
HALTON_MAX_INDEX: int = _native.HALTON_MAX_INDEX
"""Points a `Halton` sequence holds: 2**53."""


class _Engine:
    """What the two sequences share: scipy's `random`, `reset`, `fast_forward`."""

    def __init__(self, d: int, engine):
        self.d = d
        self._engine = engine

    @property
    def num_generated(self) -> int:
        """How many points were drawn (the index of the next one)."""
        return self._engine.num_generated

    def random(self, n: int = 1) -> np.ndarray:
        """The next `n` points: an `(n, d)` float64 array in [0, 1), row-major."""
        n = positive_int(n, "n", minimum=0)
        return self._engine.random(n)

    def reset(self):
        """Back to the first point. Returns self."""
        self._engine.seek(0)
        return self

    def fast_forward(self, n: int):
        """Skips `n` points. Returns self."""
        n = positive_int(n, "n", minimum=0)
        self._engine.seek(self._engine.num_generated + n)
        return self


class Halton(_Engine):
    """The Halton sequence in `d` dimensions (radical inverses in the first `d` primes).

    `scramble=False` (the default, unlike scipy's): the plain sequence from index 0, equal to
    `scipy.stats.qmc.Halton(d, scramble=False)` to 4.4e-16 (these are correctly rounded). `scramble=True`: random digit permutations
    (Owen 2017) drawn from `rng` (None: fresh entropy; an int seed; or a
    `numpy.random.Generator`).

    Raises ValueError for `d` < 1, past `HALTON_MAX_DIMENSIONS` or not an integer, or a bad
    `rng`; `random` and `fast_forward` raise ValueError past index `HALTON_MAX_INDEX`, and
    `random` MemoryError for an array that cannot be allocated.
    """

    def __init__(self, d: int, *, scramble: bool = False, rng=None):
        d = positive_int(d, "d")
        self.scramble = bool(scramble)
        if self.scramble:
            seed = seed_of(rng)
        else:
            # A bad rng is refused even where it is not used; a good one is not drawn from.
            if rng is not None and not isinstance(rng, np.random.Generator):
                seed_of(rng)
            seed = None
        super().__init__(d, _native.HaltonEngine(d, seed))


class Sobol(_Engine):
    """Owen-scrambled Sobol points in `d` dimensions (1 <= d <= 256), at most 65,536 points.

    The scramble is drawn from `rng` (None: fresh entropy; an int seed; or a
    `numpy.random.Generator`). As scipy's, `random(n)` warns when the points drawn so far
    stop being a power of 2 (the balance properties of Sobol points need it), and
    `random_base2(m)` draws `2**m` points and refuses to break the balance.

    Raises ValueError for `scramble=False` (not available: use
    `scipy.stats.qmc.Sobol(d, scramble=False)`), `d` out of range, a bad `rng`, or more points
    than the sequence holds.
    """

    def __init__(self, d: int, *, scramble: bool = True, rng=None):
        d = positive_int(d, "d")
        if not scramble:
            raise ValueError(
                "paracosm's Sobol points are always Owen-scrambled (sobol_burley); "
                "for the unscrambled sequence use scipy.stats.qmc.Sobol(d, scramble=False)"
            )
        if d > SOBOL_MAX_DIMENSIONS:
            raise ValueError(f"d = {d} is more than the {SOBOL_MAX_DIMENSIONS} dimensions Sobol supports")
        self.scramble = True
        super().__init__(d, _native.SobolEngine(d, seed_of(rng)))

    def random(self, n: int = 1) -> np.ndarray:
        n = positive_int(n, "n", minimum=0)
        total = self.num_generated + n
        if n > 0 and total & (total - 1) != 0:
            warnings.warn(
                "The balance properties of Sobol' points require n to be a power of 2.",
                stacklevel=2,
            )
        return self._engine.random(n)

    def random_base2(self, m: int) -> np.ndarray:
        """The next `2**m` points; ValueError when the points drawn so far and these would not
        be a power of 2 in all."""
        m = positive_int(m, "m", minimum=0, maximum=16)
        n = 2**m
        total = self.num_generated + n
        if total & (total - 1) != 0:
            raise ValueError(
                "The balance properties of Sobol' points require n to be a power of 2. "
                f"{self.num_generated} points have been previously generated, then: "
                f"n={self.num_generated}+2**{m}={total}."
            )
        return self._engine.random(n)


_METHODS = ("CD", "WD", "MD", "L2-star")


def discrepancy(sample, *, method: str = "CD") -> float:
    """The discrepancy of `sample` (`(n, d)`, values in [0, 1]), as
    `scipy.stats.qmc.discrepancy(sample, method=method)` (the same bits, for scipy 1.17):

    - `CD`: centered L2, squared (Hickernell, Math. Comp. 67, 1998, eq. 3.7c);
    - `WD`: wrap-around L2, squared (Hickernell 1998, eq. 3.8b);
    - `MD`: mixture, squared (Zhou, Fang, Ning, J. Complexity 29, 2013);
    - `L2-star`: L2-star, square-rooted (Warnock's formula, 1972).

    O(d n^2) time, in parallel with the GIL released; the same value on any thread count.
    Raises ValueError for an unknown method, a sample that is not a non-empty 2-D array of
    real numbers, NaN, or a value outside [0, 1]; MemoryError when the sums' working memory
    (about (2d + 130) x 8 bytes a point) cannot be allocated.
    """
    if method not in _METHODS:
        raise ValueError(f"method {method!r} is not one of {', '.join(map(repr, _METHODS))}")
    return _native.discrepancy(unit_matrix(sample, "sample"), method)


@dataclass(frozen=True)
class Bracket:
    """An estimate that is exact or a certified bracket: the true value lies in
    `[lower, upper]`, and `lower == upper` when `exact`.

    `box` is the witness, a `(2, d)` array `[lo, hi]`: for the star discrepancy the anchored
    box `[0, y)` where the local discrepancy is `lower` (`lo` is zeros); for the dispersion the
    largest empty open box found (volume `lower`). `method` says how the numbers were found.
    """

    lower: float
    upper: float
    exact: bool
    box: np.ndarray
    method: str


def star_discrepancy(sample, *, seed: int = 0) -> Bracket:
    """The L-infinity star discrepancy `sup_y |#(P in [0, y))/n - vol([0, y))|` of `sample`
    (`(n, d)`, values in [0, 1]).

    Exact for d <= 4 (n <= 20,000 for d = 2, 4,096 for d = 3, 256 for d = 4): by enumerating
    the critical grid (Bundschuh and Zhu, 1993) for d <= 2, by a sweep with blocked upper
    envelopes (Dobkin, Eppstein and Mitchell, 1996) for d = 3, by one such sweep per prefix
    along the first axis for d = 4. Otherwise a bracket: the lower bound from a coordinate
    ascent over the grid (from random starts drawn by `seed`), the upper one from Thiemard's
    delta-cover (J. Complexity 17, 2001); `method` says how far the exact value can be from
    the lower end (upper / lower). Past n² · d = 5e7 (d = 8, n = 2,500) the search is skipped
    and the lower end is the largest one-axis star discrepancy; past d = 64 the upper end is 1.
    A `RuntimeWarning` says when the bracket is loose (upper at least twice lower). Raises
    ValueError as `discrepancy` does; MemoryError when its working memory (about 32d + 64
    bytes a point) cannot be allocated.
    """
    a = unit_matrix(sample, "sample")
    lower, upper, exact, corner, method = _native.star_discrepancy(
        a, positive_int(seed, "seed", minimum=0, maximum=2**64 - 1)
    )
    if not exact and (upper >= 1.0 or upper > 2.0 * lower):
        warnings.warn(f"star_discrepancy gives a loose bracket: {method}", RuntimeWarning, stacklevel=2)
    corner = np.asarray(corner, dtype=np.float64)
    return Bracket(lower, upper, exact, np.stack([np.zeros_like(corner), corner]), method)


def dispersion(sample, *, seed: int = 0) -> Bracket:
    """The dispersion of `sample` (`(n, d)`, values in [0, 1]): the largest volume of an open
    axis-parallel box inside [0, 1]^d holding no point (PARACOSM, section 3.1).

    Exact for d <= 2, and for d >= 3 up to n = 10,000 (d = 3), 1,000 (d = 4), 120 (d = 5) and
    60 (d = 6); for d >= 7, and past those sizes, a certified bracket (greedy boxes from starts
    drawn by `seed` below, a branch and bound above) whose `method` says how far the exact
    value can be from the lower end. No other library computes it exactly. Raises ValueError
    as `discrepancy` does; MemoryError when its working memory (about 32d + 64 bytes a point)
    cannot be allocated.
    """
    a = unit_matrix(sample, "sample")
    lower, upper, exact, lo, hi, method = _native.dispersion(
        a, positive_int(seed, "seed", minimum=0, maximum=2**64 - 1)
    )
    return Bracket(lower, upper, exact, np.array([lo, hi], dtype=np.float64), method)
