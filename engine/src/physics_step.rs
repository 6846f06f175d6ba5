//! One rapier step of a test's world, without the constraint solver when no body is
//! dynamic.
//!
//! With the ego scripted (`--scripted-ego`) every body of the world is kinematic (cars,
//! pedestrians, obstacles, the ego) or fixed (the roads): rapier's island solver then has no
//! impulse to compute, yet building its islands and constraints cost a third of a scripted
//! test (`valgrind --tool=callgrind` on ALKS free driving). Such a step runs rapier's
//! collision pipeline alone and then moves each kinematic body to the pose its actor set, as
//! rapier's physics pipeline does in that order: contacts are found at the poses the step
//! starts from, and after the step each body is at its next pose with the velocity rapier
//! interpolates from the move (the ego's speed is read from it).

use rapier3d::dynamics::{RigidBodyHandle, RigidBodyPosition, RigidBodyType};
use rapier3d::math::{AngVector, Vector};
use rapier3d::pipeline::EventHandler;
use rapier3d::prelude::PhysicsWorld;

/// The velocity of each kinematic body a step without the solver moved: rapier keeps a
/// position-based kinematic body's velocity private to its pipeline (`RigidBody::set_linvel`
/// does nothing for one), so whoever reads a kinematic body's velocity (the scripted ego's
/// speed, and its velocity when it is handed to its system under test) reads it here. Empty
/// after rapier's full pipeline, whose bodies carry their own.
#[derive(Debug, Default)]
pub(crate) struct Moved(Vec<(RigidBodyHandle, KinematicVelocity)>);

/// A kinematic body's velocity over a step, as rapier's pipeline interpolates it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct KinematicVelocity {
    /// Linear velocity, m/s, world frame.
    pub(crate) linvel: Vector,
    /// Angular velocity, rad/s, world frame (rapier's scaled axis).
    pub(crate) angvel: AngVector,
}

impl Moved {
    /// The velocity the step gave `body`; `None` when rapier's pipeline ran (read the body's
    /// own) or the body did not move.
    pub(crate) fn of(&self, body: RigidBodyHandle) -> Option<KinematicVelocity> {
        self.0.iter().find(|(h, _)| *h == body).map(|(_, v)| *v)
    }
}

/// Steps `physics` by its integration step, reporting contact events to `events`: rapier's
/// full pipeline when a body is dynamic, else [`step_kinematic`].
pub(crate) fn step(physics: &mut PhysicsWorld, events: &dyn EventHandler) -> Moved {
    if physics.bodies.iter().any(|(_, b)| b.is_dynamic()) {
        physics.step_with_events(&(), events);
        Moved::default()
    } else {
        step_kinematic(physics, events)
    }
}

/// A step of a world without dynamic bodies: contacts at the current poses (rapier's
/// collision pipeline), then each position-based kinematic body moved to its next pose with
/// the velocity of that move (`RigidBodyPosition::interpolate_velocity`, as rapier's
/// pipeline sets it; returned, as rapier keeps it private), and its colliders with it.
fn step_kinematic(physics: &mut PhysicsWorld, events: &dyn EventHandler) -> Moved {
    physics.detect_collisions(&(), events);
    let inv_dt = physics.integration_parameters.inv_dt();
    let mut moved = Moved::default();
    for (handle, body) in physics.bodies.iter_mut() {
        if body.body_type() != RigidBodyType::KinematicPositionBased {
            continue;
        }
        let pos = RigidBodyPosition {
            position: *body.position(),
            next_position: *body.next_position(),
        };
        if pos.position == pos.next_position && body.is_sleeping() {
            continue;
        }
        let vels = pos.interpolate_velocity(inv_dt, body.local_center_of_mass());
        body.set_position(pos.next_position, false);
        moved.0.push((
            handle,
            KinematicVelocity {
                linvel: vels.linvel,
                angvel: vels.angvel,
            },
        ));
    }
    physics
        .bodies
        .propagate_modified_body_positions_to_colliders(&mut physics.colliders);
    moved
}

#[cfg(test)]
mod tests {
    use super::*;
    use rapier3d::prelude::*;
    use std::sync::mpsc::channel;

