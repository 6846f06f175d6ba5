//! Scripted entities driven each step by their tasks in progress: speed, lateral move and
//! trajectory, along the map's lanes.

use super::*;
use paracosm_engine::transition::LateralRule;

/// A speed target that follows another entity: its index, the value, whether a factor.
pub(in crate::xosc::story) type Track = Option<(usize, f64, bool)>;

/// A lane change's target: the lane and the offset from its centre there, m.
pub(in crate::xosc::story) type ToLane = Option<(usize, f64)>;

/// A scripted entity's motion in progress, each with the action it belongs to.
#[derive(Debug, Clone, Default)]
pub(in crate::xosc::story) struct Drive {
    /// The `SpeedAction` in progress.
    pub(in crate::xosc::story) speed: Option<SpeedTask>,
    /// The last `SpeedProfileAction`'s plan, which the speed task steps while it is
    /// [`SpeedTask::profiled`].
    pub(in crate::xosc::story) profile: Profile,
    /// The lateral move in progress.
    pub(in crate::xosc::story) lateral: Option<Lateral>,
    /// The continuous `LongitudinalDistanceAction` in progress.
    pub(in crate::xosc::story) keep: Option<Keep>,
    /// The `SynchronizeAction` in progress.
    pub(in crate::xosc::story) sync: Option<Synchronizing>,
    /// Its speed before a synchronization set this step's (m/s), for its acceleration.
    pub(in crate::xosc::story) speed_before: Option<f64>,
    /// The trajectory in progress and its action.
    pub(in crate::xosc::story) path: Option<(Path, usize)>,
    /// Where that trajectory's action is written, `file:line:col`.
    pub(in crate::xosc::story) path_at: String,
    /// A driven ego's lane change in progress: the lane it changes to, the offset from its
    /// centre there (m), the action; it ends once the ego is there ([`LANE_REACHED_M`]).
    pub(in crate::xosc::story) lane_goal: Option<(usize, f64, usize)>,
    /// A driven ego's trajectory in progress, handed to its system as its route: where it
    /// ends and the action; it ends once the ego is there ([`PATH_END_REACHED_M`]).
    pub(in crate::xosc::story) path_goal: Option<(Pose, usize)>,
    /// The roads of its route in order (its `AssignRouteAction` or `AcquirePositionAction`,
    /// junctions' connecting roads included): where its lanes fork, it takes the way on.
    pub(in crate::xosc::story) prefer_roads: Vec<usize>,
    /// How far along [`Drive::prefer_roads`] it has come: the index of the road it was last
    /// seen on.
    pub(in crate::xosc::story) route_at: usize,
    /// Its heading relative to its lane's travel, rad, kept as it moves along the lane
    /// (esmini's relative heading): set where it is placed or where its trajectory ends,
    /// 0 after a lateral move.
    pub(in crate::xosc::story) rel_h: f64,
    /// Teleported by an event in this step: it stands where it was put until the next step
    /// (esmini's `TeleportAction` marks the entity's longitudinal motion as done for the
    /// frame, so its default controller does not move it).
    pub(in crate::xosc::story) teleported: bool,
    /// The `LateralDistanceAction` in progress.
    pub(in crate::xosc::story) lat_keep: Option<LatKeep>,
    /// It goes straight along its heading, not along its lanes: CARLA's
    /// `vehicle_longitudinal_control` ([`STRAIGHT_CONTROLLERS`]) drives its speed and leaves
    /// its steering as it is.
    pub(in crate::xosc::story) straight: bool,
}

/// Controllers that drive an entity's speed only, leaving its steering straight (CARLA
/// scenario_runner's `VehicleLongitudinalControl`: the throttle to its target speed, the
/// steering untouched): the storyboard moves the entity straight along its heading at the
/// speeds its actions ask, not along its lanes.
pub const STRAIGHT_CONTROLLERS: [&str; 1] = ["vehicle_longitudinal_control"];

