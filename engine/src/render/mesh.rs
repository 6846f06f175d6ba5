//! Triangle meshes of the static world (ground, roads, markings, sidewalks, islands) and of
//! the box that stands for every car and pedestrian.

use bytemuck::{Pod, Zeroable};

use crate::segmentation::SemanticClass;

use crate::network::{
    Frame, MapLane, Network, Piece, PieceKind, RefLine, RoadMap, CURB_HEIGHT_M, GROUND_MARGIN_M,
    GROUND_TOP_M, JUNCTION_APRON_M, LANE_WIDTH_M,
};

/// One vertex: position in world metres, unit normal, albedo (linear, `[0, 1]`), and its
/// label ([`crate::segmentation`]; the class id alone, the world has no actor).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub(crate) struct Vertex {
    pub pos: [f32; 3],
    pub normal: [f32; 3],
    pub color: [f32; 3],
    pub label: u32,
}

/// What a surface is: its albedo and its class in the segmentation mask.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Material {
    pub albedo: [f32; 3],
    pub class: SemanticClass,
}

/// The world's materials.
pub(crate) mod material {
    use super::{albedo, Material, SemanticClass};

    pub const GRASS: Material = Material {
        albedo: albedo::GRASS,
        class: SemanticClass::Ground,
    };
    pub const ASPHALT: Material = Material {
        albedo: albedo::ASPHALT,
        class: SemanticClass::Road,
    };
    pub const CONCRETE: Material = Material {
        albedo: albedo::CONCRETE,
        class: SemanticClass::Sidewalk,
    };
    pub const PAINT_WHITE: Material = Material {
        albedo: albedo::PAINT_WHITE,
        class: SemanticClass::LaneMarking,
    };
    pub const PAINT_YELLOW: Material = Material {
        albedo: albedo::PAINT_YELLOW,
        class: SemanticClass::LaneMarking,
    };
    pub const ISLAND: Material = Material {
        albedo: albedo::ISLAND,
        class: SemanticClass::Ground,
    };
    /// The actors' unit cube: white, its label given per instance.
    pub const ACTOR: Material = Material {
        albedo: [1.0, 1.0, 1.0],
        class: SemanticClass::Sky,
    };
}

/// Albedos of the world's materials.
pub(crate) mod albedo {
    pub const GRASS: [f32; 3] = [0.22, 0.36, 0.16];
    pub const ASPHALT: [f32; 3] = [0.21, 0.21, 0.22];
    pub const CONCRETE: [f32; 3] = [0.56, 0.55, 0.52];
    pub const PAINT_WHITE: [f32; 3] = [0.92, 0.92, 0.90];
    pub const PAINT_YELLOW: [f32; 3] = [0.88, 0.70, 0.12];
    pub const ISLAND: [f32; 3] = [0.26, 0.46, 0.20];
    /// The sky, and the colour fog fades toward.
    pub const SKY: [f32; 3] = [0.62, 0.74, 0.90];
}

/// Height of lane markings above the asphalt, in metres (enough to never z-fight with the
/// reversed-Z depth buffer).
const PAINT_LIFT_M: f64 = 0.01;
/// Width of painted lines, in metres.
const LINE_WIDTH_M: f64 = 0.15;
/// Dashed lane dividers: dash length and period, in metres.
const DASH_M: (f64, f64) = (3.0, 9.0);

/// An indexed triangle list.
#[derive(Debug, Default, Clone)]
pub(crate) struct Mesh {
    pub vertices: Vec<Vertex>,
    pub indices: Vec<u32>,
}

impl Mesh {
    /// Adds `other`'s triangles after this mesh's, as if they had been built into it.
    fn append(&mut self, other: &Mesh) {
        let base = self.vertices.len() as u32;
        self.vertices.extend_from_slice(&other.vertices);
        self.indices.extend(other.indices.iter().map(|i| base + i));
    }

    fn quad(&mut self, corners: [[f64; 3]; 4], normal: [f32; 3], m: Material) {
        let base = self.vertices.len() as u32;
        for c in corners {
            self.vertices.push(Vertex {
                pos: [c[0] as f32, c[1] as f32, c[2] as f32],
                normal,
                color: m.albedo,
                label: u32::from(m.class.id()),
            });
        }
        self.indices
            .extend_from_slice(&[base, base + 1, base + 2, base, base + 2, base + 3]);
    }

