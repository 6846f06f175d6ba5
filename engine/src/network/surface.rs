//! Where the road is, asked of a point: the piece under it (whose friction the tyres grip
//! with), whether it is on a driving surface and how far from that surface's edge, and how far
//! it is from the centre line of the nearest lane.
//!
//! The driving surface is the union of the pieces' driving regions: a segment's carriageway
//! (`[0, len] × [-nlanes·3.5/2, nlanes·3.5/2]` m in its frame, sidewalks excluded), a curved
//! piece's carriageway (points within `nlanes·3.5/2` m of its reference line, found by
//! projecting onto the line sampled every 25 cm), and a
//! junction's or roundabout's square plaza less a roundabout's island. Where two pieces are
//! connected the shared port edge is no edge of the union; an unconnected port is a dead end,
//! and its edge is.

use super::geometry::{direction, Pose2};
use super::{MapIndex, Network, PieceId, PieceKind, SampledLine, PORT_NAMES};
use std::sync::Arc;

/// Friction coefficient of the ground beside and beyond the road network (grass), used for a
/// wheel or a car on no road piece. Dry grass and earth are commonly given 0.35–0.55; 0.5 is
/// a middle value.
pub const GROUND_FRICTION: f64 = 0.5;

/// Height of the top of the ground plane, in metres: 2 cm below the road surface (`y = 0`),
/// as the camera draws it.
pub const GROUND_TOP_M: f64 = -0.02;

/// How far the ground reaches beyond the network's bounding box, in metres.
pub const GROUND_MARGIN_M: f64 = 2000.0;

#[derive(Debug, Clone)]
enum Shape {
    /// A carriageway from `x = 0` to `x = length_m`, `half_road_m` each side of the centre line.
    Segment { length_m: f64, half_road_m: f64 },
    /// A curved carriageway along a sampled reference line of length `length_m`,
    /// `half_road_m` each side of it; the footprint reaches `half_width_m` (sidewalks).
    Curve {
        line: SampledLine,
        length_m: f64,
        half_road_m: f64,
        half_width_m: f64,
    },
    /// An OpenDRIVE map's lanes (world coordinates: a map's pose is the identity).
    Map(Box<MapIndex>),
    /// A square plaza `[-half_m, half_m]²`; road openings `half_road_m` each side of a port's
    /// centre; an island of radius `island_m` at the centre of a roundabout.
    Plaza {
        half_m: f64,
        half_road_m: f64,
        island_m: Option<f64>,
    },
}

#[derive(Debug, Clone)]
struct PieceShape {
    pose: Pose2,
    /// `(sin, cos)` of the pose's heading, so a query needs no trigonometry.
    sin_cos: (f64, f64),
    shape: Shape,
    /// Half extents `[x, z]` and centre of the whole footprint (sidewalks included).
    footprint: ([f64; 2], [f64; 2]),
    friction: f64,
    /// Whether each port is connected to another piece.
    connected: [bool; 4],
}

/// How far beyond a piece's footprint [`Surface::lane_offset_m`] counts it as near, in
/// metres.
const NEAR_M: f64 = 2.0;

/// A uniform grid over the pieces' footprints: each cell lists, in network order, the pieces
/// whose footprint widened by [`NEAR_M`] may reach into it. A point query then tests the few
/// pieces of its cell instead of every piece of the network, with the same answer: a piece
/// whose widened footprint holds a point is always listed in the point's cell.
#[derive(Debug, Clone)]
struct PieceGrid {
    /// World `[x, z]` (m) of the grid's low corner.
    origin: [f64; 2],
    /// Side of a cell, m.
    cell_m: f64,
    /// Cells along `x` and along `z`.
    dims: [usize; 2],
    /// Cell `c`'s pieces are `pieces[starts[c]..starts[c + 1]]` (cells row-major, `z` rows).
    starts: Vec<usize>,
    pieces: Vec<usize>,
    /// Every piece, for a network of at most [`GRID_FROM`] pieces: testing them all is cheaper
    /// than finding the cell.
    all: Option<Vec<usize>>,
}

/// Networks of fewer pieces than this are not gridded.
const GRID_FROM: usize = 4;

/// Most cells a [`PieceGrid`] has; the cells grow for larger networks.
const MAX_CELLS: f64 = 4096.0;

