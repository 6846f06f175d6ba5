//! A road network read from an OpenDRIVE map ([`super::opendrive`]), baked into lane strips:
//! each lane's centre line sampled along its road's reference line, with its width, its
//! direction of travel and the lanes it leads into.
//!
//! Coordinates: OpenDRIVE's `(x, y)` plane is paracosm's ground plane with `x = x` and
//! `z = -y`, so that a heading measured counter-clockwise from `+x` (OpenDRIVE's `hdg`) is
//! paracosm's heading as well ([`super::direction`]). Maps are flat: every lane lies at
//! `y = 0` (the importer warns about elevation it drops).

use std::sync::Arc;

use rstar::primitives::{GeomWithData, Line};
use rstar::RTree;
use serde::{Deserialize, Serialize};

use super::geometry::wrap;
use super::lanes::Turn;

/// One OpenDRIVE road of a map.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MapRoad {
    /// Its `<road id>`.
    pub od_id: String,
    /// Its length along the reference line, m.
    pub length_m: f64,
    /// The `<junction id>` it belongs to (a connecting road), `None` outside junctions.
    pub junction: Option<String>,
}

/// One lane of one lane section of a map.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MapLane {
    /// Index of its road in [`RoadMap::roads`].
    pub road: usize,
    /// Zero-based lane section of the road, in order of `s`.
    pub section: usize,
    /// Its OpenDRIVE `<lane id>`: negative right of the reference line, positive left.
    pub od_id: i32,
    /// Its OpenDRIVE `type` (`driving`, `sidewalk`, `shoulder`...).
    pub kind: String,
    /// Whether cars drive on it (paracosm's driving surface).
    pub drivable: bool,
    /// Whether traffic runs along increasing `s` (right-hand traffic: lanes with negative
    /// ids).
    pub forward: bool,
    /// Stations along the road's reference line, m, increasing, at most 0.5 m apart.
    pub s: Vec<f64>,
    /// The centre line at each station, world `[x, z]`, m.
    pub centre: Vec<[f64; 2]>,
    /// The lane's width at each station, m, `>= 0`.
    pub width: Vec<f64>,
    /// The centre's offset from the road's reference line at each station (OpenDRIVE's `t`,
    /// m, positive left: the `<laneOffset>` plus the widths between the centre and lane 0);
    /// empty where not known (a map deserialized from before it was kept).
    #[serde(default)]
    pub t: Vec<f64>,
    /// The lanes (indices into [`RoadMap::lanes`]) that a car leaving this lane's travel end
    /// drives into.
    pub successors: Vec<usize>,
}

impl MapLane {
    /// The centre line in the direction of travel, world `[x, z]` m.
    pub fn travel_points(&self) -> Vec<[f64; 2]> {
        let mut p = self.centre.clone();
        if !self.forward {
            p.reverse();
        }
        p
    }

    /// The segment index `i` (between stations `i` and `i + 1`) and fraction holding road
    /// station `s` (clamped to the lane's stations).
    fn locate(&self, s: f64) -> (usize, f64) {
        let n = self.s.len();
        let i = self.s.partition_point(|&x| x <= s).clamp(1, n - 1) - 1;
        let span = self.s[i + 1] - self.s[i];
        let u = if span > 0.0 {
            ((s - self.s[i]) / span).clamp(0.0, 1.0)
        } else {
            0.0
        };
        (i, u)
    }

    /// The centre point at road station `s`, world `[x, z]` m, and the direction of travel
    /// there, rad.
    pub fn pose(&self, s: f64) -> ([f64; 2], f64) {
        let (i, u) = self.locate(s);
        let (a, b) = (self.centre[i], self.centre[i + 1]);
        let p = [a[0] + u * (b[0] - a[0]), a[1] + u * (b[1] - a[1])];
        // The tangents at the two stations (central differences, exact on a circle; at the
        // lane's ends carried on from the two nearest chords), interpolated.
        let end = |j: usize| match j {
            0 => self.end_tangent(false),
            j if j + 1 == self.centre.len() => self.end_tangent(true),
            j => self.tangent(j),
        };
        let (h0, h1) = (end(i), end(i + 1));
        let along = wrap(h0 + u * wrap(h1 - h0));
        let heading = if self.forward {
            along
        } else {
            wrap(along + std::f64::consts::PI)
        };
        (p, heading)
    }

    /// The unit vector to the right of increasing `s` at station `i`, world `[x, z]`: the
    /// mean of the neighbouring segments' normals.
    pub fn right(&self, i: usize) -> [f64; 2] {
        let n = self.centre.len();
        let (a, b) = (
            self.centre[i.saturating_sub(1)],
            self.centre[(i + 1).min(n - 1)],
        );
        let d = [b[0] - a[0], b[1] - a[1]];
        let len = d[0].hypot(d[1]).max(1e-12);
        [-d[1] / len, d[0] / len]
    }

    /// The direction of increasing `s` at station `i`, rad: of the chord between the stations
    /// either side (the one chord at an end).
    fn tangent(&self, i: usize) -> f64 {
        let n = self.centre.len();
        let (a, b) = (
            self.centre[i.saturating_sub(1)],
            self.centre[(i + 1).min(n - 1)],
        );
        (-(b[1] - a[1])).atan2(b[0] - a[0])
    }

    /// The direction of increasing `s` at the lane's last station (`last`) or its first, rad:
    /// the heading of the chord nearest that end, carried on to the end at the rate the
    /// headings of the two chords nearest it change (exact on a circle, where the heading is
    /// linear in `s`), which [`MapLane::pose`] reads at the lane's ends. A one-sided
    /// difference there lags by half a sample, `0.25 m / R` on a bend of radius `R` (1.4° at
    /// 10 m), which rounded a junction's 100° turn to 99°.
    fn end_tangent(&self, last: bool) -> f64 {
        let n = self.centre.len();
        let chord = |i: usize| {
            let (a, b) = (self.centre[i], self.centre[i + 1]);
            (
                (-(b[1] - a[1])).atan2(b[0] - a[0]),
                0.5 * (self.s[i] + self.s[i + 1]),
            )
        };
        if n < 3 {
            return self.tangent(if last { n - 1 } else { 0 });
        }
        let (near, far, end) = if last {
            (chord(n - 2), chord(n - 3), self.s[n - 1])
        } else {
            (chord(0), chord(1), self.s[0])
        };
        let span = near.1 - far.1;
        if span.abs() < 1e-9 {
            return near.0;
        }
        wrap(near.0 + wrap(near.0 - far.0) * (end - near.1) / span)
    }

    /// The station range `[first, last]`, m.
    pub fn s_range(&self) -> (f64, f64) {
        (self.s[0], self.s[self.s.len() - 1])
    }
}

/// `, and N more` when a list shows `shown` of `count` items, else nothing.
fn more_roads(count: usize, shown: usize) -> String {
    if count > shown {
        format!(", and {} more", count - shown)
    } else {
        String::new()
    }
}

