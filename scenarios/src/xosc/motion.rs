//! How a scripted entity moves: its speed and lateral transitions (OpenSCENARIO 1.3,
//! "TransitionDynamics": step, linear, cubic and sinusoidal shapes over a time, a distance or
//! a rate) and the trajectories it follows.

use paracosm_openscenario::model::{Dimension, Dynamics, Shape};

use paracosm_engine::network::roads::{wrap, Pose};

pub use paracosm_engine::transition::Transition;

/// The engine's transition shape ([`paracosm_engine::transition::Shape`]) of an OpenSCENARIO
/// `dynamicsShape`: every transition of the storyboard runs on the engine's one
/// implementation, as the language's lane changes do.
pub fn shape_of(shape: Shape) -> paracosm_engine::transition::Shape {
    use paracosm_engine::transition::Shape as S;
    match shape {
        Shape::Step => S::Step,
        Shape::Linear => S::Linear,
        Shape::Cubic => S::Cubic,
        Shape::Sinusoidal => S::Sinusoidal,
    }
}

/// The peak rate of a transition of `shape` over `delta` in a unit time, per unit of
/// `delta`: linear 1, cubic 1.5, sinusoidal π/2 (the largest slope of the shape's progress,
/// [`paracosm_engine::transition::progress_slope`]).
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

/// How close two times are to be one, s (far below any step).
const TIME_EPS_S: f64 = 1e-9;

/// How the heading turns between a polyline's vertices (esmini's
/// `PolyLineBase::InterpolationMode`, chosen by the trajectory's following mode).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Turn {
    /// The heading of the vertex that starts the leg (sampled curves: clothoids, NURBS).
    None,
    /// From one vertex's heading to the next's along the whole leg (`follow`).
    Segment,
    /// The leg's vertex heading, turned to the next within 2 m (at most half a leg) of each
    /// corner, and to the last vertex's within the last 2 m (`position`).
    Corner,
}

impl Turn {
    /// The heading on leg `i` (from vertex `i` to `i + 1` of `n` vertices, `h(k)` the
    /// heading of vertex `k`, rad) at `local` m of its `len` m, as esmini's
    /// `PolyLineBase::EvaluateSegmentByLocalS` turns it. It reads at most the vertices
    /// `i − 1` to `i + 1`, so a step costs no copy of a long path's headings.
    pub fn heading(
        self,
        h: impl Fn(usize) -> f64,
        n: usize,
        i: usize,
        local: f64,
        len: f64,
    ) -> f64 {
        if i + 1 >= n || len <= 0.0 {
            return h(i.min(n - 1));
        }
        let diff = |a: f64, b: f64| wrap(a - b);
        let local = local.clamp(0.0, len);
        match self {
            Turn::None => h(i),
            Turn::Segment => wrap(h(i) + local / len * diff(h(i + 1), h(i))),
            Turn::Corner => {
                let r = (len / 2.0).min(2.0);
                if local < r {
                    if i > 0 {
                        let a = (r + local) / (2.0 * r);
                        wrap(h(i - 1) + a * diff(h(i), h(i - 1)))
                    } else {
                        h(i)
                    }
                } else if local > len - r {
                    let a = if i + 2 < n {
                        (r + (len - local)) / (2.0 * r)
                    } else {
                        (len - local) / r
                    };
                    wrap(h(i) + (1.0 - a) * diff(h(i + 1), h(i)))
                } else {
                    h(i)
                }
            }
        }
    }
}

/// A timed polyline: vertices with their times (s, from the simulation's start).
#[derive(Debug, Clone, PartialEq)]
pub struct Timed {
    /// `(t, pose)` in increasing `t`.
    pub vertices: Vec<(f64, Pose)>,
    /// How the heading turns between vertices.
    pub turn: Turn,
    /// In `followingMode="follow"`, each leg's motion at a constant acceleration
    /// ([`Legs`]); `None`: at a constant speed (`position`).
    pub legs: Option<Legs>,
}

/// A timed polyline followed in esmini's `follow` mode (`PolyLineShape::CalculatePolyLine`):
/// each leg at a constant acceleration, from the speed the leg before ended at (the first
/// from the entity's speed when the action starts), so that the leg's length is covered in
/// its time; a leg that would end below 0 m/s ends at 0 m/s sooner, as esmini's does.
#[derive(Debug, Clone, PartialEq)]
pub struct Legs {
    /// Each vertex's distance along the polyline, m.
    station_m: Vec<f64>,
    /// The speed at each vertex, m/s.
    speed_mps: Vec<f64>,
    /// The acceleration on the leg from each vertex, m/s² (0 from the last).
    acc_mps2: Vec<f64>,
}

