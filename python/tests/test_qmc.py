"""paracosm.qmc against scipy.stats.qmc on fixed point sets, and its argument checks."""

import threading
import time
import warnings

from fractions import Fraction

import numpy as np
import pytest
from scipy.stats import qmc as sqmc

from paracosm import qmc

METHODS = ["CD", "WD", "MD", "L2-star"]


def fixed_sets():
    rng = np.random.default_rng(20261122)
    return {
        "random 200x3": rng.random((200, 3)),
        "random 64x8": rng.random((64, 8)),
        "halton 500x5": sqmc.Halton(5, scramble=False).random(500),
        "with 0 and 1": np.array([[0.0, 1.0], [1.0, 0.0], [0.5, 0.5], [0.0, 0.0], [1.0, 1.0]]),
        "one point": np.array([[0.3, 0.7, 0.1]]),
    }


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("name", list(fixed_sets()))
def test_discrepancy_equals_scipy(name, method):
    sample = fixed_sets()[name]
    ours = qmc.discrepancy(sample, method=method)
    theirs = sqmc.discrepancy(sample, method=method)
    # The same bits: paracosm evaluates each term and adds them in scipy's order.
    assert ours == theirs, (name, method, ours, theirs)


def test_discrepancy_takes_integers_and_lists_as_scipy_does():
    assert qmc.discrepancy([[0, 1], [1, 0]]) == sqmc.discrepancy(
        np.array([[0.0, 1.0], [1.0, 0.0]])
    )


def test_unscrambled_halton_is_scipys_point_for_point():
    ours = qmc.Halton(6)
    theirs = sqmc.Halton(6, scramble=False)
    a = np.vstack([ours.random(300), ours.random(700)])
    b = theirs.random(1000)
    assert a.dtype == np.float64 and a.shape == (1000, 6)
    # Ours are the correctly rounded radical inverses; scipy adds digit terms in floats, so
    # some of its values are a few ulp off (Halton(5) point 3, column 2: 0.6000000000000001;
    # at most 3.3e-16 over 20,000 points in d = 8).
    assert np.max(np.abs(a - b)) <= 2 * np.finfo(float).eps
    primes = [2, 3, 5, 7, 11, 13]
    for i in range(0, 1000, 7):
        for k, q in enumerate(primes):
            j, num, den = i, 0, 1
            while j:
                num, den, j = num * q + j % q, den * q, j // q
            assert a[i, k] == float(Fraction(num, den)), (i, k)
    assert ours.num_generated == 1000
    np.testing.assert_array_equal(ours.reset().random(10), a[:10])
    np.testing.assert_array_equal(ours.reset().fast_forward(500).random(3), a[500:503])


def test_scrambled_sequences_are_seeded_and_in_the_unit_cube():
    for make in (lambda r: qmc.Halton(4, scramble=True, rng=r), lambda r: qmc.Sobol(4, rng=r)):
        a = make(7).random(1024)
        assert a.shape == (1024, 4) and a.dtype == np.float64
        assert a.flags["C_CONTIGUOUS"]
        assert ((a >= 0) & (a < 1)).all()
        np.testing.assert_array_equal(a, make(7).random(1024))
        assert not np.array_equal(a, make(8).random(1024))
        # A numpy Generator seeds it reproducibly too.
        np.testing.assert_array_equal(
            make(np.random.default_rng(3)).random(8), make(np.random.default_rng(3)).random(8)
        )
        # Each coordinate is uniform: the means of 1,024 stratified points sit near 1/2.
        assert np.abs(a.mean(axis=0) - 0.5).max() < 0.01
        # Low discrepancy: far below random points of the same size.
        rand = np.random.default_rng(0).random((1024, 4))
        assert qmc.discrepancy(a) < 0.2 * qmc.discrepancy(rand)
    assert qmc.Halton(3).random(0).shape == (0, 3)


