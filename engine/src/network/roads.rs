//! Lane coordinates on an OpenDRIVE map, the engine's lane API for scripted entities: where
//! OpenSCENARIO positions lie (road and lane positions, `anchor`), and how an entity moves
//! along its lanes (`advance`, across links and junctions, a route's roads preferred). An
//! OpenSCENARIO storyboard's tasks drive its entities through it, the engine's transitions
//! ([`crate::transition`]) and its placement (`Action::PlaceCar`). Poses here are in the OpenSCENARIO (OpenDRIVE) frame: x east, y north (m), heading
//! counter-clockwise from x (rad); [`Roads::to_engine`] turns one into the engine's world
//! (`[x, y, z]`, z = −(y − origin)).

use std::f64::consts::PI;

use std::sync::Arc;

use super::{MapIndex, MapRef, RoadMap};

/// A pose in the OpenSCENARIO frame: `x`, `y` in m, heading `h` in rad.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pose {
    /// East, m.
    pub x: f64,
    /// North, m.
    pub y: f64,
    /// Heading, rad, counter-clockwise from east.
    pub h: f64,
}

/// Where an entity stands on a lane.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LanePos {
    /// The lane, an index into [`RoadMap::lanes`].
    pub lane: usize,
    /// Station along the road's reference line, m.
    pub s: f64,
    /// Lateral offset from the lane's centre line, m, positive to the left of increasing `s`
    /// (OpenDRIVE's `t` direction).
    pub d: f64,
    /// Whether the entity faces and moves against the lane's direction of travel (a lane
    /// position faces the lane's direction of travel unless its orientation says otherwise,
    /// as esmini has it; an entity placed facing the other way drives against the lane).
    pub rev: bool,
}

impl LanePos {
    /// Whether the entity moves along increasing `s`.
    pub fn along_s(&self, roads: &Roads) -> bool {
        roads.forward(self.lane) != self.rev
    }
}

/// Why a position is not on the map: the road or lane it names is not there (the map's own
/// message, naming the roads or lanes it has).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{0}")]
pub struct RoadError(pub String);

/// `a` wrapped to `(−π, π]`.
pub fn wrap(a: f64) -> f64 {
    let mut x = (a + PI).rem_euclid(2.0 * PI) - PI;
    if x <= -PI {
        x += 2.0 * PI;
    }
    x
}

/// A map as the storyboard reads it.
#[derive(Clone)]
pub struct Roads {
    map: Arc<RoadMap>,
    index: MapIndex,
}

impl std::fmt::Debug for Roads {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Roads({})", self.map.source)
    }
}

impl Roads {
    /// The storyboard's view of `map`, with its query index (built once per map and shared
    /// by every test).
    pub fn new(map: &MapRef) -> Self {
        Roads {
            index: map.index(),
            map: map.0.clone(),
        }
    }

    /// The map.
    pub fn map(&self) -> &RoadMap {
        &self.map
    }

    fn to_od(&self, p: [f64; 2]) -> [f64; 2] {
        [p[0] + self.map.origin_m[0], -p[1] + self.map.origin_m[1]]
    }

    fn od_to_engine(&self, x: f64, y: f64) -> [f64; 2] {
        [x - self.map.origin_m[0], -(y - self.map.origin_m[1])]
    }

    /// `pose` in the engine's world: `[x, y, z]` m on the road surface, heading rad.
    pub fn to_engine(&self, pose: Pose) -> ([f64; 3], f64) {
        let [x, z] = self.od_to_engine(pose.x, pose.y);
        ([x, 0.0, z], wrap(pose.h))
    }

    /// The centre of lane `k` at station `s` (OpenSCENARIO frame) and the direction of
    /// increasing `s` there, rad.
    fn frame(&self, k: usize, s: f64) -> ([f64; 2], f64) {
        let l = &self.map.lanes[k];
        let (p, h) = l.pose(s);
        let along = if l.forward { h } else { wrap(h + PI) };
        (self.to_od(p), along)
    }

    /// Whether lane `k`'s traffic runs along increasing `s`.
    pub fn forward(&self, k: usize) -> bool {
        self.map.lanes[k].forward
    }