impl Legs {
    /// The legs of `vertices` (`(t, pose)`, increasing `t`) entered at `v0` m/s.
    pub fn new(vertices: &[(f64, Pose)], v0: f64) -> Legs {
        let n = vertices.len();
        let mut station_m = vec![0.0; n];
        for i in 1..n {
            let (a, b) = (vertices[i - 1].1, vertices[i].1);
            station_m[i] = station_m[i - 1] + (b.x - a.x).hypot(b.y - a.y);
        }
        let (mut speed_mps, mut acc_mps2) = (vec![v0; n], vec![0.0; n]);
        let mut v = v0;
        for i in 1..n {
            let ds = station_m[i] - station_m[i - 1];
            let dt = vertices[i].0 - vertices[i - 1].0;
            let mut acc = 0.0;
            if ds.abs() > 1e-6 && dt > TIME_EPS_S {
                acc = 2.0 * (ds - v * dt) / (dt * dt);
                // esmini's SIGN: 0 counts as positive.
                if ((v + acc * dt) < 0.0) != (v < 0.0) {
                    // Too long for a constant acceleration to 0 m/s: it arrives sooner.
                    acc = -v * v / (2.0 * ds);
                    v = 0.0;
                } else {
                    v += acc * dt;
                }
            } else if ds.abs() <= 1e-6 {
                v = 0.0;
            }
            acc_mps2[i - 1] = acc;
            speed_mps[i] = v;
        }
        Legs {
            station_m,
            speed_mps,
            acc_mps2,
        }
    }

    /// The distance along the polyline at `t` (s), m, on leg `i` (from vertex `i`, whose
    /// time is `t_i`).
    fn station(&self, i: usize, t_i: f64, t: f64) -> f64 {
        let (v, a) = (self.speed_mps[i], self.acc_mps2[i]);
        let mut dt = (t - t_i).max(0.0);
        if a < 0.0 {
            dt = dt.min(-v / a);
        }
        self.station_m[i] + v * dt + 0.5 * a * dt * dt
    }
}

impl Timed {
    /// The pose at `t` (s): the position linear between vertices (or, with [`Legs`], at the
    /// distance each leg's acceleration gives), the heading turned as [`Turn`] says (a
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
        if let Some(legs) = &self.legs {
            return (self.along(legs, t), false);
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
        let h = match self.turn {
            Turn::None => a.1.h,
            turn => {
                let len = (b.1.x - a.1.x).hypot(b.1.y - a.1.y);
                turn.heading(|k| self.vertices[k].1.h, n, i - 1, u * len, len)
            }
        };
        (
            Pose {
                x: a.1.x + u * (b.1.x - a.1.x),
                y: a.1.y + u * (b.1.y - a.1.y),
                h,
            },
            false,
        )
    }

    /// The pose at `t` (s, within the vertices' times) with `legs`: on the leg whose end
    /// time is the first at or after `t` (esmini's `PolyLineShape::Evaluate`), at the
    /// distance its acceleration gives, in the leg that distance falls on.
    fn along(&self, legs: &Legs, t: f64) -> Pose {
        let n = self.vertices.len();
        let i = (0..n - 1)
            .find(|&i| self.vertices[i + 1].0 >= t)
            .unwrap_or(n - 2);
        let s = legs.station(i, self.vertices[i].0, t);
        // The leg `s` falls on (a later one where the leg before is shorter).
        let j = (i..n - 1)
            .find(|&j| s <= legs.station_m[j + 1] + 1e-12)
            .unwrap_or(n - 2);
        let (a, b) = (self.vertices[j].1, self.vertices[j + 1].1);
        let len = legs.station_m[j + 1] - legs.station_m[j];
        let local = (s - legs.station_m[j]).clamp(0.0, len);
        let u = if len > 0.0 { local / len } else { 1.0 };
        let h = match self.turn {
            Turn::None => a.h,
            turn => turn.heading(|k| self.vertices[k].1.h, n, j, local, len),
        };
        Pose {
            x: a.x + u * (b.x - a.x),
            y: a.y + u * (b.y - a.y),
            h,
        }
    }
}