impl PieceGrid {
    /// A grid of no cells: a query finds `all` (every piece), or nothing.
    fn without_cells(all: Option<Vec<usize>>) -> Self {
        PieceGrid {
            origin: [0.0; 2],
            cell_m: 1.0,
            dims: [0, 0],
            starts: vec![0],
            pieces: Vec::new(),
            all,
        }
    }

    /// The grid over `boxes`, each piece's world box `[min x, max x, min z, max z]` (m).
    fn new(boxes: &[[f64; 4]]) -> Self {
        if boxes.len() < GRID_FROM {
            // A query tests every piece, so no cells (a map's box would fill them all).
            return PieceGrid::without_cells(Some((0..boxes.len()).collect()));
        }
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for b in boxes {
            lo = [lo[0].min(b[0]), lo[1].min(b[2])];
            hi = [hi[0].max(b[1]), hi[1].max(b[3])];
        }
        if !(lo[0].is_finite() && lo[1].is_finite() && hi[0].is_finite() && hi[1].is_finite()) {
            return PieceGrid::without_cells(None);
        }
        let area = ((hi[0] - lo[0]) * (hi[1] - lo[1])).max(1.0);
        let cell_m = (area / MAX_CELLS).sqrt().max(5.0);
        let count = |span: f64| ((span / cell_m).floor() as usize).saturating_add(1);
        let mut grid = PieceGrid {
            origin: lo,
            cell_m,
            dims: [count(hi[0] - lo[0]), count(hi[1] - lo[1])],
            starts: Vec::new(),
            pieces: Vec::new(),
            all: None,
        };
        let mut cells = vec![Vec::new(); grid.dims[0] * grid.dims[1]];
        for (i, b) in boxes.iter().enumerate() {
            // The same index function as a query's, so that monotone rounding keeps every
            // point of the box within the cells it is listed in.
            let (Some(x0), Some(x1), Some(z0), Some(z1)) = (
                grid.index(b[0], 0),
                grid.index(b[1], 0),
                grid.index(b[2], 1),
                grid.index(b[3], 1),
            ) else {
                continue;
            };
            for z in z0..=z1 {
                for x in x0..=x1 {
                    cells[z * grid.dims[0] + x].push(i);
                }
            }
        }
        grid.starts.push(0);
        for c in cells {
            grid.pieces.extend(c);
            grid.starts.push(grid.pieces.len());
        }
        grid
    }

    /// The cell index along `axis` (0: `x`, 1: `z`) of coordinate `v`, `None` outside (or
    /// not a number). The conversion truncates, which is the floor for `k >= 0`.
    fn index(&self, v: f64, axis: usize) -> Option<usize> {
        let k = (v - self.origin[axis]) / self.cell_m;
        (k >= 0.0 && k < self.dims[axis] as f64).then_some(k as usize)
    }

    /// The pieces that may hold the world point `p` or lie within [`NEAR_M`] of it, in
    /// network order; none for a point off the grid (or not finite).
    fn near(&self, p: [f64; 2]) -> &[usize] {
        if let Some(all) = &self.all {
            return all;
        }
        match (self.index(p[0], 0), self.index(p[1], 1)) {
            (Some(x), Some(z)) => {
                let c = z * self.dims[0] + x;
                &self.pieces[self.starts[c]..self.starts[c + 1]]
            }
            _ => &[],
        }
    }
}

/// The world box `[min x, max x, min z, max z]` (m) of a piece's footprint widened by
/// [`NEAR_M`], and by far more than the rounding of [`PieceShape::local`].
fn near_box(piece: &PieceShape) -> [f64; 4] {
    let ([hx, hz], [cx, cz]) = piece.footprint;
    let (hx, hz) = (hx + NEAR_M, hz + NEAR_M);
    let mut b = [
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    ];
    for (dx, dz) in [(-hx, -hz), (-hx, hz), (hx, -hz), (hx, hz)] {
        let [x, z] = piece.pose.apply([cx + dx, cz + dz]);
        b = [b[0].min(x), b[1].max(x), b[2].min(z), b[3].max(z)];
    }
    let slack = 1e-6 + 1e-9 * b.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    [b[0] - slack, b[1] + slack, b[2] - slack, b[3] + slack]
}

