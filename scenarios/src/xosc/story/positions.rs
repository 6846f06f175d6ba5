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
                orientation,
            } => self.object_offset(*entity, *dx, *dy, orientation),
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
            Position::RelativeLane {
                entity,
                d_lane,
                ds,
                offset,
            } => {
                let lp = self.lane_of(*entity, "RelativeLanePosition", at)?;
                let lp = self
                    .roads
                    .relative_lane(&lp, *d_lane, *ds, *offset)
                    .map_err(|e| bad(e.to_string()))?;
                (self.roads.pose_of(&lp), Some(lp))
            }
        })
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

    /// A `RelativeObjectPosition`: `dx` forward and `dy` left (m, in entity `entity`'s
    /// frame) of the entity, heading `orientation` against the entity's (rad); its pose and
    /// its place on the lanes.
    pub(in crate::xosc::story) fn object_offset(
        &self,
        entity: usize,
        dx: f64,
        dy: f64,
        orientation: &Option<m::Orientation>,
    ) -> (Pose, Option<LanePos>) {
        let r = self.actors[entity].state.pose;
        let (c, s) = (r.h.cos(), r.h.sin());
        let (x, y) = (r.x + c * dx - s * dy, r.y + s * dx + c * dy);
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
