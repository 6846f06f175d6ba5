// `Car` takes one argument per keyword, as Starlark calls it: more than clippy's seven.
#![allow(clippy::too_many_arguments)]
#![allow(non_snake_case)] // The paper's keyword names: numLane, minD, minT.

//! Actors: `AutonomousVehicle`, `Car`, `ChangeLane`, `Obstacle`, `Pedestrian`.

use crate::scene::{Scene, Site};
use anyhow::{anyhow, bail};
use paracosm_engine::behaviour::{ActorRef, Output};
use paracosm_engine::rx::{StreamId, Value as Rx};
use paracosm_engine::sut::{AebConfig, SutConfig};
use starlark::environment::GlobalsBuilder;
use starlark::eval::Evaluator;
use starlark::starlark_module;
use starlark::values::list::UnpackList;
use starlark::values::{UnpackValue, Value, ValueLike};

use crate::lang::position::Loc;
use crate::lang::scene::{turns, ObjectDecl, PedTrigger, Pending, PendingCar, SceneBuilder};
use crate::lang::types;
use crate::lang::values::{ActorVal, ChangeStart, LaneChangeVal, ObstacleVal, Stream};

use super::*;

use crate::lang::builtins::{named, Builtin, Declares, Form};

/// `route=` of the ego vehicle and of a car.
const ROUTE: crate::lang::builtins::Arg = named(
    "route",
    "a turn or a list of turns: \"straight\", \"left\", \"right\", \"uturn\", or \"road:ID\" on a map",
)
.or("[]");
/// `color=` of a car or an obstacle.
const COLOUR: &str = "a colour name: red, white, black, blue, green, yellow, orange, silver, grey";

/// The builtins of this file ([`crate::lang::builtins`]).
pub(crate) const SPECS: &[Builtin] = &[
    Builtin {
        name: "AutonomousVehicle",
        form: Form::Function,
        inputs: &[
            named("loc", "a location from onLane"),
            named("sut", "\"aeb\", \"vision\", \"pilotnet\" or \"onnx:PATH\"").or("\"aeb\""),
            ROUTE,
            named("speed", "number, the speed at t = 0")
                .checked(types::number("speed", "m/s", 0.0, f64::INFINITY, false))
                .or("12.0"),
        ],
        declares: Declares::Actor,
        takes_whole: true,
        doc: "the ego vehicle, driven by the system under test",
    },
    Builtin {
        name: "Car",
        form: Form::Function,
        inputs: &[
            named("loc", "a location from onLane"),
            named("speed", "number")
                .checked(types::CAR_SPEED)
                .or("10.0"),
            ROUTE,
            named("color", COLOUR).or("\"red\""),
            named("enabled", "bool: whether the car is in the test").or("True"),
            named("lane_change", "a ChangeLane").or("None"),
            named(
                "keep_distance",
                "number: brakes to stop this far short of what is ahead",
            )
            .checked(types::number(
                "keep_distance",
                "m",
                0.0,
                f64::INFINITY,
                false,
            ))
            .or("None"),
        ],
        declares: Declares::Actor,
        takes_whole: true,
        doc: "an NPC car that follows the lane graph and stops against whatever it meets",
    },
    Builtin {
        name: "ChangeLane",
        form: Form::Function,
        inputs: &[
            named("to", "a lane number of the car's segment"),
            named("at", "number: when it starts")
                .checked(types::number("at", "s", 0.0, f64::INFINITY, false))
                .or("None"),
            named("when", "any stream: its first event starts the change").or("None"),
            named("duration", "number")
                .checked(types::number("duration", "s", 0.0, f64::INFINITY, true))
                .or("3.0"),
        ],
        declares: Declares::Nothing,
        takes_whole: true,
        doc: "a lane change for Car(lane_change=)",
    },
    Builtin {
        name: "Obstacle",
        form: Form::Function,
        inputs: &[
            named("loc", "a location from onLane"),
            named("size", "(length, width, height)")
                .each(types::number("size", "m", 0.0, f64::INFINITY, true))
                .or("(4.5, 1.8, 1.5)"),
            named("color", COLOUR).or("\"grey\""),
        ],
        declares: Declares::Actor,
        takes_whole: true,
        doc: "a static box (a parked car, a cone, a barrier)",
    },
    Builtin {
        name: "Pedestrian",
        form: Form::Function,
        inputs: &[
            named("start", "a location from onLane"),
            named("target", "a location from onLane"),
            named("speed", "number").checked(types::PEDESTRIAN_SPEED),
            named("dist", "number: the trigger distance")
                .checked(types::TRIGGER_DISTANCE)
                .or("None"),
            named("car", "a position stream or an actor").or("None"),
            named("trigger", "any stream: its first event starts the walk").or("None"),
        ],
        declares: Declares::Actor,
        takes_whole: true,
        doc: "walks from start to target once car comes within dist of start (or trigger fires)",
    },
];

