//! `SpeedAction`: a speed transition on a scripted entity, or the set speed asked of the ego
//! the system under test drives.

use super::super::*;

/// A `SpeedAction` in progress on one entity.
#[derive(Debug, Clone, Copy)]
pub(in crate::xosc::story) struct SpeedTask {
    /// The speed over time, m/s.
    pub(in crate::xosc::story) tr: Transition,
    /// A target that follows another entity (`continuous`): its index, the value, whether a
    /// factor.
    pub(in crate::xosc::story) track: Track,
    /// Its action.
    pub(in crate::xosc::story) action: usize,
    /// How long it lasts past its transition, in CARLA's reading ([`Storyboard::carla`]).
    pub(in crate::xosc::story) hold: Option<Hold>,
    /// A `SpeedProfileAction`: the speed is its entity's [`Drive::profile`]'s (`tr` holds
    /// only its start and last speeds).
    pub(in crate::xosc::story) profiled: bool,
}

/// How long a `SpeedAction` lasts in CARLA's reading (scenario_runner's
/// `ChangeActorTargetSpeed`): until its entity has travelled this far since the action
/// started, or until this time.
#[derive(Debug, Clone, Copy)]
pub(in crate::xosc::story) enum Hold {
    /// Until the entity's distance travelled ([`State::travelled_m`]) reaches this, m.
    Travelled(f64),
    /// Until this simulation time, s.
    Until(f64),
}

impl SpeedTask {
    /// The speed the task asks at `t1` (s), m/s, given each entity's speed now (`speed_of`),
    /// and whether its transition is over: past it, a target that follows another entity
    /// is that entity's speed times, or plus, the value.
    pub(in crate::xosc::story) fn step(
        &self,
        t1: f64,
        speed_of: impl Fn(usize) -> f64,
    ) -> (f64, bool) {
        let (v, over) = self.tr.at(t1);
        match (over, self.track) {
            (true, Some((r, value, factor))) => {
                let rv = speed_of(r);
                (if factor { rv * value } else { rv + value }, true)
            }
            _ => (v, over),
        }
    }

    /// Whether the task ends at `t1` (s) with its entity's distance travelled `travelled_m`
    /// (m), its transition over: a target that follows another entity goes on, and one
    /// held (CARLA's reading) goes on until its hold ends.
    pub(in crate::xosc::story) fn ends(&self, t1: f64, travelled_m: f64) -> bool {
        self.track.is_none()
            && match self.hold {
                None => true,
                Some(Hold::Travelled(d)) => travelled_m >= d,
                Some(Hold::Until(t)) => t1 >= t - 1e-9,
            }
    }
}

/// How many times longer speed transition `tr` takes within `performance`: its peak rate of
/// change over the maximum acceleration (deceleration for a slower target) when above it,
/// else 1, as esmini's `TransitionDynamics::SetMaxRate` stretches a transition's parameter,
/// uniformly, so that its shape stays and its peak is the maximum (a step is not stretched).
fn stretch(tr: &Transition, performance: m::Performance) -> f64 {
    if tr.duration_s <= 0.0 || matches!(tr.shape, transition::Shape::Step) {
        return 1.0;
    }
    let peak = (tr.to - tr.from).abs() / tr.duration_s * transition::progress_slope(tr.shape, 0.5);
    let most = if tr.to > tr.from {
        performance.max_acceleration_mps2
    } else {
        performance.max_deceleration_mps2
    };
    if most > 0.0 && peak > most {
        peak / most
    } else {
        1.0
    }
}

