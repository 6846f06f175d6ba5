"""paracosm.falsify: paracosm's strategies in ask/tell form over the unit cube."""

import math

import numpy as np
import pytest

import paracosm
from paracosm.falsify import Falsifier, falsify


def disc(x):
    """A failure disc of radius 0.03 around (0.83, 0.21): 0.28 % of the square."""
    return math.hypot(x[0] - 0.83, x[1] - 0.21) - 0.03


@pytest.mark.parametrize("strategy", ["falsify-bo", "falsify-bo-lcb", "falsify-nm", "falsify-ce"])
def test_a_falsifier_finds_the_disc_deterministically(strategy):
    a = falsify(disc, 2, strategy=strategy, budget=400, seed=3)
    b = falsify(disc, 2, strategy=strategy, budget=400, seed=3)
    assert a.first_failure is not None, strategy
    assert a.fun <= 0.0 and a.nfev == a.first_failure
    assert np.array_equal(a.xs, b.xs) and a.first_failure == b.first_failure
    assert ((a.xs >= 0.0) & (a.xs < 1.0)).all()


def test_bayesian_optimisation_beats_halton_on_the_disc():
    bo = falsify(disc, 2, strategy="falsify-bo", budget=200, seed=1)
    halton = falsify(disc, 2, strategy="halton", budget=200)
    assert bo.first_failure is not None
    assert halton.first_failure is None or bo.first_failure < halton.first_failure


def test_the_same_points_as_the_rust_strategy_and_errors_are_told():
    f = Falsifier("falsify-bo", 3, seed=7)
    assert f.batch == 4
    first = f.ask()
    assert first.shape == (4, 3)
    # Nothing more until told (the initial design of 8 is handed out in full first).
    f.ask(100)
    assert f.ask(4).shape == (0, 3)
    f.tell([1.0, np.nan, 2.0, math.inf])
    with pytest.raises(ValueError, match="robustness values for"):
        f.tell(np.ones(100))
    g = Falsifier("halton-scrambled", 3, seed=7)
    assert g.batch is None and g.ask(5).shape == (5, 3)


def test_bad_arguments_are_value_errors():
    with pytest.raises(ValueError, match="unknown strategy"):
        Falsifier("annealing", 2)
    with pytest.raises(ValueError, match="needs a budget"):
        Falsifier("ipog", 2)
    with pytest.raises(ValueError):
        Falsifier("falsify-bo", 0)
    with pytest.raises(ValueError):
        falsify(disc, 2, budget=0)


def test_a_scenario_is_falsified_through_its_robustness():
    s = paracosm.Scenario("pedestrian-crossing")
    r = falsify(s.robustness, len(s.space), strategy="falsify-bo", budget=60, seed=2)
    assert r.first_failure is not None
    assert s.robustness(r.x) <= 0.0
