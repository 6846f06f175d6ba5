#![allow(non_snake_case)] // The paper's keyword names: numLane, minD, minT.

//! The world and its roads: `World`, `RoadSegment`, `Arc`, `Clothoid`, `TIntersection`,
//! `CrossIntersection`, `Roundabout`, `SideWalk` (paper §2, "Road pieces"), and `OpenDrive`
//! maps.

use anyhow::{anyhow, bail};
use paracosm_engine::network::PieceKind;
use paracosm_engine::rx::{Node, StreamId, Value as Rx};
use paracosm_engine::NOMINAL_LIGHT;
use starlark::environment::GlobalsBuilder;
use starlark::eval::Evaluator;
use starlark::starlark_module;
use starlark::values::Value;

use crate::lang::scene::SceneBuilder;
use crate::lang::types;
use crate::lang::values::{LaneSide, Road, WorldVal};

use super::*;

use crate::lang::builtins::{named, positional, Builtin, Declares, Form};

/// `nlanes=` and its paper spelling `numLane=` (every piece takes either, not both).
const NLANES: [crate::lang::builtins::Arg; 2] = [
    named("nlanes", "even whole number, 2–16").or("2"),
    named("numLane", "as nlanes (the paper's spelling)").or("2"),
];
/// `friction=` of every piece.
const FRICTION: crate::lang::builtins::Arg = named("friction", "number")
    .checked(types::FRICTION)
    .or("0.8");

/// The builtins of this file ([`crate::lang::builtins`]).
pub(crate) const SPECS: &[Builtin] = &[
    Builtin {
        name: "World",
        form: Form::Function,
        inputs: &[
            named("light", "number").checked(types::LIGHT).or("0.5"),
            named("fog", "number").checked(types::FOG).or("0.0"),
        ],
        declares: Declares::Actor,
        takes_whole: true,
        doc: "global conditions as streams: illumination (0.5 nominal daylight) and fog",
    },
    Builtin {
        name: "RoadSegment",
        form: Form::Function,
        inputs: &[
            named("len", "number")
                .checked(types::number(
                    "len",
                    "m",
                    0.0,
                    paracosm_engine::network::MAX_EXTENT_M,
                    true,
                ))
                .or("200.0"),
            NLANES[0],
            NLANES[1],
            FRICTION,
        ],
        declares: Declares::RoadPiece,
        takes_whole: true,
        doc: "a straight road with ports ONE and TWO",
    },
    Builtin {
        name: "Arc",
        form: Form::Function,
        inputs: &[
            named("radius", "number (of the centre line)")
                .checked(types::number(
                    "radius",
                    "m",
                    0.0,
                    paracosm_engine::network::MAX_EXTENT_M,
                    true,
                ))
                .or("50.0"),
            named("angle", "number, positive to the left")
                .checked(types::number(
                    "angle",
                    "rad",
                    -types::MAX_TURN,
                    types::MAX_TURN,
                    false,
                ))
                .or("π/2"),
            NLANES[0],
            NLANES[1],
            FRICTION,
        ],
        declares: Declares::RoadPiece,
        takes_whole: true,
        doc: "a bend of constant curvature",
    },
    Builtin {
        name: "Clothoid",
        form: Form::Function,
        inputs: &[
            named("length", "number")
                .checked(types::number("length", "m", 0.0, 10_000.0, true))
                .or("50.0"),
            named("curv_start", "number, positive to the left")
                .checked(types::number("curv_start", "1/m", -0.1, 0.1, false))
                .or("0.0"),
            named("curv_end", "number, positive to the left")
                .checked(types::number("curv_end", "1/m", -0.1, 0.1, false))
                .or("0.02"),
            NLANES[0],
            NLANES[1],
            FRICTION,
        ],
        declares: Declares::RoadPiece,
        takes_whole: true,
        doc: "a road whose curvature changes linearly along its length",
    },
    Builtin {
        name: "OpenDrive",
        form: Form::Function,
        inputs: &[
            positional(
                "path",
                "a .xodr file relative to the program, or a VarEnum of them",
            ),
            FRICTION,
        ],
        declares: Declares::RoadPiece,
        takes_whole: true,
        doc: "every road, lane and junction of an OpenDRIVE map",
    },
    Builtin {
        name: "TIntersection",
        form: Form::Function,
        inputs: &[NLANES[0], NLANES[1], FRICTION],
        declares: Declares::RoadPiece,
        takes_whole: true,
        doc: "a T junction with ports ONE, TWO (the through road) and THREE (the stem)",
    },
    Builtin {
        name: "CrossIntersection",
        form: Form::Function,
        inputs: &[NLANES[0], NLANES[1], FRICTION],
        declares: Declares::RoadPiece,
        takes_whole: true,
        doc: "a four-way junction with ports ONE to FOUR",
    },
    Builtin {
        name: "Roundabout",
        form: Form::Function,
        inputs: &[
            NLANES[0],
            NLANES[1],
            named("radius", "number, at least the lanes' width plus an island")
                .checked(types::number("radius", "m", 0.0, 1_000.0, true))
                .or("20.0"),
            FRICTION,
        ],
        declares: Declares::RoadPiece,
        takes_whole: true,
        doc: "a roundabout with ports ONE to FOUR",
    },
];

