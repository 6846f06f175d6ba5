use serde::{Deserialize, Serialize};

use super::{Cruise, Sut, SutError};
use crate::{Control, Observation};

/// Settings of the built-in [`Aeb`] system.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AebConfig {
    /// Cruise control and the braking rule.
    pub cruise: Cruise,
    /// Returns lower than this, in metres relative to the chassis centre (`y` of the vehicle
    /// frame), are ground clutter and ignored. Default -0.6 m (about 0.25 m above the road).
    pub min_height_m: f64,
    /// Lane keeping: steering per metre of lateral offset from the start line. Default 0.1.
    pub lateral_gain: f64,
    /// Lane keeping: steering per radian of heading error. Default 1.0.
    pub heading_gain: f64,
    /// Route following (pure pursuit): wheelbase in metres. Default 2.9 m.
    pub wheelbase_m: f64,
    /// Route following: front-wheel angle at full steering, rad. Default 0.5 rad.
    pub max_steer_rad: f64,
    /// Route following: look-ahead time in seconds, times the speed. Default 0.6 s.
    pub lookahead_s: f64,
    /// Route following: shortest look-ahead distance in metres. Default 5 m.
    pub min_lookahead_m: f64,
    /// Route following: largest lateral acceleration in curves, m/s². Default 2.5 m/s².
    pub lateral_accel_mps2: f64,
    /// Route following: deceleration planned before curves, m/s². Default 2 m/s².
    pub curve_decel_mps2: f64,
}

impl Default for AebConfig {
    fn default() -> Self {
        AebConfig {
            cruise: Cruise::default(),
            min_height_m: -0.6,
            lateral_gain: 0.1,
            heading_gain: 1.0,
            wheelbase_m: 2.9,
            max_steer_rad: 0.5,
            lookahead_s: 0.6,
            min_lookahead_m: 5.0,
            lateral_accel_mps2: 2.5,
            curve_decel_mps2: 2.0,
        }
    }
}

/// `aeb`: a cruise controller with automatic emergency braking.
///
/// Each step it keeps the lane it started in (proportional control on lateral offset and
/// heading from odometry) or, when the observation carries a route, follows the route by pure
/// pursuit (Coulter 1992) and slows for its curves (lateral acceleration at most
/// `lateral_accel_mps2`, planned with `curve_decel_mps2`). It looks for lidar returns inside its corridor ahead. With `g` the
/// gap from the bumper to the nearest such return and `v` the speed, it brakes at full force
/// when `g - standstill_gap_m < v · ttc_brake_s` (time to collision below `ttc_brake_s`, a
/// static-obstacle assumption), and otherwise tracks `target_speed_mps`. It sees only what the
/// lidar sees: a pedestrian outside the corridor, or one that enters it too late, is not
/// avoided. That is the failure the pedestrian-crossing study looks for.
#[derive(Debug, Clone)]
pub struct Aeb {
    config: AebConfig,
    /// Start pose `(x, z, heading)`, the line lane keeping follows.
    line: Option<(f64, f64, f64)>,
    /// Index of the route vertex reached so far.
    progress: usize,
    /// [`curvature_at`] of the route being followed, from its start as far as `act` has read
    /// it, and that route's address (cleared by `reset`): a route on a map runs kilometres
    /// ahead, and a short test reads only its first metres.
    curves: Vec<(f64, f64)>,
    curves_of: usize,
    /// The bounding box `[min x, max x, min z, max z]` (m) of each run of [`RUN`] route
    /// points of that route, for [`nearest_vertex`], as far as it has looked.
    boxes: Vec<[f64; 4]>,
}

/// Route points per bounding box of [`Aeb`]'s `boxes`.
const RUN: usize = 8;

/// How many route points ahead of the last one reached [`nearest_vertex`] looks at.
const WINDOW: usize = 64;

