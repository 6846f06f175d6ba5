#![allow(non_snake_case)] // The paper's keyword names: numLane, minD, minT.

//! Monitors: the built-in ones, `Stl`, and the program's own (`Monitor`, `Assert`, `Signal`, paper §2, "Invariants and Monitors").

use crate::scene::Site;
use anyhow::{anyhow, bail};
use starlark::environment::GlobalsBuilder;
use starlark::eval::Evaluator;
use starlark::starlark_module;
use starlark::values::none::NoneType;
use starlark::values::{Value, ValueLike};

use crate::lang::scene::SceneBuilder;
use crate::lang::types;
use crate::lang::values::{ActorVal, MonitorVal};
use crate::MonitorSpec;
use paracosm_engine::behaviour::ActorRef;

use super::*;

use crate::lang::builtins::{named, positional, Builtin, Declares, Form};

/// The builtins of this file ([`crate::lang::builtins`]).
pub(crate) const SPECS: &[Builtin] = &[
    Builtin {
        name: "CollisionMonitor",
        form: Form::Function,
        inputs: &[
            positional("a", "an actor"),
            named("name", "string").or("the variable, else \"collision\""),
        ],
        declares: Declares::Monitor,
        takes_whole: true,
        doc: "fails when the actor touches anything solid; robustness: its separation, m",
    },
    Builtin {
        name: "OffRoadMonitor",
        form: Form::Function,
        inputs: &[
            positional("v", "the AutonomousVehicle"),
            named("name", "string").or("\"offroad\""),
        ],
        declares: Declares::Monitor,
        takes_whole: true,
        doc: "fails when the ego vehicle's footprint centre leaves the drivable surface",
    },
    Builtin {
        name: "DistanceMonitor",
        form: Form::Function,
        inputs: &[
            positional("v", "the AutonomousVehicle"),
            named("minD", "number, m, >= 0"),
            named("name", "string").or("\"distance\""),
        ],
        declares: Declares::Monitor,
        takes_whole: true,
        doc: "fails unless the ego vehicle travels at least minD metres",
    },
    Builtin {
        name: "Stl",
        form: Form::Function,
        inputs: &[
            positional("formula", "a signal temporal logic formula over the signals"),
            named("name", "string").or("\"stl\""),
        ],
        declares: Declares::Monitor,
        takes_whole: true,
        doc: "a signal temporal logic requirement; robustness is the formula's",
    },
    Builtin {
        name: "Monitor",
        form: Form::Function,
        inputs: &[
            positional("stream", "a stream of numbers, its robustness"),
            named("name", "string").or("the variable, else \"monitor\""),
            named("unit", "string").or("None"),
            named("over", "\"always\", \"end\" or \"eventually\"").or("\"always\""),
        ],
        declares: Declares::Monitor,
        takes_whole: false,
        doc: "a monitor written as a stream: its robustness is the stream's minimum, last or largest value",
    },
    Builtin {
        name: "Assert",
        form: Form::Function,
        inputs: &[
            positional("stream", "a stream of bools"),
            named("name", "string").or("the variable, else \"assert\""),
        ],
        declares: Declares::Monitor,
        takes_whole: false,
        doc: "fails at the first event that is false; robustness +1 or -1",
    },
    Builtin {
        name: "Signal",
        form: Form::Function,
        inputs: &[
            positional("name", "string"),
            positional("stream", "a stream of numbers, bools or vectors"),
        ],
        declares: Declares::Setting,
        takes_whole: false,
        doc: "publishes a stream under a name, for Stl formulas and the results",
    },
    Builtin {
        name: "TimeToFailure",
        form: Form::Function,
        inputs: &[
            positional("m", "a monitor"),
            named("minT", "number, s, >= 0").or("0.0"),
            named("name", "string").or("the monitor's name"),
        ],
        declares: Declares::Monitor,
        takes_whole: true,
        doc: "wraps a monitor: fails when its first violation comes before minT seconds",
    },
];