    /// A horizontal rectangle `[x0, x1] × [z0, z1]` of the piece's local frame at height `y`.
    fn flat(&mut self, piece: &Piece, x: (f64, f64), z: (f64, f64), y: f64, color: Material) {
        let w = |lx: f64, lz: f64| {
            let [wx, wz] = piece.pose.apply([lx, lz]);
            [wx, y, wz]
        };
        self.quad(
            [w(x.0, z.0), w(x.1, z.0), w(x.1, z.1), w(x.0, z.1)],
            [0.0, 1.0, 0.0],
            color,
        );
    }

    /// A vertical curb face along local `z = z0` from `x0` to `x1`, facing `side` (`±1` in z).
    fn curb(&mut self, piece: &Piece, x: (f64, f64), z0: f64, side: f64) {
        let w = |lx: f64, y: f64| {
            let [wx, wz] = piece.pose.apply([lx, z0]);
            [wx, y, wz]
        };
        let [nx, nz] = piece.pose.apply([0.0, side]);
        let normal = [(nx - piece.pose.x) as f32, 0.0, (nz - piece.pose.z) as f32];
        self.quad(
            [
                w(x.0, 0.0),
                w(x.1, 0.0),
                w(x.1, CURB_HEIGHT_M),
                w(x.0, CURB_HEIGHT_M),
            ],
            normal,
            material::CONCRETE,
        );
    }

    /// A horizontal disc of radius `r` at height `y`, centred on the piece's origin.
    fn disc(&mut self, piece: &Piece, r: f64, y: f64, m: Material) {
        const SIDES: u32 = 48;
        let base = self.vertices.len() as u32;
        let [cx, cz] = piece.pose.apply([0.0, 0.0]);
        self.vertices.push(Vertex {
            pos: [cx as f32, y as f32, cz as f32],
            normal: [0.0, 1.0, 0.0],
            color: m.albedo,
            label: u32::from(m.class.id()),
        });
        for i in 0..SIDES {
            let a = f64::from(i) / f64::from(SIDES) * std::f64::consts::TAU;
            let [x, z] = piece.pose.apply([r * a.cos(), r * a.sin()]);
            self.vertices.push(Vertex {
                pos: [x as f32, y as f32, z as f32],
                normal: [0.0, 1.0, 0.0],
                color: m.albedo,
                label: u32::from(m.class.id()),
            });
        }
        for i in 0..SIDES {
            self.indices
                .extend_from_slice(&[base, base + 1 + i, base + 1 + (i + 1) % SIDES]);
        }
    }

    /// A painted line along local `x` from `x0` to `x1`, centred on `z`.
    fn line(&mut self, piece: &Piece, x: (f64, f64), z: f64, color: Material) {
        let h = LINE_WIDTH_M / 2.0;
        self.flat(piece, x, (z - h, z + h), PAINT_LIFT_M, color);
    }

    fn dashed(&mut self, piece: &Piece, length_m: f64, z: f64) {
        let mut x = DASH_M.1 / 2.0;
        while x < length_m {
            self.line(
                piece,
                (x, (x + DASH_M.0).min(length_m)),
                z,
                material::PAINT_WHITE,
            );
            x += DASH_M.1;
        }
    }

    fn segment(&mut self, piece: &Piece, length_m: f64) {
        let kind = &piece.kind;
        let road = kind.half_road_m();
        let outer = kind.half_width_m();
        let along = (0.0, length_m);
        self.flat(piece, along, (-road, road), 0.0, material::ASPHALT);
        for side in [-1.0, 1.0] {
            let (a, b) = (side * road, side * outer);
            self.flat(
                piece,
                along,
                (a.min(b), a.max(b)),
                CURB_HEIGHT_M,
                material::CONCRETE,
            );
            self.curb(piece, along, side * road, -side);
            // Edge line.
            self.line(piece, along, side * (road - 0.3), material::PAINT_WHITE);
            // Lane dividers between lanes of one direction.
            for k in 1..kind.lanes() / 2 {
                self.dashed(piece, length_m, side * f64::from(k) * LANE_WIDTH_M);
            }
            // Double yellow centre line.
            self.line(piece, along, side * 0.12, material::PAINT_YELLOW);
        }
    }

