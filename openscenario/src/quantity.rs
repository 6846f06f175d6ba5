//! The ranges of the numbers an OpenSCENARIO file gives paracosm (issue "Hostile input, third
//! round", requirement 3): a speed of 1e300 m/s or a teleport 1e12 m away is finite, so the
//! reader took it, and the test then passed because its target shot out of reach. Each number
//! is read as a [`Quantity`] and refused outside that quantity's range, at the attribute's
//! `file:line:col` (docs/limits.md lists the ranges). A value that comes from a run's
//! parameter is checked when that test's scenario is read, so the test ends in the same error.
//!
//! The ranges are wide: they refuse what no road test means (faster than any road vehicle,
//! further than any map, longer than any test), never a value a real scenario writes.

/// What a number in a scenario measures, with the range paracosm accepts for it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Quantity {
    /// A speed or a speed difference, m/s: `[-150, 150]` (540 km/h either way; a road
    /// vehicle's top speed is under 120 m/s).
    Speed,
    /// A factor on another entity's speed: `[-100, 100]`.
    Factor,
    /// An acceleration, deceleration or its rate of transition, m/s²: `[-100, 100]` (ten
    /// times standard gravity).
    Acceleration,
    /// A duration or a time gap, s: `[0, 1e6]` (more than eleven days).
    Duration,
    /// A point in time or a time offset (a trajectory vertex's time, a timing's offset, a
    /// simulation time to compare with), s: `[-1e8, 1e8]` (CARLA's files write 1e7 s for "never").
    Time,
    /// A distance along a road or between entities, m: `[-1e6, 1e6]` (1,000 km; a map is
    /// at most 131 km across, docs/limits.md).
    Distance,
    /// A world coordinate `x`, `y` or `z`, m: `[-1e7, 1e7]` (any projected coordinate on
    /// Earth, such as a UTM northing).
    Coordinate,
    /// A lateral offset from a lane or road (`t`, `offset`), m: `[-1000, 1000]`.
    Lateral,
    /// A curvature, 1/m: `[-100, 100]` (a radius of 1 cm).
    Curvature,
    /// A bounding box's length, width or height, or a tolerance, m: `[0, 100]`.
    Size,
    /// A bounding box centre's offset from the entity's reference point, m: `[-100, 100]`.
    Offset,
    /// A heading, pitch or roll, rad: `[-1000, 1000]` (a heading past a few turns is a
    /// mistake, and past 1e16 rad its sine is noise).
    Angle,
}

impl Quantity {
    /// The closed range `(lo, hi)` accepted, in the quantity's unit.
    pub fn range(self) -> (f64, f64) {
        match self {
            Quantity::Speed => (-150.0, 150.0),
            Quantity::Factor => (-100.0, 100.0),
            Quantity::Acceleration => (-100.0, 100.0),
            Quantity::Duration => (0.0, 1e6),
            Quantity::Time => (-1e8, 1e8),
            Quantity::Curvature => (-100.0, 100.0),
            Quantity::Distance => (-1e6, 1e6),
            Quantity::Coordinate => (-1e7, 1e7),
            Quantity::Lateral => (-1000.0, 1000.0),
            Quantity::Size => (0.0, 100.0),
            Quantity::Offset => (-100.0, 100.0),
            Quantity::Angle => (-1000.0, 1000.0),
        }
    }

    /// The quantity's name and unit in a message: `"a speed (m/s)"`.
    pub fn name(self) -> &'static str {
        match self {
            Quantity::Speed => "a speed (m/s)",
            Quantity::Factor => "a speed factor",
            Quantity::Acceleration => "an acceleration (m/s²)",
            Quantity::Duration => "a duration (s)",
            Quantity::Time => "a time (s)",
            Quantity::Curvature => "a curvature (1/m)",
            Quantity::Distance => "a distance (m)",
            Quantity::Coordinate => "a world coordinate (m)",
            Quantity::Lateral => "a lateral offset (m)",
            Quantity::Size => "a size (m)",
            Quantity::Offset => "a bounding box centre (m)",
            Quantity::Angle => "an angle (rad)",
        }
    }

    /// `None` when `v` lies in the range; otherwise why it is refused, without the
    /// attribute (the caller names it): `"1e300 is out of range for a speed (m/s): paracosm
    /// accepts -150 to 150 (docs/limits.md)"`.
    pub fn refusal(self, v: f64) -> Option<String> {
        let (lo, hi) = self.range();
        if (lo..=hi).contains(&v) {
            return None;
        }
        Some(format!(
            "{} is out of range for {}: paracosm accepts {} to {} (docs/limits.md)",
            shown(v),
            self.name(),
            shown(lo),
            shown(hi)
        ))
    }
}

/// `v` as a message shows it: as written for magnitudes below a million, in exponent form
/// (`1e300`) past it.
fn shown(v: f64) -> String {
    if v.abs() < 1e6 || !v.is_finite() {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_ends_pass_and_past_them_or_nan_is_refused() {
        for q in [
            Quantity::Speed,
            Quantity::Factor,
            Quantity::Acceleration,
            Quantity::Duration,
            Quantity::Time,
            Quantity::Curvature,
            Quantity::Distance,
            Quantity::Coordinate,
            Quantity::Lateral,
            Quantity::Size,
            Quantity::Offset,
            Quantity::Angle,
        ] {
            let (lo, hi) = q.range();
            assert_eq!(q.refusal(lo), None);
            assert_eq!(q.refusal(hi), None);
            assert!(q.refusal(hi * 1.5 + 1.0).is_some(), "{q:?}");
            assert!(q.refusal(f64::NAN).is_some(), "{q:?}");
            assert!(q.refusal(lo - 1.0).is_some(), "{q:?}");
        }
        let why = Quantity::Speed.refusal(1e300).unwrap();
        assert!(
            why.contains("a speed (m/s)") && why.contains("-150 to 150"),
            "{why}"
        );
        let why = Quantity::Coordinate.refusal(-1e12).unwrap();
        assert!(
            why.starts_with("-1e12 is out of range") && why.contains("-1e7 to 1e7"),
            "{why}"
        );
    }
}
