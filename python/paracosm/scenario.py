"""Driving scenarios as a benchmark for samplers and falsifiers.

`Scenario("pedestrian-crossing")` (a built-in name) or `Scenario("my.star")` (a program in
the language of LANGUAGE.md) loads a family of worlds with open parameters. `.space` tells
what they are; `.run(points)` runs one closed-loop test per point, in parallel with the GIL
released, and returns the records `paracosm-fuzz --points` writes for the same points and
seed; `.robustness(x)` runs one point and returns its robustness, so any Python optimiser
can falsify (minimise it below 0).
"""

from __future__ import annotations

import csv
import io
import json
import re
import math
import numbers
import os
import warnings
from dataclasses import dataclass

import numpy as np

from . import _native
from ._check import positive_int

__all__ = ["Param", "Scenario", "ScenarioWarning", "Space", "TestError"]


class TestError(RuntimeError):
    """A test ended in `error` (an invalid world, a system under test that failed, an
    internal error) where a verdict was needed: `Scenario.robustness` with
    `on_error="raise"`. `record` holds the test's record."""

    __test__ = False  # not a pytest test class

    def __init__(self, message: str, record: dict):
        super().__init__(message)
        self.record = record


class ScenarioWarning(UserWarning):
    """The program loads, but checks or varies less than it seems to (LANGUAGE.md,
    "Warnings"): a monitor missing, an open parameter no object reads."""


@dataclass(frozen=True)
class Param:
    """One open parameter: `kind` is `"interval"` (`VarInterval`, `bounds = (lo, hi)` in
    `unit`) or `"levels"` (`VarEnum`, `levels` the values in order)."""

    name: str
    kind: str
    bounds: tuple[float, float] | None
    unit: str | None
    levels: list | None


class Space:
    """The open parameters of a scenario, in declaration order: the column order of the
    unit-cube arrays `Scenario.run` takes (`d = len(space)`)."""

    def __init__(self, params: list[Param]):
        self.params = params

    def __len__(self) -> int:
        return len(self.params)

    def __iter__(self):
        return iter(self.params)

    def __getitem__(self, key) -> Param:
        if isinstance(key, str):
            for p in self.params:
                if p.name == key:
                    return p
            raise KeyError(key)
        return self.params[key]

    def __repr__(self) -> str:
        return f"Space({', '.join(p.name for p in self.params)})"

    @property
    def d(self) -> int:
        """The number of parameters."""
        return len(self.params)

    @property
    def names(self) -> list[str]:
        """The parameters' names."""
        return [p.name for p in self.params]

    @property
    def kinds(self) -> list[str]:
        """`"interval"` or `"levels"` per parameter."""
        return [p.kind for p in self.params]

    @property
    def bounds(self) -> list[tuple[float, float] | None]:
        """`(lo, hi)` per interval parameter, None for the levels."""
        return [p.bounds for p in self.params]

    @property
    def units(self) -> list[str | None]:
        """The unit per parameter (m, m/s, ...), None when unitless."""
        return [p.unit for p in self.params]

    @property
    def levels(self) -> list[list | None]:
        """The levels per `VarEnum` parameter, None for the intervals."""
        return [p.levels for p in self.params]

    def to_units(self, points) -> list[dict]:
        """Unit-cube rows (`(n, d)`) as dicts in the parameters' units: `lo + u (hi - lo)`
        for an interval, level `min(floor(u L), L - 1)` for `L` levels (as `Scenario.run`
        reads them)."""
        a = _unit_points(points, self)
        out = []
        for row in a:
            point = {}
            for u, p in zip(row, self.params):
                if p.kind == "interval":
                    lo, hi = p.bounds
                    point[p.name] = lo + min(u, 1.0 - 2.0**-53) * (hi - lo)
                else:
                    point[p.name] = p.levels[min(int(u * len(p.levels)), len(p.levels) - 1)]
            out.append(point)
        return out


def _param(raw: dict) -> Param:
    unit = raw.get("unit")
    domain = raw["domain"]
    if "interval" in domain:
        return Param(raw["name"], "interval", (domain["interval"]["lo"], domain["interval"]["hi"]), unit, None)
    return Param(raw["name"], "levels", None, unit, list(domain["levels"]))


