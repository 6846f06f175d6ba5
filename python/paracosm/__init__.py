"""paracosm from Python: samplers and coverage estimators of the unit cube (`paracosm.qmc`),
covering arrays (`paracosm.covering`), and driving scenarios as a benchmark for samplers
and falsifiers (`paracosm.Scenario`).

The numbers are those of the Rust crates behind the command-line tools `paracosm-fuzz` and
`paracosm-cover`: a scenario run from Python writes the same records as `paracosm-fuzz
--points` for the same points and seed.
"""

from . import covering, qmc
from ._native import BUILTIN_SCENARIOS, RENDER, __version__
from .scenario import Param, Scenario, Space, TestError

__all__ = [
    "BUILTIN_SCENARIOS",
    "Param",
    "RENDER",
    "Scenario",
    "Space",
    "TestError",
    "__version__",
    "covering",
    "qmc",
]