/// Why [`RoadMap::lane_at`] finds no lane; each message names the map's file.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum LaneAtError {
    /// The map has no road of that id.
    #[error(
        "{map} has no road \"{road}\": it has {count} road{} ({}{}); run `paracosm-fuzz map \
         {map}` to list them with their lanes",
        if *.count == 1 { "" } else { "s" },
        .roads.join(", "),
        more_roads(*.count, .roads.len())
    )]
    NoRoad {
        /// The map's file ([`RoadMap::source`]).
        map: String,
        /// The road asked for, its `<road id>`.
        road: String,
        /// The map's first 20 road ids.
        roads: Vec<String>,
        /// How many roads the map has.
        count: usize,
    },
    /// The station lies outside the road.
    #[error("s = {s_m} m is outside road \"{road}\" of {map}, [0, {length_m:.2}] m")]
    OffRoad {
        /// The map's file ([`RoadMap::source`]).
        map: String,
        /// The road, its `<road id>`.
        road: String,
        /// The station asked for, m.
        s_m: f64,
        /// The road's length, m.
        length_m: f64,
    },
    /// The road has no lane of that id at the station.
    #[error(
        "road \"{road}\" of {map} has no lane {lane} at s = {s_m} m; its lanes there: {}",
        .lanes.join(", ")
    )]
    NoLane {
        /// The map's file ([`RoadMap::source`]).
        map: String,
        /// The road, its `<road id>`.
        road: String,
        /// The lane asked for, its OpenDRIVE id.
        lane: i32,
        /// The station, m.
        s_m: f64,
        /// The road's lanes at the station: `id (kind)`.
        lanes: Vec<String>,
    },
}

/// A route's turn that a fork of a map does not offer ([`RoadMap::route`]).
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
#[error(
    "the route's turn {number} (\"{turn}\") is not possible at the fork where lane {lane} of road {road} of {map} ends: it offers {} there",
    .offered.join(" and ")
)]
pub struct RouteError {
    /// The turn's place in the route's list, from 1.
    pub number: usize,
    /// The turn.
    pub turn: Turn,
    /// The `<lane id>` of the lane that ends at the fork.
    pub lane: i32,
    /// Its `<road id>`.
    pub road: String,
    /// The map's file ([`RoadMap::source`]).
    pub map: String,
    /// The ways out: each one's name, connecting road and heading change, as
    /// `"left" (road:56, +90°)`.
    pub offered: Vec<String>,
}

/// A map's roads and lanes (see the module documentation).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RoadMap {
    /// The file it was read from, as the program names it (for messages).
    pub source: String,
    /// Where the map's origin lies in the file's own coordinates, OpenDRIVE `[x, y]` m: a map
    /// far from the origin is simulated moved to it (`opendrive::RESOLVED_M`), and exports
    /// add this back. `[0, 0]` for most maps.
    #[serde(default)]
    pub origin_m: [f64; 2],
    /// Its roads.
    pub roads: Vec<MapRoad>,
    /// Its lanes: every lane of every section with a positive width somewhere.
    pub lanes: Vec<MapLane>,
    /// Its traffic signals (OpenDRIVE `<signal>`s): each one's `id` and `name` (empty when it
    /// has none), in the file's order. paracosm draws and simulates none; an OpenSCENARIO
    /// storyboard's signal actions and conditions name them, and a name not here is refused.
    #[serde(default)]
    pub signals: Vec<(String, String)>,
}

/// Where a route joins two lanes, how close the next lane's first station may lie to the last
/// point and still be that point, m (a link that meets leaves a gap of well under this; one
/// that does not is refused or warned of at load, `links.rs`).
pub const JOIN_SAME_M: f64 = 0.01;

/// A shared, immutable [`RoadMap`]: cloning a network clones the handle, not the map, nor
/// what is derived from the map once and shared by every test that uses it (its query
/// index, its collision mesh: [`MapCache`]).
#[derive(Debug, Clone, PartialEq)]
pub struct MapRef(pub Arc<RoadMap>, Arc<MapCache>);

impl MapRef {
    /// A handle of `map` with an empty cache.
    pub fn new(map: Arc<RoadMap>) -> Self {
        MapRef(map, Arc::default())
    }

    /// `plan(lane, s, turns, max_len_m)` ([`RoadMap::route`], resampled by the caller),
    /// planned at the first call for these arguments and kept: tests that start an actor at
    /// the same place with the same turns share one plan (a route of kilometres through a
    /// town costs more than a short test's simulation).
    ///
    /// # Errors
    /// What `plan` returns.
    pub fn route<E>(
        &self,
        (lane, s, turns, max_len_m): (usize, f64, &[Turn], f64),
        plan: impl FnOnce() -> Result<Vec<[f64; 2]>, E>,
    ) -> Result<Arc<Vec<[f64; 2]>>, E> {
        let key: RouteKey = (lane, s.to_bits(), format!("{turns:?}"), max_len_m.to_bits());
        let lock = || self.1.routes.lock().unwrap_or_else(|e| e.into_inner());
        if let Some((_, r)) = lock().iter().find(|(k, _)| *k == key) {
            return Ok(r.clone());
        }
        let route = Arc::new(plan()?);
        let mut routes = lock();
        if routes.len() >= CACHED_ROUTES {
            routes.remove(0);
        }
        routes.push((key, route.clone()));
        Ok(route)
    }

    /// Each drivable lane's centre line in its direction of travel ([`MapIndex::lane_lines`])
    /// with the boxes of its runs of legs, for the lane offset queries of
    /// [`super::Surface`]: computed at the first call and kept.
    pub(crate) fn lane_lines(&self) -> super::surface::LaneLines {
        self.1
            .lane_lines
            .get_or_init(|| super::surface::lane_lines(self.index().lane_lines()))
            .clone()
    }

    /// [`RoadMap::bounds_m`], computed at the first call and kept.
    pub fn bounds_m(&self) -> ([f64; 2], [f64; 2]) {
        *self.1.bounds.get_or_init(|| self.0.bounds_m())
    }

    /// The map's query index ([`MapIndex`]), built at the first call and shared by every
    /// later one (and every clone of this handle).
    pub fn index(&self) -> MapIndex {
        let trees = self
            .1
            .trees
            .get_or_init(|| Arc::new(MapTrees::new(&self.0)));
        MapIndex {
            map: self.0.clone(),
            trees: trees.clone(),
            recent: no_recent_hits(),
        }
    }

