use serde::{Deserialize, Serialize};

use super::{Cruise, Sensors, Sut, SutError};
use crate::{CameraFrame, CameraSpec, Control, Observation};

/// Settings of the built-in [`Vision`] system.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct VisionConfig {
    /// The camera it reads. Default: 160 × 120 px, 24 mm, 20 Hz, pixel noise σ = 2 levels.
    pub camera: CameraSpec,
    /// Cruise control and the braking rule (as `aeb`'s).
    pub cruise: Cruise,
    /// Points at least this high above the road (m) are obstacles; lower ones are road.
    /// Default 0.3 m.
    pub obstacle_height_m: f64,
    /// Smallest colour difference (sum of |ΔR| + |ΔG| + |ΔB| in 8-bit levels) between a
    /// pixel and both the sky and the road for it to count as an object: about twice the pixel
    /// noise of the default camera. Default 10.
    pub contrast_threshold: f64,
    /// Object pixels needed in the corridor before braking. Default 6.
    pub min_obstacle_pixels: usize,
    /// Lane keeping: the look-ahead distance at which the lane centre is aimed for, metres.
    /// Default 10 m.
    pub lookahead_m: f64,
    /// Wheelbase for the pure-pursuit steering, metres. Default 2.9 m.
    pub wheelbase_m: f64,
    /// Front-wheel angle at full steering, rad. Default 0.5 rad.
    pub max_steer_rad: f64,
}

impl Default for VisionConfig {
    fn default() -> Self {
        VisionConfig {
            camera: CameraSpec {
                width: 160,
                height: 120,
                noise_sigma: 2.0,
                ..CameraSpec::default()
            },
            cruise: Cruise::default(),
            obstacle_height_m: 0.3,
            contrast_threshold: 10.0,
            min_obstacle_pixels: 6,
            lookahead_m: 10.0,
            wheelbase_m: 2.9,
            max_steer_rad: 0.5,
        }
    }
}

/// `vision`: lane keeping and emergency braking from the camera alone (image and depth map,
/// no lidar, no ground truth).
///
/// Each camera frame (20 Hz) it back-projects every pixel through the depth map into the
/// vehicle frame ([`CameraSpec::back_project`], [`CameraSpec::camera_to_vehicle`]), using the
/// chassis height from odometry to place the road plane, and then:
/// - **Objects.** A pixel is part of an object when it stands at least `obstacle_height_m`
///   above the road and its colour differs by at least `contrast_threshold` from both the sky
///   (the mean of the frame's sky pixels) and the road (the mean of the road just ahead). So it
///   sees what a camera shows: in fog an object fades toward the sky colour (Koschmieder) and
///   is found only when near; in the dark every difference shrinks with the exposure; in glare
///   bright surfaces and the sky both clip at 255. The gap to the nearest object in the
///   corridor (`min_obstacle_pixels` pixels at least) drives the same braking rule as `aeb`.
/// - **Lane.** Road pixels brighter than the road by `contrast_threshold` and by half the
///   road's own level (paint) between 4 and 16 m ahead are lane markings; the nearest marking on each side bounds the lane, and pure pursuit
///   (Coulter 1992) steers toward the lane centre `lookahead_m` ahead. With no marking seen it
///   holds the wheel straight.
///
/// Its exposure-dependent failures are the point: on `fog_light.star` it fails more the denser
/// the fog and the farther the light is from the 0.5 its camera is calibrated for.
#[derive(Debug, Clone)]
pub struct Vision {
    config: VisionConfig,
    last_frame_t: Option<f64>,
    decision: Control,
}

/// What one frame shows: the gap to the nearest object in the corridor, and the lane centre's
/// lateral offset (m, right positive) at the look-ahead distance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Perception {
    /// Distance from the chassis centre to the nearest object in the corridor, metres.
    pub obstacle_m: Option<f64>,
    /// Lane centre, metres to the right of the vehicle's axis.
    pub lane_centre_m: Option<f64>,
}

impl Vision {
    /// A `vision` system with the given settings.
    pub fn new(config: VisionConfig) -> Self {
        Vision {
            config,
            last_frame_t: None,
            decision: Control::default(),
        }
    }

