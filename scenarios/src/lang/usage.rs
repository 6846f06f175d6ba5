//! Which object reads each open parameter, found when the program loads: a parameter no
//! object reads is left out of coverage, and one that cannot affect the ego is named in a
//! warning (LANGUAGE.md, "Warnings").

use std::collections::{BTreeSet, HashSet};

use paracosm_engine::network::{PieceId, Surface};
use paracosm_engine::rx::{Node, StreamId};

use super::scene::{Fixed, SceneBuilder};
use crate::scenario::{CameraOnly, Warning};

/// What reads a parameter.
#[derive(Debug, Clone, PartialEq)]
enum Reader {
    /// Something that moves or judges the world (a speed, a trigger, the fog, presence...).
    World,
    /// The light: only cameras see it (the lidar does not).
    Light,
    /// The colour of an object: only cameras see it.
    Colour(String),
    /// The friction of a road piece.
    Friction(PieceId),
}

/// The findings: warnings, the parameters no object reads (by name), and those only a camera
/// sees.
pub struct Usage {
    /// Warnings, in parameter order.
    pub warnings: Vec<Warning>,
    /// Indices of the parameters no object reads.
    pub unused: Vec<usize>,
    /// Parameters only a camera sees.
    pub camera_only: Vec<CameraOnly>,
}

/// The open parameters a stream depends on (through every combinator), by index.
fn params_behind(b: &SceneBuilder, root: StreamId, out: &mut BTreeSet<usize>, seen: &mut [bool]) {
    let mut stack = vec![root];
    while let Some(id) = stack.pop() {
        if std::mem::replace(&mut seen[id.0], true) {
            continue;
        }
        let node = &b.graph.nodes()[id.0];
        if let Node::Param(p) = node {
            out.insert(*p);
        }
        stack.extend(node.inputs());
    }
}

/// Analyses a placed program; `names` are the parameters' final names, `stl_reads_light`
/// whether an `Stl` formula reads the `light` signal (a monitor then reads the light).
pub fn analyse(b: &SceneBuilder, names: &[String], stl_reads_light: bool) -> Usage {
    let n = b.params.len();
    let mut readers: Vec<Vec<Reader>> = vec![Vec::new(); n];
    let reach = |root: StreamId, reader: Reader, readers: &mut Vec<Vec<Reader>>| {
        let mut ps = BTreeSet::new();
        let mut seen = vec![false; b.graph.nodes().len()];
        params_behind(b, root, &mut ps, &mut seen);
        for p in ps {
            readers[p].push(reader.clone());
        }
    };
    if let Some((light, fog)) = b.world {
        let light_reader = if stl_reads_light {
            Reader::World
        } else {
            Reader::Light
        };
        reach(light, light_reader, &mut readers);
        reach(fog, Reader::World, &mut readers);
    }
    for c in &b.cars {
        reach(c.speed, Reader::World, &mut readers);
    }
    for p in &b.pedestrians {
        reach(p.speed, Reader::World, &mut readers);
    }
    // Every `foreach` acts on the world: the pedestrians' behaviours and the program's own.
    for (i, node) in b.graph.nodes().iter().enumerate() {
        if matches!(node, Node::Foreach { .. }) {
            reach(StreamId(i), Reader::World, &mut readers);
        }
    }
    for (piece, f) in &b.frictions {
        if let Fixed::Param(p) = f {
            readers[*p].push(Reader::Friction(*piece));
        }
    }
    for (c, owner) in b.cars.iter().zip(&b.car_names) {
        if let Fixed::Param(p) = c.color {
            readers[p].push(Reader::Colour(owner.clone()));
        }
        if let Fixed::Param(p) = c.enabled {
            readers[p].push(Reader::World);
        }
    }

    // Pieces a vehicle can be on: every piece the ego can reach within the horizon (on or off
    // the road, at full throttle all the way: the engine bounds any system's acceleration),
    // and every piece an NPC car's route crosses.
    let mut driven: HashSet<PieceId> = HashSet::new();
    if let Some(ego) = &b.ego {
        let t = b.horizon_s.unwrap_or(crate::lang::DEFAULT_HORIZON_S);
        let vehicle = paracosm_engine::VehicleParams::default();
        // Two driven wheels (rear-wheel drive).
        let a = 2.0 * vehicle.max_engine_force_n / vehicle.mass_kg;
        let reach_m = ego.initial_speed_mps * t + 0.5 * a * t * t;
        let start = [ego.start.pos_m[0], ego.start.pos_m[2]];
        driven.extend(
            (0..b.roads.pieces().len())
                .map(PieceId)
                .filter(|&id| b.roads.distance_to_piece_m(id, start) <= reach_m),
        );
    }
    let surface = Surface::new(&b.roads);
    for c in &b.cars {
        driven.extend(c.path.iter().filter_map(|&p| surface.piece_under(p)));
    }

    let mut usage = Usage {
        warnings: Vec::new(),
        unused: Vec::new(),
        camera_only: Vec::new(),
    };
    for (p, rs) in readers.iter().enumerate() {
        let decl = &b.params[p];
        let name = &names[p];
        if rs.is_empty() {
            usage.unused.push(p);
            usage.warnings.push(Warning {
                at: decl.at.clone(),
                message: format!(
                    "`{name}` is sampled but no object uses it: it changes nothing in a test, so \
                     coverage leaves it out (summary.json lists it under unused_params)"
                ),
            });
            continue;
        }
        let undriven = |r: &Reader| matches!(r, Reader::Friction(piece) if !driven.contains(piece));
        if rs.contains(&Reader::World) {
            continue;
        }
        if rs.iter().all(undriven) {
            let pieces: BTreeSet<String> = rs
                .iter()
                .filter_map(|r| match r {
                    Reader::Friction(piece) => Some(b.roads.piece(*piece).name.clone()),
                    _ => None,
                })
                .collect();
            usage.warnings.push(Warning {
                at: decl.at.clone(),
                message: format!(
                    "`{name}` sets the friction of {}, where no vehicle can be during a test (the \
                     ego cannot get there within the horizon even at full throttle, and no car's \
                     route crosses it): it cannot affect the ego",
                    pieces.into_iter().collect::<Vec<_>>().join(", ")
                ),
            });
            continue;
        }
        if rs
            .iter()
            .all(|r| undriven(r) || matches!(r, Reader::Light | Reader::Colour(_)))
        {
            let sets: Vec<String> = rs
                .iter()
                .filter_map(|r| match r {
                    Reader::Light => Some("the light".to_owned()),
                    Reader::Colour(owner) => Some(format!("the colour of {owner}")),
                    _ => None,
                })
                .collect();
            usage.camera_only.push(CameraOnly {
                param: name.clone(),
                at: decl.at.clone(),
                sets: sets.join(" and "),
            });
        }
    }
    usage
}
