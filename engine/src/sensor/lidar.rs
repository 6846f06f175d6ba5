//! The ray-cast lidar: its settings ([`LidarSpec`]), its returns ([`LidarReturn`]) and the
//! lidar as a [`crate::sensor::Sensor`].

use rapier3d::prelude::*;
use serde::{Deserialize, Serialize};

use super::SettingError;

/// A spinning ray-cast lidar mounted on the ego vehicle.
///
/// Beams: `channels` elevations evenly spread over `[-vertical_fov_rad/2, vertical_fov_rad/2]`
/// (a single channel is horizontal) times `beams` azimuths evenly spread over
/// `[-horizontal_fov_rad/2, horizontal_fov_rad/2]` around the vehicle's forward axis. A scan
/// is taken every `1 / rate_hz` seconds, rounded to whole physics steps; between scans the last
/// one is held, as with a real spinning lidar.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LidarSpec {
    /// Number of vertical channels, `>= 1`. Default 1.
    pub channels: u32,
    /// Number of azimuths per channel, `>= 1`. Default 121.
    pub beams: u32,
    /// Horizontal field of view in rad, in `(0, 2π]`. Default 60° (1.047 rad).
    pub horizontal_fov_rad: f64,
    /// Vertical field of view in rad, in `[0, π]`. Default 0 (one horizontal plane).
    pub vertical_fov_rad: f64,
    /// Maximum range in metres, `> 0`. Default 60 m.
    pub range_m: f64,
    /// Scan rate in Hz, `> 0`. Default 20 Hz.
    pub rate_hz: f64,
    /// Mount point in the vehicle frame (`x` forward, `y` up, `z` right) in metres, relative to
    /// the chassis centre. Default `[2.0, 0.1, 0.0]`: the front bumper, about 1 m above ground.
    pub mount_m: [f64; 3],
}

impl Default for LidarSpec {
    fn default() -> Self {
        LidarSpec {
            channels: 1,
            beams: 121,
            horizontal_fov_rad: 60f64.to_radians(),
            vertical_fov_rad: 0.0,
            range_m: 60.0,
            rate_hz: 20.0,
            mount_m: [2.0, 0.1, 0.0],
        }
    }
}

/// One lidar return.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct LidarReturn {
    /// Beam azimuth in rad, positive to the left of the forward axis.
    pub azimuth_rad: f64,
    /// Beam elevation in rad, positive up.
    pub elevation_rad: f64,
    /// Distance from the mount to the hit, in metres, `<= range_m`.
    pub range_m: f64,
    /// The hit point in the vehicle frame (`x` forward, `y` up, `z` right) in metres, relative
    /// to the chassis centre.
    pub point_m: [f64; 3],
}

impl LidarReturn {
    /// The return of the beam `(azimuth_rad, elevation_rad)` with unit vector `local` (vehicle
    /// frame) from the mount `mount_m` (vehicle frame, m) that hit at `toi` m.
    fn hit(azimuth_rad: f64, elevation_rad: f64, mount_m: Vector, local: Vector, toi: f32) -> Self {
        let p = mount_m + local * toi;
        LidarReturn {
            azimuth_rad,
            elevation_rad,
            range_m: f64::from(toi),
            point_m: [f64::from(p.x), f64::from(p.y), f64::from(p.z)],
        }
    }
}

impl LidarSpec {
    /// Beam directions `(azimuth, elevation)` in rad, channel-major.
    pub(crate) fn directions(&self) -> Vec<(f64, f64)> {
        let spread = |n: u32, fov: f64| -> Vec<f64> {
            if n <= 1 {
                vec![0.0]
            } else {
                (0..n)
                    .map(|i| -fov / 2.0 + fov * i as f64 / (n - 1) as f64)
                    .collect()
            }
        };
        let az = spread(self.beams, self.horizontal_fov_rad);
        spread(self.channels, self.vertical_fov_rad)
            .into_iter()
            .flat_map(|el| az.iter().map(move |&a| (a, el)))
            .collect()
    }

