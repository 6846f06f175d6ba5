//! Actors as sets with typed handles, the way rapier keeps bodies and colliders: each kind of
//! actor (NPC cars, pedestrians, static obstacles) lives in its own [`Set`], and each actor
//! carries its own [`Size`], look, speed source and contact state. [`ActorKind`] is what the
//! step loop asks of every kind alike.

use std::fmt;
use std::marker::PhantomData;

use rapier3d::prelude::{PhysicsWorld, Pose, Shape, SharedShape};
use serde::{Deserialize, Serialize};

use crate::segmentation::SemanticClass;

/// An actor's contact state, kept by the actor itself.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub(crate) struct Contact {
    /// Whether it touches the ego vehicle now (collision events).
    pub(crate) touching: bool,
    /// Whether it has touched anything since the test began (the ego, a car, a pedestrian,
    /// an obstacle).
    pub(crate) collided: bool,
}

/// An actor's motion as a program reads it (`pos`, `vel`, `heading`, `speed`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Motion {
    /// Its reference point `[x, y, z]`, m.
    pub(crate) pos_m: [f64; 3],
    /// Its velocity `[x, y, z]`, m/s.
    pub(crate) vel_mps: [f64; 3],
    /// The way it faces, rad, counter-clockwise from `+x` seen from above.
    pub(crate) heading_rad: f64,
    /// Its speed, m/s, `>= 0`.
    pub(crate) speed_mps: f64,
}

/// What the step loop ([`crate::Simulation`]) asks of every kind of actor, so that the loop
/// names no kind: its contact state, its motion, its solid shape, how the time-to-collision
/// test and the camera see it, and what a step does to it. Each kind implements it in its
/// own file; `actors.rs` keeps the sets and registers each kind once.
pub(crate) trait ActorKind {
    /// Its contact state.
    fn contact(&self) -> Contact;

    /// Its contact state, to record a contact.
    fn contact_mut(&mut self) -> &mut Contact;

    /// Its motion now, `None` when it is not in this test (a disabled car: its outputs have
    /// no events).
    fn motion(&self) -> Option<Motion>;

    /// Its solid shape where it is now, for contacts between kinematic actors and for its
    /// `separation` output; `None` when it is not in this test.
    fn solid(&self, physics: &PhysicsWorld) -> Option<(Pose, SharedShape)>;

    /// Its collider where the physics world has it (an asleep car: where it would be), for
    /// the snapshot's minimum separation; `None` when it is not in this test.
    fn collider_now<'a>(&self, physics: &'a PhysicsWorld) -> Option<(Pose, &'a dyn Shape)>;

    /// It as the time-to-collision test sees it, `None` when it is not in this test.
    fn mover(&self) -> Option<crate::ttc::Mover>;

    /// The box the camera draws for actor `index` of its kind, `None` when it is not seen.
    fn visible(&self, index: usize) -> Option<VisibleBox>;

    /// Records that a car ran into it.
    fn run_into_by_car(&mut self) {
        self.contact_mut().collided = true;
    }

    /// Starts a step, before the step's actions.
    fn start_step(&mut self) {}

    /// Ends a step, after the physics step has taken its moves.
    fn end_step(&mut self) {}
}

/// What a step's actions and moves of the actors read and write: the physics world, the
/// stream graph's values this step, the road surface, the time at the step's start and the
/// step's length (s).
pub(crate) struct StepWorld<'a> {
    /// The physics world the actors' bodies are in.
    pub(crate) physics: &'a mut PhysicsWorld,
    /// The stream graph, evaluated for this step.
    pub(crate) streams: &'a crate::rx::Runtime,
    /// The road surface (its frictions now).
    pub(crate) surface: &'a crate::network::Surface,
    /// The time at the step's start, s.
    pub(crate) t_s: f64,
    /// The step's length, s.
    pub(crate) dt_s: f64,
}

/// A heading from `atan2`, in `[-π, π]`, as one in `(-π, π]` (a location's and the ego's
/// range): `-π` becomes `π`, every other value keeps its bits.
pub(crate) fn half_open(heading_rad: f64) -> f64 {
    if heading_rad <= -std::f64::consts::PI {
        heading_rad + std::f64::consts::TAU
    } else {
        heading_rad
    }
}

