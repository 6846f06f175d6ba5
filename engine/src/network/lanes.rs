use serde::{Deserialize, Serialize};

use super::curve::RefLine;
use super::geometry::{direction, wrap, Pose2};
use super::{Location, Network, PieceId, PieceKind, LANE_WIDTH_M};
use crate::EngineError;

/// A choice at a junction, relative to the direction of arrival: a way out named by the
/// heading change it makes (its angle, [`Turn::of_heading`]), or, on an OpenDRIVE map, by the
/// connecting road it takes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Turn {
    /// Leave on the opposite side: a heading change within 45° of none.
    Straight,
    /// Leave a quarter turn to the left (counter-clockwise): a heading change of 45° to 135°
    /// to the left.
    Left,
    /// Leave a quarter turn to the right: a heading change of 45° to 135° to the right.
    Right,
    /// Leave back the way it came: a heading change of more than 135° either way.
    #[serde(rename = "uturn")]
    UTurn,
    /// Leave through the OpenDRIVE map's connecting road of this `<road id>` (written
    /// `"road:ID"` in programs): the way to pick one of two ways out with one name.
    Road(RoadName),
}

/// The heading change a turn is named for, rad, positive to the left: `0`, `π/2`, `-π/2`,
/// `π`; `None` for [`Turn::Road`].
fn nominal_rad(t: Turn) -> Option<f64> {
    use std::f64::consts::{FRAC_PI_2, PI};
    match t {
        Turn::Straight => Some(0.0),
        Turn::Left => Some(FRAC_PI_2),
        Turn::Right => Some(-FRAC_PI_2),
        Turn::UTurn => Some(PI),
        Turn::Road(_) => None,
    }
}

impl Turn {
    /// The turns named by their angle, in the order messages list them.
    pub const NAMED: [Turn; 4] = [Turn::Straight, Turn::Left, Turn::Right, Turn::UTurn];

    /// The turn's name in programs: `"straight"`, `"left"`, `"right"`, `"uturn"` or
    /// `"road:ID"`.
    pub fn name(self) -> String {
        self.to_string()
    }

    /// Parses `"straight"`, `"left"`, `"right"`, `"uturn"` or `"road:ID"` (a connecting road's
    /// `<road id>`, 1 to [`RoadName::MAX_BYTES`] bytes); `None` for anything else.
    pub fn parse(s: &str) -> Option<Turn> {
        match s {
            "straight" => Some(Turn::Straight),
            "left" => Some(Turn::Left),
            "right" => Some(Turn::Right),
            "uturn" => Some(Turn::UTurn),
            _ => s
                .strip_prefix("road:")
                .and_then(RoadName::new)
                .map(Turn::Road),
        }
    }

    /// The turn a heading change of `delta_rad` (positive to the left, any angle) is named
    /// by: the nearest of straight (0), left (`π/2`), right (`-π/2`) and uturn (`π`), so that
    /// each names 90° of changes; a change of ±45° (to [`Turn::EDGE_RAD`]) is straight, of
    /// ±135° left or right.
    pub fn of_heading(delta_rad: f64) -> Turn {
        use std::f64::consts::FRAC_PI_4;
        let d = wrap(delta_rad);
        if d.abs() <= FRAC_PI_4 + Turn::EDGE_RAD {
            Turn::Straight
        } else if d.abs() <= 3.0 * FRAC_PI_4 + Turn::EDGE_RAD {
            if d > 0.0 {
                Turn::Left
            } else {
                Turn::Right
            }
        } else {
            Turn::UTurn
        }
    }

    /// How far past 45° or 135° a heading change may be and still count as on the gentler
    /// side of it, rad (0.57°): a map's roundabout drawn with its ring continuing 45° through
    /// each junction continues straight, whatever the rounding of its sampled lanes.
    pub const EDGE_RAD: f64 = 0.01;