pub(super) fn lanes(v: Option<Value>, b: &SceneBuilder, default: u32) -> anyhow::Result<u32> {
    let Some(v) = v else { return Ok(default) };
    let x = load_time_number(v, b, "nlanes=")?;
    if x.fract() != 0.0 || !(2.0..=16.0).contains(&x) || (x as u32) % 2 == 1 {
        bail!("nlanes must be an even whole number from 2 to 16, got {x}");
    }
    Ok(x as u32)
}

/// A piece's size argument: its one value for the test (see `load_time_number`), or `default`.
fn number_or(v: Option<Value>, b: &SceneBuilder, what: &str, default: f64) -> anyhow::Result<f64> {
    v.map_or(Ok(default), |v| load_time_number(v, b, what))
}

pub(super) fn add_piece(
    eval: &Evaluator,
    what: &str,
    kind: PieceKind,
    friction: StreamId,
) -> anyhow::Result<Road> {
    let st = state(eval)?;
    let mut b = st.scene.borrow_mut();
    // Segments and curved pieces have onLane(lane, at) and sidewalks.
    let segment = kind.road_length_m().is_some();
    let ports = kind.ports().len();
    let name = object_name(eval, what);
    let site = crate::scene::Site::of(&super::here(eval));
    let id = b
        .scene
        .add_road(|roads| roads.add(&name, kind), friction, site)
        .map_err(|e| anyhow!(crate::lang::scene::strip(e)))?;
    Ok(Road {
        piece: id.0,
        ports,
        segment,
        network: false,
        map: false,
    })
}

/// A road piece from its keyword arguments: `make` gets the program's declarations, the lane
/// count (default 2) and the friction at the start (default 0.8; for a friction that varies
/// over the test, its value is set from its stream every step) and reads any further
/// arguments.
pub(super) fn road_piece(
    eval: &Evaluator,
    what: &str,
    nlanes: Option<Value>,
    friction: Option<Value>,
    make: impl FnOnce(&SceneBuilder, u32, f64) -> anyhow::Result<PieceKind>,
) -> anyhow::Result<Road> {
    let at = object_at(eval);
    let (kind, stream) = {
        let st = state(eval)?;
        let mut b = st.scene.borrow_mut();
        let stream = match friction {
            Some(v) => typed_arg(v, &mut b, &types::FRICTION, what, &at)?,
            None => b.scene.push(Node::Const(Rx::Num(0.8))),
        };
        let mu = match b.scene.nodes().get(stream.0) {
            Some(Node::Const(Rx::Num(mu))) => *mu,
            _ => 0.8,
        };
        let lanes = lanes(nlanes, &b, 2)?;
        (make(&b, lanes, mu)?, stream)
    };
    add_piece(eval, what, kind, stream)
}

/// The lane count given as `nlanes=` or as the paper's `numLane=`.
///
/// # Errors
/// Both given: one would be ignored.
fn lane_count<'v>(
    what: &str,
    nlanes: Option<Value<'v>>,
    num_lane: Option<Value<'v>>,
) -> anyhow::Result<Option<Value<'v>>> {
    match (nlanes, num_lane) {
        (Some(_), Some(_)) => Err(anyhow!(
            "{what} takes nlanes= or numLane= (the paper's spelling of it), not both"
        )),
        (a, b) => Ok(a.or(b)),
    }
}

