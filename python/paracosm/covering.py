"""Covering arrays and k-wise coverage (PARACOSM paper, section 3.2), as `paracosm-cover`
builds and measures them.

- `covering_array(levels, strength, *, algorithm="ipog", constraints=None, rng=None)`: an
  `(N, k)` int64 array of level indices in which every `strength`-tuple of levels of every
  `strength` columns appears in some row (a covering array of strength t).
- `kwise_coverage(array, levels, strength, *, constraints=None)`: the fraction of those
  tuples an array covers.

Constraints are forbidden combinations, each a dict `{column: level}` (PICT's
`IF [A] = "x" THEN [B] <> "y"` forbids `{A: x, B: y}`): no row holds one, and tuples no
allowed row can hold are not counted.
"""

from __future__ import annotations

import numbers
from dataclasses import dataclass, field

import numpy as np

from . import _native
from ._check import positive_int, seed_of

__all__ = ["KWiseCoverage", "covering_array", "kwise_coverage"]

_ALGORITHMS = ("ipog", "kwise", "random")
MAX_STRENGTH = 6
"""The largest strength supported."""


def _levels(levels) -> list[int]:
    try:
        items = list(levels)
    except TypeError:
        raise ValueError(f"levels must be a sequence of level counts, not {levels!r}") from None
    if not items:
        raise ValueError("levels is empty: give one level count per column")
    out = []
    for j, v in enumerate(items):
        if isinstance(v, (bool, np.bool_)) or not isinstance(v, numbers.Integral):
            raise ValueError(f"levels[{j}] = {v!r} is not an integer")
        if not 1 <= v < 2**31:
            raise ValueError(f"levels[{j}] = {v} must be at least 1")
        out.append(int(v))
    return out


def _strength(strength, k: int) -> int:
    t = positive_int(strength, "strength")
    top = min(MAX_STRENGTH, k)
    if t > top:
        raise ValueError(f"strength {t} is not in 1..{top} for {k} columns")
    return t


def _forbidden(constraints, levels: list[int]) -> list[list[tuple[int, int]]]:
    if constraints is None:
        return []
    out = []
    for i, c in enumerate(constraints):
        if not isinstance(c, dict) or not c:
            raise ValueError(
                f"constraints[{i}] must be a non-empty dict {{column: level}}, not {c!r}"
            )
        cells = []
        for col, lev in c.items():
            for what, v in (("column", col), ("level", lev)):
                if isinstance(v, (bool, np.bool_)) or not isinstance(v, numbers.Integral):
                    raise ValueError(f"constraints[{i}]: {what} {v!r} is not an integer")
            if not 0 <= col < len(levels):
                raise ValueError(f"constraints[{i}]: column {col} is not in 0..{len(levels) - 1}")
            if not 0 <= lev < levels[col]:
                raise ValueError(
                    f"constraints[{i}]: level {lev} of column {col} is not in 0..{levels[col] - 1}"
                )
            cells.append((int(col), int(lev)))
        out.append(cells)
    return out


def covering_array(levels, strength: int, *, algorithm: str = "ipog", constraints=None, rng=None) -> np.ndarray:
    """A covering array of strength `strength` over `len(levels)` columns, column `j` with
    `levels[j]` levels: an `(N, k)` int64 array of level indices in `[0, levels[j])`.

    - `ipog`: deterministic IPOG (Lei et al., "IPOG: a general strategy for t-way software
      testing", ECBS 2007); `rng` must be None.
    - `kwise`: random rows, as many as the paper's Proposition 3.2 needs for all tuples with
      probability 0.99 (not guaranteed: check with `kwise_coverage`).
    - `random`: random rows until every tuple is covered.

    The random algorithms draw from `rng` (None: fresh entropy; an int seed; a
    `numpy.random.Generator`). Raises ValueError for bad levels, a strength outside
    1..min(6, k), an unknown algorithm, or a constraint naming a column or level that does
    not exist or that leaves some row impossible.
    """
    lv = _levels(levels)
    t = _strength(strength, len(lv))
    if algorithm not in _ALGORITHMS:
        raise ValueError(f"algorithm {algorithm!r} is not one of {', '.join(map(repr, _ALGORITHMS))}")
    if algorithm == "ipog" and rng is not None:
        raise ValueError("ipog is deterministic: rng applies to algorithm 'kwise' or 'random'")
    seed = 0 if algorithm == "ipog" else seed_of(rng)
    return _native.covering_array(lv, t, algorithm, _forbidden(constraints, lv), seed)


@dataclass(frozen=True)
class KWiseCoverage:
    """k-wise coverage of an array: `covered` of the `total` t-tuples of levels appear in some
    row; `fraction = covered / total` (1 when there is none). `missing` lists up to 20
    uncovered tuples, each a tuple of `(column, level)` pairs (empty with constraints)."""

    strength: int
    covered: int
    total: int
    fraction: float
    missing: list = field(default_factory=list)

    def __float__(self) -> float:
        return self.fraction


def kwise_coverage(array, levels, strength: int, *, constraints=None) -> KWiseCoverage:
    """The t-wise coverage (t = `strength`) of `array`, an `(n, k)` array of level indices,
    column `j` in `[0, levels[j])`. With `constraints`, tuples that no allowed row can hold
    are left out of the total (PICT's convention).

    Exact (a bitset per column subset), in parallel with the GIL released. Raises
    ValueError for an array that is not 2-D with `len(levels)` columns of integers, a level
    index out of range (naming the cell), or a bad strength or constraint.
    """
    lv = _levels(levels)
    t = _strength(strength, len(lv))
    a = np.asarray(array)
    if a.dtype == np.bool_ or not np.issubdtype(a.dtype, np.integer):
        raise ValueError(f"array must hold integer level indices, not dtype {a.dtype}")
    if a.ndim != 2 or a.shape[1] != len(lv):
        raise ValueError(f"array must have shape (n, {len(lv)}) (one column per level count), got {a.shape}")
    a = np.ascontiguousarray(a, dtype=np.int64)
    bad = (a < 0) | (a >= np.asarray(lv, dtype=np.int64)[None, :])
    if bad.any():
        i, j = np.argwhere(bad)[0]
        raise ValueError(f"array[{i}, {j}] = {a[i, j]} is not a level of column {j} (0..{lv[j] - 1})")
    covered, total, missing = _native.kwise_coverage(a, lv, t, _forbidden(constraints, lv), 20)
    return KWiseCoverage(
        strength=t,
        covered=covered,
        total=total,
        fraction=1.0 if total == 0 else covered / total,
        missing=[tuple(m) for m in missing],
    )