    /// Checks the ranges documented on the fields.
    ///
    /// # Errors
    /// The first [`SettingError`] of the lidar's: no channel or beam, a range, rate or
    /// horizontal field of view that is not positive, a field of view too wide.
    pub(crate) fn validate(&self) -> Result<(), SettingError> {
        if self.channels == 0 || self.beams == 0 {
            return Err(SettingError::LidarWithoutBeams);
        }
        let ok = |v: f64| v.is_finite() && v > 0.0;
        if !ok(self.range_m) || !ok(self.rate_hz) || !ok(self.horizontal_fov_rad) {
            return Err(SettingError::LidarNotPositive);
        }
        if self.horizontal_fov_rad > std::f64::consts::TAU {
            return Err(SettingError::LidarOverFullTurn(self.horizontal_fov_rad));
        }
        if !(self.vertical_fov_rad.is_finite()
            && (0.0..=std::f64::consts::PI).contains(&self.vertical_fov_rad))
        {
            return Err(SettingError::LidarVertical(self.vertical_fov_rad));
        }
        Ok(())
    }

    /// Beam directions in the vehicle frame (`x` forward, `y` up, `z` right), unit vectors in
    /// the order of [`LidarSpec::directions`]; a positive (left) azimuth is `-z`.
    pub(crate) fn local_directions(directions: &[(f64, f64)]) -> Vec<Vector> {
        directions
            .iter()
            .map(|&(az, el)| {
                Vector::new(
                    (el.cos() * az.cos()) as f32,
                    el.sin() as f32,
                    -(el.cos() * az.sin()) as f32,
                )
            })
            .collect()
    }

    /// Casts every beam from the mount of the chassis at `chassis` (pose), ignoring the
    /// vehicle's own body, out to `range_m` metres (the spec's range, or less in fog). Sees
    /// fixed geometry and actors, including sensor colliders (pedestrians).
    ///
    /// Each return is the one rapier's query pipeline gives (bit for bit for boxes, balls,
    /// capsules, cylinders and convex hulls; on a map's triangle mesh, a hit where the mesh
    /// meets another surface exactly may differ in the last bit of its range)
    /// (`QueryPipeline::cast_ray(ray, range, solid = true)`): the nearest hit, strictly within
    /// the range, of any collider but the ego's. The colliders are culled first, with no effect
    /// on the result (issue 23): one that lies out of range, off the plane of a horizontal
    /// channel, or outside the field of view, is skipped for the scan; a beam then casts only at the colliders within its
    /// azimuth's reach whose bounding box (widened by 1 cm) it crosses, and a beam that no
    /// collider can reach is not cast. `beams` must come from one world's scans: it keeps
    /// that world's colliders sorted into fixed and moving, with the fixed ones' boxes (a fixed
    /// collider must not move), and sorts them again when the number of colliders changes or
    /// a fixed one is gone.
    ///
    /// `seen.asleep` lists the colliders taken out of the physics step (NPC cars asleep, their
    /// colliders disabled and left behind) with the pose each would have awake: the scan sees
    /// them there, as the query pipeline would with every car awake.
    pub(crate) fn scan(
        &self,
        seen: &Seen<'_>,
        chassis: &Pose,
        beams: &mut Beams,
        range_m: f64,
        out: &mut Vec<LidarReturn>,
    ) {
        out.clear();
        let mount_local = Vector::new(
            self.mount_m[0] as f32,
            self.mount_m[1] as f32,
            self.mount_m[2] as f32,
        );
        let origin = chassis.transform_point(mount_local);
        let max_toi = range_m as f32;
        let normal = chassis.rotation * Vector::Y;
        let mut scratch = candidates(seen, chassis, beams, origin, max_toi);
        let mut channel_el = f64::NAN;
        for (&(az, el), &local) in beams.directions.iter().zip(&beams.local) {
            if el != channel_el {
                // A horizontal channel's beams span the chassis's x–z plane through the
                // mount; a box that this plane misses is missed by every beam of the channel.
                channel_el = el;
                for c in scratch.iter_mut() {
                    c.in_plane = el != 0.0 || meets_plane(normal, origin, c.mins, c.maxs);
                }
            }
            let seen = |c: &&Candidate<'_>| {
                c.in_plane && c.arcs.iter().any(|&(lo, hi)| lo <= az && az <= hi)
            };
            if !scratch.iter().any(|c| seen(&c)) {
                continue;
            }
            let dir = chassis.rotation * local;
            let ray = Ray::new(origin, dir);
            let inv = dir.recip();
            let mut best: Option<f32> = None;
            for c in scratch.iter().filter(seen) {
                let limit = best.unwrap_or(max_toi);
                if !ray_meets_box(origin, dir, inv, c.mins, c.maxs, limit) {
                    continue;
                }
                if let Some(toi) = c.shape.cast_ray(&c.pose, &ray, limit, true) {
                    best = Some(toi);
                }
            }
            if let Some(toi) = best.filter(|&toi| toi < max_toi) {
                out.push(LidarReturn::hit(az, el, mount_local, local, toi));
            }
        }
    }
}

