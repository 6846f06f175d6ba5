use rapier3d::control::{DynamicRayCastVehicleController, WheelTuning};
use rapier3d::prelude::*;
use serde::{Deserialize, Serialize};

use crate::Control;

/// Mass, size and actuator limits of the ego vehicle. Defaults are a mid-size car.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct VehicleParams {
    /// Mass in kg. Default 1500.
    pub mass_kg: f64,
    /// Body size. Default 4.5 × 1.8 × 1.0 m.
    pub size: crate::Size,
    /// Wheel radius in metres. Default 0.35.
    pub wheel_radius_m: f64,
    /// Engine force at full throttle per driven (rear) wheel, in N. Default 2250 N, i.e.
    /// 3 m/s² on a 1500 kg car.
    pub max_engine_force_n: f64,
    /// Brake force at full brake per wheel on average, in N: the four wheels brake with four
    /// times this together, shared among them in proportion to the load each carries (as
    /// electronic brake-force distribution does). Default 3000 N, i.e. 8 m/s² on a 1500 kg
    /// car. Each wheel's share is capped by its tyre's grip, `μ·N` (road friction times the
    /// wheel's load), so on a road of friction `μ < 0.82` full braking gives `μ·g`.
    pub max_brake_force_n: f64,
    /// Front-wheel angle at full steering, in rad. Default 0.5 rad (about 29°).
    pub max_steer_rad: f64,
}

/// The body sizes the ego vehicle model is made for, m, each `[least, most]`: length
/// (its wheels sit 0.8 m inside each end, so a shorter body has no wheelbase), width (the
/// wheels 0.1 m inside each side) and height (a body taller than the chassis rides high is
/// raised so that it clears the road by [`GROUND_CLEARANCE_M`]). From a small city car to an
/// articulated truck's length; beyond them the ray-cast vehicle is no model of the vehicle.
pub const EGO_SIZE_RANGE_M: [[f64; 2]; 3] = [[2.5, 25.0], [1.0, 3.5], [0.5, 5.0]];

/// The least distance between the ego vehicle's body and the road at rest, m (the default
/// body rides 0.4 m above it). A body closer to the road mesh makes rapier test the two for
/// contact at every step: 0.1 m made the ALKS crossing pedestrian's campaign, whose ego is
/// 1.8 m tall, 1.7 times slower.
pub const GROUND_CLEARANCE_M: f64 = 0.3;

impl VehicleParams {
    /// Whether `size` is in [`EGO_SIZE_RANGE_M`].
    ///
    /// # Errors
    /// [`crate::EngineError::InvalidWorld`] naming the side out of range and the range, for
    /// example "the ego vehicle's length 30 m is outside the vehicle model's range
    /// [2.5, 25] m".
    pub fn check_size(size: &crate::Size) -> Result<(), crate::EngineError> {
        let sides = [
            ("length", size.length_m),
            ("width", size.width_m),
            ("height", size.height_m),
        ];
        for ((side, v), [lo, hi]) in sides.into_iter().zip(EGO_SIZE_RANGE_M) {
            if !(v >= lo && v <= hi) {
                return Err(crate::EngineError::InvalidWorld(format!(
                    "the ego vehicle's {side} {v} m is outside the vehicle model's range \
                     [{lo}, {hi}] m"
                )));
            }
        }
        Ok(())
    }
}

impl Default for VehicleParams {
    fn default() -> Self {
        VehicleParams {
            mass_kg: 1500.0,
            size: crate::Size {
                length_m: 4.5,
                width_m: 1.8,
                height_m: 1.0,
            },
            wheel_radius_m: 0.35,
            max_engine_force_n: 2250.0,
            max_brake_force_n: 3000.0,
            max_steer_rad: 0.5,
        }
    }
}

/// Suspension rest length in metres.
const SUSPENSION_REST_M: f32 = 0.3;
/// Height of the wheels' hard points below the chassis centre, in metres.
const HARD_POINT_DROP_M: f32 = 0.3;