/// Point queries on a [`Network`]'s surface, precomputed once per world.
#[derive(Debug, Clone)]
pub struct Surface {
    pieces: Vec<PieceShape>,
    /// Which pieces each part of the plane may concern.
    grid: PieceGrid,
    /// Each piece's lane centre lines: polylines in world `[x, z]` metres, in their direction
    /// of travel.
    lanes: Vec<Arc<Vec<Vec<[f64; 2]>>>>,
    /// For each lane line of `lanes`, the bounding box `[min x, max x, min z, max z]` (m) of
    /// each run of [`LEGS_PER_BOX`] legs: [`Surface::lane_offset_m`] skips a run whose box is
    /// farther than the nearest leg found so far.
    lane_boxes: Vec<Arc<Vec<Vec<[f64; 4]>>>>,
}

/// A piece's lane centre lines and their runs' boxes ([`Surface`]'s `lanes`, `lane_boxes`).
pub(crate) type LaneLines = (Arc<Vec<Vec<[f64; 2]>>>, Arc<Vec<Vec<[f64; 4]>>>);

/// `lines` with the boxes of their runs of legs.
pub(crate) fn lane_lines(lines: Vec<Vec<[f64; 2]>>) -> LaneLines {
    let boxes = lines.iter().map(|l| leg_boxes(l)).collect();
    (Arc::new(lines), Arc::new(boxes))
}

/// Legs of a lane line per bounding box of [`Surface`]'s `lane_boxes`.
const LEGS_PER_BOX: usize = 16;

/// The bounding boxes of `line`'s runs of [`LEGS_PER_BOX`] legs, widened by far more than the
/// rounding of a point–segment distance, so that a box's distance is a lower bound of the
/// distance [`segment_offset`] computes to any leg of its run.
fn leg_boxes(line: &[[f64; 2]]) -> Vec<[f64; 4]> {
    (0..line.len().saturating_sub(1))
        .step_by(LEGS_PER_BOX)
        .map(|start| {
            let run = &line[start..(start + LEGS_PER_BOX + 1).min(line.len())];
            let mut b = [
                f64::INFINITY,
                f64::NEG_INFINITY,
                f64::INFINITY,
                f64::NEG_INFINITY,
            ];
            for q in run {
                b = [
                    b[0].min(q[0]),
                    b[1].max(q[0]),
                    b[2].min(q[1]),
                    b[3].max(q[1]),
                ];
            }
            let slack = 1e-6 + 1e-9 * b.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            [b[0] - slack, b[1] + slack, b[2] - slack, b[3] + slack]
        })
        .collect()
}

/// The squared distance (m²) from `p` to the box `[min x, max x, min z, max z]`.
fn box_distance2(p: [f64; 2], b: &[f64; 4]) -> f64 {
    let dx = (b[0] - p[0]).max(p[0] - b[1]).max(0.0);
    let dz = (b[2] - p[1]).max(p[1] - b[3]).max(0.0);
    dx * dx + dz * dz
}

impl PieceShape {
    /// `p` in the piece's own frame.
    fn local(&self, p: [f64; 2]) -> [f64; 2] {
        let (s, c) = self.sin_cos;
        let (dx, dz) = (p[0] - self.pose.x, p[1] - self.pose.z);
        [dx * c - dz * s, dx * s + dz * c]
    }

    fn in_footprint(&self, q: [f64; 2], margin_m: f64) -> bool {
        let ([hx, hz], [cx, cz]) = self.footprint;
        let in_box = (q[0] - cx).abs() <= hx + margin_m && (q[1] - cz).abs() <= hz + margin_m;
        match &self.shape {
            Shape::Map(index) if in_box => index.on_any_lane(q),
            Shape::Curve {
                line, half_width_m, ..
            } if in_box => {
                let (_, t, past) = line.project(q);
                past <= margin_m && t.abs() <= half_width_m + margin_m
            }
            _ => in_box,
        }
    }

    /// Signed distance from local point `q` to the edge of this piece's driving region, in
    /// metres: `> 0` inside (ignoring connected port edges), `< 0` outside.
    fn signed_edge_m(&self, q: [f64; 2]) -> f64 {
        let [x, z] = q;
        match &self.shape {
            Shape::Map(index) => index.edge_distance_m(q),
            Shape::Curve {
                line,
                length_m,
                half_road_m,
                ..
            } => {
                let (at, t, past) = line.project(q);
                if past == 0.0 && t.abs() <= *half_road_m {
                    let mut d = half_road_m - t.abs();
                    if !self.connected[0] {
                        d = d.min(at);
                    }
                    if !self.connected[1] {
                        d = d.min(length_m - at);
                    }
                    d
                } else {
                    -past.hypot((t.abs() - half_road_m).max(0.0))
                }
            }
            _ => self.signed_edge_straight_m(x, z),
        }
    }

