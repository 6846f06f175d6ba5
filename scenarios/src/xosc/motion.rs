//! How a scripted entity moves: its speed and lateral transitions (OpenSCENARIO 1.3,
//! "TransitionDynamics": step, linear, cubic and sinusoidal shapes over a time, a distance or
//! a rate) and the trajectories it follows.

use paracosm_openscenario::model::{Dimension, Dynamics, Shape};

use super::road::Pose;

/// The fraction `[0, 1]` of a transition done at `tau` (`[0, 1]`, the fraction of its
/// duration gone) for `shape`: linear `τ`, cubic `3τ² − 2τ³`, sinusoidal `(1 − cos πτ)/2`,
/// step 1.
pub fn progress(shape: Shape, tau: f64) -> f64 {
    let tau = tau.clamp(0.0, 1.0);
    match shape {
        Shape::Step => 1.0,
        Shape::Linear => tau,
        Shape::Cubic => tau * tau * (3.0 - 2.0 * tau),
        Shape::Sinusoidal => 0.5 * (1.0 - (std::f64::consts::PI * tau).cos()),
    }
}

/// The peak rate of a transition of `shape` over `delta` in a unit time, per unit of
/// `delta`: linear 1, cubic 1.5, sinusoidal π/2 (the largest slope of [`progress`]).
fn peak_slope(shape: Shape) -> f64 {
    match shape {
        Shape::Step | Shape::Linear => 1.0,
        Shape::Cubic => 1.5,
        Shape::Sinusoidal => std::f64::consts::FRAC_PI_2,
    }
}

/// The duration (s) of a transition over `delta` (the change: m/s for a speed, m for a lateral
/// move) with `dynamics`, for an entity at `speed_mps`: by time, the value; by distance, the
/// distance over the mean speed (`mean_speed_mps`, ≥ 0.1 m/s); by rate, `delta` at the
/// value as the transition's peak rate. A step takes no time.
pub fn duration_s(dynamics: &Dynamics, delta: f64, mean_speed_mps: f64) -> f64 {
    if dynamics.shape == Shape::Step {
        return 0.0;
    }
    let v = dynamics.value.abs();
    match dynamics.dimension {
        Dimension::Time => v,
        Dimension::Distance => v / mean_speed_mps.max(0.1),
        Dimension::Rate if v > 0.0 => delta.abs() * peak_slope(dynamics.shape) / v,
        Dimension::Rate => 0.0,
    }
}

/// The duration (s) of a lateral move of `delta` m whose largest lateral acceleration is
/// `max_acc` m/s² (`LaneOffsetAction`'s `maxLateralAcc`): sinusoidal `π·√(δ/2a)`, cubic and
/// linear `√(6δ/a)` (a linear move has no finite peak; it is given the cubic's time).
pub fn offset_duration_s(shape: Shape, delta: f64, max_acc: f64) -> f64 {
    let (d, a) = (delta.abs(), max_acc.max(1e-6));
    match shape {
        Shape::Step => 0.0,
        Shape::Sinusoidal => std::f64::consts::PI * (d / (2.0 * a)).sqrt(),
        Shape::Linear | Shape::Cubic => (6.0 * d / a).sqrt(),
    }
}

/// The slope of [`progress`] at `tau` (`[0, 1]`): linear 1, cubic `6τ(1 − τ)`, sinusoidal
/// `(π/2)·sin πτ`, step 0.
pub fn progress_slope(shape: Shape, tau: f64) -> f64 {
    let tau = tau.clamp(0.0, 1.0);
    match shape {
        Shape::Step => 0.0,
        Shape::Linear => 1.0,
        Shape::Cubic => 6.0 * tau * (1.0 - tau),
        Shape::Sinusoidal => std::f64::consts::FRAC_PI_2 * (std::f64::consts::PI * tau).sin(),
    }
}

/// A value moving from `from` to `to` between `start_s` and `start_s + duration_s`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Transition {
    /// Value at the start.
    pub from: f64,
    /// Value at the end.
    pub to: f64,
    /// Start time, s.
    pub start_s: f64,
    /// Length, s (0: a step).
    pub duration_s: f64,
    /// Its shape.
    pub shape: Shape,
}

impl Transition {
    /// The value at `t` (s) and whether the transition is over.
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

    /// The value's rate of change at `t` (per s, or per unit of whatever `start_s` and
    /// `duration_s` count); 0 for a step and outside the transition.
    pub fn slope(&self, t: f64) -> f64 {
        if self.duration_s <= 0.0 || t >= self.start_s + self.duration_s || t < self.start_s {
            return 0.0;
        }
        let tau = (t - self.start_s) / self.duration_s;
        (self.to - self.from) / self.duration_s * progress_slope(self.shape, tau)
    }
}

/// How close two times are to be one, s (far below any step).
const TIME_EPS_S: f64 = 1e-9;

/// A timed polyline: vertices with their times (s, from the simulation's start).
#[derive(Debug, Clone, PartialEq)]
pub struct Timed {
    /// `(t, pose)` in increasing `t`.
    pub vertices: Vec<(f64, Pose)>,
}