/// The ego vehicle: a dynamic box chassis carried by rapier's
/// `DynamicRayCastVehicleController` on four ray-cast wheels (front steered, rear driven,
/// all braked). Forward is the chassis' local `+x`, up its `+y`.
pub(crate) struct EgoVehicle {
    pub(crate) body: RigidBodyHandle,
    pub(crate) collider: ColliderHandle,
    controller: DynamicRayCastVehicleController,
    params: VehicleParams,
    /// The engine force the last control asked of each wheel (N), and the brake impulse it
    /// asked of the four together (N·s), before [`EgoVehicle::hold_to_grip`] shares and caps
    /// them.
    asked: ([f32; 4], f32),
    /// Whether a script places it ([`crate::EgoSpec::scripted`]): a kinematic chassis that
    /// neither the controller nor the physics moves.
    pub(crate) scripted: bool,
    /// How far above the ground its chassis' centre rides, m (as built, at rest).
    ride_m: f32,
}

impl EgoVehicle {
    /// Builds the vehicle with its wheels on the ground at `pos` (surface point, metres),
    /// heading `heading_rad`, moving forward at `speed_mps`; `scripted`: a kinematic chassis
    /// that [`EgoVehicle::place`] moves, whose contacts with the other kinematic actors
    /// (pedestrians, NPC cars, obstacles) are detected as a dynamic chassis' are.
    pub(crate) fn build(
        physics: &mut PhysicsWorld,
        params: &VehicleParams,
        (pos, heading_rad, speed_mps): ([f64; 3], f64, f64),
        friction: f64,
        scripted: bool,
    ) -> Self {
        let (len, wid, hei) = (
            params.size.length_m as f32,
            params.size.width_m as f32,
            params.size.height_m as f32,
        );
        let radius = params.wheel_radius_m as f32;
        // Chassis centre so that the wheels rest with a little compression at the start.
        let ride_m = radius + SUSPENSION_REST_M + HARD_POINT_DROP_M - 0.05;
        let y = pos[1] as f32 + ride_m;
        let rotation = Rotation::from_rotation_y(heading_rad as f32);
        let forward = rotation * Vector::X;
        let body = if scripted {
            RigidBodyBuilder::kinematic_position_based()
        } else {
            RigidBodyBuilder::dynamic()
        };
        let body = body
            .pose(Pose::from_parts(
                Vector::new(pos[0] as f32, y, pos[2] as f32),
                rotation,
            ))
            .linvel(forward * speed_mps as f32)
            .linear_damping(0.02)
            .can_sleep(false);
        // A body taller than the chassis rides high is raised to clear the road; the default
        // body (1 m) sits 0.4 m above it, centred on the chassis.
        let lift = (hei / 2.0 - (ride_m - GROUND_CLEARANCE_M as f32)).max(0.0);
        let mut collider = ColliderBuilder::cuboid(len / 2.0, hei / 2.0, wid / 2.0);
        if lift > 0.0 {
            // (Only then: a body that needs none is built as it always was, bit for bit.)
            collider = collider.translation(Vector::new(0.0, lift, 0.0));
        }
        let collider = collider
            .mass(params.mass_kg as f32)
            .active_events(ActiveEvents::COLLISION_EVENTS)
            .active_collision_types(
                ActiveCollisionTypes::default() | ActiveCollisionTypes::KINEMATIC_KINEMATIC,
            );
        let (body, collider) = physics.insert(body, collider);

        // Suspension stiffness and damping are per unit of chassis mass in rapier's model
        // (force = mass · (k · compression - c · velocity)): k = 30 gives ~8 cm static
        // compression, c ≈ 2.5–3 about half critical damping.
        let tuning = WheelTuning {
            suspension_stiffness: 30.0,
            suspension_compression: 2.5,
            suspension_damping: 3.0,
            max_suspension_travel: 0.25,
            side_friction_stiffness: 1.0,
            friction_slip: friction as f32,
            max_suspension_force: (params.mass_kg * 9.81 * 2.0) as f32,
        };
        let mut controller = DynamicRayCastVehicleController::new(body);
        let (ax, az) = (len / 2.0 - 0.8, wid / 2.0 - 0.1);
        for (x, z) in [(ax, az), (ax, -az), (-ax, az), (-ax, -az)] {
            controller.add_wheel(
                Vector::new(x, -HARD_POINT_DROP_M, z),
                -Vector::Y,
                Vector::Z,
                SUSPENSION_REST_M,
                radius,
                &tuning,
            );
        }
        EgoVehicle {
            body,
            collider,
            controller,
            params: params.clone(),
            asked: ([0.0; 4], 0.0),
            scripted,
            ride_m,
        }
    }