/// The colliders a scan from `origin` (world, m) out to `max_toi` metres may see, for the
/// chassis at `chassis`: every collider the query pipeline's filter would keep, except those
/// out of range, off the plane of a horizontal channel, or outside the field of view, each
/// with its widened bounding box and the azimuths that can reach it. Sorts `beams`' colliders
/// again when the world's changed ([`Beams::gather`]).
fn candidates<'a>(
    seen: &Seen<'a>,
    chassis: &Pose,
    beams: &mut Beams,
    origin: Vector,
    max_toi: f32,
) -> Vec<Candidate<'a>> {
    let Seen {
        physics,
        own_body,
        asleep,
    } = *seen;
    let normal = chassis.rotation * Vector::Y;
    // Every collider the query pipeline's filter would keep, with its world bounding box,
    // unless it lies beyond the range.
    let mut scratch: Vec<Candidate<'_>> = Vec::new();
    let to_chassis = chassis.rotation.inverse();
    let (by_azimuth, fov, planar) = (beams.by_azimuth, beams.fov, beams.planar);
    let stale = beams.known_colliders != Some(physics.colliders.len())
        || beams.fixed.iter().any(|&(h, ..)| {
            physics
                .colliders
                .get(h)
                .is_none_or(|c| c.parent().is_some())
        });
    if stale {
        beams.gather(physics, own_body);
    }
    let fixed = beams.fixed.iter().filter_map(|&(h, mins, maxs)| {
        let co = &physics.colliders[h];
        co.is_enabled().then(|| (co, *co.position(), mins, maxs))
    });
    let moving = beams.moving.iter().filter_map(|&h| {
        let co = physics.colliders.get(h)?;
        // The query pipeline holds only enabled colliders, and none of a disabled body.
        // An NPC car taken out of the step is seen where it would be awake.
        let enabled = co.is_enabled() && co.parent().is_none_or(|b| physics.bodies[b].is_enabled());
        let pose = if enabled {
            *co.position()
        } else {
            asleep.iter().find(|&&(a, _)| a == h)?.1
        };
        let (mins, maxs) = widened_box(co.shape(), &pose);
        Some((co, pose, mins, maxs))
    });
    for (co, pose, mins, maxs) in fixed.chain(moving) {
        let nearest = origin.clamp(mins, maxs);
        if (nearest - origin).length() > max_toi {
            continue;
        }
        // Every hit within range lies in the cube of half side `max_toi` round the
        // origin: clipping the box to it lets the plane test skip a ground that only
        // meets the channel's plane out of range.
        let reach = Vector::splat(max_toi);
        let (mins, maxs) = (mins.max(origin - reach), maxs.min(origin + reach));
        if planar && !meets_plane(normal, origin, mins, maxs) {
            continue;
        }
        let arcs = if by_azimuth {
            azimuth_arcs(to_chassis * ((mins + maxs) * 0.5 - origin), mins, maxs)
        } else {
            [(-f64::INFINITY, f64::INFINITY), EMPTY_ARC, EMPTY_ARC]
        };
        // A box outside the field of view is seen by no beam.
        if !arcs.iter().any(|&(lo, hi)| lo <= fov.1 && fov.0 <= hi) {
            continue;
        }
        scratch.push(Candidate {
            mins,
            maxs,
            shape: co.shape(),
            pose,
            in_plane: true,
            arcs,
        });
    }
    scratch
}

