//! The storyboard's actions: `Init` performed, references checked, and each running action's
//! task started by its kind, one file per kind (speed, speed profile, lateral, trajectory,
//! teleport, route, controller, distance, lateral distance, synchronize, trailer), and a
//! body trailing a reference point ahead of its rear axle.

mod controller;
mod distance;
mod global;
mod lateral;
mod lateral_distance;
mod rear_axle;
mod route;
mod speed;
mod speed_profile;
mod synchronize;
mod teleport;
mod trailer;
mod trajectory;

pub(in crate::xosc::story) use distance::Keep;
pub use global::{
    precipitation_extinction_per_m, Stored, WorldEnv, MAP_FRICTION, NOMINAL_ILLUMINANCE_LX,
    VISIBLE_WAVELENGTH_NM,
};
pub(in crate::xosc::story) use lateral::Lateral;
pub use lateral::DEFAULT_LATERAL_ACC_MPS2;
pub(in crate::xosc::story) use lateral_distance::{LatKeep, LatStep};
pub(in crate::xosc::story) use speed::SpeedTask;
pub(in crate::xosc::story) use speed_profile::Profile;
pub(in crate::xosc::story) use synchronize::Synchronizing;
pub(in crate::xosc::story) use trajectory::Path;

use super::*;

impl Storyboard {
    /// Performs `scenario`'s `Init`: positions first, each once the entities it is relative
    /// to are placed (in the file's order otherwise: a position may name an entity placed
    /// later in the file, as other readers accept), then the rest.
    ///
    /// # Errors
    /// [`StoryError`] for an `Init` action that cannot be performed (a position relative to
    /// an entity that `Init` never places, or a cycle of such positions, fails at the first
    /// left).
    pub(in crate::xosc::story) fn perform_init(
        &mut self,
        scenario: &m::Scenario,
    ) -> Result<(), StoryError> {
        let (places, rest): (Vec<_>, Vec<_>) = scenario
            .init
            .iter()
            .partition(|(_, a)| matches!(a.action, Action::Teleport(_)));
        // An entity is placed once its teleports are done; one Init never places stands
        // where it is from the start.
        let mut unplaced: Vec<bool> = vec![false; self.actors.len()];
        for (e, _) in &scenario.init {
            self.actors[*e].present = true;
            // Its trailers with it (esmini activates a combination whole), where they are
            // until a placement lines them up or their tow pulls them.
            let mut next = self.actors[*e].trailer;
            for _ in 0..self.actors.len() {
                let Some(k) = next else { break };
                self.actors[k].present = true;
                next = self.actors[k].trailer;
            }
        }
        for (e, _) in &places {
            unplaced[*e] = true;
        }
        let mut left = places;
        while !left.is_empty() {
            let ready = left.iter().position(|(_, a)| match &a.action {
                Action::Teleport(p) => relative_to(p).is_none_or(|r| !unplaced[r]),
                _ => true,
            });
            // None ready: the first left fails on its reference (or is placed, if it can be).
            let (e, a) = left.remove(ready.unwrap_or(0));
            self.start_task(*e, a, None, 0.0)?;
            if !left.iter().any(|(o, _)| o == e) {
                unplaced[*e] = false;
            }
        }
        for (e, a) in rest {
            self.start_task(*e, a, None, 0.0)?;
        }
        for a in &scenario.init_global {
            self.perform_global(a, 0.0)?;
        }
        Ok(())
    }

