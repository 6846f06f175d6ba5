use std::sync::mpsc::{channel, Receiver};

use rapier3d::prelude::*;
use serde::Serialize;

use crate::pedestrian::Pedestrian;
use crate::vehicle::EgoVehicle;
use crate::{
    Control, EngineError, LidarReturn, LidarSpec, PedestrianState, RoadSegment, WorldSpec,
};

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

/// What a system under test sees at one instant.
#[derive(Debug, Clone, Copy)]
pub struct Observation<'a> {
    /// Time since the start, in seconds.
    pub t_s: f64,
    /// Physics step in seconds.
    pub dt_s: f64,
    /// The ego vehicle's own state (odometry).
    pub ego: EgoState,
    /// The latest lidar scan, in the vehicle frame.
    pub lidar: &'a [LidarReturn],
}

/// The world's state after a step: what monitors are computed from.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Snapshot {
    /// Time since the start, in seconds.
    pub t_s: f64,
    /// The ego vehicle.
    pub ego: EgoState,
    /// Every pedestrian, in the order of [`WorldSpec::pedestrians`].
    pub pedestrians: Vec<PedestrianState>,
    /// Whether the ego vehicle's body touches a pedestrian's sensor now (collision events).
    pub ego_pedestrian_contact: bool,
    /// The smallest distance between the ego vehicle's body and a pedestrian's capsule, in
    /// metres; `0` when touching, `+inf` without pedestrians.
    pub min_pedestrian_separation_m: f64,
}

/// A running world: the physics, the actors and the ego vehicle's sensors, advanced in fixed
/// steps by [`Simulation::step`].
pub struct Simulation {
    physics: PhysicsWorld,
    road: RoadSegment,
    ego: EgoVehicle,
    pedestrians: Vec<Pedestrian>,
    touching: Vec<bool>,
    lidar: LidarSpec,
    directions: Vec<(f64, f64)>,
    scan_every: u64,
    scan: Vec<LidarReturn>,
    events: Receiver<CollisionEvent>,
    collector: ChannelEventCollector,
    dt_s: f64,
    tick: u64,
}

impl Simulation {
    /// Builds the world described by `spec`.
    ///
    /// # Errors
    /// [`EngineError::InvalidWorld`] when the road, a position, a speed, the lidar or the step
    /// is invalid; the message says which.
    pub fn new(spec: &WorldSpec) -> Result<Self, EngineError> {
        let invalid = |m: String| EngineError::InvalidWorld(m);
        if !(spec.dt_s.is_finite() && spec.dt_s > 0.0) {
            return Err(invalid(format!(
                "time step {} s is not positive",
                spec.dt_s
            )));
        }
        spec.lidar.validate().map_err(invalid)?;
        let road = RoadSegment::new(spec.road.clone())?;
        if !matches!(spec.ego.lane, crate::Lane::Driving(_)) {
            return Err(invalid(
                "the ego vehicle must start on a driving lane".into(),
            ));
        }
        if !(spec.ego.initial_speed_mps.is_finite() && spec.ego.initial_speed_mps >= 0.0) {
            return Err(invalid(format!(
                "ego initial speed {} m/s is negative or not finite",
                spec.ego.initial_speed_mps
            )));
        }
        let mut physics = PhysicsWorld::new();
        physics.integration_parameters.dt = spec.dt_s as f32;
        road.build(&mut physics);

        let start = road.on_lane(spec.ego.lane, spec.ego.at_m)?;
        // Positive lanes drive along +x, negative ones along -x.
        let heading = match spec.ego.lane {
            crate::Lane::Driving(k) if k < 0 => std::f64::consts::PI,
            _ => 0.0,
        };
        let ego = EgoVehicle::build(
            &mut physics,
            &spec.ego.vehicle,
            start,
            heading,
            spec.ego.initial_speed_mps,
            spec.road.friction,
        );

        let mut pedestrians = Vec::with_capacity(spec.pedestrians.len());
        for (i, p) in spec.pedestrians.iter().enumerate() {
            let ok = |v: f64| v.is_finite() && v > 0.0;
            if !ok(p.speed_mps) || !ok(p.trigger_distance_m) {
                return Err(invalid(format!(
                    "pedestrian {i}: speed {} m/s and trigger distance {} m must be positive",
                    p.speed_mps, p.trigger_distance_m
                )));
            }
            let s = road.on_lane(p.start.0, p.start.1)?;
            let t = road.on_lane(p.target.0, p.target.1)?;
            pedestrians.push(Pedestrian::build(
                &mut physics,
                s,
                t,
                p.trigger_distance_m,
                p.speed_mps,
            ));
        }

        let (collision_tx, events) = channel();
        let (force_tx, _) = channel();
        let (tear_tx, _) = channel();
        let scan_every = ((1.0 / (spec.lidar.rate_hz * spec.dt_s)).round() as u64).max(1);
        let mut sim = Simulation {
            physics,
            road,
            touching: vec![false; pedestrians.len()],
            ego,
            pedestrians,
            directions: spec.lidar.directions(),
            lidar: spec.lidar.clone(),
            scan_every,
            scan: Vec::new(),
            events,
            collector: ChannelEventCollector::new(collision_tx, force_tx, tear_tx),
            dt_s: spec.dt_s,
            tick: 0,
        };
        // Contacts and ray casts need the broad phase filled before the first step.
        sim.physics.detect_collisions(&(), &());
        sim.rescan();
        Ok(sim)
    }

