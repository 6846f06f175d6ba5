//! `TeleportAction`: an entity placed at a position.

use super::super::*;

impl Storyboard {
    /// Performs a `TeleportAction` of entity `e` to `p` (written at `at`): places it there,
    /// notes its heading relative to its lane's travel (rad), and ends the path or lateral
    /// move it was making (and their actions).
    ///
    /// # Errors
    /// [`StoryError`] for a position off the map.
    pub(in crate::xosc::story) fn teleport(
        &mut self,
        e: usize,
        p: &Position,
        at: &paracosm_openscenario::Pos,
    ) -> Result<(), StoryError> {
        let (pose, lane) = self.resolve(p, at)?;
        let tilt = self.tilt_of(p);
        let st = &mut self.actors[e].state;
        st.tilt = tilt;
        st.pose = pose;
        st.lane = lane;
        self.drives[e].rel_h = self.relative_heading(pose.h, lane);
        let d = &mut self.drives[e];
        // The motion it was making ends (and its action with it).
        let old = [
            d.path.take().map(|p| p.1),
            d.lateral.take().map(|l| l.action),
        ];
        for o in old {
            self.override_task(o);
        }
        // Its trailers are lined up behind it where it is put (esmini's
        // `TeleportAction::Start`).
        self.align_trailers(e);
        self.align_rear_axle(e);
        Ok(())
    }
}