    /// Checks the roads and lanes that `na` names where they do not depend on where an
    /// entity is when it starts: a teleport, a synchronization's targets or a route's
    /// waypoint to a lane or road position (the road, the lane at that station), and a lane
    /// change to an absolute lane id (some road of the map has it). So a reference that
    /// cannot be met is refused when the file loads, at the action's line and column, rather
    /// than failing every test.
    ///
    /// A synchronization's target beyond its road's end is taken at the end, as esmini takes
    /// it, with a note ([`Storyboard::notes`]).
    ///
    /// # Errors
    /// [`StoryError`] at the action, naming the action and the map's refusal.
    pub(in crate::xosc::story) fn check_references(
        &mut self,
        na: &m::NamedAction,
    ) -> Result<(), StoryError> {
        if let Action::Synchronize(s) = &na.action {
            for p in [&s.master_target, &s.target] {
                if let (_, Some((asked, at))) = self.within_road(p) {
                    self.notes.push((
                        site(&na.pos),
                        format!(
                            "SynchronizeAction {:?}: its target at s = {asked} m lies beyond its \
                             road, which ends at {at:.2} m: it is taken at the road's end, as \
                             esmini takes it",
                            na.name
                        ),
                    ));
                }
            }
        }
        let refused = |message: String| StoryError {
            at: site(&na.pos),
            message: format!("{} {:?}: {message}", na.action.kind_name(), na.name),
        };
        let position = |p: &Position| -> Result<(), StoryError> {
            match p {
                Position::Lane { road, lane, s, .. } => self
                    .roads
                    .lane_pos(road, *lane, *s, 0.0)
                    .map(drop)
                    .map_err(|e| refused(e.to_string())),
                Position::Road { road, s, t, .. } => self
                    .roads
                    .road_pos(road, *s, *t)
                    .map(drop)
                    .map_err(|e| refused(e.to_string())),
                _ => Ok(()),
            }
        };
        match &na.action {
            Action::TrafficSignalState { signal, .. } => match self.signal_missing(signal) {
                Some(why) => Err(refused(why)),
                None => Ok(()),
            },
            Action::Teleport(p)
            | Action::AcquirePosition(p)
            | Action::AddEntity { position: p, .. } => position(p),
            Action::Synchronize(s) => {
                position(&self.within_road(&s.master_target).0)?;
                position(&self.within_road(&s.target).0)
            }
            Action::AssignRoute { waypoints } => {
                waypoints.iter().try_for_each(|(p, _)| position(p))
            }
            Action::LaneChange {
                target: LaneTarget::Absolute(id),
                ..
            } => {
                if self.roads.map().lanes.iter().any(|l| l.od_id == *id) {
                    Ok(())
                } else {
                    Err(refused(format!(
                        "no road of the map has a lane {id}, so no entity can change to it"
                    )))
                }
            }
            _ => Ok(()),
        }
    }

    /// Starts action `action` on entity `e` at `t` (s), for action element `a` (`None` in
    /// `Init`).
    pub(in crate::xosc::story) fn start_task(
        &mut self,
        e: usize,
        action: &m::NamedAction,
        a: Option<usize>,
        t: f64,
    ) -> Result<(), StoryError> {
        let bad = |message: String| StoryError {
            at: site(&action.pos),
            message,
        };
        let scripted = self.actors[e].scripted;
        match &action.action {
            Action::Teleport(p) => {
                if scripted || a.is_none() {
                    self.teleport(e, p, &action.pos)?;
                }
                // An event's teleport holds the entity for its step (`Drive::teleported`).
                self.drives[e].teleported = scripted && a.is_some();
            }
            Action::Speed {
                target: SpeedTarget::Absolute(v),
                ..
            } if *v < 0.0 && !scripted => {
                return Err(bad(backwards(action, *v, &self.actors[e].name)))
            }
            Action::Speed { target, dynamics } => {
                return self.start_speed(e, (target, dynamics), a, t);
            }
            Action::SpeedProfile(p) => self.start_profile_task(e, (p, action), a, t)?,
            Action::LaneChange {
                target,
                dynamics,
                offset_m,
            } => {
                return self.start_lane_change(e, (target, dynamics, offset_m), (a, &action.pos));
            }
            Action::LaneOffset {
                target,
                shape,
                max_lateral_acc,
                continuous,
            } => {
                return self.start_lane_offset(
                    e,
                    (target, shape, max_lateral_acc, continuous),
                    (a, &action.pos),
                );
            }
            Action::LongitudinalDistance { .. } if scripted => self.start_keep(e, action, a)?,
            // On the ego a system under test drives, refused at load.
            Action::LateralDistance { .. } if scripted => self.start_lat_keep(e, action, a)?,
            Action::LateralDistance { .. } => {}
            Action::LongitudinalDistance { .. } => {}
            Action::FollowTrajectory {
                shape,
                timing,
                position_mode,
                initial_offset_m: offset,
            } => {
                let how = (shape, timing, *position_mode, *offset);
                return self.start_trajectory(e, how, (a, &action.pos), t);
            }
            Action::AssignRoute { waypoints } => {
                self.assign_route(e, waypoints, &action.pos, scripted)?;
            }
            Action::AcquirePosition(p) => {
                self.acquire_position(e, p, &action.pos, scripted)?;
            }
            Action::Trailer(trailer) => self.hitch(e, *trailer, &action.pos)?,
            // On the ego a system under test drives, refused at load.
            Action::Synchronize(s) if scripted => self.start_sync(e, s, a, &action.pos)?,
            Action::Synchronize(_) => {}
            Action::ActivateController { .. }
            | Action::AssignController { .. }
            | Action::OverrideController => self.controller_action(e, &action.action),
            // Performed once by their action, not per actor ([`Storyboard::start_action`]).
            Action::Environment(_)
            | Action::SetValue { .. }
            | Action::ModifyValue { .. }
            | Action::AddEntity { .. }
            | Action::DeleteEntity { .. }
            | Action::Nothing
            | Action::TrafficSignalState { .. } => {}
            // Nothing the storyboard moves reads lights or visibility: the front end refuses
            // a visibility that a system under test would sense ([`crate::xosc::check`]).
            // Each ends in the next step, as esmini's ends in its first `Step`.
            Action::Appearance(_) | Action::Visibility { .. } => self.end_next_step(a),
        }
        Ok(())
    }
}