/// The size of a box-shaped body, metres: one struct and one axis order everywhere (the
/// collider, the camera's drawing, the placement check, time to collision).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Size {
    /// Along the heading, m, `> 0`.
    pub length_m: f64,
    /// Across the heading, m, `> 0`.
    pub width_m: f64,
    /// Up, m, `> 0`.
    pub height_m: f64,
}

impl Size {
    /// An NPC car: 4.5 × 1.8 × 1.5 m.
    pub const CAR: Size = Size {
        length_m: 4.5,
        width_m: 1.8,
        height_m: 1.5,
    };
    /// A pedestrian's bounding box: 0.6 × 0.6 × 1.8 m (a capsule of radius 0.3 m).
    pub const PEDESTRIAN: Size = Size {
        length_m: 0.6,
        width_m: 0.6,
        height_m: 1.8,
    };

    /// Whether every extent is positive and at most [`Size::MAX_EXTENT_M`] (1 km): the
    /// physics works in `f32`, and a box 10^30 m tall touched a vehicle in another lane.
    pub fn is_valid(&self) -> bool {
        [self.length_m, self.width_m, self.height_m]
            .iter()
            .all(|v| *v > 0.0 && *v <= Size::MAX_EXTENT_M)
    }

    /// The largest extent of a box, m.
    pub const MAX_EXTENT_M: f64 = 1000.0;
}

/// A box the camera draws: a car, a pedestrian, an obstacle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VisibleBox {
    /// Centre of the box's base (the ground point under it) `[x, y, z]`, metres.
    pub base_m: [f64; 3],
    /// Its size; the drawn box reaches from the base to `height_m` above it.
    pub size: Size,
    /// Heading in rad (counter-clockwise seen from above, `0` along `+x`).
    pub heading_rad: f64,
    /// Albedo, linear RGB in `[0, 1]`.
    pub albedo: [f32; 3],
    /// What it is, for the camera's segmentation mask: [`SemanticClass::Car`],
    /// [`SemanticClass::Pedestrian`] or [`SemanticClass::Obstacle`].
    pub class: SemanticClass,
    /// Its index in its kind's set (the mask's actor id, [`crate::segmentation`]).
    pub actor: usize,
}

/// A handle to an actor of kind `T` in its [`Set`]: its index, typed so that a car's handle
/// cannot name a pedestrian. Handles are made only by a [`Set`] or a [`Roster`]; an actor's
/// kind is named by its spec type ([`crate::CarSpec`], [`crate::PedestrianSpec`],
/// [`crate::ObstacleSpec`]), so that a handle handed out when a scenario declares the actor
/// names the same actor in the running simulation's set.
pub struct Handle<T> {
    index: u32,
    kind: PhantomData<fn() -> T>,
}

impl<T> Handle<T> {
    /// The handle of the `index`-th actor inserted (for [`Set`] and [`Roster`] only).
    fn from_index(index: usize) -> Self {
        Handle {
            index: index as u32,
            kind: PhantomData,
        }
    }

    /// Its index, in insertion order.
    pub fn index(self) -> usize {
        self.index as usize
    }
}

impl<T> Clone for Handle<T> {
    fn clone(&self) -> Self {
        *self
    }
}
impl<T> Copy for Handle<T> {}
impl<T> PartialEq for Handle<T> {
    fn eq(&self, other: &Self) -> bool {
        self.index == other.index
    }
}
impl<T> Eq for Handle<T> {}
impl<T> std::hash::Hash for Handle<T> {
    fn hash<H: std::hash::Hasher>(&self, state: &mut H) {
        self.index.hash(state);
    }
}
impl<T> fmt::Debug for Handle<T> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "Handle({})", self.index)
    }
}

/// A set of actors of one kind, in insertion order: items of type `T`, named by handles of
/// kind `K` (by default `T` itself; the simulation's live actors are named by their spec's
/// kind, so that a [`Roster`]'s handles reach them).
pub struct Set<T, K = T> {
    items: Vec<T>,
    kind: PhantomData<fn() -> K>,
}

impl<T: Clone, K> Clone for Set<T, K> {
    fn clone(&self) -> Self {
        Set {
            items: self.items.clone(),
            kind: PhantomData,
        }
    }
}

impl<T: fmt::Debug, K> fmt::Debug for Set<T, K> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_list().entries(&self.items).finish()
    }
}

impl<T, K> Default for Set<T, K> {
    fn default() -> Self {
        Set {
            items: Vec::new(),
            kind: PhantomData,
        }
    }
}