def test_sobol_keeps_scipys_power_of_two_rules():
    s = qmc.Sobol(2, rng=1)
    with pytest.warns(UserWarning, match="power of 2"):
        s.random(3)
    with pytest.raises(ValueError, match="power of 2"):
        s.random_base2(2)
    s.reset()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert s.random_base2(4).shape == (16, 2)
        assert s.random(16).shape == (16, 2)
    with pytest.raises(ValueError, match="65536"), pytest.warns(UserWarning, match="power of 2"):
        qmc.Sobol(2, rng=1).fast_forward(65530).random(8)
    with pytest.raises(ValueError, match="scramble"):
        qmc.Sobol(2, scramble=False)
    with pytest.raises(ValueError, match="dimensions"):
        qmc.Sobol(qmc.SOBOL_MAX_DIMENSIONS + 1)


@pytest.mark.parametrize(
    "bad, message",
    [
        (np.zeros(5), "2-D"),
        (np.zeros((2, 2, 2)), "2-D"),
        (np.zeros((0, 3)), "empty"),
        (np.zeros((3, 0)), "empty"),
        (np.array([[0.1, np.nan], [0.2, 0.3]]), r"sample\[0, 1\] is NaN"),
        (np.array([[0.1, 0.2], [1.5, 0.3]]), r"sample\[1, 0\] = 1.5 is outside the unit hypercube"),
        (np.array([[0.1, 0.2], [-0.0001, 0.3]]), r"sample\[1, 0\]"),
        (np.array([[0.1, np.inf]]), r"sample\[0, 1\] = inf"),
        (np.array([["a", "b"]]), "real numbers"),
        (np.array([[0.1 + 0j]]), "real numbers"),
        (np.array([[True, False]]), "real numbers"),
        ([[0.1, 0.2], [0.3]], "rectangular"),
    ],
)
def test_bad_samples_are_value_errors_naming_the_problem(bad, message):
    for f in (qmc.discrepancy, qmc.star_discrepancy, qmc.dispersion):
        with pytest.raises(ValueError, match=message):
            f(bad)


def test_bad_arguments_are_value_errors():
    with pytest.raises(ValueError, match="method 'XD'"):
        qmc.discrepancy(np.zeros((2, 2)), method="XD")
    for bad in (0, -1, 2.5, True, "3"):
        with pytest.raises(ValueError, match="d must be"):
            qmc.Halton(bad)
    with pytest.raises(ValueError, match="n must be"):
        qmc.Halton(2).random(-1)
    with pytest.raises(ValueError, match="rng"):
        qmc.Halton(2, scramble=True, rng=-4)
    with pytest.raises(ValueError, match="rng"):
        qmc.Sobol(2, rng="seed")
    with pytest.raises(ValueError, match="rng"):
        qmc.Halton(2, rng="x")


