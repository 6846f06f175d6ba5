//! Transitions: a value moving from one level to another over time or distance, in a given
//! shape. The one implementation behind every lane change, lane offset and speed change of
//! both front ends: the language's `changeLane` and `Car(lane_change=)` (minimum jerk over
//! time, [`crate::LaneChangeSpec`]) and an OpenSCENARIO storyboard's `TransitionDynamics`
//! (step, linear, cubic, sinusoidal; OpenSCENARIO 1.3). How a lateral move shares a step's
//! travel with the motion along the lane is each front end's rule, stated at [`LateralRule`].

/// The shape of a transition.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Shape {
    /// At once: the whole change at the start.
    Step,
    /// `τ`.
    Linear,
    /// `3τ² − 2τ³`.
    Cubic,
    /// `(1 − cos πτ) / 2`.
    Sinusoidal,
    /// `10τ³ − 15τ⁴ + 6τ⁵`, the minimum-jerk profile (Flash & Hogan 1985).
    MinimumJerk,
}

/// The fraction `[0, 1]` of a transition done at `tau` (the fraction of its duration gone,
/// clamped to `[0, 1]`) for `shape`: step 1, linear `τ`, cubic `3τ² − 2τ³`, sinusoidal
/// `(1 − cos πτ)/2`, minimum jerk `10τ³ − 15τ⁴ + 6τ⁵`.
pub fn progress(shape: Shape, tau: f64) -> f64 {
    let t = tau.clamp(0.0, 1.0);
    match shape {
        Shape::Step => 1.0,
        Shape::Linear => t,
        Shape::Cubic => t * t * (3.0 - 2.0 * t),
        Shape::Sinusoidal => 0.5 * (1.0 - (std::f64::consts::PI * t).cos()),
        Shape::MinimumJerk => t * t * t * (10.0 - 15.0 * t + 6.0 * t * t),
    }
}

/// The slope `d/dτ` of [`progress`] at `tau` (clamped to `[0, 1]`): step 0, linear 1, cubic
/// `6τ(1 − τ)`, sinusoidal `(π/2)·sin πτ`, minimum jerk `30τ²(1 − τ)²`.
pub fn progress_slope(shape: Shape, tau: f64) -> f64 {
    let t = tau.clamp(0.0, 1.0);
    match shape {
        Shape::Step => 0.0,
        Shape::Linear => 1.0,
        Shape::Cubic => 6.0 * t * (1.0 - t),
        Shape::Sinusoidal => std::f64::consts::FRAC_PI_2 * (std::f64::consts::PI * t).sin(),
        Shape::MinimumJerk => 30.0 * t * t * (1.0 - t) * (1.0 - t),
    }
}

/// A value moving from `from` to `to` between `start_s` and `start_s + duration_s` (seconds,
/// or metres for a transition over distance).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Transition {
    /// Value at the start.
    pub from: f64,
    /// Value at the end.
    pub to: f64,
    /// Start, s (or m).
    pub start_s: f64,
    /// Length, s (or m); `<= 0`: a step.
    pub duration_s: f64,
    /// Its shape.
    pub shape: Shape,
}

impl Transition {
    /// The value at `t` and whether the transition is over (within 1e-9 of its end).
    pub fn at(&self, t: f64) -> (f64, bool) {
        if self.duration_s <= 0.0 || t >= self.start_s + self.duration_s - 1e-9 {
            return (self.to, true);
        }
        let tau = (t - self.start_s) / self.duration_s;
        (
            self.from + (self.to - self.from) * progress(self.shape, tau),
            false,
        )
    }

    /// The value's rate of change at `t` (per s, or per m); 0 for a step and outside the
    /// transition.
    pub fn slope(&self, t: f64) -> f64 {
        if self.duration_s <= 0.0 || t >= self.start_s + self.duration_s || t < self.start_s {
            return 0.0;
        }
        let tau = (t - self.start_s) / self.duration_s;
        (self.to - self.from) / self.duration_s * progress_slope(self.shape, tau)
    }
}