    /// A curved piece: the segment's surfaces and markings laid along its reference line,
    /// in slices whose chords depart from the curve by at most 1 cm.
    fn curved(&mut self, piece: &Piece, line: &RefLine) {
        let kind = &piece.kind;
        let road = kind.half_road_m();
        let outer = kind.half_width_m();
        let step = (0.08 / line.max_curvature().max(1e-9)).sqrt().min(2.0);
        let stations = line.frames(step);
        let all = (0.0, line.length_m);
        self.band(
            piece,
            line,
            &stations,
            all,
            (-road, road),
            0.0,
            material::ASPHALT,
        );
        for side in [-1.0, 1.0] {
            let (a, b) = (side * road, side * outer);
            self.band(
                piece,
                line,
                &stations,
                all,
                (a.min(b), a.max(b)),
                CURB_HEIGHT_M,
                material::CONCRETE,
            );
            self.curved_curb(piece, line, &stations, side * road, -side);
            let paint = |m: &mut Mesh, range: (f64, f64), t: f64, color: Material| {
                let h = LINE_WIDTH_M / 2.0;
                m.band(
                    piece,
                    line,
                    &stations,
                    range,
                    (t - h, t + h),
                    PAINT_LIFT_M,
                    color,
                );
            };
            paint(self, all, side * (road - 0.3), material::PAINT_WHITE);
            for k in 1..kind.lanes() / 2 {
                let mut x = DASH_M.1 / 2.0;
                while x < line.length_m {
                    let range = (x, (x + DASH_M.0).min(line.length_m));
                    paint(
                        self,
                        range,
                        side * f64::from(k) * LANE_WIDTH_M,
                        material::PAINT_WHITE,
                    );
                    x += DASH_M.1;
                }
            }
            paint(self, all, side * 0.12, material::PAINT_YELLOW);
        }
    }

    /// A horizontal band of a curved piece from station `s.0` to `s.1` (m) and from `t.0` to
    /// `t.1` metres right of the reference line, at height `y`, one quad per slice between
    /// `stations` (and the band's own ends).
    #[allow(clippy::too_many_arguments)]
    fn band(
        &mut self,
        piece: &Piece,
        line: &RefLine,
        stations: &[Frame],
        s: (f64, f64),
        t: (f64, f64),
        y: f64,
        color: Material,
    ) {
        let end = |at: f64| {
            stations
                .iter()
                .find(|f| f.s == at)
                .copied()
                .unwrap_or_else(|| line.frame(at))
        };
        let mut cuts = vec![end(s.0)];
        cuts.extend(stations.iter().copied().filter(|f| f.s > s.0 && f.s < s.1));
        cuts.push(end(s.1));
        let w = |f: &Frame, b: f64| {
            let [x, z] = piece.pose.apply(f.offset(b));
            [x, y, z]
        };
        for c in cuts.windows(2) {
            self.quad(
                [w(&c[0], t.0), w(&c[1], t.0), w(&c[1], t.1), w(&c[0], t.1)],
                [0.0, 1.0, 0.0],
                color,
            );
        }
    }

    /// The vertical curb face of a curved piece at `t0` metres right of its reference line,
    /// facing `side` (`±1`: to the right or left of the direction of travel).
    fn curved_curb(
        &mut self,
        piece: &Piece,
        line: &RefLine,
        stations: &[Frame],
        t0: f64,
        side: f64,
    ) {
        let w = |f: &Frame, y: f64| {
            let [x, z] = piece.pose.apply(f.offset(t0));
            [x, y, z]
        };
        for c in stations.windows(2) {
            let r = line.right((c[0].s + c[1].s) / 2.0);
            let [nx, nz] = piece.pose.apply([side * r[0], side * r[1]]);
            let normal = [(nx - piece.pose.x) as f32, 0.0, (nz - piece.pose.z) as f32];
            self.quad(
                [
                    w(&c[0], 0.0),
                    w(&c[1], 0.0),
                    w(&c[1], CURB_HEIGHT_M),
                    w(&c[0], CURB_HEIGHT_M),
                ],
                normal,
                material::CONCRETE,
            );
        }
    }

    fn junction(&mut self, piece: &Piece) {
        let ([hx, hz], _) = piece.kind.footprint();
        self.flat(piece, (-hx, hx), (-hz, hz), 0.0, material::ASPHALT);
        if let Some(island) = piece.kind.island_radius_m() {
            self.disc(piece, island, CURB_HEIGHT_M, material::ISLAND);
        } else {
            // Stop lines where the roads enter, across the incoming lanes.
            let road = piece.kind.half_road_m();
            let edge = piece.kind.junction_half_m() - JUNCTION_APRON_M / 2.0;
            for port in piece.kind.ports() {
                let rot = crate::network::Pose2 {
                    x: piece.pose.x,
                    z: piece.pose.z,
                    heading_rad: piece.pose.heading_rad + port.heading_rad,
                };
                let rotated = Piece {
                    name: String::new(),
                    kind: piece.kind.clone(),
                    pose: rot,
                };
                // Incoming lanes lie on local -z of a frame whose x points out of the port.
                self.flat(
                    &rotated,
                    (edge - 0.25, edge + 0.25),
                    (-road, 0.0),
                    PAINT_LIFT_M,
                    material::PAINT_WHITE,
                );
            }
        }
    }