/// The beam azimuths (rad, chassis frame) that can reach the box `[mins, maxs]` whose centre
/// is at `centre` from the lidar's origin (chassis frame, m): an arc round the centre's
/// azimuth, and the same arc shifted by ∓2π; every azimuth when the origin is inside the
/// box's bounding sphere.
fn azimuth_arcs(centre: Vector, mins: Vector, maxs: Vector) -> [(f64, f64); 3] {
    let mut arcs = [(-f64::INFINITY, f64::INFINITY), EMPTY_ARC, EMPTY_ARC];
    let radius = f64::from((maxs - mins).length() * 0.5);
    let across = f64::from(centre.x).hypot(f64::from(centre.z));
    if across > radius {
        let az = f64::from(-centre.z).atan2(f64::from(centre.x));
        let half = (radius / across).asin() + AZIMUTH_MARGIN_RAD;
        let tau = std::f64::consts::TAU;
        arcs = [
            (az - half, az + half),
            (az - half - tau, az + half - tau),
            (az - half + tau, az + half + tau),
        ];
    }
    arcs
}

/// What a scan sees: the physics world but the scanning vehicle's own body, and the colliders
/// taken out of the physics step, each with the pose it would have awake.
#[derive(Clone, Copy)]
pub(crate) struct Seen<'a> {
    pub(crate) physics: &'a PhysicsWorld,
    pub(crate) own_body: RigidBodyHandle,
    pub(crate) asleep: &'a [(ColliderHandle, Pose)],
}

/// A lidar's beams, computed once: `(azimuth, elevation)` in rad ([`LidarSpec::directions`])
/// and the matching unit vectors in the vehicle frame ([`LidarSpec::local_directions`]); and
/// the widened bounding boxes of the fixed colliders (the road) of the world it scans, by
/// collider index, computed on first use.
pub(crate) struct Beams {
    pub(crate) directions: Vec<(f64, f64)>,
    pub(crate) local: Vec<Vector>,
    /// The fixed colliders (no body: the road) with their widened boxes.
    fixed: Vec<(ColliderHandle, Vector, Vector)>,
    /// The colliders on bodies other than the ego's (actors), boxes computed per scan.
    moving: Vec<ColliderHandle>,
    /// How many colliders the world had when `fixed` and `moving` were gathered.
    known_colliders: Option<usize>,
    /// Whether every beam's elevation is within π/2 of the horizon (less 1 mrad): a beam of
    /// azimuth `az` then meets only points whose azimuth about the mount, in the chassis
    /// frame, is `az`, so a box is seen only by the beams within its angular half-width of
    /// its centre's azimuth.
    by_azimuth: bool,
    /// The smallest and largest beam azimuth, rad.
    fov: (f64, f64),
    /// Whether the lidar has one horizontal channel, so the plane test can drop a box at once.
    planar: bool,
}

impl Beams {
    /// The beams of `spec`.
    pub(crate) fn of(spec: &LidarSpec) -> Self {
        let directions = spec.directions();
        let by_azimuth = directions
            .iter()
            .all(|&(_, el)| el.abs() < std::f64::consts::FRAC_PI_2 - 1e-3);
        let fov = directions
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &(az, _)| {
                (lo.min(az), hi.max(az))
            });
        let planar = directions.iter().all(|&(_, el)| el == 0.0);
        Beams {
            local: LidarSpec::local_directions(&directions),
            directions,
            fixed: Vec::new(),
            moving: Vec::new(),
            known_colliders: None,
            by_azimuth,
            fov,
            planar,
        }
    }

    /// Sorts the colliders a scan may see, all but those of `own_body`, into fixed and moving.
    fn gather(&mut self, physics: &PhysicsWorld, own_body: RigidBodyHandle) {
        self.fixed.clear();
        self.moving.clear();
        for (handle, co) in physics.colliders.iter() {
            match co.parent() {
                None => {
                    let (mins, maxs) = widened_box(co.shape(), co.position());
                    self.fixed.push((handle, mins, maxs));
                }
                Some(body) if body != own_body => self.moving.push(handle),
                Some(_) => {}
            }
        }
        self.known_colliders = Some(physics.colliders.len());
    }
}