    /// Reads one frame. `chassis_height_m` is the chassis centre's height above the road.
    pub fn perceive(&self, frame: &CameraFrame, chassis_height_m: f64) -> Perception {
        self.perceive_on_curve(frame, chassis_height_m, 0.0)
    }

    /// [`Vision::perceive`] on a road of curvature `curvature` (1/m, positive to the left)
    /// ahead: each marking's lateral position `y` at distance `x` is read as `y + κx²/2`, its
    /// offset from the arc through the vehicle, so the markings of a bend line up as on a
    /// straight road; [`Perception::lane_centre_m`] is then the lane centre's offset from that
    /// arc.
    pub fn perceive_on_curve(
        &self,
        frame: &CameraFrame,
        chassis_height_m: f64,
        curvature: f64,
    ) -> Perception {
        let c = &self.config;
        let diff = |a: [f64; 3], b: [f64; 3]| -> f64 { (0..3).map(|i| (a[i] - b[i]).abs()).sum() };
        let scan = self.scan_frame(frame, chassis_height_m);
        let mean = |(s, n): ([f64; 3], usize), fallback: [f64; 3]| {
            if n == 0 {
                fallback
            } else {
                s.map(|v| v / n as f64)
            }
        };
        let sky = mean(scan.sky, [255.0; 3]);
        let road = mean(scan.road, [60.0; 3]);
        let road_luma = road.iter().sum::<f64>() / 3.0;

        let (mut left, mut right) =
            paint_by_side(scan.markings, road_luma, c.contrast_threshold, curvature);
        let obstacle_m =
            nearest_visible_object(scan.candidates, c.min_obstacle_pixels.max(1), |mean| {
                diff(mean, sky) >= c.contrast_threshold && diff(mean, road) >= c.contrast_threshold
            });
        let half_lane = crate::network::LANE_WIDTH_M / 2.0;
        let lane_centre_m = match (
            nearest_line(&mut left, false),
            nearest_line(&mut right, true),
        ) {
            (Some(l), Some(r)) => Some((l + r) / 2.0),
            (Some(l), None) => Some(l + half_lane),
            (None, Some(r)) => Some(r - half_lane),
            (None, None) => None,
        };
        Perception {
            obstacle_m,
            lane_centre_m,
        }
    }

    /// One pass over the pixels of `frame`, back-projected with the chassis centre
    /// `chassis_height_m` (m) above the road: the sky (pixels with no depth), the road sample
    /// near the bottom centre of the image, the obstacle candidates (in the corridor, high
    /// enough), and the pixels where a marking may lie, whose brightness is judged once the
    /// road's level is known.
    fn scan_frame(&self, frame: &CameraFrame, chassis_height_m: f64) -> FrameScan {
        let c = &self.config;
        let cam = &c.camera;
        let (w, h) = (frame.width, frame.height);
        // Sky: the mean of pixels with no depth; road: the mean of road pixels near the bottom
        // centre of the image.
        let mut sky = ([0.0; 3], 0usize);
        let mut road = ([0.0; 3], 0usize);
        let project = cam.back_projector();
        // (The points of a whole frame, kept for a second pass, took 0.8 MB allocated afresh
        // every frame.)
        let mut candidates = Vec::new();
        let mut markings: Vec<(f64, f64, f64)> = Vec::new();
        for v in 0..h {
            for u in 0..w {
                let d = frame.depth_at(u, v);
                let rgb = frame.rgb_at(u, v);
                if !d.is_finite() {
                    accumulate(&mut sky, rgb);
                    continue;
                }
                let p = project.vehicle_point(f64::from(u) + 0.5, f64::from(v) + 0.5, f64::from(d));
                let height = p[1] + chassis_height_m;
                if height.abs() < 0.1 && p[2].abs() < 1.0 && (3.0..8.0).contains(&p[0]) {
                    accumulate(&mut road, rgb);
                }
                if p[0] <= 0.0 {
                    continue;
                }
                if height >= c.obstacle_height_m {
                    if p[2].abs() <= c.cruise.corridor_half_width_m {
                        candidates.push((p[0], rgb));
                    }
                } else if height.abs() < 0.1 && (4.0..16.0).contains(&p[0]) {
                    let luma = rgb.iter().map(|&v| f64::from(v)).sum::<f64>() / 3.0;
                    markings.push((p[0], p[2], luma));
                }
            }
        }
        FrameScan {
            sky,
            road,
            candidates,
            markings,
        }
    }

