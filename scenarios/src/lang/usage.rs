//! Which inputs each open parameter changes, found when the program loads by building the
//! world with each of the parameter's other values and comparing it with the first: a
//! parameter that changes nothing and that no code reads is left out of coverage, and one that
//! cannot affect the ego is named in a warning (LANGUAGE.md, "Warnings").

use std::collections::{BTreeSet, HashSet};

use paracosm_engine::network::{PieceId, Surface};
use paracosm_engine::WorldSpec;

use super::names::Syntax;
use super::scene::{ParamDecl, SceneBuilder};
use super::types;
use crate::scenario::{CameraOnly, Warning};

/// What changed between two worlds of one program.
#[derive(Debug, Clone, PartialEq)]
pub enum Change {
    /// The light (a stream no other stream reads).
    Light,
    /// The colour of car `i`.
    Colour(usize),
    /// The colour of obstacle `i`.
    ObstacleColour(usize),
    /// The friction of a road piece, named, and whether a vehicle can be on it during a test
    /// in either of the two worlds compared (see [`driven`]).
    Friction {
        /// The piece's name in messages.
        piece: String,
        /// Whether the ego can reach it within the horizon, or a car's route crosses it.
        driven: bool,
    },
    /// Anything else: geometry, an actor, a speed, the fog, a stream's value...
    Other,
}

fn debug<T: std::fmt::Debug>(x: &T) -> String {
    format!("{x:?}")
}

/// Whether two parts of worlds differ: not equal, and not written alike either (equal but
/// for a NaN in the same place). Comparing first is what keeps this cheap: writing a car's
/// route of thousands of points for every comparison took 0.15 s of a grid program's load.
fn differ<T: PartialEq + std::fmt::Debug>(a: &T, b: &T) -> bool {
    a != b && debug(a) != debug(b)
}

/// The streams some node reads.
fn read_streams(w: &WorldSpec) -> HashSet<usize> {
    w.streams
        .nodes()
        .iter()
        .flat_map(|n| n.inputs())
        .map(|s| s.0)
        .collect()
}

/// Where the program made streams whose values nothing uses (`file:line:col`): no object's
/// input, friction, light, fog, lane change, published signal (`Monitor`, `Assert`,
/// `Signal`), `foreach`, nor a lambda reading it by name (`read_by_name`: the streams of
/// top-level variables that code reads, as `lambda s: s > limit` reads `limit`) uses them,
/// directly or through other streams, so any parameter read only by their functions changes
/// no result. Only the last stream of an unread chain is named (`s = tick.map(f).filter(p)`
/// names the `filter`), and only streams made by a combinator (`map`, `filter`, `zip`,
/// `take`, `skipUntil`, `takeUntil`, `concat`, `sum`); a probe such as `v.speed` taken and
/// left unused costs nothing.
pub fn unread_streams(w: &WorldSpec, read_by_name: &[usize]) -> BTreeSet<String> {
    use paracosm_engine::rx::Node;
    let nodes = w.streams.nodes();
    let mut stack: Vec<usize> = w
        .cars
        .iter()
        .flat_map(|c| {
            let when = match c.lane_change.map(|l| l.start) {
                Some(paracosm_engine::LaneChangeStart::When(id)) => Some(id.0),
                _ => None,
            };
            [Some(c.speed.0), when]
        })
        .flatten()
        .chain(w.pedestrians.iter().map(|p| p.speed.0))
        .chain(w.frictions.iter().map(|(_, s)| s.0))
        .chain([w.environment.light.0, w.environment.fog.0])
        .chain(w.published.iter().map(|(_, s)| s.0))
        .chain(read_by_name.iter().copied())
        .chain(
            nodes
                .iter()
                .enumerate()
                .filter(|(_, n)| matches!(n, Node::Foreach { .. } | Node::Perform { .. }))
                .map(|(i, _)| i),
        )
        .collect();
    let mut live = vec![false; nodes.len()];
    while let Some(i) = stack.pop() {
        if i < nodes.len() && !live[i] {
            live[i] = true;
            stack.extend(nodes[i].inputs().iter().map(|s| s.0));
        }
    }
    let read = read_streams(w);
    nodes
        .iter()
        .enumerate()
        .filter(|&(i, n)| {
            !live[i]
                && !read.contains(&i)
                && !matches!(
                    n,
                    Node::Const(_)
                        | Node::Tick
                        | Node::Param(_)
                        | Node::Open(_)
                        | Node::Probe(_)
                        | Node::Check { .. }
                )
        })
        .filter_map(|(i, _)| w.streams.made_at(i).map(str::to_owned))
        .collect()
}