/// How far a collider's bounding box is widened before culling beams against it, in metres:
/// far more than the rounding of a ray–box test, so culling never drops a hit.
const CULL_MARGIN_M: f32 = 0.01;

/// A collider a scan may see, with its widened world bounding box (metres).
pub(crate) struct Candidate<'a> {
    mins: Vector,
    maxs: Vector,
    shape: &'a dyn Shape,
    /// Where the shape is: its collider's pose, or the pose an asleep car would have awake.
    pose: Pose,
    /// Whether the current channel's beams can reach the box.
    in_plane: bool,
    /// The beam azimuths (rad, chassis frame) that can reach the box: up to three intervals,
    /// the second and third being the first shifted by ∓2π.
    arcs: [(f64, f64); 3],
}

/// Whether the plane through `origin` with normal `normal` meets the box `[mins, maxs]`: the
/// centre's distance to the plane is within the box's half extent along the normal.
fn meets_plane(normal: Vector, origin: Vector, mins: Vector, maxs: Vector) -> bool {
    let centre = (mins + maxs) * 0.5;
    let half = (maxs - mins) * 0.5;
    normal.dot(centre - origin).abs() <= normal.abs().dot(half)
}

/// The world bounding box of `shape` at `pose`, widened by [`CULL_MARGIN_M`]: `(mins, maxs)` in
/// metres.
fn widened_box(shape: &dyn Shape, pose: &Pose) -> (Vector, Vector) {
    let aabb = shape.compute_aabb(pose);
    let margin = Vector::splat(CULL_MARGIN_M);
    (aabb.mins - margin, aabb.maxs + margin)
}

/// An empty azimuth interval.
const EMPTY_ARC: (f64, f64) = (1.0, 0.0);

/// Slack added to a box's angular half-width, in rad: far more than the rounding of the
/// chassis rotation in `f32`, so culling by azimuth never drops a hit.
const AZIMUTH_MARGIN_RAD: f64 = 1e-3;

/// Whether the ray from `origin` along `dir` (with `inv` its componentwise inverse) meets the
/// box `[mins, maxs]` at a distance in `[0, limit]` (the slab test of Kay and Kajiya, 1986).
/// An axis the ray runs parallel to is checked by position alone, so no infinity or NaN
/// enters the test.
fn ray_meets_box(
    origin: Vector,
    dir: Vector,
    inv: Vector,
    mins: Vector,
    maxs: Vector,
    limit: f32,
) -> bool {
    let (mut near, mut far) = (0.0f32, limit);
    for axis in 0..3 {
        let o = origin[axis];
        if dir[axis] == 0.0 {
            if o < mins[axis] || o > maxs[axis] {
                return false;
            }
            continue;
        }
        let (t1, t2) = ((mins[axis] - o) * inv[axis], (maxs[axis] - o) * inv[axis]);
        let (enter, exit) = if t1 <= t2 { (t1, t2) } else { (t2, t1) };
        if enter > near {
            near = enter;
        }
        if exit < far {
            far = exit;
        }
        if near > far {
            return false;
        }
    }
    true
}

impl<'a> crate::Observation<'a> {
    /// The latest scan of the sensor named `lidar`, in the vehicle frame; empty when no lidar
    /// is mounted ([`crate::SensorSpec::Lidar`]).
    pub fn lidar(&self) -> &'a [LidarReturn] {
        match self.reading("lidar") {
            Some(crate::sensor::Reading::Lidar(returns)) => returns,
            _ => &[],
        }
    }
}