    /// The pose of `lp`, facing the lane's direction of travel.
    pub fn pose_of(&self, lp: &LanePos) -> Pose {
        let (c, along) = self.frame(lp.lane, lp.s);
        let left = [-along.sin(), along.cos()];
        Pose {
            x: c[0] + left[0] * lp.d,
            y: c[1] + left[1] * lp.d,
            h: if lp.along_s(self) {
                along
            } else {
                wrap(along + PI)
            },
        }
    }

    /// The direction of increasing `s` at `lp`, rad.
    pub fn along_heading(&self, lp: &LanePos) -> f64 {
        self.frame(lp.lane, lp.s).1
    }

    /// The direction of travel of `lp`'s lane at its station, rad.
    pub fn travel_heading(&self, lp: &LanePos) -> f64 {
        self.pose_of(&LanePos { d: 0.0, ..*lp }).h
    }

    /// The lane `lane` (`<lane id>`) of road `road` at station `s` with offset `offset`.
    ///
    /// # Errors
    /// The map's refusal, naming the roads or lanes it has.
    pub fn lane_pos(
        &self,
        road: &str,
        lane: i32,
        s: f64,
        offset: f64,
    ) -> Result<LanePos, RoadError> {
        let k = self
            .map
            .lane_at(road, lane, s)
            .map_err(|e| RoadError(e.to_string()))?;
        Ok(LanePos {
            lane: k,
            s,
            d: offset,
            rev: false,
        })
    }

    /// The lane `d_lane` lanes to the left (in the road's `t` direction; `<lane id>` 0 is
    /// skipped) of `lp`'s, `ds` further along the road, `offset` from its centre.
    ///
    /// # Errors
    /// When the road has no such lane there.
    pub fn relative_lane(
        &self,
        lp: &LanePos,
        d_lane: i32,
        ds: f64,
        offset: f64,
    ) -> Result<LanePos, RoadError> {
        let l = &self.map.lanes[lp.lane];
        let mut id = l.od_id;
        for _ in 0..d_lane.unsigned_abs() {
            id += d_lane.signum();
            if id == 0 {
                id += d_lane.signum();
            }
        }
        let road = self.map.roads[l.road].od_id.clone();
        let mut to = self.lane_pos(&road, id, lp.s + ds, offset)?;
        // Facing the way the reference faces.
        to.rev = self.forward(to.lane) != lp.along_s(self);
        Ok(to)
    }

    /// The point `t` (m, left of the reference line) across road `road` at station `s`, on
    /// the lane that holds it (or the nearest lane).
    ///
    /// # Errors
    /// When the road is unknown or has no lane at `s`.
    pub fn road_pos(&self, road: &str, s: f64, t: f64) -> Result<LanePos, RoadError> {
        let (reference, left, lp) = self.reference_at(road, s)?;
        let road_index = self.map.lanes[lp.lane].road;
        let mut best: Option<(f64, LanePos)> = None;
        for (k, l) in self.map.lanes.iter().enumerate() {
            let (a, b) = l.s_range();
            if l.road != road_index || s < a - 1e-9 || s > b + 1e-9 {
                continue;
            }
            let (ck, _) = self.frame(k, s);
            let tc = (ck[0] - reference[0]) * left[0] + (ck[1] - reference[1]) * left[1];
            let miss = ((t - tc).abs() - self.lane_width(k, s) / 2.0).max(0.0);
            if best.as_ref().is_none_or(|(m, _)| miss < *m) {
                best = Some((
                    miss,
                    LanePos {
                        lane: k,
                        s,
                        d: t - tc,
                        rev: false,
                    },
                ));
            }
        }
        best.map(|(_, lp)| lp)
            .ok_or_else(|| RoadError(format!("road {road} has no lane at s = {s} m")))
    }

    /// The road (its OpenDRIVE id) and the lateral coordinate `t` (m, left of the reference
    /// line) of `lp`: the inverse of [`Roads::road_pos`].
    ///
    /// # Errors
    /// When the road has no lane −1 or 1 at the station.
    pub fn road_t(&self, lp: &LanePos) -> Result<(String, f64), RoadError> {
        let road = &self.map.roads[self.map.lanes[lp.lane].road].od_id;
        Ok((road.clone(), self.t_of(lp)?))
    }