pub(super) fn unique_monitor_name(b: &SceneBuilder, name: &str) -> anyhow::Result<()> {
    // A monitor's name keys its verdict in results.jsonl, the CSV columns and JUnit, as a
    // parameter's name does: the same rule.
    if !super::streams::result_name_ok(name) {
        bail!(
            "a monitor's name= is made of letters, digits and _ . [ ] only, got {name:?}: it \
             keys the verdicts in results files, CSV columns and JUnit"
        );
    }
    if b.scene.monitors().any(|(m, _)| m.name() == name) {
        bail!(
            "two monitors are named `{name}`: results are keyed by monitor name, so give one \
             another name="
        );
    }
    Ok(())
}

/// Publishes the stream a `Monitor` or `Assert` named `name` judges, checking that it carries
/// `want` (numbers or bools) when that is known; returns the signal's name.
pub(super) fn publish_monitored(
    eval: &Evaluator,
    stream: Value,
    name: &str,
    what: &str,
    want: types::SType,
) -> anyhow::Result<String> {
    let st = state(eval)?;
    let mut b = st.scene.borrow_mut();
    // A plain number or bool stands for a constant stream, as everywhere a stream is
    // expected (loading warns that its verdict is the same in every test).
    let id = stream_arg(stream, &mut b, what).map_err(|_| {
        anyhow!(
            "{what} judges a stream (such as `v.speed.map(lambda s: 20 - s)`), got {}",
            crate::lang::a_type(stream.get_type())
        )
    })?;
    let kind = b.scene.stream_types()[id.0];
    if kind != want && kind != types::SType::Any {
        bail!(
            "{what} needs a stream of {}, and this one carries {}{}",
            want.name(),
            kind.name(),
            if want == types::SType::Num {
                " (for a stream of bools, use Assert)"
            } else {
                ""
            }
        );
    }
    let signal = format!("monitor:{name}");
    b.scene.publish(signal.clone(), id, None);
    Ok(signal)
}

/// A monitor's name: `name=` when given, else the variable the call is assigned to
/// (`hit = CollisionMonitor(v)` is `hit`), else `default`. Every monitor builtin names its
/// monitor so.
fn monitor_name(eval: &Evaluator, name: Option<&str>, default: &str) -> String {
    name.map(str::to_owned)
        .or_else(|| variable_here(eval))
        .unwrap_or_else(|| default.to_owned())
}

pub(super) fn monitor(eval: &Evaluator, spec: MonitorSpec) -> anyhow::Result<MonitorVal> {
    let st = state(eval)?;
    let mut b = st.scene.borrow_mut();
    unique_monitor_name(&b, spec.name())?;
    let site = Site::of(&here(eval)).with_variable(variable_here(eval));
    Ok(MonitorVal {
        index: b.scene.add_monitor(spec, site),
        wraps: 0,
    })
}

pub(super) fn ego_arg(v: Value, what: &str) -> anyhow::Result<()> {
    let got = match v.downcast_ref::<ActorVal>() {
        Some(a) => match a.kind {
            ActorRef::Ego => return Ok(()),
            ActorRef::Car(_) => "a Car".to_owned(),
            ActorRef::Pedestrian(_) => "a Pedestrian".to_owned(),
            ActorRef::Obstacle(_) => "an Obstacle".to_owned(),
        },
        None => crate::lang::a_type(v.get_type()),
    };
    bail!(
        "{what} watches the AutonomousVehicle; got {got} (to judge another actor, write a \
         Monitor or an Stl formula over its outputs, e.g. `c.speed`)"
    )
}

