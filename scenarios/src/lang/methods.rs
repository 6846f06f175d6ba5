//! Methods of streams, roads and the world.
// `onLane` has three forms (segment, junction, map) and so eight arguments; starlark_module
// generates a function per method, which an attribute on the module function does not reach.
#![allow(clippy::too_many_arguments)]

use anyhow::{anyhow, bail};
use paracosm_engine::network::{Lane, PieceId, PieceKind, Turn};
use paracosm_engine::rx::{Func, NativeError, Node, StreamId, Value as Rx};
use starlark::environment::MethodsBuilder;
use starlark::eval::Evaluator;
use starlark::starlark_module;
use starlark::values::tuple::{TupleRef, UnpackTuple};
use starlark::values::{none::NoneType, Value, ValueLike};

use super::globals::{here, number, state, stream_arg};
use super::position::Loc;
use super::scene::{LaneRef, SceneBuilder};
use super::values::{Action, ActorVal, LaneSide, Port, Road, Stream, WorldVal, PORTS};
use starlark::environment::Methods;
use starlark::values::{starlark_value, Heap, StarlarkValue};

use super::builtins::{named, positional, Builtin, Declares, Form};

/// A stream method's spec: computes a stream, takes what it is given into code.
const fn stream_method(
    name: &'static str,
    inputs: &'static [super::builtins::Arg],
    takes_whole: bool,
    doc: &'static str,
) -> Builtin {
    Builtin {
        name,
        form: Form::Method("stream"),
        inputs,
        declares: Declares::Nothing,
        takes_whole,
        doc,
    }
}

/// An action's spec ([`super::values::Action`]).
const fn action(
    name: &'static str,
    on: &'static str,
    inputs: &'static [super::builtins::Arg],
    doc: &'static str,
) -> Builtin {
    Builtin {
        name,
        form: Form::Action(on),
        inputs,
        declares: Declares::Nothing,
        // `walk` takes nothing to follow.
        takes_whole: !inputs.is_empty(),
        doc,
    }
}

/// The methods and actions of this file ([`super::builtins`]).
pub(crate) const SPECS: &[Builtin] = &[
    stream_method(
        "map",
        &[positional("f", "a function of the event")],
        false,
        "f(v) for each event v",
    ),
    stream_method(
        "filter",
        &[positional("p", "a predicate of the event")],
        false,
        "the events for which p(v) is true",
    ),
    stream_method(
        "zip",
        &[positional("other", "a stream")],
        true,
        "pairs (a_i, b_i)",
    ),
    stream_method(
        "take",
        &[positional("n", "whole number >= 0")],
        false,
        "the first n events",
    ),
    stream_method(
        "skipUntil",
        &[positional("trigger", "a stream")],
        true,
        "events from the first event of trigger on",
    ),
    stream_method(
        "takeUntil",
        &[positional("stop", "a stream")],
        true,
        "events until the first event of stop",
    ),
    stream_method(
        "concat",
        &[positional("second", "a stream")],
        true,
        "a's events, then b's",
    ),
    stream_method(
        "sum",
        &[
            positional("init", "a number or a Vector").or("zero"),
            positional("f", "a fold acc, v -> acc").or("None"),
        ],
        false,
        "running total of numbers or vectors, or a fold",
    ),
    stream_method("min", &[], false, "the running minimum of a number stream"),
    stream_method("max", &[], false, "the running maximum of a number stream"),
    stream_method(
        "foreach",
        &[positional(
            "action",
            "an action, or a function that calls actions",
        )],
        false,
        "each event performs the action",
    ),
    Builtin {
        name: "onLane",
        form: Form::Method("road"),
        inputs: &[
            positional(
                "lane",
                "a lane number or r.SideWalk (a segment); a port (a junction)",
            ),
            positional("at", "number, m along the lane or path").checked(super::types::number(
                "at",
                "m",
                f64::NEG_INFINITY,
                f64::INFINITY,
                false,
            )),
            named("lane", "a lane from 1 (a junction's path)").or("1"),
            named("turn", "\"straight\", \"left\", \"right\" (a junction)"),
            named("road", "an OpenDRIVE <road id> (a map)"),
            named("s", "number, m along the road's reference line (a map)"),
            named("port", "a junction's port"),
        ],
        declares: Declares::Nothing,
        takes_whole: true,
        doc: "a location on a lane: where an actor starts or a pedestrian walks to",
    },
    Builtin {
        name: "connect",
        form: Form::Method("road"),
        inputs: &[positional("links", "(parent.PORT, child, child.PORT), ...")],
        declares: Declares::Nothing,
        takes_whole: true,
        doc: "joins each child to a port of this road or network, checked",
    },
    Builtin {
        name: "place",
        form: Form::Method("World"),
        inputs: &[positional("objects", "roads and actors, ...")],
        declares: Declares::Nothing,
        takes_whole: true,
        doc: "adds roads and actors to the scene and checks the placement",
    },
    action(
        "walk",
        "Pedestrian",
        &[],
        "one walking step toward the target",
    ),
    action(
        "setSpeed",
        "Car",
        &[positional("v", "number").checked(super::types::number(
            "v",
            "m/s",
            0.0,
            f64::INFINITY,
            false,
        ))],
        "drives at v from now on",
    ),
    action(
        "brake",
        "Car",
        &[positional("decel", "number").checked(super::types::number(
            "decel",
            "m/s²",
            0.0,
            f64::INFINITY,
            true,
        ))],
        "slows by decel times the step and keeps the lower speed",
    ),
    action(
        "changeLane",
        "Car",
        &[
            positional("lane", "a lane number of its start segment"),
            positional("duration", "number")
                .checked(super::types::number(
                    "duration",
                    "s",
                    0.0,
                    f64::INFINITY,
                    true,
                ))
                .or("3.0"),
        ],
        "changes to another lane of its segment",
    ),
];