/// How a storyboard's lateral move (a lane change or a lane offset) shares a step's travel
/// with the motion along the lane. The language's rule is not one of these: its car keeps
/// its speed over the ground, the sideways speed `v_lat` taken out of it, so it moves
/// `√(v² − v_lat²)` along its path and turns by `atan2(v_lat, along)`
/// ([`crate::LaneChangeSpec`]); both step the same [`Transition`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LateralRule {
    /// An OpenSCENARIO storyboard's `LaneChangeAction` over time, as esmini steps it: the
    /// lateral step `lat` is taken out of the step's travel `dist`, `√(dist² − lat²)` along
    /// the lane, and it faces the way it moves; it waits while the entity stands.
    TravelByTime,
    /// A storyboard's `LaneChangeAction` over distance: the parameter is the path along the
    /// lane, `dist / √(1 + r²)` of the step's travel, `r` the offset's slope per metre.
    TravelByDistance,
    /// A storyboard's `LaneOffsetAction`: the offset follows time, one step late, the motion
    /// along the lane is not slowed, and it faces `atan(rate·dt / dist)`.
    Offset,
}

/// A lateral move in progress under a [`LateralRule`]: the offset over a parameter (time, s,
/// or the path along the lane, m, from 0).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LateralMove {
    /// The offset over the parameter (`start_s` 0), m.
    pub tr: Transition,
    /// The parameter so far, s or m.
    pub param: f64,
    /// How it shares the travel.
    pub rule: LateralRule,
}

impl LateralMove {
    /// One step of `dt` (s) in which the entity, `d_now` (m) from its lane's centre, travels
    /// `dist` (m): the offset it reaches (m), whether the transition is over, how far it
    /// travels along the lane (m) and its heading against that travel (rad), by its
    /// [`LateralRule`].
    pub fn step(&mut self, d_now: f64, dist: f64, dt: f64) -> (f64, bool, f64, f64) {
        let moving = dist > 1e-12;
        let mut along = dist;
        let mut slip = 0.0;
        let (d, over) = match self.rule {
            LateralRule::Offset => {
                let (d, over) = self.tr.at(self.param);
                slip = (self.tr.slope(self.param) * dt).atan2(dist);
                self.param += dt;
                (d, over)
            }
            // Standing, a lane change waits (esmini steps it only while moving).
            _ if !moving => (d_now, false),
            _ if self.tr.duration_s <= 0.0 => (self.tr.to, true),
            LateralRule::TravelByDistance => {
                let r = self.tr.slope(self.param);
                along = dist / (1.0 + r * r).sqrt();
                self.param += along;
                slip = r.atan();
                self.tr.at(self.param)
            }
            LateralRule::TravelByTime => {
                let lat = (self.tr.slope(self.param) * dt).abs().min(dist);
                along = (dist * dist - lat * lat).sqrt();
                slip = (self.tr.slope(self.param) * dt).signum() * lat.atan2(along);
                self.param += dt;
                self.tr.at(self.param)
            }
        };
        (d, over, along, slip)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_shape_starts_at_0_ends_at_1_and_its_slope_is_its_derivative() {
        for shape in [
            Shape::Linear,
            Shape::Cubic,
            Shape::Sinusoidal,
            Shape::MinimumJerk,
        ] {
            assert_eq!(progress(shape, 0.0), 0.0, "{shape:?}");
            assert!((progress(shape, 1.0) - 1.0).abs() < 1e-15, "{shape:?}");
            for i in 1..100 {
                let tau = f64::from(i) / 100.0;
                let h = 1e-6;
                let numeric = (progress(shape, tau + h) - progress(shape, tau - h)) / (2.0 * h);
                assert!(
                    (numeric - progress_slope(shape, tau)).abs() < 1e-6,
                    "{shape:?} at {tau}"
                );
            }
        }
        assert_eq!(progress(Shape::Step, 0.0), 1.0);
    }

    #[test]
    fn a_lane_change_by_time_takes_its_lateral_step_out_of_the_travel_and_waits_standing() {
        let tr = Transition {
            from: 0.0,
            to: 3.5,
            start_s: 0.0,
            duration_s: 2.0,
            shape: Shape::Sinusoidal,
        };
        let mut m = LateralMove {
            tr,
            param: 0.0,
            rule: LateralRule::TravelByTime,
        };
        // Standing: nothing moves.
        assert_eq!(m.step(0.0, 0.0, 0.1), (0.0, false, 0.0, 0.0));
        let (mut d, mut n) = (0.0, 0);
        loop {
            let (d1, over, along, _) = m.step(d, 2.0, 0.1);
            let lat = d1 - d;
            assert!(along <= 2.0 && lat.abs() <= 2.0);
            d = d1;
            n += 1;
            if over {
                break;
            }
        }
        assert_eq!((d, n), (3.5, 20));
    }
}