/// A polyline followed at the entity's own speed.
#[derive(Debug, Clone, PartialEq)]
pub struct Untimed {
    /// Its vertices.
    pub vertices: Vec<Pose>,
    /// Distance gone along it, m.
    pub gone_m: f64,
    /// How the heading turns between vertices.
    pub turn: Turn,
    /// How the entity faced the path's direction where it started on it (esmini's
    /// `initialHeadingSign_`): `1.0` along it, `-1.0` against it (a car that reverses along
    /// a path laid behind it). Its distance along the path changes by its own move times this,
    /// and against the path it faces the other way, unless the path gives its headings
    /// ([`Untimed::explicit`]).
    pub facing: f64,
    /// Every vertex gives its heading (a polyline whose vertices each have an orientation):
    /// the entity takes them as they are, whichever way it moves.
    pub explicit: bool,
}

impl Untimed {
    /// The direction of travel along the path (rad) at distance `at` (m): the direction of
    /// the leg there.
    pub fn direction_at(&self, at: f64) -> f64 {
        let mut left = at.max(0.0);
        let legs: Vec<(Pose, Pose)> = self
            .vertices
            .windows(2)
            .map(|w| (w[0], w[1]))
            .filter(|(a, b)| (b.x - a.x).hypot(b.y - a.y) > 1e-9)
            .collect();
        for (a, b) in &legs {
            let len = (b.x - a.x).hypot(b.y - a.y);
            if left <= len {
                return (b.y - a.y).atan2(b.x - a.x);
            }
            left -= len;
        }
        legs.last()
            .map_or(self.vertices[0].h, |(a, b)| (b.y - a.y).atan2(b.x - a.x))
    }

