//! `SynchronizeAction`: a scripted entity's speed set each step so that it reaches its target
//! when its master reaches the master's, as esmini's `SynchronizeAction::Step` sets it
//! (esmini `OSCPrivateAction.cpp`, its speed profiles described there: linear, convex or
//! concave in two phases, or a stop and a restart, with an optional steady state).

use paracosm_openscenario::model::{FinalSpeed, SteadyState, Synchronize};

use super::super::*;

/// esmini's `SMALL_NUMBER`.
const SMALL: f64 = 1e-6;
/// esmini's `LARGE_NUMBER`: the master's time to its target while it stands still, s.
const LARGE: f64 = 1e10;
/// esmini's `MAX_DECELERATION`, m/s²: the braking of a synchronized entity that must stop
/// at once.
const MAX_DECELERATION_MPS2: f64 = -8.0;

/// A place resolved when the action starts: its pose and its places on the lanes: the lane a
/// lane, road or route position names, or, for a position in the world's coordinates, each
/// lane under it (where a junction's connecting roads overlap, each of them).
type Place = (Pose, Vec<LanePos>);

/// The phase of a synchronization (esmini's `SynchMode`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Mode {
    None,
    NonLinear,
    Linear,
    Stopped,
    StopImmediately,
    Waiting,
    SteadyState,
}

/// Whether the speed profile first rises (convex) or first falls (concave).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Bend {
    None,
    Concave,
    Convex,
}

/// A `SynchronizeAction` in progress on one scripted entity.
#[derive(Debug, Clone)]
pub(in crate::xosc::story) struct Synchronizing {
    master: usize,
    master_target: Place,
    target: Place,
    master_tolerance_m: f64,
    tolerance_m: f64,
    final_speed: Option<FinalSpeed>,
    /// The steady state's distance, m (a time is its distance at the final speed when the
    /// action starts).
    steady_m: Option<f64>,
    mode: Mode,
    bend: Bend,
    /// The distances to the targets at the last step, m (the entity's, the master's).
    last: (f64, f64),
    /// Its action (`usize::MAX` in `Init`).
    pub(in crate::xosc::story) action: usize,
}

impl Storyboard {
    /// Starts a `SynchronizeAction` (written at `at`) on scripted entity `e` for action `a`:
    /// both target positions are resolved now, and the entity's longitudinal tasks (a
    /// `SpeedAction`, a kept distance) end, since it takes over their domain.
    ///
    /// # Errors
    /// [`StoryError`] for a target position off the map.
    pub(in crate::xosc::story) fn start_sync(
        &mut self,
        e: usize,
        s: &Synchronize,
        a: Option<usize>,
        at: &paracosm_openscenario::Pos,
    ) -> Result<(), StoryError> {
        let master_target = self.place(&self.within_road(&s.master_target).0, at)?;
        let target = self.place(&self.within_road(&s.target).0, at)?;
        let mut sync = Synchronizing {
            master: s.master,
            master_target,
            target,
            master_tolerance_m: s.master_tolerance_m,
            tolerance_m: s.tolerance_m,
            final_speed: s.final_speed,
            steady_m: None,
            mode: Mode::None,
            bend: Bend::None,
            last: (LARGE, LARGE),
            action: a.unwrap_or(usize::MAX),
        };
        sync.steady_m = s.final_speed.and_then(|f| {
            f.steady.map(|st| match st {
                SteadyState::Distance(d) => d,
                SteadyState::Time(t) => t * self.final_speed(&sync).unwrap_or(0.0).max(0.0),
            })
        });
        self.end_longitudinal(e);
        if let Some(a) = a {
            self.elems[a].pending += 1;
        }
        self.drives[e].sync = Some(sync);
        Ok(())
    }

