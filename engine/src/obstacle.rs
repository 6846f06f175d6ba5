use rapier3d::prelude::*;
use serde::Serialize;

use crate::actor::{ActorKind, Contact, Motion, Size, VisibleBox};
use crate::{EngineError, ObstacleSpec};

/// A static obstacle's state, for snapshots.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ObstacleState {
    /// Centre of its base `[x, y, z]`, metres.
    pub base_m: [f64; 3],
    /// Heading in rad.
    pub heading_rad: f64,
    /// Its size.
    pub size: Size,
}

/// A static box (a parked car, a cone, a barrier): it never moves, collides with the ego
/// vehicle, stops lidar beams and is drawn by the camera. A kinematic body that is never
/// moved, so the ego's wheel rays (which see only fixed colliders, the road) pass under it.
pub(crate) struct Obstacle {
    pub(crate) collider: ColliderHandle,
    state: ObstacleState,
    pub(crate) albedo: [f32; 3],
    /// Whether it touches the ego vehicle now, and whether anything solid (the ego, a car, a
    /// pedestrian) has touched it since the test began.
    contact: Contact,
}

impl Obstacle {
    /// Obstacle `i` of a world, built into `physics` from its spec.
    ///
    /// # Errors
    /// [`EngineError::InvalidWorld`] for an invalid size or a base that is not finite.
    pub(crate) fn from_spec(
        i: usize,
        o: &ObstacleSpec,
        physics: &mut PhysicsWorld,
    ) -> Result<Self, EngineError> {
        if !o.size.is_valid() || o.base_m.iter().any(|v| !v.is_finite()) {
            return Err(EngineError::InvalidWorld(format!(
                "obstacle {i} has the size {:?} at {:?}",
                o.size, o.base_m
            )));
        }
        Ok(Obstacle::build(
            physics,
            o.base_m,
            o.heading_rad,
            o.size,
            crate::colour::albedo(&o.color).unwrap_or([0.45, 0.45, 0.45]),
        ))
    }

    /// An obstacle standing on `base_m` (its base's centre, metres), turned `heading_rad`.
    pub(crate) fn build(
        physics: &mut PhysicsWorld,
        base_m: [f64; 3],
        heading_rad: f64,
        size: Size,
        albedo: [f32; 3],
    ) -> Self {
        let body = RigidBodyBuilder::kinematic_position_based().pose(Pose::from_parts(
            Vector::new(
                base_m[0] as f32,
                (base_m[1] + size.height_m / 2.0) as f32,
                base_m[2] as f32,
            ),
            Rotation::from_rotation_y(heading_rad as f32),
        ));
        let collider = ColliderBuilder::cuboid(
            (size.length_m / 2.0) as f32,
            (size.height_m / 2.0) as f32,
            (size.width_m / 2.0) as f32,
        )
        .active_events(ActiveEvents::COLLISION_EVENTS);
        let (_, collider) = physics.insert(body, collider);
        Obstacle {
            collider,
            state: ObstacleState {
                base_m,
                heading_rad,
                size,
            },
            albedo,
            contact: Contact::default(),
        }
    }

    pub(crate) fn state(&self) -> ObstacleState {
        self.state
    }
}

impl ActorKind for Obstacle {
    fn contact(&self) -> Contact {
        self.contact
    }

    fn contact_mut(&mut self) -> &mut Contact {
        &mut self.contact
    }

    fn motion(&self) -> Option<Motion> {
        Some(Motion {
            pos_m: self.state.base_m,
            vel_mps: [0.0; 3],
            heading_rad: self.state.heading_rad,
            speed_mps: 0.0,
        })
    }

    fn solid(&self, physics: &PhysicsWorld) -> Option<(Pose, SharedShape)> {
        let c = &physics.colliders[self.collider];
        Some((*c.position(), c.shared_shape().clone()))
    }

    fn collider_now<'a>(&self, physics: &'a PhysicsWorld) -> Option<(Pose, &'a dyn Shape)> {
        let c = &physics.colliders[self.collider];
        Some((*c.position(), c.shape()))
    }

    fn visible(&self, index: usize) -> Option<VisibleBox> {
        Some(VisibleBox {
            base_m: self.state.base_m,
            size: self.state.size,
            heading_rad: self.state.heading_rad,
            albedo: self.albedo,
            class: crate::segmentation::SemanticClass::Obstacle,
            actor: index,
        })
    }

    /// It as the time-to-collision test sees it: standing still.
    fn mover(&self) -> Option<crate::ttc::Mover> {
        Some(crate::ttc::Mover {
            pos_m: [self.state.base_m[0], self.state.base_m[2]],
            velocity_mps: [0.0, 0.0],
            heading_rad: self.state.heading_rad,
            half_size_m: [
                self.state.size.length_m / 2.0,
                self.state.size.width_m / 2.0,
            ],
        })
    }
}