def test_a_point_set_too_large_for_the_estimators_memory_raises_memory_error():
    # A broadcast array of 2e8 points (no memory of its own) aborted the interpreter inside
    # the extension: the discrepancy's pair sums need about 1 KiB a point in d = 1. The set
    # is made large enough that its working memory is four times this machine's.
    import os

    memory = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    n = max(2 * 10**8, 4 * memory // 1056 + 1)
    sample = np.broadcast_to(np.float64(0.5), (n, 1))
    with pytest.raises(MemoryError, match="working memory"):
        qmc.discrepancy(sample, method="CD")


def test_sizes_past_what_the_sequences_hold_are_errors_not_crashes():
    # Each of these aborted the interpreter (a failed allocation), raised a PanicException
    # (a BaseException) or an OverflowError, or returned inf and values past 1.
    with pytest.raises(ValueError, match="dimensions Halton supports"):
        qmc.Halton(10**9)
    with pytest.raises(MemoryError):
        qmc.Halton(2).random(2**40)
    for n in (2**62, 2**64, 2**70):
        with pytest.raises(ValueError, match="2\\*\\*53|at most"):
            qmc.Halton(2).random(n)
    with pytest.raises(ValueError, match="2\\*\\*53|at most"):
        qmc.Halton(3).fast_forward(2**64 - 2)
    with pytest.raises(ValueError, match="2\\*\\*53"):
        qmc.Halton(3).fast_forward(2**60)
    with pytest.raises(ValueError, match="at most 16"):
        qmc.Sobol(2).random_base2(100)
    x = np.random.default_rng(0).random((20, 2))
    with pytest.raises(ValueError, match="seed"):
        qmc.star_discrepancy(x, seed=2**64)
    with pytest.raises(ValueError, match="seed"):
        qmc.dispersion(x, seed=2**70)
    # The last points the sequence holds are finite and below 1.
    h = qmc.Halton(3).fast_forward(2**53 - 2)
    last = h.random(2)
    assert np.all(np.isfinite(last)) and np.all((0 <= last) & (last < 1)), last
    assert h.num_generated == 2**53
    with pytest.raises(ValueError, match="2\\*\\*53"):
        h.random(1)


def local_discrepancy(sample, y):
    vol = float(np.prod(y))
    open_count = np.all(sample < y, axis=1).mean()
    closed_count = np.all(sample <= y, axis=1).mean()
    return max(vol - open_count, closed_count - vol)


def test_star_discrepancy_is_exact_in_one_dimension_and_certified_above():
    x = np.random.default_rng(5).random((50, 1))
    s = np.sort(x[:, 0])
    n = len(s)
    closed_form = 1 / (2 * n) + np.max(np.abs(s - (2 * np.arange(1, n + 1) - 1) / (2 * n)))
    r = qmc.star_discrepancy(x)
    assert r.exact and r.lower == r.upper
    assert r.lower == pytest.approx(closed_form, rel=1e-12)
    big = np.random.default_rng(6).random((300, 5))
    # Past d = 4 a bracket, loose here (18 cover cells per axis), which warns and says how far
    # from exact it can be.
    with pytest.warns(RuntimeWarning, match="at most [0-9.]+ times the lower end"):
        b = qmc.star_discrepancy(big)
    assert not b.exact and 0 < b.lower <= b.upper <= 1
    assert f"at most {b.upper / b.lower:.3f} times" in b.method
    assert b.box.shape == (2, 5) and (b.box[0] == 0).all()
    # The lower bound is the local discrepancy at the witness corner, recomputed here.
    assert local_discrepancy(big, b.box[1]) == pytest.approx(b.lower, rel=1e-12)


def test_dispersion_is_the_largest_empty_box():
    x = np.array([[0.2], [0.5], [0.9]])
    r = qmc.dispersion(x)
    # Gaps 0.2, 0.3, 0.4 and 0.1: the largest lies between 0.5 and 0.9.
    assert r.exact and r.lower == pytest.approx(0.4)
    np.testing.assert_allclose(r.box, [[0.5], [0.9]])
    pts = sqmc.Halton(2, scramble=False).random(64)
    r = qmc.dispersion(pts)
    assert r.exact and r.box.shape == (2, 2)
    lo, hi = r.box
    assert np.prod(hi - lo) == pytest.approx(r.lower, rel=1e-12)
    inside = np.all((pts > lo) & (pts < hi), axis=1)
    assert not inside.any(), "the witness box holds no point"
    # No larger empty box among the boxes spanned by pairs of coordinates (brute force).
    xs = np.concatenate([[0.0, 1.0], pts[:, 0]])
    ys = np.concatenate([[0.0, 1.0], pts[:, 1]])
    best = 0.0
    for x0 in xs:
        for x1 in xs[xs > x0]:
            strip = pts[(pts[:, 0] > x0) & (pts[:, 0] < x1)][:, 1]
            cuts = np.sort(np.concatenate([[0.0, 1.0], strip]))
            best = max(best, (x1 - x0) * np.max(np.diff(cuts)))
    assert r.lower == pytest.approx(best, rel=1e-12)


def test_long_computations_release_the_gil():
    sample = np.random.default_rng(1).random((8000, 8))
    done = threading.Event()
    ticks = 0

    def work():
        qmc.discrepancy(sample, method="CD")
        done.set()

    t = threading.Thread(target=work)
    t0 = time.perf_counter()
    t.start()
    while not done.is_set():
        ticks += 1
        time.sleep(0.001)
    t.join()
    elapsed = time.perf_counter() - t0
    # Holding the GIL, the native call would leave this loop one turn at most.
    assert elapsed > 0.05, f"the computation took {elapsed:.3f} s: too short to tell"
    assert ticks >= 10, f"the main thread ran {ticks} times in {elapsed:.3f} s"