    fn decide(&self, frame: &CameraFrame, obs: &Observation<'_>) -> Control {
        let c = &self.config;
        // The route's curvature ahead (0 without a route): where the lane bends.
        let kappa = route_curvature(obs, c.lookahead_m);
        let seen = self.perceive_on_curve(frame, obs.ego.pos_m[1], kappa);
        let throttle = c.cruise.throttle(
            obs.ego.speed_mps,
            obs.set_speed_mps.unwrap_or(c.cruise.target_speed_mps),
            seen.obstacle_m,
        );
        let steering = seen.lane_centre_m.map_or(0.0, |y| {
            // Pure pursuit: curvature 2y / L² toward the point (L, y); z (y) points right,
            // and positive steering turns left.
            // The lane centre `lookahead_m` ahead lies `y − κL²/2` to the right.
            let curvature = 2.0 * y / c.lookahead_m.powi(2) - kappa;
            -(c.wheelbase_m * curvature).atan() / c.max_steer_rad
        });
        Control { throttle, steering }.clamped()
    }
}

/// The mean curvature (1/m, positive to the left) of the observation's route over the
/// `ahead_m` metres after the route point nearest the vehicle: the heading change over that
/// stretch divided by its length. 0 without a route.
fn route_curvature(obs: &Observation<'_>, ahead_m: f64) -> f64 {
    let route = obs.route;
    if route.len() < 3 {
        return 0.0;
    }
    let (x, z) = (obs.ego.pos_m[0], obs.ego.pos_m[2]);
    let d2 = |p: [f64; 2]| (p[0] - x).powi(2) + (p[1] - z).powi(2);
    let i = (0..route.len() - 1)
        .min_by(|&a, &b| d2(route[a]).total_cmp(&d2(route[b])))
        .unwrap_or(0);
    let heading = |a: [f64; 2], b: [f64; 2]| (-(b[1] - a[1])).atan2(b[0] - a[0]);
    let h0 = heading(route[i], route[i + 1]);
    let mut walked = 0.0;
    let mut j = i + 1;
    while j + 1 < route.len() && walked < ahead_m {
        walked += (route[j][0] - route[j - 1][0]).hypot(route[j][1] - route[j - 1][1]);
        j += 1;
    }
    if walked <= 0.0 {
        return 0.0;
    }
    let h1 = heading(route[j - 1], route[j]);
    let turn =
        (h1 - h0 + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI;
    turn / walked
}

/// What one pass over a frame's pixels gathers ([`Vision::scan_frame`]).
struct FrameScan {
    /// Running `(sum, count)` of the sky's colours (pixels with no depth).
    sky: ([f64; 3], usize),
    /// Running `(sum, count)` of the colours of the road 3 to 8 m ahead, within 1 m of the
    /// axis.
    road: ([f64; 3], usize),
    /// `(forward distance m, rgb)` of the pixels standing above the road in the corridor.
    candidates: Vec<(f64, [u8; 3])>,
    /// `(forward m, lateral m, luma)` of the road pixels 4 to 16 m ahead.
    markings: Vec<(f64, f64, f64)>,
}

/// The lateral positions (m, right positive) of the paint among `markings` (`(forward m,
/// lateral m, luma)`): pixels brighter than the road's luma `road_luma` by `threshold` and
/// by half the road's level, each read as `y + κx²/2` on a road of curvature `curvature`
/// (1/m), split into the left (`-3..-0.3` m) and the right (`0.3..3` m) side.
fn paint_by_side(
    markings: Vec<(f64, f64, f64)>,
    road_luma: f64,
    threshold: f64,
    curvature: f64,
) -> (Vec<f64>, Vec<f64>) {
    let (mut left, mut right) = (Vec::new(), Vec::new());
    for (x, lateral, luma) in markings {
        if luma >= road_luma + threshold.max(0.5 * road_luma) {
            let y = lateral + curvature * x * x / 2.0;
            if (-3.0..-0.3).contains(&y) {
                left.push(y);
            } else if (0.3..3.0).contains(&y) {
                right.push(y);
            }
        }
    }
    (left, right)
}

/// The nearest line on one side (m): the median of the markings `xs` within 0.6 m of the
/// innermost one (the largest when not `inner_first`, the smallest when it is); `None` below
/// [`MIN_MARKING_PIXELS`]. Sorts `xs`.
fn nearest_line(xs: &mut [f64], inner_first: bool) -> Option<f64> {
    if xs.len() < MIN_MARKING_PIXELS {
        return None;
    }
    xs.sort_by(f64::total_cmp);
    if !inner_first {
        xs.reverse();
    }
    let edge = *xs.first()?;
    let band: Vec<f64> = xs
        .iter()
        .copied()
        .filter(|x| (x - edge).abs() < 0.6)
        .collect();
    Some(band[band.len() / 2])
}

/// Adds a pixel to a running `(sum, count)` of colours.
fn accumulate(acc: &mut ([f64; 3], usize), rgb: [u8; 3]) {
    for (sum, v) in acc.0.iter_mut().zip(rgb) {
        *sum += f64::from(v);
    }
    acc.1 += 1;
}

/// Paint pixels needed on one side before a lane line counts as seen.
const MIN_MARKING_PIXELS: usize = 8;

/// Depth of an object cluster along the view, metres: candidates within this of the
/// cluster's nearest point belong to it.
const CLUSTER_DEPTH_M: f64 = 1.5;

/// The distance of the nearest object whose mean colour `visible` accepts. `candidates` are
/// `(forward distance m, rgb)` of pixels standing above the road in the corridor; they are
/// grouped front to back into clusters [`CLUSTER_DEPTH_M`] deep, and a cluster of at least
/// `min_pixels` pixels is an object. Averaging over the cluster keeps pixel noise from making
/// an invisible object visible.
fn nearest_visible_object(
    mut candidates: Vec<(f64, [u8; 3])>,
    min_pixels: usize,
    visible: impl Fn([f64; 3]) -> bool,
) -> Option<f64> {
    candidates.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut start = 0;
    while start < candidates.len() {
        let near = candidates[start].0;
        let end = start
            + candidates[start..]
                .iter()
                .take_while(|(d, _)| *d < near + CLUSTER_DEPTH_M)
                .count();
        let cluster = &candidates[start..end];
        if cluster.len() >= min_pixels {
            let mut mean = [0.0; 3];
            for (_, rgb) in cluster {
                for i in 0..3 {
                    mean[i] += f64::from(rgb[i]) / cluster.len() as f64;
                }
            }
            if visible(mean) {
                // The min_pixels-th nearest point: robust to a stray pixel.
                return Some(cluster[min_pixels - 1].0);
            }
        }
        start = end;
    }
    None
}

impl Sut for Vision {
    fn sensors(&self) -> Sensors {
        Sensors {
            camera: Some(self.config.camera.clone()),
            control_hz: None,
            // The image and the depth map, all of them; never the labels.
            frame_use: crate::FrameUse {
                depth: true,
                labels: false,
                region: None,
            },
        }
    }

    fn reset(&mut self, _seed: u64) -> Result<(), SutError> {
        self.last_frame_t = None;
        self.decision = Control::default();
        Ok(())
    }

    fn act(&mut self, obs: &Observation<'_>) -> Result<Control, SutError> {
        let frame = obs.camera().ok_or_else(|| {
            SutError::Failed("vision needs camera frames but the observation has none".into())
        })?;
        // Decide once per frame; hold the decision between frames.
        if self.last_frame_t != Some(frame.t_s) {
            self.last_frame_t = Some(frame.t_s);
            self.decision = self.decide(frame, obs);
        }
        Ok(self.decision)
    }
}