    /// Time since the start, in seconds (`tick · dt`).
    pub fn t_s(&self) -> f64 {
        self.tick as f64 * self.dt_s
    }

    /// The physics step in seconds.
    pub fn dt_s(&self) -> f64 {
        self.dt_s
    }

    /// The road.
    pub fn road(&self) -> &RoadSegment {
        &self.road
    }

    /// The ego vehicle's state now.
    pub fn ego_state(&self) -> EgoState {
        let body = &self.physics.bodies[self.ego.body];
        let p = body.translation();
        let forward = *body.rotation() * Vector::X;
        EgoState {
            pos_m: [p.x, p.y, p.z].map(f64::from),
            heading_rad: f64::from(-forward.z).atan2(f64::from(forward.x)),
            speed_mps: f64::from(body.linvel().dot(forward)),
        }
    }

    /// What the system under test sees now: odometry and the latest lidar scan.
    pub fn observation(&self) -> Observation<'_> {
        Observation {
            t_s: self.t_s(),
            dt_s: self.dt_s,
            ego: self.ego_state(),
            lidar: &self.scan,
        }
    }

    /// Advances the world by one step of `dt` under `control`: vehicle model, actor behaviours,
    /// rapier step, contact events, and a lidar scan when one is due.
    pub fn step(&mut self, control: Control) {
        let dt = self.dt_s;
        self.ego.apply(control, dt);
        self.ego.update(&mut self.physics, dt);
        let t = self.t_s();
        let ego_pos = self.ego_state().pos_m;
        for p in &mut self.pedestrians {
            p.tick(&mut self.physics, t, dt, ego_pos);
        }
        self.physics.step_with_events(&(), &self.collector);
        while let Ok(event) = self.events.try_recv() {
            let (a, b, started) = match event {
                CollisionEvent::Started(a, b, _) => (a, b, true),
                CollisionEvent::Stopped(a, b, _) => (a, b, false),
            };
            let other = if a == self.ego.collider {
                b
            } else if b == self.ego.collider {
                a
            } else {
                continue;
            };
            if let Some(i) = self.pedestrians.iter().position(|p| p.collider == other) {
                self.touching[i] = started;
            }
        }
        self.tick += 1;
        if self.tick % self.scan_every == 0 {
            self.rescan();
        }
    }

    /// The state monitors are computed from.
    pub fn snapshot(&self) -> Snapshot {
        let chassis = &self.physics.colliders[self.ego.collider];
        let min_sep = self
            .pedestrians
            .iter()
            .filter_map(|p| {
                let c = &self.physics.colliders[p.collider];
                rapier3d::parry::query::distance(
                    chassis.position(),
                    chassis.shape(),
                    c.position(),
                    c.shape(),
                )
                .ok()
                .map(|d| f64::from(d.distance))
            })
            .fold(f64::INFINITY, f64::min);
        Snapshot {
            t_s: self.t_s(),
            ego: self.ego_state(),
            pedestrians: self.pedestrians.iter().map(Pedestrian::state).collect(),
            ego_pedestrian_contact: self.touching.iter().any(|&t| t),
            min_pedestrian_separation_m: min_sep,
        }
    }

    /// Length, width and height of the ego vehicle's body, in metres.
    pub fn ego_size_m(&self) -> [f64; 3] {
        self.ego.size_m()
    }

    fn rescan(&mut self) {
        let pose = *self.physics.bodies[self.ego.body].position();
        self.lidar.scan(
            &self.physics,
            &pose,
            self.ego.body,
            &self.directions,
            &mut self.scan,
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{EgoSpec, Lane, LidarSpec, PedestrianSpec, RoadSpec, VehicleParams};

    fn spec() -> WorldSpec {
        WorldSpec {
            dt_s: crate::DEFAULT_DT_S,
            road: RoadSpec::default(),
            ego: EgoSpec {
                lane: Lane::Driving(1),
                at_m: 10.0,
                initial_speed_mps: 5.0,
                vehicle: VehicleParams::default(),
            },
            pedestrians: vec![PedestrianSpec {
                start: (Lane::Driving(1), 40.0),
                target: (Lane::Driving(1), 40.0),
                trigger_distance_m: 1e-6,
                speed_mps: 1.0,
            }],
            lidar: LidarSpec::default(),
        }
    }

    #[test]
    fn invalid_worlds_are_errors_naming_the_problem() {
        let cases: Vec<(WorldSpec, &str)> = vec![
            (
                WorldSpec {
                    dt_s: 0.0,
                    ..spec()
                },
                "time step",
            ),
            (
                WorldSpec {
                    ego: EgoSpec {
                        lane: Lane::SideWalk,
                        ..spec().ego
                    },
                    ..spec()
                },
                "driving lane",
            ),
            (
                WorldSpec {
                    ego: EgoSpec {
                        initial_speed_mps: -1.0,
                        ..spec().ego
                    },
                    ..spec()
                },
                "initial speed",
            ),
            (
                WorldSpec {
                    pedestrians: vec![PedestrianSpec {
                        speed_mps: 0.0,
                        ..spec().pedestrians[0].clone()
                    }],
                    ..spec()
                },
                "pedestrian 0",
            ),
            (
                WorldSpec {
                    lidar: LidarSpec {
                        beams: 0,
                        ..LidarSpec::default()
                    },
                    ..spec()
                },
                "lidar",
            ),
        ];
        for (s, needle) in cases {
            let err = Simulation::new(&s)
                .err()
                .expect("invalid world")
                .to_string();
            assert!(err.contains(needle), "{err}");
        }
    }

    #[test]
    fn starts_at_its_lane_with_its_speed_and_the_lidar_sees_the_pedestrian() {
        let sim = Simulation::new(&spec()).unwrap();
        let ego = sim.ego_state();
        assert_eq!(ego.pos_m[0], 10.0);
        assert_eq!(ego.pos_m[2], 1.75);
        assert!((ego.speed_mps - 5.0).abs() < 1e-5);
        assert_eq!(ego.heading_rad, 0.0);
        let obs = sim.observation();
        let ahead = obs
            .lidar
            .iter()
            .filter(|r| r.point_m[2].abs() < 0.5)
            .map(|r| r.point_m[0])
            .reduce(f64::min)
            .expect("a return straight ahead");
        // Pedestrian centre 30 m ahead of the chassis centre, capsule radius 0.3 m.
        assert!((ahead - 29.7).abs() < 0.05, "nearest return at {ahead} m");
        let snap = sim.snapshot();
        assert!(!snap.ego_pedestrian_contact);
        // 30 m between centres, less half the car (2.25 m) and the capsule radius (0.3 m).
        assert!((snap.min_pedestrian_separation_m - 27.45).abs() < 0.05);
    }

    #[test]
    fn time_advances_by_whole_steps() {
        let mut sim = Simulation::new(&spec()).unwrap();
        for _ in 0..60 {
            sim.step(Control::default());
        }
        assert!((sim.t_s() - 1.0).abs() < 1e-12);
        assert_eq!(sim.snapshot().t_s, sim.t_s());
    }
}
