//! Controller actions: `ActivateControllerAction` (and an `AssignControllerAction` that
//! activates), the hand-over of the ego to the system under test.

use super::super::*;

impl Storyboard {
    /// Performs controller action `action` on entity `e`: an activation, or an assignment
    /// that activates ([`m::Action::hands_over`]), hands it over
    /// ([`Storyboard::activate_controller`]); an assignment that activates nothing waits for
    /// an `ActivateControllerAction`, and an override of inactive values does nothing (an
    /// active one is refused at load).
    pub(in crate::xosc::story) fn controller_action(&mut self, e: usize, action: &m::Action) {
        match action {
            m::Action::ActivateController {
                lateral,
                longitudinal,
            } => self.activate_controller(e, *lateral, *longitudinal),
            m::Action::AssignController {
                lateral,
                longitudinal,
                kind,
                ..
            } if action.hands_over() => {
                if kind
                    .as_deref()
                    .is_some_and(|k| drive::STRAIGHT_CONTROLLERS.contains(&k))
                {
                    self.drives[e].straight = true;
                }
                self.activate_controller(
                    e,
                    Some(*lateral == Some(true)),
                    Some(*longitudinal == Some(true)),
                )
            }
            _ => {}
        }
    }

    /// Performs an `ActivateControllerAction` on entity `e` with its `lateral` and
    /// `longitudinal` domains: the ego handed over on activation is then driven by the
    /// system under test, its lateral move and path ended.
    pub(in crate::xosc::story) fn activate_controller(
        &mut self,
        e: usize,
        lateral: Option<bool>,
        longitudinal: Option<bool>,
    ) {
        // Any domain activated hands the whole ego over (the load says so); a
        // deactivation is refused at load (`check`).
        let on = lateral.unwrap_or(true) || longitudinal.unwrap_or(true);
        if on && Some(e) == self.hand_over && self.actors[e].scripted {
            self.actors[e].scripted = false;
            // Its lateral move, path, kept distance and synchronization end with the script
            // (and their actions); a running SpeedAction goes on as the system's set speed.
            let old = [
                self.drives[e].lateral.take().map(|l| l.action),
                self.drives[e].lat_keep.take().map(|k| k.action),
                self.drives[e].path.take().map(|p| p.1),
                self.drives[e].keep.take().map(|k| k.action),
                self.drives[e].sync.take().map(|s| s.action),
            ];
            for o in old {
                self.override_task(o);
            }
        }
    }

    /// Has the storyboard move `ego` (scripted, as in [`Storyboard::new`] with `None`) until
    /// an `ActivateControllerAction` on it activates a domain: from then on the system
    /// under test drives it (its [`Actor::scripted`] turns false, the host hands it over and
    /// feeds its motion back through [`Storyboard::observe`]), as esmini's default
    /// controller hands the ego to the controller the file activates.
    pub fn hand_over_on_activation(&mut self, ego: usize) {
        self.hand_over = Some(ego);
        self.actors[ego].scripted = true;
    }
}
