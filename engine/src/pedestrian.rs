use rapier3d::prelude::*;
use serde::Serialize;

use crate::actor::{half_open, ActorKind, Contact, Motion, StepWorld, VisibleBox};
use crate::behaviour::{bad_input, placed_pose, Action, ActorRef, POSE_EXPECTED};
use crate::contact::Solids;
use crate::rx::{number, Graph, Input, Value};
use crate::{EngineError, PedestrianSpec};

/// Capsule radius of a pedestrian, in metres.
pub(crate) const PED_RADIUS_M: f32 = 0.3;
/// Half-height of the capsule's cylinder, in metres (total height 1.8 m).
pub(crate) const PED_HALF_HEIGHT_M: f32 = 0.6;

/// Where a pedestrian is in its behaviour `tick.skipUntil(trigger).takeUntil(done).foreach(walk)`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum PedestrianPhase {
    /// Standing at the start, waiting for the trigger.
    Waiting,
    /// Walking toward the target.
    Walking,
    /// At the target; stays there.
    Arrived,
}

/// A pedestrian's observable state.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PedestrianState {
    /// Ground position `[x, y, z]` in metres (feet).
    pub pos_m: [f64; 3],
    /// The behaviour's phase.
    pub phase: PedestrianPhase,
    /// Time the walk started, in seconds since the run began, `None` before the trigger.
    pub triggered_at_s: Option<f64>,
    /// Velocity `[x, y, z]`, m/s: its move over the last step (a placed pedestrian: its
    /// script's speed along its heading; before the first step, its initial speed).
    pub velocity_mps: [f64; 3],
    /// The way it faces, rad (counter-clockwise from `+x` seen from above).
    pub heading_rad: f64,
    /// Whether it is in this test now: not while an OpenSCENARIO storyboard has it out
    /// (`DeleteEntityAction`, [`crate::Action::SetPresent`]).
    pub present: bool,
}

/// A kinematic pedestrian: a sensor capsule moved by position, not by forces. It never pushes
/// the car; contact is reported through collision events on the sensor. Its behaviour comes
/// from the stream graph: a step with an event on its `walk` sink moves it one step toward
/// the target, however many `walk` events the step has (two behaviours that walk it in the
/// same step do not double its speed). It faces its target from the start and keeps that
/// heading: it walks a straight line, so its heading never turns.
pub(crate) struct Pedestrian {
    pub(crate) body: RigidBodyHandle,
    pub(crate) collider: ColliderHandle,
    /// Its walking speed stream, m/s.
    pub(crate) speed_stream: crate::rx::Input,
    /// Whether it touches the ego vehicle now, and whether it has touched anything since the
    /// test began (the ego, a car, an obstacle).
    contact: Contact,
    /// How messages name it ([`PedestrianSpec::name`], else `pedestrian i`).
    name: String,
    target: [f64; 3],
    pos: [f64; 3],
    /// Where it was at the start of this step ([`Pedestrian::rest`]).
    step_start: [f64; 3],
    /// Whether it has taken this step's walking step.
    walked: bool,
    heading_rad: f64,
    velocity: [f64; 3],
    phase: PedestrianPhase,
    triggered_at_s: Option<f64>,
    /// Whether it is out of the test ([`crate::Action::SetPresent`]): its body and collider
    /// are disabled.
    pub(crate) absent: bool,
}

impl Pedestrian {
    /// Checks pedestrian `i` before anything is built: its initial speed.
    ///
    /// # Errors
    /// [`EngineError::InvalidWorld`] for an initial speed that is negative or not finite.
    pub(crate) fn check_spec(i: usize, p: &PedestrianSpec) -> Result<(), EngineError> {
        if !(p.initial_speed_mps.is_finite() && p.initial_speed_mps >= 0.0) {
            return Err(EngineError::InvalidWorld(format!(
                "pedestrian {i}'s initial speed {} m/s is negative or not finite",
                p.initial_speed_mps
            )));
        }
        Ok(())
    }

    /// Pedestrian `i` of a world whose stream graph is `graph`, built into `physics` from
    /// its spec (checked by [`Pedestrian::check_spec`]).
    pub(crate) fn from_spec(
        i: usize,
        p: &PedestrianSpec,
        graph: &Graph,
        physics: &mut PhysicsWorld,
    ) -> Self {
        let speed = Input::of(graph, p.speed);
        let mut ped = Pedestrian::build(physics, (p.start, p.target), speed, p.initial_speed_mps);
        ped.name = if p.name.is_empty() {
            format!("pedestrian {i}")
        } else {
            p.name.clone()
        };
        ped
    }