/// The builtins of this topic.
#[starlark_module]
#[allow(non_snake_case)]
pub(super) fn register(builder: &mut GlobalsBuilder) {
    const SideWalk: LaneSide = LaneSide { opposite: false };

    /// `World(light=0.5, fog=0.0)`: global conditions as streams (light 0.5 is the nominal
    /// daylight a camera's exposure is calibrated for).
    fn World<'v>(
        #[starlark(require = named)] light: Option<Value<'v>>,
        #[starlark(require = named)] fog: Option<Value<'v>>,
        eval: &mut Evaluator<'v, '_, '_>,
    ) -> anyhow::Result<WorldVal> {
        let st = state(eval)?;
        let mut b = st.scene.borrow_mut();
        if b.scene.environment().is_some() {
            bail!("a program has one World");
        }
        let heap = eval.heap();
        let at = object_at(eval);
        let light = typed_arg(
            light.unwrap_or_else(|| heap.alloc(NOMINAL_LIGHT)),
            &mut b,
            &types::LIGHT,
            "World",
            &at,
        )?;
        let fog = typed_arg(
            fog.unwrap_or_else(|| heap.alloc(0.0)),
            &mut b,
            &types::FOG,
            "World",
            &at,
        )?;
        b.scene
            .set_environment(light, fog, crate::scene::Site::of(&at))
            .map_err(|e| anyhow!("a program has one World: {e}"))?;
        Ok(WorldVal {
            light: light.0,
            fog: fog.0,
        })
    }

    /// `RoadSegment(len=200.0, nlanes=2, friction=0.8)`; `numLane=` is the paper's spelling of
    /// `nlanes=` (every piece takes either, not both).
    fn RoadSegment<'v>(
        #[starlark(require = named)] len: Option<Value<'v>>,
        #[starlark(require = named)] nlanes: Option<Value<'v>>,
        #[starlark(require = named)] numLane: Option<Value<'v>>,
        #[starlark(require = named)] friction: Option<Value<'v>>,
        eval: &mut Evaluator<'v, '_, '_>,
    ) -> anyhow::Result<Road> {
        road_piece(
            eval,
            "RoadSegment",
            lane_count("RoadSegment", nlanes, numLane)?,
            friction,
            |b, lanes, friction| {
                let length_m = match len {
                    Some(v) => load_time_number(v, b, "RoadSegment(len=)")?,
                    None => 200.0,
                };
                Ok(PieceKind::Segment {
                    length_m,
                    lanes,
                    friction,
                })
            },
        )
    }

    /// `Arc(radius=50.0, angle=π/2, nlanes=2, friction=0.8)`: a bend of constant curvature;
    /// `radius` in m (of the centre line), `angle` in rad, positive to the left.
    fn Arc<'v>(
        #[starlark(require = named)] radius: Option<Value<'v>>,
        #[starlark(require = named)] angle: Option<Value<'v>>,
        #[starlark(require = named)] nlanes: Option<Value<'v>>,
        #[starlark(require = named)] numLane: Option<Value<'v>>,
        #[starlark(require = named)] friction: Option<Value<'v>>,
        eval: &mut Evaluator<'v, '_, '_>,
    ) -> anyhow::Result<Road> {
        let nlanes = lane_count("Arc", nlanes, numLane)?;
        road_piece(eval, "Arc", nlanes, friction, |b, lanes, friction| {
            Ok(PieceKind::Arc {
                radius_m: number_or(radius, b, "Arc(radius=)", 50.0)?,
                angle_rad: number_or(angle, b, "Arc(angle=)", std::f64::consts::FRAC_PI_2)?,
                lanes,
                friction,
            })
        })
    }
}

