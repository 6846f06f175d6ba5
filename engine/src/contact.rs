//! Contacts of the kinematic actors (NPC cars and pedestrians) with everything solid that is
//! not the ego vehicle: obstacles, other cars, pedestrians. rapier moves a kinematic body
//! wherever it is told and reports no contact between two kinematic bodies, so these are
//! found here with parry's shape queries (rapier's own geometry) on the actors' colliders:
//! an NPC car that would move into one stops against it instead, and both record the
//! collision ([`crate::behaviour::Output::Collided`]). The ego vehicle is a dynamic body:
//! rapier resolves its contacts and reports them as collision events.

use rapier3d::parry::query;
use rapier3d::prelude::*;

/// Something a car or a pedestrian can touch.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Other {
    /// The ego vehicle (only for keeping a distance: its contacts are rapier's).
    Ego,
    /// NPC car `i` in the simulation's set.
    Car(usize),
    /// Pedestrian `i`.
    Pedestrian(usize),
    /// Obstacle `i`.
    Obstacle(usize),
}

/// The colliders of a step's solid objects, each with its pose now.
pub(crate) struct Solids {
    items: Vec<(Other, Pose, SharedShape)>,
}

impl Solids {
    /// An empty set.
    pub(crate) fn new() -> Self {
        Solids { items: Vec::new() }
    }

    /// Adds `who` with `shape` at `pose`, or moves it there when it is in the set.
    pub(crate) fn put(&mut self, who: Other, pose: Pose, shape: SharedShape) {
        match self.items.iter_mut().find(|(o, _, _)| *o == who) {
            Some(item) => {
                item.1 = pose;
                item.2 = shape;
            }
            None => self.items.push((who, pose, shape)),
        }
    }

    /// Moves `who` to `pose` (nothing when it is not in the set).
    pub(crate) fn move_to(&mut self, who: Other, pose: Pose) {
        if let Some(item) = self.items.iter_mut().find(|(o, _, _)| *o == who) {
            item.1 = pose;
        }
    }

    /// The first object, other than `me` and the ego unless `with_ego`, that `shape` at
    /// `pose` touches or overlaps; `None` when it is free.
    pub(crate) fn first_hit(
        &self,
        me: Other,
        shape: &dyn Shape,
        pose: &Pose,
        with_ego: bool,
    ) -> Option<Other> {
        self.items
            .iter()
            .filter(|(o, _, _)| *o != me && (with_ego || *o != Other::Ego))
            .find(|(_, p, s)| {
                // A pair parry cannot test (no such pair among boxes and capsules) counts as
                // touching: a contact is never assumed away.
                query::intersection_test(pose, shape, p, s.as_ref())
                    .map_or(true, |i| i.intersecting)
            })
            .map(|(o, _, _)| *o)
    }

    /// The smallest distance (m) from `shape` at `pose` to any object other than `me`, the
    /// ego included; `inf` when there is none, `0` when touching.
    pub(crate) fn clearance_m(&self, me: Other, shape: &dyn Shape, pose: &Pose) -> f64 {
        self.items
            .iter()
            .filter(|(o, _, _)| *o != me)
            .map(|(_, p, s)| {
                query::distance(pose, shape, p, s.as_ref())
                    .map_or(0.0, |d| f64::from(d.distance).max(0.0))
            })
            .fold(f64::INFINITY, f64::min)
    }
}
