//! Contacts of the kinematic actors (NPC cars and pedestrians) with everything solid that is
//! not the ego vehicle: obstacles, other cars, pedestrians. rapier moves a kinematic body
//! wherever it is told and reports no contact between two kinematic bodies, so these are
//! found here with parry's shape queries (rapier's own geometry) on the actors' colliders:
//! an NPC car that would move into one stops against it instead, and both record the
//! collision ([`crate::behaviour::Output::Collided`]). The ego vehicle is a dynamic body:
//! rapier resolves its contacts and reports them as collision events.

use crate::behaviour::ActorRef;
use rapier3d::parry::query;
use rapier3d::prelude::*;

/// The colliders of a step's solid objects, each with its pose now and the radius of its
/// bounding sphere about its pose's origin (m): two objects whose origins are farther apart
/// than their radii together cannot touch, which most pairs are, so they skip parry's test.
pub(crate) struct Solids {
    items: Vec<(ActorRef, Pose, SharedShape, f32)>,
}

/// The radius of `shape`'s bounding sphere about its frame's origin, m.
fn reach(shape: &dyn Shape) -> f32 {
    let s = shape.compute_local_bounding_sphere();
    s.center().length() + s.radius()
}

/// Whether two bounding spheres about the origins of `a` and `b` (radii `ra`, `rb`) are
/// apart (then the shapes cannot touch).
fn apart(a: &Pose, ra: f32, b: &Pose, rb: f32) -> bool {
    (a.translation - b.translation).length() > ra + rb
}

impl Solids {
    /// An empty set.
    pub(crate) fn new() -> Self {
        Solids { items: Vec::new() }
    }

    /// Adds `who` with `shape` at `pose`, or moves it there when it is in the set.
    pub(crate) fn put(&mut self, who: ActorRef, pose: Pose, shape: SharedShape) {
        let r = reach(shape.as_ref());
        match self.items.iter_mut().find(|(o, ..)| *o == who) {
            Some(item) => *item = (who, pose, shape, r),
            None => self.items.push((who, pose, shape, r)),
        }
    }

    /// Moves `who` to `pose` (nothing when it is not in the set).
    pub(crate) fn move_to(&mut self, who: ActorRef, pose: Pose) {
        if let Some(item) = self.items.iter_mut().find(|(o, ..)| *o == who) {
            item.1 = pose;
        }
    }

    /// The first object, other than `me` and the ego unless `with_ego`, that `shape` at
    /// `pose` touches or overlaps; `None` when it is free.
    pub(crate) fn first_hit(
        &self,
        me: ActorRef,
        shape: &dyn Shape,
        pose: &Pose,
        with_ego: bool,
    ) -> Option<ActorRef> {
        let r = reach(shape);
        self.items
            .iter()
            .filter(|(o, ..)| *o != me && (with_ego || *o != ActorRef::Ego))
            .find(|(_, p, s, rs)| {
                // A pair parry cannot test (no such pair among boxes and capsules) counts as
                // touching: a contact is never assumed away.
                !apart(pose, r, p, *rs)
                    && query::intersection_test(pose, shape, p, s.as_ref())
                        .map_or(true, |i| i.intersecting)
            })
            .map(|(o, ..)| *o)
    }

    /// Whether any object other than `me` (and the ego unless `with_ego`) has its bounding
    /// sphere within `radius_m` of the point `centre` (m): when none has, nothing there can
    /// touch a shape that reaches no farther than `radius_m` from it.
    pub(crate) fn any_near(
        &self,
        me: ActorRef,
        centre: [f64; 3],
        radius_m: f64,
        with_ego: bool,
    ) -> bool {
        self.items
            .iter()
            .filter(|(o, ..)| *o != me && (with_ego || *o != ActorRef::Ego))
            .any(|(_, p, _, r)| {
                let t = p.translation;
                let d = [
                    f64::from(t.x) - centre[0],
                    f64::from(t.y) - centre[1],
                    f64::from(t.z) - centre[2],
                ];
                let near = radius_m + f64::from(*r) + 1e-3;
                d[0] * d[0] + d[1] * d[1] + d[2] * d[2] <= near * near
            })
    }

    /// The smallest distance (m) from `shape` at `pose` to any object other than `me`, the
    /// ego included; `inf` when there is none, `0` when touching.
    pub(crate) fn clearance_m(&self, me: ActorRef, shape: &dyn Shape, pose: &Pose) -> f64 {
        self.items
            .iter()
            .filter(|(o, ..)| *o != me)
            .map(|(_, p, s, _)| {
                query::distance(pose, shape, p, s.as_ref())
                    .map_or(0.0, |d| f64::from(d.distance).max(0.0))
            })
            .fold(f64::INFINITY, f64::min)
    }
}