impl Timed {
    /// The pose at `t` (s): the position linear between vertices, the heading of the vertex
    /// that starts the leg (not interpolated: esmini's polyline without interpolation; a
    /// vertex whose file gives no heading faces along its leg: the storyboard fills it in),
    /// and whether `t` is past the last vertex.
    pub fn at(&self, t: f64) -> (Pose, bool) {
        let n = self.vertices.len();
        let last = self.vertices[n - 1];
        if t >= last.0 - TIME_EPS_S {
            return (last.1, t >= last.0);
        }
        let first = self.vertices[0];
        if t <= first.0 {
            return (first.1, false);
        }
        // A time within rounding of a vertex's is the vertex's (a step that adds `dt` to the
        // time lands a few ulps short of the vertex it means, and would face as the vertex
        // before).
        let i = self
            .vertices
            .partition_point(|v| v.0 <= t + TIME_EPS_S)
            .clamp(1, n - 1);
        let (a, b) = (self.vertices[i - 1], self.vertices[i]);
        let u = if b.0 > a.0 {
            ((t - a.0) / (b.0 - a.0)).max(0.0)
        } else {
            1.0
        };
        (
            Pose {
                x: a.1.x + u * (b.1.x - a.1.x),
                y: a.1.y + u * (b.1.y - a.1.y),
                h: a.1.h,
            },
            false,
        )
    }
}

/// A polyline followed at the entity's own speed.
#[derive(Debug, Clone, PartialEq)]
pub struct Untimed {
    /// Its vertices.
    pub vertices: Vec<Pose>,
    /// Distance gone along it, m.
    pub gone_m: f64,
}

impl Untimed {
    /// Goes `dist` m further; the pose there and whether the end is reached.
    pub fn advance(&mut self, dist: f64) -> (Pose, bool) {
        self.gone_m += dist.max(0.0);
        let mut left = self.gone_m;
        for w in self.vertices.windows(2) {
            let (a, b) = (w[0], w[1]);
            let len = (b.x - a.x).hypot(b.y - a.y);
            if left <= len && len > 0.0 {
                let u = left / len;
                return (
                    Pose {
                        x: a.x + u * (b.x - a.x),
                        y: a.y + u * (b.y - a.y),
                        h: a.h,
                    },
                    false,
                );
            }
            left -= len;
        }
        (self.vertices[self.vertices.len() - 1], true)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shapes_start_at_zero_end_at_one_and_are_symmetric() {
        for shape in [Shape::Linear, Shape::Cubic, Shape::Sinusoidal] {
            assert_eq!(progress(shape, 0.0), 0.0);
            assert!((progress(shape, 1.0) - 1.0).abs() < 1e-12);
            assert!((progress(shape, 0.5) - 0.5).abs() < 1e-12, "{shape:?}");
        }
        assert_eq!(progress(Shape::Step, 0.0), 1.0);
    }

    #[test]
    fn a_rate_is_the_peak_slope() {
        let d = Dynamics {
            shape: Shape::Sinusoidal,
            dimension: Dimension::Rate,
            value: 1.0,
        };
        // 3.5 m at a peak of 1 m/s: the sinusoid's peak slope is π/2 · δ/T.
        let t = duration_s(&d, 3.5, 10.0);
        assert!((t - 3.5 * std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        let tr = Transition {
            from: 0.0,
            to: 3.5,
            start_s: 0.0,
            duration_s: t,
            shape: Shape::Sinusoidal,
        };
        let h = 1e-6;
        let slope = (tr.at(t / 2.0 + h).0 - tr.at(t / 2.0 - h).0) / (2.0 * h);
        assert!((slope - 1.0).abs() < 1e-6, "{slope}");
        // By distance: 20 m at a mean of 10 m/s.
        let by_distance = Dynamics {
            dimension: Dimension::Distance,
            value: 20.0,
            ..d
        };
        assert!((duration_s(&by_distance, 1.0, 10.0) - 2.0).abs() < 1e-12);
    }

    #[test]
    fn a_sinusoidal_offset_peaks_at_its_maximum_acceleration() {
        let (delta, a) = (1.5, 2.0);
        let t = offset_duration_s(Shape::Sinusoidal, delta, a);
        let tr = Transition {
            from: 0.0,
            to: delta,
            start_s: 0.0,
            duration_s: t,
            shape: Shape::Sinusoidal,
        };
        let h = 1e-4;
        let acc = (tr.at(2.0 * h).0 - 2.0 * tr.at(h).0 + tr.at(0.0).0) / (h * h);
        assert!((acc - a).abs() < 1e-2, "{acc}");
    }

    #[test]
    fn a_timed_polyline_is_linear_between_its_vertices_facing_as_each_leg_starts() {
        let p = |x: f64, y: f64| Pose { x, y, h: 0.3 };
        let path = Timed {
            vertices: vec![
                (1.0, p(0.0, 0.0)),
                (
                    3.0,
                    Pose {
                        h: 0.7,
                        ..p(0.0, 4.0)
                    },
                ),
            ],
        };
        let (q, done) = path.at(2.0);
        assert!(!done && (q.y - 2.0).abs() < 1e-12);
        // The vertex's own heading, not the leg's direction (pi/2), nor interpolated.
        assert_eq!(q.h, 0.3);
        let (end, done) = path.at(3.5);
        assert!(done && end.h == 0.7 && end.y == 4.0);
        let mut u = Untimed {
            vertices: vec![p(0.0, 0.0), p(3.0, 0.0), p(3.0, 4.0)],
            gone_m: 0.0,
        };
        let (q, done) = u.advance(5.0);
        assert!(!done && (q.x - 3.0).abs() < 1e-12 && (q.y - 2.0).abs() < 1e-12);
        assert!(u.advance(3.0).1);
    }
}
