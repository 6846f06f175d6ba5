//! Road networks (paper §2, "More Complex Worlds"): road pieces, `connect`, the geometric and
//! topological checks, the lane graph that NPC cars route on, and `onLane`.
//!
//! Pieces live in groups that move rigidly. A fresh piece is its own group at the origin.
//! `connect(parent.port, child, child.port)` moves the child's whole group so that the two
//! ports coincide and face each other, then checks that no two pieces overlap. Connecting two
//! pieces of the same group (closing a loop) moves nothing and checks instead that the ports
//! already coincide.

mod build;
mod centre_tree;
#[cfg(test)]
pub(crate) use build::SEPARATE_ROAD;
mod curve;
mod geometry;
mod lanes;
mod map;
pub mod opendrive;
mod piece;
pub mod roads;
mod surface;

pub use curve::{Frame, RefLine, SampledLine, POLYLINE_STEP_M};
pub use geometry::{direction, wrap, Pose2};
pub(crate) use lanes::{heading_between, tangent_at};
#[cfg(test)]
pub(crate) use lanes::{heading_on_leg, vertex_tangents};
pub use lanes::{LanePath, RoadName, Turn, MIN_PATH_RADIUS_M};
pub use map::{LaneAtError, MapIndex, MapLane, MapRef, MapRoad, RoadMap, RouteError};
pub use piece::{
    Piece, PieceKind, PortGeometry, JUNCTION_APRON_M, LANE_WIDTH_M, MAX_EXTENT_M, MAX_TURN_RAD,
    MIN_CURVE_RADIUS_M, PORT_NAMES, SIDEWALK_WIDTH_M,
};
pub use surface::{Surface, GROUND_FRICTION, GROUND_MARGIN_M, GROUND_TOP_M};

use rapier3d::parry::bounding_volume::BoundingVolume;
use rapier3d::parry::query::intersection_test;
use rapier3d::parry::shape::{Cuboid, SharedShape};
use rapier3d::prelude::{Pose, Rotation, Vector};
use serde::{Deserialize, Serialize};

use crate::EngineError;

/// Height of the sidewalks and of a roundabout's island above the road surface, in metres.
pub const CURB_HEIGHT_M: f64 = 0.15;
/// How far apart two ports may be and still count as coinciding, in metres.
pub const PORT_TOLERANCE_M: f64 = 0.01;
/// How far from opposite two coinciding ports may face, in rad.
pub const PORT_TOLERANCE_RAD: f64 = 1e-3;
/// Pieces are shrunk by this much, in metres, before the overlap test, so that pieces that
/// merely touch along a shared edge do not count as overlapping.
const TOUCH_MARGIN_M: f64 = 0.05;

/// A place across a road segment (paper §2, `onLane`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Lane {
    /// A driving lane: `1..=n/2` right of the centre line driving along the segment's `+x`,
    /// `-1..=-n/2` left of it driving along `-x`. Lane `±1` is next to the centre line.
    Driving(i32),
    /// The sidewalk on the right (`+z`) side: the paper's `r.SideWalk`.
    SideWalk,
    /// The sidewalk on the left (`-z`) side: the paper's `-r.SideWalk`.
    OppositeSideWalk,
}

/// Index of a piece in its [`Network`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct PieceId(pub usize);

/// A resolved `onLane(lane, at)`: a world position and the direction of travel there.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Location {
    /// Surface point `[x, y, z]` in metres (`y` is 0 on the road, the curb on a sidewalk).
    pub pos_m: [f64; 3],
    /// Direction of travel of the lane in rad (for sidewalks, the segment's heading).
    pub heading_rad: f64,
    /// The segment.
    pub piece: PieceId,
    /// The lane.
    pub lane: Lane,
    /// Distance along the segment from its port `ONE`, in metres; in a junction, along the
    /// lane path from where it enters.
    pub at_m: f64,
    /// In a junction or roundabout: the lane path it is on, `(entry port, exit port)`;
    /// `None` on a segment.
    pub through: Option<(usize, usize)>,
    /// On an OpenDRIVE map: the lane, an index into [`RoadMap::lanes`]; `None` elsewhere.
    #[serde(default)]
    pub map_lane: Option<usize>,
}

/// Two connected ports: `(piece, port index)` each.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Link {
    /// The parent side.
    pub a: (PieceId, usize),
    /// The child side.
    pub b: (PieceId, usize),
}