/// The names of the methods registered on streams, roads and the world (for the test that
/// every one has a spec).
#[cfg(test)]
pub(crate) fn registered_names() -> Vec<&'static str> {
    let ty = starlark::typing::Ty::any();
    let mut names = Vec::new();
    for f in [stream_methods, road_methods, world_methods] {
        let methods = MethodsBuilder::new().with(f).build();
        for (name, _) in methods.documentation(ty.clone()).members {
            names.push(&*String::leak(name));
        }
    }
    names
}

/// Stores `f` as host function `n` and returns `Func::Host(n)`.
fn lambda<'v>(f: Value<'v>, what: &str, eval: &mut Evaluator<'v, '_, '_>) -> anyhow::Result<Func> {
    if f.get_type() != "function" {
        bail!(
            "{what} needs a function (a lambda or a def), got {}",
            crate::lang::a_type(f.get_type())
        );
    }
    let st = state(eval)?;
    let n = {
        let mut b = st.scene.borrow_mut();
        b.lambdas += 1;
        b.lambdas - 1
    };
    eval.module().set(&super::lambda_name(n), f);
    Ok(Func::Host(n))
}

fn push(eval: &Evaluator<'_, '_, '_>, node: Node) -> anyhow::Result<Stream> {
    let st = state(eval)?;
    let id = st
        .scene
        .borrow_mut()
        .scene
        .graph_mut()
        .push_at(node, here(eval));
    Ok(Stream::of(id.0))
}

fn other<'v>(
    v: Value<'v>,
    what: &str,
    eval: &mut Evaluator<'v, '_, '_>,
) -> anyhow::Result<StreamId> {
    let st = state(eval)?;
    let mut b = st.scene.borrow_mut();
    stream_arg(v, &mut b, what)
}

/// The stream methods (paper §2; `engine::rx` gives their semantics): the combinators ([`stream_combinators`]) and folds ([`stream_folds`]).
pub(crate) fn stream_methods(builder: &mut MethodsBuilder) {
    stream_combinators(builder);
    stream_folds(builder);
}

