use serde::{Deserialize, Serialize};

use super::geometry::{direction, wrap};
use super::{Location, Network, PieceId, PieceKind, LANE_WIDTH_M};
use crate::EngineError;

/// A choice at a junction, relative to the direction of arrival.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Turn {
    /// Leave on the opposite side.
    Straight,
    /// Leave a quarter turn to the left (counter-clockwise).
    Left,
    /// Leave a quarter turn to the right.
    Right,
}

impl Turn {
    /// The turn's name in programs: `"straight"`, `"left"` or `"right"`.
    pub fn name(self) -> &'static str {
        match self {
            Turn::Straight => "straight",
            Turn::Left => "left",
            Turn::Right => "right",
        }
    }

    /// Parses `"straight"`, `"left"` or `"right"`.
    pub fn parse(s: &str) -> Option<Turn> {
        match s {
            "straight" => Some(Turn::Straight),
            "left" => Some(Turn::Left),
            "right" => Some(Turn::Right),
            _ => None,
        }
    }
}

/// One lane's path across a piece: a polyline in world `[x, z]` metres, entering through a
/// port's incoming lane `j` and leaving through a port's outgoing lane `j` (lanes counted
/// from the centre line, `1..=n/2`).
#[derive(Debug, Clone, PartialEq)]
pub struct LanePath {
    /// The piece.
    pub piece: PieceId,
    /// `(port, lane)` it enters through.
    pub entry: (usize, u32),
    /// `(port, lane)` it leaves through.
    pub exit: (usize, u32),
    /// The turn it makes.
    pub turn: Turn,
    /// The polyline, at least two points.
    pub points: Vec<[f64; 2]>,
}

/// Largest step between the points of a curved piece's lane paths, metres (their chords
/// depart from the curve by at most 3 mm at the tightest radius, 10 m).
pub const LANE_STEP_M: f64 = 0.5;

/// Points sampled along each turning path.
const CURVE_POINTS: usize = 12;

/// Lane `j` of a road piece (segment or curve) both ways: `fwd` from port `ONE` to `TWO`,
/// `back` from `TWO` to `ONE`.
fn both_ways(
    out: &mut Vec<LanePath>,
    piece: PieceId,
    j: u32,
    fwd: Vec<[f64; 2]>,
    back: Vec<[f64; 2]>,
) {
    for (entry, exit, points) in [(0, 1, fwd), (1, 0, back)] {
        out.push(LanePath {
            piece,
            entry: (entry, j),
            exit: (exit, j),
            turn: Turn::Straight,
            points,
        });
    }
}

fn add(a: [f64; 2], b: [f64; 2], s: f64) -> [f64; 2] {
    [a[0] + s * b[0], a[1] + s * b[1]]
}