/// A set of road pieces and their connections.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Network {
    pieces: Vec<Piece>,
    group: Vec<usize>,
    links: Vec<Link>,
}

impl Network {
    /// An empty network.
    pub fn new() -> Self {
        Network::default()
    }

    /// A network of one straight segment at the origin.
    ///
    /// # Errors
    /// As [`Network::add`].
    pub fn single_segment(length_m: f64, lanes: u32, friction: f64) -> Result<Self, EngineError> {
        let mut n = Network::new();
        n.add(
            "RoadSegment",
            PieceKind::Segment {
                length_m,
                lanes,
                friction,
            },
        )?;
        Ok(n)
    }

    /// Adds a piece at the origin, in a group of its own.
    ///
    /// # Errors
    /// [`EngineError::InvalidWorld`] when the piece's sizes are invalid.
    pub fn add(&mut self, name: &str, kind: PieceKind) -> Result<PieceId, EngineError> {
        kind.validate()?;
        let id = self.pieces.len();
        self.pieces.push(Piece {
            name: name.to_owned(),
            kind,
            pose: Pose2::default(),
        });
        self.group.push(id);
        Ok(PieceId(id))
    }

    /// Adds every road of an OpenDRIVE map as one piece, where the map puts it, with tyre–road
    /// friction `friction` on all its lanes.
    ///
    /// # Errors
    /// [`EngineError::InvalidWorld`] for a friction outside `(0, 2]`.
    pub fn add_map(
        &mut self,
        name: &str,
        map: std::sync::Arc<RoadMap>,
        friction: f64,
    ) -> Result<PieceId, EngineError> {
        self.add(
            name,
            PieceKind::Map {
                map: MapRef::new(map),
                friction,
            },
        )
    }

    /// `m.onLane(road=, lane=, s=)` on an OpenDRIVE map: the centre of lane `lane` (its
    /// `<lane id>`) of road `road` (its `<road id>`) at `s_m` metres along the road's
    /// reference line, heading in the lane's direction of travel.
    ///
    /// # Errors
    /// [`EngineError::InvalidWorld`] when `piece` is no map, or as [`RoadMap::lane_at`].
    pub fn on_map_lane(
        &self,
        piece: PieceId,
        road: &str,
        lane: i32,
        s_m: f64,
    ) -> Result<Location, EngineError> {
        let p = &self.pieces[piece.0];
        let PieceKind::Map { map, .. } = &p.kind else {
            return Err(EngineError::InvalidWorld(format!(
                "onLane(road=, lane=, s=) is for an OpenDrive map; {} is a {}",
                p.name,
                p.kind.type_name()
            )));
        };
        let k = map
            .0
            .lane_at(road, lane, s_m)
            .map_err(|e| EngineError::InvalidWorld(e.to_string()))?;
        let l = &map.0.lanes[k];
        let (q, heading_rad) = l.pose(s_m);
        let [x, z] = p.pose.apply(q);
        Ok(Location {
            pos_m: [x, 0.0, z],
            heading_rad: wrap(heading_rad + p.pose.heading_rad),
            piece,
            lane: if l.drivable {
                Lane::Driving(lane)
            } else if lane < 0 {
                Lane::SideWalk
            } else {
                Lane::OppositeSideWalk
            },
            at_m: s_m,
            through: None,
            map_lane: Some(k),
        })
    }

    /// Sets the friction of piece `id` (a test case's value for an open friction stream).
    ///
    /// # Errors
    /// [`EngineError::InvalidWorld`] for a friction outside `(0, 2]`.
    pub fn set_friction(&mut self, id: PieceId, friction: f64) -> Result<(), EngineError> {
        let kind = self.pieces[id.0].kind.with_friction(friction);
        kind.validate()?;
        self.pieces[id.0].kind = kind;
        Ok(())
    }

    /// The pieces, by [`PieceId`].
    pub fn pieces(&self) -> &[Piece] {
        &self.pieces
    }

    /// The connections.
    pub fn links(&self) -> &[Link] {
        &self.links
    }

    /// The piece `id`.
    pub fn piece(&self, id: PieceId) -> &Piece {
        &self.pieces[id.0]
    }