/// Stream methods: the combinators.
#[starlark_module]
fn stream_combinators(builder: &mut MethodsBuilder) {
    /// `s.map(f)`: `f(v)` for each event `v`.
    fn map<'v>(
        this: &Stream,
        f: Value<'v>,
        eval: &mut Evaluator<'v, '_, '_>,
    ) -> anyhow::Result<Stream> {
        let f = lambda(f, "map", eval)?;
        push(
            eval,
            Node::Map {
                src: StreamId(this.id),
                f,
            },
        )
    }

    /// `s.filter(p)`: the events for which `p(v)` is true.
    fn filter<'v>(
        this: &Stream,
        p: Value<'v>,
        eval: &mut Evaluator<'v, '_, '_>,
    ) -> anyhow::Result<Stream> {
        let pred = lambda(p, "filter", eval)?;
        push(
            eval,
            Node::Filter {
                src: StreamId(this.id),
                pred,
            },
        )
    }

    /// `a.zip(b)`: pairs `(a_i, b_i)`.
    fn zip<'v>(
        this: &Stream,
        other_stream: Value<'v>,
        eval: &mut Evaluator<'v, '_, '_>,
    ) -> anyhow::Result<Stream> {
        let b = other(other_stream, "zip", eval)?;
        push(eval, Node::Zip(StreamId(this.id), b))
    }

    /// `s.take(n)`: the first `n` events.
    fn take<'v>(this: &Stream, n: i32, eval: &mut Evaluator<'v, '_, '_>) -> anyhow::Result<Stream> {
        if n < 0 {
            bail!("take needs n >= 0, got {n}");
        }
        push(
            eval,
            Node::Take {
                src: StreamId(this.id),
                n: n as u64,
            },
        )
    }

    /// `s.skipUntil(t)`: events from the first event of `t` on.
    fn skipUntil<'v>(
        this: &Stream,
        trigger: Value<'v>,
        eval: &mut Evaluator<'v, '_, '_>,
    ) -> anyhow::Result<Stream> {
        let t = other(trigger, "skipUntil", eval)?;
        push(
            eval,
            Node::SkipUntil {
                src: StreamId(this.id),
                trigger: t,
            },
        )
    }

    /// `s.takeUntil(t)`: events until the first event of `t`.
    fn takeUntil<'v>(
        this: &Stream,
        stop: Value<'v>,
        eval: &mut Evaluator<'v, '_, '_>,
    ) -> anyhow::Result<Stream> {
        let t = other(stop, "takeUntil", eval)?;
        push(
            eval,
            Node::TakeUntil {
                src: StreamId(this.id),
                stop: t,
            },
        )
    }

    /// `a.concat(b)`: `a`'s events, then `b`'s.
    fn concat<'v>(
        this: &Stream,
        second: Value<'v>,
        eval: &mut Evaluator<'v, '_, '_>,
    ) -> anyhow::Result<Stream> {
        let b = other(second, "concat", eval)?;
        push(eval, Node::Concat(StreamId(this.id), b))
    }
}

/// Stream methods, continued: the folds and `foreach`.
#[starlark_module]
fn stream_folds(builder: &mut MethodsBuilder) {
    /// `s.sum(init=0.0, f=None)`: running total of numbers or vectors (from zero of the
    /// stream's kind, or from `init`: a number or a `Vector`), or running fold
    /// `acc = f(acc, v)` (from `init`, default 0.0).
    fn sum<'v>(
        this: &Stream,
        #[starlark(default = NoneType)] init: Value<'v>,
        #[starlark(default = NoneType)] f: Value<'v>,
        eval: &mut Evaluator<'v, '_, '_>,
    ) -> anyhow::Result<Stream> {
        let init = if init.is_none() {
            // A total starts from zero of the kind of the first event; a fold from 0.0.
            if f.is_none() {
                Rx::Unit
            } else {
                Rx::Num(0.0)
            }
        } else if let Some(v) = init.downcast_ref::<super::position::Vector>() {
            Rx::Vec3(v.0)
        } else {
            Rx::Num(number(
                init,
                "sum(init=) (a number, or a Vector for a sum of vectors)",
            )?)
        };
        let f = if f.is_none() {
            None
        } else {
            Some(lambda(f, "sum", eval)?)
        };
        push(
            eval,
            Node::Sum {
                src: StreamId(this.id),
                init,
                f,
            },
        )
    }

    /// `s.min()`: the running minimum of a number stream (an event per event of `s`).
    fn min<'v>(this: &Stream, eval: &mut Evaluator<'v, '_, '_>) -> anyhow::Result<Stream> {
        extreme(this, eval, "min", f64::INFINITY, f64::min)
    }

    /// `s.max()`: the running maximum of a number stream.
    fn max<'v>(this: &Stream, eval: &mut Evaluator<'v, '_, '_>) -> anyhow::Result<Stream> {
        extreme(this, eval, "max", f64::NEG_INFINITY, f64::max)
    }

    /// `s.foreach(action)`: each event performs `action`: `p.walk`, `car.setSpeed`,
    /// `car.brake(decel)`, `car.changeLane(lane)` (unbound: the event's value is the
    /// argument), or a function of the event that calls actions.
    fn foreach<'v>(
        this: &Stream,
        action: Value<'v>,
        eval: &mut Evaluator<'v, '_, '_>,
    ) -> anyhow::Result<NoneType> {
        let src = StreamId(this.id);
        if let Some(a) = action.downcast_ref::<Action>() {
            let src = match a.bound_value() {
                Some(v) => {
                    if a.method == "changeLane" {
                        check_lane(a, eval)?;
                    }
                    // The argument rides in the graph as a fold's initial value, kept at every
                    // event, so that a world whose argument differs differs in its graph (the
                    // usage analysis sees which parameters an action reads).
                    let keep = Func::native("the action's argument", |a| Ok(a[0].clone()));
                    push(
                        eval,
                        Node::Sum {
                            src,
                            init: v,
                            f: Some(keep),
                        },
                    )?
                    .id
                }
                None => src.0,
            };
            push(
                eval,
                Node::Foreach {
                    src: StreamId(src),
                    sink: a.sink,
                },
            )?;
            return Ok(NoneType);
        }
        if action.get_type() != "function" {
            bail!(
                "foreach needs an action (`p.walk`, `car.brake(6)`, `car.setSpeed`, \
                 `car.changeLane(2)`) or a function that performs actions, got {}",
                crate::lang::a_type(action.get_type())
            );
        }
        let f = lambda(action, "foreach", eval)?;
        push(eval, Node::Perform { src, f })?;
        Ok(NoneType)
    }
}