impl Network {
    /// Every lane path of `piece` in world coordinates.
    pub fn lane_paths(&self, piece: PieceId) -> Vec<LanePath> {
        let p = &self.pieces[piece.0];
        let half = p.kind.lanes() / 2;
        let offset = |j: u32| (f64::from(j) - 0.5) * LANE_WIDTH_M;
        let mut out = Vec::new();
        if let PieceKind::Segment { length_m, .. } = p.kind {
            for j in 1..=half {
                let z = offset(j);
                let fwd = vec![p.pose.apply([0.0, z]), p.pose.apply([length_m, z])];
                let back = vec![p.pose.apply([length_m, -z]), p.pose.apply([0.0, -z])];
                both_ways(&mut out, piece, j, fwd, back);
            }
            return out;
        }
        if let Some(line) = p.kind.ref_line() {
            let frames = line.frames(LANE_STEP_M);
            for j in 1..=half {
                let t = offset(j);
                let fwd = frames.iter().map(|f| p.pose.apply(f.offset(t))).collect();
                let back = frames
                    .iter()
                    .rev()
                    .map(|f| p.pose.apply(f.offset(-t)))
                    .collect();
                both_ways(&mut out, piece, j, fwd, back);
            }
            return out;
        }
        let ports = p.kind.ports();
        for (a, pa) in ports.iter().enumerate() {
            for (b, pb) in ports.iter().enumerate() {
                if a == b {
                    continue;
                }
                let inward = wrap(pa.heading_rad + std::f64::consts::PI);
                let delta = wrap(pb.heading_rad - inward);
                let turn = if delta.abs() < 0.1 {
                    Turn::Straight
                } else if (delta - std::f64::consts::FRAC_PI_2).abs() < 0.1 {
                    Turn::Left
                } else if (delta + std::f64::consts::FRAC_PI_2).abs() < 0.1 {
                    Turn::Right
                } else {
                    continue;
                };
                for j in 1..=half {
                    // Incoming lanes lie left of the port's outward direction, outgoing right.
                    let left = direction(pa.heading_rad + std::f64::consts::FRAC_PI_2);
                    let right = direction(pb.heading_rad - std::f64::consts::FRAC_PI_2);
                    let e = add(pa.pos, left, offset(j));
                    let x = add(pb.pos, right, offset(j));
                    let local = match p.kind.island_radius_m() {
                        Some(island) => ring(e, x, island + p.kind.half_road_m() / 2.0 + 0.5),
                        None => bend(e, direction(inward), x, direction(pb.heading_rad)),
                    };
                    out.push(LanePath {
                        piece,
                        entry: (a, j),
                        exit: (b, j),
                        turn,
                        points: local.into_iter().map(|q| p.pose.apply(q)).collect(),
                    });
                }
            }
        }
        out
    }

