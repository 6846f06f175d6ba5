//! Vehicle combinations: a trailer pulled by its tow's hitch (`Trailer`, `TrailerHitch`,
//! `TrailerCoupler`) and `TrailerAction`, as esmini moves them (`ScenarioEngine::step`'s
//! trailer update, `Vehicle::AlignTrailers`).

use super::super::*;

impl Storyboard {
    /// The entity that tows entity `e` now, if any.
    pub(in crate::xosc::story) fn tow_of(&self, e: usize) -> Option<usize> {
        self.actors.iter().position(|a| a.trailer == Some(e))
    }

    /// Where entity `e`'s hitch is now (m, the OpenDRIVE frame), `hitch_dx` m ahead of its
    /// reference point along heading `h` (rad).
    fn hitch_at(&self, e: usize, h: f64) -> [f64; 2] {
        let a = &self.actors[e];
        let dx = a.hitch_dx_m.unwrap_or(0.0);
        [a.state.pose.x + dx * h.cos(), a.state.pose.y + dx * h.sin()]
    }

    /// Lines up the trailers entity `e` tows (when nothing tows `e`) straight behind it, as
    /// esmini's `Vehicle::AlignTrailers` does where an entity is placed: each trailer's coupler
    /// at its tow's hitch, each facing as `e` faces, at `e`'s speed.
    pub(in crate::xosc::story) fn align_trailers(&mut self, e: usize) {
        if self.tow_of(e).is_some() {
            return;
        }
        let front = self.actors[e].state;
        let h = front.pose.h;
        let (mut tow, mut next) = (e, self.actors[e].trailer);
        for _ in 0..self.actors.len() {
            let Some(k) = next else { break };
            let [hx, hy] = self.hitch_at(tow, h);
            let c = self.actors[k].coupler_dx_m.unwrap_or(0.0);
            let pose = Pose {
                x: hx - c * h.cos(),
                y: hy - c * h.sin(),
                h,
            };
            let lane = self
                .roads
                .anchor(pose.x, pose.y)
                .map(|lp| self.roads.facing(lp, h));
            let present = self.actors[tow].present;
            let a = &mut self.actors[k];
            a.present = present;
            a.state.pose = pose;
            a.state.lane = lane;
            a.state.speed = front.speed;
            a.state.vel = [front.speed * h.cos(), front.speed * h.sin()];
            (tow, next) = (k, a.trailer);
        }
    }

    /// Pulls every trailer after its tow has moved over a step of `dt` s, as esmini's
    /// `ScenarioEngine::step` does: each trailer's coupler is put at its tow's hitch, on the
    /// line from the hitch to where the trailer was, and the trailer faces the hitch (a
    /// trailer follows its tow's path as a tractrix); it has its tow's speed, and is in the
    /// scenario while its tow is. With `dt` 0 (after `Init`, as esmini's initial frame pulls
    /// them) only their poses change.
    pub(in crate::xosc::story) fn pull_trailers(&mut self, dt: f64) {
        for e in 0..self.actors.len() {
            if self.actors[e].trailer.is_none() || self.tow_of(e).is_some() {
                continue;
            }
            let (mut tow, mut next) = (e, self.actors[e].trailer);
            for _ in 0..self.actors.len() {
                let Some(k) = next else { break };
                let t = &self.actors[tow];
                let [hx, hy] = self.hitch_at(tow, t.state.pose.h);
                let (speed, present) = (t.state.speed, t.present);
                let before = self.actors[k].state;
                let (mut dx, mut dy) = (before.pose.x - hx, before.pose.y - hy);
                let len = dx.hypot(dy);
                if len < 1e-12 {
                    // On the hitch itself: behind the tow.
                    (dx, dy) = (-t.state.pose.h.cos(), -t.state.pose.h.sin());
                } else {
                    (dx, dy) = (dx / len, dy / len);
                }
                let c = self.actors[k].coupler_dx_m.unwrap_or(0.0);
                let pose = Pose {
                    x: hx + c * dx,
                    y: hy + c * dy,
                    h: wrap(dy.atan2(dx) + std::f64::consts::PI),
                };
                let lane = self
                    .roads
                    .anchor(pose.x, pose.y)
                    .map(|lp| self.roads.facing(lp, pose.h));
                let a = &mut self.actors[k];
                let st = &mut a.state;
                // After `Init` (no time): only where it is.
                if dt > 0.0 {
                    let moved = (pose.x - before.pose.x).hypot(pose.y - before.pose.y);
                    st.vel = [(pose.x - before.pose.x) / dt, (pose.y - before.pose.y) / dt];
                    st.accel = (speed - before.speed) / dt;
                    st.travelled_m += moved;
                    st.still_s = if speed.abs() < 1e-3 {
                        st.still_s + dt
                    } else {
                        0.0
                    };
                }
                st.speed = speed;
                st.pose = pose;
                st.lane = lane;
                a.present = present;
                (tow, next) = (k, a.trailer);
            }
        }
    }

    /// Performs a `TrailerAction` of entity `e` (written at `at`): hitches `trailer` to it
    /// (`Some`; the one it towed is unhitched first), or unhitches the one it tows (`None`),
    /// as esmini's `ConnectTrailerAction` and `DisconnectTrailerAction` do. The trailer is
    /// pulled to the hitch from the next step on.
    ///
    /// # Errors
    /// [`StoryError`] for a trailer with no coupler, an entity with no hitch, a trailer
    /// another entity tows, or a connection that would make a chain come back to `e`.
    pub(in crate::xosc::story) fn hitch(
        &mut self,
        e: usize,
        trailer: Option<usize>,
        at: &paracosm_openscenario::Pos,
    ) -> Result<(), StoryError> {
        let refuse = |message: String| StoryError {
            at: site(at),
            message,
        };
        let Some(k) = trailer else {
            self.actors[e].trailer = None;
            return Ok(());
        };
        let name = |i: usize| self.actors[i].name.clone();
        if self.actors[e].hitch_dx_m.is_none() {
            return Err(refuse(format!(
                "{} has no <TrailerHitch> to hitch {} to",
                name(e),
                name(k)
            )));
        }
        if self.actors[k].coupler_dx_m.is_none() {
            return Err(refuse(format!(
                "{} has no <TrailerCoupler>: it is no trailer",
                name(k)
            )));
        }
        if let Some(other) = self.tow_of(k).filter(|&o| o != e) {
            return Err(refuse(format!(
                "{} is towed by {} already",
                name(k),
                name(other)
            )));
        }
        // The chain from `k` must not come back to `e`.
        let mut next = Some(k);
        for _ in 0..self.actors.len() {
            match next {
                Some(i) if i == e => {
                    return Err(refuse(format!(
                        "hitching {} to {} would make a chain of trailers that comes back to {}",
                        name(k),
                        name(e),
                        name(e)
                    )))
                }
                Some(i) => next = self.actors[i].trailer,
                None => break,
            }
        }
        self.actors[e].trailer = Some(k);
        Ok(())
    }
}
