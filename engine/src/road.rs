use rapier3d::prelude::*;
use serde::{Deserialize, Serialize};

use crate::{EngineError, RoadSpec};

/// Height of the sidewalks above the road surface, in metres.
pub(crate) const CURB_HEIGHT_M: f64 = 0.15;
/// Thickness of the road slab under the surface `y = 0`, in metres.
const SLAB_THICKNESS_M: f64 = 0.2;

/// A place across the road (paper §2, `onLane`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Lane {
    /// A driving lane: `1..=n/2` right of the centre line driving along `+x`, `-1..=-n/2` left
    /// of it driving along `-x`. Lane `±1` is next to the centre line.
    Driving(i32),
    /// The sidewalk on the right (`+z`) side: the paper's `r.SideWalk`.
    SideWalk,
    /// The sidewalk on the left (`-z`) side: the paper's `-r.SideWalk`.
    OppositeSideWalk,
}

/// A straight road segment along `+x` from `x = 0` to `x = length_m`, with its driving lanes
/// centred on `z = 0` and a raised sidewalk on each side, built as fixed colliders.
#[derive(Debug, Clone, PartialEq)]
pub struct RoadSegment {
    spec: RoadSpec,
}

impl RoadSegment {
    /// Checks `spec` and wraps it.
    ///
    /// # Errors
    /// [`EngineError::InvalidWorld`] for a non-positive or non-finite length or width, an odd
    /// or zero lane count, or a friction outside `(0, 2]`.
    pub fn new(spec: RoadSpec) -> Result<Self, EngineError> {
        let bad = |m: String| Err(EngineError::InvalidWorld(m));
        if !(spec.length_m.is_finite() && spec.length_m > 0.0) {
            return bad(format!("road length {} m is not positive", spec.length_m));
        }
        if spec.lanes == 0 || spec.lanes % 2 == 1 {
            return bad(format!(
                "road has {} lanes; need an even number >= 2",
                spec.lanes
            ));
        }
        let positive = |v: f64| v.is_finite() && v > 0.0;
        if !positive(spec.lane_width_m) || !positive(spec.sidewalk_width_m) {
            return bad("lane and sidewalk widths must be positive".into());
        }
        if !(spec.friction > 0.0 && spec.friction <= 2.0) {
            return bad(format!("road friction {} is outside (0, 2]", spec.friction));
        }
        Ok(RoadSegment { spec })
    }

    /// The road's description.
    pub fn spec(&self) -> &RoadSpec {
        &self.spec
    }

    /// Half the width of the driving surface, in metres.
    pub fn half_width_m(&self) -> f64 {
        self.spec.lanes as f64 * self.spec.lane_width_m / 2.0
    }

    /// The point on the surface at the middle of `lane`, `at_m` metres along the road, as
    /// `[x, y, z]` in metres (`y` is the surface height: 0 on the road, the curb on a sidewalk).
    ///
    /// # Errors
    /// [`EngineError::InvalidWorld`] for lane 0, a lane beyond `±lanes/2`, or `at_m` outside
    /// `[0, length_m]`.
    pub fn on_lane(&self, lane: Lane, at_m: f64) -> Result<[f64; 3], EngineError> {
        if !(0.0..=self.spec.length_m).contains(&at_m) {
            return Err(EngineError::InvalidWorld(format!(
                "position {at_m} m is outside the road [0, {}] m",
                self.spec.length_m
            )));
        }
        let w = self.spec.lane_width_m;
        let sidewalk_z = self.half_width_m() + self.spec.sidewalk_width_m / 2.0;
        Ok(match lane {
            Lane::Driving(k) => {
                let half = (self.spec.lanes / 2) as i32;
                if k == 0 || k.abs() > half {
                    return Err(EngineError::InvalidWorld(format!(
                        "lane {k} does not exist on a {}-lane road (lanes ±1..=±{half})",
                        self.spec.lanes
                    )));
                }
                let z = (k.abs() as f64 - 0.5) * w * f64::from(k.signum());
                [at_m, 0.0, z]
            }
            Lane::SideWalk => [at_m, CURB_HEIGHT_M, sidewalk_z],
            Lane::OppositeSideWalk => [at_m, CURB_HEIGHT_M, -sidewalk_z],
        })
    }

    /// Inserts the road slab and the two sidewalks as fixed colliders (friction as specified).
    pub(crate) fn build(&self, physics: &mut PhysicsWorld) {
        let len = self.spec.length_m as f32;
        let hw = self.half_width_m() as f32;
        let sw = self.spec.sidewalk_width_m as f32;
        let mu = self.spec.friction as f32;
        let slab = SLAB_THICKNESS_M as f32;
        physics.insert_collider(
            ColliderBuilder::cuboid(len / 2.0, slab / 2.0, hw)
                .translation(Vector::new(len / 2.0, -slab / 2.0, 0.0))
                .friction(mu),
            None,
        );
        let curb = CURB_HEIGHT_M as f32;
        for side in [1.0f32, -1.0] {
            let h = (slab + curb) / 2.0;
            physics.insert_collider(
                ColliderBuilder::cuboid(len / 2.0, h, sw / 2.0)
                    .translation(Vector::new(len / 2.0, curb - h, side * (hw + sw / 2.0)))
                    .friction(mu),
                None,
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn on_lane_places_lanes_and_sidewalks() {
        let r = RoadSegment::new(RoadSpec::default()).unwrap();
        assert_eq!(
            r.on_lane(Lane::Driving(1), 10.0).unwrap(),
            [10.0, 0.0, 1.75]
        );
        assert_eq!(
            r.on_lane(Lane::Driving(-1), 10.0).unwrap(),
            [10.0, 0.0, -1.75]
        );
        assert_eq!(
            r.on_lane(Lane::SideWalk, 100.0).unwrap(),
            [100.0, 0.15, 4.5]
        );
        assert_eq!(
            r.on_lane(Lane::OppositeSideWalk, 100.0).unwrap(),
            [100.0, 0.15, -4.5]
        );
        let four = RoadSegment::new(RoadSpec {
            lanes: 4,
            ..RoadSpec::default()
        })
        .unwrap();
        assert_eq!(four.on_lane(Lane::Driving(2), 0.0).unwrap()[2], 5.25);
    }

    #[test]
    fn bad_roads_and_lanes_are_errors() {
        let r = RoadSegment::new(RoadSpec::default()).unwrap();
        assert!(r.on_lane(Lane::Driving(0), 1.0).is_err());
        assert!(r.on_lane(Lane::Driving(2), 1.0).is_err());
        assert!(r.on_lane(Lane::Driving(1), 250.0).is_err());
        for spec in [
            RoadSpec {
                lanes: 3,
                ..RoadSpec::default()
            },
            RoadSpec {
                length_m: -1.0,
                ..RoadSpec::default()
            },
            RoadSpec {
                friction: 0.0,
                ..RoadSpec::default()
            },
            RoadSpec {
                lane_width_m: f64::NAN,
                ..RoadSpec::default()
            },
        ] {
            assert!(RoadSegment::new(spec).is_err());
        }
    }
}
