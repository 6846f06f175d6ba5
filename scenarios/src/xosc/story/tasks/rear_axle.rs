//! Vehicles driven by a reference point ahead of their rear axle (esmini's
//! `refpoint_x_offset` property, [`paracosm_openscenario::model::Entity::refpoint_dx_m`]):
//! their body trails the reference point as a rear axle trails its front one.

use super::super::*;

impl Storyboard {
    /// Puts entity `e`'s rear axle straight behind its reference point, as it faces, where
    /// it is placed (esmini's `Vehicle::AlignRearAxlePosition`).
    pub(in crate::xosc::story) fn align_rear_axle(&mut self, e: usize) {
        let a = &mut self.actors[e];
        if let Some((dx, rear)) = &mut a.front_ref {
            let p = a.state.pose;
            *rear = [p.x - *dx * p.h.cos(), p.y - *dx * p.h.sin()];
        }
    }

    /// Turns each scripted entity driven by a reference point ahead of its rear axle after
    /// a step: it faces from where its rear axle was to where its reference point is now,
    /// and its rear axle is put that far behind it on that line, as esmini's
    /// `ScenarioEngine::step` does after it has pulled the trailers. Where the reference
    /// point stands on the rear axle's spot, it keeps its heading.
    pub(in crate::xosc::story) fn trail_rear_axles(&mut self) {
        for a in &mut self.actors {
            let Some((dx, rear)) = &mut a.front_ref else {
                continue;
            };
            if !a.scripted {
                // The system under test's vehicle model turns the ego.
                continue;
            }
            let p = &mut a.state.pose;
            let (ux, uy) = (p.x - rear[0], p.y - rear[1]);
            if ux.hypot(uy) > 1e-12 {
                p.h = uy.atan2(ux);
            }
            *rear = [p.x - *dx * p.h.cos(), p.y - *dx * p.h.sin()];
        }
    }
}