/// The speed `v` (m/s) a `SpeedAction`'s `task` asks at the end of a step from `t` of `dt` s
/// from the entity's speed `v0` (m/s), within the entity's `performance` as esmini keeps it
/// (`LongSpeedAction::Step`): the speed at most `max_speed` in magnitude, and a change faster
/// than `max_acceleration` (or `max_deceleration`) cut to it, the transition put back by the
/// time the step did not cover; with whether the action is `over`, which it is only once its
/// target is reached. A step shape jumps in the step it starts in (esmini sets its speed
/// when the action starts); one that follows another entity's speed is limited after.
fn limited(
    task: &mut SpeedTask,
    performance: m::Performance,
    (v, over): (f64, bool),
    (v0, t, dt): (f64, f64, f64),
) -> (f64, bool) {
    let v = v.clamp(-performance.max_speed_mps, performance.max_speed_mps);
    let starts_now = task.tr.start_s >= t - 1e-9;
    if task.tr.duration_s <= 0.0 && (task.track.is_none() || starts_now) || dt <= 0.0 {
        return (v, over);
    }
    let required = (v - v0) / dt;
    let (lo, hi) = (
        -performance.max_deceleration_mps2,
        performance.max_acceleration_mps2,
    );
    if required <= hi + 1e-6 && required >= lo - 1e-6 {
        return (v, over);
    }
    let acc = required.clamp(lo, hi);
    let cut = (v0 + acc * dt).clamp(-performance.max_speed_mps, performance.max_speed_mps);
    // The share of the step the transition moved on.
    let covered = (cut - v0) / required;
    task.tr.start_s += dt - covered;
    let target = task
        .tr
        .to
        .clamp(-performance.max_speed_mps, performance.max_speed_mps);
    (cut, over && (cut - target).abs() < 1e-6)
}

impl Storyboard {
    /// Moves scripted entity `e` from `t` to `t + dt`.
    pub(in crate::xosc::story) fn drive(
        &mut self,
        e: usize,
        t: f64,
        dt: f64,
    ) -> Result<(), StoryError> {
        let t1 = t + dt;
        let st = self.actors[e].state;
        // Speed.
        let mut v1 = st.speed;
        let mut done = Vec::new();
        let speed_action = self.drives[e].speed.map(|task| task.action);
        if let Some(mut task) = self.drives[e].speed {
            let (v, over) = self.speed_task_at(e, &task, t1);
            let performance = self.actors[e].performance;
            // A profile keeps its own constraints (esmini's sets its speed as planned).
            let (v, over) = if task.profiled {
                (v, over)
            } else {
                limited(&mut task, performance, (v, over), (st.speed, t, dt))
            };
            v1 = v;
            self.drives[e].speed = Some(task);
            // A hold by distance (CARLA's reading) counts this step's move.
            if over && task.ends(t1, st.travelled_m + v.max(0.0) * dt) {
                self.drives[e].speed = None;
                done.push(task.action);
            }
        }
        // At the new speed over the step (esmini's integration: the speed first, then the
        // move), backwards at a negative one (esmini's `MoveAlongS` by a negative distance);
        // not at all in the step an event teleported it.
        let held = std::mem::take(&mut self.drives[e].teleported);
        let travel = if self.lane_change_first(e, speed_action) {
            st.speed
        } else {
            v1
        };
        let dist = if held { 0.0 } else { travel * dt };
        // A kept lateral distance moves it itself, or places it on its lane to move on from.
        let (lat, lat_ended) = self.lat_keep_step(e, v1, dt);
        done.extend(lat_ended);
        let (pose, lane, at_end, speed_now) = match lat {
            LatStep::Moved(p, l) => (p, l, false, v1),
            LatStep::Offset(lp, h) => {
                self.drives[e].rel_h = self.relative_heading(h, Some(lp));
                let from = State {
                    pose: self.roads.pose_of(&lp),
                    lane: Some(lp),
                    ..st
                };
                self.move_on(e, &from, (dist, v1), (t1, dt), &mut done)
            }
            LatStep::Idle => self.move_on(e, &st, (dist, v1), (t1, dt), &mut done),
        };
        // Held at its road's end since the step before, where it did not move: it stands
        // (esmini's `ScenarioEngine::step` sets such an entity's speed to 0, so an action
        // started later begins from rest).
        let stuck = at_end && st.at_end_s.is_some() && st.vel[0].hypot(st.vel[1]) < 1e-9;
        let speed_now = if stuck { 0.0 } else { speed_now };
        let moved = (pose.x - st.pose.x).hypot(pose.y - st.pose.y);
        // Standing where its road ended, it is still there (esmini's position keeps its
        // end-of-road status while it does not move).
        let at_end = at_end || (!held && moved < 1e-12 && st.at_end_s.is_some());
        let before = self.drives[e].speed_before.take();
        let s = &mut self.actors[e].state;
        s.accel = (speed_now - before.unwrap_or(s.speed)) / dt;
        s.speed = speed_now;
        s.lane = lane;
        s.travelled_m += moved;
        s.vel = if held {
            [speed_now * pose.h.cos(), speed_now * pose.h.sin()]
        } else {
            [(pose.x - s.pose.x) / dt, (pose.y - s.pose.y) / dt]
        };
        s.pose = pose;
        s.still_s = if speed_now.abs() < 1e-3 {
            s.still_s + dt
        } else {
            0.0
        };
        s.at_end_s = at_end.then(|| s.at_end_s.map_or(0.0, |d| d + dt));
        for a in done {
            self.override_task(Some(a));
        }
        Ok(())
    }