pub(super) fn location(v: Value, what: &str) -> anyhow::Result<usize> {
    v.downcast_ref::<Loc>().map(|l| l.index).ok_or_else(|| {
        anyhow!(
            "{what} must be a location from r.onLane(lane, at), got {}",
            crate::lang::a_type(v.get_type())
        )
    })
}

pub(super) fn declare(
    eval: &Evaluator,
    b: &mut SceneBuilder,
    what: &str,
    declare_as: fn(&mut Scene, String, Site) -> ActorRef,
    pending: Pending,
) -> ActorVal {
    let name = object_name(eval, what);
    let at = here(eval);
    let variable = variable_here(eval);
    let site = Site::of(&at).with_variable(variable.clone());
    let actor = declare_as(&mut b.scene, name.clone(), site);
    let outputs = Output::ALL.map(|o| b.probe(actor, o).0);
    b.objects.push(ObjectDecl {
        name,
        at,
        variable,
        actor: Some(actor),
        pending,
        placed: false,
    });
    ActorVal {
        kind: actor,
        outputs,
        object: b.objects.len() - 1,
    }
}

/// A route: `None`, one turn (a string, `Const("left")`, or an open `VarEnum` of turns) or a
/// list of turns.
pub(super) fn route_arg(
    v: Option<Value>,
    b: &SceneBuilder,
) -> anyhow::Result<Option<Vec<paracosm_engine::network::Turn>>> {
    let one = |v: Value| text_value(v, b);
    match v {
        None => Ok(None),
        Some(v) if v.is_none() => Ok(None),
        // One turn, e.g. an open parameter `VarEnum(["left", "straight", "right"])`.
        Some(v) if one(v).is_some() => turns(&[one(v).unwrap_or_default()])
            .map(Some)
            .map_err(|e| anyhow!(e)),
        Some(v) if v.downcast_ref::<Stream>().is_some() => bail!(
            "route is fixed for a test, since the path is planned when the world is built: give \
             a turn, a list of turns or an open VarEnum of turns, not a stream"
        ),
        Some(v) => {
            let wrong = || {
                anyhow!(
                    "route must be a turn or a list of turns such as [\"left\", \"straight\"], \
                     got {}",
                    crate::lang::a_type(v.get_type())
                )
            };
            let items = UnpackList::<Value>::unpack_value(v)
                .ok()
                .flatten()
                .ok_or_else(wrong)?;
            let list = items
                .items
                .into_iter()
                .map(|t| one(t).ok_or_else(wrong))
                .collect::<anyhow::Result<Vec<String>>>()?;
            turns(&list).map(Some).map_err(|e| anyhow!(e))
        }
    }
}

