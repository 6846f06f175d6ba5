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
    /// Pairs coupled at a hitch (a trailer and its tow, [`crate::CarSpec::tow`]): their
    /// contact is no collision, and neither is in the other's way.
    coupled: Vec<(ActorRef, ActorRef)>,
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
        Solids {
            items: Vec::new(),
            coupled: Vec::new(),
        }
    }

    /// Couples `a` and `b` (a trailer and its tow): from now on neither meets the other.
    pub(crate) fn couple(&mut self, a: ActorRef, b: ActorRef) {
        self.coupled.push((a, b));
    }

    /// Whether `o` is another object than `me`, not coupled to it, and not the ego unless
    /// `with_ego`: one `me` can meet.
    fn other(&self, me: ActorRef, o: ActorRef, with_ego: bool) -> bool {
        o != me
            && (with_ego || o != ActorRef::Ego)
            && !self
                .coupled
                .iter()
                .any(|&(a, b)| (a, b) == (me, o) || (a, b) == (o, me))
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
            .filter(|(o, ..)| self.other(me, *o, with_ego))
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
            .filter(|(o, ..)| self.other(me, *o, with_ego))
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

    /// The smallest distance (m) from `shape` at `pose` to any object other than `me` and
    /// what is coupled to it, the ego included; `inf` when there is none, `0` when touching.
    pub(crate) fn clearance_m(&self, me: ActorRef, shape: &dyn Shape, pose: &Pose) -> f64 {
        self.items
            .iter()
            .filter(|(o, ..)| self.other(me, *o, true))
            .map(|(_, p, s, _)| {
                query::distance(pose, shape, p, s.as_ref())
                    .map_or(0.0, |d| f64::from(d.distance).max(0.0))
            })
            .fold(f64::INFINITY, f64::min)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::actor::Roster;
    use crate::CarSpec;

    /// A trailer and its tow overlap at the hitch: coupled, neither meets the other nor counts
    /// it in its separation, while a third car in the same place still meets both.
    #[test]
    fn coupled_cars_do_not_meet_each_other_but_others_meet_them() {
        let mut roster: Roster<CarSpec> = Roster::default();
        let (tow, trailer, other) = (
            ActorRef::Car(roster.add()),
            ActorRef::Car(roster.add()),
            ActorRef::Car(roster.add()),
        );
        let shape = SharedShape::cuboid(2.3, 0.75, 0.95);
        let at = |x: f32| Pose::from_translation(Vector::new(x, 0.75, 0.0));
        let mut solids = Solids::new();
        solids.put(tow, at(0.0), shape.clone());
        solids.put(trailer, at(-4.0), shape.clone());
        // Overlapping by 0.6 m: uncoupled, they meet.
        assert_eq!(
            solids.first_hit(tow, shape.as_ref(), &at(0.0), true),
            Some(trailer)
        );
        assert_eq!(solids.clearance_m(trailer, shape.as_ref(), &at(-4.0)), 0.0);
        solids.couple(trailer, tow);
        assert_eq!(solids.first_hit(tow, shape.as_ref(), &at(0.0), true), None);
        assert_eq!(
            solids.first_hit(trailer, shape.as_ref(), &at(-4.0), true),
            None
        );
        assert!(!solids.any_near(tow, [0.0, 0.75, 0.0], 2.6, true));
        assert_eq!(
            solids.clearance_m(trailer, shape.as_ref(), &at(-4.0)),
            f64::INFINITY
        );
        // A car that is not coupled to them meets either.
        assert_eq!(
            solids.first_hit(other, shape.as_ref(), &at(-2.0), true),
            Some(tow)
        );
    }
}