/// The index of the route point nearest `(x, z)` among the [`WINDOW`] points from `from` on:
/// the first of the smallest squared distances, compared with `f64::total_cmp`. A run of
/// points whose box is farther than the nearest point found so far is skipped: each point's
/// squared distance is at least its box's (floating-point subtraction, squaring and addition
/// are monotone), so it could not be smaller.
/// `boxes` holds [`run_boxes`] at least up to the run of the window's last point.
fn nearest_vertex(route: &[[f64; 2]], boxes: &[[f64; 4]], from: usize, x: f64, z: f64) -> usize {
    let d2 = |p: [f64; 2]| (p[0] - x).powi(2) + (p[1] - z).powi(2);
    let end = route.len().min(from + WINDOW);
    let (mut best, mut best_d2) = (from, f64::NAN);
    let mut i = from;
    while i < end {
        let run_end = ((i / RUN + 1) * RUN).min(end);
        let b = &boxes[i / RUN];
        let dx = (b[0] - x).max(x - b[1]).max(0.0);
        let dz = (b[2] - z).max(z - b[3]).max(0.0);
        if i > from && dx.powi(2) + dz.powi(2) > best_d2 {
            i = run_end;
            continue;
        }
        for (k, &p) in route.iter().enumerate().take(run_end).skip(i) {
            let d = d2(p);
            if k == from || d.total_cmp(&best_d2) == std::cmp::Ordering::Less {
                (best, best_d2) = (k, d);
            }
        }
        i = run_end;
    }
    best
}

/// The bounding boxes of `route`'s runs of [`RUN`] points.
#[cfg(test)]
fn run_boxes(route: &[[f64; 2]]) -> Vec<[f64; 4]> {
    let mut boxes = Vec::new();
    extend_boxes(&mut boxes, route, route.len());
    boxes
}

/// Extends `boxes`, the bounding boxes of `route`'s runs of [`RUN`] points from the first,
/// until it covers the run of point `upto - 1` (or the whole route).
fn extend_boxes(boxes: &mut Vec<[f64; 4]>, route: &[[f64; 2]], upto: usize) {
    let runs = upto.min(route.len()).div_ceil(RUN);
    while boxes.len() < runs {
        let k = boxes.len();
        let run = &route[k * RUN..((k + 1) * RUN).min(route.len())];
        boxes.push(run.iter().fold(
            [
                f64::INFINITY,
                f64::NEG_INFINITY,
                f64::INFINITY,
                f64::NEG_INFINITY,
            ],
            |b, p| {
                [
                    b[0].min(p[0]),
                    b[1].max(p[0]),
                    b[2].min(p[1]),
                    b[3].max(p[1]),
                ]
            },
        ));
    }
}

impl Aeb {
    /// An `aeb` system with the given settings.
    pub fn new(config: AebConfig) -> Self {
        Aeb {
            config,
            line: None,
            progress: 0,
            curves: Vec::new(),
            curves_of: 0,
            boxes: Vec::new(),
        }
    }

    /// Distance in metres from the chassis centre to the nearest lidar return in the
    /// corridor ahead, if any.
    pub fn nearest_obstacle_m(&self, obs: &Observation<'_>) -> Option<f64> {
        let c = &self.config;
        obs.lidar()
            .iter()
            .filter(|r| {
                r.point_m[0] > 0.0
                    && r.point_m[2].abs() <= c.cruise.corridor_half_width_m
                    && r.point_m[1] >= c.min_height_m
            })
            .map(|r| r.point_m[0])
            .reduce(f64::min)
    }

    /// Gap in metres from the bumper to the nearest return in the corridor, if any.
    pub fn nearest_gap_m(&self, obs: &Observation<'_>) -> Option<f64> {
        self.nearest_obstacle_m(obs)
            .map(|d| d - self.config.cruise.front_offset_m)
    }
}

impl Sut for Aeb {
    fn reset(&mut self, _seed: u64) -> Result<(), SutError> {
        self.line = None;
        self.progress = 0;
        self.curves.clear();
        self.boxes.clear();
        self.curves_of = 0;
        Ok(())
    }

    fn act(&mut self, obs: &Observation<'_>) -> Result<Control, SutError> {
        let (steering, target_speed) = if obs.route.len() >= 2 {
            self.pursue(obs)
        } else {
            (
                self.keep_line(obs),
                obs.set_speed_mps
                    .unwrap_or(self.config.cruise.target_speed_mps),
            )
        };
        let throttle = self.config.cruise.throttle(
            obs.ego.speed_mps,
            target_speed,
            self.nearest_obstacle_m(obs),
        );
        Ok(Control { throttle, steering }.clamped())
    }
}

