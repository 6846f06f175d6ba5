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

/// Point queries on a [`Network`]'s surface, precomputed once per world.
#[derive(Debug, Clone)]
pub struct Surface {
    pieces: Vec<PieceShape>,
    /// Each piece's lane centre lines: polylines in world `[x, z]` metres, in their direction
    /// of travel.
    lanes: Vec<Vec<Vec<[f64; 2]>>>,
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
                    PieceKind::Map { map, .. } => {
                        Shape::Map(Box::new(MapIndex::new(map.0.clone())))
                    }
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
        let lanes = (0..network.pieces().len())
            .map(|i| match &pieces[i].shape {
                Shape::Map(index) => index.lane_lines(),
                _ => network
                    .lane_paths(PieceId(i))
                    .into_iter()
                    .map(|l| l.points)
                    .collect(),
            })
            .collect();
        debug_assert!(PORT_NAMES.len() == 4);
        Surface { pieces, lanes }
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
        self.pieces
            .iter()
            .position(|s| s.in_footprint(s.local(p), 0.0))
            .map(PieceId)
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
        for s in &self.pieces {
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
            s.in_footprint(s.local(p), 2.0)
        };
        let any_near = (0..self.pieces.len()).any(|i| near(&i));
        let h = direction(heading_rad);
        let (mut agreeing, mut any) = ((f64::INFINITY, f64::NAN), (f64::INFINITY, f64::NAN));
        for i in (0..self.pieces.len()).filter(|i| !any_near || near(i)) {
            for line in &self.lanes[i] {
                for w in line.windows(2) {
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
    use crate::network::PieceKind;

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