    /// `p`, a lane or road position beyond its road's end (or before its start), taken at
    /// the end (the start), as esmini's `Position::SetLanePos` takes it, with the station
    /// asked and the one taken (m); any other position as it is.
    pub(in crate::xosc::story) fn within_road(
        &self,
        p: &Position,
    ) -> (Position, Option<(f64, f64)>) {
        let (road, s) = match p {
            Position::Lane { road, s, .. } | Position::Road { road, s, .. } => (road, *s),
            _ => return (p.clone(), None),
        };
        let Some(r) = self.roads.map().roads.iter().find(|r| &r.od_id == road) else {
            return (p.clone(), None);
        };
        let within = s.clamp(0.0, r.length_m);
        if within == s {
            return (p.clone(), None);
        }
        let mut q = p.clone();
        if let Position::Lane { s, .. } | Position::Road { s, .. } = &mut q {
            *s = within;
        }
        (q, Some((s, within)))
    }

    /// Where `p` (written at `at`) is now: its pose and its lanes ([`Place`]), facing its
    /// heading.
    ///
    /// # Errors
    /// [`StoryError`] for a position off the map.
    fn place(&self, p: &Position, at: &paracosm_openscenario::Pos) -> Result<Place, StoryError> {
        let (pose, lp) = self.resolve(p, at)?;
        let mut lanes: Vec<LanePos> = lp.into_iter().collect();
        let in_the_world = matches!(
            p,
            Position::World { .. }
                | Position::RelativeWorld { .. }
                | Position::RelativeObject { .. }
        );
        if !in_the_world {
            return Ok((pose, lanes));
        }
        for other in self.roads.anchors(pose.x, pose.y) {
            if lanes.iter().all(|l| l.lane != other.lane) {
                lanes.push(self.roads.facing(other, pose.h));
            }
        }
        Ok((pose, lanes))
    }

    /// The final speed asked now, m/s: absolute, or the master's speed now plus or times the
    /// value.
    fn final_speed(&self, s: &Synchronizing) -> Option<f64> {
        let f = s.final_speed?;
        let vm = self.actors[s.master].state.speed;
        Some(match f.relative {
            None => f.value,
            Some(true) => vm * f.value,
            Some(false) => vm + f.value,
        })
    }

    /// The speed of entity `e` along its road's `s` axis, m/s, unsigned: its velocity over
    /// the last step ([`State::vel`]) projected on the road's heading (esmini's `GetVelS`);
    /// off the lanes the velocity's length; 0 when every entity is `still`. An entity put
    /// back by the start of a trajectory has a small velocity for that step, as in esmini.
    fn speed_along_road(&self, e: usize, still: bool) -> f64 {
        let st = &self.actors[e].state;
        if still {
            return 0.0;
        }
        match st.lane {
            Some(lp) => {
                let h = self.roads.along_heading(&lp);
                (st.vel[0] * h.cos() + st.vel[1] * h.sin()).abs()
            }
            None => st.vel[0].hypot(st.vel[1]),
        }
    }

    /// How far entity `e` is from `place`, m (unsigned), and whether the place is ahead
    /// (`1.0`) or behind (`-1.0`): along the trajectory it follows, else along the lanes to
    /// the nearest of the place's lanes ([`Storyboard::road_offsets`]; where connecting roads
    /// overlap, the one its lanes lead to), else in a straight line (esmini's fallback when
    /// no road leads there).
    fn distance_to_place(&self, e: usize, place: &Place) -> (f64, f64) {
        let st = &self.actors[e].state;
        let sign = |d: f64| if d < 0.0 { -1.0 } else { 1.0 };
        if let Some((Path::Untimed(u), _)) = &self.drives[e].path {
            let d = u.station_of([place.0.x, place.0.y]) - u.gone_m;
            return (d.abs(), sign(d));
        }
        if let Some(la) = st.lane {
            let nearest = place
                .1
                .iter()
                .filter_map(|lb| self.road_offsets(la, *lb))
                .map(|(long, _)| long)
                .min_by(|a, b| a.abs().total_cmp(&b.abs()));
            if let Some(long) = nearest {
                return (long.abs(), sign(long));
            }
        }
        let (dx, dy) = (place.0.x - st.pose.x, place.0.y - st.pose.y);
        let forward = wrap(dy.atan2(dx) - st.pose.h).abs() < std::f64::consts::FRAC_PI_2;
        (dx.hypot(dy), if forward { 1.0 } else { -1.0 })
    }

