"""The bench's objectives and the wrapper that counts evaluations, shared by every runner.

Each objective maps a point of [0, 1]^d to a robustness (<= 0: falsified):
- `pedestrian-crossing`, `follow-lead-car`, `cut-in`: paracosm's built-in scenarios with
  their built-in system under test, `paracosm.Scenario(name).robustness` (one closed-loop
  test per evaluation; discrete parameters read as floor(u * levels));
- `alks-crossing-pedestrian`: UN R157's (ALKS) crossing pedestrian from the published
  OpenSCENARIO suite (tests/data/xosc/alks), its variation file's parameters with the
  pedestrian's lateral offset (-8 to -2 m) and speed (2 to 10 km/h) opened, as
  docs/openscenario.md runs it; about 0.5 s a test, so not in the default list (tests with
  the ego on lane 4, which faces off the map, end in error: NaN);
- `disc`: a failure disc of radius 0.03 (0.28 % of the square) whose centre each seed draws
  in [0.1, 0.9]^2; the robustness is the distance to it;
- `branin`: the Branin function on [-5, 10] x [0, 15] minus 0.5 (its minimum is 0.397887 at
  three points; 0.19 % of the square falsifies).
"""

import math
import time
import warnings

import numpy as np

import os

SCENARIOS = ["pedestrian-crossing", "follow-lead-car", "cut-in"]
ANALYTIC = ["disc", "branin"]
OBJECTIVES = SCENARIOS + ANALYTIC
ALKS = "alks-crossing-pedestrian"
ALKS_FILE = os.path.join(os.path.dirname(__file__), "..", "..", "..", "tests", "data", "xosc", "alks",
                         "alks_scenario_4_2_3_crossing_pedestrian_variation.xosc")
ALKS_OPEN = ["TargetBlocking_InitPosition_LateralOffset_m=-8..-2", "TargetBlocking_Speed_kph=2..10"]


def objective(name: str, seed: int):
    """(fun, d) for objective `name` and seed `seed`."""
    if name in SCENARIOS or name == ALKS:
        import paracosm

        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            s = (paracosm.Scenario(os.path.normpath(ALKS_FILE), open=ALKS_OPEN) if name == ALKS
                 else paracosm.Scenario(name))
        return (lambda x: s.robustness(x, on_error="nan")), len(s.space)
    if name == "disc":
        c = np.random.default_rng(1000 + seed).uniform(0.1, 0.9, 2)
        return (lambda x: math.hypot(x[0] - c[0], x[1] - c[1]) - 0.03), 2
    if name == "branin":
        def branin(x):
            a, b = 15.0 * x[0] - 5.0, 15.0 * x[1]
            return ((b - 5.1 / (4 * math.pi ** 2) * a * a + 5 / math.pi * a - 6) ** 2
                    + 10 * (1 - 1 / (8 * math.pi)) * math.cos(a) + 10 - 0.5)
        return branin, 2
    raise ValueError(f"unknown objective {name!r}; expected one of {OBJECTIVES + [ALKS]}")


class Stop(Exception):
    """Raised by `Counted` to end a tool's search: the first failure, or the cap."""


class Counted:
    """`fun` clamped into [0, 1]^d, counting evaluations; raises `Stop` right after the first
    value <= 0 or the `cap`-th evaluation, so every tool stops where the bench says."""

    def __init__(self, fun, d: int, cap: int):
        self.fun, self.d, self.cap = fun, d, cap
        self.values: list[float] = []

    def __call__(self, x) -> float:
        if len(self.values) >= self.cap:
            raise Stop()
        x = np.clip(np.asarray(x, dtype=np.float64).reshape(self.d), 0.0, 1.0 - 2.0 ** -53)
        r = float(self.fun(x))
        self.values.append(r)
        if r <= 0.0 or len(self.values) >= self.cap:
            raise Stop()
        if math.isfinite(r):
            return r
        # A test that errored (NaN) or where nothing counted (+inf): one more than the worst
        # finite value so far, so that no tool sees an infinity or a huge outlier.
        finite = [v for v in self.values if math.isfinite(v)]
        return max(finite) + 1.0 if finite else 1e3


def trial(tool: str, run, objective_name: str, seed: int, cap: int) -> dict:
    """One search: `run(counted_fun, d, seed, cap)` until it stops; a record of the result."""
    fun, d = objective(objective_name, seed)
    counted = Counted(fun, d, cap)
    t0 = time.process_time()
    try:
        run(counted, d, seed, cap)
    except Stop:
        pass
    cpu = time.process_time() - t0
    first = next((i + 1 for i, v in enumerate(counted.values) if v <= 0.0), None)
    return {"tool": tool, "objective": objective_name, "seed": seed, "cap": cap,
            "evaluations": len(counted.values), "first_failure": first,
            "best": min(counted.values) if counted.values else None,
            "cpu_s": cpu}