    /// The roads of entity `e`'s route it may take next from lane `lane`: where that lane's
    /// road is on the route at or after where it has come ([`Drive::route_at`], moved on to
    /// it), that road and the two after it (a junction's connecting road and the road it
    /// leads to), so that a road the route takes again later does not draw it off its way;
    /// off the route, every road of it.
    fn route_ahead(&mut self, e: usize, lane: usize) -> Vec<usize> {
        let road = self.roads.ids(lane).1;
        let d = &mut self.drives[e];
        let from = d.route_at.min(d.prefer_roads.len());
        match d.prefer_roads[from..].iter().position(|&r| r == road) {
            Some(j) => {
                d.route_at = from + j;
                let end = (d.route_at + 3).min(d.prefer_roads.len());
                d.prefer_roads[d.route_at..end].to_vec()
            }
            None => d.prefer_roads.clone(),
        }
    }

    /// Whether entity `e`'s lane change is stepped before its speed's action
    /// (`speed_action`) in esmini's order: `Init`'s actions first, then the stories' in the
    /// order they are written. esmini's `LatLaneChangeAction` moves the entity along its
    /// lane itself, at the speed it has when the lane change is stepped; a speed action
    /// stepped later changes the speed for the next step.
    fn lane_change_first(&self, e: usize, speed_action: Option<usize>) -> bool {
        // `Init`'s actions (`usize::MAX`) come first.
        let order = |a: usize| a.wrapping_add(1);
        match (self.drives[e].lateral, speed_action) {
            (Some(l), Some(s)) => {
                !matches!(l.mv.rule, LateralRule::Offset) && order(l.action) < order(s)
            }
            _ => false,
        }
    }

    /// Scripted entity `e` in state `st` moved a step of `dt` s ending at `t1` (s), in which
    /// it travels `dist` m at speed `v1` (m/s): along its trajectory, its lanes, or its
    /// heading. Its pose, lane position, whether its lanes ended, and its speed (a timed
    /// trajectory's own); the actions whose motion ended are pushed on `done`.
    fn move_on(
        &mut self,
        e: usize,
        st: &State,
        (dist, v1): (f64, f64),
        (t1, dt): (f64, f64),
        done: &mut Vec<usize>,
    ) -> (Pose, Option<LanePos>, bool, f64) {
        let mut pose = st.pose;
        let mut lane = st.lane;
        let mut at_end = false;
        let mut speed_now = v1;
        if let Some((path, a)) = &mut self.drives[e].path {
            let (p, over) = path.step(t1, dist);
            let timed = matches!(path, Path::Timed(_));
            let a = *a;
            if timed {
                let moved = (p.x - pose.x).hypot(p.y - pose.y);
                if moved > 1e-9 || !over {
                    speed_now = moved / dt;
                }
            }
            pose = p;
            lane = self.facing(self.roads.anchor(p.x, p.y), p.h);
            if over {
                // It goes on at the speed it had, along its lane facing the way the last leg
                // went (esmini's reading).
                self.drives[e].rel_h = self.relative_heading(p.h, lane);
                self.drives[e].path = None;
                done.push(a);
            }
        } else if let Some(lp) = lane.filter(|_| !self.drives[e].straight) {
            let (p, l, end, ended) = self.drive_on_lane(e, lp, (dist, dt, pose.h));
            pose = p;
            lane = Some(l);
            at_end = end;
            done.extend(ended);
        } else if self.roads.map().roads.is_empty() {
            // On open ground (no road network) nothing but a trajectory moves it: esmini's
            // default controller cannot move it along a road and stops it.
            speed_now = 0.0;
        } else {
            (pose, lane) = self.straight_on(e, pose, dist);
        }
        (pose, lane, at_end, speed_now)
    }