/// The builtins of this topic, continued.
#[starlark_module]
#[allow(non_snake_case)]
pub(super) fn register_curves_and_maps(builder: &mut GlobalsBuilder) {
    /// `Clothoid(length=50.0, curv_start=0.0, curv_end=0.02, nlanes=2, friction=0.8)`: a
    /// road whose curvature (1/m, positive to the left) changes linearly along its `length`
    /// (m), the transition between a straight and a bend.
    fn Clothoid<'v>(
        #[starlark(require = named)] length: Option<Value<'v>>,
        #[starlark(require = named)] curv_start: Option<Value<'v>>,
        #[starlark(require = named)] curv_end: Option<Value<'v>>,
        #[starlark(require = named)] nlanes: Option<Value<'v>>,
        #[starlark(require = named)] numLane: Option<Value<'v>>,
        #[starlark(require = named)] friction: Option<Value<'v>>,
        eval: &mut Evaluator<'v, '_, '_>,
    ) -> anyhow::Result<Road> {
        let nlanes = lane_count("Clothoid", nlanes, numLane)?;
        road_piece(eval, "Clothoid", nlanes, friction, |b, lanes, friction| {
            Ok(PieceKind::Clothoid {
                length_m: number_or(length, b, "Clothoid(length=)", 50.0)?,
                curv_start: number_or(curv_start, b, "Clothoid(curv_start=)", 0.0)?,
                curv_end: number_or(curv_end, b, "Clothoid(curv_end=)", 0.02)?,
                lanes,
                friction,
            })
        })
    }

    /// `OpenDrive(path, friction=0.8)`: every road, lane and junction of the OpenDRIVE map at
    /// `path` (relative to the program's file; a string, or a `VarEnum` of them), with
    /// tyre–road friction `friction` on all its lanes.
    fn OpenDrive<'v>(
        #[starlark(require = pos)] path: Value<'v>,
        #[starlark(require = named)] friction: Option<Value<'v>>,
        eval: &mut Evaluator<'v, '_, '_>,
    ) -> anyhow::Result<Road> {
        let at = object_at(eval);
        let (kind, stream) = {
            let st = state(eval)?;
            let mut b = st.scene.borrow_mut();
            let file = crate::lang::globals::text_value(path, &b).ok_or_else(|| {
                anyhow!("OpenDrive takes the path of a .xodr file (a string, or a VarEnum of them), got {path}")
            })?;
            let map = st.maps.load(&file).map_err(|e| anyhow!(e))?;
            let stream = match friction {
                Some(v) => typed_arg(v, &mut b, &types::FRICTION, "OpenDrive", &at)?,
                None => b.scene.push(Node::Const(Rx::Num(0.8))),
            };
            let mu = match b.scene.nodes().get(stream.0) {
                Some(Node::Const(Rx::Num(mu))) => *mu,
                _ => 0.8,
            };
            (PieceKind::Map { map, friction: mu }, stream)
        };
        let road = add_piece(eval, "OpenDrive", kind, stream)?;
        Ok(Road { map: true, ..road })
    }
}

/// The builtins of this topic, continued.
#[starlark_module]
#[allow(non_snake_case)]
pub(super) fn register_junctions(builder: &mut GlobalsBuilder) {
    /// `TIntersection(nlanes=2, friction=0.8)`; `numLane=` is the paper's spelling.
    fn TIntersection<'v>(
        #[starlark(require = named)] nlanes: Option<Value<'v>>,
        #[starlark(require = named)] numLane: Option<Value<'v>>,
        #[starlark(require = named)] friction: Option<Value<'v>>,
        eval: &mut Evaluator<'v, '_, '_>,
    ) -> anyhow::Result<Road> {
        road_piece(
            eval,
            "TIntersection",
            lane_count("TIntersection", nlanes, numLane)?,
            friction,
            |_, lanes, friction| Ok(PieceKind::TIntersection { lanes, friction }),
        )
    }

    /// `CrossIntersection(nlanes=2, friction=0.8)`; `numLane=` too.
    fn CrossIntersection<'v>(
        #[starlark(require = named)] nlanes: Option<Value<'v>>,
        #[starlark(require = named)] numLane: Option<Value<'v>>,
        #[starlark(require = named)] friction: Option<Value<'v>>,
        eval: &mut Evaluator<'v, '_, '_>,
    ) -> anyhow::Result<Road> {
        road_piece(
            eval,
            "CrossIntersection",
            lane_count("CrossIntersection", nlanes, numLane)?,
            friction,
            |_, lanes, friction| Ok(PieceKind::CrossIntersection { lanes, friction }),
        )
    }

    /// `Roundabout(nlanes=2, radius=20.0, friction=0.8)`; `numLane=` too.
    fn Roundabout<'v>(
        #[starlark(require = named)] nlanes: Option<Value<'v>>,
        #[starlark(require = named)] numLane: Option<Value<'v>>,
        #[starlark(require = named)] radius: Option<Value<'v>>,
        #[starlark(require = named)] friction: Option<Value<'v>>,
        eval: &mut Evaluator<'v, '_, '_>,
    ) -> anyhow::Result<Road> {
        road_piece(
            eval,
            "Roundabout",
            lane_count("Roundabout", nlanes, numLane)?,
            friction,
            |b, lanes, friction| {
                let radius_m = match radius {
                    Some(v) => load_time_number(v, b, "Roundabout(radius=)")?,
                    None => 20.0,
                };
                Ok(PieceKind::Roundabout {
                    lanes,
                    radius_m,
                    friction,
                })
            },
        )
    }
}