    /// A mesh of the map placed by `pose_key` (the bits of the piece's pose), one per type
    /// `T` (the collision mesh, the render mesh): built by `build` at the first call for that
    /// type and pose and shared after (a call for another pose replaces it).
    pub(crate) fn mesh<T: Clone + Send + Sync + 'static>(
        &self,
        pose_key: [u64; 3],
        build: impl FnOnce() -> Option<T>,
    ) -> Option<T> {
        let kind = std::any::TypeId::of::<T>();
        let lookup = |slots: &[CachedMesh]| {
            slots.iter().find_map(|(t, key, shape)| {
                (*t == kind && *key == pose_key)
                    .then(|| shape.downcast_ref::<T>().cloned())
                    .flatten()
            })
        };
        {
            let slots = self.1.meshes.lock().unwrap_or_else(|e| e.into_inner());
            if let Some(shape) = lookup(&slots) {
                return Some(shape);
            }
        }
        // Built without the lock, so that a build may itself read another type's mesh (the
        // GPU buffers upload the render mesh); two workers that start together may both
        // build, and the first to finish is kept (the builds are equal).
        let shape = build()?;
        let mut slots = self.1.meshes.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(first) = lookup(&slots) {
            return Some(first);
        }
        let entry = (
            kind,
            pose_key,
            Box::new(shape.clone()) as Box<dyn std::any::Any + Send + Sync>,
        );
        match slots.iter().position(|(t, _, _)| *t == kind) {
            Some(k) => slots[k] = entry,
            None => slots.push(entry),
        }
        Some(shape)
    }
}

/// What a route is planned from: the start lane, the bits of its station, the turns (as
/// written) and the bits of the length planned.
type RouteKey = (usize, u64, String, u64);

/// A planned route, world `[x, z]` m, shared by the tests that plan it.
type SharedRoute = Arc<Vec<[f64; 2]>>;

/// How many routes a map's cache keeps (one per distinct start and turns a campaign plans;
/// past this many, the oldest goes).
const CACHED_ROUTES: usize = 64;

/// A mesh of a map ([`MapRef::mesh`]): its type, the bits of the pose it was built for, and
/// the mesh.
type CachedMesh = (
    std::any::TypeId,
    [u64; 3],
    Box<dyn std::any::Any + Send + Sync>,
);

/// What is derived from a [`RoadMap`] once per map, for every test that uses it: the key is
/// the map itself (one per file a program reads, [`MapRef`]'s `Arc`) and, for the mesh, the
/// pose it is placed at. A test's world reads it; nothing writes it after it is built, so
/// every test sees the same bits whichever worker built it.
#[derive(Default)]
pub struct MapCache {
    bounds: std::sync::OnceLock<([f64; 2], [f64; 2])>,
    lane_lines: std::sync::OnceLock<super::surface::LaneLines>,
    routes: std::sync::Mutex<Vec<(RouteKey, SharedRoute)>>,
    trees: std::sync::OnceLock<Arc<MapTrees>>,
    meshes: std::sync::Mutex<Vec<CachedMesh>>,
}

impl std::fmt::Debug for MapCache {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("MapCache")
    }
}

/// Derived data compares equal: two handles of equal maps are equal.
impl PartialEq for MapCache {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

impl Serialize for MapRef {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        self.0.serialize(s)
    }
}

impl<'de> Deserialize<'de> for MapRef {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        RoadMap::deserialize(d).map(|m| MapRef::new(Arc::new(m)))
    }
}

impl RoadMap {
    /// A map with no roads, named `source`: the ground of a scenario that names no road
    /// network (esmini's examples of a parking lot, a combination of vehicles on open
    /// ground). Every position on it is off the road; nothing can be placed on a lane.
    pub fn empty(source: &str) -> RoadMap {
        RoadMap {
            source: source.to_string(),
            origin_m: [0.0, 0.0],
            roads: Vec::new(),
            lanes: Vec::new(),
            signals: Vec::new(),
        }
    }

    /// The bounding box of every lane's strip, world `([x_min, z_min], [x_max, z_max])` m.
    pub fn bounds_m(&self) -> ([f64; 2], [f64; 2]) {
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for lane in &self.lanes {
            for (p, w) in lane.centre.iter().zip(&lane.width) {
                lo = [lo[0].min(p[0] - w / 2.0), lo[1].min(p[1] - w / 2.0)];
                hi = [hi[0].max(p[0] + w / 2.0), hi[1].max(p[1] + w / 2.0)];
            }
        }
        if lo[0] > hi[0] {
            return ([0.0; 2], [0.0; 2]);
        }
        (lo, hi)
    }

    /// The lane `od_id` of road `road` (its `<road id>`) at station `s` (m).
    ///
    /// # Errors
    /// A [`LaneAtError`] naming the roads (for an unknown road), the lanes of the road at `s`
    /// (for a lane it lacks there), or the road's length (for `s` outside it).
    pub fn lane_at(&self, road: &str, od_id: i32, s: f64) -> Result<usize, LaneAtError> {
        let Some(r) = self.roads.iter().position(|r| r.od_id == road) else {
            let mut roads: Vec<String> = self.roads.iter().map(|r| r.od_id.clone()).collect();
            let count = roads.len();
            roads.truncate(20);
            return Err(LaneAtError::NoRoad {
                map: self.source.clone(),
                road: road.to_owned(),
                roads,
                count,
            });
        };
        let length = self.roads[r].length_m;
        if !(0.0..=length).contains(&s) {
            return Err(LaneAtError::OffRoad {
                map: self.source.clone(),
                road: road.to_owned(),
                s_m: s,
                length_m: length,
            });
        }
        let here = |i: &usize| {
            let l = &self.lanes[*i];
            let (a, b) = l.s_range();
            l.road == r && a - 1e-9 <= s && s <= b + 1e-9
        };
        (0..self.lanes.len())
            .filter(here)
            .find(|&i| self.lanes[i].od_id == od_id)
            .ok_or_else(|| {
                let lanes: Vec<String> = (0..self.lanes.len())
                    .filter(here)
                    .map(|i| format!("{} ({})", self.lanes[i].od_id, self.lanes[i].kind))
                    .collect();
                LaneAtError::NoLane {
                    map: self.source.clone(),
                    road: road.to_owned(),
                    lane: od_id,
                    s_m: s,
                    lanes,
                }
            })
    }

    /// The direction of travel at the end of lane `k`'s travel, rad.
    fn travel_end_heading(&self, k: usize) -> f64 {
        let l = &self.lanes[k];
        let along = l.end_tangent(l.forward);
        if l.forward {
            along
        } else {
            wrap(along + std::f64::consts::PI)
        }
    }

    /// The lane where a car that enters lane `to` leaves the road `to` belongs to, when that
    /// road is a junction's connecting road (following `to`'s successors on that road, through
    /// its lane sections); `to` itself otherwise.
    fn through_junction(&self, to: usize) -> usize {
        let mut k = to;
        if self.roads[self.lanes[k].road].junction.is_none() {
            return k;
        }
        for _ in 0..self.lanes.len() {
            let l = &self.lanes[k];
            match l.successors.iter().find(|&&n| self.lanes[n].road == l.road) {
                Some(&n) if n != to => k = n,
                _ => break,
            }
        }
        k
    }

