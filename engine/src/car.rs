use rapier3d::prelude::*;
use serde::Serialize;

/// Height of an NPC car's body above the road, in metres.
pub(crate) const CLEARANCE_M: f64 = 0.2;

/// An NPC car's observable state.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct CarState {
    /// Ground point under the centre `[x, y, z]`, metres.
    pub pos_m: [f64; 3],
    /// Heading in rad.
    pub heading_rad: f64,
    /// Speed along the path in m/s.
    pub speed_mps: f64,
    /// Whether it is in this test.
    pub enabled: bool,
}

/// A kinematic NPC car following a polyline at a commanded speed. Solid: the ego vehicle
/// collides with it physically, and the lidar sees it.
pub(crate) struct Car {
    pub(crate) body: Option<(RigidBodyHandle, ColliderHandle)>,
    path: Vec<[f64; 2]>,
    cumulative: Vec<f64>,
    s: f64,
    speed: f64,
    half_height: f64,
    /// Half length and half width, metres.
    pub(crate) half_size_m: [f64; 2],
}

impl Car {
    pub(crate) fn build(
        physics: &mut PhysicsWorld,
        path: Vec<[f64; 2]>,
        size_m: [f64; 3],
        enabled: bool,
    ) -> Self {
        let mut cumulative = vec![0.0];
        for w in path.windows(2) {
            let last = *cumulative.last().expect("non-empty");
            cumulative.push(last + (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]));
        }
        let mut car = Car {
            body: None,
            path,
            cumulative,
            s: 0.0,
            speed: 0.0,
            half_height: size_m[1] / 2.0,
            half_size_m: [size_m[0] / 2.0, size_m[2] / 2.0],
        };
        if enabled {
            let pose = car.pose();
            let body = RigidBodyBuilder::kinematic_position_based().pose(pose);
            let [l, h, w] = size_m.map(|v| (v / 2.0) as f32);
            let collider =
                ColliderBuilder::cuboid(l, h, w).active_events(ActiveEvents::COLLISION_EVENTS);
            car.body = Some(physics.insert(body, collider));
        }
        car
    }

    /// Position `[x, z]` and heading at arc length `s`.
    fn at(&self, s: f64) -> ([f64; 2], f64) {
        let i = self
            .cumulative
            .partition_point(|&c| c <= s)
            .clamp(1, self.path.len() - 1);
        let (a, b) = (self.path[i - 1], self.path[i]);
        let len = self.cumulative[i] - self.cumulative[i - 1];
        let u = if len > 0.0 {
            ((s - self.cumulative[i - 1]) / len).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let heading = (-(b[1] - a[1])).atan2(b[0] - a[0]);
        (
            [a[0] + u * (b[0] - a[0]), a[1] + u * (b[1] - a[1])],
            heading,
        )
    }

    fn pose(&self) -> Pose {
        let ([x, z], h) = self.at(self.s);
        Pose::from_parts(
            Vector::new(x as f32, (CLEARANCE_M + self.half_height) as f32, z as f32),
            Rotation::from_rotation_y(h as f32),
        )
    }

    /// Drives `speed_mps · dt_s` metres further (not past the path's end).
    pub(crate) fn advance(&mut self, physics: &mut PhysicsWorld, speed_mps: f64, dt_s: f64) {
        let end = *self.cumulative.last().expect("non-empty");
        let before = self.s;
        self.s = (self.s + speed_mps.max(0.0) * dt_s).min(end);
        self.speed = (self.s - before) / dt_s;
        if let Some((body, _)) = self.body {
            let pose = self.pose();
            physics.bodies[body].set_next_kinematic_position(pose);
        }
    }

    /// The car as the time-to-collision test sees it, `None` when it is not in this test.
    pub(crate) fn mover(&self) -> Option<crate::ttc::Mover> {
        self.body?;
        let ([x, z], heading_rad) = self.at(self.s);
        Some(crate::ttc::Mover {
            pos_m: [x, z],
            velocity_mps: [
                self.speed * heading_rad.cos(),
                -self.speed * heading_rad.sin(),
            ],
            heading_rad,
            half_size_m: self.half_size_m,
        })
    }

    pub(crate) fn state(&self) -> CarState {
        let ([x, z], heading_rad) = self.at(self.s);
        CarState {
            pos_m: [x, 0.0, z],
            heading_rad,
            speed_mps: self.speed,
            enabled: self.body.is_some(),
        }
    }
}