def _unit_points(points, space: Space) -> np.ndarray:
    from ._check import real_matrix

    if len(space) == 0:
        # Without open parameters a test is a row of nothing: an (n, 0) array gives n tests.
        a = np.asarray(points, dtype=np.float64)
        if a.ndim != 2 or a.shape[1] != 0 or a.shape[0] == 0:
            raise ValueError(
                f"the scenario has no open parameters: give an (n, 0) array for n tests, got shape {a.shape}"
            )
        return np.ascontiguousarray(a)
    a = real_matrix(points, "points")
    if a.shape[1] != len(space):
        raise ValueError(
            f"points has {a.shape[1]} columns, the scenario has {len(space)} parameters "
            f"({', '.join(space.names)})"
        )
    out = (a < 0.0) | (a > 1.0)
    if out.any():
        i, j = np.argwhere(out)[0]
        raise ValueError(
            f"points[{i}, {j}] = {float(a[i, j])!r} (`{space.names[j]}`) is outside the unit interval [0, 1]"
        )
    return a


def _cell(value, where: str) -> str:
    """A value in units as `paracosm-fuzz --points` reads it from a CSV cell."""
    if isinstance(value, (bool, np.bool_)):
        return "true" if value else "false"
    if isinstance(value, numbers.Integral):
        return str(int(value))
    if isinstance(value, numbers.Real):
        return repr(float(value))
    if isinstance(value, str):
        return value
    raise ValueError(f"{where}: {value!r} is not a number, a bool or a text")


def points_csv(points, space: Space) -> str:
    """Dicts in the parameters' units (a list of dicts, or a pandas DataFrame) as the CSV
    text `paracosm-fuzz --points FILE` reads: a header of the parameters' names, one row per
    point. Floats are written with `repr`, so they read back exactly.

    Raises ValueError for a point that lacks a parameter or names one the scenario lacks."""
    if hasattr(points, "to_dict") and hasattr(points, "columns"):
        points = points.to_dict("records")
    names = space.names
    out = io.StringIO()
    w = csv.writer(out, lineterminator="\n")
    w.writerow(names)
    for i, p in enumerate(points):
        if not isinstance(p, dict):
            raise ValueError(f"points[{i}] is not a dict of parameter values: {p!r}")
        unknown = sorted(set(p) - set(names))
        if unknown:
            raise ValueError(f"points[{i}] names {', '.join(map(repr, unknown))}, not a parameter of the scenario ({', '.join(names)})")
        missing = [n for n in names if n not in p]
        if missing:
            raise ValueError(f"points[{i}] has no value for {', '.join(map(repr, missing))}")
        w.writerow([_cell(p[n], f"points[{i}][{n!r}]") for n in names])
    return out.getvalue()


def _python_place(message: str) -> str:
    """A message about line L, column C (`name`) of the CSV `points_csv` wrote, reworded to
    name the Python input: `points[L - 2]['name']` (line 1 is the header)."""
    m = re.match(r"points:(\d+): column \d+ \(`([^`]+)`\): (.*)", message, re.S)
    if not m:
        return message
    return f"points[{int(m.group(1)) - 2}][{m.group(2)!r}]: {m.group(3)}"


def _sut_args(sut) -> dict:
    """`sut` as the native arguments: None (the scenario's), a built-in name (`"aeb"`,
    `"vision"`), or a command (a list of words) speaking SUT_PROTOCOL.md."""
    if sut is None:
        return {}
    if isinstance(sut, str):
        return {"sut": sut}
    if isinstance(sut, (list, tuple)) and all(isinstance(w, str) for w in sut):
        return {"sut_cmd": list(sut)}
    raise ValueError(f"sut must be None, a built-in name or a command as a list of words, not {sut!r}")


def _monitor_robustness(m: dict) -> float:
    """A monitor's robustness as a float. JSON has no infinity, so paracosm writes an infinite
    robustness as null: +inf when the monitor passed (nothing to measure, e.g. a
    CollisionMonitor with no other actor), -inf when it failed (a stream with no event)."""
    if m["robustness"] is None:
        return math.inf if m["passed"] else -math.inf
    return m["robustness"]


def _robustness(monitors: dict, passive=()) -> float:
    """The smallest robustness over the monitors (<= 0: failed; +inf without monitors), the
    `passive` ones counting only where they are <= 0, and monitors cut short by another's
    failure not at all (paracosm's falsification cost)."""
    values = [
        _monitor_robustness(m)
        for name, m in monitors.items()
        if not m.get("cut_short", False)
        and (name not in passive or _monitor_robustness(m) <= 0.0)
    ]
    return min(values, default=math.inf)