impl<T, K> Set<T, K> {
    /// Adds `item`; returns its handle.
    pub fn insert(&mut self, item: T) -> Handle<K> {
        self.items.push(item);
        Handle::from_index(self.items.len() - 1)
    }

    /// The actor of handle `h`, if it is in the set.
    pub fn get(&self, h: Handle<K>) -> Option<&T> {
        self.items.get(h.index())
    }

    /// The actor of handle `h`, mutably.
    pub fn get_mut(&mut self, h: Handle<K>) -> Option<&mut T> {
        self.items.get_mut(h.index())
    }

    /// Every actor with its handle, in insertion order.
    pub fn iter(&self) -> impl Iterator<Item = (Handle<K>, &T)> {
        self.items
            .iter()
            .enumerate()
            .map(|(i, t)| (Handle::from_index(i), t))
    }

    /// Every actor with its handle, mutably, in insertion order.
    pub fn iter_mut(&mut self) -> impl Iterator<Item = (Handle<K>, &mut T)> {
        self.items
            .iter_mut()
            .enumerate()
            .map(|(i, t)| (Handle::from_index(i), t))
    }

    /// Every actor, mutably, in insertion order.
    pub fn values_mut(&mut self) -> impl Iterator<Item = &mut T> {
        self.items.iter_mut()
    }

    /// Every actor, in insertion order.
    pub fn values(&self) -> impl Iterator<Item = &T> {
        self.items.iter()
    }

    /// How many actors it holds.
    pub fn len(&self) -> usize {
        self.items.len()
    }

    /// Whether it holds none.
    pub fn is_empty(&self) -> bool {
        self.items.is_empty()
    }
}

/// Hands out the handles of actors declared before their [`Set`] exists: a scenario declares
/// its pedestrians, cars and obstacles (and streams read and act on them) before the
/// simulation is built. The `i`-th handle handed out names the `i`-th actor a set of kind `K`
/// inserts, so the world's specs are listed in the order their handles were handed out.
pub struct Roster<K> {
    count: u32,
    kind: PhantomData<fn() -> K>,
}

impl<K> Default for Roster<K> {
    fn default() -> Self {
        Roster {
            count: 0,
            kind: PhantomData,
        }
    }
}

impl<K> Clone for Roster<K> {
    fn clone(&self) -> Self {
        Roster {
            count: self.count,
            kind: PhantomData,
        }
    }
}

impl<K> fmt::Debug for Roster<K> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "Roster({})", self.count)
    }
}

impl<K> Roster<K> {
    /// The next actor's handle.
    pub fn add(&mut self) -> Handle<K> {
        self.count += 1;
        Handle::from_index(self.count as usize - 1)
    }

    /// How many handles it has handed out.
    pub fn len(&self) -> usize {
        self.count as usize
    }

    /// Whether it has handed out none.
    pub fn is_empty(&self) -> bool {
        self.count == 0
    }

    /// The handle of the `index`-th actor declared, when there is one.
    pub fn get(&self, index: usize) -> Option<Handle<K>> {
        (index < self.len()).then(|| Handle::from_index(index))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn handles_are_typed_indices_in_insertion_order() {
        let mut s: Set<&str> = Set::default();
        let a = s.insert("a");
        let b = s.insert("b");
        assert_eq!((a.index(), b.index()), (0, 1));
        assert_eq!(s.get(b), Some(&"b"));
        assert_eq!(s.iter().map(|(h, _)| h).collect::<Vec<_>>(), [a, b]);
        // A roster's handles name what a set of the same kind inserts, in order.
        let mut r: Roster<&str> = Roster::default();
        assert_eq!([r.add(), r.add()], [a, b]);
        assert_eq!((r.len(), r.get(1), r.get(2)), (2, Some(b), None));
        assert!(Size::CAR.is_valid());
        assert!(!Size {
            length_m: 1.0,
            width_m: 0.0,
            height_m: 1.0
        }
        .is_valid());
        for bad in [1e30, f64::INFINITY, f64::NAN, 1000.5] {
            assert!(!Size {
                length_m: 50.0,
                width_m: 0.5,
                height_m: bad
            }
            .is_valid());
        }
        assert!(Size {
            length_m: 1000.0,
            width_m: 0.5,
            height_m: 1.0
        }
        .is_valid());
    }
}