    /// A band along a map lane from `t.0` to `t.1` metres right of its centre line (right of
    /// increasing `s`) at height `y`, over the stations for which `keep` holds.
    fn lane_band(
        &mut self,
        piece: &Piece,
        lane: &MapLane,
        t: (f64, f64),
        y: f64,
        color: Material,
        keep: impl Fn(f64) -> bool,
    ) {
        let at = |i: usize, off: f64| {
            let r = lane.right(i);
            let c = lane.centre[i];
            let [x, z] = piece.pose.apply([c[0] + off * r[0], c[1] + off * r[1]]);
            [x, y, z]
        };
        for i in 0..lane.s.len() - 1 {
            if !keep(lane.s[i]) {
                continue;
            }
            // Wound as a curved piece's bands are (stations increasing, `t` to the right).
            self.quad(
                [at(i, t.0), at(i + 1, t.0), at(i + 1, t.1), at(i, t.1)],
                [0.0, 1.0, 0.0],
                color,
            );
        }
    }

    /// An OpenDRIVE map: asphalt on driving lanes, concrete on the others, and markings on
    /// roads outside junctions: a double yellow line between the two directions, dashed
    /// white between lanes of one direction, a solid white edge line where the driving
    /// surface ends.
    fn map(&mut self, piece: &Piece, map: &RoadMap) {
        use std::collections::HashMap;
        let by_id: HashMap<(usize, usize, i32), &MapLane> = map
            .lanes
            .iter()
            .map(|l| ((l.road, l.section, l.od_id), l))
            .collect();
        for l in &map.lanes {
            let h = |i: usize| l.width[i] / 2.0;
            let w = l.width.iter().copied().fold(0.0, f64::max) / 2.0;
            let m = if l.drivable {
                material::ASPHALT
            } else {
                material::CONCRETE
            };
            // Each quad spans the widest half-width; narrower stretches come out right only
            // for constant widths, so varying lanes are drawn quad by quad.
            if l.width.windows(2).all(|p| (p[0] - p[1]).abs() < 1e-9) {
                self.lane_band(piece, l, (-w, w), 0.0, m, |_| true);
            } else {
                for i in 0..l.s.len() - 1 {
                    let hw = h(i).max(h(i + 1));
                    let s0 = l.s[i];
                    self.lane_band(piece, l, (-hw, hw), 0.0, m, |s| s == s0);
                }
            }
            if !l.drivable || map.roads[l.road].junction.is_some() {
                continue;
            }
            // Outward: +t (right of s) for right lanes (negative ids), -t for left ones.
            let out = if l.od_id < 0 { 1.0 } else { -1.0 };
            let outer = by_id.get(&(
                l.road,
                l.section,
                l.od_id + if l.od_id < 0 { -1 } else { 1 },
            ));
            let half_line = LINE_WIDTH_M / 2.0;
            match outer {
                Some(o) if o.drivable => {
                    let edge = out * w;
                    self.lane_band(
                        piece,
                        l,
                        (edge - half_line, edge + half_line),
                        PAINT_LIFT_M,
                        material::PAINT_WHITE,
                        |s| (s + DASH_M.1 / 2.0).rem_euclid(DASH_M.1) < DASH_M.0,
                    );
                }
                _ => {
                    let edge = out * (w - 0.3);
                    self.lane_band(
                        piece,
                        l,
                        (edge - half_line, edge + half_line),
                        PAINT_LIFT_M,
                        material::PAINT_WHITE,
                        |_| true,
                    );
                }
            }
            if l.od_id.abs() == 1
                && by_id
                    .get(&(l.road, l.section, -l.od_id))
                    .is_some_and(|o| o.drivable && o.forward != l.forward)
            {
                let inner = -out * w;
                let c = inner + out * 0.12;
                self.lane_band(
                    piece,
                    l,
                    (c - half_line, c + half_line),
                    PAINT_LIFT_M,
                    material::PAINT_YELLOW,
                    |_| true,
                );
            }
        }
    }