    /// The names of the ways out of one fork, from their heading changes (rad, positive to
    /// the left): each way's [`Turn::of_heading`]; where several share a name, the one nearest
    /// the name's angle keeps it and each other takes the next name on its side (from
    /// straight, left or right; from left, uturn or straight; from right, straight or uturn;
    /// from uturn, right or left) where no way has that one, the nearest to its angle first;
    /// `None` for a way left without a name (a route takes it by its road, [`Turn::Road`]).
    pub fn name_ways(deltas: &[f64]) -> Vec<Option<Turn>> {
        let by_angle: Vec<Turn> = deltas.iter().map(|&d| Turn::of_heading(d)).collect();
        let off = |i: usize, t: Turn| t.off_nominal_rad(deltas[i]);
        let mut names: Vec<Option<Turn>> = vec![None; deltas.len()];
        let mut movers: Vec<(usize, Turn)> = Vec::new();
        for t in Turn::NAMED {
            let mut holders: Vec<usize> = (0..deltas.len()).filter(|&i| by_angle[i] == t).collect();
            holders.sort_by(|&a, &b| off(a, t).total_cmp(&off(b, t)));
            let Some(&keeper) = holders.first() else {
                continue;
            };
            names[keeper] = Some(t);
            for &i in &holders[1..] {
                let left_of_keeper = wrap(deltas[i] - deltas[keeper]) > 0.0;
                let next = match (t, left_of_keeper) {
                    (Turn::Straight, true) | (Turn::UTurn, false) => Turn::Left,
                    (Turn::Straight, false) | (Turn::UTurn, true) => Turn::Right,
                    (Turn::Left, true) | (Turn::Right, false) => Turn::UTurn,
                    _ => Turn::Straight,
                };
                movers.push((i, next));
            }
        }
        movers.sort_by(|a, b| off(a.0, a.1).total_cmp(&off(b.0, b.1)));
        for (i, next) in movers {
            if !names.contains(&Some(next)) && !by_angle.contains(&next) {
                names[i] = Some(next);
            }
        }
        names
    }

    /// How far a heading change of `delta_rad` is from the one this turn is named for, rad
    /// (`0` for [`Turn::Road`], which names no angle).
    pub fn off_nominal_rad(self, delta_rad: f64) -> f64 {
        nominal_rad(self).map_or(0.0, |n| wrap(delta_rad - n).abs())
    }
}

impl std::fmt::Display for Turn {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Turn::Straight => f.write_str("straight"),
            Turn::Left => f.write_str("left"),
            Turn::Right => f.write_str("right"),
            Turn::UTurn => f.write_str("uturn"),
            Turn::Road(r) => write!(f, "road:{}", r.as_str()),
        }
    }
}

/// An OpenDRIVE `<road id>` held inline, so that a [`Turn`] stays `Copy`: 1 to
/// [`RoadName::MAX_BYTES`] bytes of UTF-8.
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub struct RoadName {
    len: u8,
    bytes: [u8; RoadName::MAX_BYTES],
}

impl RoadName {
    /// The longest road id a route can name, bytes.
    pub const MAX_BYTES: usize = 30;

    /// `id` as a road name; `None` when it is empty or longer than [`RoadName::MAX_BYTES`].
    pub fn new(id: &str) -> Option<RoadName> {
        let n = id.len();
        if n == 0 || n > RoadName::MAX_BYTES {
            return None;
        }
        let mut bytes = [0u8; RoadName::MAX_BYTES];
        bytes[..n].copy_from_slice(id.as_bytes());
        Some(RoadName {
            len: n as u8,
            bytes,
        })
    }

    /// The road id.
    pub fn as_str(&self) -> &str {
        // Built from a `&str` cut at its own length: valid UTF-8.
        std::str::from_utf8(&self.bytes[..usize::from(self.len)]).unwrap_or("")
    }
}

impl std::fmt::Debug for RoadName {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{:?}", self.as_str())
    }
}

impl Serialize for RoadName {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.as_str())
    }
}

impl<'de> Deserialize<'de> for RoadName {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let id = String::deserialize(d)?;
        RoadName::new(&id).ok_or_else(|| {
            serde::de::Error::custom(format!(
                "a road id of 1 to {} bytes, got {id:?}",
                RoadName::MAX_BYTES
            ))
        })
    }
}