impl Aeb {
    /// Steering that holds the start line.
    fn keep_line(&mut self, obs: &Observation<'_>) -> f64 {
        let c = &self.config;
        let ego = obs.ego;
        let (x0, z0, h0) = *self
            .line
            .get_or_insert((ego.pos_m[0], ego.pos_m[2], ego.heading_rad));
        // Lateral offset to the right of the start line, in the start heading's frame.
        let (dx, dz) = (ego.pos_m[0] - x0, ego.pos_m[2] - z0);
        let right = dz * h0.cos() + dx * h0.sin();
        let heading_err = (ego.heading_rad - h0 + std::f64::consts::PI)
            .rem_euclid(std::f64::consts::TAU)
            - std::f64::consts::PI;
        c.lateral_gain * right - c.heading_gain * heading_err
    }

    /// Pure-pursuit steering toward the route point one look-ahead distance ahead, and the
    /// speed the curves ahead allow.
    fn pursue(&mut self, obs: &Observation<'_>) -> (f64, f64) {
        let c = &self.config;
        let route = obs.route;
        let (x, z) = (obs.ego.pos_m[0], obs.ego.pos_m[2]);
        let d2 = |p: [f64; 2]| (p[0] - x).powi(2) + (p[1] - z).powi(2);
        if self.curves_of != route.as_ptr() as usize || self.curves.len() > route.len() {
            self.curves.clear();
            self.boxes.clear();
            self.curves_of = route.as_ptr() as usize;
            // A new route (a storyboard's lane change): followed from its start.
            self.progress = 0;
        }
        if self.progress < route.len() {
            extend_boxes(&mut self.boxes, route, self.progress + WINDOW);
            self.progress = nearest_vertex(route, &self.boxes, self.progress, x, z);
        }
        let v = obs.ego.speed_mps.max(0.0);
        let lookahead = (v * c.lookahead_s).max(c.min_lookahead_m);
        let mut target = *route.last().expect("two points");
        let mut travelled = d2(route[self.progress]).sqrt();
        for w in route[self.progress..].windows(2) {
            let seg = ((w[1][0] - w[0][0]).powi(2) + (w[1][1] - w[0][1]).powi(2)).sqrt();
            if travelled + seg >= lookahead {
                let u = ((lookahead - travelled) / seg.max(1e-9)).clamp(0.0, 1.0);
                target = [
                    w[0][0] + u * (w[1][0] - w[0][0]),
                    w[0][1] + u * (w[1][1] - w[0][1]),
                ];
                break;
            }
            travelled += seg;
        }
        let bearing = (-(target[1] - z)).atan2(target[0] - x);
        let alpha = wrap(bearing - obs.ego.heading_rad);
        let ld = d2(target).sqrt().max(1e-3);
        let steer = (2.0 * c.wheelbase_m * alpha.sin() / ld).atan() / c.max_steer_rad;

        // Speed allowed by each curve ahead, less what braking at curve_decel covers.
        let mut speed = obs.set_speed_mps.unwrap_or(c.cruise.target_speed_mps);
        let mut ahead = 0.0;
        let horizon = v * v / (2.0 * c.curve_decel_mps2) + 20.0;
        for i in self.progress + 1..route.len().saturating_sub(1) {
            let (l1, kappa) = curvature_at(&mut self.curves, route, i);
            ahead += l1;
            if ahead > horizon {
                break;
            }
            if kappa > 1e-4 {
                let v_curve = (c.lateral_accel_mps2 / kappa).sqrt();
                speed = speed.min((v_curve * v_curve + 2.0 * c.curve_decel_mps2 * ahead).sqrt());
            }
        }
        (steer, speed)
    }
}