    /// Sets the speed of every scripted entity that synchronizes for the step of `dt` s
    /// about to be moved, and ends the synchronizations that arrived (esmini's
    /// `SynchronizeAction::Step`, run before the entities move). In the storyboard's `first`
    /// step a synchronization is first stepped as esmini steps it in its initial frame: for
    /// no time, every entity without a velocity yet (so its master seems to stand still).
    pub(in crate::xosc::story) fn synchronize(&mut self, dt: f64, first: bool) {
        for e in 0..self.actors.len() {
            if !self.actors[e].scripted {
                continue;
            }
            let Some(mut s) = self.drives[e].sync.take() else {
                continue;
            };
            self.drives[e].speed_before = Some(self.actors[e].state.speed);
            if first && self.sync_step(e, &mut s, (0.0, true)) {
                self.task_done(Some(s.action).filter(|&a| a != usize::MAX));
                continue;
            }
            if self.sync_step(e, &mut s, (dt, false)) {
                self.task_done(Some(s.action).filter(|&a| a != usize::MAX));
            } else {
                self.drives[e].sync = Some(s);
            }
        }
    }

    /// One step of `s` on entity `e` of `dt` s (with every entity `still`, without a
    /// velocity, or not): its speed set; whether it arrived.
    fn sync_step(&mut self, e: usize, s: &mut Synchronizing, (dt, still): (f64, bool)) -> bool {
        let (master_dist, master_dir) = self.distance_to_place(s.master, &s.master_target);
        let (dist, _) = self.distance_to_place(e, &s.target);
        // Arrived, or passed (a distance that grows).
        let mut done = dist < s.tolerance_m + SMALL
            || master_dist < s.master_tolerance_m + SMALL
            || dist > s.last.0
            || master_dist > s.last.1;
        s.last = (dist, master_dist);
        let mut dist = (dist - s.tolerance_m).max(SMALL);
        let master_dist = (master_dist - s.master_tolerance_m).max(SMALL);
        let vm = self.actors[s.master].state.speed;
        let master_speed = vm.signum() * master_dir * self.speed_along_road(s.master, still);
        let mut time_left = LARGE;
        if master_speed > SMALL {
            time_left = master_dist / master_speed;
            done |= time_left < dt;
        } else if s.mode != Mode::Waiting {
            // The master stands still: so does the entity.
            s.mode = Mode::Waiting;
            self.actors[e].state.speed = 0.0;
        }
        let final_v = self.final_speed(s);
        if done {
            if let Some(v) = final_v {
                self.actors[e].state.speed = v;
            }
            return true;
        }
        let v = self.actors[e].state.speed;
        let Some(v1) = final_v else {
            // No final speed: a constant acceleration to arrive in time.
            if master_speed > SMALL {
                s.mode = Mode::Linear;
                let end_v = 2.0 * dist / time_left - v;
                self.actors[e].state.speed = v + (end_v - v) / time_left * dt;
            }
            return false;
        };
        // A final speed relative to the master's may come to 0 or less: no steady state then
        // (no time at it reaches the target).
        let steady_m = s.steady_m.filter(|_| v1 > SMALL);
        if let (Some(steady_m), false) = (steady_m, s.mode == Mode::SteadyState) {
            let steady_s = steady_m / v1;
            if dist - steady_m < SMALL || time_left - steady_s < SMALL {
                s.mode = Mode::SteadyState;
                s.bend = Bend::None;
            } else {
                dist -= steady_m;
                time_left -= steady_s;
            }
        }
        let v0 = v.signum() * self.speed_along_road(e, still);
        if let Some(speed) = profile(s, (dist, time_left), (v, v0, v1), dt) {
            self.actors[e].state.speed = speed;
        }
        false
    }
}