    /// A fixed ground, a car-sized box driving at 10 m/s into a second box that turns while it
    /// slides sideways, all moved by their next poses: what a scripted test's world is.
    fn world() -> (PhysicsWorld, [RigidBodyHandle; 2]) {
        let mut physics = PhysicsWorld::new();
        physics.integration_parameters.dt = 1.0 / 60.0;
        let ground = physics.bodies.insert(RigidBodyBuilder::fixed());
        let slab =
            ColliderBuilder::cuboid(50.0, 0.1, 50.0).translation(Vector::new(0.0, -0.1, 0.0));
        physics
            .colliders
            .insert_with_parent(slab.build(), ground, &mut physics.bodies);
        let mut bodies = [RigidBodyHandle::invalid(); 2];
        for (k, x) in [(0, 0.0f32), (1, 8.0)] {
            let body =
                RigidBodyBuilder::kinematic_position_based().translation(Vector::new(x, 0.8, 0.0));
            bodies[k] = physics.bodies.insert(body);
            let collider = ColliderBuilder::cuboid(2.3, 0.75, 0.95)
                .active_events(ActiveEvents::COLLISION_EVENTS)
                .active_collision_types(
                    ActiveCollisionTypes::default() | ActiveCollisionTypes::KINEMATIC_KINEMATIC,
                );
            physics
                .colliders
                .insert_with_parent(collider.build(), bodies[k], &mut physics.bodies);
        }
        physics.detect_collisions(&(), &());
        (physics, bodies)
    }

    fn poses(i: u32) -> [Pose; 2] {
        let t = i as f32 / 60.0;
        [
            Pose::translation(10.0 * t, 0.8, 0.0),
            Pose::from_parts(
                Vector::new(8.0, 0.8, 0.5 * t),
                Rotation::from_rotation_y(0.3 * t),
            ),
        ]
    }

    #[test]
    fn a_world_of_kinematic_bodies_steps_as_rapiers_pipeline_steps_it() {
        let (mut full, bodies) = world();
        let (mut alone, _) = world();
        let (full_tx, full_rx) = channel();
        let (alone_tx, alone_rx) = channel();
        let full_events = ChannelEventCollector::new(full_tx, channel().0, channel().0);
        let alone_events = ChannelEventCollector::new(alone_tx, channel().0, channel().0);
        let mut contacts = 0;
        for i in 1..=120 {
            for physics in [&mut full, &mut alone] {
                for (b, pose) in bodies.iter().zip(poses(i)) {
                    physics.bodies[*b].set_next_kinematic_position(pose);
                }
            }
            full.step_with_events(&(), &full_events);
            let moved = step(&mut alone, &alone_events);
            for b in bodies {
                assert_eq!(
                    full.bodies[b].position(),
                    alone.bodies[b].position(),
                    "step {i}"
                );
                let v = moved.of(b).expect("a moved body's velocity");
                assert_eq!(full.bodies[b].linvel(), v.linvel, "step {i}");
                assert_eq!(full.bodies[b].angvel(), v.angvel, "step {i}");
                for c in full.bodies[b].colliders() {
                    assert_eq!(
                        full.colliders[*c].position(),
                        alone.colliders[*c].position()
                    );
                }
            }
            let a: Vec<String> = full_rx.try_iter().map(|e| format!("{e:?}")).collect();
            let b: Vec<String> = alone_rx.try_iter().map(|e| format!("{e:?}")).collect();
            assert_eq!(a, b, "step {i}");
            contacts += a.len();
        }
        // The first box reaches the second (their gap closes at 10 m/s from 3.4 m) and passes
        // through it: a contact starts and stops.
        assert_eq!(contacts, 2);
    }

    #[test]
    fn a_world_with_a_dynamic_body_takes_rapiers_pipeline() {
        let (mut physics, _) = world();
        physics
            .bodies
            .insert(RigidBodyBuilder::dynamic().translation(Vector::new(0.0, 5.0, 0.0)));
        let moved = step(&mut physics, &());
        assert!(moved.0.is_empty());
    }
}