/// For point `i` of `route`, which has neighbours on both sides: the length of the leg into
/// it (m) and the curvature there (1/m), the turn between its legs over their mean length.
/// `curves` holds these for the points before `i` (`(0, 0)` for the first) and is extended
/// to `i`, since `act` reads them every step.
fn curvature_at(curves: &mut Vec<(f64, f64)>, route: &[[f64; 2]], i: usize) -> (f64, f64) {
    if curves.is_empty() {
        curves.push((0.0, 0.0));
    }
    while curves.len() <= i {
        let k = curves.len();
        let (a, b, d) = (route[k - 1], route[k], route[k + 1]);
        let l1 = (b[0] - a[0]).hypot(b[1] - a[1]);
        let l2 = (d[0] - b[0]).hypot(d[1] - b[1]);
        let turn = wrap((-(d[1] - b[1])).atan2(d[0] - b[0]) - (-(b[1] - a[1])).atan2(b[0] - a[0]));
        curves.push((l1, turn.abs() / ((l1 + l2) / 2.0).max(1e-6)));
    }
    curves[i]
}

fn wrap(a: f64) -> f64 {
    (a + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{EgoState, LidarReturn};

    fn obs(speed: f64, returns: &[[f64; 3]]) -> (EgoState, Vec<LidarReturn>) {
        let ego = EgoState {
            pos_m: [0.0, 0.85, 1.75],
            heading_rad: 0.0,
            speed_mps: speed,
        };
        let lidar = returns
            .iter()
            .map(|&p| LidarReturn {
                azimuth_rad: 0.0,
                elevation_rad: 0.0,
                range_m: p[0],
                point_m: p,
            })
            .collect();
        (ego, lidar)
    }

    fn act(speed: f64, returns: &[[f64; 3]]) -> Control {
        let (ego, lidar) = obs(speed, returns);
        let mut aeb = Aeb::new(AebConfig::default());
        aeb.act(&Observation {
            t_s: 0.0,
            dt_s: 1.0 / 60.0,
            ego,
            route: &[],
            set_speed_mps: None,
            readings: vec![("lidar", crate::sensor::Reading::Lidar(&lidar))],
        })
        .unwrap()
    }

    #[test]
    fn skipping_far_runs_finds_the_nearest_vertex_of_the_whole_window() {
        // A spiral that comes back near itself, with repeated points, probed from points
        // on it, beside it and far away, from every start index.
        let mut route: Vec<[f64; 2]> = (0..300)
            .map(|i| {
                let t = i as f64 * 0.21;
                [(3.0 + 0.2 * t) * t.cos(), (3.0 + 0.2 * t) * t.sin()]
            })
            .collect();
        route.insert(40, route[40]);
        route.insert(41, route[40]);
        let boxes = run_boxes(&route);
        let probes = [
            [0.0, 0.0],
            [3.1, 0.2],
            [-8.0, 5.0],
            [40.0, -40.0],
            [1e4, 3.0],
        ];
        for from in 0..route.len() {
            for &[x, z] in &probes {
                let d2 = |p: [f64; 2]| (p[0] - x).powi(2) + (p[1] - z).powi(2);
                let plain = (from..route.len().min(from + WINDOW))
                    .min_by(|&a, &b| d2(route[a]).total_cmp(&d2(route[b])))
                    .unwrap();
                assert_eq!(
                    nearest_vertex(&route, &boxes, from, x, z),
                    plain,
                    "{from} {x} {z}"
                );
            }
        }
    }

    #[test]
    fn brakes_when_time_to_collision_is_short() {
        // gap 10 m, 12 m/s: 10 - 2 < 12 · 1.4
        assert_eq!(act(12.0, &[[12.25, 0.1, 0.0]]).throttle, -1.0);
        // gap 40 m: 38 > 16.8, so it cruises
        assert!(act(12.0, &[[42.25, 0.1, 0.0]]).throttle >= 0.0);
    }

    #[test]
    fn ignores_returns_outside_the_corridor_and_ground_hits() {
        assert!(act(12.0, &[[10.0, 0.1, 2.0]]).throttle >= 0.0);
        assert!(act(12.0, &[[10.0, -0.8, 0.0]]).throttle >= 0.0);
    }

    #[test]
    fn holds_the_brake_at_standstill_close_to_an_obstacle() {
        assert_eq!(act(0.0, &[[3.5, 0.1, 0.0]]).throttle, -1.0);
        // and drives off once the way is clear
        assert!(act(0.0, &[]).throttle > 0.0);
    }
}
