use rapier3d::prelude::*;
use serde::{Deserialize, Serialize};

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
    /// Vertical field of view in rad, `>= 0`. Default 0 (one horizontal plane).
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
    pub(crate) fn validate(&self) -> Result<(), String> {
        if self.channels == 0 || self.beams == 0 {
            return Err("lidar needs at least one channel and one beam".into());
        }
        let ok = |v: f64| v.is_finite() && v > 0.0;
        if !ok(self.range_m) || !ok(self.rate_hz) || !ok(self.horizontal_fov_rad) {
            return Err("lidar range, rate and horizontal field of view must be positive".into());
        }
        Ok(())
    }

    /// Casts every beam from the mount of the chassis at `chassis` (pose), ignoring the
    /// vehicle's own body, out to `range_m` metres (the spec's range, or less in fog). Sees fixed geometry and actors, including sensor colliders
    /// (pedestrians).
    pub(crate) fn scan(
        &self,
        physics: &PhysicsWorld,
        chassis: &Pose,
        own_body: RigidBodyHandle,
        directions: &[(f64, f64)],
        range_m: f64,
        out: &mut Vec<LidarReturn>,
    ) {
        out.clear();
        let filter = QueryFilter::default().exclude_rigid_body(own_body);
        let queries = physics.query_pipeline_with_filter(filter);
        let mount_local = Vector::new(
            self.mount_m[0] as f32,
            self.mount_m[1] as f32,
            self.mount_m[2] as f32,
        );
        let origin = chassis.transform_point(mount_local);
        for &(az, el) in directions {
            // Vehicle frame: x forward, y up, z right, so a positive (left) azimuth is -z.
            let local = Vector::new(
                (el.cos() * az.cos()) as f32,
                el.sin() as f32,
                -(el.cos() * az.sin()) as f32,
            );
            let ray = Ray::new(origin, chassis.rotation * local);
            if let Some((_, toi)) = queries.cast_ray(&ray, range_m as f32, true) {
                let p = mount_local + local * toi;
                out.push(LidarReturn {
                    azimuth_rad: az,
                    elevation_rad: el,
                    range_m: f64::from(toi),
                    point_m: [f64::from(p.x), f64::from(p.y), f64::from(p.z)],
                });
            }
        }
    }
}

/// The lidar as a [`crate::sensor::Sensor`]: scans at its rate, its range capped by the fog's
/// visibility ([`crate::visibility_m`]); light does not affect it.
pub(crate) struct Lidar {
    spec: LidarSpec,
    directions: Vec<(f64, f64)>,
    period: u64,
    scan: Vec<LidarReturn>,
}

impl Lidar {
    /// A lidar of `spec` on a simulation stepping `dt_s` seconds.
    pub(crate) fn new(spec: &LidarSpec, dt_s: f64) -> Self {
        Lidar {
            directions: spec.directions(),
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

    fn capture(&mut self, scene: &crate::sensor::Scene<'_>) -> Result<(), crate::EngineError> {
        let pose = *scene.physics.bodies[scene.ego_body].position();
        let range_m = self.spec.range_m.min(crate::visibility_m(scene.fog));
        self.spec.scan(
            scene.physics,
            &pose,
            scene.ego_body,
            &self.directions,
            range_m,
            &mut self.scan,
        );
        Ok(())
    }

    fn reading(&self) -> Option<crate::sensor::Reading<'_>> {
        Some(crate::sensor::Reading::Lidar(&self.scan))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
