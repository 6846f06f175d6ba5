//! What differs between two tests of one scenario: their scenes' worlds compared part by part
//! (a colour, the light, a piece's friction, or anything else), and what their front end's
//! host reads ([`crate::scene::HostInputs`]: an OpenSCENARIO storyboard).

use std::collections::{BTreeSet, HashSet};

use paracosm_engine::network::{PieceId, Surface};
use paracosm_engine::WorldSpec;

use crate::scene::{LoadError, Scene};

/// What changed between two tests of one scenario.
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

/// What differs between the tests of the scenes `a` and `b` of one scenario, whose tests last
/// `horizon_s`: their worlds ([`world_changes`]), and [`Change::Other`] when they judge with
/// other monitors or settings, run another system under test, or their hosts read different
/// inputs ([`Scene::host_inputs`]: a storyboard with other speeds, routes, triggers).
///
/// # Errors
/// What [`Scene::world`] returns for either scene.
pub fn scene_changes(a: &Scene, b: &Scene, horizon_s: f64) -> Result<Vec<Change>, LoadError> {
    let mut out = world_changes(&a.world()?, &b.world()?, horizon_s);
    let same_host = same_host_inputs(a.host_inputs(), b.host_inputs());
    let judged = |s: &Scene| {
        let monitors: Vec<_> = s.monitors().map(|(m, _)| m.clone()).collect();
        let settings = s.settings();
        (
            monitors,
            settings.horizon_s,
            settings.offroad,
            s.ego().map(|(_, sut)| sut.clone()),
        )
    };
    if !same_host || differ(&judged(a), &judged(b)) {
        out.push(Change::Other);
    }
    Ok(out)
}

/// Whether two tests' hosts read the same inputs ([`Scene::host_inputs`]): both have none,
/// or both have some that are [`crate::scene::HostInputs::same_as`] each other.
pub fn same_host_inputs(
    a: Option<&dyn crate::scene::HostInputs>,
    b: Option<&dyn crate::scene::HostInputs>,
) -> bool {
    match (a, b) {
        (None, None) => true,
        (Some(x), Some(y)) => x.same_as(y),
        _ => false,
    }
}

/// What differs between `a` and `b`, two worlds of one scenario whose tests last `horizon_s`.
/// Every field of [`WorldSpec`] is named here, so that a field added to it fails to compile
/// until its comparison is written.
pub fn world_changes(a: &WorldSpec, b: &WorldSpec, horizon_s: f64) -> Vec<Change> {
    let WorldSpec {
        dt_s,
        network: _, // piece_changes
        frictions,  // and stream_changes
        ego,
        pedestrians,
        cars: _, // car_changes
        obstacles,
        environment,
        streams: _,   // stream_changes
        published: _, // the streams monitors judge: stream_changes
        sensors,
    } = a;
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
    other(differ(ego, &b.ego), &mut out);
    other(differ(pedestrians, &b.pedestrians), &mut out);
    recoloured(
        obstacles,
        &b.obstacles,
        |o| &mut o.color,
        Change::ObstacleColour,
        &mut out,
    );
    other(
        differ(environment, &b.environment) || *dt_s != b.dt_s,
        &mut out,
    );
    other(differ(sensors, &b.sensors), &mut out);
    other(differ(frictions, &b.frictions), &mut out);
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
