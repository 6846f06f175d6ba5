//! A test's trace (`--trace`, `replay --trace`): every entity's pose, speed and acceleration
//! at a chosen rate, as a CSV file laid out like esmini's `--csv_logger` log (issue "An
//! imported scenario tests the ego it names", requirement 4), so that a reader of esmini's
//! log reads paracosm's by the same columns and the two compare line by line.
//!
//! Layout: three lines `paracosm VERSION: ...`, `Scenario File Name: ...`, `Number of
//! Vehicles: N`, then esmini's column line (`Index [-], TimeStamp [s], #1 Entity_Name [-],
//! ...`, 31 columns per entity, the ego first), then one line per sampled step: its index,
//! its time (s), and each entity's columns. What paracosm knows is filled in; what it does not
//! model (wheel angle and rotation, the position along the road, the lane, pitch, curvature,
//! collision ids) is left empty.
//!
//! Frame and reference point: `World_Position_X`/`_Y` are in the map's OpenDRIVE frame
//! (x east, y north, m; the engine's `x` and `−z`, shifted back by the map's recentring
//! `RoadMap::origin_m`), `World_Heading_Angle` counter-clockwise from `+x` (rad). The position
//! is the centre of the entity's bounding box on the ground, so `bb_x` and `bb_y` are 0;
//! esmini logs a vehicle's reference point (its rear axle) with the box centre `bb_x` ahead:
//! compare esmini's `X + bb_x·cos h` with paracosm's `X`. Speed is along the heading (m/s);
//! velocity is the speed along the heading, as esmini writes it; acceleration the change of
//! velocity over the last step (m/s², 0 at the start); `Heading_Angle_Rate` the change of
//! heading over the last step (rad/s).

use std::fmt::Write as _;
use std::path::Path;

use paracosm_engine::network::PieceKind;
use paracosm_engine::{Size, Snapshot, WorldSpec};

use crate::Error;

/// esmini's 31 columns of one entity, after `#N ` (its `CSV_Logger::Open`).
const COLUMNS: [&str; 31] = [
    "Entity_Name [-]",
    "Entity_ID [-]",
    "Current_Speed [m/s]",
    "Wheel_Angle [deg]",
    "Wheel_Rotation [-]",
    "bb_x [m]",
    "bb_y [m]",
    "bb_z [m]",
    "bb_length [m]",
    "bb_width [m]",
    "bb_height [m]",
    "World_Position_X [m]",
    "World_Position_Y [m]",
    "World_Position_Z [m]",
    "Vel_X [m/s]",
    "Vel_Y [m/s]",
    "Vel_Z [m/s]",
    "Acc_X [m/s2]",
    "Acc_Y [m/s2]",
    "Acc_Z [m/s2]",
    "Distance_Travelled_Along_Road_Segment [m]",
    "Lateral_Distance_Lanem [m]",
    "lane_id",
    "lane_offset [m]",
    "World_Heading_Angle [rad]",
    "Heading_Angle_Rate [rad/s]",
    "Relative_Heading_Angle [rad]",
    "Relative_Heading_Angle_Drive_Direction [rad]",
    "World_Pitch_Angle [rad]",
    "Road_Curvature [1/m]",
    "collision_ids",
];

/// The default time between two lines of a trace, s (esmini's fixtures of
/// `tests/data/xosc/esmini-trajectories` are taken every 0.1 s too).
pub const DEFAULT_EVERY_S: f64 = 0.1;

/// One entity at one instant: ground point of its box centre in the engine's frame
/// `[x, y, z]` (m), heading (rad), speed (m/s).
#[derive(Debug, Clone, Copy)]
struct Pose {
    pos: [f64; 3],
    heading: f64,
    speed: f64,
}