    /// The pieces of the group that `id` belongs to (`id` and everything connected to it).
    pub fn group_of(&self, id: PieceId) -> Vec<PieceId> {
        let g = self.group[id.0];
        (0..self.pieces.len())
            .filter(|&i| self.group[i] == g)
            .map(PieceId)
            .collect()
    }

    /// A port as messages name it: its piece's name and the port's (`RoadSegment r.TWO`).
    pub fn port_name(&self, (piece, port): (PieceId, usize)) -> String {
        format!("{}.{}", self.pieces[piece.0].name, PORT_NAMES[port])
    }

    fn port(&self, piece: PieceId, port: usize) -> Result<PortGeometry, EngineError> {
        let p = &self.pieces[piece.0];
        p.port(port).ok_or_else(|| {
            let names = PORT_NAMES[..p.kind.ports().len()].join(", ");
            EngineError::InvalidWorld(format!(
                "{} has ports {names}; it has no port {}",
                p.name,
                PORT_NAMES.get(port).copied().unwrap_or("?")
            ))
        })
    }

    /// `parent.connect((port, child, child_port))`: joins `child`'s port to `parent`'s.
    ///
    /// # Errors
    /// [`EngineError::InvalidWorld`] for a port the piece lacks or one already connected, a
    /// lane-count mismatch, ports of one group that do not coincide, or pieces that would
    /// overlap. Nothing moves when it fails.
    pub fn connect(
        &mut self,
        parent: PieceId,
        port: usize,
        child: PieceId,
        child_port: usize,
    ) -> Result<(), EngineError> {
        let bad = |m: String| Err(EngineError::InvalidWorld(m));
        for id in [parent, child] {
            if let PieceKind::Map { .. } = self.pieces[id.0].kind {
                return bad(format!(
                    "{} is an OpenDRIVE map: its roads are linked by the map, and connect cannot join other pieces to it",
                    self.pieces[id.0].name
                ));
            }
        }
        let pp = self.port(parent, port)?;
        let cp = self.port(child, child_port)?;
        let (a, b) = ((parent, port), (child, child_port));
        if parent == child {
            return bad(format!(
                "{} cannot connect to itself",
                self.pieces[parent.0].name
            ));
        }
        for end in [a, b] {
            if self.links.iter().any(|l| l.a == end || l.b == end) {
                return bad(format!("port {} is already connected", self.port_name(end)));
            }
        }
        let (pk, ck) = (&self.pieces[parent.0].kind, &self.pieces[child.0].kind);
        if pk.lanes() != ck.lanes() {
            return bad(format!(
                "lane-count mismatch: {} has {} lanes but {} has {}",
                self.port_name(a),
                pk.lanes(),
                self.port_name(b),
                ck.lanes()
            ));
        }
        let target_heading = wrap(pp.heading_rad + std::f64::consts::PI);
        if self.group[parent.0] == self.group[child.0] {
            let gap = (pp.pos[0] - cp.pos[0]).hypot(pp.pos[1] - cp.pos[1]);
            let turn = wrap(cp.heading_rad - target_heading).abs();
            if gap > PORT_TOLERANCE_M || turn > PORT_TOLERANCE_RAD {
                return bad(format!(
                    "connection points do not coincide: {} is at ({:.2}, {:.2}) m facing {:.1}°, {} at ({:.2}, {:.2}) m facing {:.1}°",
                    self.port_name(a),
                    pp.pos[0],
                    pp.pos[1],
                    pp.heading_rad.to_degrees(),
                    self.port_name(b),
                    cp.pos[0],
                    cp.pos[1],
                    cp.heading_rad.to_degrees()
                ));
            }
            self.links.push(Link { a, b });
            return Ok(());
        }
        // Rotate the child's group about its port, then move that port onto the parent's.
        let delta = wrap(target_heading - cp.heading_rad);
        let rot = Pose2 {
            x: 0.0,
            z: 0.0,
            heading_rad: delta,
        };
        let [rx, rz] = rot.apply(cp.pos);
        let motion = Pose2 {
            x: pp.pos[0] - rx,
            z: pp.pos[1] - rz,
            heading_rad: delta,
        };
        let moved = self.group_of(child);
        let mut next = self.clone();
        for &PieceId(i) in &moved {
            next.pieces[i].pose = motion.compose(&self.pieces[i].pose);
        }
        let others = self.group_of(parent);
        next.check_overlaps(&moved, &others)?;
        let g = self.group[parent.0];
        for &PieceId(i) in &moved {
            next.group[i] = g;
        }
        next.links.push(Link { a, b });
        *self = next;
        Ok(())
    }

