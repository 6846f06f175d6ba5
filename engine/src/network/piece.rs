use serde::{Deserialize, Serialize};

use super::curve::RefLine;
use super::geometry::{direction, Pose2};
use super::map::MapRef;
use crate::EngineError;

/// Width of one driving lane, in metres, on every piece.
pub const LANE_WIDTH_M: f64 = 3.5;
/// Smallest radius of a curved piece's reference line, metres (a tighter bend is no road a
/// car of the ego's size can follow).
pub const MIN_CURVE_RADIUS_M: f64 = 10.0;

/// The longest road segment and the largest arc radius, metres (100 km): the physics runs in
/// f32, whose steps are 8 mm at 100 km from the origin.
pub const MAX_EXTENT_M: f64 = 100_000.0;

/// `x` as a message shows it: in scientific notation from a billion on (`1e300`, not its 301
/// digits).
fn readable(x: f64) -> String {
    if x.abs() >= 1e9 {
        format!("{x:e}")
    } else {
        x.to_string()
    }
}
/// Largest angle a curved piece may turn through, rad (3π/2: a fuller turn would bring its
/// ends onto each other).
pub const MAX_TURN_RAD: f64 = 3.0 * std::f64::consts::FRAC_PI_2;
/// Width of each sidewalk along a road segment, in metres.
pub const SIDEWALK_WIDTH_M: f64 = 2.0;
/// Extra paved margin on each side of an intersection beyond the roads' width, in metres, so
/// that turning paths have radii a car can steer (a right turn from lane 1 of a two-lane road
/// has a 6.75 m radius, above the ego vehicle's 5.3 m minimum).
pub const JUNCTION_APRON_M: f64 = 3.0;

/// What a road piece is, in its own frame (paper §2, "More Complex Worlds").
///
/// Local frames: a segment runs along `+x` from port `ONE` at `x = 0` to port `TWO` at
/// `x = len`. A curved piece (`Arc`, `Clothoid`) starts at port `ONE` at the origin heading
/// along `+x` and follows its [`RefLine`] to port `TWO`. Junctions are centred on their origin with port `ONE` east (`+x`), `TWO` south
/// (`+z`), `THREE` west (`-x`) and, for four-way pieces, `FOUR` north (`-z`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PieceKind {
    /// `RoadSegment`: a straight road with sidewalks.
    Segment {
        /// Length in metres, `> 0`.
        length_m: f64,
        /// Driving lanes, even and `>= 2`: half each way.
        lanes: u32,
        /// Tyre–road friction, in `(0, 2]`.
        friction: f64,
    },
    /// `Arc`: a road of constant curvature with sidewalks, ports `ONE` (start) and `TWO` (end).
    Arc {
        /// Radius of the reference line (the centre line), metres, `>= 10` and wide enough
        /// that the inner sidewalk keeps a radius of at least 1 m.
        radius_m: f64,
        /// Angle turned, rad: positive turns left (counter-clockwise seen from above),
        /// `0 < |angle| <= 3π/2`.
        angle_rad: f64,
        /// Driving lanes, even and `>= 2`: half each way.
        lanes: u32,
        /// Tyre–road friction, in `(0, 2]`.
        friction: f64,
    },
    /// `Clothoid`: a road whose curvature changes linearly with arc length (an Euler spiral,
    /// OpenDRIVE's `spiral`), ports `ONE` (start) and `TWO` (end).
    Clothoid {
        /// Length along the reference line, metres, in `(0, 10000]`.
        length_m: f64,
        /// Curvature at port `ONE`, 1/m (positive: turning left).
        curv_start: f64,
        /// Curvature at port `TWO`, 1/m.
        curv_end: f64,
        /// Driving lanes, even and `>= 2`: half each way.
        lanes: u32,
        /// Tyre–road friction, in `(0, 2]`.
        friction: f64,
    },
    /// `TIntersection`: three ports `ONE`, `TWO`, `THREE` (the stem is `TWO`, south).
    TIntersection {
        /// Lanes of the roads it joins.
        lanes: u32,
        /// Friction.
        friction: f64,
    },
    /// `CrossIntersection`: four ports.
    CrossIntersection {
        /// Lanes of the roads it joins.
        lanes: u32,
        /// Friction.
        friction: f64,
    },
    /// `Roundabout`: four ports on a square plaza of side `2 · radius_m` around a raised
    /// central island; traffic circles counter-clockwise.
    Roundabout {
        /// Lanes of the roads it joins.
        lanes: u32,
        /// Half the plaza's side, in metres.
        radius_m: f64,
        /// Friction.
        friction: f64,
    },
    /// `OpenDrive("map.xodr")`: every road, lane and junction of an OpenDRIVE map, placed
    /// where the map puts it (no ports: the map links its own roads).
    Map {
        /// The baked map.
        map: MapRef,
        /// Tyre–road friction of every lane, in `(0, 2]`.
        friction: f64,
    },
}