    /// The ways out of the fork where lane `at`'s travel ends: each successor lane with the
    /// heading change it makes (rad, positive to the left: from the end of `at` to where the
    /// car leaves the successor's connecting road, or the successor's own end outside
    /// junctions) and the turn it is named by ([`Turn::name_ways`]; `None` for a way that
    /// only its road names).
    pub fn ways_out(&self, at: usize) -> Vec<(usize, f64, Option<Turn>)> {
        let from = self.travel_end_heading(at);
        let next = &self.lanes[at].successors;
        let deltas: Vec<f64> = next
            .iter()
            .map(|&n| wrap(self.travel_end_heading(self.through_junction(n)) - from))
            .collect();
        let names = Turn::name_ways(&deltas);
        next.iter()
            .zip(deltas)
            .zip(names)
            .map(|((&n, d), t)| (n, d, t))
            .collect()
    }

    /// The successor lane a route takes at the fork where lane `at` ends: the turn `wanted`
    /// (by name, the way [`RoadMap::ways_out`] names so; by road id, the way through that
    /// road), or, with none, straight on (the least heading change).
    ///
    /// # Errors
    /// A [`RouteError`] (with `number` 0, for the caller to fill) when no way out makes the
    /// turn.
    fn choose(&self, at: usize, wanted: Option<Turn>) -> Result<usize, RouteError> {
        let ways = self.ways_out(at);
        // Among the ways `wanted` names, the one that turns least.
        let pick = ways
            .iter()
            .filter(|w| match wanted {
                None => true,
                Some(Turn::Road(id)) => self.roads[self.lanes[w.0].road].od_id == id.as_str(),
                Some(t) => w.2 == Some(t),
            })
            .min_by(|a, b| a.1.abs().total_cmp(&b.1.abs()))
            .map(|w| w.0);
        pick.ok_or_else(|| {
            let here = &self.lanes[at];
            RouteError {
                number: 0,
                turn: wanted.unwrap_or(Turn::Straight),
                lane: here.od_id,
                road: self.roads[here.road].od_id.clone(),
                map: self.source.clone(),
                offered: ways
                    .iter()
                    .map(|w| {
                        let road = &self.roads[self.lanes[w.0].road].od_id;
                        let angle = w.1.to_degrees();
                        match w.2 {
                            Some(t) => format!("\"{t}\" (road:{road}, {angle:+.0}°)"),
                            None => format!("\"road:{road}\" ({angle:+.0}°)"),
                        }
                    })
                    .collect(),
            }
        })
    }

    /// The route from road station `s` of lane `lane` in its direction of travel, then on
    /// through its successors until the lanes end or the route is `max_len_m` long. At a
    /// fork (a lane with more than one drivable successor) it takes the next turn of `turns`
    /// (straight on, the least heading change, when the list is used up). A fork's ways out
    /// are named by the heading change from the end of the lane to where the car leaves the
    /// junction's connecting road ([`RoadMap::ways_out`], [`Turn::name_ways`]): straight,
    /// left, right or uturn, or [`Turn::Road`] for the way through a connecting road. World
    /// `[x, z]` m.
    ///
    /// # Errors
    /// A [`RouteError`] when a fork lacks the turn the list gives it (naming the turn, its
    /// place in the list, the road and lane that end there and the ways out it offers): a
    /// turn is never replaced by another. Turns left over where the lanes end are not an
    /// error.
    pub fn route(
        &self,
        lane: usize,
        s: f64,
        turns: &[Turn],
        max_len_m: f64,
    ) -> Result<Vec<[f64; 2]>, RouteError> {
        self.follow(lane, s, turns, max_len_m)
            .map(|(_, points)| points)
    }

    /// The lanes (indices into [`RoadMap::lanes`]) that [`RoadMap::route`] drives, in order,
    /// `lane` first.
    ///
    /// # Errors
    /// As [`RoadMap::route`].
    pub fn route_lanes(
        &self,
        lane: usize,
        s: f64,
        turns: &[Turn],
        max_len_m: f64,
    ) -> Result<Vec<usize>, RouteError> {
        self.follow(lane, s, turns, max_len_m)
            .map(|(lanes, _)| lanes)
    }

    /// [`RoadMap::route`]'s lanes and points: the start lane's stations ahead of `s`, then
    /// each next lane's, a next lane's first station left out where it is the join itself
    /// (within [`JOIN_SAME_M`] of the last point, or behind it).
    fn follow(
        &self,
        lane: usize,
        s: f64,
        turns: &[Turn],
        max_len_m: f64,
    ) -> Result<(Vec<usize>, Vec<[f64; 2]>), RouteError> {
        let l = &self.lanes[lane];
        let mut points = vec![l.pose(s).0];
        let ahead =
            l.s.iter()
                .zip(&l.centre)
                .filter(|(x, _)| if l.forward { **x > s } else { **x < s })
                .map(|(_, p)| *p);
        if l.forward {
            points.extend(ahead);
        } else {
            let mut back: Vec<[f64; 2]> = ahead.collect();
            back.reverse();
            points.extend(back);
        }
        let mut length: f64 = points
            .windows(2)
            .map(|w| (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]))
            .sum();
        let mut turns = turns.iter().enumerate();
        let mut lanes = vec![lane];
        let mut at = lane;
        while length < max_len_m && lanes.len() <= 10_000 {
            let next = &self.lanes[at].successors;
            let pick = match next.len() {
                0 => break,
                1 => next[0],
                _ => {
                    let wanted = turns.next();
                    self.choose(at, wanted.map(|(_, &t)| t))
                        .map_err(|e| RouteError {
                            number: wanted.map_or(0, |(k, _)| k + 1),
                            ..e
                        })?
                }
            };
            for (i, q) in self.lanes[pick].travel_points().into_iter().enumerate() {
                let last = *points.last().expect("non-empty");
                let d = (q[0] - last[0]).hypot(q[1] - last[1]);
                // Where two lanes join, the next lane's first station lies on the last one's
                // end up to the link's gap (a fraction of a millimetre on most maps, once
                // rounded to f32): one within a centimetre, or one behind the way the path
                // goes, is the same place, and a leg to it would turn the path back on itself
                // for an instant (a car's heading follows its path's legs).
                let behind = i == 0 && points.len() >= 2 && {
                    let prev = points[points.len() - 2];
                    let dir = [last[0] - prev[0], last[1] - prev[1]];
                    (q[0] - last[0]) * dir[0] + (q[1] - last[1]) * dir[1] < 0.0
                };
                let same = if i == 0 {
                    d <= JOIN_SAME_M || behind
                } else {
                    d <= 1e-6
                };
                if !same {
                    length += d;
                    points.push(q);
                }
            }
            lanes.push(pick);
            at = pick;
        }
        if points.len() < 2 {
            let (p, h) = l.pose(s);
            points.push([p[0] + h.cos() * 0.5, p[1] - h.sin() * 0.5]);
        }
        Ok((lanes, points))
    }

    /// Every lane's strip as triangles: vertices (world `[x, z]` m, the left and right
    /// border at each kept station) and index triples, two triangles per pair of kept
    /// stations. Stations are kept as [`strip_stations`] picks them: a straight lane of
    /// constant width is a few long quads rather than one per 0.5 m step, which keeps the
    /// collision mesh's tree (every wheel casts a ray into it every step) and the render
    /// mesh small; each border departs from the sampled one by at most
    /// [`STRIP_CHORD_TOL_M`].
    pub fn strip_triangles(&self) -> (Vec<[f64; 2]>, Vec<[u32; 3]>) {
        let (mut vertices, mut indices) = (Vec::new(), Vec::new());
        for l in &self.lanes {
            let base = vertices.len() as u32;
            let borders: Vec<[[f64; 2]; 2]> = (0..l.s.len())
                .map(|i| {
                    let r = l.right(i);
                    let h = l.width[i] / 2.0;
                    let c = l.centre[i];
                    [
                        [c[0] - h * r[0], c[1] - h * r[1]],
                        [c[0] + h * r[0], c[1] + h * r[1]],
                    ]
                })
                .collect();
            let kept = strip_stations(&borders);
            for &i in &kept {
                vertices.extend(borders[i]);
            }
            for i in 0..kept.len() as u32 - 1 {
                let (a, b, c, d) = (
                    base + 2 * i,
                    base + 2 * i + 1,
                    base + 2 * i + 2,
                    base + 2 * i + 3,
                );
                indices.push([a, c, b]);
                indices.push([b, c, d]);
            }
        }
        (vertices, indices)
    }

    /// Whether the world point `[x, z]` lies on a drivable lane (a linear scan: for checks
    /// at load; [`MapIndex`] answers the per-step queries).
    pub fn on_driving_surface(&self, p: [f64; 2]) -> bool {
        self.lanes
            .iter()
            .filter(|l| l.drivable)
            .any(|l| (0..l.s.len() - 1).any(|i| strip_offset(l, i, p).is_some()))
    }

    /// Distance from the world point `[x, z]` to the nearest lane strip, m (0 on one).
    pub fn distance_m(&self, p: [f64; 2]) -> f64 {
        let mut best = f64::INFINITY;
        for l in &self.lanes {
            for i in 0..l.s.len() - 1 {
                let (d, _, _) = segment_projection(p, l.centre[i], l.centre[i + 1]);
                let w = l.width[i].max(l.width[i + 1]) / 2.0;
                best = best.min((d - w).max(0.0));
            }
        }
        best
    }
}