def _flat(record: dict, space: Space) -> dict:
    """One row of the DataFrame: id, seed, status, the parameters by name, `robustness` (the
    smallest over the monitors), `<monitor>.robustness`, `<monitor>.passed`,
    `<monitor>.first_violation_s`, the metrics by name, error, wall_ms."""
    row = {"id": record["id"], "seed": record["seed"], "status": record["status"]}
    params = record.get("params") or {}
    for n in space.names:
        row[n] = params.get(n, math.nan)
    monitors = record["monitors"]
    row["robustness"] = math.nan if record["status"] == "error" else _robustness(monitors)
    for name, m in monitors.items():
        row[f"{name}.robustness"] = _monitor_robustness(m)
        row[f"{name}.passed"] = m["passed"]
        row[f"{name}.first_violation_s"] = (
            math.nan if m["first_violation_s"] is None else m["first_violation_s"]
        )
    for name, v in record["metrics"].items():
        row[name] = math.nan if v is None else v
    row["error"] = record["error"]
    row["wall_ms"] = record["wall_ms"]
    return row


def _uniform(rows: list[dict], records: list[dict], space: Space) -> list[dict]:
    """The rows with the same columns in the documented order, whatever each test wrote: a
    metric only a failed test has (`time_to_failure_s`), or monitors a test in error lacks,
    are NaN in the other rows (the DataFrame's columns followed the first row that had them,
    after `wall_ms`, or were missing when no test failed and had them)."""
    def first_seen(keys):
        return list(dict.fromkeys(k for ks in keys for k in ks))

    monitors = first_seen(r["monitors"].keys() for r in records)
    metrics = first_seen(r["metrics"].keys() for r in records)
    columns = ["id", "seed", "status", *space.names, "robustness"]
    for m in monitors:
        columns += [f"{m}.robustness", f"{m}.passed", f"{m}.first_violation_s"]
    columns += [*metrics, "error", "wall_ms"]
    return [{c: row.get(c, math.nan) for c in columns} for row in rows]