/// What differs between two lists of painted things (cars, obstacles): item `i`'s colour alone
/// is `colour(i)`; any other difference, or another count, is [`Change::Other`].
fn recoloured<T: Clone + PartialEq + std::fmt::Debug>(
    a: &[T],
    b: &[T],
    paint: impl Fn(&mut T) -> &mut String,
    colour: fn(usize) -> Change,
    out: &mut Vec<Change>,
) {
    if a.len() != b.len() {
        out.push(Change::Other);
        return;
    }
    for (i, (x, y)) in a.iter().zip(b).enumerate() {
        let (mut x2, mut y2) = (x.clone(), y.clone());
        if paint(&mut x2) != paint(&mut y2) {
            out.push(colour(i));
        }
        *paint(&mut y2) = paint(&mut x2).clone();
        if differ(x, &y2) {
            out.push(Change::Other);
        }
    }
}

/// What differs between `a` and `b`, two worlds of one program whose tests last `horizon_s`.
pub fn changes(a: &WorldSpec, b: &WorldSpec, horizon_s: f64) -> Vec<Change> {
    let mut out = Vec::new();
    // The pieces a vehicle can be on, in either world, worked out once a friction differs.
    let mut reached: Option<HashSet<PieceId>> = None;
    let mut friction = |p: PieceId, out: &mut Vec<Change>| {
        let reached = reached.get_or_insert_with(|| {
            let mut r = driven(a, horizon_s);
            r.extend(driven(b, horizon_s));
            r
        });
        out.push(Change::Friction {
            piece: a.network.piece(p).name.clone(),
            driven: reached.contains(&p),
        });
    };
    let other = |c: bool, out: &mut Vec<Change>| {
        if c {
            out.push(Change::Other);
        }
    };
    piece_changes(a, b, &mut friction, &mut out);
    other(differ(&a.ego, &b.ego), &mut out);
    other(differ(&a.pedestrians, &b.pedestrians), &mut out);
    recoloured(
        &a.obstacles,
        &b.obstacles,
        |o| &mut o.color,
        Change::ObstacleColour,
        &mut out,
    );
    other(
        differ(&a.environment, &b.environment) || a.dt_s != b.dt_s,
        &mut out,
    );
    other(differ(&a.sensors, &b.sensors), &mut out);
    other(differ(&a.frictions, &b.frictions), &mut out);
    car_changes(a, b, &mut out);
    stream_changes(a, b, &mut friction, &mut out);
    out
}

/// What differs between the road pieces of `a` and `b`, pushed on `out`: a piece's friction
/// alone goes to `friction`; any other difference (geometry, links, another count) is
/// [`Change::Other`].
fn piece_changes(
    a: &WorldSpec,
    b: &WorldSpec,
    friction: &mut impl FnMut(PieceId, &mut Vec<Change>),
    out: &mut Vec<Change>,
) {
    // Road pieces: a friction, or geometry.
    let (pa, pb) = (a.network.pieces(), b.network.pieces());
    if pa.len() != pb.len() || differ(&a.network.links(), &b.network.links()) {
        out.push(Change::Other);
    } else {
        for (i, (x, y)) in pa.iter().zip(pb).enumerate() {
            if x == y {
                continue;
            }
            let mut y2 = y.clone();
            y2.kind = y.kind.with_friction(x.kind.friction());
            if *x == y2 {
                friction(PieceId(i), out);
            } else {
                out.push(Change::Other);
            }
        }
    }
}

/// What differs between the cars of `a` and `b`, pushed on `out`: a car's colour, or
/// [`Change::Other`]; a car disabled in both worlds counts as unchanged.
fn car_changes(a: &WorldSpec, b: &WorldSpec, out: &mut Vec<Change>) {
    // A car disabled in both worlds is not in either test (nothing collides with it or sees
    // it): what else differs about it changes nothing.
    if a.cars.len() == b.cars.len() && a.cars.iter().any(|c| !c.enabled) {
        let mut cars_b = b.cars.clone();
        for (x, y) in a.cars.iter().zip(cars_b.iter_mut()) {
            if !x.enabled && !y.enabled {
                *y = x.clone();
            }
        }
        recoloured(&a.cars, &cars_b, |c| &mut c.color, Change::Colour, out);
    } else {
        recoloured(&a.cars, &b.cars, |c| &mut c.color, Change::Colour, out);
    }
}