/// The distance from `p` to segment `a b`, the signed lateral offset (positive to the right
/// of `a → b`) and the unclamped fraction along it.
fn segment_projection(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> (f64, f64, f64) {
    let d = [b[0] - a[0], b[1] - a[1]];
    let rel = [p[0] - a[0], p[1] - a[1]];
    let len2 = d[0] * d[0] + d[1] * d[1];
    if len2 == 0.0 {
        return (rel[0].hypot(rel[1]), 0.0, 0.0);
    }
    let raw = (rel[0] * d[0] + rel[1] * d[1]) / len2;
    let u = raw.clamp(0.0, 1.0);
    let e = [rel[0] - u * d[0], rel[1] - u * d[1]];
    let lateral = (rel[1] * d[0] - rel[0] * d[1]) / len2.sqrt();
    (e[0].hypot(e[1]), lateral, raw)
}

/// Whether `p` lies on segment `i` of lane `l`'s strip: its lateral offset from the centre
/// line if so. Between two segments of one lane the joint is covered by a disc of the
/// lane's half width; past the lane's first and last station nothing is, not even such a
/// disc (stations 0.5 m apart on a lane 3.5 m wide put a point 1 m past a dead end inside the
/// disc of the joint before the last, and a vehicle there read as on the road). A segment of
/// zero length holds nothing.
fn strip_offset(l: &MapLane, i: usize, p: [f64; 2]) -> Option<f64> {
    let (a, b) = (l.centre[i], l.centre[i + 1]);
    if same_station(a, b) {
        return None;
    }
    // `segment_projection` with the distance compared squared: every wheel of every car asks
    // this every step, and `hypot` was most of its cost.
    let dir = [b[0] - a[0], b[1] - a[1]];
    let rel = [p[0] - a[0], p[1] - a[1]];
    let len2 = dir[0] * dir[0] + dir[1] * dir[1];
    let raw = (rel[0] * dir[0] + rel[1] * dir[1]) / len2;
    let u = raw.clamp(0.0, 1.0);
    let e = [rel[0] - u * dir[0], rel[1] - u * dir[1]];
    let w = l.width[i] + u * (l.width[i + 1] - l.width[i]);
    if !(e[0] * e[0] + e[1] * e[1] <= (w / 2.0) * (w / 2.0) && w > 0.0) {
        return None;
    }
    let lateral = (rel[1] * dir[0] - rel[0] * dir[1]) / len2.sqrt();
    // Beside the segment, the point is between the lane's ends. Before it (after it), in the
    // disc around its first (last) station, it may not be: it is beyond the lane's start (end)
    // when it lies before the line across the lane's first (last) segment and is within the
    // lane's width of that end. The distance keeps a lane that turns almost full circle, whose
    // end looks back at its start, from losing the points near its start.
    let near = |x: [f64; 2]| (x[0] - p[0]).hypot(x[1] - p[1]) <= w;
    let beyond = if raw < 0.0 {
        near(l.centre[0]) && beyond_ends(l, p).0
    } else if raw > 1.0 {
        near(l.centre[l.centre.len() - 1]) && beyond_ends(l, p).1
    } else {
        false
    };
    (!beyond).then_some(lateral)
}

/// Stations closer than a micrometre are one.
fn same_station(a: [f64; 2], b: [f64; 2]) -> bool {
    (a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) < 1e-12
}

/// Whether `p` lies before the line across lane `l` at its first station, and whether past
/// the line across it at its last (each across the segment that ends there).
fn beyond_ends(l: &MapLane, p: [f64; 2]) -> (bool, bool) {
    let c = &l.centre;
    let (start, end) = (c[0], c[c.len() - 1]);
    let past_end = c
        .iter()
        .rev()
        .find(|&&x| !same_station(x, end))
        .is_some_and(|&x| segment_projection(p, x, end).2 > 1.0);
    let before_start = c
        .iter()
        .find(|&&x| !same_station(x, start))
        .is_some_and(|&x| segment_projection(p, start, x).2 < 0.0);
    (before_start, past_end)
}

/// Point queries on a map: R-trees of the lanes' centre-line segments and of the driving
/// surface's edges, built once per map ([`MapRef::index`]) and shared.
#[derive(Debug)]
pub struct MapIndex {
    map: Arc<RoadMap>,
    trees: Arc<MapTrees>,
    /// The centre-line segments that last held a point ([`MapIndex::on_any_lane`]), packed
    /// `lane << 32 | segment` (`u64::MAX`: none), tried before the tree: a wheel stays on one
    /// strip for many steps. Only a shortcut to the same answer.
    recent: [std::sync::atomic::AtomicU64; RECENT_HITS],
}

/// How many recent hits a [`MapIndex`] keeps: one per wheel and a few more.
const RECENT_HITS: usize = 8;

impl Clone for MapIndex {
    fn clone(&self) -> Self {
        MapIndex {
            map: self.map.clone(),
            trees: self.trees.clone(),
            recent: no_recent_hits(),
        }
    }
}

/// Most a border of [`RoadMap::strip_triangles`] departs from the lane's sampled border, m
/// (the 1 cm of a curved piece's slices).
pub const STRIP_CHORD_TOL_M: f64 = 0.01;

/// Most stations one quad of [`RoadMap::strip_triangles`] spans (8 m at the 0.5 m step), so
/// that its triangles' boxes stay tight for the collision tree.
const STRIP_MAX_RUN: usize = 16;

/// The stations of a lane strip, given its `[left, right]` border points at each sampled
/// station, that [`RoadMap::strip_triangles`] keeps: the first, the last, and greedily the
/// farthest next one such that every skipped station's border points lie within
/// [`STRIP_CHORD_TOL_M`] of the chords between the kept ones (at most [`STRIP_MAX_RUN`]
/// stations apart).
fn strip_stations(borders: &[[[f64; 2]; 2]]) -> Vec<usize> {
    let n = borders.len();
    let mut kept = vec![0];
    let mut from = 0;
    while from + 1 < n {
        let mut to = from + 1;
        let limit = (from + STRIP_MAX_RUN).min(n - 1);
        while to < limit {
            let next = to + 1;
            let fits = (from + 1..next).all(|m| {
                (0..2).all(|side| {
                    segment_projection(borders[m][side], borders[from][side], borders[next][side]).0
                        <= STRIP_CHORD_TOL_M
                })
            });
            if !fits {
                break;
            }
            to = next;
        }
        kept.push(to);
        from = to;
    }
    kept
}

fn no_recent_hits() -> [std::sync::atomic::AtomicU64; RECENT_HITS] {
    std::array::from_fn(|_| std::sync::atomic::AtomicU64::new(u64::MAX))
}

/// The drivable lanes of a map in a tree of their own, for [`MapTrees::new`]'s probes of the
/// edges of the driving surface: only drivable lanes answer, and the reach is half the widest
/// drivable lane, not the widest lane of any kind (a 6 m verge would triple the search).
struct DrivableLanes<'a> {
    lanes: &'a [MapLane],
    tree: super::centre_tree::CentreTree,
    reach_2: f64,
}

