//! `LaneChangeAction` and `LaneOffsetAction`: a lateral move over time or distance, or the
//! route asked of the driven ego.

use super::super::*;
use paracosm_engine::transition::{LateralMove, LateralRule};
use paracosm_openscenario::model::OffsetTarget;

/// The largest lateral acceleration of a `LaneOffsetAction` without `maxLateralAcc`, m/s².
pub const DEFAULT_LATERAL_ACC_MPS2: f64 = 0.5;

/// A lateral move (`LaneChangeAction`, `LaneOffsetAction`) as esmini performs it: the
/// engine's [`LateralMove`] (the offset `d`, m, left of increasing `s`, over time or the path
/// along the lane, stepped by its [`LateralRule`]), with the lane it changes to and its action.
#[derive(Debug, Clone, Copy)]
pub(in crate::xosc::story) struct Lateral {
    /// The move, stepped by the engine.
    pub(in crate::xosc::story) mv: LateralMove,
    /// The lane it changes to.
    pub(in crate::xosc::story) to_lane: ToLane,
    /// Its action.
    pub(in crate::xosc::story) action: usize,
    /// Whether it goes on after its transition (`continuous`).
    pub(in crate::xosc::story) continuous: bool,
}

impl Storyboard {
    /// Starts a `LaneChangeAction` on `e`.
    pub(in crate::xosc::story) fn start_lane_change(
        &mut self,
        e: usize,
        (target, dynamics, offset_m): (&LaneTarget, &m::Dynamics, &f64),
        (a, pos): (Option<usize>, &paracosm_openscenario::Pos),
    ) -> Result<(), StoryError> {
        let bad = |message: String| StoryError {
            at: site(pos),
            message,
        };
        let scripted = self.actors[e].scripted;
        let st = self.actors[e].state;
        let Some(lp) = st.lane else {
            return Err(bad(format!(
                "a LaneChangeAction for {}, which is not on a lane",
                self.actors[e].name
            )));
        };
        let id = self.lane_change_target_id(target, pos)?;
        let to_lane = self.roads.lane_with_id(lp.lane, id, lp.s).ok_or_else(|| {
            bad(format!(
                "{}'s road has no lane {id} at s = {:.1} m",
                self.actors[e].name, lp.s
            ))
        })?;
        let target_d = self.roads.lateral_between(lp.lane, to_lane, lp.s) + offset_m;
        // By distance, the parameter is the path along the lane; by time or rate, time.
        let by_distance = dynamics.dimension == m::Dimension::Distance;
        let duration = if by_distance {
            dynamics.value.abs()
        } else {
            duration_s(dynamics, target_d - lp.d, st.speed.abs())
        };
        if !scripted {
            self.ask_lane_change_route(e, (lp, to_lane, *offset_m), (by_distance, duration), a);
            return Ok(());
        }
        // As esmini's `LatLaneChangeAction`: the entity is anchored on the lane it changes
        // to from the start, its offset from that lane's centre moving to the offset asked,
        // so that it follows where that lane runs (a lane that widens as it opens beside
        // it, esmini's `two_plus_one_road`), not where it ran when the change started.
        let from = lp.d - (target_d - offset_m);
        let anchored = LanePos {
            lane: to_lane,
            d: from,
            rev: self.roads.forward(to_lane) != lp.along_s(&self.roads),
            ..lp
        };
        self.actors[e].state.lane = Some(anchored);
        let tr = Transition {
            from,
            to: *offset_m,
            start_s: 0.0,
            duration_s: if dynamics.shape == m::Shape::Step {
                0.0
            } else {
                duration
            },
            shape: shape_of(dynamics.shape),
        };
        let rule = if by_distance {
            LateralRule::TravelByDistance
        } else {
            LateralRule::TravelByTime
        };
        self.begin_lateral(
            e,
            Lateral {
                mv: LateralMove {
                    tr,
                    param: 0.0,
                    rule,
                },
                to_lane: Some((to_lane, *offset_m)),
                action: a.unwrap_or(usize::MAX),
                continuous: false,
            },
            a,
        );
        Ok(())
    }

    /// The lane id a `LaneChangeAction` (written at `pos`) changes to: an absolute one as
    /// written; a relative one counted from the reference entity's lane, to its left as it
    /// drives, skipping id 0.
    ///
    /// # Errors
    /// [`StoryError`] at `pos` when the reference entity is on no lane.
    pub(in crate::xosc::story) fn lane_change_target_id(
        &self,
        target: &LaneTarget,
        pos: &paracosm_openscenario::Pos,
    ) -> Result<i32, StoryError> {
        Ok(match target {
            LaneTarget::Absolute(id) => *id,
            LaneTarget::Relative { entity, lanes } => {
                let Some(rl) = self.actors[*entity].state.lane else {
                    return Err(StoryError {
                        at: site(pos),
                        message: format!(
                            "a lane change relative to {}, which is not on a lane",
                            self.actors[*entity].name
                        ),
                    });
                };
                // Counted to the reference's left as it drives: +t along s.
                let step = if rl.along_s(&self.roads) {
                    lanes.signum()
                } else {
                    -lanes.signum()
                };
                let mut id = self.roads.ids(rl.lane).0;
                for _ in 0..lanes.unsigned_abs() {
                    id += step;
                    if id == 0 {
                        id += step;
                    }
                }
                id
            }
        })
    }