    /// The lateral coordinate `t` of `lp` (m, left of the reference line): the offset of
    /// its lane's centre from the line across the normal of lane −1's (or 1's) direction
    /// at that station, plus `lp.d`. [`Roads::road_t`] without the road's name.
    ///
    /// # Errors
    /// When the road has no lane −1 or 1 at the station.
    pub fn t_of(&self, lp: &LanePos) -> Result<f64, RoadError> {
        let road = &self.map.roads[self.map.lanes[lp.lane].road].od_id;
        let (reference, left, _) = self.reference_at(road, lp.s)?;
        let (c, _) = self.frame(lp.lane, lp.s);
        Ok((c[0] - reference[0]) * left[0] + (c[1] - reference[1]) * left[1] + lp.d)
    }

    /// The reference line's point at station `s` of road `road` (OpenDRIVE frame, m), the
    /// unit vector to its left (towards increasing `t`), and lane −1's (or 1's) position
    /// there: the line lies on the inner border of lane −1 (or +1).
    ///
    /// # Errors
    /// When the road is unknown or has no lane −1 or 1 at `s`.
    fn reference_at(&self, road: &str, s: f64) -> Result<([f64; 2], [f64; 2], LanePos), RoadError> {
        let inner = [-1, 1]
            .into_iter()
            .find_map(|id| self.lane_pos(road, id, s, 0.0).ok().map(|lp| (id, lp)));
        let Some((id, lp)) = inner else {
            // The map's own message for the road.
            self.lane_pos(road, -1, s, 0.0)?;
            return Err(RoadError(format!(
                "road {road} has no lane −1 or 1 at s = {s} m"
            )));
        };
        let (c, along) = self.frame(lp.lane, s);
        let left = [-along.sin(), along.cos()];
        let w = self.lane_width(lp.lane, s);
        let sign = if id < 0 { 1.0 } else { -1.0 };
        let reference = [
            c[0] + left[0] * sign * w / 2.0,
            c[1] + left[1] * sign * w / 2.0,
        ];
        Ok((reference, left, lp))
    }

    /// Whether `lp` lies across its road's lanes at its station, of any type but `none`
    /// (its point within half a lane's width of some lane's centre, across that lane): off
    /// its road otherwise, as esmini's `Position::IsOffRoad` takes `t` against the road's
    /// width (`~LANE_TYPE_NONE`), whatever other road's lanes the point may fall on.
    pub fn on_its_road(&self, lp: &LanePos) -> bool {
        let p = self.pose_of(lp);
        let road = self.map.lanes[lp.lane].road;
        (0..self.map.lanes.len()).any(|j| {
            let l = &self.map.lanes[j];
            let (a, b) = l.s_range();
            if l.road != road || l.kind == "none" || !(a - 1e-9 <= lp.s && lp.s <= b + 1e-9) {
                return false;
            }
            let (c, along) = self.frame(j, lp.s);
            let across = (p.x - c[0]) * -along.sin() + (p.y - c[1]) * along.cos();
            across.abs() <= self.lane_width(j, lp.s) / 2.0 + 1e-9
        })
    }

    /// The width of lane `k` at station `s`, m.
    pub fn lane_width(&self, k: usize, s: f64) -> f64 {
        let l = &self.map.lanes[k];
        let i = l.s.partition_point(|&x| x <= s).clamp(1, l.s.len()) - 1;
        l.width[i]
    }

    /// The lane under the point `(x, y)` and where on it, nearest centre line first; `None`
    /// off every lane.
    pub fn anchor(&self, x: f64, y: f64) -> Option<LanePos> {
        let p = self.od_to_engine(x, y);
        let (k, i, _) = self.index.nearest_lane_at(p)?;
        Some(self.anchor_on(k, i, (x, y), p))
    }

