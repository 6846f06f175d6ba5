"""Shared fixtures: where the repository and the `paracosm-fuzz` binary are."""

import os
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="session")
def paracosm_fuzz() -> Path:
    """The `paracosm-fuzz` binary of this checkout (`cargo build --release` or the test
    command builds it), or $PARACOSM_FUZZ. Missing, the tests that compare with it fail."""
    path = Path(os.environ.get("PARACOSM_FUZZ", REPO / "target" / "release" / "paracosm-fuzz"))
    assert path.is_file(), f"{path} is missing: run `cargo build --release` first"
    return path


@pytest.fixture(scope="session")
def box_program() -> Path:
    """A fast synthetic scenario (tests/scenarios/failure_box.star): 4 parameters, one of
    them levels, failing exactly inside a known box."""
    return REPO / "tests" / "scenarios" / "failure_box.star"