    /// Performs one of this step's actions on the pedestrian ([`Action::Walk`] at its speed
    /// stream's value now, [`Action::PlacePedestrian`]) with its event's `value`.
    ///
    /// # Errors
    /// [`EngineError::Stream`] for a speed stream without a number now;
    /// [`crate::rx::RxError::Input`] for a pose that is not one, naming the pedestrian.
    pub(crate) fn act(
        &mut self,
        action: Action,
        value: &Value,
        world: &mut StepWorld,
    ) -> Result<(), EngineError> {
        let (t, dt) = (world.t_s, world.dt_s);
        match action {
            Action::Walk(_) => {
                let what = || format!("the speed of {}", self.name);
                let v = number(world.streams, self.speed_stream, t, what)?;
                self.walk(world.physics, t, dt, v);
            }
            Action::PlacePedestrian(_) => {
                let pose = placed_pose(value).ok_or_else(|| {
                    let name = format!("the pose given to {}", self.name);
                    bad_input(t, name, value, POSE_EXPECTED)
                })?;
                self.place(world.physics, (pose.0, pose.1), pose.2, dt);
            }
            _ => {}
        }
        Ok(())
    }

    /// What it walked into this step among `solids`, as `me` (rapier reports no contact
    /// between two kinematic bodies); it records the collision.
    pub(crate) fn walked_into(&mut self, me: ActorRef, solids: &Solids) -> Option<ActorRef> {
        let capsule = Capsule::new_y(PED_HALF_HEIGHT_M, PED_RADIUS_M);
        let hit = solids.first_hit(me, &capsule, &self.collider_pose(), false);
        self.contact.collided |= hit.is_some();
        hit
    }

    /// Builds a pedestrian standing at `start`, facing `target`, moving at
    /// `initial_speed_mps` (m/s) the way it faces until its first step.
    pub(crate) fn build(
        physics: &mut PhysicsWorld,
        (start, target): ([f64; 3], [f64; 3]),
        speed_stream: crate::rx::Input,
        initial_speed_mps: f64,
    ) -> Self {
        let body = RigidBodyBuilder::kinematic_position_based().translation(centre(start));
        let collider = ColliderBuilder::capsule_y(PED_HALF_HEIGHT_M, PED_RADIUS_M)
            .sensor(true)
            .active_events(ActiveEvents::COLLISION_EVENTS);
        let (body, collider) = physics.insert(body, collider);
        let heading_rad = if (target[0], target[2]) == (start[0], start[2]) {
            0.0
        } else {
            (-(target[2] - start[2])).atan2(target[0] - start[0])
        };
        Pedestrian {
            body,
            collider,
            speed_stream,
            contact: Contact::default(),
            name: String::new(),
            target,
            pos: start,
            step_start: start,
            walked: false,
            heading_rad,
            velocity: [
                initial_speed_mps * heading_rad.cos(),
                0.0,
                -initial_speed_mps * heading_rad.sin(),
            ],
            phase: PedestrianPhase::Waiting,
            triggered_at_s: None,
            absent: false,
        }
    }

    /// One walking step at time `t_s`: `speed_mps · dt_s` metres toward the target, stopping
    /// there. Sets the kinematic target of the next physics step. The first step marks the
    /// trigger time. A second call in the same step (after the same [`Pedestrian::rest`])
    /// does nothing: a pedestrian takes at most one walking step per step.
    pub(crate) fn walk(&mut self, physics: &mut PhysicsWorld, t_s: f64, dt_s: f64, speed_mps: f64) {
        if self.walked {
            return;
        }
        self.walked = true;
        if self.phase == PedestrianPhase::Waiting {
            self.phase = PedestrianPhase::Walking;
            self.triggered_at_s = Some(t_s);
        }
        if self.phase != PedestrianPhase::Walking {
            return;
        }
        let delta = [0, 1, 2].map(|i| self.target[i] - self.pos[i]);
        let remaining = delta.iter().map(|d| d * d).sum::<f64>().sqrt();
        let step = speed_mps.max(0.0) * dt_s;
        let before = self.step_start;
        if remaining <= step {
            self.pos = self.target;
            self.phase = PedestrianPhase::Arrived;
        } else {
            for (p, d) in self.pos.iter_mut().zip(delta) {
                *p += d / remaining * step;
            }
        }
        self.velocity = [0, 1, 2].map(|i| (self.pos[i] - before[i]) / dt_s);
        physics.bodies[self.body].set_next_kinematic_translation(centre(self.pos));
    }

    /// Puts the pedestrian at `pose` (`[x, y, z]` m of its feet, heading rad) for this step
    /// (a scripted pedestrian): its velocity is the move over the step and it faces `pose`'s
    /// heading. A pedestrian placed does not also walk in the same step.
    pub(crate) fn place(
        &mut self,
        physics: &mut PhysicsWorld,
        pose: ([f64; 3], f64),
        speed: Option<f64>,
        dt_s: f64,
    ) {
        self.walked = true;
        let before = self.step_start;
        self.pos = pose.0;
        self.heading_rad = pose.1;
        self.velocity = match speed {
            // Its script's speed along its heading (a teleport's step too).
            Some(v) => [v * pose.1.cos(), 0.0, -v * pose.1.sin()],
            None => [0, 1, 2].map(|i| (self.pos[i] - before[i]) / dt_s),
        };
        physics.bodies[self.body].set_next_kinematic_translation(centre(self.pos));
    }

