//! Positions of the storyboard's actions and conditions (world, relative, lane, road) resolved
//! on the map's lanes, in the OpenSCENARIO frame.

use super::*;

impl Storyboard {
    /// Lane position `lp` facing `h` (rad): its pose, and its place on the lanes the way it
    /// faces.
    pub(in crate::xosc::story) fn placed(&self, lp: LanePos, h: f64) -> (Pose, Option<LanePos>) {
        let lp = self.roads.facing(lp, h);
        let pose = Pose {
            h,
            ..self.roads.pose_of(&lp)
        };
        (pose, Some(lp))
    }

    /// Where entity `e` is on the lanes, for a position of kind `what` relative to it.
    ///
    /// # Errors
    /// [`StoryError`] at `at` when `e` is on no lane.
    pub(in crate::xosc::story) fn lane_of(
        &self,
        e: usize,
        what: &str,
        at: &paracosm_openscenario::Pos,
    ) -> Result<LanePos, StoryError> {
        let r = &self.actors[e];
        let (x, y) = (r.state.pose.x, r.state.pose.y);
        r.state.lane.ok_or_else(|| StoryError {
            at: site(at),
            message: format!(
                "a {what} to {}, which is not on a lane: it stands at x = {x:.1} m, y = {y:.1} m \
                 (where its last position put it, or the origin before its Init places it)",
                r.name
            ),
        })
    }

    /// The pitch and roll (rad) an entity placed at `p` has: a relative object or world
    /// position's are its entity's, turned by a relative orientation or set by an absolute
    /// one; any other position's are its orientation's (paracosm's roads are flat), 0
    /// without one (esmini's `Position` modes).
    pub(in crate::xosc::story) fn tilt_of(&self, p: &Position) -> [f64; 2] {
        let (base, orientation) = match p {
            Position::RelativeObject {
                entity,
                orientation,
                ..
            }
            | Position::RelativeWorld {
                entity,
                orientation,
                ..
            } => (self.actors[*entity].state.tilt, orientation),
            Position::Lane { orientation, .. }
            | Position::Road { orientation, .. }
            | Position::RelativeRoad { orientation, .. }
            | Position::RelativeLane { orientation, .. }
            | Position::Route { orientation, .. }
            | Position::Trajectory { orientation, .. } => ([0.0; 2], orientation),
            _ => return [0.0; 2],
        };
        match orientation {
            Some(o) if o.relative => [wrap(base[0] + o.p), wrap(base[1] + o.r)],
            Some(o) => [o.p, o.r],
            None => base,
        }
    }

    /// Where `p` is now: its pose and its place on the lanes.
    ///
    /// # Errors
    /// [`StoryError`] for a position off the map.
    pub fn resolve(
        &self,
        p: &Position,
        at: &paracosm_openscenario::Pos,
    ) -> Result<(Pose, Option<LanePos>), StoryError> {
        let bad = |message: String| StoryError {
            at: site(at),
            message,
        };
        Ok(match p {
            Position::World { x, y, h } => {
                let pose = Pose {
                    x: *x,
                    y: *y,
                    h: h.unwrap_or(0.0),
                };
                (pose, self.facing(self.roads.anchor(*x, *y), pose.h))
            }
            Position::RelativeWorld {
                entity,
                dx,
                dy,
                orientation,
            } => self.world_offset(*entity, *dx, *dy, orientation),
            Position::RelativeObject {
                entity,
                dx,
                dy,
                dz,
                orientation,
            } => self.object_offset(*entity, [*dx, *dy, *dz], orientation),
            Position::Road {
                road,
                s,
                t,
                orientation,
            } => {
                let lp = self
                    .roads
                    .road_pos(road, *s, *t)
                    .map_err(|e| bad(e.to_string()))?;
                let h = orient(orientation, self.roads.along_heading(&lp));
                self.placed(lp, h)
            }
            Position::Lane {
                road,
                lane,
                s,
                offset,
                orientation,
            } => self.lane_position(road, (*lane, *s, *offset), orientation, at)?,
            Position::RelativeRoad {
                entity,
                ds,
                dt,
                orientation,
            } => self.road_offset(*entity, (*ds, *dt), orientation, at)?,
            Position::Route {
                waypoints,
                at: in_route,
                orientation,
            } => self.route_position(waypoints, in_route, orientation, at)?,
            Position::Trajectory {
                shape,
                s,
                t,
                orientation,
            } => {
                let pose = self.trajectory_position(shape, (*s, *t), orientation, at)?;
                (pose, self.facing(self.roads.anchor(pose.x, pose.y), pose.h))
            }
            Position::RelativeLane {
                entity,
                d_lane,
                ds,
                offset,
                orientation,
            } => {
                let lp = self.lane_of(*entity, "RelativeLanePosition", at)?;
                let lp = self
                    .roads
                    .relative_lane(&lp, *d_lane, *ds, *offset)
                    .map_err(|e| bad(e.to_string()))?;
                let mut pose = self.roads.pose_of(&lp);
                pose.h = orient(orientation, pose.h);
                (pose, Some(lp))
            }
        })
    }

