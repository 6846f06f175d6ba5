"""Argument checks shared by the modules: each failure is a ValueError naming the argument,
the position and the value."""

from __future__ import annotations

import numbers
import secrets

import numpy as np


def positive_int(value, name: str, minimum: int = 1, maximum: int = 2**63 - 1) -> int:
    """`value` as an int in `[minimum, maximum]` (by default at most 2**63 - 1, what the
    native code takes); bools and non-integers are refused."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Integral):
        raise ValueError(f"{name} must be an integer, not {value!r}")
    if value < minimum:
        raise ValueError(f"{name} must be at least {minimum}, got {value}")
    if value > maximum:
        raise ValueError(f"{name} must be at most {maximum}, got {value}")
    return int(value)


def seed_of(rng) -> int:
    """A 64-bit seed from `rng`: None (fresh entropy), an int in [0, 2**64), or a
    numpy.random.Generator (one draw from it)."""
    if rng is None:
        return secrets.randbits(64)
    if isinstance(rng, (bool, np.bool_)):
        raise ValueError(f"rng must be None, an int seed or a numpy.random.Generator, not {rng!r}")
    if isinstance(rng, numbers.Integral):
        if not 0 <= rng < 2**64:
            raise ValueError(f"rng seed {rng} is not in [0, 2**64)")
        return int(rng)
    if isinstance(rng, np.random.Generator):
        return int(rng.integers(0, 2**64, dtype=np.uint64))
    raise ValueError(
        f"rng must be None, an int seed or a numpy.random.Generator, not {type(rng).__name__}"
    )


def real_matrix(sample, name: str) -> np.ndarray:
    """`sample` as a C-contiguous (n, d) float64 array with n, d >= 1 and no NaN; a copy only
    when the input is not already one."""
    try:
        a = np.asarray(sample)
    except ValueError as e:  # ragged nested lists
        raise ValueError(f"{name} is not a rectangular array: {e}") from None
    if a.dtype == np.bool_ or not (
        np.issubdtype(a.dtype, np.floating) or np.issubdtype(a.dtype, np.integer)
    ):
        raise ValueError(f"{name} must hold real numbers, not dtype {a.dtype}")
    if a.ndim != 2:
        raise ValueError(
            f"{name} must be a 2-D array of shape (n, d), got {a.ndim} dimension(s), shape {a.shape}"
        )
    if a.shape[0] == 0 or a.shape[1] == 0:
        raise ValueError(f"{name} is empty: shape {a.shape}")
    a = np.ascontiguousarray(a, dtype=np.float64)
    nan = np.isnan(a)
    if nan.any():
        i, j = np.argwhere(nan)[0]
        raise ValueError(f"{name}[{i}, {j}] is NaN")
    return a


def unit_matrix(sample, name: str) -> np.ndarray:
    """As `real_matrix`, every value in the unit hypercube [0, 1]."""
    a = real_matrix(sample, name)
    out = (a < 0.0) | (a > 1.0)
    if out.any():
        i, j = np.argwhere(out)[0]
        raise ValueError(
            f"{name}[{i}, {j}] = {float(a[i, j])!r} is outside the unit hypercube [0, 1]"
        )
    return a
