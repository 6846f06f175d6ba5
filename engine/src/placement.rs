//! Placement checks (paper §2: "the runtime system ensures that a composition maintains
//! invariants such as no collision"): objects that start in collision, and vehicles that
//! start off the road.

use rapier3d::parry::query::intersection_test;
use rapier3d::parry::shape::{Capsule, Cuboid, Shape};
use rapier3d::prelude::{Pose, Rotation, Vector};

use crate::network::Network;
use crate::pedestrian::{PED_HALF_HEIGHT_M, PED_RADIUS_M};
use crate::EngineError;

/// The space an object occupies at the start.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Footprint {
    /// A box on the ground (a vehicle, an obstacle): centre of its base `pos_m` (metres),
    /// heading (rad), and its size.
    Vehicle {
        /// Ground point under the centre, metres.
        pos_m: [f64; 3],
        /// Heading, rad.
        heading_rad: f64,
        /// Its size.
        size: crate::Size,
    },
    /// A standing pedestrian's capsule, feet at `pos_m` (metres).
    Pedestrian {
        /// Feet position, metres.
        pos_m: [f64; 3],
    },
}

/// An object to place: a name for messages, its footprint, and whether it must start on a
/// driving surface.
#[derive(Debug, Clone, PartialEq)]
pub struct Placed {
    /// E.g. `Car lead (follow.star:12:8)`.
    pub name: String,
    /// Its shape and pose.
    pub footprint: Footprint,
    /// Whether it must start on a driving surface (vehicles) or may stand anywhere.
    pub on_road: bool,
}

fn shape(f: &Footprint) -> (Pose, Box<dyn Shape>) {
    match *f {
        Footprint::Vehicle {
            pos_m,
            heading_rad,
            size,
        } => (
            Pose::from_parts(
                Vector::new(
                    pos_m[0] as f32,
                    (pos_m[1] + size.height_m / 2.0) as f32,
                    pos_m[2] as f32,
                ),
                Rotation::from_rotation_y(heading_rad as f32),
            ),
            // Half extents along x (length), y (height), z (width).
            Box::new(Cuboid::new(Vector::new(
                (size.length_m / 2.0) as f32,
                (size.height_m / 2.0) as f32,
                (size.width_m / 2.0) as f32,
            ))),
        ),
        Footprint::Pedestrian { pos_m } => (
            Pose::from_parts(
                Vector::new(
                    pos_m[0] as f32,
                    pos_m[1] as f32 + PED_HALF_HEIGHT_M + PED_RADIUS_M,
                    pos_m[2] as f32,
                ),
                Rotation::IDENTITY,
            ),
            Box::new(Capsule::new_y(PED_HALF_HEIGHT_M, PED_RADIUS_M)),
        ),
    }
}

/// Checks that no two objects start in collision (parry's intersection test) and that every
/// object with `on_road` starts on a driving surface of `network`.
///
/// # Errors
/// [`EngineError::InvalidWorld`] naming both objects of the first colliding pair, or the
/// object that is off the road and where it is.
pub fn check(objects: &[Placed], network: &Network) -> Result<(), EngineError> {
    for o in objects.iter().filter(|o| o.on_road) {
        let p = match o.footprint {
            Footprint::Vehicle { pos_m, .. } | Footprint::Pedestrian { pos_m } => pos_m,
        };
        if network.driving_surface_at([p[0], p[2]]).is_none() {
            return Err(EngineError::InvalidWorld(format!(
                "{} is off the road: ({:.2}, {:.2}) m is on no driving surface of the road network",
                o.name, p[0], p[2]
            )));
        }
    }
    let shapes: Vec<_> = objects.iter().map(|o| shape(&o.footprint)).collect();
    for i in 0..objects.len() {
        for j in i + 1..objects.len() {
            let ((pa, sa), (pb, sb)) = (&shapes[i], &shapes[j]);
            if intersection_test(pa, sa.as_ref(), pb, sb.as_ref()).map_or(true, |i| i.intersecting)
            {
                return Err(EngineError::InvalidWorld(format!(
                    "{} and {} start in collision",
                    objects[i].name, objects[j].name
                )));
            }
        }
    }
    Ok(())
}