/// A running minimum or maximum: `sum(init, f)` with a native fold.
fn extreme(
    this: &Stream,
    eval: &Evaluator<'_, '_, '_>,
    name: &'static str,
    init: f64,
    pick: fn(f64, f64) -> f64,
) -> anyhow::Result<Stream> {
    let f = Func::native(name, move |a| match (&a[0], &a[1]) {
        (Rx::Num(acc), Rx::Num(v)) => Ok(Rx::Num(pick(*acc, *v))),
        (_, v) => Err(NativeError(format!(
            "{name}() needs a stream of numbers, got a {}",
            v.kind()
        ))),
    });
    push(
        eval,
        Node::Sum {
            src: StreamId(this.id),
            init: Rx::Num(init),
            f: Some(f),
        },
    )
}

/// Checks at load that a bound `car.changeLane(lane)` names a lane of the segment the car
/// starts on.
fn check_lane(a: &Action, eval: &Evaluator<'_, '_, '_>) -> anyhow::Result<()> {
    use paracosm_engine::behaviour::{Action as Act, ActorRef};
    let (Act::ChangeLane(car), Some((lane, _))) = (a.sink, a.bound) else {
        return Ok(());
    };
    let at = super::globals::here(eval);
    let st = state(eval)?;
    let mut b = st.scene.borrow_mut();
    let Some(object) = b
        .objects
        .iter()
        .find(|o| o.actor == Some(ActorRef::Car(car)))
        .cloned()
    else {
        return Ok(());
    };
    let super::scene::Pending::Car(super::scene::PendingCar { loc, .. }) = &object.pending else {
        return Ok(());
    };
    let Some(start) = b
        .locs
        .get(*loc)
        .and_then(|r| r.resolve(b.scene.roads()).ok())
    else {
        return Ok(());
    };
    let lanes = b.lane_offsets(&start);
    if !lanes.iter().any(|(l, _)| f64::from(*l) == lane) {
        let known: Vec<String> = lanes.iter().map(|(l, _)| l.to_string()).collect();
        bail!(
            "{}.changeLane({lane}): the segment it starts on has {}",
            object.name,
            if known.is_empty() {
                "no lanes to change to (it starts inside a junction or on an OpenDRIVE map)"
                    .to_owned()
            } else {
                format!("the lanes {}", known.join(", "))
            }
        );
    }
    // Into the other direction's lane: allowed (an overtaking manoeuvre), with the warning
    // ChangeLane(to=) gives.
    if let paracosm_engine::Lane::Driving(k) = start.lane {
        if f64::from(k).signum() != lane.signum() {
            b.warnings.push(crate::scenario::Warning {
                at,
                message: format!(
                    "{}.changeLane({lane}) moves it from lane {k} into a lane of the other \
                     direction, where it goes on driving its own way (against the traffic there)",
                    object.name
                ),
            });
        }
    }
    Ok(())
}