    /// Puts a scripted vehicle's chassis at the end of this step where its footprint's
    /// centre on the ground is `pos` (m) and it faces `heading_rad` (yaw only), at the height
    /// it was built to ride at. rapier gives it the velocity of that move.
    pub(crate) fn place(&self, physics: &mut PhysicsWorld, pos: [f64; 3], heading_rad: f64) {
        let pose = Pose::from_parts(
            Vector::new(pos[0] as f32, pos[1] as f32 + self.ride_m, pos[2] as f32),
            Rotation::from_rotation_y(heading_rad as f32),
        );
        physics.bodies[self.body].set_next_kinematic_position(pose);
    }

    /// Hands a scripted vehicle to its controls ([`crate::Action::ReleaseEgo`]): its chassis
    /// becomes a dynamic body moving at `velocity_mps` (m/s, world frame), which the vehicle
    /// model drives from the next step on, turning at `angvel` (rad/s) when the last step
    /// moved it without rapier's solver (else at the rate rapier's step gave its body). A
    /// vehicle no script places is left as it is.
    pub(crate) fn release(
        &mut self,
        physics: &mut PhysicsWorld,
        velocity_mps: [f64; 3],
        angvel: Option<AngVector>,
    ) {
        if !self.scripted {
            return;
        }
        let body = &mut physics.bodies[self.body];
        body.set_body_type(RigidBodyType::Dynamic, true);
        if let Some(w) = angvel {
            body.set_angvel(w, true);
        }
        body.set_linvel(
            Vector::new(
                velocity_mps[0] as f32,
                velocity_mps[1] as f32,
                velocity_mps[2] as f32,
            ),
            true,
        );
        self.scripted = false;
    }

    /// Sets engine, brake and steering from `control` (clamped), as documented on [`Control`].
    /// rapier's `brake` is an impulse per step, hence the factor `dt`.
    pub(crate) fn apply(&mut self, control: Control, dt_s: f64) {
        let c = control.clamped();
        let engine = (c.throttle.max(0.0) * self.params.max_engine_force_n) as f32;
        let brake = ((-c.throttle).max(0.0) * self.params.max_brake_force_n * dt_s) as f32;
        let steer = (c.steering * self.params.max_steer_rad) as f32;
        for (i, wheel) in self.controller.wheels_mut().iter_mut().enumerate() {
            let front = i < 2;
            wheel.steering = if front { steer } else { 0.0 };
            wheel.engine_force = if front { 0.0 } else { engine };
            wheel.brake = brake;
            self.asked.0[i] = wheel.engine_force;
        }
        self.asked.1 = 4.0 * brake;
    }

    /// Shares the brake among the wheels and holds each wheel's engine force and brake to
    /// what its tyre can pass to the road.
    ///
    /// The brake impulse asked of the four wheels goes to each in proportion to its load `N`:
    /// its suspension force over the last step, N (0 for a wheel off the ground, which grips
    /// nothing; the static share `m·g/4` before the first step). Then each wheel's
    /// longitudinal force is at most `μ·N`, with `μ` the wheel's friction: full braking or
    /// pulling on a road of friction `μ` accelerates at most `μ·g` (LANGUAGE.md, "friction").
    /// Combined with a side force `S`, rapier's own limit `(F/2)² + S² <= (μ·N)²` then scales
    /// both down together, so a tyre sliding sideways still brakes; the total may reach
    /// `1.32·μ·N` (at `F = μ·N`), where Coulomb's circle would stop at `μ·N`.
    ///
    /// rapier's `DynamicRayCastVehicleController` alone limits only
    /// `(F/2)² + S² <= (friction_slip·N)²` (Bullet's `fwdFactor = 0.5`), which let a tyre
    /// brake or pull with twice `friction_slip·N`: full braking on ice (`μ = 0.1`) stopped from
    /// 12 m/s in 34 m, at 2.1 m/s² instead of 0.98.
    fn hold_to_grip(&mut self, dt_s: f32) {
        let first_step = self.controller.wheels().iter().all(|w| {
            w.wheel_suspension_force == 0.0 && w.forward_impulse == 0.0 && w.side_impulse == 0.0
        });
        let static_n = (self.params.mass_kg * 9.81 / 4.0) as f32;
        let load = |w: &rapier3d::control::Wheel| {
            if first_step {
                static_n
            } else {
                w.wheel_suspension_force.max(0.0)
            }
        };
        let total_n: f32 = self.controller.wheels().iter().map(load).sum();
        let (engine, brake) = self.asked;
        for (wheel, engine) in self.controller.wheels_mut().iter_mut().zip(engine) {
            let n = load(wheel);
            let grip_n = wheel.friction_slip * n;
            let share = if total_n > 0.0 { n / total_n } else { 0.0 };
            wheel.engine_force = engine.clamp(-grip_n, grip_n);
            wheel.brake = (brake * share).min(grip_n * dt_s);
        }
    }