impl<'a> DrivableLanes<'a> {
    fn new(lanes: &'a [MapLane]) -> Self {
        let widest = lanes
            .iter()
            .filter(|l| l.drivable && l.s.len() > 1)
            .flat_map(|l| l.width.iter())
            .fold(0.0f64, |w, &x| w.max(x));
        let r = widest / 2.0 + 1e-9;
        DrivableLanes {
            lanes,
            tree: super::centre_tree::CentreTree::new(lanes, |k| lanes[k].drivable),
            reach_2: r * r,
        }
    }

    /// Whether a drivable lane other than `except` holds `p` (its strip, [`strip_offset`]):
    /// the segment `last` and its two neighbours first, then the tree, whose hit becomes
    /// `last`. The same answer as a search of every lane's segments.
    fn hold(&self, p: [f64; 2], except: usize, last: &mut Option<(usize, usize)>) -> bool {
        if let Some((k, i)) = *last {
            let lane = &self.lanes[k];
            let near = i.saturating_sub(1)..(i + 2).min(lane.centre.len() - 1);
            if near.into_iter().any(|j| strip_offset(lane, j, p).is_some()) {
                return true;
            }
        }
        let hit = self
            .tree
            .within(self.lanes, p, self.reach_2)
            .find(|&(k, i)| k != except && strip_offset(&self.lanes[k], i, p).is_some());
        if hit.is_some() {
            *last = hit;
        }
        hit.is_some()
    }
}

/// The R-trees of a [`MapIndex`], derived from its map alone and shared by every index of
/// that map ([`MapRef::index`]).
#[derive(Debug)]
pub struct MapTrees {
    centres: super::centre_tree::CentreTree,
    edges: RTree<GeomWithData<Line<[f64; 2]>, ()>>,
    widest_m: f64,
}

impl MapIndex {
    /// Indexes `map`, building its trees ([`MapRef::index`] shares them between tests).
    pub fn new(map: Arc<RoadMap>) -> MapIndex {
        MapIndex {
            trees: Arc::new(MapTrees::new(&map)),
            map,
            recent: no_recent_hits(),
        }
    }
}

impl MapTrees {
    /// The trees of `map`. The edges of the driving surface are the borders of drivable lanes
    /// with no drivable lane beyond them (probed 0.2 m outside), and the ends of drivable
    /// lanes that nothing continues.
    fn new(map: &Arc<RoadMap>) -> MapTrees {
        let widest = map
            .lanes
            .iter()
            .filter(|l| l.s.len() > 1)
            .flat_map(|l| l.width.iter())
            .fold(0.0f64, |w, &x| w.max(x));
        let drivable = DrivableLanes::new(&map.lanes);
        let mut has_predecessor = vec![false; map.lanes.len()];
        for l in &map.lanes {
            for &n in &l.successors {
                has_predecessor[n] = true;
            }
        }
        let mut edges = Vec::new();
        for (k, l) in map.lanes.iter().enumerate().filter(|(_, l)| l.drivable) {
            let n = l.s.len();
            let normal = |i: usize| {
                let (a, b) = (l.centre[i.min(n - 2)], l.centre[(i + 1).min(n - 1).max(1)]);
                let d = [b[0] - a[0], b[1] - a[1]];
                let len = d[0].hypot(d[1]).max(1e-12);
                // Right of a → b: (-d_z, d_x).
                [-d[1] / len, d[0] / len]
            };
            for side in [1.0, -1.0] {
                let border = |i: usize, extra: f64| {
                    let r = normal(i);
                    let t = side * (l.width[i] / 2.0 + extra);
                    [l.centre[i][0] + t * r[0], l.centre[i][1] + t * r[1]]
                };
                // The segment that last held a probe is tried first, with its neighbours:
                // along a border the next probe is almost always on the same neighbour lane.
                let mut last: Option<(usize, usize)> = None;
                let closed: Vec<bool> = (0..n)
                    .map(|i| !drivable.hold(border(i, 0.2), k, &mut last))
                    .collect();
                for i in 0..n - 1 {
                    if closed[i] || closed[i + 1] {
                        edges.push(GeomWithData::new(
                            Line::new(border(i, 0.0), border(i + 1, 0.0)),
                            (),
                        ));
                    }
                }
            }
            let (start_open, end_open) = if l.forward {
                (has_predecessor[k], !l.successors.is_empty())
            } else {
                (!l.successors.is_empty(), has_predecessor[k])
            };
            for (i, open) in [(0, start_open), (n - 1, end_open)] {
                if !open {
                    let r = normal(i);
                    let h = l.width[i] / 2.0;
                    let c = l.centre[i];
                    edges.push(GeomWithData::new(
                        Line::new(
                            [c[0] - h * r[0], c[1] - h * r[1]],
                            [c[0] + h * r[0], c[1] + h * r[1]],
                        ),
                        (),
                    ));
                }
            }
        }
        MapTrees {
            centres: super::centre_tree::CentreTree::new(&map.lanes, |_| true),
            edges: RTree::bulk_load(edges),
            widest_m: widest,
        }
    }
}