    /// [`PieceShape::signed_edge_m`] of a segment or plaza.
    fn signed_edge_straight_m(&self, x: f64, z: f64) -> f64 {
        match self.shape {
            Shape::Curve { .. } | Shape::Map(_) => {
                unreachable!("curves and maps are measured by projection")
            }
            Shape::Segment {
                length_m,
                half_road_m,
            } => {
                let inside = (0.0..=length_m).contains(&x) && z.abs() <= half_road_m;
                if inside {
                    let mut d = half_road_m - z.abs();
                    if !self.connected[0] {
                        d = d.min(x);
                    }
                    if !self.connected[1] {
                        d = d.min(length_m - x);
                    }
                    d
                } else {
                    let dx = (-x).max(x - length_m).max(0.0);
                    let dz = (z.abs() - half_road_m).max(0.0);
                    -dx.hypot(dz)
                }
            }
            Shape::Plaza {
                half_m,
                half_road_m,
                island_m,
            } => {
                let r = x.hypot(z);
                let in_square = x.abs() <= half_m && z.abs() <= half_m;
                if !in_square {
                    let dx = (x.abs() - half_m).max(0.0);
                    let dz = (z.abs() - half_m).max(0.0);
                    return -dx.hypot(dz);
                }
                if let Some(island) = island_m {
                    if r < island {
                        return -(island - r);
                    }
                }
                // Sides by port index: ONE east (x = +h), TWO south (z = +h), THREE west
                // (x = -h), FOUR north (z = -h); `(normal distance, coordinate along it)`.
                let sides = [
                    (half_m - x, z),
                    (half_m - z, x),
                    (half_m + x, z),
                    (half_m + z, x),
                ];
                let mut d = island_m.map_or(f64::INFINITY, |i| r - i);
                for (port, (n, u)) in sides.into_iter().enumerate() {
                    let along = if self.connected[port] {
                        // The edge is the side less the road's opening.
                        (half_road_m - u.abs()).max(0.0)
                    } else {
                        0.0
                    };
                    d = d.min(n.hypot(along));
                }
                d
            }
        }
    }
}