    /// Every lane under the point `(x, y)` (OpenDRIVE frame, m) and where on each, nearest
    /// centre line first: where roads overlap (a junction's connecting roads), each of them.
    pub fn anchors(&self, x: f64, y: f64) -> Vec<LanePos> {
        let p = self.od_to_engine(x, y);
        self.index
            .lanes_at(p)
            .into_iter()
            .map(|(k, i, _)| self.anchor_on(k, i, (x, y), p))
            .collect()
    }

    /// The point `(x, y)` (OpenDRIVE frame; `p` in the engine's) on lane `k`, whose segment
    /// at station `i` holds it.
    fn anchor_on(&self, k: usize, i: usize, (x, y): (f64, f64), p: [f64; 2]) -> LanePos {
        let l = &self.map.lanes[k];
        let last = l.centre.len().saturating_sub(2);
        // The point's projection on segment `j`, as a share of it (unclamped), and the
        // projected point.
        let project = |j: usize| {
            let (a, b) = (l.centre[j], l.centre[j + 1]);
            let d = [b[0] - a[0], b[1] - a[1]];
            let len2 = d[0] * d[0] + d[1] * d[1];
            if len2 > 0.0 {
                ((p[0] - a[0]) * d[0] + (p[1] - a[1]) * d[1]) / len2
            } else {
                0.0
            }
        };
        // The index names a station of the strip that holds the point, which may lie a few
        // segments from it: walk to the segment the point projects into (never back).
        let mut j = i.min(last);
        let mut step = 0i8;
        for _ in 0..l.centre.len() {
            let u = project(j);
            if u > 1.0 && j < last && step >= 0 {
                (j, step) = (j + 1, 1);
            } else if u < 0.0 && j > 0 && step <= 0 {
                (j, step) = (j - 1, -1);
            } else {
                break;
            }
        }
        // The station: the point's projection on the nearest of that segment and its
        // neighbours (a point past a segment's end is still held by its strip).
        let mut best = (f64::INFINITY, l.s[j]);
        for j in j.saturating_sub(1)..=(j + 1).min(last) {
            let (a, b) = (l.centre[j], l.centre[j + 1]);
            let u = project(j).clamp(0.0, 1.0);
            let q = [a[0] + u * (b[0] - a[0]), a[1] + u * (b[1] - a[1])];
            let e = (p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2);
            if e < best.0 {
                best = (e, l.s[j] + u * (l.s[j + 1] - l.s[j]));
            }
        }
        let s = best.1;
        let (c, along) = self.frame(k, s);
        let left = [-along.sin(), along.cos()];
        let d = (x - c[0]) * left[0] + (y - c[1]) * left[1];
        LanePos {
            lane: k,
            s,
            d,
            rev: false,
        }
    }

    /// `lp` facing heading `h` (rad): against its lane's travel when `h` points against it.
    pub fn facing(&self, mut lp: LanePos, h: f64) -> LanePos {
        let along = self.along_heading(&lp);
        let with_s = (h - along).cos() >= 0.0;
        lp.rev = with_s != self.forward(lp.lane);
        lp
    }

    /// The lateral distance from lane `from`'s centre to lane `to`'s at station `s`, m,
    /// positive to the left of increasing `s` (`to` on the same road).
    pub fn lateral_between(&self, from: usize, to: usize, s: f64) -> f64 {
        let (a, along) = self.frame(from, s);
        let (b, _) = self.frame(to, s);
        let left = [-along.sin(), along.cos()];
        (b[0] - a[0]) * left[0] + (b[1] - a[1]) * left[1]
    }

    /// The lane beside lane `k` at its station `s` with `<lane id>` `id` on the same road.
    pub fn lane_with_id(&self, k: usize, id: i32, s: f64) -> Option<usize> {
        let l = &self.map.lanes[k];
        self.map.lane_at(&self.map.roads[l.road].od_id, id, s).ok()
    }

    /// The road a car in lane `k` drives on to when `k` is on a junction's connecting road
    /// (following its successors off that road); `k`'s own road otherwise.
    pub fn exit_road(&self, k: usize) -> usize {
        let mut at = k;
        let road = self.map.lanes[k].road;
        if self.map.roads[road].junction.is_none() {
            return road;
        }
        for _ in 0..self.map.lanes.len() {
            match self.map.lanes[at].successors.first() {
                Some(&n) if self.map.lanes[n].road == road => at = n,
                Some(&n) => return self.map.lanes[n].road,
                None => break,
            }
        }
        road
    }

