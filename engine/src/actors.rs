//! The world's actors: one [`Set`] per kind, and the one place that lists the kinds. The
//! step loop ([`crate::Simulation`]) reaches every actor through [`ActorKind`] by its
//! [`ActorRef`]; what a kind does (its build, its actions, its move over a step) lives in its
//! own file (`car.rs`, `pedestrian.rs`, `obstacle.rs`). A new kind adds its file, its set
//! here, its arms in [`Actors::get`], [`Actors::get_mut`] and [`Actors::all`], and its build
//! in [`Actors::build`].

use std::collections::HashMap;

use rapier3d::prelude::*;

use crate::actor::{ActorKind, Set, StepWorld, VisibleBox};
use crate::behaviour::{Action, ActorRef};
use crate::car::Car;
use crate::contact::Solids;
use crate::obstacle::Obstacle;
use crate::pedestrian::Pedestrian;
use crate::rx::{StreamId, Value};
use crate::{CarSpec, EngineError, ObstacleSpec, PedestrianSpec, WorldSpec};

/// The world's actors, each kind in its set in the order of its specs in [`WorldSpec`].
pub(crate) struct Actors {
    /// The NPC cars ([`WorldSpec::cars`]).
    pub(crate) cars: Set<Car, CarSpec>,
    /// The pedestrians ([`WorldSpec::pedestrians`]).
    pub(crate) pedestrians: Set<Pedestrian, PedestrianSpec>,
    /// The static obstacles ([`WorldSpec::obstacles`]).
    pub(crate) obstacles: Set<Obstacle, ObstacleSpec>,
    /// The actor each actor collider belongs to.
    owners: HashMap<ColliderHandle, ActorRef>,
    /// The actors out of the test now ([`Action::SetPresent`]): [`Actors::all`] leaves them
    /// out.
    absent: Vec<ActorRef>,
    /// Each trailer and its tow ([`CarSpec::tow`]).
    coupled: Vec<(ActorRef, ActorRef)>,
}

impl Actors {
    /// Checks what must hold before anything is built (each pedestrian's initial speed).
    ///
    /// # Errors
    /// [`EngineError::InvalidWorld`] naming the first value out of range.
    pub(crate) fn check(spec: &WorldSpec) -> Result<(), EngineError> {
        for (i, p) in spec.pedestrians.iter().enumerate() {
            Pedestrian::check_spec(i, p)?;
        }
        Ok(())
    }