    /// The distance along the path, m, of its point nearest `p` (`[x, y]`, m).
    pub fn station_of(&self, p: [f64; 2]) -> f64 {
        let (mut best, mut best_d2, mut along) = (0.0, f64::INFINITY, 0.0);
        for w in self.vertices.windows(2) {
            let (a, b) = (w[0], w[1]);
            let (ux, uy) = (b.x - a.x, b.y - a.y);
            let len2 = ux * ux + uy * uy;
            let u = if len2 > 0.0 {
                (((p[0] - a.x) * ux + (p[1] - a.y) * uy) / len2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let (qx, qy) = (a.x + u * ux, a.y + u * uy);
            let d2 = (p[0] - qx).powi(2) + (p[1] - qy).powi(2);
            if d2 < best_d2 {
                (best, best_d2) = (along + u * len2.sqrt(), d2);
            }
            along += len2.sqrt();
        }
        best
    }

    /// Goes `dist` m further; the pose there and whether the end is reached.
    pub fn advance(&mut self, dist: f64) -> (Pose, bool) {
        let (pose, over) = self.advance_along(dist * self.facing);
        if self.facing < 0.0 && !self.explicit {
            return (
                Pose {
                    h: paracosm_engine::network::roads::wrap(pose.h + std::f64::consts::PI),
                    ..pose
                },
                over,
            );
        }
        (pose, over)
    }

    /// [`Untimed::advance`] by `along` m along the path's direction (backwards when
    /// negative: it is over once back at the path's start).
    fn advance_along(&mut self, along: f64) -> (Pose, bool) {
        self.gone_m += along;
        if along < 0.0 && self.gone_m <= 1e-6 {
            self.gone_m = 0.0;
            return (self.vertices[0], true);
        }
        let mut left = self.gone_m.max(0.0);
        for (i, w) in self.vertices.windows(2).enumerate() {
            let (a, b) = (w[0], w[1]);
            let len = (b.x - a.x).hypot(b.y - a.y);
            if left <= len && len > 0.0 {
                let u = left / len;
                let h = match self.turn {
                    Turn::None => a.h,
                    turn => {
                        let n = self.vertices.len();
                        turn.heading(|k| self.vertices[k].h, n, i, left, len)
                    }
                };
                return (
                    Pose {
                        x: a.x + u * (b.x - a.x),
                        y: a.y + u * (b.y - a.y),
                        h,
                    },
                    false,
                );
            }
            left -= len;
        }
        (self.vertices[self.vertices.len() - 1], true)
    }
}

/// Most steps a clothoid trajectory is sampled into (25 km at the engine's 0.25 m step; a
/// clothoid may be as long as [`paracosm_openscenario::Quantity::Distance`] allows, 1,000 km).
pub const CLOTHOID_SAMPLES: usize = 100_000;

/// A clothoid's points from `start` (OpenSCENARIO `x`, `y` m; its heading the curve's), of
/// curvature `curvature` (1/m, positive to the left) changing by `prime` (1/m²) over `length`
/// m: `(distance along it m, pose)`, one at least every
/// [`paracosm_engine::network::POLYLINE_STEP_M`] (for a clothoid longer than
/// [`CLOTHOID_SAMPLES`] such steps, its length over [`CLOTHOID_SAMPLES`]: at most that many
/// points, whatever the length), facing along the curve. The engine's clothoid quadrature
/// ([`paracosm_engine::network::RefLine`]).
pub fn clothoid_poses(start: Pose, curvature: f64, prime: f64, length: f64) -> Vec<(f64, Pose)> {
    use paracosm_engine::network::{RefLine, POLYLINE_STEP_M};
    let line = RefLine {
        length_m: length,
        curv_start: curvature,
        curv_end: curvature + prime * length,
    };
    let (c, s) = (start.h.cos(), start.h.sin());
    line.polyline(POLYLINE_STEP_M.max(length / CLOTHOID_SAMPLES as f64))
        .into_iter()
        .map(|(d, [x, z])| {
            // The engine's frame has +z to the right of travel; OpenSCENARIO's +y is left.
            let (lx, ly) = (x, -z);
            (
                d,
                Pose {
                    x: start.x + c * lx - s * ly,
                    y: start.y + s * lx + c * ly,
                    h: wrap(start.h + line.heading(d)),
                },
            )
        })
        .collect()
}

/// The B-spline basis functions of `order` over `knots` at `u` that can be non-zero there,
/// among the first `n`: `(first, values)`, `values[i]` being function `first + i` (Cox–de
/// Boor recursion; Piegl and Tiller, *The NURBS Book*, 1997, eq. 2.5), with the curve's last
/// parameter in its last non-empty span. Only the spans that hold `u` and the triangle of
/// functions above them are computed, `O(order²)` whatever the number of knots (every other
/// function is zero at `u`); the arithmetic is the full recursion's, so the values are its
/// bits.
fn basis(order: usize, knots: &[f64], n: usize, u: f64) -> (usize, Vec<f64>) {
    let end = knots[n];
    // The degree-0 functions that are 1: the non-empty span holding `u` (knots do not
    // decrease, so at most one) and, at the end, the last non-empty span ending there.
    let holds = knots.partition_point(|&k| k <= u);
    let mut ones: Vec<usize> = Vec::with_capacity(2);
    if holds > 0 && holds < knots.len() {
        ones.push(holds - 1);
    }
    if u >= end {
        let last = knots.partition_point(|&k| k < end);
        if last > 0 && last < knots.len() && knots[last] == end && knots[last - 1] < end {
            ones.push(last - 1);
        }
    }
    let spans = knots.len() - 1;
    let (Some(&lo), Some(&hi)) = (ones.iter().min(), ones.iter().max()) else {
        return (0, Vec::new());
    };
    let first = lo.saturating_sub(order - 1);
    let mut b: Vec<f64> = (first..=hi)
        .map(|i| if ones.contains(&i) { 1.0 } else { 0.0 })
        .collect();
    let at = |b: &[f64], i: usize| {
        if i >= first && i <= hi {
            b[i - first]
        } else {
            0.0
        }
    };
    for d in 1..order {
        for i in first..=hi.min(spans.saturating_sub(d + 1)) {
            let left = if knots[i + d] > knots[i] {
                (u - knots[i]) / (knots[i + d] - knots[i]) * at(&b, i)
            } else {
                0.0
            };
            let right = if knots[i + d + 1] > knots[i + 1] {
                (knots[i + d + 1] - u) / (knots[i + d + 1] - knots[i + 1]) * at(&b, i + 1)
            } else {
                0.0
            };
            b[i - first] = left + right;
        }
    }
    b.truncate(n.saturating_sub(first));
    (first, b)
}

/// Most points a NURBS trajectory is sampled into.
const NURBS_SAMPLES: usize = 100_000;

/// How far apart a NURBS trajectory's samples are along its control polygon, m (esmini's
/// `NURBS_STEPLENGTH`).
const NURBS_STEP_M: f64 = 1.0;

/// Turns `out`'s samples (`(parameter, pose)`) of the NURBS `(order, points, knots)` to
/// face along the curve, as esmini's `NurbsShape::CalculatePolyLine` faces each sample: its
/// tangent, from the point a `step` of the parameter further (before, at the last), within
/// `[u0, u1]`; the first sample as the second (esmini resolves the first segment's heading
/// from its successor); a sample where the curve does not move as the one before.
fn face_along(
    out: &mut [(f64, Pose)],
    (order, points, knots): (usize, &[ControlPoint], &[f64]),
    (u0, u1, step): (f64, f64, f64),
) {
    let n = points.len();
    let at = |u: f64| {
        let (first, b) = basis(order, knots, n, u);
        let near = points.get(first..).unwrap_or(&[]);
        let w: f64 = b.iter().zip(near).map(|(bi, p)| bi * p.1).sum();
        let w = if w > 0.0 { w } else { 1.0 };
        b.iter().zip(near).fold([0.0, 0.0], |[x, y], (bi, p)| {
            [x + bi * p.1 / w * p.2[0], y + bi * p.1 / w * p.2[1]]
        })
    };
    let m = out.len();
    for k in 1..m {
        let (u, p) = (out[k].0, out[k].1);
        let [qx, qy] = if k + 1 < m {
            at((u + step).min(u1))
        } else {
            at((u - step).max(u0))
        };
        let (dx, dy) = if k + 1 < m {
            (qx - p.x, qy - p.y)
        } else {
            (p.x - qx, p.y - qy)
        };
        out[k].1.h = if dx.hypot(dy) > 1e-6 {
            dy.atan2(dx)
        } else {
            out[k - 1].1.h
        };
    }
    if m > 1 {
        out[0].1.h = out[1].1.h;
    }
}

/// Where each control point's basis function peaks over `out`'s samples of the NURBS
/// `(order, points, knots)`, `(value, parameter)`: as esmini finds it, each sample read a
/// `step` of the parameter on (back, at the last), where esmini's `CalculatePolyLine` last
/// evaluated the curve, and credited to the sample.
fn peaks(
    out: &[(f64, Pose)],
    (order, points, knots): (usize, &[ControlPoint], &[f64]),
    (u0, u1, step): (f64, f64, f64),
) -> Vec<(f64, f64)> {
    let n = points.len();
    let mut peak = vec![(0.0f64, u0); n];
    for (k, (u, _)) in out.iter().enumerate() {
        let read = if k + 1 < out.len() {
            (u + step).min(u1)
        } else {
            (u - step).max(u0)
        };
        let (first, b) = basis(order, knots, n, read);
        for (j, bi) in b.iter().enumerate() {
            if let Some(pk) = peak.get_mut(first + j) {
                if *bi > pk.0 {
                    *pk = (*bi, *u);
                }
            }
        }
    }
    peak
}

/// The step of a NURBS curve's parameter over which a sample's tangent is taken (esmini's
/// `NurbsShape::CalculatePolyLine`: 0.001, or the sampling step if smaller).
const NURBS_TANGENT_STEP: f64 = 0.001;

/// One control point of a NURBS trajectory: its time (s), weight (> 0), `[x, y]` (m) and the
/// heading its position gives (rad), if it gives one.
pub type ControlPoint = (Option<f64>, f64, [f64; 2], Option<f64>);

/// A NURBS curve of `order` over `points` and `knots` (Piegl and Tiller, *The NURBS Book*,
/// 1997, eq. 4.2), sampled evenly in its parameter, one step per metre of its control
/// polygon (at most [`NURBS_SAMPLES`] points): `(time, pose)`, as esmini samples it and reads
/// the standard's optional times and headings (`roadmanager::NurbsShape`). Each control point's time belongs to the parameter
/// where its basis function peaks, and times are linear in the parameter between those
/// (when every control point has one). A point faces as the control points' headings blend
/// by the same rational basis when every control point gives one, else along the curve (its
/// tangent at each sample, the first as the second, as esmini faces them).
pub fn nurbs_poses(
    order: usize,
    points: &[ControlPoint],
    knots: &[f64],
) -> Vec<(Option<f64>, Pose)> {
    let n = points.len();
    let (u0, u1) = (knots[order - 1], knots[n]);
    let polygon: f64 = points
        .windows(2)
        .map(|w| (w[1].2[0] - w[0].2[0]).hypot(w[1].2[1] - w[0].2[1]))
        .sum();
    let samples = ((polygon / NURBS_STEP_M) as usize + 2).clamp(2, NURBS_SAMPLES);
    let headed = points.iter().all(|p| p.3.is_some());
    let mut out: Vec<(f64, Pose)> = (0..samples)
        .map(|k| {
            let u = u0 + (u1 - u0) * k as f64 / (samples - 1) as f64;
            let (first, b) = basis(order, knots, n, u);
            let near = points.get(first..).unwrap_or(&[]);
            let w: f64 = b.iter().zip(near).map(|(bi, p)| bi * p.1).sum();
            let w = if w > 0.0 { w } else { 1.0 };
            let (mut x, mut y, mut h) = (0.0, 0.0, 0.0);
            for (bi, p) in b.iter().zip(near) {
                let f = bi * p.1 / w;
                x += f * p.2[0];
                y += f * p.2[1];
                if *bi > 1e-12 {
                    h += f * wrap(p.3.unwrap_or(0.0) - h);
                }
            }
            (u, Pose { x, y, h: wrap(h) })
        })
        .collect();
    // The parameter's step to where esmini reads a sample's tangent and its basis peaks.
    let step = ((u1 - u0) / (samples - 1) as f64).min(NURBS_TANGENT_STEP);
    if !headed {
        face_along(&mut out, (order, points, knots), (u0, u1, step));
    }
    let peak = peaks(&out, (order, points, knots), (u0, u1, step));
    let times: Option<Vec<f64>> = points.iter().map(|p| p.0).collect();
    let Some(times) = times else {
        return out.into_iter().map(|(_, p)| (None, p)).collect();
    };
    let mut cur = 0;
    out.into_iter()
        .map(|(u, p)| {
            if u >= peak[cur + 1].1 {
                cur = (cur + 1).min(n.max(2) - 2);
            }
            let (a, b) = (peak[cur].1, peak[cur + 1].1);
            let w = if b > a { (u - a) / (b - a) } else { 0.0 };
            (Some(times[cur] + w * (times[cur + 1] - times[cur])), p)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shapes_start_at_zero_end_at_one_and_are_symmetric() {
        use paracosm_engine::transition::progress;
        for shape in [Shape::Linear, Shape::Cubic, Shape::Sinusoidal] {
            assert_eq!(progress(shape_of(shape), 0.0), 0.0);
            assert!((progress(shape_of(shape), 1.0) - 1.0).abs() < 1e-12);
            assert!(
                (progress(shape_of(shape), 0.5) - 0.5).abs() < 1e-12,
                "{shape:?}"
            );
        }
        assert_eq!(progress(shape_of(Shape::Step), 0.0), 1.0);
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
            shape: shape_of(Shape::Sinusoidal),
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
            shape: shape_of(Shape::Sinusoidal),
        };
        let h = 1e-4;
        let acc = (tr.at(2.0 * h).0 - 2.0 * tr.at(h).0 + tr.at(0.0).0) / (h * h);
        assert!((acc - a).abs() < 1e-2, "{acc}");
    }

    /// In `follow` mode each leg is covered at a constant acceleration from the speed the leg
    /// before ended at (esmini's `bicycle_fall_over`: at 10 m/s, 20 m in 2 s and 5 m in
    /// 0.5 s keep 10 m/s; 5 m in 1 s then brakes from 10 to 0 m/s, 128.75 m at its middle;
    /// a leg of no length stands); in `position` mode each leg is at its own constant speed.
    #[test]
    fn a_timed_polyline_in_follow_mode_accelerates_along_each_leg() {
        let p = |x: f64| Pose { x, y: 0.0, h: 0.0 };
        let vertices = vec![
            (0.0, p(100.0)),
            (2.0, p(120.0)),
            (2.5, p(125.0)),
            (3.5, p(130.0)),
            (4.0, p(130.0)),
        ];
        let follow = Timed {
            turn: Turn::Segment,
            legs: Some(Legs::new(&vertices, 10.0)),
            vertices: vertices.clone(),
        };
        let position = Timed {
            turn: Turn::Segment,
            legs: None,
            vertices,
        };
        for (t, x) in [
            (1.0, 110.0),
            (2.25, 122.5),
            (3.0, 128.75),
            (3.4, 129.95),
            (3.8, 130.0),
        ] {
            let (q, done) = follow.at(t);
            assert!(!done && (q.x - x).abs() < 1e-9, "{t}: {}", q.x);
        }
        assert!((position.at(3.0).0.x - 127.5).abs() < 1e-9);
        // Entered at rest, the first leg accelerates: 20 m in 2 s at 10 m/s², 5 m at 1 s.
        let from_rest = Legs::new(&follow.vertices, 0.0);
        let at_rest = Timed {
            legs: Some(from_rest),
            ..follow.clone()
        };
        assert!((at_rest.at(1.0).0.x - 105.0).abs() < 1e-9);
    }

    /// An entity that faces against a path it follows (esmini's `initialHeadingSign_` of
    /// −1: a car reversing along a path laid behind it, as in esmini's `trailer_connect`) goes
    /// along the path at a negative speed, facing away from the way it goes; the path's own
    /// headings, when it gives them, are taken as they are; at a positive speed it goes back
    /// along the path and the trajectory is over at its start.
    #[test]
    fn an_entity_facing_against_its_path_reverses_along_it() {
        let p = |x: f64| Pose { x, y: 0.0, h: 0.0 };
        let mut u = Untimed {
            turn: Turn::Segment,
            vertices: vec![p(0.0), p(10.0)],
            gone_m: 0.0,
            facing: -1.0,
            explicit: false,
        };
        assert_eq!(u.direction_at(3.0), 0.0);
        let (q, over) = u.advance(-4.0);
        assert!(!over && (q.x - 4.0).abs() < 1e-12);
        assert!((q.h - std::f64::consts::PI).abs() < 1e-12, "{}", q.h);
        u.explicit = true;
        assert_eq!(u.advance(-1.0).0.h, 0.0);
        let (q, over) = u.advance(6.0);
        assert!(over && q.x == 0.0, "{q:?}");
    }

    #[test]
    fn a_timed_polyline_is_linear_between_its_vertices_facing_as_each_leg_starts() {
        let p = |x: f64, y: f64| Pose { x, y, h: 0.3 };
        let path = Timed {
            turn: Turn::None,
            legs: None,
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
            turn: Turn::None,
            vertices: vec![p(0.0, 0.0), p(3.0, 0.0), p(3.0, 4.0)],
            gone_m: 0.0,
            facing: 1.0,
            explicit: false,
        };
        let (q, done) = u.advance(5.0);
        assert!(!done && (q.x - 3.0).abs() < 1e-12 && (q.y - 2.0).abs() < 1e-12);
        assert!(u.advance(3.0).1);
    }

    #[test]
    fn a_rational_quadratic_nurbs_is_a_quarter_circle() {
        // The NURBS Book, example 7.1: control points (R, 0), (R, R), (0, R), weights 1,
        // √2/2, 1, knots 0 0 0 1 1 1.
        let r = 7.0;
        let w = std::f64::consts::FRAC_1_SQRT_2;
        let points = [
            (Some(0.0), 1.0, [r, 0.0], None),
            (Some(1.0), w, [r, r], None),
            (Some(2.0), 1.0, [0.0, r], None),
        ];
        let poses = nurbs_poses(3, &points, &[0.0, 0.0, 0.0, 1.0, 1.0, 1.0]);
        // One step per metre of the control polygon (14 m).
        assert_eq!(poses.len(), 16);
        for (t, p) in &poses {
            assert!((p.x.hypot(p.y) - r).abs() < 1e-9, "{p:?}");
            assert!(t.is_some_and(|t| (0.0..=2.0).contains(&t)));
        }
        // Each control point's time where its basis function peaks (esmini's reading): the
        // first at the start, the last at the end, the middle one halfway.
        assert_eq!(poses[0].0, Some(0.0));
        assert_eq!(poses[poses.len() - 1].0, Some(2.0));
        assert!(poses.iter().any(|(t, _)| *t == Some(1.0)));
        assert!(poses.windows(2).all(|w| w[1].0 >= w[0].0));
        let mid = poses.len() / 2;
        let (first, last) = (poses[0].1, poses[poses.len() - 1].1);
        assert!((first.x - r).abs() < 1e-12 && first.y.abs() < 1e-12);
        assert!(last.x.abs() < 1e-12 && (last.y - r).abs() < 1e-12);
        // Facing along the circle, counter-clockwise: heading = angle + pi/2.
        let mid = poses[mid].1;
        let tangent = mid.y.atan2(mid.x) + std::f64::consts::FRAC_PI_2;
        assert!((mid.h - tangent).abs() < 0.1, "{} vs {tangent}", mid.h);
    }

    /// The full Cox–de Boor recursion over every knot span, as the basis was computed before
    /// it kept to the spans that hold `u`.
    fn full_basis(order: usize, knots: &[f64], n: usize, u: f64) -> Vec<f64> {
        let end = knots[n];
        let mut b: Vec<f64> = knots
            .windows(2)
            .map(|k| {
                let at_end = u >= end && k[0] < k[1] && k[1] == end;
                f64::from(u8::from((k[0] <= u && u < k[1]) || at_end))
            })
            .collect();
        for d in 1..order {
            for i in 0..knots.len() - 1 - d {
                let left = if knots[i + d] > knots[i] {
                    (u - knots[i]) / (knots[i + d] - knots[i]) * b[i]
                } else {
                    0.0
                };
                let right = if knots[i + d + 1] > knots[i + 1] {
                    (knots[i + d + 1] - u) / (knots[i + d + 1] - knots[i + 1]) * b[i + 1]
                } else {
                    0.0
                };
                b[i] = left + right;
            }
        }
        b.truncate(n);
        b
    }

    #[test]
    fn the_basis_near_u_has_the_full_recursions_bits_and_zeros_elsewhere() {
        // Clamped, uniform, repeated inner knots, and an unclamped end with knots past it.
        let cases: [(usize, Vec<f64>); 4] = [
            (3, vec![0.0, 0.0, 0.0, 0.3, 0.7, 1.0, 1.0, 1.0]),
            (4, (0..12).map(f64::from).collect()),
            (3, vec![0.0, 0.0, 0.0, 0.5, 0.5, 0.8, 1.0, 1.0, 1.0]),
            (2, vec![0.0, 1.0, 2.0, 3.0, 3.0, 4.0]),
        ];
        for (order, knots) in cases {
            let n = knots.len() - order;
            let (u0, u1) = (knots[order - 1], knots[n]);
            for k in 0..=200 {
                let u = u0 + (u1 - u0) * f64::from(k) / 200.0;
                let full = full_basis(order, &knots, n, u);
                let (first, near) = basis(order, &knots, n, u);
                for (i, f) in full.iter().enumerate() {
                    let got = i.checked_sub(first).and_then(|j| near.get(j)).copied();
                    match got {
                        Some(g) => assert!(g == *f, "order {order} u {u} i {i}: {g} vs {f}"),
                        None => assert!(*f == 0.0, "order {order} u {u} i {i}: {f} left out"),
                    }
                }
                // `order` functions, and at the curve's end of an unclamped knot vector
                // those of the last non-empty span too.
                assert!(near.len() <= 2 * order, "{} functions at u {u}", near.len());
            }
        }
    }

    #[test]
    fn a_nurbs_of_100000_control_points_is_sampled_in_linear_time() {
        // A straight line of 100,000 control points 1 m apart, order 16: the full recursion
        // took order · knots per sample (1.6e11 in all); the near basis order² per sample.
        let n = 100_000;
        let points: Vec<ControlPoint> =
            (0..n).map(|i| (None, 1.0, [i as f64, 0.0], None)).collect();
        let order = 16;
        let knots: Vec<f64> = (0..n + order)
            .map(|i| (i.clamp(order - 1, n) - (order - 1)) as f64)
            .collect();
        let poses = nurbs_poses(order, &points, &knots);
        assert_eq!(poses.len(), NURBS_SAMPLES);
        assert!(poses
            .iter()
            .all(|(_, p)| p.y.abs() < 1e-9 && p.h.abs() < 1e-9));
        let (a, b) = (poses[0].1, poses[poses.len() - 1].1);
        assert!(
            a.x.abs() < 1e-9 && (b.x - (n - 1) as f64).abs() < 1e-6,
            "{a:?} {b:?}"
        );
    }

    #[test]
    fn a_clothoid_without_curvature_change_is_an_arc_from_its_start() {
        let start = Pose {
            x: 10.0,
            y: -3.0,
            h: 0.4,
        };
        let (k, len) = (1.0 / 25.0, 30.0);
        let poses = clothoid_poses(start, k, 0.0, len);
        // The centre lies 25 m to the left of the start.
        let centre = (
            start.x - 25.0 * start.h.sin(),
            start.y + 25.0 * start.h.cos(),
        );
        for (d, p) in &poses {
            assert!(
                ((p.x - centre.0).hypot(p.y - centre.1) - 25.0).abs() < 1e-6,
                "{p:?}"
            );
            assert!((p.h - (start.h + k * d)).abs() < 1e-9);
        }
        let (d, _) = poses[poses.len() - 1];
        assert!((d - len).abs() < 1e-9);
    }
}