impl MapIndex {
    /// Whether `other` reads the very same trees (one map's shared cache).
    pub fn shares_trees_with(&self, other: &MapIndex) -> bool {
        Arc::ptr_eq(&self.trees, &other.trees)
    }

    /// The map.
    pub fn map(&self) -> &RoadMap {
        &self.map
    }

    /// The lanes whose strips hold `p`, with `p`'s lateral offset from their centre line
    /// (m, positive to the right of increasing `s`).
    fn strips_at(&self, p: [f64; 2]) -> impl Iterator<Item = (usize, usize, f64)> + '_ {
        self.segments_near(p)
            .filter_map(move |(k, i)| strip_offset(&self.map.lanes[k], i, p).map(|t| (k, i, t)))
    }

    /// The centre-line segments `(lane, i)` (stations `i`, `i + 1`) within half the widest
    /// lane's width of `p`: every segment whose strip may hold it, in no particular order.
    fn segments_near(&self, p: [f64; 2]) -> impl Iterator<Item = (usize, usize)> + '_ {
        let r = self.trees.widest_m / 2.0 + 1e-9;
        self.trees.centres.within(&self.map.lanes, p, r * r)
    }

    /// The lanes (indices into [`RoadMap::lanes`]) whose strips hold the world point `[x, z]`
    /// (m), each with the station `i` of the segment (stations `i`, `i + 1`) that holds it and
    /// the point's lateral offset from the centre line (m, positive to the right of
    /// increasing `s`), nearest centre first, one segment a lane.
    pub fn lanes_at(&self, p: [f64; 2]) -> Vec<(usize, usize, f64)> {
        let mut out: Vec<(usize, usize, f64)> = self.strips_at(p).collect();
        out.sort_by(|a, b| {
            a.2.abs()
                .total_cmp(&b.2.abs())
                .then(a.0.cmp(&b.0))
                .then(a.1.cmp(&b.1))
        });
        let mut seen = std::collections::BTreeSet::new();
        out.retain(|x| seen.insert(x.0));
        out
    }

    /// The first of [`MapIndex::lanes_at`]: the lane whose strip holds `[x, z]` (m) with the
    /// nearest centre line (ties to the lower lane, then station), its station `i` and the
    /// point's offset (m); `None` on no lane. Without gathering and sorting the others.
    pub fn nearest_lane_at(&self, p: [f64; 2]) -> Option<(usize, usize, f64)> {
        self.strips_at(p).min_by(|a, b| {
            a.2.abs()
                .total_cmp(&b.2.abs())
                .then(a.0.cmp(&b.0))
                .then(a.1.cmp(&b.1))
        })
    }

    /// Whether the world point `[x, z]` lies on any lane of the map (driving or not).
    pub fn on_any_lane(&self, p: [f64; 2]) -> bool {
        self.held(p, |_| true)
    }

    /// Whether a lane that `wanted` accepts (by index) holds `p`: the recent hits first,
    /// then the tree, whose hit becomes the newest recent one. The same answer as a search
    /// of the tree alone.
    fn held(&self, p: [f64; 2], wanted: impl Fn(usize) -> bool) -> bool {
        use std::sync::atomic::Ordering::Relaxed;
        let holds =
            |(k, i): (usize, usize)| wanted(k) && strip_offset(&self.map.lanes[k], i, p).is_some();
        let unpack = |packed: u64| ((packed >> 32) as usize, (packed & 0xffff_ffff) as usize);
        let recent = self.recent.iter().map(|r| r.load(Relaxed));
        if recent.filter(|&r| r != u64::MAX).any(|r| holds(unpack(r))) {
            return true;
        }
        let hit = self.segments_near(p).find(|&seg| holds(seg));
        if let Some((k, i)) = hit {
            // The oldest slot goes: slots shift by one, the newest hit first.
            for j in (1..RECENT_HITS).rev() {
                self.recent[j].store(self.recent[j - 1].load(Relaxed), Relaxed);
            }
            self.recent[0].store(((k as u64) << 32) | i as u64, Relaxed);
        }
        hit.is_some()
    }

    /// Signed distance from the world point `[x, z]` to the edge of the map's driving
    /// surface, m: `> 0` on it, `<= 0` off it (see [`super::Surface::edge_distance_m`]).
    pub fn edge_distance_m(&self, p: [f64; 2]) -> f64 {
        let d = self
            .trees
            .edges
            .nearest_neighbor(p)
            .map_or(f64::INFINITY, |e| {
                let l = e.geom();
                segment_projection(p, l.from, l.to).0
            });
        if self.held(p, |k| self.map.lanes[k].drivable) {
            d
        } else {
            -d
        }
    }

    /// Each drivable lane's centre line in its direction of travel, world `[x, z]` m.
    pub fn lane_lines(&self) -> Vec<Vec<[f64; 2]>> {
        self.map
            .lanes
            .iter()
            .filter(|l| l.drivable)
            .map(MapLane::travel_points)
            .collect()
    }
}

#[cfg(test)]
impl MapLane {
    /// A forward driving lane of road 0 with the stations `s` (m), the centre line `centre`
    /// (world `[x, z]`, m, one point a station) and one width (m) all along, for tests.
    pub(crate) fn driving_for_tests(s: Vec<f64>, centre: Vec<[f64; 2]>, width_m: f64) -> MapLane {
        MapLane {
            road: 0,
            section: 0,
            od_id: -1,
            kind: "driving".into(),
            drivable: true,
            forward: true,
            width: vec![width_m; s.len()],
            t: vec![-width_m / 2.0; s.len()],
            s,
            centre,
            successors: Vec::new(),
        }
    }
}

#[cfg(test)]
mod strip_tests {
    use super::*;

    fn load(path: &str) -> Arc<RoadMap> {
        let path = format!("{}/../tests/data/maps/{path}", env!("CARGO_MANIFEST_DIR"));
        let text = std::fs::read_to_string(&path).unwrap();
        super::super::opendrive::import(&path, &text).unwrap().map
    }

    /// Distance from `p` to the polyline through `line`, m.
    fn to_polyline(p: [f64; 2], line: &[[f64; 2]]) -> f64 {
        line.windows(2)
            .map(|w| segment_projection(p, w[0], w[1]).0)
            .fold(f64::INFINITY, f64::min)
    }