/// The builtins of this topic.
#[starlark_module]
#[allow(non_snake_case)]
pub(super) fn register(builder: &mut GlobalsBuilder) {
    /// `AutonomousVehicle(loc=, sut="aeb", route=None, speed=None)`: the ego vehicle and its
    /// default system under test (`aeb`, `vision`, `pilotnet`, or `onnx:PATH` with `PATH`
    /// relative to the program's file; `--sut`/`--sut-cmd`/`--sut-onnx` override it).
    fn AutonomousVehicle<'v>(
        #[starlark(require = named)] loc: Value<'v>,
        #[starlark(require = named)] sut: Option<&str>,
        #[starlark(require = named)] route: Option<Value<'v>>,
        #[starlark(require = named)] speed: Option<Value<'v>>,
        eval: &mut Evaluator<'v, '_, '_>,
    ) -> anyhow::Result<ActorVal> {
        let loc = location(loc, "loc")?;
        // `onnx:PATH` is relative to the program's folder.
        let at = super::here(eval);
        let file = at.rsplitn(3, ':').nth(2).unwrap_or_default();
        let base = std::path::Path::new(file)
            .parent()
            .unwrap_or(std::path::Path::new(""));
        let sut = SutConfig::named(sut.unwrap_or("aeb"), base).map_err(anyhow::Error::msg)?;
        let initial_speed_mps = match speed {
            Some(v) => number(v, "AutonomousVehicle(speed=), the initial speed,")?,
            None => AebConfig::default().cruise.target_speed_mps,
        };
        if !(initial_speed_mps.is_finite() && initial_speed_mps >= 0.0) {
            bail!("speed {initial_speed_mps} m/s must be >= 0");
        }
        let st = state(eval)?;
        let mut b = st.scene.borrow_mut();
        let route = route_arg(route, &b)?;
        Ok(declare(
            eval,
            &mut b,
            "AutonomousVehicle",
            Scene::declare_ego,
            Pending::Ego {
                loc,
                route,
                initial_speed_mps,
                sut,
            },
        ))
    }
}

/// The builtins of this topic, continued.
#[starlark_module]
#[allow(non_snake_case)]
pub(super) fn register_cars(builder: &mut GlobalsBuilder) {
    /// `Car(loc=, speed=10.0, route=[], color="red", enabled=True, lane_change=None,
    /// keep_distance=None)`: an NPC car that follows the lane graph, may change lanes once
    /// (`ChangeLane`), stops against whatever it meets, and with `keep_distance` (m, `>= 0`)
    /// brakes to stop that far short of whatever is ahead on its path.
    fn Car<'v>(
        #[starlark(require = named)] loc: Value<'v>,
        #[starlark(require = named)] speed: Option<Value<'v>>,
        #[starlark(require = named)] route: Option<Value<'v>>,
        #[starlark(require = named)] color: Option<Value<'v>>,
        #[starlark(require = named)] enabled: Option<Value<'v>>,
        #[starlark(require = named)] lane_change: Option<Value<'v>>,
        #[starlark(require = named)] keep_distance: Option<Value<'v>>,
        eval: &mut Evaluator<'v, '_, '_>,
    ) -> anyhow::Result<ActorVal> {
        let loc = location(loc, "loc")?;
        let keep_distance_m = match keep_distance {
            None => None,
            Some(v) if v.is_none() => None,
            Some(v) => {
                let d = number(v, "Car(keep_distance=)")?;
                if !(d.is_finite() && d >= 0.0) {
                    bail!(
                        "Car(keep_distance=) is the gap in m the car keeps to what is ahead of \
                         it, finite and >= 0, got {d}"
                    );
                }
                Some(d)
            }
        };
        let lane_change = match lane_change {
            None => None,
            Some(v) if v.is_none() => None,
            Some(v) => Some(*v.downcast_ref::<LaneChangeVal>().ok_or_else(|| {
                anyhow!(
                    "Car(lane_change=) takes ChangeLane(to = lane, at = seconds or when = stream, duration = seconds), got {}",
                    crate::lang::a_type(v.get_type())
                )
            })?),
        };
        let heap = eval.heap();
        let st = state(eval)?;
        let mut b = st.scene.borrow_mut();
        let route = route_arg(route, &b)?.unwrap_or_default();
        let at = object_at(eval);
        let speed = typed_arg(
            speed.unwrap_or_else(|| heap.alloc(10.0)),
            &mut b,
            &types::CAR_SPEED,
            "Car",
            &at,
        )?;
        let color = match fixed_typed(
            color.unwrap_or_else(|| heap.alloc("red")),
            &b,
            &types::COLOR,
            "Car",
        )? {
            Rx::Text(t) => t.to_ascii_lowercase(),
            c => bail!("Car(color=) takes a colour name, got a {}", c.kind()),
        };
        let enabled = fixed_typed(
            enabled.unwrap_or_else(|| Value::new_bool(true)),
            &b,
            &types::ENABLED,
            "Car",
        )?
        .as_bool()
        .unwrap_or(true);
        Ok(declare(
            eval,
            &mut b,
            "Car",
            Scene::declare_car,
            Pending::Car(PendingCar {
                loc,
                route,
                speed,
                color,
                enabled,
                lane_change,
                keep_distance_m,
            }),
        ))
    }
}