    /// The path a vehicle drives from `start` (a driving lane of a segment): along its lane,
    /// then across the connected pieces, until the network ends or the path is `max_len_m`
    /// metres long. Each junction on the way (a piece with more than one exit from the lane it
    /// is entered by) takes the next turn of `turns`, even into a dead end; once the list is
    /// used up, exits that lead on into the network before dead ends, then `straight`,
    /// `right`, `left` in that order of preference. World `[x, z]` points in metres.
    ///
    /// # Errors
    /// [`EngineError::InvalidWorld`] when `start` is not on a driving lane, or when a turn of
    /// `turns` is not one the junction it falls on has (naming the turn, the junction, the
    /// port it is entered by and the turns it has). Turns left over when the network ends are
    /// not an error: with an open lane, a route may be meant for one direction only.
    pub fn route(
        &self,
        start: &Location,
        turns: &[Turn],
        max_len_m: f64,
    ) -> Result<Vec<[f64; 2]>, EngineError> {
        let super::Lane::Driving(k) = start.lane else {
            return Err(EngineError::InvalidWorld(
                "a route must start on a driving lane".into(),
            ));
        };
        if let (Some(lane), super::PieceKind::Map { map, .. }) =
            (start.map_lane, &self.pieces[start.piece.0].kind)
        {
            let points = map
                .0
                .route(lane, start.at_m, turns, max_len_m)
                .map_err(EngineError::InvalidWorld)?;
            return Ok(resample(&points, ROUTE_SPACING_M));
        }
        let j = k.unsigned_abs();
        let (mut path, mut points) = match start.through {
            // Inside a junction: the rest of the lane path it is on.
            Some((entry, exit)) => {
                let path = self
                    .lane_paths(start.piece)
                    .into_iter()
                    .find(|l| l.entry == (entry, j) && l.exit.0 == exit)
                    .ok_or_else(|| {
                        EngineError::InvalidWorld("a junction location off its lane path".into())
                    })?;
                let mut points = vec![[start.pos_m[0], start.pos_m[2]]];
                let mut walked = 0.0;
                for w in path.points.windows(2) {
                    walked += dist(w[0], w[1]);
                    if walked > start.at_m {
                        points.push(w[1]);
                    }
                }
                if points.len() < 2 {
                    points.push(*path.points.last().expect("two points"));
                }
                (path, points)
            }
            None => {
                let entry = if k > 0 { 0 } else { 1 };
                let path = self
                    .lane_paths(start.piece)
                    .into_iter()
                    .find(|l| l.entry == (entry, j))
                    .expect("a segment has both directions of each lane");
                let mut points = vec![[start.pos_m[0], start.pos_m[2]]];
                match self.pieces[start.piece.0].kind.ref_line() {
                    // A curved piece: the lane's points beyond the start, in driving order.
                    Some(line) => {
                        let stations = line.stations(LANE_STEP_M);
                        let ahead = |s: f64| {
                            if k > 0 {
                                s > start.at_m
                            } else {
                                s < start.at_m
                            }
                        };
                        let order: Vec<f64> = if k > 0 {
                            stations
                        } else {
                            stations.into_iter().rev().collect()
                        };
                        points.extend(
                            order
                                .iter()
                                .zip(&path.points)
                                .filter(|(s, _)| ahead(**s))
                                .map(|(_, q)| *q),
                        );
                        if points.len() < 2 {
                            points.push(*path.points.last().expect("two points"));
                        }
                    }
                    None => points.push(*path.points.last().expect("two points")),
                }
                (path, points)
            }
        };
        let mut length = points.windows(2).map(|w| dist(w[0], w[1])).sum::<f64>();
        // A route of kilometres passes the same pieces again and again: each piece's lane
        // paths are worked out once per route.
        let mut paths_of: Vec<Option<Vec<LanePath>>> = vec![None; self.pieces.len()];
        let mut turns = turns.iter();
        // How many of the turns the path has taken.
        let mut used = 0;
        while length < max_len_m {
            let out = (path.piece, path.exit.0);
            let Some(next) = self.links.iter().find_map(|l| {
                if l.a == out {
                    Some(l.b)
                } else if l.b == out {
                    Some(l.a)
                } else {
                    None
                }
            }) else {
                break;
            };
            let mut candidates: Vec<&LanePath> = paths_of[next.0 .0]
                .get_or_insert_with(|| self.lane_paths(next.0))
                .iter()
                .filter(|l| l.entry == (next.1, path.exit.1))
                .collect();
            // Each junction on the way (a piece with more than one exit from this lane) takes
            // the route's next turn, which it must have; into a dead end if the program asks.
            let wanted = if candidates.len() > 1 {
                turns.next().copied()
            } else {
                None
            };
            let pick = match wanted {
                Some(t) => {
                    let Some(c) = candidates.iter().find(|c| c.turn == t) else {
                        let offered: Vec<String> = [Turn::Straight, Turn::Left, Turn::Right]
                            .into_iter()
                            .filter(|o| candidates.iter().any(|c| c.turn == *o))
                            .map(|o| format!("\"{}\"", o.name()))
                            .collect();
                        return Err(EngineError::InvalidWorld(format!(
                            "the route's turn {} (\"{}\") is not possible at {}, entered by {}: \
                             it offers {} there",
                            used + 1,
                            t.name(),
                            self.pieces[next.0 .0].name,
                            self.port_name(next),
                            offered.join(" and ")
                        )));
                    };
                    used += 1;
                    Some(c)
                }
                // No turn left to take: exits that lead on into the network before dead ends,
                // then straight, right, left.
                None => {
                    let linked = |l: &&LanePath| {
                        let end = (l.piece, l.exit.0);
                        self.links.iter().any(|k| k.a == end || k.b == end)
                    };
                    if candidates.iter().any(linked) {
                        candidates.retain(linked);
                    }
                    [Turn::Straight, Turn::Right, Turn::Left]
                        .into_iter()
                        .find_map(|t| candidates.iter().find(|c| c.turn == t))
                }
            };
            let Some(pick) = pick.map(|&c| c.clone()) else {
                break;
            };
            for &q in &pick.points[1..] {
                length += dist(*points.last().expect("non-empty"), q);
                points.push(q);
            }
            path = pick;
        }
        Ok(resample(&points, ROUTE_SPACING_M))
    }
}

