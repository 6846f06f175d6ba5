//! `LateralDistanceAction`: an entity kept at a lateral distance from another, as esmini's
//! `LatDistanceAction` keeps it: in the reference's frame by steering towards the line at the
//! distance beside it (a turn radius from the maximum acceleration), or in road coordinates
//! by its offset on its lane (at once, or at a lateral speed: a critically damped spring
//! within the maximum acceleration, or the maximum speed alone).

use super::super::*;
use std::f64::consts::PI;

/// The distance error under which a lateral distance that is not continuous ends, m
/// (esmini's `LATERAL_DISTANCE_THRESHOLD`).
pub(in crate::xosc::story) const LATERAL_REACHED_M: f64 = 0.01;

/// A tiny length or speed, kept off a limit so that a motion keeps its direction (esmini's
/// `SMALL_NUMBER`).
const SMALL: f64 = 1e-10;

/// How a kept lateral distance moves its entity, as esmini's `LatDistanceAction` moves it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(in crate::xosc::story) enum LatMode {
    /// In the reference's frame: its speed along a path that steers to the line beside the
    /// reference (no maximum acceleration: onto the line at once).
    Entity,
    /// In road coordinates, before its first step (it moves as it did).
    RoadStart,
    /// In road coordinates, its offset set to the distance each step.
    RoadRigid,
    /// In road coordinates, at a lateral speed within the constraints.
    RoadDynamic,
}

/// A `LateralDistanceAction` in progress on an entity.
#[derive(Debug, Clone, Copy)]
pub(in crate::xosc::story) struct LatKeep {
    /// The entity it keeps its distance from.
    pub(in crate::xosc::story) reference: usize,
    /// The distance asked, m, signed as esmini's: in the reference's frame, to its left when
    /// positive; in road coordinates, the reference's `t` less the entity's when both face
    /// along `s` (negative: the entity to its left).
    distance: f64,
    /// How it moves.
    mode: LatMode,
    /// Whether it holds the distance once reached.
    continuous: bool,
    /// Maximum lateral acceleration, m/s², and its rate, m/s³, and maximum lateral speed,
    /// m/s (each infinite when not constrained).
    max_acc: f64,
    max_acc_rate: f64,
    max_speed: f64,
    /// Its lateral speed (in the road's `t`) and acceleration in the last step.
    lat_vel: f64,
    acceleration: f64,
    /// Where it was at the end of the last step (its heading is taken from the move).
    old: [f64; 2],
    /// Its action.
    pub(in crate::xosc::story) action: usize,
}

/// What a kept lateral distance did in a step.
pub(in crate::xosc::story) enum LatStep {
    /// Nothing: the entity moves as it would.
    Idle,
    /// It put the entity here (its motion along its lane or heading is done).
    Moved(Pose, Option<LanePos>),
    /// It set the entity's place on its lane, facing `h` (rad); the entity then moves along
    /// its lane as it would.
    Offset(LanePos, f64),
}

