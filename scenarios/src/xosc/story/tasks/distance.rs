//! `LongitudinalDistanceAction`: an entity kept at a distance or time gap from another.

use super::super::*;

/// A continuous `LongitudinalDistanceAction` in progress on one entity: placed each step at
/// the distance from its reference, with the reference's speed (esmini's
/// `LongDistanceAction::Step` without dynamic constraints).
#[derive(Debug, Clone)]
pub(in crate::xosc::story) struct Keep {
    /// The entity it keeps its distance to.
    pub(in crate::xosc::story) reference: usize,
    /// Distance, m, or time gap, s (one of the two), and whether between bounding boxes.
    pub(in crate::xosc::story) gap: (Option<f64>, Option<f64>, bool),
    /// `displacement` as written.
    pub(in crate::xosc::story) displacement: String,
    /// Its action (`usize::MAX` in `Init`).
    pub(in crate::xosc::story) action: usize,
    /// Where the action is written, `file:line:col`.
    pub(in crate::xosc::story) at: String,
}

impl Storyboard {
    /// Starts a `LongitudinalDistanceAction` on scripted entity `e` for action `a`: placed at
    /// the distance now, and, `continuous`, kept there each step ([`Storyboard::keep_distances`])
    /// until its action is stopped or a `SpeedAction` (the same longitudinal domain) replaces
    /// it, the action running meanwhile.
    ///
    /// # Errors
    /// What [`Storyboard::place_at_distance`] returns.
    pub(in crate::xosc::story) fn start_distance(
        &mut self,
        e: usize,
        keep: Keep,
        continuous: bool,
    ) -> Result<(), RoadError> {
        self.place_at_distance(e, keep.reference, keep.gap, &keep.displacement)?;
        if continuous {
            self.end_longitudinal(e);
            if keep.action != usize::MAX {
                self.elems[keep.action].pending += 1;
            }
            self.drives[e].keep = Some(keep);
        }
        Ok(())
    }

    /// Places every scripted entity that keeps a distance, against where its reference is at
    /// the start of this step, before any entity moves (esmini steps every action, then moves
    /// the entities), with its reference's speed at the end of the step `t1` (s).
    ///
    /// # Errors
    /// What [`Storyboard::place_at_distance`] returns, at the action.
    pub(in crate::xosc::story) fn keep_distances(&mut self, t1: f64) -> Result<(), StoryError> {
        for e in 0..self.actors.len() {
            if !self.actors[e].scripted {
                continue;
            }
            // Taken out for the step and put back: no copy of its texts each step.
            let Some(k) = self.drives[e].keep.take() else {
                continue;
            };
            let placed = self.place_at_distance(e, k.reference, k.gap, &k.displacement);
            // With the speed a scripted reference's `SpeedAction` gives it over this step,
            // which esmini has stepped by then (an action before this one). A reference the
            // system under test drives has the speed it drives at: its `SpeedAction` is
            // only the speed asked of that system.
            if placed.is_ok() && self.actors[k.reference].scripted {
                if let Some(task) = self.drives[k.reference].speed {
                    let (v, _) = task.step(t1, |r| self.actors[r].state.speed);
                    self.actors[e].state.speed = v.max(0.0);
                }
            }
            let result = placed.map_err(|err| StoryError {
                at: k.at.clone(),
                message: format!(
                    "LongitudinalDistanceAction of {}: {err}",
                    self.actors[e].name
                ),
            });
            self.drives[e].keep = Some(k);
            result?;
        }
        Ok(())
    }

    /// Puts entity `e` on `reference`'s lane at a distance `(distance, time gap, freespace)`
    /// ahead of it (`leadingReferencedEntity`; `any` with a negative distance, or when ahead
    /// now) or behind it, with the reference's speed.
    pub(in crate::xosc::story) fn place_at_distance(
        &mut self,
        e: usize,
        reference: usize,
        (distance, gap_s, freespace): (Option<f64>, Option<f64>, bool),
        displacement: &str,
    ) -> Result<(), RoadError> {
        let r = self.actors[reference].clone();
        let me = self.actors[e].clone();
        let Some(rl) = r.state.lane else {
            return Err(RoadError(format!(
                "a LongitudinalDistanceAction to {}, which is not on a lane",
                r.name
            )));
        };
        let gap = match (distance, gap_s) {
            (Some(d), _) => d,
            (None, Some(g)) => g * r.state.speed.abs(),
            (None, None) => 0.0,
        };
        // The standard's distance is at least 0; a negative one with `any` (the
        // `scenariogeneration` package's Euro NCAP CCRb files write -12) puts the entity ahead,
        // as esmini reads it (its requested distance from the entity to its reference keeps
        // the sign); with `leading` or `trailing` only its magnitude counts.
        let (gap, ahead) = match displacement {
            "trailingReferencedEntity" => (gap.abs(), false),
            "leadingReferencedEntity" => (gap.abs(), true),
            _ if gap < 0.0 => (-gap, true),
            _ => (gap, {
                let p = me.state.pose;
                let (dx, dy) = (p.x - r.state.pose.x, p.y - r.state.pose.y);
                dx * r.state.pose.h.cos() + dy * r.state.pose.h.sin() >= 0.0
            }),
        };
        let ds = match (freespace, ahead) {
            (false, true) => gap,
            (false, false) => -gap,
            (true, true) => {
                gap + (r.centre_m[0] + r.size_m[0] / 2.0) - (me.centre_m[0] - me.size_m[0] / 2.0)
            }
            (true, false) => {
                -(gap + (me.centre_m[0] + me.size_m[0] / 2.0) - (r.centre_m[0] - r.size_m[0] / 2.0))
            }
        };
        let mut lp = rl;
        if ds >= 0.0 {
            let prefer = |_: usize| false;
            self.roads.advance(&mut lp, ds, &prefer);
        } else {
            let up = lp.along_s(&self.roads);
            let s = lp.s + if up { ds } else { -ds };
            let (id, road) = self.roads.ids(lp.lane);
            let road = self.roads.map().roads[road].od_id.clone();
            let rev = lp.rev;
            lp = self.roads.lane_pos(&road, id, s, lp.d)?;
            lp.rev = rev;
        }
        // On a lane of the same road, it keeps its own lane and offset there (esmini moves
        // it along `s`); elsewhere it takes the reference's.
        if let Some(own) = me.state.lane {
            let (id, road) = self.roads.ids(own.lane);
            if road == self.roads.ids(lp.lane).1 {
                let name = self.roads.map().roads[road].od_id.clone();
                if let Ok(mut mine) = self.roads.lane_pos(&name, id, lp.s, own.d) {
                    mine.rev = own.rev;
                    lp = mine;
                }
            }
        }
        let st = &mut self.actors[e].state;
        st.pose = self.roads.pose_of(&lp);
        st.lane = Some(lp);
        // And it takes the reference's speed.
        st.speed = r.state.speed;
        Ok(())
    }
}