/// The point `at_m` metres along the polyline `points` (clamped to its ends), the heading of
/// the piece it is on, and the polyline's length, metres.
pub(crate) fn along(points: &[[f64; 2]], at_m: f64) -> ([f64; 2], f64, f64) {
    let length: f64 = points.windows(2).map(|w| dist(w[0], w[1])).sum();
    let mut left = at_m.clamp(0.0, length);
    for w in points.windows(2) {
        let d = dist(w[0], w[1]);
        let heading = (-(w[1][1] - w[0][1])).atan2(w[1][0] - w[0][0]);
        if left <= d || d == 0.0 && left == 0.0 {
            let u = if d > 0.0 { left / d } else { 0.0 };
            return (
                [
                    w[0][0] + u * (w[1][0] - w[0][0]),
                    w[0][1] + u * (w[1][1] - w[0][1]),
                ],
                heading,
                length,
            );
        }
        left -= d;
    }
    let n = points.len();
    let (a, b) = (points[n - 2], points[n - 1]);
    (b, (-(b[1] - a[1])).atan2(b[0] - a[0]), length)
}

/// Largest distance between consecutive points of a route, in metres, so that followers find
/// their place on it by the nearest point.
const ROUTE_SPACING_M: f64 = 1.0;

/// `points` with points inserted so that no two consecutive ones are more than `max_m` apart.
fn resample(points: &[[f64; 2]], max_m: f64) -> Vec<[f64; 2]> {
    let mut out = vec![points[0]];
    for w in points.windows(2) {
        let n = (dist(w[0], w[1]) / max_m).ceil().max(1.0) as usize;
        for i in 1..=n {
            let t = i as f64 / n as f64;
            out.push([
                w[0][0] + t * (w[1][0] - w[0][0]),
                w[0][1] + t * (w[1][1] - w[0][1]),
            ]);
        }
    }
    out
}

fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

/// A quadratic Bézier from `e` (heading `de`) to `x` (heading `dx`) through the crossing of
/// the two lines; a straight line when they are parallel.
fn bend(e: [f64; 2], de: [f64; 2], x: [f64; 2], dx: [f64; 2]) -> Vec<[f64; 2]> {
    let cross = de[0] * dx[1] - de[1] * dx[0];
    if cross.abs() < 1e-9 {
        return vec![e, x];
    }
    // e + s·de = x - u·dx, solved for s.
    let r = [x[0] - e[0], x[1] - e[1]];
    let s = (r[0] * dx[1] - r[1] * dx[0]) / cross;
    let c = add(e, de, s);
    (0..=CURVE_POINTS)
        .map(|i| {
            let t = i as f64 / CURVE_POINTS as f64;
            let (a, b, d) = ((1.0 - t) * (1.0 - t), 2.0 * t * (1.0 - t), t * t);
            [
                a * e[0] + b * c[0] + d * x[0],
                a * e[1] + b * c[1] + d * x[1],
            ]
        })
        .collect()
}

/// From `e` onto a counter-clockwise circle of radius `r` about the origin, around to the
/// angle of `x`, and out to `x`.
fn ring(e: [f64; 2], x: [f64; 2], r: f64) -> Vec<[f64; 2]> {
    let angle = |p: [f64; 2]| (-p[1]).atan2(p[0]);
    // Join the ring a little after the entry and leave it a little before the exit.
    let a0 = angle(e) + 0.35;
    let mut a1 = angle(x) - 0.35;
    while a1 <= a0 {
        a1 += std::f64::consts::TAU;
    }
    let n = ((a1 - a0) / 0.15).ceil().max(2.0) as usize;
    let mut pts = vec![e];
    pts.extend((0..=n).map(|i| {
        let a = a0 + (a1 - a0) * i as f64 / n as f64;
        [r * a.cos(), -r * a.sin()]
    }));
    pts.push(x);
    pts
}