impl Storyboard {
    /// Starts `LateralDistanceAction` `action` on entity `e` for action element `a`: the
    /// distance resolved as esmini's `LatDistanceAction::Start` resolves it (`any` is left; with
    /// `freespace` the half widths added), ending the lateral move it replaces.
    ///
    /// # Errors
    /// [`StoryError`] at the action for a distance in road coordinates of an entity on no lane.
    pub(in crate::xosc::story) fn start_lat_keep(
        &mut self,
        e: usize,
        action: &m::NamedAction,
        a: Option<usize>,
    ) -> Result<(), StoryError> {
        let m::Action::LateralDistance {
            entity,
            distance_m,
            freespace,
            continuous,
            displacement,
            frame,
            constraints,
        } = &action.action
        else {
            return Ok(());
        };
        let right = displacement == "rightToReferencedEntity";
        let widths = (self.actors[e].size_m[1] + self.actors[*entity].size_m[1]) / 2.0;
        let road = frame == "road";
        let st = self.actors[e].state;
        if road && st.lane.is_none() {
            return Err(StoryError {
                at: site(&action.pos),
                message: format!(
                    "a lateral distance in road coordinates for {}, which is not on a lane",
                    self.actors[e].name
                ),
            });
        }
        // The distance kept when none is given: as it is now.
        let now = || {
            if road {
                let (la, lb) = (st.lane, self.actors[*entity].state.lane);
                la.zip(lb)
                    .and_then(|(la, lb)| self.road_offsets(la, lb))
                    .map_or(0.0, |(_, lat)| lat)
            } else {
                let r = self.actors[*entity].state.pose;
                -(st.pose.x - r.x) * r.h.sin() + (st.pose.y - r.y) * r.h.cos()
            }
        };
        let distance = match distance_m {
            None => now(),
            Some(d) if road => {
                let side = if right { 1.0 } else { -1.0 };
                side * (d.abs() + if *freespace { widths } else { 0.0 })
            }
            Some(d) => {
                let d = d + if *freespace { widths } else { 0.0 };
                if right {
                    -d
                } else {
                    d
                }
            }
        };
        let c = constraints.unwrap_or_default();
        let keep = LatKeep {
            reference: *entity,
            distance,
            mode: if road {
                LatMode::RoadStart
            } else {
                LatMode::Entity
            },
            continuous: *continuous,
            max_acc: c.max_acceleration_mps2.unwrap_or(f64::INFINITY),
            max_acc_rate: c.max_acceleration_rate_mps3.unwrap_or(f64::INFINITY),
            max_speed: c.max_speed_mps.unwrap_or(f64::INFINITY),
            lat_vel: 0.0,
            acceleration: 0.0,
            old: [st.pose.x, st.pose.y],
            action: a.unwrap_or(usize::MAX),
        };
        let old = [
            self.drives[e].lat_keep.take().map(|k| k.action),
            self.drives[e].lateral.take().map(|l| l.action),
        ];
        for o in old {
            self.override_task(o);
        }
        if let Some(a) = a {
            self.elems[a].pending += 1;
        }
        self.drives[e].lat_keep = Some(keep);
        Ok(())
    }

    /// The error of entity `e`'s lateral distance from `reference` in road coordinates, m
    /// along the road's `t` (esmini's `GetDistanceError`: positive when `e` must move to
    /// larger `t`), for the distance `distance` (signed as [`LatKeep`]'s); `None` when either
    /// is on no lane or no lanes lead between them.
    fn lateral_error(&self, e: usize, reference: usize, distance: f64) -> Option<f64> {
        let (la, lb) = (
            self.actors[e].state.lane?,
            self.actors[reference].state.lane?,
        );
        // `lat` is the reference's `t` less `e`'s, times `dir` (1 along `s`, -1 against):
        // esmini's error is `-(dt + distance)` along `s` and `-(dt - distance)` against it,
        // `dt` being `e`'s `t` less the reference's.
        let (_, lat) = self.road_offsets(la, lb)?;
        let dir = if la.along_s(&self.roads) { 1.0 } else { -1.0 };
        Some(dir * (lat - distance))
    }

    /// One step of `dt` s of entity `e`'s kept lateral distance, at its speed `v` (m/s) after
    /// this step's speed change: what it did, and its action when it ended.
    pub(in crate::xosc::story) fn lat_keep_step(
        &mut self,
        e: usize,
        v: f64,
        dt: f64,
    ) -> (LatStep, Option<usize>) {
        let Some(mut k) = self.drives[e].lat_keep else {
            return (LatStep::Idle, None);
        };
        let (step, ended) = match k.mode {
            LatMode::Entity => (self.lat_entity(e, &k, v, dt), false),
            LatMode::RoadStart => {
                let c = k.max_acc.is_finite() || k.max_speed.is_finite();
                k.mode = if c {
                    LatMode::RoadDynamic
                } else {
                    LatMode::RoadRigid
                };
                let p = self.actors[e].state.pose;
                k.old = [p.x, p.y];
                (LatStep::Idle, false)
            }
            LatMode::RoadRigid => self.lat_rigid(e, &mut k),
            LatMode::RoadDynamic => self.lat_dynamic(e, &mut k, v, dt),
        };
        if ended {
            self.drives[e].lat_keep = None;
            return (step, Some(k.action));
        }
        self.drives[e].lat_keep = Some(k);
        (step, None)
    }