/// The builtins of this topic, continued.
#[starlark_module]
#[allow(non_snake_case)]
pub(super) fn register_lane_changes_and_obstacles(builder: &mut GlobalsBuilder) {
    /// `ChangeLane(to=, at=None, when=None, duration=3.0)`: a lane change for
    /// `Car(lane_change=)`: to lane `to` of the car's segment, starting `at` seconds into the
    /// test or at the first event of the stream `when`, over `duration` seconds.
    fn ChangeLane<'v>(
        #[starlark(require = named)] to: Value<'v>,
        #[starlark(require = named)] at: Option<Value<'v>>,
        #[starlark(require = named)] when: Option<Value<'v>>,
        #[starlark(require = named)] duration: Option<Value<'v>>,
        eval: &mut Evaluator<'v, '_, '_>,
    ) -> anyhow::Result<LaneChangeVal> {
        let to = number(to, "ChangeLane(to=)")?;
        if to.fract() != 0.0 || to == 0.0 {
            bail!("ChangeLane(to=) is a lane number (1, 2, ... or -1, -2, ...), got {to}");
        }
        let duration_s = match duration {
            Some(v) => number(v, "ChangeLane(duration=)")?,
            None => 3.0,
        };
        if !(duration_s.is_finite() && duration_s > 0.0) {
            bail!("ChangeLane(duration=) takes a number in s, > 0, got {duration_s}");
        }
        let start = match (at, when) {
            (Some(t), None) => {
                let t = number(t, "ChangeLane(at=)")?;
                if !(t.is_finite() && t >= 0.0) {
                    bail!("ChangeLane(at=) takes a number in s, >= 0, got {t}");
                }
                ChangeStart::At(t)
            }
            (None, Some(w)) => {
                let st = state(eval)?;
                let mut b = st.scene.borrow_mut();
                ChangeStart::When(stream_arg(w, &mut b, "ChangeLane(when=)")?.0)
            }
            (Some(_), Some(_)) => bail!(
                "ChangeLane takes one start, at = seconds or when = a stream, not both: a lane \
                 change starts once"
            ),
            (None, None) => bail!("ChangeLane needs either at = seconds or when = a stream"),
        };
        Ok(LaneChangeVal {
            to: to as i32,
            start,
            duration_s,
        })
    }

    /// `Obstacle(loc=, size=(4.5, 1.8, 1.5), color="grey")`: a static box (a parked car, a
    /// cone, a barrier) standing at `loc`, turned along its lane; `size` is its length, width
    /// and height in metres. It collides with the ego vehicle, stops lidar beams and is drawn
    /// by the camera.
    fn Obstacle<'v>(
        #[starlark(require = named)] loc: Value<'v>,
        #[starlark(require = named)] size: Option<Value<'v>>,
        #[starlark(require = named)] color: Option<Value<'v>>,
        eval: &mut Evaluator<'v, '_, '_>,
    ) -> anyhow::Result<ObstacleVal> {
        let loc = location(loc, "loc")?;
        let size = match size {
            None => paracosm_engine::Size::CAR,
            Some(v) => {
                let items: Vec<Value> = v
                    .iterate(eval.heap())
                    .map_err(|_| {
                        anyhow!(
                            "Obstacle(size=) takes (length, width, height) in m, got {}",
                            crate::lang::a_type(v.get_type())
                        )
                    })?
                    .collect();
                let [l, w, h] = items.as_slice() else {
                    bail!(
                        "Obstacle(size=) takes three numbers (length, width, height) in m, got {}",
                        items.len()
                    );
                };
                let size = paracosm_engine::Size {
                    length_m: number(*l, "Obstacle(size=) length")?,
                    width_m: number(*w, "Obstacle(size=) width")?,
                    height_m: number(*h, "Obstacle(size=) height")?,
                };
                if !size.is_valid() {
                    bail!(
                        "Obstacle(size=) needs three lengths in m, each > 0 and <= 1000, got ({}, {}, {})",
                        size.length_m,
                        size.width_m,
                        size.height_m
                    );
                }
                size
            }
        };
        let heap = eval.heap();
        let st = state(eval)?;
        let mut b = st.scene.borrow_mut();
        let color = match fixed_typed(
            color.unwrap_or_else(|| heap.alloc("grey")),
            &b,
            &types::COLOR,
            "Obstacle",
        )? {
            Rx::Text(t) => t.to_ascii_lowercase(),
            c => bail!("Obstacle(color=) takes a colour name, got a {}", c.kind()),
        };
        b.objects.push(ObjectDecl {
            name: object_name(eval, "Obstacle"),
            at: here(eval),
            variable: variable_here(eval),
            actor: None,
            pending: Pending::Obstacle { loc, size, color },
            placed: false,
        });
        Ok(ObstacleVal {
            object: b.objects.len() - 1,
        })
    }
}

