//! `paracosm-fuzz report DIR --on-map`: the campaign's tests drawn over its road map, each at
//! the place where a parameter put an actor, by outcome.
//!
//! Each recorded test's world is built again from its parameters (the program runs, nothing
//! is simulated), and the start of every actor (the ego, each car, pedestrian and obstacle) is
//! read from it. The actor whose start moves most between the tests is the one the campaign's
//! position-valued parameters place (an `onLane(s=...)` or a distance along a road); each test
//! is drawn where that actor started, over the road map: the program's OpenDRIVE map, or its
//! pieces written as OpenDRIVE ([`crate::export::xodr`]) and read back.

use std::path::Path;
use std::sync::Arc;

use paracosm_engine::network::{opendrive, PieceKind, RoadMap};
use paracosm_engine::WorldSpec;
use paracosm_scenarios::Scenario;

use crate::record::RunRecord;
use crate::report::plot::{road_map_png, road_map_svg, MapMark, RoadMapDrawing};
use crate::Error;

/// Every actor's start in one world, world `[x, z]` m, by name ([`starts`]).
type Starts = Vec<(String, [f64; 2])>;

/// The drawing's file stem in the campaign folder (`failure_map-road.{png,svg}`).
pub const ON_MAP_STEM: &str = "failure_map-road";

/// The smallest spread of an actor's start over the tests, m, for it to count as placed by
/// the parameters.
const MOVES_M: f64 = 0.5;

/// Draws `records` of `scenario` over its road map into `dir/failure_map-road.{png,svg}` and
/// returns the two paths and the line that says what was drawn.
///
/// # Errors
/// [`Error::BadInput`] when no test's world can be built, when the road network changes
/// between tests (a parameter shapes it), when no actor's start moves between the tests (no
/// parameter is a position), or when the network mixes an OpenDRIVE map with pieces;
/// [`Error::Plot`] when a drawing cannot be written.
pub fn draw(
    dir: &Path,
    scenario: &Scenario,
    records: &[RunRecord],
) -> Result<(Vec<String>, String), Error> {
    let mut first: Option<WorldSpec> = None;
    // Per test: its outcome and every actor's start.
    let mut tests: Vec<(&RunRecord, Starts)> = Vec::new();
    for r in records {
        let Some(world) = r.params.as_ref().and_then(|a| scenario.instantiate(a).ok()) else {
            continue;
        };
        if let Some(f) = &first {
            if f.network != world.network {
                return Err(Error::BadInput(format!(
                    "--on-map: the road network of test {} differs from the first test's (a parameter shapes the roads), so there is no one road map to draw the tests on",
                    r.id
                )));
            }
        }
        tests.push((r, starts(&world)));
        first.get_or_insert(world);
    }
    let world = first.ok_or_else(|| {
        Error::BadInput("--on-map: no recorded test's world can be built again".into())
    })?;
    let (actor, spread) = moving_actor(&tests).ok_or_else(|| {
        Error::BadInput(format!(
            "--on-map: no actor's start moves by {MOVES_M} m or more between the tests: no parameter of {} places an actor on the road, so there is nothing to draw on the map (use --map for a failure map over the parameters)",
            scenario.name()
        ))
    })?;
    let marks: Vec<MapMark> = tests
        .iter()
        .filter_map(|(r, at)| {
            let p = at.iter().find(|(n, _)| *n == actor)?.1;
            Some(MapMark {
                at_m: p,
                status: r.status,
            })
        })
        .collect();
    let map = road_map(&world, scenario)?;
    let label = format!("where {actor} starts in each test (it moves over {spread:.1} m)");
    let title = format!(
        "{}: {} tests over the road map",
        scenario.name(),
        marks.len()
    );
    let drawing = RoadMapDrawing {
        map: &map,
        title: &title,
        marks: &marks,
        marks_label: &label,
    };
    let stem = dir.join(ON_MAP_STEM);
    let png = road_map_png(&drawing, &stem.with_extension("png"))?;
    let svg = road_map_svg(&drawing, &stem.with_extension("svg"))?;
    Ok((
        vec![png.display().to_string(), svg.display().to_string()],
        format!("on the road map: {label}"),
    ))
}

/// Every actor's start in `world`, world `[x, z]` m, by name: `the ego`, each car's and
/// pedestrian's own name (`Car oncoming (file:line:col)`; `car N`, `pedestrian N` when it has
/// none), `obstacle N`.
fn starts(world: &WorldSpec) -> Starts {
    let p = world.ego.start.pos_m;
    let mut out = vec![("the ego".to_owned(), [p[0], p[2]])];
    out.extend(world.cars.iter().enumerate().filter_map(|(i, c)| {
        let name = if c.name.is_empty() {
            format!("car {}", i + 1)
        } else {
            c.name.clone()
        };
        c.path.first().map(|&p| (name, p))
    }));
    out.extend(world.pedestrians.iter().enumerate().map(|(i, w)| {
        let name = if w.name.is_empty() {
            format!("pedestrian {}", i + 1)
        } else {
            w.name.clone()
        };
        (name, [w.start[0], w.start[2]])
    }));
    out.extend(
        world
            .obstacles
            .iter()
            .enumerate()
            .map(|(i, o)| (format!("obstacle {}", i + 1), [o.base_m[0], o.base_m[2]])),
    );
    out
}

/// The actor whose start moves most between the tests (the largest distance from its start
/// in the first test), and that distance (m); `None` when none moves [`MOVES_M`] or more.
fn moving_actor(tests: &[(&RunRecord, Starts)]) -> Option<(String, f64)> {
    let (_, first) = tests.first()?;
    first
        .iter()
        .map(|(name, a)| {
            let spread = tests
                .iter()
                .filter_map(|(_, at)| at.iter().find(|(n, _)| n == name))
                .map(|(_, b)| (b[0] - a[0]).hypot(b[1] - a[1]))
                .fold(0.0, f64::max);
            (name.clone(), spread)
        })
        .filter(|(_, spread)| *spread >= MOVES_M)
        .max_by(|a, b| a.1.total_cmp(&b.1))
}

/// The road map of `world`: its OpenDRIVE map, or its pieces written as OpenDRIVE and read
/// back.
fn road_map(world: &WorldSpec, scenario: &Scenario) -> Result<Arc<RoadMap>, Error> {
    let pieces = world.network.pieces();
    let maps: Vec<&Arc<RoadMap>> = pieces
        .iter()
        .filter_map(|p| match &p.kind {
            PieceKind::Map { map, .. } => Some(&map.0),
            _ => None,
        })
        .collect();
    match (maps.len(), pieces.len()) {
        (1, 1) => Ok(maps[0].clone()),
        (0, _) => {
            let text = crate::export::xodr::write(&world.network, scenario.name())
                .map_err(|e| Error::BadInput(format!("--on-map: {e}")))?;
            let name = format!("the roads of {}", scenario.name());
            opendrive::import(&name, &text)
                .map(|i| i.map)
                .map_err(|e| {
                    Error::Internal(format!(
                        "--on-map: the scenario's roads, written as OpenDRIVE, do not read back: {e}"
                    ))
                })
        }
        _ => Err(Error::BadInput(
            "--on-map: the network mixes an OpenDRIVE map with other pieces, which have no one road map"
                .into(),
        )),
    }
}