    /// [`LatMode::Entity`]: towards the line `k.distance` m beside the reference (esmini's
    /// `LatDistanceAction::Step` in the entity's coordinate system).
    fn lat_entity(&self, e: usize, k: &LatKeep, v: f64, dt: f64) -> LatStep {
        let p = self.actors[e].state.pose;
        let r = self.actors[k.reference].state.pose;
        let axis = [r.h.cos(), r.h.sin()];
        let base = [r.x - axis[1] * k.distance, r.y + axis[0] * k.distance];
        // The foot of `e` on the line through `base` along `axis`.
        let along = (p.x - base[0]) * axis[0] + (p.y - base[1]) * axis[1];
        let target = [base[0] + axis[0] * along, base[1] + axis[1] * along];
        let delta = [target[0] - p.x, target[1] - p.y];
        let dist = delta[0].hypot(delta[1]);
        let step_len = v * dt;
        let at = |x: f64, y: f64, h: f64| {
            let pose = Pose { x, y, h: wrap(h) };
            LatStep::Moved(pose, self.facing(self.roads.anchor(x, y), pose.h))
        };
        if !k.max_acc.is_finite() {
            // At once onto the line, and on along it by what of the step remains.
            let rest = (step_len.abs() - dist).max(0.0);
            return at(target[0] + axis[0] * rest, target[1] + axis[1] * rest, r.h);
        }
        if dist < SMALL {
            return at(p.x + axis[0] * step_len, p.y + axis[1] * step_len, r.h);
        }
        let turn_radius = (1.5 * v * v / k.max_acc.min(1000.0)).max(0.5);
        let dh_max = ((v / turn_radius * dt).abs() * 1.5).min(PI - SMALL);
        if dist < step_len / 2.0 - SMALL && step_len / 2.0 > turn_radius - SMALL {
            // Close: straight onto the line, at the point a step away most along the
            // reference's heading.
            let (i0, i1) = line_circle([base, axis], [p.x, p.y], step_len);
            let h0 = (i0[1] - p.y).atan2(i0[0] - p.x);
            let h1 = (i1[1] - p.y).atan2(i1[0] - p.x);
            let (pt, h) = if wrap(h0 - r.h).abs() < wrap(h1 - r.h).abs() {
                (i0, h0)
            } else {
                (i1, h1)
            };
            return at(pt[0], pt[1], h);
        }
        let limit = |x: f64| x.clamp(-dh_max, dh_max);
        let dh = if dist > turn_radius - SMALL {
            // Far: head for the aiming point, turning no faster than the radius allows.
            limit(wrap(delta[1].atan2(delta[0]) - p.h))
        } else {
            // Within the radius: blend heading for the point and the reference's heading.
            let h_delta = wrap(delta[1].atan2(delta[0]) - p.h);
            let h_heading = wrap(r.h - p.h);
            let d_angle = step_len / turn_radius;
            let angle = (1.0 - dist / turn_radius).acos().max(d_angle / 2.0);
            let w = (2.0 * angle - d_angle / 2.0) / PI;
            let w = 3.0 * w * w - 2.0 * w * w * w;
            limit(w * h_delta + (1.0 - w) * h_heading)
        };
        let h = p.h + dh;
        at(p.x + h.cos() * step_len, p.y + h.sin() * step_len, h)
    }