fn lane_of(v: Value) -> anyhow::Result<Lane> {
    if let Some(s) = v.downcast_ref::<LaneSide>() {
        return Ok(if s.opposite {
            Lane::OppositeSideWalk
        } else {
            Lane::SideWalk
        });
    }
    // A whole number, also as a float (`nlanes / 2`) or `Const(2)`.
    match number(v, "onLane(lane=)") {
        Ok(x) if x.fract() == 0.0 && x.abs() <= f64::from(i32::MAX) => Ok(Lane::Driving(x as i32)),
        Ok(x) if x.fract() != 0.0 || !x.is_finite() => bail!("a lane is a whole number, got {x}"),
        Ok(x) => bail!("a lane number is at most {} in size, got {x}", i32::MAX),
        Err(e) if v.downcast_ref::<Stream>().is_some() => Err(e),
        Err(_) => bail!(
            "a lane is a lane number or r.SideWalk / -r.SideWalk, got {}",
            crate::lang::a_type(v.get_type())
        ),
    }
}

/// The arguments of `onLane`, by position or by keyword: a segment's `(lane, at)`, a
/// junction's `(port, turn, at, lane=)`, a map's `(road=, lane=, s=)`.
struct OnLaneArgs<'v> {
    first: Option<Value<'v>>,
    second: Option<Value<'v>>,
    at: Option<Value<'v>>,
    lane: Option<Value<'v>>,
    port: Option<Value<'v>>,
    turn: Option<Value<'v>>,
    road: Option<Value<'v>>,
    s: Option<Value<'v>>,
}

/// An argument that may be given by position or by name, once.
fn once<'v>(
    pos: Option<Value<'v>>,
    named: Option<Value<'v>>,
    what: &str,
) -> anyhow::Result<Option<Value<'v>>> {
    match (pos, named) {
        (Some(_), Some(_)) => Err(anyhow!(
            "onLane: {what} is given twice, by position and as {what}="
        )),
        (p, n) => Ok(p.or(n)),
    }
}

impl<'v> OnLaneArgs<'v> {
    /// A map's onLane takes `road=`, `lane=`, `s=` and nothing else; a piece's takes no
    /// `road=` or `s=`.
    fn check_form(&self, this: &Road) -> anyhow::Result<()> {
        let positional = self.first.is_some()
            || self.second.is_some()
            || self.at.is_some()
            || self.port.is_some()
            || self.turn.is_some();
        if this.map != (self.road.is_some() || self.s.is_some()) || (this.map && positional) {
            if this.map {
                bail!("an OpenDrive map's onLane takes road=, lane= and s= by name: m.onLane(road = \"1\", lane = -1, s = 20.0)");
            }
            bail!("onLane(road=, lane=, s=) is for an OpenDrive map; this is a road piece");
        }
        Ok(())
    }

    /// `m.onLane(road=, lane=, s=)` on the map `piece`.
    fn on_map(&self, this: &Road, piece: PieceId, b: &SceneBuilder) -> anyhow::Result<LaneRef> {
        let (Some(road), Some(lane), Some(s)) = (self.road, self.lane, self.s) else {
            bail!("an OpenDrive map's onLane needs road=, lane= and s=: m.onLane(road = \"1\", lane = -1, s = 20.0)");
        };
        let road = match super::globals::text_value(road, b) {
            Some(t) => t,
            None => {
                let x = number(road, "onLane(road=)").map_err(|_| {
                    anyhow!("onLane(road=) is a <road id>, a string such as \"1\", got {road}")
                })?;
                if x.fract() != 0.0 {
                    bail!("onLane(road=) is a <road id>, a string such as \"1\", got {x}");
                }
                format!("{x:.0}")
            }
        };
        let lane = number(lane, "onLane(lane=)")?;
        if lane.fract() != 0.0 || lane == 0.0 {
            bail!("onLane(lane=) on a map is an OpenDRIVE <lane id>: a whole number, not 0 (negative right of the reference line), got {lane}");
        }
        if lane.abs() > paracosm_engine::network::opendrive::MAX_LANES_PER_SIDE as f64 {
            bail!(
                "onLane(lane=) on a map is an OpenDRIVE <lane id>, at most {} from the centre lane 0 (a map's section has at most that many lanes a side), got {lane}",
                paracosm_engine::network::opendrive::MAX_LANES_PER_SIDE
            );
        }
        let s_m = number(s, "onLane(s=)")?;
        let PieceKind::Map { map, .. } = &b.scene.roads().piece(piece).kind else {
            bail!("{this} is no map");
        };
        match map.0.roads.iter().position(|r| r.od_id == road) {
            Some(index) => Ok(LaneRef::Map {
                piece,
                road: index,
                lane: lane as i32,
                s_m,
            }),
            // The map's message lists its roads.
            None => Err(anyhow!(map.0.lane_at(&road, lane as i32, s_m).unwrap_err())),
        }
    }

