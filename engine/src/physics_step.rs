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
//!
//! One difference remains, and it is rapier's approximation, not this step's: rapier's
//! physics pipeline recycles a contact pair's manifold while the pair's relative pose has
//! moved less than 2 cm (5 cm while touching) since its last update, and its collision
//! pipeline does not. A contact that starts or ends while the two bodies move that slowly
//! relative to each other is found here at the step it happens, and by rapier's physics
//! pipeline up to that distance later (at 1 m/s, one step of 1/60 s later:
//! `tests::a_slow_contact_is_found_as_soon_or_sooner`).

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
    /// own) or `body` is asleep (one of the cars paracosm puts to sleep far from the ego).
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
        if !pos.next_position.is_finite() {
            // As rapier's pipeline does: a body is left at its last valid pose.
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

    fn poses(i: u32, speed: f32) -> [Pose; 2] {
        let t = i as f32 / 60.0;
        [
            Pose::translation(speed * t, 0.8, 0.0),
            Pose::from_parts(
                Vector::new(8.0, 0.8, 0.5 * t),
                Rotation::from_rotation_y(0.3 * t),
            ),
        ]
    }

    /// Bodies that meet and part slowly: the same contact events in the same order, each at
    /// the step rapier's physics pipeline reports it or at most the steps its contact
    /// recycling covers (5 cm of relative motion) sooner; at 2 m/s and faster, at the same
    /// step.
    #[test]
    fn a_slow_contact_is_found_as_soon_or_sooner() {
        let mut sooner = 0;
        for speed in [0.9f32, 1.0, 1.2, 1.5, 2.0, 3.0, 4.0] {
            let steps = (60.0 * 14.0 / speed) as u32;
            let (full, alone) = compare(speed, steps);
            let shape = rapier3d::parry::shape::Cuboid::new(Vector::new(2.3, 0.75, 0.95));
            let touching: Vec<u32> = (1..=steps)
                .filter(|&i| {
                    let [p, q] = poses(i, speed);
                    rapier3d::parry::query::intersection_test(&p, &shape, &q, &shape)
                        .unwrap()
                        .intersecting
                })
                .collect();
            assert!(!touching.is_empty(), "{speed} m/s: the boxes meet");
            assert_eq!(full.len(), 2, "{speed} m/s: a contact starts and stops");
            let kinds = |e: &[(u32, String)]| e.iter().map(|x| x.1.clone()).collect::<Vec<_>>();
            assert_eq!(kinds(&full), kinds(&alone), "{speed} m/s");
            let window = (0.05 / (speed / 60.0)).ceil() as u32;
            for (f, a) in full.iter().zip(&alone) {
                assert!(
                    a.0 <= f.0 && f.0 - a.0 <= window,
                    "{speed} m/s: {f:?} {a:?}"
                );
                if speed >= 2.0 {
                    assert_eq!(a.0, f.0, "{speed} m/s");
                }
                sooner += f.0 - a.0;
            }
        }
        // The slow cases do differ: the test would hold for two identical paths only if this
        // did not.
        assert!(sooner > 0);
    }

    /// One world stepped by rapier's physics pipeline (`full`) and one by [`step`] (`alone`),
    /// their bodies moved to the same poses, with each one's contact events.
    struct Twin {
        full: PhysicsWorld,
        alone: PhysicsWorld,
        bodies: [RigidBodyHandle; 2],
        events: [(
            ChannelEventCollector,
            std::sync::mpsc::Receiver<CollisionEvent>,
        ); 2],
    }

    impl Twin {
        fn new() -> Twin {
            let (full, bodies) = world();
            let (alone, _) = world();
            let events = [(), ()].map(|_| {
                let (tx, rx) = channel();
                (ChannelEventCollector::new(tx, channel().0, channel().0), rx)
            });
            Twin {
                full,
                alone,
                bodies,
                events,
            }
        }

        /// Step `i` with the first box at `speed` m/s: what [`step`] moved, and the contact
        /// events of each world.
        fn advance(&mut self, i: u32, speed: f32) -> (Moved, [Vec<String>; 2]) {
            for physics in [&mut self.full, &mut self.alone] {
                for (b, pose) in self.bodies.iter().zip(poses(i, speed)) {
                    physics.bodies[*b].set_next_kinematic_position(pose);
                }
            }
            self.full.step_with_events(&(), &self.events[0].0);
            let moved = step(&mut self.alone, &self.events[1].0);
            let seen = |k: usize| {
                let rx = &self.events[k].1;
                rx.try_iter().map(|e| format!("{e:?}")).collect()
            };
            (moved, [seen(0), seen(1)])
        }
    }

    /// The contact events of `steps` steps of the two boxes (the first at `speed` m/s) under
    /// rapier's physics pipeline and under [`step`]: (step, event) in order.
    #[allow(clippy::type_complexity)]
    fn compare(speed: f32, steps: u32) -> (Vec<(u32, String)>, Vec<(u32, String)>) {
        let mut twin = Twin::new();
        let (mut a, mut b) = (Vec::new(), Vec::new());
        for i in 1..=steps {
            let (_, [full, alone]) = twin.advance(i, speed);
            a.extend(full.into_iter().map(|e| (i, e)));
            b.extend(alone.into_iter().map(|e| (i, e)));
        }
        (a, b)
    }

    #[test]
    fn a_world_of_kinematic_bodies_steps_as_rapiers_pipeline_steps_it() {
        let mut twin = Twin::new();
        let mut contacts = 0;
        for i in 1..=120 {
            let (moved, [seen_full, seen_alone]) = twin.advance(i, 10.0);
            let (full, alone, bodies) = (&twin.full, &twin.alone, twin.bodies);
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
            assert_eq!(seen_full, seen_alone, "step {i}");
            contacts += seen_full.len();
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