/// What differs between the streams of `a` and `b`, pushed on `out`: the light, a piece's
/// friction (to `friction`), or [`Change::Other`] for a stream something reads.
fn stream_changes(
    a: &WorldSpec,
    b: &WorldSpec,
    friction: &mut impl FnMut(PieceId, &mut Vec<Change>),
    out: &mut Vec<Change>,
) {
    // Streams: the light, a piece's friction, or anything else.
    let (na, nb) = (a.streams.nodes(), b.streams.nodes());
    if na.len() != nb.len() {
        out.push(Change::Other);
    } else {
        let read = read_streams(a);
        // A disabled car's speed drives nothing (a change of `enabled` itself is a change of
        // the cars, above).
        let inputs: HashSet<usize> = a
            .cars
            .iter()
            .zip(&b.cars)
            .filter(|(x, y)| x.enabled || y.enabled)
            .map(|(c, _)| c.speed.0)
            .chain(a.pedestrians.iter().map(|p| p.speed.0))
            .chain([a.environment.fog.0])
            // What the monitors judge: `Monitor(k)`, `Assert(VarEnum([True, False]))`.
            .chain(a.published.iter().map(|(_, id)| id.0))
            .collect();
        for (i, (x, y)) in na.iter().zip(nb).enumerate() {
            if debug(x) == debug(y) {
                continue;
            }
            let piece = a.frictions.iter().find(|(_, s)| s.0 == i).map(|(p, _)| *p);
            if read.contains(&i) || inputs.contains(&i) {
                out.push(Change::Other);
            } else if i == a.environment.light.0 {
                out.push(Change::Light);
            } else if let Some(p) = piece {
                friction(p, out);
            }
            // Any other stream is read by nothing: a constant friction, which the network
            // carries and the comparison of the pieces has seen.
        }
    }
}

/// What [`analyse`] needs.
pub struct Inputs<'a> {
    /// Each parameter's final name and declaration.
    pub params: &'a [(String, ParamDecl)],
    /// What each parameter's other values changed, by parameter.
    pub changes: &'a [Vec<Change>],
    /// Whether code of the program (a lambda, a `def`, an expression) reads the parameter's
    /// variable, by parameter.
    pub read_in_code: &'a [bool],
    /// Whether an `Stl` formula reads the `light` signal.
    pub stl_reads_light: bool,
    /// The program's first evaluation (for the cars' and obstacles' names).
    pub world: &'a SceneBuilder,
}

/// The findings: warnings, the parameters no object reads (by index), and those only a camera
/// sees.
pub struct Usage {
    /// Warnings, in parameter order.
    pub warnings: Vec<Warning>,
    /// Indices of the parameters that change nothing.
    pub unused: Vec<usize>,
    /// Parameters only a camera sees.
    pub camera_only: Vec<CameraOnly>,
}

/// Pieces a vehicle can be on during a test of world `w`: every piece the ego can reach
/// within the horizon (on or off the road, at full throttle all the way: the engine bounds any
/// system's acceleration), and every piece an NPC car in the test drives over on its route.
fn driven(w: &WorldSpec, horizon_s: f64) -> HashSet<PieceId> {
    let mut driven = HashSet::new();
    let ego = &w.ego;
    // Two driven wheels (rear-wheel drive).
    let a = 2.0 * ego.vehicle.max_engine_force_n / ego.vehicle.mass_kg;
    let reach_m = ego.initial_speed_mps * horizon_s + 0.5 * a * horizon_s * horizon_s;
    let start = [ego.start.pos_m[0], ego.start.pos_m[2]];
    driven.extend(
        (0..w.network.pieces().len())
            .map(PieceId)
            .filter(|&id| w.network.distance_to_piece_m(id, start) <= reach_m),
    );
    let surface = Surface::new(&w.network);
    for c in w.cars.iter().filter(|c| c.enabled) {
        driven.extend(c.path.iter().filter_map(|&p| surface.piece_under(p)));
    }
    driven
}

/// Whether a change cannot affect the ego: a friction where no vehicle can be, or what only a
/// camera sees (a colour; the light, unless an `Stl` formula reads it).
pub fn inert(c: &Change, stl_reads_light: bool) -> bool {
    match c {
        Change::Friction { driven, .. } => !driven,
        Change::Colour(_) | Change::ObstacleColour(_) => true,
        Change::Light => !stl_reads_light,
        Change::Other => false,
    }
}