    /// `r.onLane(lane, at)` on the segment `piece`.
    fn on_segment(&self, piece: PieceId) -> anyhow::Result<LaneRef> {
        if self.port.is_some() || self.turn.is_some() {
            bail!("a RoadSegment's onLane takes (lane, at); port= and turn= are for junctions: j.onLane(port, turn, at, lane=)");
        }
        let (lane, at) = match (self.first, self.second, self.at) {
            (_, Some(_), Some(_)) => bail!(
                "a RoadSegment's onLane takes (lane, at), each once; onLane(port, turn, at, lane=) is for junctions"
            ),
            (first, second, at) => (once(first, self.lane, "lane")?, second.or(at)),
        };
        let (Some(lane), Some(at)) = (lane, at) else {
            bail!("a RoadSegment's onLane needs a lane and how far along it: r.onLane(lane, at), or r.onLane(lane = 1, at = 20.0)");
        };
        Ok(LaneRef::Segment {
            piece,
            lane: lane_of(lane)?,
            at_m: number(at, "onLane(at=)")?,
        })
    }

    /// `j.onLane(port, turn, at, lane=1)` in the junction or roundabout `piece`.
    fn in_junction(
        &self,
        this: &Road,
        piece: PieceId,
        b: &SceneBuilder,
    ) -> anyhow::Result<LaneRef> {
        let (Some(first), Some(second)) = (
            once(self.first, self.port, "port")?,
            once(self.second, self.turn, "turn")?,
        ) else {
            bail!("a junction's onLane takes (port, turn, at, lane=): j.onLane(j.ONE, \"left\", 5.0), or j.onLane(port = j.ONE, turn = \"left\", at = 5.0)");
        };
        let port = match first.downcast_ref::<Port>() {
            Some(p) if p.piece == this.piece => p.index,
            Some(p) => bail!(
                "a junction's onLane takes one of its own ports first (such as j.ONE), got {}.{}, a port of another piece",
                b.scene.roads().piece(PieceId(p.piece)).name,
                crate::lang::values::PORTS[p.index]
            ),
            None => bail!(
                "a junction's onLane takes one of its ports first (such as j.ONE), got {}",
                crate::lang::a_type(first.get_type())
            ),
        };
        let turn = super::globals::text_value(second, b)
            .as_deref()
            .and_then(Turn::parse)
            .ok_or_else(|| {
                if second.downcast_ref::<Stream>().is_some() {
                    anyhow!("a junction's onLane takes one turn for the whole test (the start is placed when the world is built): \"straight\", \"left\", \"right\" or an open VarEnum of them, not a stream")
                } else {
                    anyhow!("a junction's onLane takes a turn second: \"straight\", \"left\" or \"right\", got {second}")
                }
            })?;
        let at = self
            .at
            .ok_or_else(|| anyhow!("a junction's onLane needs how far along its path, at="))?;
        let lane = match self.lane {
            Some(v) => {
                let x = number(v, "onLane(lane=)")?;
                if x.fract() != 0.0 || x < 1.0 {
                    bail!("onLane(lane=) is a lane number from 1, got {x}");
                }
                x as u32
            }
            None => 1,
        };
        Ok(LaneRef::Junction {
            piece,
            entry: port,
            turn,
            lane,
            at_m: number(at, "onLane(at=)")?,
        })
    }
}