    /// A `TrajectoryPosition` (written at `at`): `s` m along `shape` from its start (its
    /// points as a `FollowTrajectoryAction` would sample them), `t` m to its left there,
    /// facing along it, turned by `orientation`.
    ///
    /// # Errors
    /// [`StoryError`] for a shape that starts where an entity is (a clothoid without its
    /// start: a position names no entity), or an `s` past the shape's end.
    pub(in crate::xosc::story) fn trajectory_position(
        &self,
        shape: &m::TrajectoryShape,
        (s, t): (f64, f64),
        orientation: &Option<m::Orientation>,
        at: &paracosm_openscenario::Pos,
    ) -> Result<Pose, StoryError> {
        let bad = |message: String| StoryError {
            at: site(at),
            message,
        };
        if matches!(
            shape,
            m::TrajectoryShape::Clothoid { start: None, .. }
                | m::TrajectoryShape::ClothoidSpline { start: None, .. }
        ) {
            return Err(bad(
                "a trajectory position on a clothoid without a start position: it would start \
                 where an entity is, and a position names none"
                    .into(),
            ));
        }
        let points: Vec<Pose> = self
            // No entity: a shape that needs one is refused above.
            .trajectory_points(0, shape, at)?
            .into_iter()
            .map(|(_, p)| p)
            .collect();
        let mut left = s;
        for w in points.windows(2) {
            let (a, b) = (w[0], w[1]);
            let len = (b.x - a.x).hypot(b.y - a.y);
            if left <= len + 1e-9 && len > 0.0 {
                let u = (left / len).min(1.0);
                let h = (b.y - a.y).atan2(b.x - a.x);
                return Ok(Pose {
                    x: a.x + u * (b.x - a.x) - t * h.sin(),
                    y: a.y + u * (b.y - a.y) + t * h.cos(),
                    h: orient(orientation, h),
                });
            }
            left -= len;
        }
        Err(bad(format!(
            "a trajectory position {s} m along a trajectory {:.2} m long",
            s - left
        )))
    }

    /// A `RelativeWorldPosition`: `dx`, `dy` (m, along the world's axes) from entity
    /// `entity`, heading `orientation` against the entity's (rad); its pose and its place on
    /// the lanes.
    pub(in crate::xosc::story) fn world_offset(
        &self,
        entity: usize,
        dx: f64,
        dy: f64,
        orientation: &Option<m::Orientation>,
    ) -> (Pose, Option<LanePos>) {
        let r = self.actors[entity].state.pose;
        let (x, y) = (r.x + dx, r.y + dy);
        let pose = Pose {
            x,
            y,
            h: orient(orientation, r.h),
        };
        (pose, self.facing(self.roads.anchor(x, y), pose.h))
    }

    /// A `RelativeObjectPosition`: `[dx, dy, dz]` forward, left and up (m, in entity
    /// `entity`'s frame, turned by its heading, pitch and roll as esmini's `RotateVec3d`
    /// turns them: `Rz(h)·Ry(p)·Rx(r)`) of the entity, its part along the ground taken, heading
    /// `orientation` against the entity's (rad); its pose and its place on the lanes.
    pub(in crate::xosc::story) fn object_offset(
        &self,
        entity: usize,
        [dx, dy, dz]: [f64; 3],
        orientation: &Option<m::Orientation>,
    ) -> (Pose, Option<LanePos>) {
        let st = &self.actors[entity].state;
        let r = st.pose;
        let (sh, ch) = r.h.sin_cos();
        let (sp, cp) = st.tilt[0].sin_cos();
        let (sr, cr) = st.tilt[1].sin_cos();
        // The offset in the entity's level frame (turned by roll, then pitch) ...
        let fx = cp * dx + sp * sr * dy + sp * cr * dz;
        let fy = cr * dy - sr * dz;
        // ... then by the heading.
        let (x, y) = (r.x + ch * fx - sh * fy, r.y + sh * fx + ch * fy);
        let pose = Pose {
            x,
            y,
            h: orient(orientation, r.h),
        };
        (pose, self.facing(self.roads.anchor(x, y), pose.h))
    }

    /// A `LanePosition`: lane id `lane` of road `road`, `s` along the road (m), `offset` from
    /// the lane's centre (m), heading `orientation` against the lane's driving direction
    /// (rad); its pose and its place on the lanes.
    ///
    /// # Errors
    /// [`StoryError`] at `at` for a road or lane the map lacks.
    pub(in crate::xosc::story) fn lane_position(
        &self,
        road: &str,
        (lane, s, offset): (i32, f64, f64),
        orientation: &Option<m::Orientation>,
        at: &paracosm_openscenario::Pos,
    ) -> Result<(Pose, Option<LanePos>), StoryError> {
        let lp = self
            .roads
            .lane_pos(road, lane, s, offset)
            .map_err(|e| StoryError {
                at: site(at),
                message: e.to_string(),
            })?;
        // Without an orientation, or relative to it, the lane's driving direction
        // (esmini's reading: a left lane of right-hand traffic faces against `s`).
        let travel = self.roads.travel_heading(&LanePos { rev: false, ..lp });
        let h = orient(orientation, travel);
        Ok(self.placed(lp, h))
    }