impl Storyboard {
    /// Starts `SpeedProfileAction` `p` (of action `action`) on `e`, for action element `a` at
    /// `t` (s).
    ///
    /// # Errors
    /// [`StoryError`] at the action when it asks the ego a system under test drives a
    /// negative speed (its systems drive forward only).
    fn start_profile_task(
        &mut self,
        e: usize,
        (p, action): (&m::SpeedProfile, &m::NamedAction),
        a: Option<usize>,
        t: f64,
    ) -> Result<(), StoryError> {
        if !self.actors[e].scripted && p.entity.is_none() {
            if let Some((_, v)) = p.entries.iter().find(|(_, v)| *v < 0.0) {
                return Err(StoryError {
                    at: site(&action.pos),
                    message: backwards(action, *v, &self.actors[e].name),
                });
            }
        }
        self.start_speed_profile(e, p, a, t);
        Ok(())
    }

    /// Has action element `a` (if any) end in the next step.
    fn end_next_step(&mut self, a: Option<usize>) {
        if let Some(a) = a {
            self.elems[a].pending += 1;
            self.ending_next.push(a);
        }
    }

    /// Starts the `LongitudinalDistanceAction` `action` on scripted entity `e`, for action
    /// element `a` (`None` in `Init`).
    ///
    /// # Errors
    /// [`StoryError`] at the action when the entity cannot be placed at its distance.
    fn start_keep(
        &mut self,
        e: usize,
        action: &m::NamedAction,
        a: Option<usize>,
    ) -> Result<(), StoryError> {
        let Action::LongitudinalDistance {
            entity,
            distance_m,
            time_gap_s,
            freespace,
            displacement,
            continuous,
            frame,
            constraints,
        } = &action.action
        else {
            return Ok(());
        };
        let spring = constraints
            .map(|c| self.spring_for(e, *entity, &c, (displacement, frame, *continuous)));
        let keep = distance::Keep {
            reference: *entity,
            gap: (*distance_m, *time_gap_s, *freespace),
            displacement: displacement.clone(),
            action: a.unwrap_or(usize::MAX),
            at: site(&action.pos),
            spring,
        };
        self.start_distance(e, keep, *continuous)
            .map_err(|err| StoryError {
                at: site(&action.pos),
                message: err.to_string(),
            })
    }
}

/// Why `SpeedAction` or `SpeedProfileAction` `action`, to `v` m/s (`< 0`), cannot be performed on entity `name`,
/// which a system under test drives.
fn backwards(action: &m::NamedAction, v: f64, name: &str) -> String {
    format!(
        "{} {:?} to {v} m/s asks {name} to drive backwards, which paracosm's systems \
         under test do not do (they drive forward only; the storyboard reverses an entity it \
         moves itself: --scripted-ego)",
        action.action.kind_name(),
        action.name
    )
}

/// The entity position `p` is relative to, if any.
fn relative_to(p: &Position) -> Option<usize> {
    match p {
        Position::RelativeWorld { entity, .. }
        | Position::RelativeObject { entity, .. }
        | Position::RelativeRoad { entity, .. }
        | Position::RelativeLane { entity, .. } => Some(*entity),
        Position::Route {
            at: m::InRoute::Entity(entity),
            ..
        } => Some(*entity),
        _ => None,
    }
}