    /// The `<lane id>`s of the driving lanes of road `road` (an index of the map's roads)
    /// at station `s` (m), in the map's order.
    pub fn driving_ids_at(&self, road: usize, s: f64) -> impl Iterator<Item = i32> + '_ {
        (self.map.lanes.iter())
            .filter(move |l| l.road == road && l.drivable)
            .filter(move |l| {
                let (a, b) = l.s_range();
                a - 1e-9 <= s && s <= b + 1e-9
            })
            .map(|l| l.od_id)
    }

    /// The `<lane id>` and road of lane `k`.
    pub fn ids(&self, k: usize) -> (i32, usize) {
        let l = &self.map.lanes[k];
        (l.od_id, l.road)
    }

    /// The roads of the shortest way (by lane length, Dijkstra) from `from` to the road of
    /// `to`, in order, junctions' connecting roads included: along lanes into their
    /// successors, and across to a lane of the same road section that travels the same way
    /// (a lane change, free). The way starts in `from`'s direction of travel and ends on a
    /// lane of `to`'s road that travels as `to`'s does. `None` when no way leads there.
    pub fn route_roads(&self, from: &LanePos, to: &LanePos) -> Option<Vec<usize>> {
        self.route_between(from, to).map(|(roads, _)| roads)
    }

    /// As [`Roads::route_roads`], with the way's length in the roads' stations (m): from
    /// `from`'s station to `to`'s, over the lanes between.
    pub fn route_between(&self, from: &LanePos, to: &LanePos) -> Option<(Vec<usize>, f64)> {
        use std::cmp::Reverse;
        use std::collections::BinaryHeap;
        let lanes = &self.map.lanes;
        let n = lanes.len();
        let goal_road = lanes[to.lane].road;
        let goal_way = lanes[to.lane].forward != to.rev;
        let way = |k: usize| lanes[k].forward;
        let length = |k: usize| {
            let (a, b) = lanes[k].s_range();
            (b - a).max(0.0)
        };
        // The lanes of each road section, for the free lane changes.
        let mut sections: std::collections::HashMap<(usize, usize), Vec<usize>> =
            std::collections::HashMap::new();
        for (k, l) in lanes.iter().enumerate() {
            if l.drivable {
                sections.entry((l.road, l.section)).or_default().push(k);
            }
        }
        let mut dist = vec![f64::INFINITY; n];
        let mut back = vec![usize::MAX; n];
        let mut heap = BinaryHeap::new();
        let start = from.lane;
        // Along `from`'s lane from where it stands to the lane's end.
        let (a, b) = lanes[start].s_range();
        let up = lanes[start].forward != from.rev;
        dist[start] = if up { b - from.s } else { from.s - a }.max(0.0);
        heap.push(Reverse((ordered(dist[start]), start)));
        while let Some(Reverse((d, k))) = heap.pop() {
            let d = d.0;
            if d > dist[k] {
                continue;
            }
            if lanes[k].road == goal_road && way(k) == goal_way {
                // `d` runs to the end of lane `k`: back to `to`'s station on it.
                let (ka, kb) = lanes[k].s_range();
                let past = if way(k) {
                    kb - to.s.clamp(ka, kb)
                } else {
                    to.s.clamp(ka, kb) - ka
                };
                let length = d - past;
                let mut roads = Vec::new();
                let mut at = k;
                loop {
                    let r = lanes[at].road;
                    if roads.last() != Some(&r) {
                        roads.push(r);
                    }
                    if back[at] == usize::MAX {
                        break;
                    }
                    at = back[at];
                }
                roads.reverse();
                return Some((roads, length));
            }
            let siblings = sections
                .get(&(lanes[k].road, lanes[k].section))
                .into_iter()
                .flatten()
                .copied()
                .filter(|&j| j != k && way(j) == way(k));
            let next = lanes[k]
                .successors
                .iter()
                .map(|&j| (j, length(j)))
                .chain(siblings.map(|j| (j, 0.0)));
            for (j, cost) in next {
                let nd = d + cost;
                if nd < dist[j] {
                    dist[j] = nd;
                    back[j] = k;
                    heap.push(Reverse((ordered(nd), j)));
                }
            }
        }
        None
    }

    /// Moves `lp` `ds` metres of station (≥ 0, the roads' `s`, as OpenSCENARIO's route
    /// positions count `pathS`) in its lane's direction of travel, into a successor lane
    /// where the lane ends: the first that `prefer` accepts, else the first. Returns `false`
    /// when the lanes end before: `lp` then stands at the end.
    pub fn advance_stations(
        &self,
        lp: &mut LanePos,
        mut ds: f64,
        prefer: &dyn Fn(usize) -> bool,
    ) -> bool {
        for _ in 0..self.map.lanes.len().max(1) {
            let l = &self.map.lanes[lp.lane];
            let (a, b) = l.s_range();
            let up = l.forward != lp.rev;
            let left = if up { b - lp.s } else { lp.s - a };
            if ds <= left {
                lp.s += if up { ds } else { -ds };
                return true;
            }
            ds -= left.max(0.0);
            let Some(next) = l
                .successors
                .iter()
                .copied()
                .find(|&n| prefer(n))
                .or_else(|| l.successors.first().copied())
            else {
                lp.s = if up { b } else { a };
                return false;
            };
            let n = &self.map.lanes[next];
            let (na, nb) = n.s_range();
            *lp = LanePos {
                lane: next,
                s: if n.forward { na } else { nb },
                d: lp.d,
                rev: false,
            };
        }
        false
    }

    /// Moves `lp` `dist` metres (≥ 0, along the path at its offset from its lane's centre
    /// line, less the lane's drift across the road: [`super::MapLane::t`]) in the lane's direction
    /// of travel, into a successor lane where the lane ends:
    /// the first that `prefer` accepts, else the first. Returns `false` when the lanes end before: `lp` then stands at the
    /// end.
    pub fn advance(&self, lp: &mut LanePos, mut dist: f64, prefer: &dyn Fn(usize) -> bool) -> bool {
        for _ in 0..self.map.lanes.len().max(1) {
            let l = &self.map.lanes[lp.lane];
            let (a, b) = l.s_range();
            // Metres of the centre line per metre of station, here.
            let i = l.s.partition_point(|&x| x <= lp.s).clamp(1, l.s.len() - 1) - 1;
            let span = l.s[i + 1] - l.s[i];
            let mut chord =
                (l.centre[i + 1][0] - l.centre[i][0]).hypot(l.centre[i + 1][1] - l.centre[i][1]);
            // A lane drifting across its road (a changing lane offset, or widths inside it
            // that change) counts only its run along the road, as esmini's motion along `s`
            // does (`DistanceToDS` scales by the curvature at the entity's `t` alone).
            if let (Some(t0), Some(t1)) = (l.t.get(i), l.t.get(i + 1)) {
                let drift = t1 - t0;
                if drift != 0.0 {
                    chord = (chord * chord - drift * drift).max(0.0).sqrt();
                }
            }
            // Off the centre line by `d` (left of increasing `s`), a path bends with the lane:
            // its length per metre of the centre line is `1 − κ·d`, `κ` the centre line's
            // curvature there (esmini's `DistanceToDS` at the entity's own offset).
            let tangent = |j: usize| {
                let r = l.right(j);
                r[0].atan2(r[1])
            };
            let kappa = if chord > 1e-9 {
                wrap(tangent(i + 1) - tangent(i)) / chord
            } else {
                0.0
            };
            let ratio = if span > 1e-9 {
                (chord / span * (1.0 - kappa * lp.d)).max(1e-6)
            } else {
                1.0
            };
            let up = l.forward != lp.rev;
            let left_m = if up { b - lp.s } else { lp.s - a } * ratio;
            if dist <= left_m {
                let ds = dist / ratio;
                lp.s += if up { ds } else { -ds };
                return true;
            }
            dist -= left_m.max(0.0);
            // Against the lane's travel, the way on is a lane this one succeeds.
            let ways: Vec<usize> = if lp.rev {
                (0..self.map.lanes.len())
                    .filter(|&p| self.map.lanes[p].successors.contains(&lp.lane))
                    .collect()
            } else {
                l.successors.clone()
            };
            let next = ways
                .iter()
                .copied()
                .find(|&n| prefer(n))
                .or_else(|| ways.first().copied());
            let Some(n) = next else {
                lp.s = if up { b } else { a };
                return false;
            };
            let nl = &self.map.lanes[n];
            let (na, nb) = nl.s_range();
            // Into a road whose reference line runs the other way: the same side of the
            // motion is the other side of `s`.
            if nl.road != l.road && nl.forward != l.forward {
                lp.d = -lp.d;
            }
            lp.lane = n;
            lp.s = if nl.forward != lp.rev { na } else { nb };
        }
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `t` of a point on a lane of CARLA's Town01 (roads of driving lanes each way with
    /// 0.3 m lanes beside them) is the widths of the lanes between it and the reference line
    /// plus half its own, positive to the left, plus its offset (to 1 cm: on a bend the lanes
    /// are polylines of 0.5 m chords, which cut its corners); and `road_pos` takes
    /// that `t` back to the same lane and offset.
    #[test]
    fn t_is_the_widths_between_the_lane_and_the_reference_line() {
        let path = format!(
            "{}/../tests/data/maps/carla/Town01.xodr",
            env!("CARGO_MANIFEST_DIR")
        );
        let text = std::fs::read_to_string(&path).unwrap();
        let map = crate::network::opendrive::import(&path, &text).unwrap().map;
        let roads = Roads::new(&MapRef::new(map.clone()));
        let mut checked = 0;
        for (k, l) in map.lanes.iter().enumerate() {
            if map.roads[l.road].junction.is_some() {
                continue;
            }
            let (a, b) = l.s_range();
            let s = (a + b) / 2.0;
            let inner: f64 = (map.lanes.iter().enumerate())
                .filter(|(_, m)| m.road == l.road && m.section == l.section)
                .filter(|(_, m)| {
                    m.od_id.signum() == l.od_id.signum() && m.od_id.abs() < l.od_id.abs()
                })
                .map(|(j, _)| roads.lane_width(j, s))
                .sum();
            let want = f64::from(l.od_id.signum()) * (inner + roads.lane_width(k, s) / 2.0);
            for d in [0.0, 0.3, -0.4] {
                let lp = LanePos {
                    lane: k,
                    s,
                    d,
                    rev: false,
                };
                let t = roads.t_of(&lp).unwrap();
                assert!(
                    (t - (want + d)).abs() < 0.01,
                    "lane {} d {d}: t {t}, want {}",
                    l.od_id,
                    want + d
                );
                let road = &map.roads[l.road].od_id;
                assert_eq!(roads.road_t(&lp).unwrap(), (road.clone(), t));
                let back = roads.road_pos(road, s, t).unwrap();
                if d.abs() < roads.lane_width(k, s) / 2.0 {
                    assert_eq!(back.lane, k, "lane {} d {d}", l.od_id);
                    assert!((back.d - d).abs() < 1e-9, "{} {d}", back.d);
                }
            }
            checked += 1;
        }
        assert!(checked > 100, "{checked} lanes");
    }

    #[test]
    fn wrap_keeps_angles_in_range() {
        assert!((wrap(3.0 * PI) - PI).abs() < 1e-12);
        assert!((wrap(-PI) - PI).abs() < 1e-12);
        assert!((wrap(0.5) - 0.5).abs() < 1e-12);
    }
}

/// A distance as a totally ordered key for the route search's heap (distances are finite
/// and ≥ 0, so their bits order as the numbers do).
fn ordered(d: f64) -> Ordered {
    Ordered(d)
}

/// See [`ordered`].
#[derive(Debug, Clone, Copy, PartialEq)]
struct Ordered(f64);

impl Eq for Ordered {}

impl PartialOrd for Ordered {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Ordered {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.0.total_cmp(&other.0)
    }
}