/// The entities of `state`, the ego first, then the NPC cars, then the pedestrians (in the
/// world's order), `None` for one out of the test now (an OpenSCENARIO entity not yet added
/// or deleted: esmini's CSV leaves an inactive entity out too). A pedestrian's speed is its
/// move over the last step (`previous`); in the first row, its initial speed and heading.
fn poses(
    state: &Snapshot,
    previous: Option<&Snapshot>,
    dt: f64,
    ego_ride_m: f64,
) -> Vec<Option<Pose>> {
    let mut out = vec![Some(Pose {
        pos: [
            state.ego.pos_m[0],
            state.ego.pos_m[1] - ego_ride_m,
            state.ego.pos_m[2],
        ],
        heading: state.ego.heading_rad,
        speed: state.ego.speed_mps,
    })];
    out.extend(state.cars.iter().map(|c| {
        c.enabled.then_some(Pose {
            pos: c.pos_m,
            heading: c.heading_rad,
            speed: c.speed_mps,
        })
    }));
    for (i, p) in state.pedestrians.iter().enumerate() {
        let before = previous.and_then(|s| s.pedestrians.get(i));
        let (speed, heading) = match before {
            Some(b) if dt > 0.0 => {
                let (dx, dz) = (p.pos_m[0] - b.pos_m[0], p.pos_m[2] - b.pos_m[2]);
                (dx.hypot(dz) / dt, (-dz).atan2(dx))
            }
            // The first row: its initial speed and the way it faces.
            _ => (p.velocity_mps[0].hypot(p.velocity_mps[2]), p.heading_rad),
        };
        out.push(p.present.then_some(Pose {
            pos: p.pos_m,
            heading,
            speed,
        }));
    }
    out
}

/// What a name of the world calls an actor: `Car Lead (f.xosc:9:5)` is `Lead`.
fn short_name(name: &str, fallback: String) -> String {
    let rest = name.split_once(' ').map_or(name, |(_, r)| r);
    let short = rest.rsplit_once(" (").map_or(rest, |(n, _)| n).trim();
    if short.is_empty() {
        fallback
    } else {
        short.to_owned()
    }
}

/// The trace of one test as CSV text: `world` as built, `states` at the start and after each
/// step (`dt_s` apart, s), a line every `every_s` s (at least every step), the ego called
/// `ego_name`, the file called `scenario`.
///
/// # Errors
/// [`Error::BadInput`] when `every_s` is not a finite number `> 0`.
pub fn csv(
    world: &WorldSpec,
    states: &[Snapshot],
    (every_s, dt_s): (f64, f64),
    (scenario, ego_name): (&str, &str),
) -> Result<String, Error> {
    if !(every_s.is_finite() && every_s > 0.0) {
        return Err(Error::BadInput(format!(
            "--trace-every {every_s} s must be a finite number of seconds > 0"
        )));
    }
    let period = ((every_s / dt_s).round() as usize).max(1);
    let origin = world
        .network
        .pieces()
        .iter()
        .find_map(|p| match &p.kind {
            PieceKind::Map { map, .. } => Some(map.0.origin_m),
            _ => None,
        })
        .unwrap_or([0.0, 0.0]);
    let mut names = vec![ego_name.to_owned()];
    let mut sizes = vec![world.ego.vehicle.size];
    for (i, c) in world.cars.iter().enumerate() {
        names.push(short_name(&c.name, format!("car {i}")));
        sizes.push(c.size);
    }
    for (i, p) in world.pedestrians.iter().enumerate() {
        names.push(short_name(&p.name, format!("pedestrian {i}")));
        sizes.push(Size::PEDESTRIAN);
    }
    // The ego's pose is its chassis centre, which rides above the ground by its height at
    // the start (its wheels on the road).
    let ego_ride_m = states
        .first()
        .map_or(0.0, |s| s.ego.pos_m[1] - world.ego.start.pos_m[1]);
    let mut out = String::new();
    let _ = writeln!(out, "paracosm VERSION: {}, ", env!("CARGO_PKG_VERSION"));
    let _ = writeln!(out, "Scenario File Name: {scenario}, ");
    let _ = writeln!(out, "Number of Vehicles: {}, ", names.len());
    out.push_str("Index [-], TimeStamp [s], ");
    for k in 1..=names.len() {
        for c in COLUMNS {
            let _ = write!(out, "#{k} {c}, ");
        }
    }
    out.push('\n');
    let mut previous: Option<(&Snapshot, Vec<Option<Pose>>)> = None;
    for (step, state) in states.iter().enumerate() {
        let now = poses(state, previous.as_ref().map(|p| p.0), dt_s, ego_ride_m);
        if step % period == 0 {
            let _ = write!(out, "{}, {:.6}, ", step / period, state.t_s);
            for (i, p) in now.iter().enumerate() {
                let Some(p) = p else {
                    continue;
                };
                let before = previous.as_ref().and_then(|(_, b)| b.get(i)?.as_ref());
                let vel = [p.speed * p.heading.cos(), p.speed * p.heading.sin()];
                let (acc, rate) = match before {
                    Some(b) => (
                        [
                            (vel[0] - b.speed * b.heading.cos()) / dt_s,
                            (vel[1] - b.speed * b.heading.sin()) / dt_s,
                        ],
                        wrap(p.heading - b.heading) / dt_s,
                    ),
                    None => ([0.0, 0.0], 0.0),
                };
                let s = sizes[i];
                let _ = write!(
                    out,
                    "{}, {i}, {:.6}, , , 0.000000, 0.000000, {:.6}, {:.6}, {:.6}, {:.6}, \
                     {:.6}, {:.6}, {:.6}, {:.6}, {:.6}, 0.000000, {:.6}, {:.6}, 0.000000, \
                     , , , , {:.6}, {:.6}, , , , , , ",
                    names[i],
                    p.speed,
                    s.height_m / 2.0,
                    s.length_m,
                    s.width_m,
                    s.height_m,
                    p.pos[0] + origin[0],
                    -p.pos[2] + origin[1],
                    p.pos[1],
                    vel[0],
                    vel[1],
                    acc[0],
                    acc[1],
                    p.heading,
                    rate,
                );
            }
            out.push('\n');
        }
        previous = Some((state, now));
    }
    Ok(out)
}