/// The squared distance from `p` to segment `a b` (m²), the signed lateral offset of `p` from
/// the line through them (m, positive to the right of the direction `a → b`), and that
/// direction, not normalised.
fn segment_offset(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> (f64, f64, [f64; 2]) {
    let d = [b[0] - a[0], b[1] - a[1]];
    let rel = [p[0] - a[0], p[1] - a[1]];
    let len2 = d[0] * d[0] + d[1] * d[1];
    if len2 == 0.0 {
        let dist2 = rel[0] * rel[0] + rel[1] * rel[1];
        return (dist2, dist2.sqrt(), d);
    }
    let t = ((rel[0] * d[0] + rel[1] * d[1]) / len2).clamp(0.0, 1.0);
    let (ex, ez) = (rel[0] - t * d[0], rel[1] - t * d[1]);
    // Right of a driver heading along d: (-d_z, d_x) in the (x, z) plane.
    let lateral = (rel[1] * d[0] - rel[0] * d[1]) / len2.sqrt();
    (ex * ex + ez * ez, lateral, d)
}

impl Surface {
    /// Precomputes the queries for `network` as it stands (pieces, connections, frictions).
    pub fn new(network: &Network) -> Self {
        let mut connected = vec![[false; 4]; network.pieces().len()];
        for link in network.links() {
            for (piece, port) in [link.a, link.b] {
                connected[piece.0][port] = true;
            }
        }
        let pieces = network
            .pieces()
            .iter()
            .zip(&connected)
            .map(|(p, &connected)| PieceShape {
                pose: p.pose,
                sin_cos: p.pose.heading_rad.sin_cos(),
                shape: match &p.kind {
                    PieceKind::Map { map, .. } => Shape::Map(Box::new(map.index())),
                    &PieceKind::Segment { length_m, .. } => Shape::Segment {
                        length_m,
                        half_road_m: p.kind.half_road_m(),
                    },
                    PieceKind::Arc { .. } | PieceKind::Clothoid { .. } => {
                        let line = p.kind.ref_line().expect("curved");
                        Shape::Curve {
                            line: SampledLine::new(&line),
                            length_m: line.length_m,
                            half_road_m: p.kind.half_road_m(),
                            half_width_m: p.kind.half_width_m(),
                        }
                    }
                    _ => Shape::Plaza {
                        half_m: p.kind.footprint().0[0],
                        half_road_m: p.kind.half_road_m(),
                        island_m: p.kind.island_radius_m(),
                    },
                },
                footprint: p.kind.footprint(),
                friction: p.kind.friction(),
                connected,
            })
            .collect::<Vec<PieceShape>>();
        // A map's lines and boxes are its cache's, built once per program.
        let (lanes, lane_boxes): (Vec<_>, Vec<_>) = network
            .pieces()
            .iter()
            .enumerate()
            .map(|(i, p)| match &p.kind {
                PieceKind::Map { map, .. } => map.lane_lines(),
                _ => lane_lines(
                    network
                        .lane_paths(PieceId(i))
                        .into_iter()
                        .map(|l| l.points)
                        .collect(),
                ),
            })
            .unzip();
        debug_assert!(PORT_NAMES.len() == 4);
        let grid = PieceGrid::new(&pieces.iter().map(near_box).collect::<Vec<_>>());
        Surface {
            pieces,
            grid,
            lanes,
            lane_boxes,
        }
    }

    /// Sets the friction of piece `id` (a friction that varies over the test); an id not of
    /// this network is ignored.
    pub fn set_friction(&mut self, id: PieceId, friction: f64) {
        if let Some(p) = self.pieces.get_mut(id.0) {
            p.friction = friction;
        }
    }

    /// The piece whose footprint (carriageway, sidewalks, plaza) contains the world point
    /// `[x, z]` (m), if any; the first in network order where two touch.
    pub fn piece_under(&self, p: [f64; 2]) -> Option<PieceId> {
        self.grid
            .near(p)
            .iter()
            .find(|&&i| {
                let s = &self.pieces[i];
                s.in_footprint(s.local(p), 0.0)
            })
            .map(|&i| PieceId(i))
    }

    /// The friction coefficient under the world point `[x, z]` (m): the friction of the piece
    /// there, or [`GROUND_FRICTION`] off the network.
    pub fn friction_at(&self, p: [f64; 2]) -> f64 {
        self.piece_under(p)
            .map_or(GROUND_FRICTION, |id| self.pieces[id.0].friction)
    }

    /// Signed distance from the world point `[x, z]` to the edge of the driving surface, in
    /// metres: `> 0` on the surface (the distance to the nearest edge), `<= 0` off it (minus the
    /// distance to the nearest driving surface). Sidewalks, islands and the ground beyond a
    /// dead end are off the surface.
    pub fn edge_distance_m(&self, p: [f64; 2]) -> f64 {
        // On the road: the largest inside distance over the pieces whose footprint holds the
        // point (the others' would be negative). Off it: the distance to the nearest piece.
        let mut inside = f64::NEG_INFINITY;
        for s in self.grid.near(p).iter().map(|&i| &self.pieces[i]) {
            let q = s.local(p);
            if s.in_footprint(q, 0.0) {
                inside = inside.max(s.signed_edge_m(q));
            }
        }
        if inside >= 0.0 {
            return inside;
        }
        -self
            .pieces
            .iter()
            .map(|s| -s.signed_edge_m(s.local(p)))
            .fold(f64::INFINITY, f64::min)
    }

    /// Whether the world point `[x, z]` is on no driving surface of the network.
    pub fn off_road(&self, p: [f64; 2]) -> bool {
        self.edge_distance_m(p) < 0.0
    }

    /// Lateral offset of the world point `[x, z]` from the centre line of the nearest lane
    /// whose direction of travel is within 90° of `heading_rad`, in metres, positive to the
    /// right of that direction (the nearest lane of any direction when none agrees; NaN for a
    /// network without lanes). Lanes inside junctions are their turning paths.
    pub fn lane_offset_m(&self, p: [f64; 2], heading_rad: f64) -> f64 {
        // The lanes of the pieces around the point, or of every piece when it is off them all.
        let near = |i: &usize| {
            let s = &self.pieces[*i];
            s.in_footprint(s.local(p), NEAR_M)
        };
        let candidates = self.grid.near(p);
        let any_near = candidates.iter().any(near);
        let h = direction(heading_rad);
        let (mut agreeing, mut any) = ((f64::INFINITY, f64::NAN), (f64::INFINITY, f64::NAN));
        let mut visit = |i: usize| {
            for (line, boxes) in self.lanes[i].iter().zip(self.lane_boxes[i].iter()) {
                for (k, b) in boxes.iter().enumerate() {
                    // No leg of the run is nearer than its box: when the box is farther than
                    // the nearest agreeing leg (no farther than the nearest of any
                    // direction), no leg of it can replace either; skipping it changes
                    // nothing.
                    if box_distance2(p, b) > agreeing.0 {
                        continue;
                    }
                    let start = k * LEGS_PER_BOX;
                    for w in line[start..(start + LEGS_PER_BOX + 1).min(line.len())].windows(2) {
                        let (dist2, lateral, u) = segment_offset(p, w[0], w[1]);
                        if dist2 < any.0 {
                            any = (dist2, lateral);
                        }
                        if u[0] * h[0] + u[1] * h[1] > 0.0 && dist2 < agreeing.0 {
                            agreeing = (dist2, lateral);
                        }
                    }
                }
            }
        };
        if any_near {
            candidates
                .iter()
                .filter(|i| near(i))
                .for_each(|&i| visit(i));
        } else {
            (0..self.pieces.len()).for_each(&mut visit);
        }
        if agreeing.0.is_finite() {
            agreeing.1
        } else {
            any.1
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::network::{Lane, PieceKind};

    fn segment(length_m: f64, friction: f64) -> PieceKind {
        PieceKind::Segment {
            length_m,
            lanes: 2,
            friction,
        }
    }

    /// Three segments end to end: 0..60 m dry, 60..180 m wet, 180..380 m dry.
    fn patch() -> Network {
        let mut n = Network::new();
        let a = n.add("a", segment(60.0, 0.9)).unwrap();
        let b = n.add("b", segment(120.0, 0.2)).unwrap();
        let c = n.add("c", segment(200.0, 0.9)).unwrap();
        n.connect(a, 1, b, 0).unwrap();
        n.connect(b, 1, c, 0).unwrap();
        n
    }

    #[test]
    fn friction_follows_the_piece_under_the_point_and_the_ground_beyond() {
        let s = Surface::new(&patch());
        assert_eq!(s.friction_at([30.0, 1.75]), 0.9);
        assert_eq!(s.friction_at([61.0, 1.75]), 0.2);
        assert_eq!(s.friction_at([179.0, -1.75]), 0.2);
        assert_eq!(s.friction_at([181.0, 1.75]), 0.9);
        // The sidewalk belongs to its piece; beyond it is grass.
        assert_eq!(s.friction_at([100.0, 4.0]), 0.2);
        assert_eq!(s.friction_at([100.0, 9.0]), GROUND_FRICTION);
        assert_eq!(s.friction_at([400.0, 0.0]), GROUND_FRICTION);
    }

    #[test]
    fn edge_distance_is_signed_and_connected_ends_are_no_edge() {
        let s = Surface::new(&patch());
        // Lane 1 centre: 1.75 m from the right edge (carriageway half width 3.5 m).
        assert!((s.edge_distance_m([100.0, 1.75]) - 1.75).abs() < 1e-12);
        // At the joint between two pieces, still 1.75 m from an edge.
        assert!((s.edge_distance_m([60.0, 1.75]) - 1.75).abs() < 1e-12);
        // Near the dead ends at x = 0 and x = 380 m.
        assert!((s.edge_distance_m([0.5, 0.0]) - 0.5).abs() < 1e-12);
        assert!((s.edge_distance_m([379.0, 0.0]) - 1.0).abs() < 1e-12);
        // Beyond the dead end and on the sidewalk: off the road.
        assert!((s.edge_distance_m([390.0, 0.0]) + 10.0).abs() < 1e-12);
        assert!((s.edge_distance_m([100.0, 4.5]) + 1.0).abs() < 1e-12);
        assert!(s.off_road([390.0, 0.0]) && !s.off_road([379.0, 0.0]));
    }

    /// Across the joint between a curved piece and the next piece, every point of the road's
    /// width is on the surface: the curve ends at its exact cross-section, not at its last
    /// chord's (which left a wedge of up to |t|·κ·step/2 off the road at the outer lanes:
    /// 8 mm at 5.25 m on a radius of 80 m).
    #[test]
    fn the_joints_of_curved_pieces_leave_no_gap_across_the_road() {
        let curves = [
            PieceKind::Arc {
                radius_m: 80.80941758504919,
                angle_rad: 0.7,
                lanes: 4,
                friction: 0.8,
            },
            PieceKind::Arc {
                radius_m: 16.0,
                angle_rad: -1.3,
                lanes: 6,
                friction: 0.8,
            },
            PieceKind::Clothoid {
                length_m: 37.0,
                curv_start: 0.0,
                curv_end: 1.0 / 30.0,
                lanes: 6,
                friction: 0.8,
            },
        ];
        for curve in curves {
            let lanes = curve.lanes();
            let mut n = Network::new();
            let a = n.add("a", segment_of(40.0, lanes)).unwrap();
            let c = n.add("c", curve.clone()).unwrap();
            let e = n.add("e", segment_of(100.0, lanes)).unwrap();
            n.connect(a, 1, c, 0).unwrap();
            n.connect(c, 1, e, 0).unwrap();
            let s = Surface::new(&n);
            let length = n.piece(c).kind.road_length_m().unwrap();
            let half = f64::from(lanes) * 3.5 / 2.0;
            let mut worst = f64::INFINITY;
            for (piece, at) in [(c, 0.0), (c, length), (e, 0.0)] {
                for k in -100..=100 {
                    let t = half * 0.999 * f64::from(k) / 100.0;
                    for d in [-0.02, -0.003, 0.0, 0.003, 0.02] {
                        let loc = n.on_lane(piece, Lane::Driving(1), at).unwrap();
                        let h = loc.heading_rad;
                        let (fwd, right) = ([h.cos(), -h.sin()], [h.sin(), h.cos()]);
                        // From lane 1's centre (1.75 m right of the line) to offset t.
                        let base = [
                            loc.pos_m[0] - 1.75 * right[0],
                            loc.pos_m[2] - 1.75 * right[1],
                        ];
                        let p = [
                            base[0] + t * right[0] + d * fwd[0],
                            base[1] + t * right[1] + d * fwd[1],
                        ];
                        let edge = s.edge_distance_m(p);
                        worst = worst.min(edge - (half - t.abs()));
                        assert!(
                            edge > 0.0,
                            "{curve:?}: {p:?} (t = {t}, d = {d}) reads {edge}"
                        );
                    }
                }
            }
            // The chords (0.25 m) shift the lateral offset by a fraction of a millimetre.
            assert!(
                worst > -1e-3,
                "{curve:?}: an edge nearer than the road's side: {worst}"
            );
        }
    }

    fn segment_of(length_m: f64, lanes: u32) -> PieceKind {
        PieceKind::Segment {
            length_m,
            lanes,
            friction: 0.8,
        }
    }

    #[test]
    fn junction_openings_are_no_edge_but_its_other_sides_and_island_are() {
        let mut n = Network::new();
        let j = n
            .add(
                "j",
                PieceKind::Roundabout {
                    lanes: 2,
                    radius_m: 20.0,
                    friction: 0.7,
                },
            )
            .unwrap();
        let e = n.add("e", segment(50.0, 0.9)).unwrap();
        n.connect(j, 0, e, 0).unwrap();
        let s = Surface::new(&n);
        let island = n.piece(j).kind.island_radius_m().unwrap();
        // On the east opening's centre line, 1 m inside the plaza: far from any edge.
        assert!(s.edge_distance_m([19.0, 0.0]) > 1.5);
        // On the unconnected west side: 1 m from the edge.
        assert!((s.edge_distance_m([-19.0, 0.0]) - 1.0).abs() < 1e-9);
        // On the island: off the road.
        assert!(s.off_road([0.0, 0.0]));
        assert!(
            (s.edge_distance_m([island + 0.5, 5.0]) - (island + 0.5).hypot(5.0) + island).abs()
                < 1e-9
        );
        assert_eq!(s.friction_at([0.0, 10.0]), 0.7);
    }

    /// [`Surface::lane_offset_m`] without the boxes: every leg of every lane line near `p`.
    fn lane_offset_every_leg(s: &Surface, p: [f64; 2], heading_rad: f64) -> f64 {
        let near = |i: &usize| s.pieces[*i].in_footprint(s.pieces[*i].local(p), 2.0);
        let any_near = (0..s.pieces.len()).any(|i| near(&i));
        let h = direction(heading_rad);
        let (mut agreeing, mut any) = ((f64::INFINITY, f64::NAN), (f64::INFINITY, f64::NAN));
        for i in (0..s.pieces.len()).filter(|i| !any_near || near(i)) {
            for w in s.lanes[i].iter().flat_map(|l| l.windows(2)) {
                let (dist2, lateral, u) = segment_offset(p, w[0], w[1]);
                if dist2 < any.0 {
                    any = (dist2, lateral);
                }
                if u[0] * h[0] + u[1] * h[1] > 0.0 && dist2 < agreeing.0 {
                    agreeing = (dist2, lateral);
                }
            }
        }
        if agreeing.0.is_finite() {
            agreeing.1
        } else {
            any.1
        }
    }

    #[test]
    fn the_grid_and_the_boxes_change_no_answer() {
        // A cross junction (turning paths of many legs), an arc and a roundabout, probed on a
        // grid of points and headings, on the network and off it.
        let mut n = Network::new();
        let a = n.add("a", segment(40.0, 0.8)).unwrap();
        let x = n
            .add(
                "x",
                PieceKind::CrossIntersection {
                    lanes: 2,
                    friction: 0.8,
                },
            )
            .unwrap();
        let bend = n
            .add(
                "bend",
                PieceKind::Arc {
                    radius_m: 25.0,
                    angle_rad: 1.2,
                    lanes: 2,
                    friction: 0.8,
                },
            )
            .unwrap();
        let o = n
            .add(
                "o",
                PieceKind::Roundabout {
                    lanes: 2,
                    radius_m: 15.0,
                    friction: 0.8,
                },
            )
            .unwrap();
        n.connect(a, 1, x, 2).unwrap();
        n.connect(x, 0, bend, 0).unwrap();
        n.connect(x, 1, o, 3).unwrap();
        let s = Surface::new(&n);
        assert!(s
            .lane_boxes
            .iter()
            .flat_map(|b| b.iter())
            .any(|b| b.len() > 1));
        // The grid has more than one cell, and cells that list fewer pieces than the network.
        assert!(s.grid.dims[0] * s.grid.dims[1] > 1);
        assert!((0..s.grid.starts.len() - 1)
            .any(|c| s.grid.starts[c + 1] - s.grid.starts[c] < s.pieces.len()));
        let mut probed = 0;
        let mut points: Vec<[f64; 2]> = (-30..=60)
            .flat_map(|i| (-40..=40).map(move |j| [i as f64 * 2.37, j as f64 * 2.11]))
            .collect();
        points.extend([[1e6, 0.0], [f64::NAN, 0.0], [-500.0, 3.0]]);
        for p in points {
            // Every piece, in network order, as before the grid.
            let under = s
                .pieces
                .iter()
                .position(|q| q.in_footprint(q.local(p), 0.0))
                .map(PieceId);
            assert_eq!(s.piece_under(p), under, "{p:?}");
            let inside = s
                .pieces
                .iter()
                .filter(|q| q.in_footprint(q.local(p), 0.0))
                .map(|q| q.signed_edge_m(q.local(p)))
                .fold(f64::NEG_INFINITY, f64::max);
            let edge = if inside >= 0.0 {
                inside
            } else {
                -s.pieces
                    .iter()
                    .map(|q| -q.signed_edge_m(q.local(p)))
                    .fold(f64::INFINITY, f64::min)
            };
            assert_eq!(s.edge_distance_m(p).to_bits(), edge.to_bits(), "{p:?}");
            for k in 0..5 {
                let heading = k as f64 * 1.3 - 2.6;
                let fast = s.lane_offset_m(p, heading);
                let every = lane_offset_every_leg(&s, p, heading);
                assert_eq!(fast.to_bits(), every.to_bits(), "{p:?} {heading}");
                probed += 1;
            }
        }
        assert!(probed > 30_000);
    }

    #[test]
    fn lane_offset_is_positive_to_the_right_of_travel() {
        let s = Surface::new(&patch());
        // Lane 1 drives +x at z = 1.75; 0.3 m to its right is z = 2.05.
        assert!((s.lane_offset_m([100.0, 2.05], 0.0) - 0.3).abs() < 1e-9);
        assert!((s.lane_offset_m([100.0, 1.45], 0.0) + 0.3).abs() < 1e-9);
        // Driving the other way, the nearest agreeing lane is lane -1 at z = -1.75.
        assert!((s.lane_offset_m([100.0, -2.0], std::f64::consts::PI) - 0.25).abs() < 1e-9);
    }
}