/// One lane's path across a piece: a polyline in world `[x, z]` metres, entering through a
/// port's incoming lane `j` and leaving through a port's outgoing lane `j` (lanes counted
/// from the centre line, `1..=n/2`). Through a junction or a roundabout the polyline samples
/// a G1-continuous chain of lines and circular arcs ([`LanePath::curve`]): its heading is
/// continuous, and equals the arms' headings at the ports.
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
    /// For a junction's or a roundabout's path, the curve the polyline samples: lines and
    /// arcs ([`RefLine`]s of constant curvature), each placed by the pose of its start
    /// (position `[x, z]` m, heading rad), end to end with equal headings where they meet.
    /// Empty for a road piece's lanes, whose curve is the piece's own reference line.
    pub curve: Vec<(Pose2, RefLine)>,
}

/// Smallest radius of a lane path through a junction or a roundabout, metres: the tightest
/// turn an NPC car follows ([`crate::car`]'s yaw-rate limit is its speed over this radius).
/// A roundabout's ring is placed so that its entry and exit curves keep to it.
pub const MIN_PATH_RADIUS_M: f64 = 4.0;

/// Distance from each end of an arc at which its sampled polyline has an extra point, m: the
/// polyline's first and last legs on an arc then run along its end tangents (to `κ·ε/2` rad),
/// so headings interpolated along the polyline ([`vertex_tangents`]) are continuous where a
/// line meets an arc.
const TANGENT_GUARD_M: f64 = 1e-3;
/// Largest step between the points of a curved piece's lane paths, metres (their chords
/// depart from the curve by at most 3 mm at the tightest radius, 10 m).
pub const LANE_STEP_M: f64 = 0.5;

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
            curve: Vec::new(),
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
                // Named by its angle as a map's turns are; ports only at those angles.
                let turn = Turn::of_heading(delta);
                if turn.off_nominal_rad(delta) >= 0.1 {
                    continue;
                }
                for j in 1..=half {
                    // Incoming lanes lie left of the port's outward direction, outgoing right.
                    let left = direction(pa.heading_rad + std::f64::consts::FRAC_PI_2);
                    let right = direction(pb.heading_rad - std::f64::consts::FRAC_PI_2);
                    let e = add(pa.pos, left, offset(j));
                    let x = add(pb.pos, right, offset(j));
                    let local = match p.kind.island_radius_m() {
                        Some(island) => ring(
                            (e, inward),
                            (x, pb.heading_rad),
                            island,
                            island + p.kind.half_road_m() / 2.0 + 0.5,
                        ),
                        None => bend((e, inward), (x, pb.heading_rad)),
                    };
                    let curve: Vec<(Pose2, RefLine)> = local
                        .into_iter()
                        .map(|(start, line)| (p.pose.compose(&start), line))
                        .collect();
                    out.push(LanePath {
                        piece,
                        entry: (a, j),
                        exit: (b, j),
                        turn,
                        points: sample(&curve),
                        curve,
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
            let route = map.route((lane, start.at_m, turns, max_len_m), || {
                let points = map
                    .0
                    .route(lane, start.at_m, turns, max_len_m)
                    .map_err(|e| EngineError::InvalidWorld(e.to_string()))?;
                Ok::<_, EngineError>(resample(&points, ROUTE_SPACING_M))
            })?;
            return Ok(route.to_vec());
        }
        let j = k.unsigned_abs();
        let (mut path, mut points) = match start.through {
            // Inside a junction: the rest of the lane path it is on.
            Some((entry, exit)) => self.junction_start(start, j, entry, exit)?,
            None => self.segment_start(start, k, j),
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
            let pick = self.choose_exit(&mut candidates, wanted, used, next)?;
            if wanted.is_some() {
                used += 1;
            }
            let Some(pick) = pick else {
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

    /// The start of a route from `start`, inside a junction on lane `j` of the lane path from
    /// port `entry` to port `exit`: that path, and the route's first points (`start`, then
    /// the path's points beyond it), world `[x, z]` m.
    ///
    /// # Errors
    /// [`EngineError::InvalidWorld`] when the junction has no such lane path.
    fn junction_start(
        &self,
        start: &Location,
        j: u32,
        entry: usize,
        exit: usize,
    ) -> Result<(LanePath, Vec<[f64; 2]>), EngineError> {
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
        Ok((path, points))
    }

    /// The start of a route from `start` on driving lane `k` (`j = |k|`) of a segment: the
    /// lane's path in its driving direction, and the route's first points (`start`, then the
    /// lane's points ahead of it), world `[x, z]` m.
    fn segment_start(&self, start: &Location, k: i32, j: u32) -> (LanePath, Vec<[f64; 2]>) {
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

    /// The lane path a route takes among `candidates`, the paths from the port `next` that it
    /// enters by: the turn `wanted` (the route's turn number `used + 1`), or, with none, an
    /// exit that leads on into the network before a dead end, then straight, right, left.
    /// `None`: no candidate.
    ///
    /// # Errors
    /// [`EngineError::InvalidWorld`] when no candidate makes the turn `wanted`, naming the
    /// junction, the port and the turns it offers.
    fn choose_exit(
        &self,
        candidates: &mut Vec<&LanePath>,
        wanted: Option<Turn>,
        used: usize,
        next: (PieceId, usize),
    ) -> Result<Option<LanePath>, EngineError> {
        let pick = match wanted {
            Some(t) => {
                let Some(c) = candidates.iter().find(|c| c.turn == t) else {
                    let offered: Vec<String> = Turn::NAMED
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
        Ok(pick.map(|&c| c.clone()))
    }
}

/// The point `at_m` metres along the polyline `points` (clamped to its ends), the heading
/// there ([`heading_on_leg`] of its [`vertex_tangents`]: continuous along the polyline, and
/// the curve's tangent where the polyline samples a line or an arc), and the polyline's
/// length, metres.
pub(crate) fn along(points: &[[f64; 2]], at_m: f64) -> ([f64; 2], f64, f64) {
    let length: f64 = points.windows(2).map(|w| dist(w[0], w[1])).sum();
    let tangents = vertex_tangents(points);
    let mut left = at_m.clamp(0.0, length);
    for (i, w) in points.windows(2).enumerate() {
        let d = dist(w[0], w[1]);
        if left <= d || d == 0.0 && left == 0.0 {
            let u = if d > 0.0 { left / d } else { 0.0 };
            return (
                [
                    w[0][0] + u * (w[1][0] - w[0][0]),
                    w[0][1] + u * (w[1][1] - w[0][1]),
                ],
                heading_on_leg(&tangents, i + 1, u),
                length,
            );
        }
        left -= d;
    }
    let n = points.len();
    (points[n - 1], tangents[n - 1], length)
}

/// The heading (rad) of the leg from `a` to `b` (`0` for a leg of no length).
fn leg_heading(a: [f64; 2], b: [f64; 2]) -> f64 {
    (-(b[1] - a[1])).atan2(b[0] - a[0])
}

/// The tangent heading at each vertex of the polyline `points`, rad: between two legs of
/// lengths `l₁` and `l₂` and headings `h₁`, `h₂`, `h₁ + (h₂ − h₁)·l₁/(l₁ + l₂)`, which is the
/// exact tangent when both legs are chords of one circle (or of one line), so a polyline
/// sampled from lines and arcs gives their tangents at its vertices; at the ends, the end
/// legs' headings. Legs of no length are skipped (a vertex on one takes its neighbours'
/// tangent). A polyline of one point, or of coincident points, has heading 0.
pub(crate) fn vertex_tangents(points: &[[f64; 2]]) -> Vec<f64> {
    (0..points.len()).map(|i| tangent_at(points, i)).collect()
}

/// The tangent heading at vertex `i` of the polyline `points`, rad: element `i` of
/// [`vertex_tangents`], worked out from the legs next to it alone (a follower of a route
/// kilometres long needs only the vertices it reaches).
pub(crate) fn tangent_at(points: &[[f64; 2]], i: usize) -> f64 {
    let leg = |k: usize| {
        let (a, b) = (points[k], points[k + 1]);
        let l = dist(a, b);
        (l > 0.0).then(|| (l, leg_heading(a, b)))
    };
    // The nearest leg with a length before vertex `i` (legs `< i`) and after it.
    let before = (0..i.min(points.len().saturating_sub(1)))
        .rev()
        .find_map(leg);
    let after = (i..points.len().saturating_sub(1)).find_map(leg);
    match (before, after) {
        (Some((l1, h1)), Some((l2, h2))) => h1 + wrap(h2 - h1) * l1 / (l1 + l2),
        (Some((_, h)), None) | (None, Some((_, h))) => h,
        (None, None) => 0.0,
    }
}

/// The heading `u` of the way (in `[0, 1]`) along leg `i` (`points[i - 1] → points[i]`) of a
/// polyline with vertex tangents `tangents` ([`vertex_tangents`]): [`heading_between`] the
/// two vertices' tangents.
pub(crate) fn heading_on_leg(tangents: &[f64], i: usize, u: f64) -> f64 {
    heading_between(tangents[i - 1], tangents[i], u)
}

/// The heading `u` of the way (in `[0, 1]`) from tangent `a` to tangent `b` (rad), the short
/// way round: continuous along a polyline, turning at a constant rate along each leg (on a
/// sampled arc of curvature `κ`, `κ` rad per metre).
pub(crate) fn heading_between(a: f64, b: f64, u: f64) -> f64 {
    wrap(a + u * wrap(b - a))
}

/// The points of a chain of lines and arcs (each placed by its start pose), at most
/// [`LANE_STEP_M`] apart in equal steps along each, with an extra point
/// [`TANGENT_GUARD_M`] from each end of an arc; each piece's end is the next one's start, so
/// it is listed once.
pub(crate) fn sample(curve: &[(Pose2, RefLine)]) -> Vec<[f64; 2]> {
    let mut out: Vec<[f64; 2]> = Vec::new();
    for (pose, line) in curve {
        let mut stations = line.stations(LANE_STEP_M);
        if line.curv_start != 0.0 && line.length_m > 4.0 * TANGENT_GUARD_M {
            let last = stations.len() - 1;
            stations.insert(last, line.length_m - TANGENT_GUARD_M);
            stations.insert(1, TANGENT_GUARD_M);
        }
        let skip = usize::from(!out.is_empty());
        // `Pose2::apply` with its rotation worked out once.
        let (sin, cos) = pose.heading_rad.sin_cos();
        out.extend(stations.into_iter().skip(skip).map(|s| {
            let [x, z] = arc_point(line, s);
            [pose.x + x * cos + z * sin, pose.z - x * sin + z * cos]
        }));
    }
    out
}

/// The point `s` metres along a line or an arc (`line` of constant curvature `κ`), in its
/// frame, in closed form: `(sin κs / κ, (cos κs − 1) / κ)`, or `(s, 0)` for a line (the
/// quadrature of [`RefLine::point`] costs `O(s)`, too much for a ring kilometres round).
fn arc_point(line: &RefLine, s: f64) -> [f64; 2] {
    let k = line.curv_start;
    if k == 0.0 {
        [s, 0.0]
    } else {
        let (sin, cos) = (k * s).sin_cos();
        [sin / k, (cos - 1.0) / k]
    }
}

/// The pose at the end of `line` (a line or an arc) placed at `pose`.
fn end_pose(pose: &Pose2, line: &RefLine) -> Pose2 {
    let [x, z] = pose.apply(arc_point(line, line.length_m));
    Pose2 {
        x,
        z,
        heading_rad: wrap(pose.heading_rad + line.heading(line.length_m)),
    }
}

/// A straight line of `length_m` metres (`> 0`).
fn line(length_m: f64) -> RefLine {
    RefLine {
        length_m,
        curv_start: 0.0,
        curv_end: 0.0,
    }
}

/// A turning path from `e` (heading `he`) to `x` (heading `hx`), both `(point, heading)`:
/// along the entry line, a circular arc tangent to both lines, and along the exit line
/// (the arc's tangent points are equally far from the lines' crossing, as far as the nearer
/// of the two ends is). A straight line when the headings agree; lines and arcs are the
/// pieces of the chain, each with its start pose.
fn bend((e, he): ([f64; 2], f64), (x, hx): ([f64; 2], f64)) -> Vec<(Pose2, RefLine)> {
    let start = Pose2 {
        x: e[0],
        z: e[1],
        heading_rad: he,
    };
    let turn = wrap(hx - he);
    let (de, dx) = (direction(he), direction(hx));
    let cross = de[0] * dx[1] - de[1] * dx[0];
    if turn.abs() < 1e-9 || cross.abs() < 1e-12 {
        return vec![(start, line(dist(e, x)))];
    }
    // e + s·de + u·dx = x: the crossing is s along the entry line and u before the exit.
    let r = [x[0] - e[0], x[1] - e[1]];
    let s = (r[0] * dx[1] - r[1] * dx[0]) / cross;
    let u = (de[0] * r[1] - de[1] * r[0]) / cross;
    let tangent = s.min(u);
    if tangent <= 0.0 {
        // No arc fits (not a junction's geometry): the chord.
        return vec![(
            Pose2 {
                heading_rad: leg_heading(e, x),
                ..start
            },
            line(dist(e, x)),
        )];
    }
    let radius = tangent / (turn.abs() / 2.0).tan();
    let mut chain = Vec::new();
    let mut at = start;
    if s - tangent > 1e-9 {
        chain.push((at, line(s - tangent)));
        at = end_pose(&at, &line(s - tangent));
    }
    let arc = RefLine::arc(radius, turn);
    chain.push((at, arc));
    at = end_pose(&at, &arc);
    if u - tangent > 1e-9 {
        chain.push((at, line(u - tangent)));
    }
    chain
}

/// The radius of the arc that leaves a roundabout's entry point `e` (on the entry line,
/// `o` metres left of the port's centre line, `d` metres from the centre) turning right and
/// meets the ring of radius `r` from outside: `(d² + o² − r²) / (2 (r − o))`.
fn fillet_radius(d: f64, o: f64, r: f64) -> f64 {
    (d * d + o * o - r * r) / (2.0 * (r - o))
}

/// The ring radius of a roundabout's lane path: the one nearest `preferred` at least 1.2 m
/// outside the island (the half width of a car and a margin) whose entry and exit curves
/// (radius [`fillet_radius`]) are no tighter than [`MIN_PATH_RADIUS_M`] and leave at least
/// 0.1 rad of ring between the entry and the exit of a right turn; `None` when none is (the
/// plaza is too small for the lanes: [`roundabout_fits`]).
fn ring_radius(d: f64, o: f64, island: f64, preferred: f64) -> Option<f64> {
    let fits = |r: f64| {
        let rho = fillet_radius(d, o, r);
        r > o
            && rho >= MIN_PATH_RADIUS_M
            && 2.0 * (o + rho).atan2(d) <= std::f64::consts::FRAC_PI_2 - 0.1
    };
    if fits(preferred) {
        return Some(preferred);
    }
    let lo = island + 1.2;
    let hi = d - o;
    (0..=4000)
        .map(|k| lo + (hi - lo) * f64::from(k) / 4000.0)
        .filter(|&r| fits(r))
        .min_by(|a, b| (a - preferred).abs().total_cmp(&(b - preferred).abs()))
}

/// The ring radius of lane `j` of a roundabout of `lanes` lanes and plaza half side
/// `radius_m`, and how far the lane's entry lies from the port's centre line (m).
fn roundabout_lane(lanes: u32, radius_m: f64, j: u32) -> (Option<f64>, f64) {
    let kind = PieceKind::Roundabout {
        lanes,
        radius_m,
        friction: 1.0,
    };
    let island = kind.island_radius_m().unwrap_or(0.0);
    let o = (f64::from(j) - 0.5) * LANE_WIDTH_M;
    let preferred = island + kind.half_road_m() / 2.0 + 0.5;
    (ring_radius(radius_m, o, island, preferred), o)
}

/// Whether every lane of a `Roundabout` of `lanes` lanes and half side `radius_m` (m) has a
/// way onto its ring and off it no tighter than [`MIN_PATH_RADIUS_M`], with ring between
/// entry and exit for a right turn ([`ring_radius`]): a plaza too small for its lanes has not.
pub fn roundabout_fits(lanes: u32, radius_m: f64) -> bool {
    (1..=lanes / 2).all(|j| roundabout_lane(lanes, radius_m, j).0.is_some())
}

/// The smallest half side (m, in steps of 0.25 m) at which a `Roundabout` of `lanes` lanes
/// fits its lanes ([`roundabout_fits`]): 8.5 m for 2 lanes, 18.5 m for 4, 28 m for 6.
pub fn min_roundabout_radius_m(lanes: u32) -> f64 {
    let mut r = f64::from(lanes) * LANE_WIDTH_M / 2.0 + super::SIDEWALK_WIDTH_M + 3.0;
    while !roundabout_fits(lanes, r) && r < 1_000.0 {
        r += 0.25;
    }
    r
}

/// A roundabout's path (counter-clockwise) from the entry point `e` (heading `he`, toward the
/// centre) to the exit point `x` (heading `hx`, away from it), about the origin: an arc
/// turning right from the entry line onto the ring (radius [`ring_radius`], near `preferred`),
/// the ring counter-clockwise, and an arc turning right off the ring onto the exit line. The
/// arcs meet the ring tangentially, so the heading is continuous throughout.
fn ring(
    (e, he): ([f64; 2], f64),
    (x, hx): ([f64; 2], f64),
    island: f64,
    preferred: f64,
) -> Vec<(Pose2, RefLine)> {
    // Distance from the centre along the port's line, and offset to the side of it.
    let d = e[0] * direction(he)[0] + e[1] * direction(he)[1];
    let d = -d;
    let o = (e[0].hypot(e[1]).powi(2) - d * d).max(0.0).sqrt();
    // A plaza too small for its lanes is refused when the piece is made
    // (`roundabout_fits`); any ring between the lane and the port stands in.
    let r = ring_radius(d, o, island, preferred).unwrap_or(0.5 * (o + d));
    let rho = fillet_radius(d, o, r);
    let angle = |p: [f64; 2]| (-p[1]).atan2(p[0]);
    // The entry arc: centre `rho` to the right of the entry line, touching the ring where
    // the line from the origin to that centre crosses it.
    let right = |h: f64| direction(h - std::f64::consts::FRAC_PI_2);
    let c_in = [e[0] + rho * right(he)[0], e[1] + rho * right(he)[1]];
    let a0 = angle(c_in);
    let ring_in = a0 + std::f64::consts::FRAC_PI_2;
    let turn_in = -wrap(he - ring_in).abs();
    // The exit arc: centre `rho` to the right of the exit line.
    let c_out = [x[0] + rho * right(hx)[0], x[1] + rho * right(hx)[1]];
    let mut a1 = angle(c_out);
    while a1 <= a0 {
        a1 += std::f64::consts::TAU;
    }
    let ring_out = a1 + std::f64::consts::FRAC_PI_2;
    let turn_out = -wrap(ring_out - hx).abs();
    let start = Pose2 {
        x: e[0],
        z: e[1],
        heading_rad: he,
    };
    let entry = RefLine::arc(rho, turn_in);
    let on_ring = Pose2 {
        x: r * a0.cos(),
        z: -r * a0.sin(),
        heading_rad: wrap(ring_in),
    };
    let around = RefLine::arc(r, a1 - a0);
    let off_ring = Pose2 {
        x: r * a1.cos(),
        z: -r * a1.sin(),
        heading_rad: wrap(ring_out),
    };
    let exit = RefLine::arc(rho, turn_out);
    vec![(start, entry), (on_ring, around), (off_ring, exit)]
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