    /// Checks that no piece of `xs` overlaps a piece of `ys` (parry's intersection test on
    /// the footprints, shrunk by a few centimetres so shared edges do not count).
    ///
    /// # Errors
    /// [`EngineError::InvalidWorld`] naming the first overlapping pair.
    pub fn check_overlaps(&self, xs: &[PieceId], ys: &[PieceId]) -> Result<(), EngineError> {
        for &x in xs {
            for &y in ys {
                if x != y && self.overlap(x, y) {
                    return Err(EngineError::InvalidWorld(format!(
                        "road pieces overlap: {} and {}",
                        self.pieces[x.0].name, self.pieces[y.0].name
                    )));
                }
            }
        }
        Ok(())
    }

    /// Checks every pair of pieces for overlap (see [`Network::check_overlaps`]).
    ///
    /// # Errors
    /// [`EngineError::InvalidWorld`] naming the first overlapping pair.
    pub fn check_all_overlaps(&self) -> Result<(), EngineError> {
        match self.first_overlap() {
            Some((a, b)) => Err(EngineError::InvalidWorld(format!(
                "road pieces overlap: {} and {}",
                self.pieces[a.0].name, self.pieces[b.0].name
            ))),
            None => Ok(()),
        }
    }

    /// The first pair of pieces that overlap (in piece order; see
    /// [`Network::check_overlaps`]), if any.
    pub fn first_overlap(&self) -> Option<(PieceId, PieceId)> {
        (0..self.pieces.len()).find_map(|i| {
            (i + 1..self.pieces.len())
                .find(|&j| self.overlap(PieceId(i), PieceId(j)))
                .map(|j| (PieceId(i), PieceId(j)))
        })
    }

    /// The piece's footprint as convex parts in world coordinates, shrunk by
    /// [`TOUCH_MARGIN_M`] (a map's lanes are not): one box for a segment or junction; for an
    /// OpenDRIVE map, one prism per quad of each lane's strip ([`map::RoadMap::strip_triangles`]); for a curved piece, one
    /// quadrilateral prism per slice of at most 2 m, whose ends lie across the reference line
    /// (so the first and last end exactly at the ports).
    fn footprint_parts(&self, id: PieceId) -> Vec<(Pose, SharedShape)> {
        let p = &self.pieces[id.0];
        let shrink = |h: f64| (h - TOUCH_MARGIN_M).max(0.001);
        if let PieceKind::Map { map, .. } = &p.kind {
            // One quadrilateral prism per quad of each lane (the map's pose is the identity).
            let (vertices, triangles) = map.0.strip_triangles();
            return triangles
                .chunks(2)
                .filter_map(|pair| {
                    let corners: Vec<Vector> = pair
                        .iter()
                        .flatten()
                        .flat_map(|&v| {
                            let [x, z] = p.pose.apply(vertices[v as usize]);
                            [-0.5f32, 0.5].map(|y| Vector::new(x as f32, y, z as f32))
                        })
                        .collect();
                    SharedShape::convex_hull(&corners).map(|s| (Pose::identity(), s))
                })
                .collect();
        }
        if let Some(line) = p.kind.ref_line() {
            let w = shrink(p.kind.half_width_m());
            let mut frames = line.frames(2.0);
            let last = frames.len() - 1;
            // The ends pulled in along the line, so that pieces meeting at a port only touch.
            for (i, sign) in [(0, 1.0), (last, -1.0)] {
                let f = &mut frames[i];
                let along = [f.right[1], -f.right[0]];
                f.point = [
                    f.point[0] + sign * TOUCH_MARGIN_M * along[0],
                    f.point[1] + sign * TOUCH_MARGIN_M * along[1],
                ];
            }
            let mut parts = Vec::with_capacity(last);
            for pair in frames.windows(2) {
                let mut corners = Vec::with_capacity(8);
                for f in pair {
                    for t in [-w, w] {
                        let [x, z] = p.pose.apply(f.offset(t));
                        for y in [-0.5f32, 0.5] {
                            corners.push(Vector::new(x as f32, y, z as f32));
                        }
                    }
                }
                if let Some(shape) = SharedShape::convex_hull(&corners) {
                    parts.push((Pose::identity(), shape));
                }
            }
            return parts;
        }
        let ([hx, hz], centre) = p.kind.footprint();
        let [x, z] = p.pose.apply(centre);
        let pose = Pose::from_parts(
            Vector::new(x as f32, 0.0, z as f32),
            Rotation::from_rotation_y(p.pose.heading_rad as f32),
        );
        let cuboid = Cuboid::new(Vector::new(shrink(hx) as f32, 0.5, shrink(hz) as f32));
        vec![(pose, SharedShape::new(cuboid))]
    }

