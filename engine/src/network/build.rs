use rapier3d::prelude::*;

use super::{
    MapRef, Network, Piece, PieceKind, CURB_HEIGHT_M, GROUND_FRICTION, GROUND_MARGIN_M,
    GROUND_TOP_M, SIDEWALK_WIDTH_M,
};

/// Road shapes of one friction from which they go into one compound collider
/// ([`Network::build`]).
const COMPOUND_FROM: usize = 8;

thread_local! {
    /// Tests set it to build every road shape as a collider of its own, to compare.
    pub(crate) static SEPARATE_ROAD: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// Thickness of the road slab under the surface `y = 0`, in metres.
const SLAB_THICKNESS_M: f64 = 0.2;

impl Network {
    /// Inserts every piece as fixed colliders with its friction: a slab whose top is the
    /// surface `y = 0`, raised sidewalks along segments (on curved pieces, slab and sidewalks
    /// are convex prisms over slices whose chords depart from the curve by at most 1 cm), and a roundabout's raised island;
    /// then the ground (grass, top [`GROUND_TOP_M`], friction [`GROUND_FRICTION`]) reaching
    /// [`GROUND_MARGIN_M`] beyond the network, so a vehicle that leaves the road drives on
    /// instead of falling. The ground goes in last, so the pieces' collider handles do not
    /// depend on it.
    pub(crate) fn build(&self, physics: &mut PhysicsWorld) {
        self.build_pieces(physics);
        let (lo, hi) = self.bounds_m();
        let m = GROUND_MARGIN_M;
        let half = [(hi[0] - lo[0]) / 2.0 + m, (hi[1] - lo[1]) / 2.0 + m];
        let thickness = 1.0f32;
        physics.insert_collider(
            ColliderBuilder::cuboid(half[0] as f32, thickness / 2.0, half[1] as f32)
                .position(Pose::from_parts(
                    Vector::new(
                        ((lo[0] + hi[0]) / 2.0) as f32,
                        GROUND_TOP_M as f32 - thickness / 2.0,
                        ((lo[1] + hi[1]) / 2.0) as f32,
                    ),
                    Rotation::from_rotation_y(0.0),
                ))
                .friction(GROUND_FRICTION as f32),
            None,
        );
    }

    /// Inserts the pieces' shapes. Shapes of equal friction go into one compound collider
    /// (in piece order) when there are [`COMPOUND_FROM`] or more of them, so the broad phase
    /// holds one leaf for the whole road instead of one per slab and sidewalk: with several moving actors, rapier refits and traverses
    /// its whole tree every step, and a few dozen road leaves made that cost grow with the
    /// network (issue 23, long horizons). A ray or a contact sees the same shapes at the same
    /// poses: the compound sits at the origin, and each part keeps its own pose. A map's
    /// triangle mesh, itself a composite shape, stays a collider of its own.
    fn build_pieces(&self, physics: &mut PhysicsWorld) {
        // (friction, parts) in order of first appearance.
        let mut groups: Groups = Vec::new();
        for p in &self.pieces {
            let mu = p.kind.friction() as f32;
            match &p.kind {
                PieceKind::Map { map, .. } => insert_map_mesh(physics, p, map, mu),
                PieceKind::Arc { .. } | PieceKind::Clothoid { .. } => {
                    insert_curve_slices(physics, p, mu);
                }
                _ => {
                    for (pose, shape) in flat_parts(p) {
                        add_part(&mut groups, mu, pose, shape);
                    }
                }
            }
        }
        insert_groups(physics, groups);
    }
}

/// Road shapes by friction, in order of first appearance: each friction with its parts
/// (pose, shape).
type Groups = Vec<(f32, Vec<(Pose, SharedShape)>)>;

/// Adds a shape at `pose` to the group of friction `mu` (matched bit for bit), opening a new
/// group at the end when there is none.
fn add_part(groups: &mut Groups, mu: f32, pose: Pose, shape: SharedShape) {
    match groups.iter_mut().find(|(f, _)| f.to_bits() == mu.to_bits()) {
        Some((_, parts)) => parts.push((pose, shape)),
        None => groups.push((mu, vec![(pose, shape)])),
    }
}

/// Inserts a map piece as one triangle mesh, friction `mu`, of every lane's strip at the
/// surface `y = 0` (maps are flat and have no curbs).
fn insert_map_mesh(physics: &mut PhysicsWorld, p: &Piece, map: &MapRef, mu: f32) {
    // Built once per map and pose, shared by every test (`MapRef::mesh`):
    // the mesh's BVH is most of a map world's cost to build.
    let pose = &p.pose;
    let key = [pose.x, pose.z, pose.heading_rad].map(f64::to_bits);
    let mesh = map.mesh(key, || {
        let (vertices, indices) = map.0.strip_triangles();
        let vertices = vertices
            .iter()
            .map(|q| {
                let [x, z] = pose.apply(*q);
                Vector::new(x as f32, 0.0, z as f32)
            })
            .collect();
        SharedShape::trimesh(vertices, indices).ok()
    });
    if let Some(mesh) = mesh {
        physics.insert_collider(ColliderBuilder::new(mesh).friction(mu), None);
    }
}

/// Inserts a curved piece (`Arc`, `Clothoid`), friction `mu`, as convex prisms over slices
/// of its reference line: per slice the slab (top `y = 0`) and both sidewalks (top
/// [`CURB_HEIGHT_M`]), each a collider of its own.
fn insert_curve_slices(physics: &mut PhysicsWorld, p: &Piece, mu: f32) {
    let slab = SLAB_THICKNESS_M as f32;
    let line = p.kind.ref_line().expect("curved");
    let hw = p.kind.half_road_m();
    let sw = SIDEWALK_WIDTH_M;
    let curb = CURB_HEIGHT_M as f32;
    // Each slice's chord departs from the curve by at most 1 cm.
    let step = (0.08 / line.max_curvature().max(1e-9)).sqrt().min(2.0);
    let frames = line.frames(step);
    for pair in frames.windows(2) {
        for (t0, t1, top) in [(-hw, hw, 0.0), (hw, hw + sw, curb), (-hw - sw, -hw, curb)] {
            let mut corners = Vec::with_capacity(8);
            for f in pair {
                for t in [t0, t1] {
                    let [x, z] = p.pose.apply(f.offset(t));
                    for y in [-slab, top] {
                        corners.push(Vector::new(x as f32, y, z as f32));
                    }
                }
            }
            // Slices stay colliders of their own: in one compound, a wheel
            // ray met them in another order, and worlds with curves drifted by
            // millimetres from what they gave before (verdicts unchanged).
            if let Some(c) = ColliderBuilder::convex_hull(&corners) {
                physics.insert_collider(c.friction(mu), None);
            }
        }
    }
}

/// The shapes of a segment or junction piece, in world poses and in insertion order: the
/// slab (top `y = 0`), then a segment's two sidewalks or a roundabout's island (top
/// [`CURB_HEIGHT_M`]).
fn flat_parts(p: &Piece) -> Vec<(Pose, SharedShape)> {
    let mut parts = Vec::new();
    let rotation = Rotation::from_rotation_y(p.pose.heading_rad as f32);
    // Heights in f32 as rapier stores them, so that a segment at the origin builds
    // exactly the colliders of the single-road engine before networks.
    let at = |local: [f64; 2], y: f32| {
        let [x, z] = p.pose.apply(local);
        Pose::from_parts(Vector::new(x as f32, y, z as f32), rotation)
    };
    let slab = SLAB_THICKNESS_M as f32;
    let ([hx, hz], centre) = p.kind.footprint();
    match p.kind {
        PieceKind::Segment { length_m, .. } => {
            let hw = p.kind.half_road_m();
            parts.push((
                at(centre, -slab / 2.0),
                SharedShape::cuboid(hx as f32, slab / 2.0, hw as f32),
            ));
            let sw = SIDEWALK_WIDTH_M;
            let curb = CURB_HEIGHT_M as f32;
            let h = (slab + curb) / 2.0;
            for side in [1.0, -1.0] {
                parts.push((
                    at([length_m / 2.0, side * (hw + sw / 2.0)], curb - h),
                    SharedShape::cuboid(hx as f32, h, (sw / 2.0) as f32),
                ));
            }
        }
        _ => {
            parts.push((
                at(centre, -slab / 2.0),
                SharedShape::cuboid(hx as f32, slab / 2.0, hz as f32),
            ));
            if let Some(r) = p.kind.island_radius_m() {
                let curb = CURB_HEIGHT_M as f32;
                let h = (slab + curb) / 2.0;
                parts.push((at(centre, curb - h), SharedShape::cylinder(h, r as f32)));
            }
        }
    }
    parts
}

/// Inserts each friction group: as one compound collider at the origin when it has
/// [`COMPOUND_FROM`] or more parts (and [`SEPARATE_ROAD`] is off), else as a collider per
/// part.
fn insert_groups(physics: &mut PhysicsWorld, groups: Groups) {
    for (mu, parts) in groups {
        if parts.len() < COMPOUND_FROM || SEPARATE_ROAD.with(std::cell::Cell::get) {
            // A few shapes: a compound would only add a tree level to every ray.
            for (pose, shape) in parts {
                physics.insert_collider(
                    ColliderBuilder::new(shape).position(pose).friction(mu),
                    None,
                );
            }
        } else {
            physics.insert_collider(ColliderBuilder::compound(parts).friction(mu), None);
        }
    }
}