    /// The static world of `network`: a ground plane and every road piece.
    pub(crate) fn world(network: &Network) -> Mesh {
        let mut mesh = Mesh::default();
        for piece in network.pieces() {
            match &piece.kind {
                PieceKind::Map { map, .. } => {
                    // Built once per map and pose, shared by every test that renders it.
                    let pose = &piece.pose;
                    let key = [pose.x, pose.z, pose.heading_rad].map(f64::to_bits);
                    let part = map.mesh(key, || {
                        let mut part = Mesh::default();
                        part.map(piece, &map.0);
                        Some(std::sync::Arc::new(part))
                    });
                    if let Some(part) = part {
                        mesh.append(&part);
                    }
                }
                &PieceKind::Segment { length_m, .. } => mesh.segment(piece, length_m),
                PieceKind::Arc { .. } | PieceKind::Clothoid { .. } => {
                    let line = piece.kind.ref_line().expect("curved");
                    mesh.curved(piece, &line);
                }
                _ => mesh.junction(piece),
            }
        }
        let (lo, hi) = network.bounds_m();
        let (m, y) = (GROUND_MARGIN_M, GROUND_TOP_M);
        mesh.quad(
            [
                [lo[0] - m, y, lo[1] - m],
                [hi[0] + m, y, lo[1] - m],
                [hi[0] + m, y, hi[1] + m],
                [lo[0] - m, y, hi[1] + m],
            ],
            [0.0, 1.0, 0.0],
            material::GRASS,
        );
        mesh
    }

    /// The unit cube `[-0.5, 0.5]³` with flat normals, white: scaled, turned and tinted per
    /// instance into cars and pedestrians.
    pub(crate) fn unit_cube() -> Mesh {
        let mut mesh = Mesh::default();
        let h = 0.5;
        let white = material::ACTOR;
        for axis in 0..3 {
            for sign in [-1.0f64, 1.0] {
                let mut normal = [0.0f32; 3];
                normal[axis] = sign as f32;
                let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
                let corner = |a: f64, b: f64| {
                    let mut p = [0.0; 3];
                    p[axis] = sign * h;
                    p[u] = a;
                    p[v] = b;
                    p
                };
                mesh.quad(
                    [corner(-h, -h), corner(h, -h), corner(h, h), corner(-h, h)],
                    normal,
                    white,
                );
            }
        }
        mesh
    }
}

/// The albedo of a colour name used by scenarios (`Car(color=...)`, see
/// [`crate::colour::COLOURS`]); a name not in the list (which the scenario language refuses
/// when the program loads) is mid grey.
pub fn color_albedo(name: &str) -> [f32; 3] {
    crate::colour::albedo(name).unwrap_or([0.45, 0.45, 0.45])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_segment_has_asphalt_sidewalks_and_markings() {
        let n = Network::single_segment(100.0, 4, 1.0).unwrap();
        let m = Mesh::world(&n);
        assert_eq!(m.indices.len() % 3, 0);
        assert!(m.indices.iter().all(|&i| (i as usize) < m.vertices.len()));
        let count = |c: [f32; 3]| m.vertices.iter().filter(|v| v.color == c).count();
        assert_eq!(count(albedo::ASPHALT), 4);
        assert!(
            count(albedo::PAINT_WHITE) > 4 * 20,
            "dashes of two dividers"
        );
        assert_eq!(count(albedo::PAINT_YELLOW), 8);
        assert_eq!(Mesh::unit_cube().indices.len(), 36);
    }

    #[test]
    fn a_maps_render_mesh_is_built_once_and_gives_the_same_buffers() {
        let text = include_str!("../../../scenarios/maps/junction.xodr");
        let map = crate::network::opendrive::import("junction.xodr", text)
            .unwrap()
            .map;
        let shared = crate::network::MapRef::new(map);
        let mut n = Network::new();
        n.add(
            "m",
            PieceKind::Map {
                map: shared.clone(),
                friction: 0.8,
            },
        )
        .unwrap();
        // The map's part built in place, as before the cache.
        let mut direct = Mesh::default();
        direct.map(&n.pieces()[0], &shared.0);
        let first = Mesh::world(&n);
        let again = Mesh::world(&n.clone());
        assert_eq!(first.indices, again.indices);
        assert_eq!(first.vertices, again.vertices);
        assert_eq!(&first.indices[..direct.indices.len()], &direct.indices[..]);
        assert_eq!(
            &first.vertices[..direct.vertices.len()],
            &direct.vertices[..]
        );
        // The second world's map part came from the cache: the same Arc.
        let key = [0.0f64, 0.0, 0.0].map(f64::to_bits);
        let a = shared.mesh::<std::sync::Arc<Mesh>>(key, || None).unwrap();
        let b = shared.mesh::<std::sync::Arc<Mesh>>(key, || None).unwrap();
        assert!(std::sync::Arc::ptr_eq(&a, &b));
    }
}