/// The builtins of this topic.
#[starlark_module]
#[allow(non_snake_case)]
pub(super) fn register(builder: &mut GlobalsBuilder) {
    /// `CollisionMonitor(a, name=<variable> or "collision")`: fails when actor `a` touches
    /// anything solid (for the ego vehicle: a pedestrian, a car or an obstacle; for a car or
    /// a pedestrian also each other and the ego); robustness is its smallest separation in
    /// metres (`0` once it has collided).
    fn CollisionMonitor<'v>(
        v: Value<'v>,
        #[starlark(require = named)] name: Option<&str>,
        eval: &mut Evaluator<'v, '_, '_>,
    ) -> anyhow::Result<MonitorVal> {
        let name = monitor_name(eval, name, "collision");
        let actor = *v.downcast_ref::<ActorVal>().ok_or_else(|| {
            anyhow!(
                "CollisionMonitor watches an actor (the AutonomousVehicle, a Car or a \
                 Pedestrian); got {}",
                crate::lang::a_type(v.get_type())
            )
        })?;
        if actor.kind == ActorRef::Ego {
            return monitor(eval, MonitorSpec::Collision { name });
        }
        // Another actor: its separation, 0 from the step it first touched anything.
        let signal = {
            use paracosm_engine::rx::{Func, Node, StreamId, Value as Rx};
            let st = state(eval)?;
            let mut b = st.scene.borrow_mut();
            unique_monitor_name(&b, &name)?;
            // outputs: pos, vel, heading, speed, collision, collided, separation.
            let pair = b.scene.push(Node::Zip(
                StreamId(actor.outputs[5]),
                StreamId(actor.outputs[6]),
            ));
            let clearance = b.scene.push(Node::Map {
                src: pair,
                f: Func::native("collided ? 0 : separation", |a| match &a[0] {
                    Rx::Tuple(p) => match (&p[0], p[1].as_num()) {
                        (Rx::Bool(true), _) => Ok(Rx::Num(0.0)),
                        (Rx::Bool(false), Some(d)) => Ok(Rx::Num(d)),
                        _ => Err("expected (collided, separation)".into()),
                    },
                    v => Err(paracosm_engine::rx::NativeError(format!(
                        "expected a (collided, separation) pair, got a {}",
                        v.kind()
                    ))),
                }),
            });
            let signal = format!("monitor:{name}");
            b.scene.publish(signal.clone(), clearance, None);
            signal
        };
        monitor(
            eval,
            MonitorSpec::Stream {
                name,
                signal,
                unit: Some("m".into()),
                over: paracosm_oracles::Over::Always,
            },
        )
    }

    /// `OffRoadMonitor(v, name="offroad")`: fails when the centre of the ego vehicle's
    /// footprint leaves the driving surface (a sidewalk, an island, the ground beside the road
    /// or past a dead end); robustness is the smallest signed distance to the surface's edge
    /// in metres.
    fn OffRoadMonitor<'v>(
        v: Value<'v>,
        #[starlark(require = named)] name: Option<&str>,
        eval: &mut Evaluator<'v, '_, '_>,
    ) -> anyhow::Result<MonitorVal> {
        ego_arg(v, "OffRoadMonitor")?;
        monitor(
            eval,
            MonitorSpec::OffRoad {
                name: monitor_name(eval, name, "offroad"),
                implicit: false,
            },
        )
    }

    /// `DistanceMonitor(v, minD=, name="distance")`: fails unless the ego vehicle travels at
    /// least `minD` metres; robustness `D - minD` in metres.
    fn DistanceMonitor<'v>(
        v: Value<'v>,
        #[starlark(require = named)] minD: Value<'v>,
        #[starlark(require = named)] name: Option<&str>,
        eval: &mut Evaluator<'v, '_, '_>,
    ) -> anyhow::Result<MonitorVal> {
        ego_arg(v, "DistanceMonitor")?;
        let min_distance_m = number(minD, "minD")?;
        if !(min_distance_m.is_finite() && min_distance_m >= 0.0) {
            bail!(
                "DistanceMonitor(minD = {min_distance_m}): minD is a distance in metres, >= 0 \
                 (below it no test could fail)"
            );
        }
        monitor(
            eval,
            MonitorSpec::Distance {
                name: monitor_name(eval, name, "distance"),
                min_distance_m,
            },
        )
    }
}

