"""paracosm.covering: arrays that cover, coverage that counts, and its argument checks."""

import itertools

import numpy as np
import pytest

from paracosm import covering


def brute_coverage(array, levels, t, forbidden=()):
    """Fraction of t-tuples of levels present in some row, counting only tuples that some
    row breaking no forbidden combination can hold."""
    k = len(levels)
    allowed_rows = [
        r
        for r in itertools.product(*[range(v) for v in levels])
        if not any(all(r[c] == l for c, l in f.items()) for f in forbidden)
    ]
    covered = total = 0
    for cols in itertools.combinations(range(k), t):
        feasible = {tuple(r[c] for c in cols) for r in allowed_rows}
        seen = {tuple(int(row[c]) for c in cols) for row in array}
        total += len(feasible)
        covered += len(feasible & seen)
    return covered, total


@pytest.mark.parametrize("levels, t", [([3, 3, 2, 2], 2), ([2, 3, 2, 4, 2], 3), ([5, 4], 2), ([2] * 8, 2)])
@pytest.mark.parametrize("algorithm", ["ipog", "random"])
def test_arrays_cover_every_tuple(levels, t, algorithm):
    rng = None if algorithm == "ipog" else 11
    a = covering.covering_array(levels, t, algorithm=algorithm, rng=rng)
    assert a.dtype == np.int64 and a.ndim == 2 and a.shape[1] == len(levels)
    assert ((a >= 0) & (a < np.array(levels))).all()
    c = covering.kwise_coverage(a, levels, t)
    assert (c.covered, c.total) == brute_coverage(a, levels, t)
    assert c.fraction == 1.0 and float(c) == 1.0 and c.missing == []


def test_ipog_is_small_and_deterministic():
    a = covering.covering_array([3] * 4, 2)
    # 9 rows is optimal for four 3-level columns at strength 2; IPOG finds at most a few more.
    assert 9 <= len(a) <= 11
    np.testing.assert_array_equal(a, covering.covering_array([3] * 4, 2))


def test_random_arrays_follow_their_seed():
    a = covering.covering_array([3, 3, 3], 2, algorithm="random", rng=5)
    np.testing.assert_array_equal(a, covering.covering_array([3, 3, 3], 2, algorithm="random", rng=5))
    k = covering.covering_array([3, 3, 3], 2, algorithm="kwise", rng=np.random.default_rng(2))
    assert k.shape[1] == 3


def test_constraints_are_kept_and_change_what_counts():
    levels = [2, 3, 2]
    forbidden = [{0: 0, 1: 1}, {1: 2, 2: 1}]
    a = covering.covering_array(levels, 2, constraints=forbidden)
    assert not ((a[:, 0] == 0) & (a[:, 1] == 1)).any()
    assert not ((a[:, 1] == 2) & (a[:, 2] == 1)).any()
    with_c = covering.kwise_coverage(a, levels, 2, constraints=forbidden)
    assert (with_c.covered, with_c.total) == brute_coverage(a, levels, 2, forbidden)
    assert with_c.fraction == 1.0
    plain = covering.kwise_coverage(a, levels, 2)
    assert plain.total == 2 * 3 + 2 * 2 + 3 * 2 and plain.fraction < 1.0


def test_partial_coverage_names_the_missing_tuples():
    c = covering.kwise_coverage(np.array([[0, 0], [1, 1]]), [2, 2], 2)
    assert (c.covered, c.total, c.fraction) == (2, 4, 0.5)
    assert sorted(c.missing) == [((0, 0), (1, 1)), ((0, 1), (1, 0))]
    empty = covering.kwise_coverage(np.zeros((0, 2), dtype=int), [2, 2], 1)
    assert (empty.covered, empty.total) == (0, 4)


def test_coverage_of_columns_with_many_levels_fits_in_memory():
    # 2**20 levels a column: 2**40 pairs, a 137 GB bitset that aborted the interpreter. The
    # rows' distinct combinations give the same counts and the same first missing tuples.
    c = covering.kwise_coverage(np.array([[0, 0], [0, 1], [5, 0], [0, 1]]), [2**20, 2**20], 2)
    assert (c.covered, c.total) == (3, 2**40)
    assert c.missing[:3] == [((0, 0), (1, 2)), ((0, 0), (1, 3)), ((0, 0), (1, 4))]
    t3 = covering.kwise_coverage(np.zeros((1, 3), dtype=int), [2**16] * 3, 3)
    assert (t3.covered, t3.total) == (1, 2**48)
    # Under constraints every tuple is checked one by one: refused past 2**27.
    with pytest.raises(ValueError, match="with constraints every 2-tuple"):
        covering.kwise_coverage(np.zeros((1, 2), dtype=int), [2**20, 2**20], 2, constraints=[{0: 1}])


@pytest.mark.parametrize(
    "call, message",
    [
        (lambda: covering.covering_array([3, 3], 0), "strength must be at least 1"),
        (lambda: covering.covering_array([3, 3], 3), r"strength 3 is not in 1\.\.2"),
        (lambda: covering.covering_array([], 1), "levels is empty"),
        (lambda: covering.covering_array([3, 0], 1), r"levels\[1\] = 0"),
        (lambda: covering.covering_array([3, 2.5], 1), r"levels\[1\] = 2.5 is not an integer"),
        (lambda: covering.covering_array([3, 3], 2, algorithm="aetg"), "algorithm 'aetg'"),
        (lambda: covering.covering_array([3, 3], 2, rng=1), "ipog is deterministic"),
        (lambda: covering.covering_array([3, 3], 2, constraints=[{2: 0}]), r"constraints\[0\]: column 2"),
        (lambda: covering.covering_array([3, 3], 2, constraints=[{0: 3}]), r"constraints\[0\]: level 3"),
        (lambda: covering.covering_array([3, 3], 2, constraints=[{}]), r"constraints\[0\] must be"),
        (lambda: covering.covering_array([2, 2], 1, constraints=[{0: 0}, {0: 1}]), "forbid every row"),
        (lambda: covering.kwise_coverage(np.array([[0.0, 1.0]]), [2, 2], 2), "integer level indices"),
        (lambda: covering.kwise_coverage(np.array([[0, 1, 0]]), [2, 2], 2), r"shape \(n, 2\)"),
        (lambda: covering.kwise_coverage(np.array([[0, 1], [1, 2]]), [2, 2], 2), r"array\[1, 1\] = 2"),
        (lambda: covering.kwise_coverage(np.array([[0, -1]]), [2, 2], 2), r"array\[0, 1\] = -1"),
    ],
)
def test_bad_arguments_are_value_errors(call, message):
    with pytest.raises(ValueError, match=message):
        call()