    /// A lane change of the driven ego `e` (which the system under test drives), from `lp`
    /// into lane `to_lane` at `offset_m` (m) from its centre, for action `a`: asks for a
    /// route into the lane over the change's length (`duration` is m when `by_distance`,
    /// else s at the ego's speed; at least one second of driving and 1 m), which it follows,
    /// and notes the lane goal that ends the action, ending the one it replaces.
    pub(in crate::xosc::story) fn ask_lane_change_route(
        &mut self,
        e: usize,
        (lp, to_lane, offset_m): (LanePos, usize, f64),
        (by_distance, duration): (bool, f64),
        a: Option<usize>,
    ) {
        let st = self.actors[e].state;
        // The system under test drives it: a route into the lane, over the change's
        // length (at least one second of driving), which it follows.
        let ahead_m = if by_distance {
            duration
        } else {
            duration * st.speed.abs()
        }
        .max(st.speed.abs())
        .max(1.0);
        let join = LanePos {
            lane: to_lane,
            s: lp.s,
            d: offset_m,
            rev: lp.rev,
        };
        self.route = Some(RouteAsk {
            join,
            ahead_m,
            path: Vec::new(),
        });
        // A trajectory handed before ends: the lane change's route replaces it.
        let old_path = self.drives[e].path_goal.take().map(|g| g.1);
        self.override_task(old_path);
        let old = self.drives[e].lane_goal.take().map(|g| g.2);
        self.override_task(old);
        if let Some(a) = a {
            self.elems[a].pending += 1;
        }
        self.drives[e].lane_goal = Some((to_lane, offset_m, a.unwrap_or(usize::MAX)));
    }

    /// Starts lateral move `l` of `e` for action `a`, ending the one it replaces.
    pub(in crate::xosc::story) fn begin_lateral(&mut self, e: usize, l: Lateral, a: Option<usize>) {
        let old = [
            self.drives[e].lateral.take().map(|s| s.action),
            self.drives[e].lat_keep.take().map(|k| k.action),
        ];
        for o in old {
            self.override_task(o);
        }
        if let Some(a) = a {
            self.elems[a].pending += 1;
        }
        // It aligns with the road as it starts (esmini's reading).
        self.drives[e].rel_h = 0.0;
        self.drives[e].lateral = Some(l);
    }

    /// Starts a `LaneOffsetAction` on `e`.
    pub(in crate::xosc::story) fn start_lane_offset(
        &mut self,
        e: usize,
        (target, shape, max_lateral_acc, continuous): (
            &OffsetTarget,
            &m::Shape,
            &Option<f64>,
            &bool,
        ),
        (a, pos): (Option<usize>, &paracosm_openscenario::Pos),
    ) -> Result<(), StoryError> {
        let bad = |message: String| StoryError {
            at: site(pos),
            message,
        };
        let scripted = self.actors[e].scripted;
        let Some(lp) = self.actors[e].state.lane else {
            return Err(bad(format!(
                "a LaneOffsetAction for {}, which is not on a lane",
                self.actors[e].name
            )));
        };
        let to = match target {
            OffsetTarget::Absolute(v) => *v,
            OffsetTarget::Relative { entity, value } => {
                self.actors[*entity].state.lane.map_or(0.0, |l| l.d) + value
            }
        };
        let acc = max_lateral_acc.unwrap_or(DEFAULT_LATERAL_ACC_MPS2);
        if !scripted {
            // The system under test drives it: a route along its lane at the offset, over
            // the move's time at its speed; a continuous offset is held until another
            // lateral action replaces it (its goal is never reached).
            let duration = offset_duration_s(*shape, to - lp.d, acc);
            self.ask_lane_change_route(e, (lp, lp.lane, to), (false, duration), a);
            if *continuous {
                if let Some(goal) = &mut self.drives[e].lane_goal {
                    goal.1 = f64::NAN;
                }
            }
            return Ok(());
        }
        let tr = Transition {
            from: lp.d,
            to,
            start_s: 0.0,
            duration_s: offset_duration_s(*shape, to - lp.d, acc),
            shape: shape_of(*shape),
        };
        self.begin_lateral(
            e,
            Lateral {
                mv: LateralMove {
                    tr,
                    param: 0.0,
                    rule: LateralRule::Offset,
                },
                to_lane: None,
                action: a.unwrap_or(usize::MAX),
                continuous: *continuous,
            },
            a,
        );
        Ok(())
    }

    /// Ends the driven ego `e`'s `LaneChangeAction` once it is in the lane it changes to,
    /// within [`LANE_REACHED_M`] of the offset asked.
    pub(in crate::xosc::story) fn ask_lane(&mut self, e: usize) {
        let Some((lane, offset, a)) = self.drives[e].lane_goal else {
            return;
        };
        let there = self.actors[e]
            .state
            .lane
            .is_some_and(|lp| lp.lane == lane && (lp.d - offset).abs() <= LANE_REACHED_M);
        if there {
            self.drives[e].lane_goal = None;
            self.task_done(Some(a));
        }
    }
}