/// Road methods: `onLane` and `connect`.
#[starlark_module]
pub(crate) fn road_methods(builder: &mut MethodsBuilder) {
    /// `r.onLane(lane, at)` on a segment: the point `at` metres along lane `lane` (a number,
    /// negative for the opposite direction, or `r.SideWalk` / `-r.SideWalk`).
    /// `j.onLane(port, turn, at, lane=1)` in a junction or roundabout: the point `at` metres
    /// along the lane path that enters through `port` in lane `lane` and makes `turn`
    /// (`"straight"`, `"left"`, `"right"`).
    /// `m.onLane(road=, lane=, s=)` on an OpenDRIVE map: the centre of lane `lane` (its
    /// `<lane id>`, negative right of the reference line) of road `road` (its `<road id>`) at
    /// `s` metres along the road's reference line.
    fn onLane<'v>(
        this: &Road,
        #[starlark(require = pos)] first: Option<Value<'v>>,
        #[starlark(require = pos)] second: Option<Value<'v>>,
        at: Option<Value<'v>>,
        lane: Option<Value<'v>>,
        #[starlark(require = named)] port: Option<Value<'v>>,
        #[starlark(require = named)] turn: Option<Value<'v>>,
        #[starlark(require = named)] road: Option<Value<'v>>,
        #[starlark(require = named)] s: Option<Value<'v>>,
        eval: &mut Evaluator<'v, '_, '_>,
    ) -> anyhow::Result<Loc> {
        if this.network {
            bail!("onLane needs a road piece, not the network connect returns: call it on one of the pieces");
        }
        let st = state(eval)?;
        let mut b = st.scene.borrow_mut();
        let args = OnLaneArgs {
            first,
            second,
            at,
            lane,
            port,
            turn,
            road,
            s,
        };
        args.check_form(this)?;
        let piece = PieceId(this.piece);
        let r = if this.map {
            args.on_map(this, piece, &b)?
        } else if this.segment {
            args.on_segment(piece)?
        } else {
            args.in_junction(this, piece, &b)?
        };
        let at = r.resolve(b.scene.roads()).map_err(|e| anyhow!(e))?;
        b.locs.push(r);
        if let Ok(mut t) = b.loc_table.write() {
            t.push(Some(at));
        }
        Ok(Loc {
            index: b.locs.len() - 1,
            table: b.loc_table.clone(),
        })
    }

    /// `parent.connect((parent.PORT, child, child.PORT), ...)`: joins each child to a port of
    /// this road or network, positioning it; returns the composite network.
    fn connect<'v>(
        this: &Road,
        #[starlark(args)] links: UnpackTuple<Value<'v>>,
        eval: &mut Evaluator<'v, '_, '_>,
    ) -> anyhow::Result<Road> {
        let st = state(eval)?;
        let mut b = st.scene.borrow_mut();
        if b.placed {
            bail!("connect after place(...): the world is already placed");
        }
        for link in links.items {
            connect_one(&mut b, this, link)?;
        }
        // Pieces moved: every location stands where the network now puts it.
        b.resolve_locations();
        Ok(Road {
            network: true,
            ..*this
        })
    }
}

/// One `(port, child, child_port)` tuple of `parent.connect(...)`: joins the child to the
/// port of `this` road or network.
///
/// # Errors
/// A tuple of another shape, a child port not of the child, a port outside this network, or
/// the network's refusal (overlap, mismatched lanes).
fn connect_one<'v>(b: &mut SceneBuilder, this: &Road, link: Value<'v>) -> anyhow::Result<()> {
    let t = TupleRef::from_value(link)
        .filter(|t| t.len() == 3)
        .ok_or_else(|| anyhow!("connect takes tuples (port, child, child_port), got {link}"))?;
    let items = t.content();
    let port = |v: Value<'v>| {
        v.downcast_ref::<Port>().copied().ok_or_else(|| {
            anyhow!(
                "connect's tuples name ports first and last (such as t.ONE), got {}",
                crate::lang::a_type(v.get_type())
            )
        })
    };
    let (p, c) = (port(items[0])?, port(items[2])?);
    let child = items[1].downcast_ref::<Road>().ok_or_else(|| {
        anyhow!(
            "connect's tuples name a road piece second, got {}",
            crate::lang::a_type(items[1].get_type())
        )
    })?;
    let port_name = |q: Port| b.scene.roads().port_name((PieceId(q.piece), q.index));
    let piece_name = |i: usize| b.scene.roads().piece(PieceId(i)).name.clone();
    if c.piece != child.piece {
        bail!(
            "the child port {} is not a port of the child {}: the third item of each \
             tuple is a port of the second",
            port_name(c),
            piece_name(child.piece),
        );
    }
    if b.scene.roads().group_of(PieceId(p.piece)) != b.scene.roads().group_of(PieceId(this.piece)) {
        bail!(
            "the port {} belongs to neither {} nor a piece already connected to it: \
             connect it from its own piece or network",
            port_name(p),
            piece_name(this.piece)
        );
    }
    b.scene
        .roads_mut()
        .connect(PieceId(p.piece), p.index, PieceId(c.piece), c.index)
        .map_err(|e| anyhow!(super::scene::strip(e)))?;
    Ok(())
}

