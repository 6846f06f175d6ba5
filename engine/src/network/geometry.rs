use serde::{Deserialize, Serialize};

/// A planar pose: position `(x, z)` in metres and heading in rad (counter-clockwise seen from
/// above, `0` along `+x`). A piece's local frame maps onto the world through it.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Pose2 {
    /// `x` in metres.
    pub x: f64,
    /// `z` in metres.
    pub z: f64,
    /// Heading in rad.
    pub heading_rad: f64,
}

impl Pose2 {
    /// The world point `[x, z]` of the local point `[lx, lz]` (rotation about `+y`, as
    /// rapier's `Rotation::from_rotation_y(heading)`).
    pub fn apply(&self, p: [f64; 2]) -> [f64; 2] {
        let (s, c) = self.heading_rad.sin_cos();
        [self.x + p[0] * c + p[1] * s, self.z - p[0] * s + p[1] * c]
    }

    /// The composition `self ∘ inner`: first `inner`, then `self`.
    pub fn compose(&self, inner: &Pose2) -> Pose2 {
        let [x, z] = self.apply([inner.x, inner.z]);
        Pose2 {
            x,
            z,
            heading_rad: wrap(self.heading_rad + inner.heading_rad),
        }
    }
}

/// The unit direction `[dx, dz]` of a heading.
pub fn direction(heading_rad: f64) -> [f64; 2] {
    [heading_rad.cos(), -heading_rad.sin()]
}

/// The heading wrapped into `(-π, π]`.
pub fn wrap(heading_rad: f64) -> f64 {
    use std::f64::consts::{PI, TAU};
    let h = (heading_rad + PI).rem_euclid(TAU) - PI;
    if h <= -PI {
        h + TAU
    } else {
        h
    }
}