    #[test]
    fn a_lanes_strip_keeps_its_borders_within_a_centimetre_with_far_fewer_quads() {
        for (file, most) in [
            ("esmini/straight_500m.xodr", 0.07),
            ("carla/Town07.xodr", 0.6),
        ] {
            let map = load(file);
            let (vertices, triangles) = map.strip_triangles();
            let stations: usize = map.lanes.iter().map(|l| l.s.len() - 1).sum();
            // Two triangles per kept step, and far fewer steps than stations (a straight lane
            // keeps one station in 16, the most one quad spans).
            assert!(triangles.len() % 2 == 0);
            let quads = triangles.len() / 2;
            assert!(
                (quads as f64) < most * stations as f64,
                "{file}: {quads} quads for {stations} steps"
            );
            // Every sampled border point lies within the tolerance of its kept border.
            let mut base = 0;
            for l in &map.lanes {
                let kept = strip_stations(
                    &(0..l.s.len())
                        .map(|i| {
                            let (r, h, c) = (l.right(i), l.width[i] / 2.0, l.centre[i]);
                            [
                                [c[0] - h * r[0], c[1] - h * r[1]],
                                [c[0] + h * r[0], c[1] + h * r[1]],
                            ]
                        })
                        .collect::<Vec<_>>(),
                );
                assert_eq!(kept[0], 0);
                assert_eq!(*kept.last().unwrap(), l.s.len() - 1);
                let sides: [Vec<[f64; 2]>; 2] = std::array::from_fn(|side| {
                    (0..kept.len())
                        .map(|k| vertices[base + 2 * k + side])
                        .collect()
                });
                for i in 0..l.s.len() {
                    let (r, h, c) = (l.right(i), l.width[i] / 2.0, l.centre[i]);
                    for (side, sign) in [(0, -1.0), (1, 1.0)] {
                        let p = [c[0] + sign * h * r[0], c[1] + sign * h * r[1]];
                        let d = to_polyline(p, &sides[side]);
                        assert!(d <= STRIP_CHORD_TOL_M + 1e-12, "{file}: {d} m off");
                    }
                }
                base += 2 * kept.len();
            }
            assert_eq!(base, vertices.len());
        }
    }
}

#[cfg(test)]
mod end_tangent_tests {
    use super::*;

    /// A lane along a circle of radius `r` (m) turning left by `turn` (rad), sampled every
    /// 0.5 m with a shorter last step, as the importer samples lanes.
    fn arc(r: f64, turn: f64) -> MapLane {
        let len = r * turn;
        let mut s: Vec<f64> = (0..)
            .map(|k| f64::from(k) * 0.5)
            .take_while(|&x| x < len)
            .collect();
        s.push(len);
        // Heading 0 along +x at the start, turning counter-clockwise seen from above (the
        // engine's z is to the right, so left is −z).
        let centre = s
            .iter()
            .map(|&x| [r * (x / r).sin(), -(r - r * (x / r).cos())])
            .collect();
        MapLane::driving_for_tests(s, centre, 3.5)
    }

    /// The heading at a bend's ends is its true tangent within 0.01°, where a one-sided
    /// difference would lag by about 0.25 m / R (1.4° at R = 10 m): a 100° turn reads +100°,
    /// not +99°; `pose` reads the same there (it lagged until 2026-11-30: esmini's `ltap-od`
    /// turned 0.0115 rad late at a junction's end).
    #[test]
    fn a_bends_end_heading_is_its_tangent() {
        for (r, deg) in [(10.0, 100.0_f64), (7.3, 90.0), (25.0, 45.0)] {
            let l = arc(r, deg.to_radians());
            let start = l.end_tangent(false).to_degrees();
            let end = l.end_tangent(true).to_degrees();
            assert!(start.abs() < 0.01, "r {r}: start {start}");
            assert!((end - deg).abs() < 0.01, "r {r}: end {end}, want {deg}");
            assert_eq!(format!("{:+.0}", end - start), format!("{deg:+.0}"));
            let (s0, s1) = l.s_range();
            let (at_start, at_end) = (l.pose(s0).1.to_degrees(), l.pose(s1).1.to_degrees());
            assert!(at_start.abs() < 0.01, "r {r}: pose at the start {at_start}");
            assert!(
                (at_end - deg).abs() < 0.01,
                "r {r}: pose at the end {at_end}"
            );
        }
    }
}

#[cfg(test)]
mod edge_probe_tests {
    use super::*;

    /// [`DrivableLanes::hold`], with its hint carried along each border as
    /// [`MapTrees::new`] carries it, answers as a search of every lane's segments within half
    /// the widest lane of any kind does (the search before drivable lanes had a tree of their
    /// own), at every probe of the edges of four maps (a motorway on a curve, a town with
    /// junctions, lanes whose widths and offsets vary, and junctions next to each other).
    #[test]
    fn the_edge_probes_answer_as_a_search_of_every_lane() {
        let mut probes = 0;
        let mut open = 0;
        for file in [
            "tests/data/xosc/alks/concrete_scenarios/road_networks/alks_road_left_radius_250m.xodr",
            "tests/data/maps/carla/Town07.xodr",
            "tests/data/maps/esmini/lane_width_and_offset.xodr",
            "tests/data/maps/esmini/multi_intersections.xodr",
        ] {
            let path = format!("{}/../{file}", env!("CARGO_MANIFEST_DIR"));
            let text = std::fs::read_to_string(&path).unwrap();
            let map = super::super::opendrive::import(&path, &text).unwrap().map;
            let drivable = DrivableLanes::new(&map.lanes);
            let every = super::super::centre_tree::CentreTree::new(&map.lanes, |_| true);
            let widest = map
                .lanes
                .iter()
                .flat_map(|l| l.width.iter())
                .fold(0.0f64, |w, &x| w.max(x));
            let r = widest / 2.0 + 1e-9;
            let reference = |p: [f64; 2], except: usize| {
                every.within(&map.lanes, p, r * r).any(|(k, i)| {
                    k != except
                        && map.lanes[k].drivable
                        && strip_offset(&map.lanes[k], i, p).is_some()
                })
            };
            for (k, l) in map.lanes.iter().enumerate().filter(|(_, l)| l.drivable) {
                let n = l.s.len();
                for side in [1.0, -1.0] {
                    let mut last = None;
                    for i in 0..n - 1 {
                        let (a, b) = (l.centre[i], l.centre[i + 1]);
                        let d = [b[0] - a[0], b[1] - a[1]];
                        let len = d[0].hypot(d[1]).max(1e-12);
                        let t = side * (l.width[i] / 2.0 + 0.2);
                        let p = [a[0] - t * d[1] / len, a[1] + t * d[0] / len];
                        let fast = drivable.hold(p, k, &mut last);
                        assert_eq!(fast, reference(p, k), "{file}: lane {k} station {i}");
                        probes += 1;
                        open += usize::from(fast);
                    }
                }
            }
        }
        // Both answers were met many times.
        assert!(
            open > 1000 && probes - open > 1000,
            "{open} open of {probes} probes"
        );
    }
}