/// World methods: `place`.
#[starlark_module]
pub(crate) fn world_methods(builder: &mut MethodsBuilder) {
    /// `w.place(objects...)`: adds roads and actors to the scene and checks the placement.
    fn place<'v>(
        #[allow(unused_variables)] this: &super::values::WorldVal,
        #[starlark(args)] objects: UnpackTuple<Value<'v>>,
        eval: &mut Evaluator<'v, '_, '_>,
    ) -> anyhow::Result<NoneType> {
        let at = super::globals::here(eval);
        let st = state(eval)?;
        let mut b = st.scene.borrow_mut();
        b.placed_at = Some(at);
        let mut actors = Vec::new();
        for o in objects.items {
            if let Some(a) = o.downcast_ref::<ActorVal>() {
                if a.object == super::globals::import::IMPORTED {
                    bail!(
                        "{o} comes from Import(...), whose scenario places it: leave it out of \
                         place(...)"
                    );
                }
                actors.push(a.object);
            } else if let Some(x) = o.downcast_ref::<super::values::ObstacleVal>() {
                actors.push(x.object);
            } else if o.downcast_ref::<Road>().is_none() {
                bail!(
                    "place takes roads, actors and obstacles, got {}",
                    crate::lang::a_type(o.get_type())
                );
            }
        }
        b.place(&actors).map_err(|e| anyhow!(e))?;
        Ok(NoneType)
    }
}

// The Starlark types with methods, here beside their methods so that `values.rs` needs
// nothing of this module.

starlark::methods_static!(STREAM_METHODS = stream_methods);

#[starlark_value(type = "Stream")]
impl<'v> StarlarkValue<'v> for Stream {
    fn get_methods() -> Option<&'static Methods> {
        Some(STREAM_METHODS.methods())
    }
}

starlark::methods_static!(ROAD_METHODS = road_methods);

#[starlark_value(type = "Road")]
impl<'v> StarlarkValue<'v> for Road {
    fn get_methods() -> Option<&'static Methods> {
        Some(ROAD_METHODS.methods())
    }

    fn get_attr(&self, attribute: &str, heap: Heap<'v>) -> Option<Value<'v>> {
        if attribute == "SideWalk" && self.segment {
            return Some(heap.alloc(LaneSide { opposite: false }));
        }
        let i = PORTS.iter().position(|p| *p == attribute)?;
        (i < self.ports && !self.network).then(|| {
            heap.alloc(Port {
                piece: self.piece,
                index: i,
            })
        })
    }

    fn dir_attr(&self) -> Vec<String> {
        let mut v: Vec<String> = PORTS[..self.ports].iter().map(|s| s.to_string()).collect();
        if self.segment {
            v.push("SideWalk".into());
        }
        v
    }
}

starlark::methods_static!(WORLD_METHODS = world_methods);

#[starlark_value(type = "World")]
impl<'v> StarlarkValue<'v> for WorldVal {
    fn get_methods() -> Option<&'static Methods> {
        Some(WORLD_METHODS.methods())
    }

    fn get_attr(&self, attribute: &str, heap: Heap<'v>) -> Option<Value<'v>> {
        match attribute {
            "light" => Some(heap.alloc(Stream::of(self.light))),
            "fog" => Some(heap.alloc(Stream::of(self.fog))),
            _ => None,
        }
    }

    fn dir_attr(&self) -> Vec<String> {
        vec!["light".into(), "fog".into()]
    }
}