    /// [`LatMode::RoadRigid`]: its offset on its lane set to the distance, facing the way it
    /// moved since the last step; the action ends once within [`LATERAL_REACHED_M`] unless
    /// it is continuous.
    fn lat_rigid(&mut self, e: usize, k: &mut LatKeep) -> (LatStep, bool) {
        let Some(error) = self.lateral_error(e, k.reference, k.distance) else {
            return (LatStep::Idle, true);
        };
        let Some(mut lp) = self.actors[e].state.lane else {
            return (LatStep::Idle, true);
        };
        lp.d += error;
        let p = self.roads.pose_of(&lp);
        let h = (p.y - k.old[1]).atan2(p.x - k.old[0]);
        k.old = [p.x, p.y];
        let ended = !k.continuous && error.abs() < LATERAL_REACHED_M;
        (LatStep::Offset(lp, h), ended)
    }

    /// [`LatMode::RoadDynamic`]: at a lateral speed towards the distance (a critically damped
    /// spring of stiffness `0.4·maxAcceleration` within the maximum acceleration, its rate and
    /// the maximum speed; or, without a maximum acceleration, at the maximum speed), along its
    /// lane at what of its speed remains, facing the way it moved.
    fn lat_dynamic(&mut self, e: usize, k: &mut LatKeep, v: f64, dt: f64) -> (LatStep, bool) {
        let Some(error) = self.lateral_error(e, k.reference, k.distance) else {
            return (LatStep::Idle, true);
        };
        let Some(lp) = self.actors[e].state.lane else {
            return (LatStep::Idle, true);
        };
        let cap = k.max_speed.min(v.abs()) - SMALL;
        let mut ended = false;
        let d_offset = if k.max_acc.is_finite() {
            let stiffness = 0.4 * k.max_acc;
            let v_ref = self.lateral_speed(k.reference);
            let a = stiffness * error - 2.0 * stiffness.sqrt() * (k.lat_vel - v_ref);
            let jerk = k.max_acc_rate * dt;
            let delta = (a - k.acceleration).clamp(-jerk, jerk);
            k.acceleration = (k.acceleration + delta).clamp(-k.max_acc, k.max_acc);
            k.lat_vel = (k.lat_vel + k.acceleration * dt).clamp(-cap.abs(), cap.abs());
            ended = !k.continuous && error.abs() < LATERAL_REACHED_M;
            k.lat_vel * dt
        } else {
            k.lat_vel = error.signum() * cap;
            let mut d = k.lat_vel * dt;
            if (error - d).signum() != error.signum() {
                d = error;
                k.lat_vel = d / dt;
                ended = !k.continuous;
            }
            d
        };
        let long = (v * v - k.lat_vel * k.lat_vel).max(0.0).sqrt() * v.signum();
        let (_, mut moved, _, _) =
            self.drive_on_lane(e, lp, (long * dt, dt, self.actors[e].state.pose.h));
        moved.d += d_offset;
        let mut pose = self.roads.pose_of(&moved);
        pose.h = (pose.y - k.old[1]).atan2(pose.x - k.old[0]);
        k.old = [pose.x, pose.y];
        (LatStep::Moved(pose, Some(moved)), ended)
    }

    /// Entity `e`'s velocity across its own heading (to its left), m/s, as esmini's
    /// `Position::GetVelLat` gives it.
    fn lateral_speed(&self, e: usize) -> f64 {
        let st = &self.actors[e].state;
        let h = st.pose.h;
        -st.vel[0] * h.sin() + st.vel[1] * h.cos()
    }
}

/// The two points where the line through `line[0]` along the unit vector `line[1]` meets the
/// circle of radius `r` about `c` (the foot of `c` twice when they do not meet).
fn line_circle(line: [[f64; 2]; 2], c: [f64; 2], r: f64) -> ([f64; 2], [f64; 2]) {
    let [p, u] = line;
    let t0 = (c[0] - p[0]) * u[0] + (c[1] - p[1]) * u[1];
    let foot = [p[0] + u[0] * t0, p[1] + u[1] * t0];
    let d2 = (c[0] - foot[0]).powi(2) + (c[1] - foot[1]).powi(2);
    let half = (r * r - d2).max(0.0).sqrt();
    (
        [foot[0] - u[0] * half, foot[1] - u[1] * half],
        [foot[0] + u[0] * half, foot[1] + u[1] * half],
    )
}