    /// Starts a step: until a walk event moves it, it stands still (velocity 0).
    pub(crate) fn rest(&mut self) {
        self.velocity = [0.0; 3];
        self.step_start = self.pos;
        self.walked = false;
    }

    /// Its capsule's pose now (its feet at [`Pedestrian::pos`]).
    pub(crate) fn collider_pose(&self) -> Pose {
        Pose::from_translation(centre(self.pos))
    }

    pub(crate) fn state(&self) -> PedestrianState {
        PedestrianState {
            pos_m: self.pos,
            phase: self.phase,
            triggered_at_s: self.triggered_at_s,
            velocity_mps: self.velocity,
            heading_rad: self.heading_rad,
            present: !self.absent,
        }
    }
}

impl ActorKind for Pedestrian {
    fn contact(&self) -> Contact {
        self.contact
    }

    fn contact_mut(&mut self) -> &mut Contact {
        &mut self.contact
    }

    fn motion(&self) -> Option<Motion> {
        let v = self.velocity;
        Some(Motion {
            pos_m: self.pos,
            vel_mps: v,
            heading_rad: half_open(self.heading_rad),
            speed_mps: v[0].hypot(v[1]).hypot(v[2]),
        })
    }

    fn solid(&self, _: &PhysicsWorld) -> Option<(Pose, SharedShape)> {
        Some((
            self.collider_pose(),
            SharedShape::capsule_y(PED_HALF_HEIGHT_M, PED_RADIUS_M),
        ))
    }

    fn collider_now<'a>(&self, physics: &'a PhysicsWorld) -> Option<(Pose, &'a dyn Shape)> {
        let c = &physics.colliders[self.collider];
        Some((*c.position(), c.shape()))
    }

    /// The pedestrian as the time-to-collision test sees it.
    fn mover(&self) -> Option<crate::ttc::Mover> {
        let r = f64::from(PED_RADIUS_M);
        Some(crate::ttc::Mover {
            pos_m: [self.pos[0], self.pos[2]],
            velocity_mps: [self.velocity[0], self.velocity[2]],
            heading_rad: 0.0,
            half_size_m: [r, r],
        })
    }

    /// The box the camera draws: the capsule's bounding box, [`crate::Size::PEDESTRIAN`].
    fn visible(&self, index: usize) -> Option<VisibleBox> {
        Some(VisibleBox {
            base_m: self.pos,
            size: crate::Size::PEDESTRIAN,
            heading_rad: 0.0,
            albedo: [0.75, 0.22, 0.18],
            class: crate::segmentation::SemanticClass::Pedestrian,
            actor: index,
        })
    }

    fn start_step(&mut self) {
        self.rest();
    }
}

/// The capsule's centre for feet at `feet` (m).
fn centre(feet: [f64; 3]) -> Vector {
    Vector::new(
        feet[0] as f32,
        feet[1] as f32 + PED_HALF_HEIGHT_M + PED_RADIUS_M,
        feet[2] as f32,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn walks_at_its_speed_marks_the_trigger_time_and_stops_at_the_target() {
        let mut physics = PhysicsWorld::new();
        let mut p = Pedestrian::build(
            &mut physics,
            ([100.0, 0.0, 4.0], [100.0, 0.0, -4.0]),
            crate::rx::Input::Stream(crate::rx::StreamId(0)),
            0.0,
        );
        let dt = 0.1;
        assert_eq!(p.state().phase, PedestrianPhase::Waiting);
        p.rest();
        p.walk(&mut physics, 0.1, dt, 2.0);
        let s = p.state();
        assert_eq!(s.phase, PedestrianPhase::Walking);
        assert_eq!(s.triggered_at_s, Some(0.1));
        assert!((s.pos_m[2] - 3.8).abs() < 1e-12);
        assert!((p.state().velocity_mps[2] + 2.0).abs() < 1e-9);
        // A second walk event in the same step takes no second step.
        p.walk(&mut physics, 0.1, dt, 2.0);
        assert!((p.state().pos_m[2] - 3.8).abs() < 1e-12);
        assert!((p.state().velocity_mps[2] + 2.0).abs() < 1e-9);
        // It faces its target (-z: heading pi/2) from the start.
        assert!((p.state().heading_rad - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        // 8 m at 0.2 m per step: arrives after 40 steps in all, and stays.
        for i in 0..45 {
            p.rest();
            p.walk(&mut physics, 0.2 + 0.1 * i as f64, dt, 2.0);
        }
        assert_eq!(p.state().phase, PedestrianPhase::Arrived);
        assert_eq!(p.state().pos_m, [100.0, 0.0, -4.0]);
        assert_eq!(p.state().triggered_at_s, Some(0.1));
    }
}
