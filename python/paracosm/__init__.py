"""paracosm from Python: samplers and coverage estimators of the unit cube (`paracosm.qmc`),
covering arrays (`paracosm.covering`), paracosm's falsifiers on any objective
(`paracosm.falsify`), and driving scenarios as a benchmark for samplers and falsifiers
(`paracosm.Scenario`).

The numbers are those of the Rust crates behind the command-line tools `paracosm-fuzz` and
`paracosm-cover`: a scenario run from Python writes the same records as `paracosm-fuzz
--points` for the same points and seed.
"""

import os as _os
import tempfile as _tempfile

# Mesa's Vulkan loader (the camera renders through it) prints "error: XDG_RUNTIME_DIR is
# invalid or not set" on every render when the environment has no runtime folder (a sandbox,
# a batch job), though rendering works. As paracosm-fuzz does, give it a private folder then,
# kept between runs; an existing valid XDG_RUNTIME_DIR is left alone.
if not _os.path.isdir(_os.environ.get("XDG_RUNTIME_DIR", "")):
    _dir = _os.path.join(_tempfile.gettempdir(), f"paracosm-xdg-{_os.environ.get('USER', 'user')}")
    try:
        _os.makedirs(_dir, mode=0o700, exist_ok=True)
        _os.environ["XDG_RUNTIME_DIR"] = _dir
    except OSError:
        pass

from . import covering, falsify, qmc  # noqa: E402
from ._native import BUILTIN_SCENARIOS, RENDER, __version__  # noqa: E402
from .scenario import Param, Scenario, Space, TestError  # noqa: E402

__all__ = [
    "BUILTIN_SCENARIOS",
    "Param",
    "RENDER",
    "Scenario",
    "Space",
    "TestError",
    "__version__",
    "covering",
    "falsify",
    "qmc",
]