/// The builtins of this topic, continued.
#[starlark_module]
#[allow(non_snake_case)]
pub(super) fn register_pedestrians(builder: &mut GlobalsBuilder) {
    /// `Pedestrian(start=, target=, speed=, dist=None, car=None, trigger=None)`: walks from
    /// `start` to `target` once `car` comes within `dist` metres of `start` (or once
    /// `trigger` fires).
    fn Pedestrian<'v>(
        #[starlark(require = named)] start: Value<'v>,
        #[starlark(require = named)] target: Value<'v>,
        #[starlark(require = named)] speed: Value<'v>,
        #[starlark(require = named)] dist: Option<Value<'v>>,
        #[starlark(require = named)] car: Option<Value<'v>>,
        #[starlark(require = named)] trigger: Option<Value<'v>>,
        eval: &mut Evaluator<'v, '_, '_>,
    ) -> anyhow::Result<ActorVal> {
        let (start, target) = (location(start, "start")?, location(target, "target")?);
        let at = object_at(eval);
        let st = state(eval)?;
        let mut b = st.scene.borrow_mut();
        let owner = "Pedestrian";
        let speed = typed_arg(speed, &mut b, &types::PEDESTRIAN_SPEED, owner, &at)?;
        let trigger = match (dist, car, trigger) {
            (Some(d), Some(c), None) => {
                let car = match c.downcast_ref::<ActorVal>() {
                    Some(a) => StreamId(a.outputs[0]),
                    None if c.downcast_ref::<Stream>().is_none() => bail!(
                        "Pedestrian(car=) takes a position (x, y, z) in m that moves: the actor \
                         whose approach triggers the walk (`car = v`) or a stream of its position \
                         (`car = v.pos`), got {c} ({}); a fixed point cannot come near",
                        crate::lang::a_type(c.get_type())
                    ),
                    None => typed_arg(c, &mut b, &types::WATCHED_POSITION, owner, &at)?,
                };
                PedTrigger::Near {
                    car,
                    dist: typed_arg(d, &mut b, &types::TRIGGER_DISTANCE, owner, &at)?,
                }
            }
            (None, None, Some(t)) => {
                PedTrigger::Stream(typed_arg(t, &mut b, &types::TRIGGER, owner, &at)?)
            }
            (None, None, None) => PedTrigger::Never,
            _ => bail!(
                "Pedestrian takes dist= and car= together, or trigger=, or neither (then it \
                 walks only when an action moves it: stream.foreach(p.walk))"
            ),
        };
        Ok(declare(
            eval,
            &mut b,
            "Pedestrian",
            Scene::declare_pedestrian,
            Pending::Pedestrian {
                start,
                target,
                speed,
                trigger,
            },
        ))
    }
}