    /// Sets each wheel's tyre friction (rapier's per-wheel `friction_slip`) to the friction of
    /// the surface under its hard point now: the road piece there, or the ground
    /// ([`crate::network::GROUND_FRICTION`]) off the network. Called at the start of every
    /// step, so a wheel that crossed onto another piece grips with that piece's friction in
    /// the very next step.
    pub(crate) fn grip(&mut self, physics: &PhysicsWorld, surface: &crate::network::Surface) {
        let chassis = *physics.bodies[self.body].position();
        for wheel in self.controller.wheels_mut() {
            let p = chassis.transform_point(wheel.chassis_connection_point_cs);
            wheel.friction_slip = surface.friction_at([f64::from(p.x), f64::from(p.z)]) as f32;
        }
    }

    /// Each wheel's tyre friction coefficient as set by the last [`EgoVehicle::grip`], in the
    /// order front right, front left, rear right, rear left (`+z` is right of the driver).
    pub(crate) fn wheel_frictions(&self) -> Vec<f64> {
        self.controller
            .wheels()
            .iter()
            .map(|w| f64::from(w.friction_slip))
            .collect()
    }

    /// Runs the controller's suspension and tyre model for one step; call before the physics
    /// step. The wheels' rays see only fixed colliders (the road), never actors or sensors.
    pub(crate) fn update(&mut self, physics: &mut PhysicsWorld, dt_s: f64) {
        let queries = physics.broad_phase.as_query_pipeline_mut(
            physics.narrow_phase.query_dispatcher(),
            &mut physics.bodies,
            &mut physics.colliders,
            QueryFilter::only_fixed().exclude_sensors(),
        );
        self.hold_to_grip(dt_s as f32);
        self.controller.update_vehicle(dt_s as f32, queries);
    }

    /// The size of the body.
    pub(crate) fn size(&self) -> crate::Size {
        self.params.size
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn control_maps_to_engine_brake_and_steering_within_limits() {
        let mut physics = PhysicsWorld::new();
        let params = VehicleParams::default();
        let mut v = EgoVehicle::build(
            &mut physics,
            &params,
            ([0.0, 0.0, 0.0], 0.0, 0.0),
            0.8,
            false,
        );
        let dt = 1.0 / 60.0;
        v.apply(
            Control {
                throttle: 0.5,
                steering: -2.0,
            },
            dt,
        );
        let w = v.controller.wheels();
        assert_eq!(w.len(), 4);
        assert_eq!(w[0].steering, -0.5); // clamped to -1, times 0.5 rad
        assert_eq!(w[2].steering, 0.0);
        assert_eq!(w[0].engine_force, 0.0); // front wheels are not driven
        assert_eq!(w[2].engine_force, 1125.0);
        assert!(w.iter().all(|w| w.brake == 0.0));

        v.apply(
            Control {
                throttle: -1.0,
                steering: 0.0,
            },
            dt,
        );
        let w = v.controller.wheels();
        assert!(w.iter().all(|w| w.engine_force == 0.0));
        // 3000 N for one step of 1/60 s is an impulse of 50 N·s per wheel.
        assert!(w.iter().all(|w| (w.brake - 50.0).abs() < 1e-3));
    }
}