class Scenario:
    """A scenario program: a built-in name (`paracosm.BUILTIN_SCENARIOS`) or the path of a
    `.star` file; or an OpenSCENARIO file (`.xosc`, a variation file or a scenario) read with
    `paracosm-fuzz`'s options: `open` (a list of `"Name=lo..hi"` or `"Name=a,b,c"`),
    `continuous`, `scripted_ego`, `ego` (the vehicle's name), `horizon` (s), `ego_speed`
    (m/s: the system under test's set speed where the file asks the ego none) and `maps` (a
    folder where a map the file names is found, such as CARLA's towns) and `carla` (read the
    file as CARLA's scenario_runner reads its own).

    Warnings of the program (LANGUAGE.md, "Warnings") are issued as `ScenarioWarning`.
    Raises ValueError naming the file, line and column when the program does not load.
    Instances are thread-safe: two threads may run tests of one scenario at once.
    """

    def __init__(self, name_or_path, *, sut=None, open=(), continuous=False, scripted_ego=False,
                 ego=None, horizon=None, ego_speed=None, maps=None, carla=False):
        if isinstance(open, str):
            raise TypeError("open is a list of 'Name=lo..hi' or 'Name=a,b,c' strings, not one string")
        self._native = _native.ScenarioHandle(
            os.fspath(name_or_path), open=list(open), continuous=continuous,
            scripted_ego=scripted_ego, ego=ego, horizon=horizon, ego_speed=ego_speed,
            maps=None if maps is None else os.fspath(maps), carla=carla)
        self._sut = _sut_args(sut)
        # Checked now, as a run would check it: a bad name fails here, not at the first run.
        self._sut_name = self._native.sut_name(**self._sut)
        self.space = Space([_param(p) for p in json.loads(self._native.space_json())])
        for w in self._native.warnings:
            warnings.warn(w, ScenarioWarning, stacklevel=2)

    def __repr__(self) -> str:
        return f"Scenario({self.name!r}, d={len(self.space)}, monitors={self.monitors})"

    @property
    def name(self) -> str:
        """The scenario's name."""
        return self._native.name

    @property
    def description(self) -> str:
        """Its one-line description."""
        return self._native.description

    @property
    def horizon_s(self) -> float:
        """Length of one test in seconds of simulated time."""
        return self._native.horizon_s

    @property
    def monitors(self) -> list[str]:
        """The monitors' names, in the records' order."""
        return self._native.monitors

    @property
    def sut(self) -> str:
        """The system under test it runs by default: the one given to the constructor, else
        the scenario's."""
        return self._sut_name

    @property
    def warnings(self) -> list[str]:
        """The program's load warnings."""
        return self._native.warnings

    def _lines(self, points, *, sut, jobs, seed) -> list[str]:
        seed = positive_int(seed, "seed", minimum=0, maximum=2**64 - 1)
        if jobs is not None:
            jobs = positive_int(jobs, "jobs", maximum=4096)
        kw = dict(self._sut if sut is None else _sut_args(sut))
        if isinstance(points, dict):
            raise ValueError("points is one dict: give a list of dicts (one per test)")
        is_dicts = (hasattr(points, "to_dict") and hasattr(points, "columns")) or (
            isinstance(points, (list, tuple)) and len(points) > 0 and isinstance(points[0], dict)
        )
        if is_dicts:
            rows = points.to_dict("records") if hasattr(points, "to_dict") else list(points)
            if len(self.space) == 0:
                # No parameter: each dict (empty) is one test, as a row of an (n, 0) array.
                points_csv(rows, self.space)  # names any key the scenario lacks
                return self._native.run_unit(np.zeros((len(rows), 0)), seed, jobs, **kw)
            try:
                return self._native.run_csv(points_csv(rows, self.space), "points", seed, jobs, **kw)
            except ValueError as e:
                raise ValueError(_python_place(str(e))) from None
        return self._native.run_unit(_unit_points(points, self.space), seed, jobs, **kw)

    def run(self, points, *, sut=None, jobs: int | None = None, seed: int = 0, output: str = "frame"):
        """Runs one test per point and returns the records in point order.

        `points`: an `(n, d)` array in the unit cube [0, 1] (columns in `space` order; a
        continuous coordinate `u` maps to `lo + u (hi - lo)`, 1 to the interval's upper end;
        a discrete one to level `min(floor(u L), L - 1)`), or a list of dicts (or a pandas
        DataFrame) of values in the parameters' units, levels as their values.

        Test `i` is seeded from `seed` and `i` as in `paracosm-fuzz`, whose `--points FILE
        --seed SEED` writes the same records (strategy `points`) for the same points.
        `sut`: None (the scenario's, or the one given to the constructor), a built-in name
        (`"aeb"`, `"vision"`), or a command as a list of words (SUT_PROTOCOL.md). `jobs`:
        worker threads (default: all cores); results do not depend on it.

        `output`: `"frame"` (a pandas DataFrame when pandas is installed, else a list of flat
        dicts; columns id, seed, status, the parameters, robustness, `<monitor>.robustness`,
        `<monitor>.passed`, `<monitor>.first_violation_s`, the metrics, error, wall_ms),
        `"records"` (the records as nested dicts, as in results.jsonl) or `"jsonl"` (the lines
        of results.jsonl).

        Raises ValueError for points that do not fit the space (naming the row, column and
        value), a bad `sut`, `jobs` or `seed`.
        """
        if output not in ("frame", "records", "jsonl"):
            raise ValueError(f"output {output!r} is not one of 'frame', 'records', 'jsonl'")
        lines = self._lines(points, sut=sut, jobs=jobs, seed=seed)
        if output == "jsonl":
            return lines
        records = [json.loads(line) for line in lines]
        if output == "records":
            return records
        rows = _uniform([_flat(r, self.space) for r in records], records, self.space)
        try:
            import pandas as pd
        except ImportError:
            return rows
        return pd.DataFrame(rows)

    @property
    def passive_monitors(self) -> list[str]:
        """The monitors that steer no falsifier until they fail: the implicit `offroad`
        monitor, whose margin to the road's edge (about 1.75 m in the middle of a lane) would
        otherwise flatten the cost an optimiser descends."""
        return self._native.passive_monitors

    def robustness(self, x, *, sut=None, seed: int = 0, on_error: str = "raise") -> float:
        """The falsification cost of one test, what paracosm's own falsifiers minimise: the
        smallest robustness over the monitors, the `passive_monitors` counting only where
        they fail; <= 0 exactly when the test failed, +inf when nothing counts. `x` is a point
        of the unit cube (a length-`d` sequence) or a dict in units, run as test 0 of a
        campaign seeded `seed`, on the calling thread.

        A test that ends in `error` raises `TestError` (`on_error="raise"`) or returns NaN
        (`on_error="nan"`).
        """
        if on_error not in ("raise", "nan"):
            raise ValueError(f"on_error {on_error!r} is not one of 'raise', 'nan'")
        points = [x] if isinstance(x, dict) else np.atleast_2d(np.asarray(x, dtype=np.float64))
        if not isinstance(x, dict) and np.asarray(x).ndim != 1:
            raise ValueError(f"x must be one point: a length-{len(self.space)} sequence or a dict, got shape {np.shape(x)}")
        (line,) = self._lines(points, sut=sut, jobs=1, seed=seed)
        record = json.loads(line)
        if record["status"] == "error":
            if on_error == "raise":
                raise TestError(f"test ended in error: {record['error']}", record)
            return math.nan
        return _robustness(record["monitors"], self.passive_monitors)
