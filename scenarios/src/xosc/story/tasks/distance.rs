//! `LongitudinalDistanceAction`: an entity kept at a distance or time gap from another.

use super::super::*;

impl Storyboard {
    /// Puts entity `e` on `reference`'s lane at a distance `(distance, time gap, freespace)`
    /// ahead of it (`leadingReferencedEntity`, or `any` when ahead now) or behind it.
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
        let ahead = match displacement {
            "trailingReferencedEntity" => false,
            "leadingReferencedEntity" => true,
            _ => {
                let p = me.state.pose;
                let (dx, dy) = (p.x - r.state.pose.x, p.y - r.state.pose.y);
                dx * r.state.pose.h.cos() + dy * r.state.pose.h.sin() >= 0.0
            }
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