    fn overlap(&self, a: PieceId, b: PieceId) -> bool {
        let pa = self.footprint_parts(a);
        let pb = self.footprint_parts(b);
        // Bounding boxes first: a map has thousands of parts.
        let boxes = |parts: &[(Pose, SharedShape)]| {
            parts
                .iter()
                .map(|(x, s)| s.compute_aabb(x))
                .collect::<Vec<_>>()
        };
        let (ba, bb) = (boxes(&pa), boxes(&pb));
        pa.iter().zip(&ba).any(|((xa, sa), aa)| {
            pb.iter().zip(&bb).any(|((xb, sb), ab)| {
                aa.intersects(ab)
                    && intersection_test(xa, sa.as_ref(), xb, sb.as_ref())
                        .map_or(true, |i| i.intersecting)
            })
        })
    }

    /// `piece.onLane(lane, at)`: the point on `lane` of segment `piece`, `at_m` metres from its
    /// port `ONE`.
    ///
    /// # Errors
    /// [`EngineError::InvalidWorld`] if the piece is not a segment, for lane 0 or a lane
    /// beyond `±lanes/2`, or `at_m` outside `[0, len]`.
    pub fn on_lane(&self, piece: PieceId, lane: Lane, at_m: f64) -> Result<Location, EngineError> {
        let p = &self.pieces[piece.0];
        let (Some(length_m), lanes) = (p.kind.road_length_m(), p.kind.lanes()) else {
            return Err(EngineError::InvalidWorld(format!(
                "onLane(lane, at) needs a RoadSegment, Arc or Clothoid; {} is a {}",
                p.name,
                p.kind.type_name()
            )));
        };
        if !(0.0..=length_m).contains(&at_m) {
            return Err(EngineError::InvalidWorld(format!(
                "position {at_m} m is outside {} [0, {length_m}] m",
                p.name
            )));
        }
        let sidewalk_z = p.kind.half_road_m() + SIDEWALK_WIDTH_M / 2.0;
        let (z, y, reverse) = match lane {
            Lane::Driving(k) => {
                let half = (lanes / 2) as i32;
                if k == 0 || k.abs() > half {
                    return Err(EngineError::InvalidWorld(format!(
                        "lane {k} does not exist on {} with {lanes} lanes (lanes ±1..=±{half})",
                        p.name
                    )));
                }
                let z = (k.abs() as f64 - 0.5) * LANE_WIDTH_M * f64::from(k.signum());
                (z, 0.0, k < 0)
            }
            Lane::SideWalk => (sidewalk_z, CURB_HEIGHT_M, false),
            Lane::OppositeSideWalk => (-sidewalk_z, CURB_HEIGHT_M, false),
        };
        let (local, local_heading) = match p.kind.ref_line() {
            Some(line) => (line.offset(at_m, z), line.heading(at_m)),
            None => ([at_m, z], 0.0),
        };
        let [x, wz] = p.pose.apply(local);
        let heading = if reverse {
            wrap(p.pose.heading_rad + local_heading + std::f64::consts::PI)
        } else if local_heading == 0.0 {
            p.pose.heading_rad
        } else {
            wrap(p.pose.heading_rad + local_heading)
        };
        Ok(Location {
            pos_m: [x, y, wz],
            heading_rad: heading,
            piece,
            lane,
            at_m,
            through: None,
            map_lane: None,
        })
    }