/// An angle in `(−π, π]`, rad.
fn wrap(a: f64) -> f64 {
    let t = std::f64::consts::TAU;
    let w = a.rem_euclid(t);
    if w > std::f64::consts::PI {
        w - t
    } else {
        w
    }
}

/// What a campaign or a replay needs to write traces: the folder (or file) and the time
/// between two lines, s.
#[derive(Debug, Clone, PartialEq)]
pub struct TraceSpec {
    /// For a campaign the folder `OUT/trace`, each test in `test_N.csv`; for a replay the
    /// file itself.
    pub path: std::path::PathBuf,
    /// The time between two lines, s, finite and `> 0` ([`DEFAULT_EVERY_S`]).
    pub every_s: f64,
}

/// Writes [`csv`] to `path` (atomically: a temporary file renamed over it).
///
/// # Errors
/// As [`csv`]; [`Error::Write`] or [`Error::BadInput`] when the file cannot be written.
pub fn write(
    path: &Path,
    world: &WorldSpec,
    states: &[Snapshot],
    (every_s, dt_s): (f64, f64),
    (scenario, ego_name): (&str, &str),
) -> Result<(), Error> {
    let text = csv(world, states, (every_s, dt_s), (scenario, ego_name))?;
    crate::atomic::write(path, text.as_bytes())
}

/// The name a trace gives the ego: the entity's name when the scenario's file chose it
/// (`Scenario::ego`, `Ego, 5 × 2 × 1.8 m`), else `ego`.
pub fn ego_name(scenario: &paracosm_scenarios::Scenario) -> String {
    scenario
        .ego()
        .and_then(|e| e.split(", ").next())
        .unwrap_or("ego")
        .to_owned()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_lose_their_kind_and_site() {
        assert_eq!(short_name("Car Lead (f.xosc:9:5)", "x".into()), "Lead");
        assert_eq!(short_name("Pedestrian p", "x".into()), "p");
        assert_eq!(short_name("", "car 3".into()), "car 3");
    }

    #[test]
    fn every_entity_has_esminis_31_columns() {
        assert_eq!(COLUMNS.len(), 31);
        assert_eq!(COLUMNS[2], "Current_Speed [m/s]");
        assert_eq!(COLUMNS[11], "World_Position_X [m]");
        assert_eq!(COLUMNS[24], "World_Heading_Angle [rad]");
    }
}