    /// The streams the actors read every step: each pedestrian's and each car's speed.
    pub(crate) fn read_streams(spec: &WorldSpec) -> impl Iterator<Item = StreamId> + Clone + '_ {
        spec.pedestrians
            .iter()
            .map(|p| p.speed)
            .chain(spec.cars.iter().map(|c| c.speed))
    }

    /// Builds `spec`'s actors into `physics`: the pedestrians, the cars, then the obstacles.
    ///
    /// # Errors
    /// [`EngineError::InvalidWorld`] for a car or an obstacle whose values are out of range,
    /// naming it.
    pub(crate) fn build(spec: &WorldSpec, physics: &mut PhysicsWorld) -> Result<Self, EngineError> {
        let mut actors = Actors {
            cars: Set::default(),
            pedestrians: Set::default(),
            obstacles: Set::default(),
            owners: HashMap::new(),
            absent: Vec::new(),
            coupled: Vec::new(),
        };
        for (i, p) in spec.pedestrians.iter().enumerate() {
            let ped = Pedestrian::from_spec(i, p, &spec.streams, physics);
            let collider = ped.collider;
            let h = actors.pedestrians.insert(ped);
            actors.owners.insert(collider, ActorRef::Pedestrian(h));
        }
        let mut handles = Vec::new();
        for (i, c) in spec.cars.iter().enumerate() {
            let car = Car::from_spec(i, c, &spec.streams, physics)?;
            let collider = car.body.map(|(_, c)| c);
            let h = actors.cars.insert(car);
            if let Some(collider) = collider {
                actors.owners.insert(collider, ActorRef::Car(h));
            }
            handles.push(h);
        }
        for (i, c) in spec.cars.iter().enumerate() {
            let Some(tow) = c.tow else { continue };
            if tow == i || tow >= handles.len() {
                return Err(EngineError::InvalidWorld(format!(
                    "car {i} is towed by car {tow}, which is {} (a trailer's tow is another car \
                     of the world's {})",
                    if tow == i {
                        "itself"
                    } else {
                        "not in the world"
                    },
                    handles.len()
                )));
            }
            actors
                .coupled
                .push((ActorRef::Car(handles[i]), ActorRef::Car(handles[tow])));
        }
        for (i, o) in spec.obstacles.iter().enumerate() {
            let obstacle = Obstacle::from_spec(i, o, physics)?;
            let collider = obstacle.collider;
            let h = actors.obstacles.insert(obstacle);
            actors.owners.insert(collider, ActorRef::Obstacle(h));
        }
        Ok(actors)
    }

    /// The actor `r` names, `None` for the ego or a handle past its set.
    pub(crate) fn get(&self, r: ActorRef) -> Option<&dyn ActorKind> {
        match r {
            ActorRef::Ego => None,
            ActorRef::Car(h) => self.cars.get(h).map(|a| a as &dyn ActorKind),
            ActorRef::Pedestrian(h) => self.pedestrians.get(h).map(|a| a as &dyn ActorKind),
            ActorRef::Obstacle(h) => self.obstacles.get(h).map(|a| a as &dyn ActorKind),
        }
    }

    /// The actor `r` names, to change it.
    pub(crate) fn get_mut(&mut self, r: ActorRef) -> Option<&mut dyn ActorKind> {
        match r {
            ActorRef::Ego => None,
            ActorRef::Car(h) => self.cars.get_mut(h).map(|a| a as &mut dyn ActorKind),
            ActorRef::Pedestrian(h) => self.pedestrians.get_mut(h).map(|a| a as &mut dyn ActorKind),
            ActorRef::Obstacle(h) => self.obstacles.get_mut(h).map(|a| a as &mut dyn ActorKind),
        }
    }

    /// Every actor with its reference: the cars, the pedestrians, then the obstacles, each
    /// kind in its order.
    pub(crate) fn all(&self) -> impl Iterator<Item = (ActorRef, &dyn ActorKind)> {
        let cars = (self.cars.iter()).map(|(h, a)| (ActorRef::Car(h), a as &dyn ActorKind));
        let pedestrians =
            (self.pedestrians.iter()).map(|(h, a)| (ActorRef::Pedestrian(h), a as &dyn ActorKind));
        let obstacles =
            (self.obstacles.iter()).map(|(h, a)| (ActorRef::Obstacle(h), a as &dyn ActorKind));
        let absent = &self.absent;
        cars.chain(pedestrians)
            .chain(obstacles)
            .filter(move |(r, _)| absent.is_empty() || !absent.contains(r))
    }

    /// Calls `f` on every actor, in [`Actors::all`]'s order.
    fn each_mut(&mut self, mut f: impl FnMut(&mut dyn ActorKind)) {
        self.cars.values_mut().for_each(|a| f(a));
        self.pedestrians.values_mut().for_each(|a| f(a));
        self.obstacles.values_mut().for_each(|a| f(a));
    }

    /// Starts a step for every actor ([`ActorKind::start_step`]).
    pub(crate) fn start_step(&mut self) {
        self.each_mut(|a| a.start_step());
    }

    /// Ends a step for every actor, after the physics step ([`ActorKind::end_step`]).
    pub(crate) fn end_step(&mut self) {
        self.each_mut(|a| a.end_step());
    }

    /// Performs one of this step's actions on the actor it names, with its event's `value`;
    /// an action on the ego does nothing here.
    ///
    /// # Errors
    /// The actor's error for a value its action cannot take.
    pub(crate) fn act(
        &mut self,
        action: Action,
        value: &Value,
        world: &mut StepWorld,
    ) -> Result<(), EngineError> {
        if let Action::SetPresent(r) = action {
            let Value::Bool(present) = value else {
                return Err(crate::behaviour::bad_input(
                    world.t_s,
                    "an actor's presence".into(),
                    value,
                    "a boolean (true: in the test)",
                ));
            };
            self.set_present(r, *present, world.physics);
            return Ok(());
        }
        match action.actor() {
            ActorRef::Car(h) => match self.cars.get_mut(h) {
                Some(car) => car.act(action, value, world),
                None => Ok(()),
            },
            ActorRef::Pedestrian(h) => match self.pedestrians.get_mut(h) {
                Some(p) => p.act(action, value, world),
                None => Ok(()),
            },
            ActorRef::Obstacle(_) | ActorRef::Ego => Ok(()),
        }
    }

    /// Puts actor `r` into the test (`present`) or out of it ([`Action::SetPresent`]): its
    /// body and collider enabled or disabled, its own flag set so that its moves leave them
    /// so. Nothing changes for the ego, an obstacle, or an actor already so.
    fn set_present(&mut self, r: ActorRef, present: bool, physics: &mut PhysicsWorld) {
        let was = !self.absent.contains(&r);
        if was == present {
            return;
        }
        let parts = match r {
            ActorRef::Car(h) => self.cars.get_mut(h).map(|c| {
                c.absent = !present;
                (c.body, Some(c.collider_pose()))
            }),
            ActorRef::Pedestrian(h) => self.pedestrians.get_mut(h).map(|p| {
                p.absent = !present;
                (Some((p.body, p.collider)), Some(p.collider_pose()))
            }),
            ActorRef::Obstacle(_) | ActorRef::Ego => None,
        };
        let Some((body, pose)) = parts else {
            return;
        };
        if present {
            self.absent.retain(|a| *a != r);
        } else {
            self.absent.push(r);
        }
        if let Some((body, collider)) = body {
            let rb = &mut physics.bodies[body];
            if present {
                if let Some(pose) = pose {
                    rb.set_position(pose, true);
                }
            }
            rb.set_enabled(present);
            physics.colliders[collider].set_enabled(present);
        }
    }

    /// Moves the kinematic actors over the step: each car along its path or to its script's
    /// pose (stopping short of, or against, what it meets), then records the pedestrians
    /// that walked into a car or an obstacle. `solids` holds every solid where it is now;
    /// `reach` is as [`Car::step`] takes it.
    ///
    /// # Errors
    /// [`EngineError::Stream`] for a car speed stream without a number now.
    pub(crate) fn move_kinematic(
        &mut self,
        world: &mut StepWorld,
        solids: &mut Solids,
        reach: ([f64; 2], f64),
    ) -> Result<(), EngineError> {
        let handles: Vec<_> = self.cars.iter().map(|(h, _)| h).collect();
        for h in handles {
            let Some(car) = self.cars.get_mut(h) else {
                continue;
            };
            let hit = car.step(ActorRef::Car(h), world, reach, solids)?;
            if let Some(a) = hit.and_then(|o| self.get_mut(o)) {
                a.run_into_by_car();
            }
        }
        // A pedestrian that walks into a car or an obstacle (rapier reports no contact
        // between two kinematic bodies): both record the collision.
        if !self.kinematic_contacts() {
            return Ok(());
        }
        let mut hits = Vec::new();
        for (h, p) in self.pedestrians.iter_mut().filter(|(_, p)| !p.absent) {
            if let Some(o) = p.walked_into(ActorRef::Pedestrian(h), solids) {
                hits.push(o);
            }
        }
        for o in hits {
            if let ActorRef::Car(_) | ActorRef::Obstacle(_) = o {
                if let Some(a) = self.get_mut(o) {
                    a.contact_mut().collided = true;
                }
            }
        }
        Ok(())
    }

    /// Whether anything kinematic can meet something this step: a world without NPC cars
    /// has only its pedestrians to meet its obstacles.
    pub(crate) fn kinematic_contacts(&self) -> bool {
        !self.cars.is_empty() || !(self.pedestrians.is_empty() || self.obstacles.is_empty())
    }

    /// Records a collision event between the ego and `collider` (`started`: it began, else
    /// it ended); a collider of no actor is ignored.
    pub(crate) fn record_ego_contact(&mut self, collider: ColliderHandle, started: bool) {
        let Some(&r) = self.owners.get(&collider) else {
            return;
        };
        if let Some(a) = self.get_mut(r) {
            let c = a.contact_mut();
            c.touching = started;
            c.collided |= started;
        }
    }

    /// Whether any actor touches the ego vehicle now.
    pub(crate) fn touching_ego(&self) -> bool {
        self.all().any(|(_, a)| a.contact().touching)
    }

    /// Puts every actor in the test into `solids` where it is now.
    pub(crate) fn put_solids(&self, physics: &PhysicsWorld, solids: &mut Solids) {
        for &(a, b) in &self.coupled {
            solids.couple(a, b);
        }
        for (r, a) in self.all() {
            if let Some((pose, shape)) = a.solid(physics) {
                solids.put(r, pose, shape);
            }
        }
    }

    /// The boxes the camera draws: every actor it sees, in [`Actors::all`]'s order.
    pub(crate) fn visible_boxes(&self) -> Vec<VisibleBox> {
        self.all()
            .filter_map(|(r, a)| a.visible(r.index()))
            .collect()
    }

    /// The colliders of the cars asleep out of the physics step, each with the pose it
    /// would have now (what a sensor sees in its place).
    pub(crate) fn asleep(&self, physics: &PhysicsWorld) -> Vec<(ColliderHandle, Pose)> {
        self.cars
            .values()
            .filter(|c| !c.absent && c.is_asleep(physics))
            .filter_map(|c| Some((c.body?.1, c.collider_pose())))
            .collect()
    }
}
