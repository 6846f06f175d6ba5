//! The ego vehicle as the step loop keeps it: its vehicle model, what its system under test is
//! asked (a route, a set speed), whether it has collided, and its velocity measured over the
//! last step; and a storyboard's actions on it.

use rapier3d::prelude::*;
use serde::Serialize;

use crate::actor::{half_open, Motion};
use crate::behaviour::{bad_input, placed_pose, Action, POSE_EXPECTED};
use crate::control::Control;
use crate::network::Surface;
use crate::physics_step::KinematicVelocity;
use crate::rx::Value;
use crate::vehicle::EgoVehicle;
use crate::EngineError;

/// The ego vehicle's state.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct EgoState {
    /// Chassis centre `[x, y, z]` in metres.
    pub pos_m: [f64; 3],
    /// Heading in rad, counter-clockwise seen from above, `0` along `+x`, in `(-π, π]`.
    pub heading_rad: f64,
    /// Signed speed along the heading in m/s (negative when reversing).
    pub speed_mps: f64,
}

/// The ego vehicle in a running world.
pub(crate) struct Ego {
    /// Its vehicle model (a rapier body on the ray-cast vehicle controller).
    pub(crate) vehicle: EgoVehicle,
    /// The route its system under test follows, world `[x, z]` m ([`crate::EgoSpec::route`],
    /// or a storyboard's).
    pub(crate) route: Vec<[f64; 2]>,
    /// The speed its system under test is asked to keep, m/s ([`crate::EgoSpec::set_speed_mps`]).
    pub(crate) set_speed_mps: Option<f64>,
    /// Whether it has touched anything since the test began.
    pub(crate) collided: bool,
    /// Its velocity over the last step, m/s: its chassis centre's move over the step's length
    /// (rapier integrates the position over substeps, so the body's final `linvel` differs
    /// from the move by up to 0.06 m/s while the suspension settles); before the first step,
    /// its body's velocity.
    pub(crate) velocity: [f64; 3],
    /// Its body's velocity when the last step moved it without rapier's solver (a scripted
    /// ego in a world of kinematic bodies, [`crate::physics_step::Moved`]); `None` when its
    /// body carries its own.
    pub(crate) kinematic: Option<KinematicVelocity>,
}

impl Ego {
    /// The ego of `vehicle`, with its system under test's route and set speed, its velocity
    /// its body's in `physics`.
    pub(crate) fn new(
        vehicle: EgoVehicle,
        physics: &PhysicsWorld,
        route: Vec<[f64; 2]>,
        set_speed_mps: Option<f64>,
    ) -> Self {
        let v = physics.bodies[vehicle.body].linvel();
        Ego {
            vehicle,
            route,
            set_speed_mps,
            collided: false,
            velocity: [v.x, v.y, v.z].map(f64::from),
            kinematic: None,
        }
    }

    /// Its state now.
    pub(crate) fn state(&self, physics: &PhysicsWorld) -> EgoState {
        let body = &physics.bodies[self.vehicle.body];
        let p = body.translation();
        let forward = *body.rotation() * Vector::X;
        EgoState {
            pos_m: [p.x, p.y, p.z].map(f64::from),
            heading_rad: half_open(f64::from(-forward.z).atan2(f64::from(forward.x))),
            speed_mps: f64::from(
                self.kinematic
                    .map_or(body.linvel(), |k| k.linvel)
                    .dot(forward),
            ),
        }
    }

    /// Its motion as a program reads it: its speed is the size of its measured velocity,
    /// negative when it moves backwards.
    pub(crate) fn motion(&self, physics: &PhysicsWorld) -> Motion {
        let s = self.state(physics);
        let vel = self.velocity;
        let norm = vel[0].hypot(vel[1]).hypot(vel[2]);
        Motion {
            pos_m: s.pos_m,
            vel_mps: vel,
            heading_rad: s.heading_rad,
            speed_mps: if s.speed_mps < 0.0 { -norm } else { norm },
        }
    }

    /// Its chassis position now, m.
    pub(crate) fn position(&self, physics: &PhysicsWorld) -> [f64; 3] {
        let p = physics.bodies[self.vehicle.body].translation();
        [p.x, p.y, p.z].map(f64::from)
    }

    /// Drives the vehicle model one step of `dt_s` under its system's `control`, each wheel
    /// gripping the piece under it; a scripted ego is not driven.
    pub(crate) fn drive(
        &mut self,
        control: Control,
        physics: &mut PhysicsWorld,
        surface: &Surface,
        dt_s: f64,
    ) {
        if self.vehicle.scripted {
            return;
        }
        self.vehicle.apply(control, dt_s);
        self.vehicle.grip(physics, surface);
        self.vehicle.update(physics, dt_s);
    }

    /// Measures its velocity over a step of `dt_s` that began at `before` (its chassis
    /// position then, m).
    pub(crate) fn measure(&mut self, before: [f64; 3], physics: &PhysicsWorld, dt_s: f64) {
        let after = self.position(physics);
        self.velocity = [0, 1, 2].map(|i| (after[i] - before[i]) / dt_s);
    }

    /// Performs a storyboard's action on the ego at time `t` (s): a pose for a scripted ego,
    /// a route or a set speed for its system under test, the hand-over to that system.
    ///
    /// # Errors
    /// [`crate::rx::RxError::Input`] for a value the action cannot take (a pose or route that
    /// is not a tuple of finite numbers, a negative set speed), or a pose for an ego the system
    /// under test drives.
    pub(crate) fn act(
        &mut self,
        action: Action,
        value: &Value,
        physics: &mut PhysicsWorld,
        t: f64,
    ) -> Result<(), EngineError> {
        let bad = |name: &str, expected: &str| bad_input(t, name.into(), value, expected);
        match action {
            Action::PlaceEgo => {
                let pose = placed_pose(value)
                    .ok_or_else(|| bad("the pose given to the ego", POSE_EXPECTED))?;
                if !self.vehicle.scripted {
                    return Err(bad(
                        "a pose given to the ego, which the system under test drives \
                         (EgoSpec::scripted is not set)",
                        "no pose",
                    ));
                }
                self.vehicle.place(physics, pose.0, pose.1);
            }
            Action::SetEgoRoute => {
                let points: Option<Vec<[f64; 2]>> = match value {
                    Value::Tuple(items) if items.len() >= 2 => items
                        .iter()
                        .map(|v| match v {
                            Value::Vec3(p) if p[0].is_finite() && p[2].is_finite() => {
                                Some([p[0], p[2]])
                            }
                            _ => None,
                        })
                        .collect(),
                    _ => None,
                };
                let Some(points) = points else {
                    return Err(bad(
                        "the route given to the ego's system under test",
                        "a tuple of two or more Vec3 [x, y, z] points of finite numbers (m)",
                    ));
                };
                self.route = points;
            }
            Action::ReleaseEgo => {
                let v = self.velocity;
                let angvel = self.kinematic.map(|k| k.angvel);
                self.vehicle.release(physics, [v[0], 0.0, v[2]], angvel);
            }
            Action::SetEgoSpeed => match value {
                Value::Num(v) if v.is_finite() && *v >= 0.0 => self.set_speed_mps = Some(*v),
                _ => {
                    return Err(bad(
                        "the set speed given to the ego's system under test",
                        "a finite number >= 0 (m/s)",
                    ))
                }
            },
            _ => {}
        }
        Ok(())
    }
}