    /// `j.onLane(port, turn, at, lane=1)` for a junction or roundabout: the point `at_m` metres
    /// along the lane path that enters through port `entry` in lane `lane` (`1..=nlanes/2`,
    /// counted from the centre line) and makes `turn`.
    ///
    /// # Errors
    /// [`EngineError::InvalidWorld`] for a segment (use [`Network::on_lane`]), a port the piece
    /// lacks, a turn it has no path for, a lane beyond `nlanes/2`, or `at_m` outside
    /// `[0, path length]`.
    pub fn on_junction_lane(
        &self,
        piece: PieceId,
        entry: usize,
        turn: Turn,
        lane: u32,
        at_m: f64,
    ) -> Result<Location, EngineError> {
        let p = &self.pieces[piece.0];
        let bad = |m: String| Err(EngineError::InvalidWorld(m));
        if p.kind.road_length_m().is_some() {
            return bad(format!(
                "{} is a {}: give onLane a lane number and a distance",
                p.name,
                p.kind.type_name()
            ));
        }
        let half = p.kind.lanes() / 2;
        if lane == 0 || lane > half {
            return bad(format!(
                "lane {lane} does not exist in {} with {} lanes (lanes 1..={half})",
                p.name,
                p.kind.lanes()
            ));
        }
        let Some(path) = self
            .lane_paths(piece)
            .into_iter()
            .find(|l| l.entry == (entry, lane) && l.turn == turn)
        else {
            return bad(format!(
                "{} has no \"{}\" turn from port {}",
                p.name,
                turn.name(),
                PORT_NAMES.get(entry).copied().unwrap_or("?")
            ));
        };
        let (point, heading, length) = lanes::along(&path.points, at_m);
        if !(0.0..=length).contains(&at_m) {
            return bad(format!(
                "position {at_m} m is outside the {length:.1} m path through {}",
                p.name
            ));
        }
        Ok(Location {
            pos_m: [point[0], 0.0, point[1]],
            heading_rad: heading,
            piece,
            lane: Lane::Driving(lane as i32),
            at_m,
            through: Some((path.entry.0, path.exit.0)),
            map_lane: None,
        })
    }

    /// The bounding box of every piece's footprint, world `([x_min, z_min], [x_max, z_max])`
    /// in metres (`([0, 0], [0, 0])` for an empty network; the origin is always inside).
    pub fn bounds_m(&self) -> ([f64; 2], [f64; 2]) {
        let (mut lo, mut hi) = ([0.0f64; 2], [0.0f64; 2]);
        for piece in &self.pieces {
            let ([hx, hz], [cx, cz]) = piece.kind.footprint();
            for (sx, sz) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                let [x, z] = piece.pose.apply([cx + sx * hx, cz + sz * hz]);
                lo = [lo[0].min(x), lo[1].min(z)];
                hi = [hi[0].max(x), hi[1].max(z)];
            }
        }
        (lo, hi)
    }

    /// Distance in metres from the world point `[x, z]` to the footprint of piece `id`
    /// (carriageway, sidewalks or plaza); `0` inside it.
    pub fn distance_to_piece_m(&self, id: PieceId, p: [f64; 2]) -> f64 {
        let piece = &self.pieces[id.0];
        let inv = Pose2 {
            x: 0.0,
            z: 0.0,
            heading_rad: -piece.pose.heading_rad,
        };
        let q = inv.apply([p[0] - piece.pose.x, p[1] - piece.pose.z]);
        if let PieceKind::Map { map, .. } = &piece.kind {
            return map.0.distance_m(q);
        }
        if let Some(line) = piece.kind.ref_line() {
            let (_, t, past) = SampledLine::new(&line).project(q);
            return past.hypot((t.abs() - piece.kind.half_width_m()).max(0.0));
        }
        let ([hx, hz], [cx, cz]) = piece.kind.footprint();
        let dx = ((q[0] - cx).abs() - hx).max(0.0);
        let dz = ((q[1] - cz).abs() - hz).max(0.0);
        dx.hypot(dz)
    }

    /// The piece whose driving surface contains the world point `[x, z]`, if any.
    pub fn driving_surface_at(&self, p: [f64; 2]) -> Option<PieceId> {
        self.pieces
            .iter()
            .position(|piece| {
                let inv = Pose2 {
                    x: 0.0,
                    z: 0.0,
                    heading_rad: -piece.pose.heading_rad,
                };
                let local = inv.apply([p[0] - piece.pose.x, p[1] - piece.pose.z]);
                piece.kind.on_driving_surface(local)
            })
            .map(PieceId)
    }
}

#[cfg(test)]
mod tests;