/// A connection point of a piece, in the piece's frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PortGeometry {
    /// Centre of the road's end `[x, z]`, in metres.
    pub pos: [f64; 2],
    /// Outward heading, in rad: the direction a car leaving through it drives.
    pub heading_rad: f64,
}

/// Names of ports by index.
pub const PORT_NAMES: [&str; 4] = ["ONE", "TWO", "THREE", "FOUR"];

impl PieceKind {
    /// The paper's name of the piece type.
    pub fn type_name(&self) -> &'static str {
        match self {
            PieceKind::Segment { .. } => "RoadSegment",
            PieceKind::Arc { .. } => "Arc",
            PieceKind::Clothoid { .. } => "Clothoid",
            PieceKind::TIntersection { .. } => "TIntersection",
            PieceKind::CrossIntersection { .. } => "CrossIntersection",
            PieceKind::Roundabout { .. } => "Roundabout",
            PieceKind::Map { .. } => "OpenDrive",
        }
    }

    /// Driving lanes of the roads at its ports.
    pub fn lanes(&self) -> u32 {
        match *self {
            PieceKind::Segment { lanes, .. }
            | PieceKind::Arc { lanes, .. }
            | PieceKind::Clothoid { lanes, .. }
            | PieceKind::TIntersection { lanes, .. }
            | PieceKind::CrossIntersection { lanes, .. }
            | PieceKind::Roundabout { lanes, .. } => lanes,
            PieceKind::Map { .. } => 0,
        }
    }

    /// Friction coefficient of its surface.
    pub fn friction(&self) -> f64 {
        match *self {
            PieceKind::Segment { friction, .. }
            | PieceKind::Arc { friction, .. }
            | PieceKind::Clothoid { friction, .. }
            | PieceKind::TIntersection { friction, .. }
            | PieceKind::CrossIntersection { friction, .. }
            | PieceKind::Roundabout { friction, .. }
            | PieceKind::Map { friction, .. } => friction,
        }
    }

    /// The same piece with friction `mu` (not checked; see [`PieceKind::validate`]).
    pub fn with_friction(&self, mu: f64) -> PieceKind {
        let mut k = self.clone();
        match &mut k {
            PieceKind::Segment { friction, .. }
            | PieceKind::Arc { friction, .. }
            | PieceKind::Clothoid { friction, .. }
            | PieceKind::TIntersection { friction, .. }
            | PieceKind::CrossIntersection { friction, .. }
            | PieceKind::Roundabout { friction, .. }
            | PieceKind::Map { friction, .. } => *friction = mu,
        }
        k
    }

    /// Half the width of the driving surface of its roads, in metres.
    pub fn half_road_m(&self) -> f64 {
        self.lanes() as f64 * LANE_WIDTH_M / 2.0
    }

    /// Half the width of a road including both sidewalks, in metres.
    pub fn half_width_m(&self) -> f64 {
        self.half_road_m() + SIDEWALK_WIDTH_M
    }

    /// Half the side of a T- or cross-intersection, in metres: the roads' half width plus
    /// [`JUNCTION_APRON_M`].
    pub fn junction_half_m(&self) -> f64 {
        self.half_width_m() + JUNCTION_APRON_M
    }

    /// Checks the documented ranges.
    ///
    /// # Errors
    /// [`EngineError::InvalidWorld`] naming the value.
    pub fn validate(&self) -> Result<(), EngineError> {
        let bad = |m: String| Err(EngineError::InvalidWorld(m));
        let name = self.type_name();
        let lanes = self.lanes();
        if let PieceKind::Map { friction, .. } = self {
            return if *friction > 0.0 && *friction <= 2.0 {
                Ok(())
            } else {
                bad(format!("OpenDrive friction {friction} is outside (0, 2]"))
            };
        }
        if lanes == 0 || lanes % 2 == 1 {
            return bad(format!(
                "{name} has {lanes} lanes; need an even number >= 2"
            ));
        }
        let mu = self.friction();
        if !(mu > 0.0 && mu <= 2.0) {
            return bad(format!("{name} friction {mu} is outside (0, 2]"));
        }
        match *self {
            PieceKind::Segment { length_m, .. }
                if !(length_m.is_finite() && length_m > 0.0 && length_m <= MAX_EXTENT_M) =>
            {
                bad(format!(
                    "RoadSegment length {} m is outside (0, {MAX_EXTENT_M}] (the physics runs \
                     in f32: 8 mm apart at 100 km)",
                    readable(length_m)
                ))
            }
            PieceKind::Arc {
                radius_m,
                angle_rad,
                ..
            } => self.validate_arc(radius_m, angle_rad),
            PieceKind::Clothoid {
                length_m,
                curv_start,
                curv_end,
                ..
            } => self.validate_clothoid(length_m, curv_start, curv_end),
            PieceKind::Roundabout { radius_m, .. } => self.validate_roundabout(radius_m),
            _ => Ok(()),
        }
    }

    /// Checks an `Arc`'s radius (m) against its lanes and [`MAX_EXTENT_M`], and its angle
    /// (rad) against [`MAX_TURN_RAD`].
    fn validate_arc(&self, radius_m: f64, angle_rad: f64) -> Result<(), EngineError> {
        let bad = |m: String| Err(EngineError::InvalidWorld(m));
        let lanes = self.lanes();
        let min = MIN_CURVE_RADIUS_M.max(self.half_width_m() + 1.0);
        if !(radius_m.is_finite() && radius_m >= min) {
            bad(format!(
                "Arc radius {radius_m} m is too tight for {lanes} lanes (at least {min} m)"
            ))
        } else if radius_m > MAX_EXTENT_M {
            bad(format!(
                "Arc radius {} m is over {MAX_EXTENT_M} m (use a RoadSegment)",
                readable(radius_m)
            ))
        } else if !(angle_rad.is_finite()
            && angle_rad != 0.0
            && angle_rad.abs() <= MAX_TURN_RAD + 1e-12)
        {
            bad(format!(
                "Arc angle {angle_rad} rad must be non-zero and within ±3π/2 (±{MAX_TURN_RAD:.4})"
            ))
        } else {
            Ok(())
        }
    }

    /// Checks a `Clothoid`'s length (m), its curvatures (1/m) against its lanes, and its turn
    /// (rad) against [`MAX_TURN_RAD`].
    fn validate_clothoid(
        &self,
        length_m: f64,
        curv_start: f64,
        curv_end: f64,
    ) -> Result<(), EngineError> {
        let bad = |m: String| Err(EngineError::InvalidWorld(m));
        let lanes = self.lanes();
        let max_k = 1.0 / MIN_CURVE_RADIUS_M.max(self.half_width_m() + 1.0);
        if !(length_m.is_finite() && length_m > 0.0 && length_m <= 10_000.0) {
            bad(format!(
                "Clothoid length {length_m} m is outside (0, 10000]"
            ))
        } else if !(curv_start.is_finite() && curv_end.is_finite())
            || curv_start.abs().max(curv_end.abs()) > max_k
        {
            bad(format!(
                "Clothoid curvature from {curv_start} to {curv_end} 1/m is too tight for \
                 {lanes} lanes (|curvature| at most {max_k:.4} 1/m, a radius of {:.1} m)",
                1.0 / max_k
            ))
        } else {
            let turn = self.ref_line().expect("curved").heading(length_m);
            if turn.abs() > MAX_TURN_RAD + 1e-12 {
                bad(format!(
                    "Clothoid turns {turn:.4} rad; at most ±3π/2 (±{MAX_TURN_RAD:.4})"
                ))
            } else {
                Ok(())
            }
        }
    }

    /// Checks a `Roundabout`'s radius (m): large enough for its lanes and their paths onto
    /// and off the ring, at most 1000 m.
    fn validate_roundabout(&self, radius_m: f64) -> Result<(), EngineError> {
        let bad = |m: String| Err(EngineError::InvalidWorld(m));
        let lanes = self.lanes();
        let min = self.half_width_m() + 3.0;
        if !(radius_m.is_finite() && radius_m >= min) {
            bad(format!(
                "Roundabout radius {radius_m} m is too small for {lanes} lanes (at least {} m)",
                super::lanes::min_roundabout_radius_m(lanes)
            ))
        } else if radius_m > 1_000.0 {
            bad(format!(
                "Roundabout radius {} m is over 1000 m",
                readable(radius_m)
            ))
        } else if !super::lanes::roundabout_fits(lanes, radius_m) {
            bad(format!(
                "Roundabout radius {radius_m} m is too small for {lanes} lanes: the way \
                 from an outer lane onto the ring and off it would turn tighter than \
                 {} m or leave no ring between entry and exit (at least {} m)",
                super::lanes::MIN_PATH_RADIUS_M,
                super::lanes::min_roundabout_radius_m(lanes)
            ))
        } else {
            Ok(())
        }
    }

    /// The reference line of a curved piece (`Arc`, `Clothoid`), `None` for the others.
    pub fn ref_line(&self) -> Option<RefLine> {
        match *self {
            PieceKind::Arc {
                radius_m,
                angle_rad,
                ..
            } => Some(RefLine::arc(radius_m, angle_rad)),
            PieceKind::Clothoid {
                length_m,
                curv_start,
                curv_end,
                ..
            } => Some(RefLine {
                length_m,
                curv_start,
                curv_end,
            }),
            _ => None,
        }
    }

    /// Length along the reference line of a segment or curved piece, metres (`None` for
    /// junctions): the range of `onLane`'s `at`.
    pub fn road_length_m(&self) -> Option<f64> {
        match *self {
            PieceKind::Segment { length_m, .. } => Some(length_m),
            _ => self.ref_line().map(|l| l.length_m),
        }
    }

    /// Half-extents `[along x, along z]` of the rectangular footprint (for a curved piece,
    /// the bounding box of its road and sidewalks), in metres, and its centre in the local
    /// frame.
    pub fn footprint(&self) -> ([f64; 2], [f64; 2]) {
        if let Some(line) = self.ref_line() {
            let w = self.half_width_m();
            let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
            for f in line.frames(1.0) {
                for t in [-w, w] {
                    let p = f.offset(t);
                    lo = [lo[0].min(p[0]), lo[1].min(p[1])];
                    hi = [hi[0].max(p[0]), hi[1].max(p[1])];
                }
            }
            return (
                [(hi[0] - lo[0]) / 2.0 + 0.1, (hi[1] - lo[1]) / 2.0 + 0.1],
                [(hi[0] + lo[0]) / 2.0, (hi[1] + lo[1]) / 2.0],
            );
        }
        match self {
            PieceKind::Segment { length_m, .. } => {
                ([length_m / 2.0, self.half_width_m()], [length_m / 2.0, 0.0])
            }
            PieceKind::Map { map, .. } => {
                let (lo, hi) = map.bounds_m();
                (
                    [(hi[0] - lo[0]) / 2.0 + 0.1, (hi[1] - lo[1]) / 2.0 + 0.1],
                    [(hi[0] + lo[0]) / 2.0, (hi[1] + lo[1]) / 2.0],
                )
            }
            PieceKind::TIntersection { .. } | PieceKind::CrossIntersection { .. } => {
                let h = self.junction_half_m();
                ([h, h], [0.0, 0.0])
            }
            PieceKind::Roundabout { radius_m, .. } => ([*radius_m, *radius_m], [0.0, 0.0]),
            PieceKind::Arc { .. } | PieceKind::Clothoid { .. } => unreachable!("curved above"),
        }
    }

    /// Radius of the raised central island of a roundabout, in metres.
    pub fn island_radius_m(&self) -> Option<f64> {
        match *self {
            PieceKind::Roundabout { radius_m, .. } => {
                Some(radius_m - self.half_road_m() - SIDEWALK_WIDTH_M)
            }
            _ => None,
        }
    }

    /// Its ports, by index.
    pub fn ports(&self) -> Vec<PortGeometry> {
        use std::f64::consts::{FRAC_PI_2, PI};
        let compass = |h: f64, n: usize| -> Vec<PortGeometry> {
            [0.0, -FRAC_PI_2, PI, FRAC_PI_2][..n]
                .iter()
                .map(|&heading_rad| {
                    let d = direction(heading_rad);
                    PortGeometry {
                        pos: [d[0] * h, d[1] * h],
                        heading_rad,
                    }
                })
                .collect()
        };
        match *self {
            PieceKind::Segment { length_m, .. } => vec![
                PortGeometry {
                    pos: [0.0, 0.0],
                    heading_rad: PI,
                },
                PortGeometry {
                    pos: [length_m, 0.0],
                    heading_rad: 0.0,
                },
            ],
            PieceKind::Arc { .. } | PieceKind::Clothoid { .. } => {
                let line = self.ref_line().expect("curved");
                vec![
                    PortGeometry {
                        pos: [0.0, 0.0],
                        heading_rad: PI,
                    },
                    PortGeometry {
                        pos: line.point(line.length_m),
                        heading_rad: super::geometry::wrap(line.heading(line.length_m)),
                    },
                ]
            }
            PieceKind::TIntersection { .. } => compass(self.junction_half_m(), 3),
            PieceKind::CrossIntersection { .. } => compass(self.junction_half_m(), 4),
            PieceKind::Roundabout { radius_m, .. } => compass(radius_m, 4),
            PieceKind::Map { .. } => Vec::new(),
        }
    }

    /// Whether the local point `[x, z]` is on the driving surface (not a sidewalk).
    pub fn on_driving_surface(&self, p: [f64; 2]) -> bool {
        if let Some(line) = self.ref_line() {
            let (_, t, past) = super::curve::SampledLine::new(&line).project(p);
            return past == 0.0 && t.abs() <= self.half_road_m();
        }
        match self {
            PieceKind::Segment { length_m, .. } => {
                (0.0..=*length_m).contains(&p[0]) && p[1].abs() <= self.half_road_m()
            }
            PieceKind::Map { map, .. } => map.0.on_driving_surface(p),
            _ => {
                let ([hx, hz], _) = self.footprint();
                let r = p[0].hypot(p[1]);
                p[0].abs() <= hx && p[1].abs() <= hz && self.island_radius_m().is_none_or(|i| r > i)
            }
        }
    }
}

/// A piece placed in the world.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Piece {
    /// A name for messages, e.g. `RoadSegment r (grid.star:4:5)`.
    pub name: String,
    /// What it is.
    pub kind: PieceKind,
    /// Where its local frame sits in the world.
    pub pose: Pose2,
}

impl Piece {
    /// Port `i` in world coordinates: centre `[x, z]` and outward heading.
    pub fn port(&self, i: usize) -> Option<PortGeometry> {
        self.kind.ports().get(i).map(|p| PortGeometry {
            pos: self.pose.apply(p.pos),
            heading_rad: super::geometry::wrap(self.pose.heading_rad + p.heading_rad),
        })
    }
}
