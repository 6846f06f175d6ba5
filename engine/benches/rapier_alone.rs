//! The physics of one pedestrian-crossing test written with rapier alone, as a user of rapier
//! would write it: the floor paracosm's closed loop is measured against (issue 23).
//!
//! The world matches `WorldSpec::straight_road(200, …)`: a 200 m two-lane road slab with raised
//! sidewalks on a ground slab; a 1,500 kg chassis on a `DynamicRayCastVehicleController` with
//! paracosm's four wheels and tuning; a kinematic capsule pedestrian that crosses at
//! `walk_mps` once the car is within `trigger_m`. 900 steps of 1/60 s (15 s). The driver
//! holds 12 m/s and brakes when a lidar return lies in its corridor, as `aeb` does. The lidar
//! (optional) is paracosm's default: 121 beams over 60°, 60 m, 20 Hz, cast through rapier's
//! query pipeline with directions computed once.
//!
//! Included by `engine/benches/baseline.rs` and `scenarios/benches/simulate.rs`, so each
//! ratio to paracosm is measured in one run.

use rapier3d::control::{DynamicRayCastVehicleController, WheelTuning};
use rapier3d::prelude::*;

/// Step of the physics, s.
const DT_S: f32 = 1.0 / 60.0;

/// Runs one test: 900 steps. Returns the chassis's final x (m), so the work cannot be
/// optimised away.
pub fn run_test(walk_mps: f32, trigger_m: f32, lidar: bool) -> f32 {
    let mut physics = PhysicsWorld::new();
    physics.integration_parameters.dt = DT_S;
    let fixed = |physics: &mut PhysicsWorld, half: [f32; 3], at: [f32; 3]| {
        physics.insert_collider(
            ColliderBuilder::cuboid(half[0], half[1], half[2])
                .translation(Vector::new(at[0], at[1], at[2]))
                .friction(0.8),
            None,
        );
    };
    // Road slab (two 3.5 m lanes), sidewalks 2 m wide with a 0.15 m curb, ground.
    fixed(&mut physics, [100.0, 0.1, 3.5], [100.0, -0.1, 0.0]);
    for side in [1.0, -1.0] {
        fixed(
            &mut physics,
            [100.0, 0.175, 1.0],
            [100.0, -0.025, side * 4.5],
        );
    }
    fixed(&mut physics, [150.0, 0.5, 55.0], [100.0, -0.52, 0.0]);

    // Chassis 4.5 × 1.0 × 1.8 m, 1,500 kg, 12 m/s, in lane 1 at x = 10 m.
    let start_y = 0.35 + 0.3 + 0.3 - 0.05;
    let (body, _) = physics.insert(
        RigidBodyBuilder::dynamic()
            .translation(Vector::new(10.0, start_y, 1.75))
            .linvel(Vector::new(12.0, 0.0, 0.0))
            .linear_damping(0.02)
            .can_sleep(false),
        ColliderBuilder::cuboid(2.25, 0.5, 0.9)
            .mass(1500.0)
            .active_events(ActiveEvents::COLLISION_EVENTS),
    );
    let tuning = WheelTuning {
        suspension_stiffness: 30.0,
        suspension_compression: 2.5,
        suspension_damping: 3.0,
        max_suspension_travel: 0.25,
        side_friction_stiffness: 1.0,
        friction_slip: 0.8,
        max_suspension_force: 1500.0 * 9.81 * 2.0,
    };
    let mut vehicle = DynamicRayCastVehicleController::new(body);
    for (x, z) in [(1.45, 0.8), (1.45, -0.8), (-1.45, 0.8), (-1.45, -0.8)] {
        vehicle.add_wheel(
            Vector::new(x, -0.3, z),
            -Vector::Y,
            Vector::Z,
            0.3,
            0.35,
            &tuning,
        );
    }

    // Pedestrian: a kinematic capsule (radius 0.3 m, 1.8 m tall) on the right sidewalk.
    let (pedestrian, _) = physics.insert(
        RigidBodyBuilder::kinematic_position_based().translation(Vector::new(100.0, 0.9, 4.5)),
        ColliderBuilder::capsule_y(0.6, 0.3).sensor(true),
    );

    let beams: Vec<Vector> = (0..121)
        .map(|i| {
            let az = -30f32.to_radians() + 60f32.to_radians() * i as f32 / 120.0;
            Vector::new(az.cos(), 0.0, -az.sin())
        })
        .collect();
    let mut nearest_ahead: Option<f32> = None;
    let mut walking = false;
    let (contact_tx, contacts) = std::sync::mpsc::channel();
    let collector = ChannelEventCollector::new(
        contact_tx,
        std::sync::mpsc::channel().0,
        std::sync::mpsc::channel().0,
    );
    for step in 0..900 {
        let chassis = *physics.bodies[body].position();
        let speed = physics.bodies[body].linvel().x;
        // Driver: hold 12 m/s; brake fully when something is in the corridor within the
        // stopping distance plus 5 m.
        let stopping = speed * speed / (2.0 * 6.0) + 5.0;
        let brake = nearest_ahead.is_some_and(|d| d < stopping);
        let throttle = if brake {
            0.0
        } else {
            (0.5 * (12.0 - speed)).clamp(0.0, 1.0)
        };
        for (i, wheel) in vehicle.wheels_mut().iter_mut().enumerate() {
            wheel.engine_force = if i < 2 { 0.0 } else { throttle * 2250.0 };
            wheel.brake = if brake { 3000.0 * DT_S } else { 0.0 };
        }
        let queries = physics.broad_phase.as_query_pipeline_mut(
            physics.narrow_phase.query_dispatcher(),
            &mut physics.bodies,
            &mut physics.colliders,
            QueryFilter::only_fixed().exclude_sensors(),
        );
        vehicle.update_vehicle(DT_S, queries);

        // The pedestrian walks across once the car is within the trigger distance.
        let ped = physics.bodies[pedestrian].translation();
        walking |= (ped - chassis.translation).length() < trigger_m;
        if walking && ped.z > -4.5 {
            let next = ped - Vector::new(0.0, 0.0, walk_mps * DT_S);
            physics.bodies[pedestrian].set_next_kinematic_translation(next);
        }

        physics.step_with_events(&(), &collector);
        while contacts.try_recv().is_ok() {}

        if lidar && step % 3 == 0 {
            let chassis = *physics.bodies[body].position();
            let origin = chassis.transform_point(Vector::new(2.0, 0.1, 0.0));
            let queries =
                physics.query_pipeline_with_filter(QueryFilter::default().exclude_rigid_body(body));
            nearest_ahead = beams
                .iter()
                .filter_map(|&b| {
                    let ray = Ray::new(origin, chassis.rotation * b);
                    let (_, toi) = queries.cast_ray(&ray, 60.0, true)?;
                    let local = b * toi;
                    (local.z.abs() < 1.2).then_some(local.x)
                })
                .reduce(f32::min);
        }
    }
    physics.bodies[body].translation().x
}