/// The builtins of this topic, continued.
#[starlark_module]
#[allow(non_snake_case)]
pub(super) fn register_stream_monitors(builder: &mut GlobalsBuilder) {
    /// `Stl(formula, name="stl")`: a signal temporal logic property over the runner's
    /// signals ([`crate::signal::ALL`]), judged at the start of the test; robustness in the
    /// formula's units. The formula is parsed when the program loads: a syntax error shows a
    /// caret, an unknown signal is named.
    fn Stl<'v>(
        #[starlark(require = pos)] formula: &str,
        #[starlark(require = named)] name: Option<&str>,
        eval: &mut Evaluator<'v, '_, '_>,
    ) -> anyhow::Result<MonitorVal> {
        // Signal names are checked once the program has run (a Signal(...) or an actor may
        // come later in the program).
        paracosm_oracles::stl::parse(formula).map_err(anyhow::Error::msg)?;
        monitor(
            eval,
            MonitorSpec::Stl {
                // As a Monitor: the variable it is assigned to, else `stl`.
                name: monitor_name(eval, name, "stl"),
                formula: formula.to_owned(),
            },
        )
    }

    /// `Monitor(stream, name=<variable> or "monitor", unit=None, over="always")`: a monitor
    /// written by the program; its robustness is the stream's value taken `over` the test
    /// (`"always"`: the minimum, failing at the first value `<= 0`; `"end"`: the last value;
    /// `"eventually"`: the maximum), in `unit`.
    fn Monitor<'v>(
        #[starlark(require = pos)] stream: Value<'v>,
        #[starlark(require = named)] name: Option<&str>,
        #[starlark(require = named)] unit: Option<&str>,
        #[starlark(require = named)] over: Option<&str>,
        eval: &mut Evaluator<'v, '_, '_>,
    ) -> anyhow::Result<MonitorVal> {
        let word = over.unwrap_or("always");
        let over = paracosm_oracles::Over::parse(word).ok_or_else(|| {
            anyhow!("Monitor(over=) is \"always\", \"end\" or \"eventually\", got {word:?}")
        })?;
        let name = monitor_name(eval, name, "monitor");
        let signal = publish_monitored(eval, stream, &name, "Monitor", types::SType::Num)?;
        monitor(
            eval,
            MonitorSpec::Stream {
                name,
                signal,
                unit: unit.map(str::to_owned),
                over,
            },
        )
    }

    /// `Assert(stream, name=<variable> or "assert")`: fails at the first event of the stream
    /// (of bools) that is false; robustness `+1` or `-1`.
    fn Assert<'v>(
        #[starlark(require = pos)] stream: Value<'v>,
        #[starlark(require = named)] name: Option<&str>,
        eval: &mut Evaluator<'v, '_, '_>,
    ) -> anyhow::Result<MonitorVal> {
        let name = monitor_name(eval, name, "assert");
        let signal = publish_monitored(eval, stream, &name, "Assert", types::SType::Bool)?;
        monitor(eval, MonitorSpec::Assert { name, signal })
    }

    /// `Signal(name, stream)`: publishes a stream of numbers, bools or vectors under `name`
    /// for `Stl` formulas (a vector as `name.x`, `name.y`, `name.z`).
    fn Signal<'v>(
        #[starlark(require = pos)] name: &str,
        #[starlark(require = pos)] stream: Value<'v>,
        eval: &mut Evaluator<'v, '_, '_>,
    ) -> anyhow::Result<NoneType> {
        let valid = name.split('.').all(|part| {
            part.chars()
                .next()
                .is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
                && part.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
        });
        if !valid {
            bail!(
                "Signal: `{name}` is not a signal name (letters, digits and _, parts joined by .)"
            );
        }
        if crate::runner::signal::ALL.contains(&name) {
            bail!("Signal: `{name}` is one of the runner's own signals; choose another name");
        }
        let st = state(eval)?;
        let mut b = st.scene.borrow_mut();
        if b.scene.signals().iter().any(|s| s.name == name) {
            bail!("Signal: `{name}` is published twice");
        }
        let id = stream_arg(stream, &mut b, "Signal")?;
        let kind = b.scene.stream_types()[id.0];
        if matches!(
            kind,
            types::SType::Text | types::SType::Tuple | types::SType::Unit
        ) {
            bail!(
                "Signal `{name}` carries {}; a signal is a number, a bool or a vector",
                kind.name()
            );
        }
        b.scene
            .publish(name.to_owned(), id, Some(Site::of(&here(eval))));
        Ok(NoneType)
    }
}