/// Classifies every parameter by what it changes.
pub fn analyse(i: Inputs<'_>) -> Usage {
    let mut usage = Usage {
        warnings: Vec::new(),
        unused: Vec::new(),
        camera_only: Vec::new(),
    };
    for (k, (name, decl)) in i.params.iter().enumerate() {
        let changes = &i.changes[k];
        if i.read_in_code[k] {
            continue;
        }
        if changes.is_empty() {
            usage.unused.push(k);
            usage.warnings.push(Warning {
                at: decl.site.to_string(),
                message: format!(
                    "`{name}` is sampled but no object uses it: every value builds the same \
                     world, so coverage leaves it out (summary.json lists it under unused_params)"
                ),
            });
            continue;
        }
        let undriven = |c: &Change| matches!(c, Change::Friction { driven: false, .. });
        if changes.iter().all(undriven) {
            let pieces: BTreeSet<String> = changes
                .iter()
                .filter_map(|c| match c {
                    Change::Friction { piece, .. } => Some(piece.clone()),
                    _ => None,
                })
                .collect();
            usage.warnings.push(Warning {
                at: decl.site.to_string(),
                message: format!(
                    "`{name}` sets the friction of {}, where no vehicle can be during a test (the \
                     ego cannot get there within the horizon even at full throttle, and no car's \
                     route crosses it): it cannot affect the ego",
                    pieces.into_iter().collect::<Vec<_>>().join(", ")
                ),
            });
            continue;
        }
        if changes.iter().all(|c| inert(c, i.stl_reads_light)) {
            let mut sets: Vec<String> = Vec::new();
            for c in changes {
                let s = match c {
                    Change::Light => "the light".to_owned(),
                    Change::Colour(car) => format!(
                        "the colour of {}",
                        i.world.scene.car_name(*car).unwrap_or("a car")
                    ),
                    Change::ObstacleColour(k) => format!(
                        "the colour of {}",
                        i.world.scene.obstacle_name(*k).unwrap_or("an obstacle")
                    ),
                    _ => continue,
                };
                if !sets.contains(&s) {
                    sets.push(s);
                }
            }
            usage.camera_only.push(CameraOnly {
                param: name.clone(),
                at: decl.site.to_string(),
                sets: sets.join(" and "),
            });
        }
    }
    usage
}

/// A warning for each parameter declared with a `unit=` that is passed whole to an input in
/// another unit (`unit = "km/h"` feeding `Car(speed=)`, in m/s).
pub fn unit_warnings(params: &[(String, ParamDecl)], syntax: &Syntax) -> Vec<Warning> {
    // Spellings of one unit compare equal: spaces dropped, `m/s^2` and `m/s**2` are `m/s²`.
    let norm = |u: &str| {
        u.split_whitespace()
            .collect::<String>()
            .replace("**", "^")
            .replace("^2", "²")
            .replace("^3", "³")
    };
    let mut out = Vec::new();
    for (name, decl) in params {
        let (Some(unit), Some(site)) = (&decl.unit, syntax.site(&decl.site.to_string())) else {
            continue;
        };
        // Where it is passed whole: through its variable, or written inline in the call; or
        // added to other numbers through its variable (`onLane(1, 10.0 + gap)`).
        let mut inputs: Vec<(&str, &str)> = site
            .variable
            .as_deref()
            .map(|v| {
                let mut all = syntax.passed_to(v);
                all.extend(syntax.summed_in(v));
                all
            })
            .unwrap_or_default();
        if let Some((builtin, keyword)) = &site.argument_of {
            inputs.push((builtin, keyword));
        }
        for (builtin, keyword) in inputs {
            if let Some(input) = super::builtins::input_of(builtin, keyword) {
                if let types::Kind::Number { unit: theirs, .. } = input.kind {
                    // A dimensionless input: any unit but "1" or "-" says the program expects
                    // another scale (`unit = "%"` for a fog in [0, 1]).
                    let plain = theirs.is_empty();
                    let mismatch = if plain {
                        !matches!(norm(unit).as_str(), "" | "1" | "-")
                    } else {
                        norm(theirs) != norm(unit)
                    };
                    if mismatch {
                        let theirs = if plain {
                            "a plain number (no unit)".to_owned()
                        } else {
                            format!("in {theirs}")
                        };
                        out.push(Warning {
                            at: decl.site.to_string(),
                            message: format!(
                                "`{name}` is declared in {unit} but feeds {builtin}({keyword}=), \
                                 which is {theirs}"
                            ),
                        });
                    }
                }
            }
        }
    }
    out
}