    /// Scripted entity `e` at `pose`, off its lanes or driven straight
    /// ([`Drive::straight`]), moved `dist` m along its heading: its pose, and where it is on
    /// the lanes when it is driven straight (for the conditions that read it), else none.
    fn straight_on(&self, e: usize, mut pose: Pose, dist: f64) -> (Pose, Option<LanePos>) {
        pose.x += dist * pose.h.cos();
        pose.y += dist * pose.h.sin();
        let lane = if self.drives[e].straight {
            self.facing(self.roads.anchor(pose.x, pose.y), pose.h)
        } else {
            None
        };
        (pose, lane)
    }

    /// Moves scripted entity `e`, on lane position `lp` facing `h0`, a step of `dt` s in which
    /// it travels `dist` m, along its lanes with its lateral move: its pose, lane position,
    /// whether its lanes ended, and the action whose lateral move ended (if any).
    ///
    /// A lateral move is stepped by the engine's one transition implementation
    /// ([`paracosm_engine::transition::LateralMove::step`], esmini's `LatLaneChangeAction` and
    /// `LatLaneOffsetAction`).
    pub(in crate::xosc::story) fn drive_on_lane(
        &mut self,
        e: usize,
        mut lp: LanePos,
        (dist, dt, h0): (f64, f64, f64),
    ) -> (Pose, LanePos, bool, Option<usize>) {
        let mut ended = None;
        // Backwards, the same path the other way: the lateral move steps on the distance
        // travelled, and the move along the lane is taken against its travel.
        let back = dist < 0.0;
        let mut along = dist.abs();
        // The heading relative to the lane's travel, as a slope against the travel.
        let mut slip = 0.0;
        if let Some(mut l) = self.drives[e].lateral {
            let (d, over, a, s) = l.mv.step(lp.d, dist.abs(), dt);
            (along, slip) = (a, s);
            lp.d = d;
            self.drives[e].lateral = Some(l);
            if over {
                slip = 0.0;
                if let Some((k, offset)) = l.to_lane {
                    let up = lp.along_s(&self.roads);
                    let beside = (self.roads.ids(k).1 == self.roads.ids(lp.lane).1)
                        .then(|| self.roads.lane_with_id(lp.lane, self.roads.ids(k).0, lp.s))
                        .flatten();
                    if let Some(k2) = beside {
                        // Re-anchored on the target lane beside it here.
                        lp.lane = k2;
                        lp.rev = self.roads.forward(k2) != up;
                        lp.d = offset;
                    }
                }
                if !l.continuous {
                    self.drives[e].lateral = None;
                    ended = Some(l.action);
                }
            }
        }
        let prefer_roads = self.route_ahead(e, lp.lane);
        // A route names the roads it takes; a junction's connecting road is preferred by
        // the road it leads to.
        let prefer = |n: usize| {
            prefer_roads.contains(&self.roads.ids(n).1)
                || prefer_roads.contains(&self.roads.exit_road(n))
        };
        let up_before = lp.along_s(&self.roads);
        lp.rev ^= back;
        let at_end = !self.roads.advance(&mut lp, along, &prefer);
        lp.rev ^= back;
        if lp.along_s(&self.roads) != up_before {
            // Its lane runs on in a road of the other direction: a lateral move in
            // progress keeps its side of the motion.
            if let Some(l) = &mut self.drives[e].lateral {
                l.mv.tr.from = -l.mv.tr.from;
                l.mv.tr.to = -l.mv.tr.to;
                if let Some((_, offset)) = &mut l.to_lane {
                    *offset = -*offset;
                }
            }
        }
        let travel = self.roads.travel_heading(&lp);
        // `d` is left of increasing `s`: against `s`, the same move turns the other way.
        let side = if lp.along_s(&self.roads) { 1.0 } else { -1.0 };
        let h = if dist.abs() > 1e-12 {
            wrap(travel + side * slip + self.drives[e].rel_h)
        } else {
            h0
        };
        let mut pose = self.roads.pose_of(&lp);
        // Standing still, it keeps the way it faces.
        pose.h = h;
        (pose, lp, at_end, ended)
    }
}