/// The builtins of this topic, continued.
#[starlark_module]
#[allow(non_snake_case)]
pub(super) fn register_time_to_failure(builder: &mut GlobalsBuilder) {
    /// `TimeToFailure(m, minT=0.0)`: wraps monitor `m`; reports the time of its first
    /// violation and fails when it comes before `minT` seconds (`minT >= 0`, finite, or an
    /// error).
    fn TimeToFailure<'v>(
        m: Value<'v>,
        #[starlark(require = named)] minT: Option<Value<'v>>,
        #[starlark(require = named)] name: Option<&str>,
        eval: &mut Evaluator<'v, '_, '_>,
    ) -> anyhow::Result<MonitorVal> {
        let m = *m.downcast_ref::<MonitorVal>().ok_or_else(|| {
            anyhow!(
                "TimeToFailure wraps a monitor, got {}",
                crate::lang::a_type(m.get_type())
            )
        })?;
        let inner = m.index;
        let min_s = match minT {
            Some(v) => number(v, "minT")?,
            None => 0.0,
        };
        if !(min_s.is_finite() && min_s >= 0.0) {
            bail!(
                "TimeToFailure(minT = {min_s}): minT is a time in seconds, >= 0 (a failure \
                 before it fails the monitor)"
            );
        }
        let st = state(eval)?;
        let mut b = st.scene.borrow_mut();
        let wrapped = b
            .scene
            .monitors()
            .nth(inner)
            .map(|(m, _)| m.clone())
            .ok_or_else(|| anyhow!("no such monitor"))?;
        // The slot holds the outermost wrapper: a monitor wrapped once already is not there
        // any more, and wrapping it again would wrap that wrapper in its name.
        let depth = {
            let mut d = 0;
            let mut spec = &wrapped;
            while let MonitorSpec::TimeToFailure { inner, .. } = spec {
                d += 1;
                spec = inner;
            }
            d
        };
        if depth != m.wraps {
            // The wrapper directly around `m`: `depth - m.wraps - 1` levels inside the slot.
            let mut spec = &wrapped;
            for _ in 0..depth - m.wraps - 1 {
                if let MonitorSpec::TimeToFailure { inner, .. } = spec {
                    spec = inner;
                }
            }
            let at = if depth - m.wraps == 1 {
                format!(
                    " ({})",
                    b.scene
                        .monitors()
                        .nth(inner)
                        .map(|(_, s)| s.to_string())
                        .unwrap_or_default()
                )
            } else {
                String::new()
            };
            bail!(
                "this monitor is wrapped already, by TimeToFailure `{}`{at}: a monitor takes \
                 part in one TimeToFailure, which takes its place in the results; to judge \
                 its failure time against a second minT, declare a second monitor of the same \
                 kind, or wrap that TimeToFailure",
                spec.name(),
            );
        }
        let name = name
            .map(str::to_owned)
            .or_else(|| variable_here(eval))
            .unwrap_or_else(|| "time_to_failure".to_owned());
        let name = name.as_str();
        if wrapped.name() != name {
            unique_monitor_name(&b, name)?;
        }
        let site = Site::of(&here(eval)).with_variable(variable_here(eval));
        b.scene.replace_monitor(
            inner,
            MonitorSpec::TimeToFailure {
                name: name.to_owned(),
                inner: Box::new(wrapped),
                min_s,
            },
            site,
        );
        Ok(MonitorVal {
            index: inner,
            wraps: depth + 1,
        })
    }
}