    /// A `RelativeRoadPosition`: `ds` along and `dt` across (m) entity `entity`'s road from
    /// its road coordinates, heading `orientation` against the road's reference line (rad);
    /// its pose and its place on the lanes.
    ///
    /// # Errors
    /// [`StoryError`] at `at` when the entity is on no lane or the place is off its road.
    pub(in crate::xosc::story) fn road_offset(
        &self,
        entity: usize,
        (ds, dt): (f64, f64),
        orientation: &Option<m::Orientation>,
        at: &paracosm_openscenario::Pos,
    ) -> Result<(Pose, Option<LanePos>), StoryError> {
        let bad = |message: String| StoryError {
            at: site(at),
            message,
        };
        let lp = self.lane_of(entity, "RelativeRoadPosition", at)?;
        let (road, t) = self.roads.road_t(&lp).map_err(|e| bad(e.to_string()))?;
        let lp = self
            .roads
            .road_pos(&road, lp.s + ds, t + dt)
            .map_err(|e| bad(e.to_string()))?;
        let h = orient(orientation, self.roads.along_heading(&lp));
        Ok(self.placed(lp, h))
    }

    /// `lp` (if any) facing `h`.
    pub(in crate::xosc::story) fn facing(&self, lp: Option<LanePos>, h: f64) -> Option<LanePos> {
        lp.map(|lp| self.roads.facing(lp, h))
    }

    /// Heading `h` relative to the travel of lane position `lp`, rad (0 off the lanes).
    pub(in crate::xosc::story) fn relative_heading(&self, h: f64, lp: Option<LanePos>) -> f64 {
        lp.map_or(0.0, |lp| wrap(h - self.roads.travel_heading(&lp)))
    }
}

impl Storyboard {
    /// A `RoutePosition`: on the route through `waypoints`, where `in_route` says: from its
    /// first waypoint's lane, `path_s` m of the roads' stations along its lanes in their
    /// direction of travel (into the successor on a road of the route where lanes fork),
    /// then the lane of the `<lane id>` asked on the road there (or `t` across it); or where
    /// an entity is. Its heading is the route's direction there, turned by `orientation`
    /// (relative to it, or absolute).
    ///
    /// # Errors
    /// [`StoryError`] at `at` for a first waypoint off the map's lanes, a route that ends
    /// before `path_s`, a road with no such lane there.
    pub(in crate::xosc::story) fn route_position(
        &self,
        waypoints: &[(Position, String)],
        in_route: &m::InRoute,
        orientation: &Option<m::Orientation>,
        at: &paracosm_openscenario::Pos,
    ) -> Result<(Pose, Option<LanePos>), StoryError> {
        let bad = |message: String| StoryError {
            at: site(at),
            message,
        };
        if let m::InRoute::Entity(e) = in_route {
            let st = &self.actors[*e].state;
            return Ok((st.pose, st.lane));
        }
        let first = match waypoints.first() {
            Some((p, _)) => self.resolve(p, at)?.1,
            None => None,
        };
        let Some(mut lp) = first else {
            return Err(bad(
                "a route position's route starts off the map's lanes: its first waypoint is on no lane".into(),
            ));
        };
        lp.d = 0.0;
        lp.rev = false;
        let mut roads = Vec::new();
        for (p, _) in waypoints {
            if let (_, Some(w)) = self.resolve(p, at)? {
                roads.push(self.roads.ids(w.lane).1);
            }
        }
        let prefer = |k: usize| {
            roads.contains(&self.roads.ids(k).1) || roads.contains(&self.roads.exit_road(k))
        };
        let path_s = match in_route {
            m::InRoute::Lane { path_s, .. } | m::InRoute::Road { path_s, .. } => *path_s,
            m::InRoute::Entity(_) => 0.0,
        };
        if !self
            .roads
            .advance_stations(&mut lp, path_s.max(0.0), &prefer)
        {
            return Err(bad(format!("the route ends before {path_s} m along it")));
        }
        // Facing as esmini's `OSCPositionRoute` faces it, not along the route's direction of
        // travel: a lane position the driving direction of the lane it names, a road
        // position the road's increasing `s`, each turned by the orientation given.
        match in_route {
            m::InRoute::Lane { lane, offset, .. } => {
                let road = &self.roads.map().roads[self.roads.ids(lp.lane).1].od_id;
                let to = self
                    .roads
                    .lane_pos(road, *lane, lp.s, *offset)
                    .map_err(|e| bad(e.to_string()))?;
                let h = orient(orientation, self.roads.travel_heading(&to));
                Ok(self.placed(to, h))
            }
            m::InRoute::Road { t, .. } => {
                let road = &self.roads.map().roads[self.roads.ids(lp.lane).1].od_id;
                let to = self
                    .roads
                    .road_pos(road, lp.s, *t)
                    .map_err(|e| bad(e.to_string()))?;
                Ok(self.placed(to, orient(orientation, self.roads.along_heading(&to))))
            }
            m::InRoute::Entity(_) => unreachable!("returned above"),
        }
    }
}