/// The lidar as a [`crate::sensor::Sensor`]: scans at its rate, its range capped by the fog's
/// visibility ([`crate::visibility_m`]); light does not affect it.
pub(crate) struct Lidar {
    spec: LidarSpec,
    beams: Beams,
    period: u64,
    scan: Vec<LidarReturn>,
}

impl Lidar {
    /// A lidar of `spec` on a simulation stepping `dt_s` seconds.
    pub(crate) fn new(spec: &LidarSpec, dt_s: f64) -> Self {
        Lidar {
            beams: Beams::of(spec),
            period: ((1.0 / (spec.rate_hz * dt_s)).round() as u64).max(1),
            spec: spec.clone(),
            scan: Vec::new(),
        }
    }
}

impl crate::sensor::Sensor for Lidar {
    fn name(&self) -> &'static str {
        "lidar"
    }

    fn period_ticks(&self) -> u64 {
        self.period
    }

    fn physics_reach_m(&self) -> f64 {
        // It sees an asleep car where it would be awake (`Scene::asleep`), so no car needs
        // to stay in the physics step for it.
        0.0
    }

    fn recaptures_before_first_step(&self) -> bool {
        // Its scan when mounted was taken before the fog was known.
        true
    }

    fn capture(&mut self, scene: &crate::sensor::Scene<'_>) -> Result<(), crate::EngineError> {
        let pose = *scene.physics.bodies[scene.ego_body].position();
        let range_m = self.spec.range_m.min(crate::visibility_m(scene.fog));
        let seen = Seen {
            physics: scene.physics,
            own_body: scene.ego_body,
            asleep: scene.asleep,
        };
        self.spec
            .scan(&seen, &pose, &mut self.beams, range_m, &mut self.scan);
        Ok(())
    }

    fn reading(&self) -> Option<crate::sensor::Reading<'_>> {
        Some(crate::sensor::Reading::Lidar(&self.scan))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The plain scan issue 23 replaced: every beam through rapier's query pipeline.
    fn reference_scan(
        spec: &LidarSpec,
        physics: &PhysicsWorld,
        chassis: &Pose,
        own: RigidBodyHandle,
        range_m: f64,
    ) -> Vec<LidarReturn> {
        let queries =
            physics.query_pipeline_with_filter(QueryFilter::default().exclude_rigid_body(own));
        let mount = Vector::new(
            spec.mount_m[0] as f32,
            spec.mount_m[1] as f32,
            spec.mount_m[2] as f32,
        );
        let origin = chassis.transform_point(mount);
        let directions = spec.directions();
        let beams = LidarSpec::local_directions(&directions);
        let mut out = Vec::new();
        for (&(az, el), &local) in directions.iter().zip(&beams) {
            let ray = Ray::new(origin, chassis.rotation * local);
            if let Some((_, toi)) = queries.cast_ray(&ray, range_m as f32, true) {
                out.push(LidarReturn::hit(az, el, mount, local, toi));
            }
        }
        out
    }

    /// The culled scan returns exactly what the query pipeline returns, beam for beam, bit for
    /// bit: random worlds of boxes, capsules, cylinders, balls and convex hulls round a
    /// chassis pitched, rolled and turned at random, for a planar lidar, a 3-channel one and
    /// a 360° one (azimuths wrapping round ±π).
    #[test]
    fn culling_changes_no_return() {
        use rand::{Rng, SeedableRng};
        let specs = [
            LidarSpec::default(),
            LidarSpec {
                channels: 3,
                beams: 31,
                vertical_fov_rad: 0.4,
                ..LidarSpec::default()
            },
            LidarSpec {
                beams: 90,
                horizontal_fov_rad: std::f64::consts::TAU,
                range_m: 25.0,
                ..LidarSpec::default()
            },
        ];
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(23);
        let (mut returns, mut cases) = (0, 0);
        for world in 0..60 {
            let mut physics = PhysicsWorld::new();
            // Ground and road slabs, as the network builds them.
            physics.insert_collider(
                ColliderBuilder::cuboid(150.0, 0.5, 60.0).translation(Vector::new(0.0, -0.52, 0.0)),
                None,
            );
            physics.insert_collider(
                ColliderBuilder::cuboid(100.0, 0.1, 3.5).translation(Vector::new(0.0, -0.1, 0.0)),
                None,
            );
            let mut coord = |r: f32| rng.random_range(-r..r);
            for _ in 0..12 {
                let at = Vector::new(coord(40.0), coord(1.5) + 0.5, coord(15.0));
                let rot =
                    Rotation::from_rotation_y(coord(3.0)) * Rotation::from_rotation_x(coord(0.3));
                let builder = match world % 5 {
                    0 => ColliderBuilder::cuboid(1.0 + coord(0.8), 0.8, 2.0 + coord(1.5)),
                    1 => ColliderBuilder::capsule_y(0.6, 0.3),
                    2 => ColliderBuilder::cylinder(0.4, 3.0),
                    3 => ColliderBuilder::ball(0.7),
                    _ => ColliderBuilder::convex_hull(&[
                        Vector::new(0.0, 0.0, 0.0),
                        Vector::new(2.0, 0.0, 0.3),
                        Vector::new(0.4, 1.5, 0.0),
                        Vector::new(0.3, 0.2, 1.8),
                    ])
                    .unwrap(),
                };
                // Half the actors move (kinematic bodies), half are fixed.
                if coord(1.0) > 0.0 {
                    let body = physics.bodies.insert(
                        RigidBodyBuilder::kinematic_position_based()
                            .pose(Pose::from_parts(at, rot)),
                    );
                    physics.insert_collider(builder, Some(body));
                } else {
                    physics.insert_collider(builder.position(Pose::from_parts(at, rot)), None);
                }
            }
            let chassis_pose = Pose::from_parts(
                Vector::new(coord(5.0), 0.9 + coord(0.3), coord(2.0)),
                Rotation::from_rotation_y(coord(3.2))
                    * Rotation::from_rotation_z(coord(0.05))
                    * Rotation::from_rotation_x(coord(0.05)),
            );
            let own = physics
                .bodies
                .insert(RigidBodyBuilder::kinematic_position_based().pose(chassis_pose));
            physics.insert_collider(ColliderBuilder::cuboid(2.25, 0.5, 0.9), Some(own));
            physics.step();
            let mut beams: Vec<Beams> = specs.iter().map(Beams::of).collect();
            // Two scans per lidar, the actors moved between them: the second reuses the
            // fixed colliders' boxes gathered by the first.
            for scan in 0..2 {
                if scan == 1 {
                    let shift = Vector::new(coord(3.0), 0.0, coord(3.0));
                    for (h, body) in physics.bodies.iter_mut() {
                        if h != own && body.is_kinematic() {
                            let to = body.translation() + shift;
                            body.set_next_kinematic_translation(to);
                        }
                    }
                    physics.step();
                }
                let chassis = *physics.bodies[own].position();
                for (spec, beams) in specs.iter().zip(&mut beams) {
                    let mut fast = Vec::new();
                    let seen = Seen {
                        physics: &physics,
                        own_body: own,
                        asleep: &[],
                    };
                    spec.scan(&seen, &chassis, beams, spec.range_m, &mut fast);
                    let plain = reference_scan(spec, &physics, &chassis, own, spec.range_m);
                    assert_eq!(fast, plain, "world {world}, scan {scan}");
                    returns += plain.len();
                    cases += 1;
                }
            }
        }
        // The worlds are not empty: many beams hit something.
        assert!(returns > 20 * cases, "{returns} returns in {cases} scans");
    }

    #[test]
    fn directions_span_the_field_of_view() {
        let spec = LidarSpec {
            channels: 3,
            beams: 5,
            horizontal_fov_rad: 1.0,
            vertical_fov_rad: 0.2,
            ..LidarSpec::default()
        };
        let d = spec.directions();
        assert_eq!(d.len(), 15);
        assert_eq!(d[0], (-0.5, -0.1));
        assert_eq!(d[4], (0.5, -0.1));
        assert_eq!(d[7], (0.0, 0.0));
        assert_eq!(LidarSpec::default().directions()[60], (0.0, 0.0));
    }
}
