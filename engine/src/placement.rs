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

/// A box on the ground seen from above: its centre `[x, y]` (m, the OpenDRIVE frame: x east,
/// y north), heading (rad, anticlockwise from x) and `[length, width]` (m, ≥ 0).
pub type GroundBox = ([f64; 2], f64, [f64; 2]);

/// Whether boxes `a` and `b` overlap seen from above (boxes that only touch overlap), as
/// esmini's `Object::Collision` tests bounding boxes (separating axes in the ground plane):
/// parry's intersection test of the two boxes, made 1 m high, taken relative to `a`'s centre
/// so that single precision keeps millimetres far from the origin.
#[must_use]
pub fn boxes_overlap(a: GroundBox, b: GroundBox) -> bool {
    // The engine's frame: x east, y up, z south; a heading turns about y.
    let pose = |(c, h, _): GroundBox| {
        Pose::from_parts(
            Vector::new((c[0] - a.0[0]) as f32, 0.0, -(c[1] - a.0[1]) as f32),
            Rotation::from_rotation_y(h as f32),
        )
    };
    let cuboid = |(_, _, s): GroundBox| {
        Cuboid::new(Vector::new((s[0] / 2.0) as f32, 0.5, (s[1] / 2.0) as f32))
    };
    intersection_test(&pose(a), &cuboid(a), &pose(b), &cuboid(b)).is_ok_and(|i| i.intersecting)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn boxes_overlap_by_their_sides_not_their_bounds() {
        let car = ([1000.0, -2000.0], 0.0, [4.0, 2.0]);
        // Side by side, 0.1 m apart, and just touching.
        assert!(!boxes_overlap(car, ([1000.0, -1997.9], 0.0, [4.0, 2.0])));
        assert!(boxes_overlap(car, ([1000.0, -1998.0], 0.0, [4.0, 2.0])));
        // A 1 m square turned 45° off the car's front-left corner: their axis-aligned
        // bounds overlap, the boxes do not (its nearest side is 0.066 m from the corner) ...
        let diamond = |d: f64| {
            (
                [1002.0 + d, -1999.0 + d],
                std::f64::consts::FRAC_PI_4,
                [1.0, 1.0],
            )
        };
        assert!(!boxes_overlap(car, diamond(0.4)));
        // ... and 0.1 m nearer, they do.
        assert!(boxes_overlap(car, diamond(0.3)));
        // A long box turned 90° across the car's front overlaps it.
        assert!(boxes_overlap(
            car,
            ([1002.5, -2000.0], std::f64::consts::FRAC_PI_2, [6.0, 1.2])
        ));
        // Headings are anticlockwise: a 10 m bar turned +30° from (1005, -2000) reaches
        // (1009.3, -1997.5), clear of a box there turned the other way.
        let bar = ([1005.0, -2000.0], std::f64::consts::FRAC_PI_6, [10.0, 0.2]);
        assert!(boxes_overlap(bar, ([1009.3, -1997.5], 0.0, [0.4, 0.4])));
        assert!(!boxes_overlap(bar, ([1009.3, -2002.5], 0.0, [0.4, 0.4])));
    }
}