impl Storyboard {
    /// Starts a `SpeedAction` on `e` (see [`Storyboard::start_task`]).
    pub(in crate::xosc::story) fn start_speed(
        &mut self,
        e: usize,
        (target, dynamics): (&SpeedTarget, &m::Dynamics),
        a: Option<usize>,
        t: f64,
    ) -> Result<(), StoryError> {
        let scripted = self.actors[e].scripted;
        let begin = |sb: &mut Storyboard| {
            if let Some(a) = a {
                sb.elems[a].pending += 1;
            }
        };

        let v0 = self.actors[e].state.speed;
        let (to, track) = match target {
            SpeedTarget::Absolute(v) => (*v, None),
            SpeedTarget::Relative {
                entity,
                value,
                factor,
                continuous,
            } => {
                let r = self.actors[*entity].state.speed;
                let v = if *factor { r * value } else { r + value };
                (v, continuous.then_some((*entity, *value, *factor)))
            }
        };
        // The target within the entity's `maxSpeed`, as esmini's `LongSpeedAction::Start`
        // sets it (before its transition's length is taken).
        let max = self.actors[e].performance.max_speed_mps;
        let to = to.clamp(-max, max);
        if !scripted && a.is_none() {
            // The ego's initial speed; later, the system under test drives it.
            self.actors[e].state.speed = to.max(0.0);
            return Ok(());
        }
        // A scripted entity reverses at a negative target (esmini's reading); the system
        // under test is asked to stop there.
        let to = if scripted { to } else { to.max(0.0) };
        let mut tr = Transition {
            from: v0,
            to,
            start_s: t,
            duration_s: duration_s(dynamics, to - v0, 0.5 * (v0 + to).abs()),
            shape: shape_of(dynamics.shape),
        };
        if scripted {
            tr.duration_s *= stretch(&tr, self.actors[e].performance);
        }
        // CARLA: the target at once, held for the dynamics' value (its distance or time).
        let hold = (self.carla && a.is_some()).then(|| {
            tr.duration_s = 0.0;
            match dynamics.dimension {
                m::Dimension::Distance => {
                    Hold::Travelled(self.actors[e].state.travelled_m + dynamics.value)
                }
                _ => Hold::Until(t + dynamics.value),
            }
        });
        // A gap kept to another entity, or a synchronization, is the same longitudinal
        // domain: it ends.
        let old = self.drives[e].keep.take().map(|k| k.action);
        self.override_task(old);
        let old = self.drives[e].sync.take().map(|s| s.action);
        self.override_task(old);
        if a.is_none() && tr.duration_s == 0.0 {
            self.actors[e].state.speed = tr.to;
            return Ok(());
        }
        let old = self.drives[e].speed.take().map(|s| s.action);
        self.override_task(old);
        begin(self);
        self.drives[e].speed = Some(SpeedTask {
            tr,
            track,
            action: a.unwrap_or(usize::MAX),
            hold,
            profiled: false,
        });

        Ok(())
    }

    /// The speed the storyboard asks of the ego the system under test drives, m/s, at the
    /// end of the last step: the value its `SpeedAction`s' transitions have then (a target
    /// that follows another entity, that entity's speed then); `None` before the first
    /// `SpeedAction` of the storyboard on it (its set speed is its `Init` speed).
    pub fn set_speed(&self) -> Option<f64> {
        self.set_speed
    }

    /// The speed asked at `t1` of entity `e`, which the system under test drives
    /// ([`Storyboard::set_speed`]); its `SpeedAction` ends once the transition is over and
    /// its speed has come within [`SET_SPEED_REACHED_MPS`] and [`SET_SPEED_REACHED_SHARE`]
    /// of the target.
    pub(in crate::xosc::story) fn ask_speed(&mut self, e: usize, t1: f64) {
        let Some(task) = self.drives[e].speed else {
            return;
        };
        let (v, over) = self.speed_task_at(e, &task, t1);
        if over && task.ends(t1, self.actors[e].state.travelled_m) {
            let reached = SET_SPEED_REACHED_MPS + SET_SPEED_REACHED_SHARE * task.tr.to.abs();
            if (self.actors[e].state.speed - task.tr.to).abs() <= reached {
                self.drives[e].speed = None;
                self.task_done(Some(task.action));
            }
        }
        self.set_speed = Some(v.max(0.0));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A transition from `from` to `to` m/s over `duration_s` s of `shape`.
    fn tr(from: f64, to: f64, duration_s: f64, shape: transition::Shape) -> Transition {
        Transition {
            from,
            to,
            start_s: 0.0,
            duration_s,
            shape,
        }
    }

    /// A sinusoidal 0 → 15 m/s over 3 s peaks at π/2 · 5 = 7.85 m/s²: within a maximum
    /// acceleration of 5 m/s² it takes 3 · 7.85 / 5 = 4.71 s (esmini's light_state); a
    /// cubic peaks at 1.5 times the mean rate, a linear one at it; a braking is held to the
    /// maximum deceleration; one within the limits, and a step, keep their time.
    #[test]
    fn a_speed_transition_faster_than_the_performance_is_stretched_to_its_peak() {
        use transition::Shape::{Cubic, Linear, Sinusoidal, Step};
        let p = m::Performance {
            max_speed_mps: 70.0,
            max_acceleration_mps2: 5.0,
            max_deceleration_mps2: 10.0,
        };
        let k = stretch(&tr(0.0, 15.0, 3.0, Sinusoidal), p);
        assert!((3.0 * k - 1.5 * std::f64::consts::PI).abs() < 1e-12, "{k}");
        assert!((stretch(&tr(0.0, 15.0, 3.0, Cubic), p) - 1.5).abs() < 1e-12);
        assert!((stretch(&tr(0.0, 15.0, 1.0, Linear), p) - 3.0).abs() < 1e-12);
        assert!((stretch(&tr(15.0, 0.0, 1.0, Linear), p) - 1.5).abs() < 1e-12);
        assert_eq!(stretch(&tr(0.0, 15.0, 5.0, Sinusoidal), p), 1.0);
        assert_eq!(stretch(&tr(0.0, 15.0, 0.0, Step), p), 1.0);
        assert_eq!(stretch(&tr(0.0, -3.0, 0.1, Linear), p), 3.0);
    }
}