/// esmini's speed profile for one step (its modes and the two-phase solution of its
/// quadratic): the entity's new speed, m/s, or `None` to keep it. `dist` (m) and
/// `time_left` (s) are to the target (less the steady state), `v` its speed, `v0` its speed
/// along the road, `v1` the final speed, m/s.
fn profile(
    s: &mut Synchronizing,
    (dist, time_left): (f64, f64),
    (v, v0, v1): (f64, f64, f64),
    dt: f64,
) -> Option<f64> {
    match s.mode {
        Mode::SteadyState => return Some(v1),
        Mode::Waiting if time_left >= LARGE => return None,
        Mode::Waiting => s.mode = Mode::None,
        Mode::StopImmediately => {
            let next = v + MAX_DECELERATION_MPS2 * dt;
            if next < 0.0 {
                s.mode = Mode::Waiting;
                return Some(0.0);
            }
            return Some(next);
        }
        Mode::Stopped if time_left < 2.0 * dist / v1 => s.mode = Mode::Linear,
        Mode::Stopped => return Some(0.0),
        _ => {}
    }
    if s.mode == Mode::Linear {
        if time_left > LARGE - 1.0 {
            return Some(0.0);
        }
        return Some(linear_start_speed(v1.max(0.0), time_left, dist).max(0.0));
    }
    if s.mode == Mode::NonLinear && time_left < LARGE {
        // On the straight line of a linear profile: past the apex.
        if (v - (2.0 * dist / time_left - v1)).abs() < 0.1 {
            s.mode = Mode::Linear;
            return None;
        }
    }
    if s.mode == Mode::None {
        s.mode = Mode::NonLinear;
        s.bend = if (v1 + v) / 2.0 < dist / time_left {
            Bend::Convex
        } else {
            Bend::Concave
        };
    }
    let (vx, mut acc) = two_phases(dist, time_left, v0, v1);
    if s.mode == Mode::NonLinear
        && ((s.bend == Bend::Concave && acc > 0.0) || (s.bend == Bend::Convex && acc < 0.0))
    {
        // The apex: the last phase is linear.
        s.mode = Mode::Linear;
        acc = 0.0;
    }
    if s.mode == Mode::NonLinear && vx < 0.0 {
        // Slower than standing still would be needed: brake to a stop, wait, restart.
        let t1 = 2.0 * v0 * dist / (v0 * v0 + v1 * v1);
        acc = if t1.abs() > SMALL { -v0 / t1 } else { 0.0 };
        if t1 * v0 / 2.0 > dist / 2.0 {
            acc = MAX_DECELERATION_MPS2;
            s.mode = Mode::StopImmediately;
        }
        if v0 + acc * dt < 0.0 {
            s.mode = Mode::Stopped;
            return Some(0.0);
        }
    }
    Some(v + acc * dt)
}

/// The speed now that reaches `v_final` (m/s) after `time` s over `dist` m at a constant
/// acceleration (esmini's `CalcSpeedForLinearProfile`); 0 for a time or distance under 1 mm
/// or 1 ms.
fn linear_start_speed(v_final: f64, time: f64, dist: f64) -> f64 {
    if time < 0.001 || dist < 0.001 {
        return 0.0;
    }
    2.0 * dist / time - v_final
}

/// The two-phase profile over `s` m in `t` s from `v0` to `v1` (m/s): the speed at the turn
/// (m/s) and the first phase's acceleration (m/s²); `(0, 0)` when no turn lies within the
/// time.
fn two_phases(s: f64, t: f64, v0: f64, v1: f64) -> (f64, f64) {
    if (v1 - v0).abs() < SMALL {
        let vx = (s - (t / 2.0) * v0) / (t / 2.0);
        return (vx, (vx - v0) / (t / 2.0));
    }
    let root =
        2f64.sqrt() * (2.0 * s * s - 2.0 * (v1 + v0) * t * s + (v1 * v1 + v0 * v0) * t * t).sqrt();
    let x1 = -(root + 2.0 * s - 2.0 * v1 * t) / (2.0 * (v1 - v0));
    let x2 = -(-root + 2.0 * s - 2.0 * v1 * t) / (2.0 * (v1 - v0));
    if x1 > 0.0 && x1 < t {
        let vx = (2.0 * s - root) / (2.0 * t);
        (vx, (vx - v0) / x1)
    } else if x2 > 0.0 && x2 < t {
        let vx = (2.0 * s + root) / (2.0 * t);
        (vx, (vx - v0) / x2)
    } else {
        (0.0, 0.0)
    }
}
