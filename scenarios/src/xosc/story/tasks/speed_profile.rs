//! `SpeedProfileAction` (OpenSCENARIO 1.2): an entity's speed through a sequence of speeds
//! over time, planned when the action starts as esmini's `LongSpeedProfileAction::Start`
//! plans it: the entries become vertices of a piecewise linear speed over time (entries on
//! one line merged, an entry too steep for the constraints' acceleration moved later), and
//! the vertices segments of constant jerk (`followingMode="follow"`: each corner rounded at
//! the constraints' maximum rate of acceleration) or of constant acceleration (`position`).

use super::super::*;

/// esmini's `SMALL_NUMBER`: speeds, times and slopes closer than this are equal.
const SMALL: f64 = 1e-6;

/// esmini's `LARGE_NUMBER`, a constraint the action leaves out: unbounded, kept finite so
/// that the planning's divisions stay finite.
const UNBOUNDED: f64 = 1e10;

/// How long past its last segment a profile is still stepped, s (esmini's
/// `LongSpeedProfileAction::Step`): its speed then stays.
const STEPPED_PAST_S: f64 = 10.0;

/// A profile's constraints: acceleration and deceleration (m/s², magnitudes), their rates
/// (m/s³, magnitudes) and the speed (m/s).
#[derive(Debug, Clone, Copy)]
struct Limits {
    acc: f64,
    dec: f64,
    acc_rate: f64,
    dec_rate: f64,
    speed: f64,
}

/// A vertex of the piecewise linear profile: at time `t` (s) the speed `v` (m/s), the slope
/// `k` (m/s²) of the line leaving it and that line's intercept `m` (m/s, `v − k·t`).
#[derive(Debug, Clone, Copy)]
struct Vertex {
    t: f64,
    v: f64,
    k: f64,
    m: f64,
}

impl Vertex {
    /// A vertex whose slope is not known yet (slope and intercept 0, as esmini's).
    fn at(t: f64, v: f64) -> Vertex {
        Vertex {
            t,
            v,
            k: 0.0,
            m: 0.0,
        }
    }

    /// A vertex with its slope.
    fn sloped(t: f64, v: f64, k: f64) -> Vertex {
        Vertex {
            t,
            v,
            k,
            m: v - k * t,
        }
    }

    fn set_k(&mut self, k: f64) {
        self.k = k;
        self.m = self.v - k * self.t;
    }
}

/// A segment of the planned speed: from time `t` (s) the speed is
/// `v + k·(τ − t) + j·(τ − t)²/2` (m/s, m/s², m/s³).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(in crate::xosc::story) struct Segment {
    t: f64,
    v: f64,
    k: f64,
    j: f64,
}

/// A `SpeedProfileAction` in progress: its segments, the one it is in and its speed.
#[derive(Debug, Clone, Default)]
pub(in crate::xosc::story) struct Profile {
    segments: Vec<Segment>,
    /// How many entries the action has (its end is tested against it, as esmini's is).
    entries: usize,
    current: usize,
    speed: f64,
}

/// The segments' builder: it falls back from `follow` to `position` when a segment breaks
/// the constraints (esmini's `CheckSpeed`, `CheckAcceleration`, `CheckAccelerationRate`),
/// the segment still added.
struct Plan {
    segments: Vec<Segment>,
    follow: bool,
    lim: Limits,
}

impl Plan {
    fn add(&mut self, t: f64, v: f64, k: f64, j: f64) {
        let l = self.lim;
        if self.follow
            && (v.abs() > l.speed + SMALL
                || k > l.acc + SMALL
                || k < -l.dec - SMALL
                || j > l.acc_rate + SMALL
                || j < -l.dec_rate - SMALL)
        {
            self.follow = false;
        }
        self.segments.push(Segment { t, v, k, j });
    }
}

/// The profile's vertices from `entries` (time s or `None`, speed m/s, each speed plus
/// `offset` m/s), starting at `t0` (s) at speed `v0` (m/s) and acceleration `a0` (m/s²).
fn vertices(
    entries: &[(Option<f64>, f64)],
    (offset, t0, v0, a0): (f64, f64, f64, f64),
    follow: bool,
    lim: Limits,
) -> Vec<Vertex> {
    let n = entries.len();
    let mut vx = Vec::with_capacity(n + 1);
    let mut index = 0;
    match entries[0].0 {
        Some(t) if t > SMALL => vx.push(Vertex::at(t0, v0)),
        // The first entry now: in follow mode the current speed stands for it; in position
        // mode its speed is taken at once.
        Some(_) if follow => {
            vx.push(Vertex::at(t0, v0));
            index = 1;
        }
        Some(_) => vx.push(Vertex::at(t0, entries[0].1 + offset)),
        None => vx.push(Vertex::at(t0, v0)),
    }
    let mut time = t0;
    while index < n {
        let (given, speed) = entries[index];
        let target = speed + offset;
        let dt = given.unwrap_or(-1.0);
        let last = vx[vx.len() - 1];
        let mut k = (target - last.v) / dt;
        if given.is_none() || k < -lim.dec || k > lim.acc {
            let dv = target - last.v;
            if dv.abs() < SMALL {
                index += 1;
                continue;
            }
            k = match given {
                // No time: reached at the constraints' acceleration.
                None if dv < 0.0 => (-lim.dec).min(-SMALL),
                None => lim.acc.max(SMALL),
                // Too steep: at the constraints' acceleration, later.
                Some(_) if k < 0.0 => k.max(-lim.dec),
                Some(_) => k.min(lim.acc),
            };
            let l = vx.len() - 1;
            vx[l].t = time;
            time += dv / k;
        } else {
            time += dt;
        }
        let l = vx.len() - 1;
        if index < n - 1 && given.is_some_and(|t| t < SMALL) {
            // An entry at no time after the one before replaces it. (esmini's test here is
            // on the time as it reads it, -1 for one left out, so that it drops the vertex
            // before an entry without a time: a jump to that entry's speed. paracosm reaches
            // such an entry at the constraints' acceleration, as the standard says.)
            vx[l] = Vertex::at(time, target);
            index += 1;
            continue;
        }
        vx[l].set_k(if k.is_nan() { 0.0 } else { k });
        let second = (index > 1 && l >= 1).then(|| vx[l - 1]);
        let dk = match second {
            Some(s) => vx[l].k - s.k,
            None => vx[l].k - a0,
        };
        if let Some(s) = second.filter(|_| dk.abs() < SMALL) {
            // On the line of the vertex before: one line from that vertex's.
            let k = (target - s.v) / (time - s.t);
            vx[l] = Vertex::sloped(time, target, k);
            index += 1;
            continue;
        }
        vx.push(if index == n - 1 {
            Vertex::sloped(time, target, 0.0)
        } else {
            Vertex::at(time, target)
        });
        index += 1;
    }
    vx
}

/// One target speed in follow mode (two vertices): a jerk from acceleration `k0` (m/s²)
/// towards the line to the target, a stretch of constant acceleration if there is time for
/// one, and a jerk back to none at the target (its time extended where the constraints do
/// not reach it in time).
fn single_target(plan: &mut Plan, vx: &[Vertex], k0: f64) {
    let lim = plan.lim;
    let j0 = if vx[0].k - k0 < 0.0 {
        -lim.dec_rate
    } else {
        lim.acc_rate
    };
    plan.add(vx[0].t, vx[0].v, k0, j0);
    let j1 = if vx[0].k < 0.0 {
        lim.acc_rate
    } else {
        -lim.dec_rate
    };
    let (t0, v0) = (vx[0].t, vx[0].v);
    let (mut t3, v3) = (vx[1].t, vx[1].v);
    let (mut k1, mut t2, mut v2) = (0.0, 0.0, 0.0);
    let within = |k: f64| k >= -lim.dec && k <= lim.acc;
    if (j1 - j0).abs() < SMALL {
        if (t0 - t3).abs() > SMALL && (j1 * (t0 - t3) - k0).abs() > SMALL {
            let t1 = (2.0 * j1 * (v0 + t0 * j1 * (t0 - t3) - v3)
                + k0 * k0
                + 2.0 * k0 * j1 * (t3 - 2.0 * t0))
                / (2.0 * j1 * (j1 * (t0 - t3) - k0));
            if t1 >= 0.0 {
                let v1 = v0 + k0 * (t1 - t0) + j0 * 0.5 * (t1 - t0).powi(2);
                k1 = k0 + j0 * (t1 - t0);
                t2 = k1 / j1 + t3;
                if t2 >= 0.0 {
                    v2 = v1 + k1 * (t2 - t1);
                    if k1 < lim.acc && k1 > -lim.dec {
                        plan.add(t1, v1, k1, 0.0);
                    }
                }
            }
        }
    } else {
        let factor = j0
            * j1
            * (2.0 * v0 * (j1 - j0)
                + k0 * k0
                + 2.0 * k0 * j1 * (t3 - t0)
                + j0 * j1 * (t0 - t3).powi(2)
                + 2.0 * v3 * (j0 - j1));
        if factor < 0.0 {
            // No time for a stretch of constant acceleration.
            t2 = ((j1 * -(j0 - j1) * (j0 * (2.0 * v3 - 2.0 * v0) + k0 * k0)).sqrt()
                + (j0 - j1) * (t0 * j0 - k0))
                / (j0 * (j0 - j1));
            v2 = v0 + k0 * (t2 - t0) + j0 * 0.5 * (t2 - t0).powi(2);
            k1 = k0 + j0 * (t2 - t0);
            t3 = t2 - k1 / j1;
        } else {
            let t1 = (-factor.sqrt() - j0 * (k0 + t3 * j1) + t0 * j0 * j0) / (j0 * (j0 - j1));
            let v1 = v0 + k0 * (t1 - t0) + j0 * 0.5 * (t1 - t0).powi(2);
            k1 = k0 + j0 * (t1 - t0);
            t2 = k1 / j1 + t3;
            v2 = v1 + k1 * (t2 - t1);
            if within(k1) {
                plan.add(t1, v1, k1, 0.0);
            }
        }
    }
    if within(k1) {
        plan.add(t2, v2, k1, j1);
        plan.add(t3, v3, 0.0, 0.0);
        return;
    }
    // The acceleration held to the constraints: the target reached later.
    k1 = k1.clamp(-lim.dec, lim.acc);
    let t1 = t0 + (k1 - k0) / j0;
    let v1 = v0 + k0 * (t1 - t0) + 0.5 * j0 * (t1 - t0).powi(2);
    let t2 = (v3 - v1) / k1 + t1 + k1 / (2.0 * j1);
    let v2 = v3 + k1 * k1 / (2.0 * j1);
    let t3 = -v1 / k1 + v3 / k1 + t1 - k1 / (2.0 * j1);
    plan.add(t1, v1, k1, 0.0);
    plan.add(t2, v2, k1, j1);
    plan.add(t3, v3, 0.0, 0.0);
}

/// Several targets in follow mode, or any in position mode: each line of the profile, in
/// follow mode joined to the next by a jerk at the constraints' rate (a corner that cannot
/// be rounded in time falls back to position mode from there).
fn lines(plan: &mut Plan, vx: &[Vertex], (t_start, k_start): (f64, f64)) {
    let lim = plan.lim;
    let jerk = |dk: f64| {
        if dk < 0.0 {
            -lim.dec_rate
        } else {
            lim.acc_rate
        }
    };
    let (mut t3, mut v3, mut k1, mut m1) = (vx[0].t, 0.0, 0.0, 0.0);
    if plan.follow {
        let mut j = 0.0;
        if vx[0].k.abs() > SMALL {
            j = jerk(vx[0].k - k_start);
            plan.add(vx[0].t, vx[0].v, k_start, j);
            t3 = vx[0].t
                + if j.abs() > SMALL {
                    (vx[0].k - k_start) / j
                } else {
                    0.0
                };
        }
        v3 = vx[0].v + k_start * (t3 - t_start) + 0.5 * j * (t3 - t_start).powi(2);
        k1 = vx[0].k;
        m1 = v3 - k1 * t3;
        plan.add(t3, v3, k1, 0.0);
    }
    for index in 0..vx.len() {
        if !plan.follow {
            plan.add(vx[index].t, vx[index].v, vx[index].k, 0.0);
            continue;
        }
        if index + 1 >= vx.len() {
            continue;
        }
        let (k0, t0, v0, m0) = (k1, t3, v3, m1);
        let next = vx[index + 1];
        k1 = next.k;
        m1 = next.m;
        let j = jerk(next.k - k0);
        if (k0 - k1).abs() >= SMALL {
            // Where the jerk starts, so that it ends on the next line.
            let t1 =
                (k0 * k0 - 2.0 * k0 * k1 + k1 * k1 - 2.0 * j * (m0 - m1)) / (2.0 * j * (k0 - k1));
            if t1 < t0 {
                plan.follow = false;
                continue;
            }
            let v1 = v0 + k0 * (t1 - t0);
            t3 = t1 + (next.k - k0) / j;
            v3 = v1 + k0 * (t3 - t1) + 0.5 * j * (t3 - t1).powi(2);
            plan.add(t1, v1, k0, j);
        }
        plan.add(t3, v3, next.k, 0.0);
    }
}

impl Profile {
    /// Plans `profile` from `t0` (s), the entity at speed `v0` (m/s) and acceleration `a0`
    /// (m/s²), its entries relative to `offset` (m/s), within the entity's `performance`
    /// where the constraints leave a limit out (as esmini's `parseDynamicConstraints`: a
    /// rate unbounded; a limit above the performance cut to it; no constraints, all
    /// unbounded).
    pub(in crate::xosc::story) fn plan(
        profile: &m::SpeedProfile,
        (t0, v0, a0, offset): (f64, f64, f64, f64),
        performance: m::Performance,
    ) -> Profile {
        let finite = |v: f64| if v.is_finite() { v } else { UNBOUNDED };
        let lim = match profile.constraints {
            None => Limits {
                acc: UNBOUNDED,
                dec: UNBOUNDED,
                acc_rate: UNBOUNDED,
                dec_rate: UNBOUNDED,
                speed: UNBOUNDED,
            },
            Some(c) => {
                let cut = |v: Option<f64>, most: f64| finite(v.map_or(most, |v| v.min(most)));
                Limits {
                    acc: cut(c.max_acceleration_mps2, performance.max_acceleration_mps2),
                    dec: cut(c.max_deceleration_mps2, performance.max_deceleration_mps2),
                    acc_rate: finite(c.max_acceleration_rate_mps3.unwrap_or(UNBOUNDED)),
                    dec_rate: finite(c.max_deceleration_rate_mps3.unwrap_or(UNBOUNDED)),
                    speed: cut(c.max_speed_mps, performance.max_speed_mps),
                }
            }
        };
        let vx = vertices(&profile.entries, (offset, t0, v0, a0), profile.follow, lim);
        let mut plan = Plan {
            segments: Vec::new(),
            follow: profile.follow,
            lim,
        };
        if vx.len() == 1 {
            plan.add(vx[0].t, vx[0].v, 0.0, 0.0);
        } else if plan.follow && vx.len() == 2 {
            single_target(&mut plan, &vx, a0);
        } else {
            lines(&mut plan, &vx, (t0, a0));
        }
        Profile {
            segments: plan.segments,
            entries: profile.entries.len(),
            current: 0,
            speed: v0,
        }
    }

    /// The speed furthest outside `[lo, hi]` (m/s) that the plan, from `t0` (s), reaches
    /// before it ends (stepped every 0.01 s as the storyboard steps it), if it leaves that
    /// range by more than 0.01 m/s.
    pub(in crate::xosc::story) fn leaves(&self, (t0, lo, hi): (f64, f64, f64)) -> Option<f64> {
        let mut p = self.clone();
        let end = p.segments[p.segments.len() - 1].t + STEPPED_PAST_S;
        let mut worst: Option<(f64, f64)> = None;
        for k in 1.. {
            let t = t0 + k as f64 * 0.01;
            let (v, over) = p.step(t);
            let out = (lo - v).max(v - hi);
            if out > 0.01 && worst.is_none_or(|(o, _)| out > o) {
                worst = Some((out, v));
            }
            if over || t > end {
                break;
            }
        }
        worst.map(|(_, v)| v)
    }

    /// The speed at `t1` (s), m/s, and whether the action ends there (esmini's
    /// `LongSpeedProfileAction::Step`: in its last entry's segment or past, at the last
    /// segment's speed).
    pub(in crate::xosc::story) fn step(&mut self, t1: f64) -> (f64, bool) {
        let last = self.segments[self.segments.len() - 1];
        let settled = t1 > last.t && (self.speed - last.v).abs() < SMALL;
        if t1 < last.t + STEPPED_PAST_S && !settled {
            while self.current + 1 < self.segments.len()
                && t1 > self.segments[self.current + 1].t - SMALL
            {
                self.current += 1;
            }
            let s = self.segments[self.current];
            let d = t1 - s.t;
            self.speed = s.v + s.k * d + 0.5 * s.j * d * d;
            if self.speed.abs() < SMALL {
                self.speed = 0.0;
            }
        }
        if self.current + 1 >= self.entries && (self.speed - last.v).abs() < SMALL {
            self.speed = last.v;
            return (self.speed, true);
        }
        (self.speed, false)
    }
}

impl Storyboard {
    /// Starts `SpeedProfileAction` `profile` on `e` at `t` (s), for action element `a`
    /// (`None` in `Init`): planned now, from the entity's speed and acceleration, relative
    /// to its `entityRef`'s speed now. It is the entity's speed task, so a `SpeedAction`
    /// ends it and it ends one, and a kept distance or a synchronization.
    pub(in crate::xosc::story) fn start_speed_profile(
        &mut self,
        e: usize,
        profile: &m::SpeedProfile,
        a: Option<usize>,
        t: f64,
    ) {
        let st = self.actors[e].state;
        let offset = profile.entity.map_or(0.0, |r| self.actors[r].state.speed);
        let plan = Profile::plan(
            profile,
            (t, st.speed, st.accel, offset),
            self.actors[e].performance,
        );
        let last = plan.segments[plan.segments.len() - 1].v;
        // The entries' speeds (and the speed it starts from): a plan that leaves them (a
        // corner its jerk limit cannot round in time) is said in the test's record.
        let (lo, hi) = (profile.entries.iter().map(|(_, v)| v + offset))
            .fold((st.speed, st.speed), |(lo, hi), v| (lo.min(v), hi.max(v)));
        if let Some(v) = plan.leaves((t, lo, hi)) {
            let name = a.map_or(String::from("in Init"), |a| {
                format!("{:?}", self.elems[a].name)
            });
            self.said.push(format!(
                "SpeedProfileAction {name} on {}: its plan leaves its entries' speeds, \
                 [{lo:.2}, {hi:.2}] m/s, reaching {v:.2} m/s (its constraints' rate of \
                 acceleration cannot round a corner in time; esmini plans and runs it so, \
                 warning that it falls back to linear)",
                self.actors[e].name
            ));
        }
        for old in [
            self.drives[e].keep.take().map(|k| k.action),
            self.drives[e].sync.take().map(|s| s.action),
            self.drives[e].speed.take().map(|s| s.action),
        ] {
            self.override_task(old);
        }
        if let Some(a) = a {
            self.elems[a].pending += 1;
        }
        self.drives[e].profile = plan;
        self.drives[e].speed = Some(SpeedTask {
            tr: Transition {
                from: st.speed,
                to: last,
                start_s: t,
                duration_s: 0.0,
                shape: transition::Shape::Step,
            },
            track: None,
            action: a.unwrap_or(usize::MAX),
            hold: None,
            profiled: true,
        });
    }

    /// The speed entity `e`'s speed task asks at `t1` (s), m/s, and whether it is over: its
    /// profile stepped, or its transition.
    pub(in crate::xosc::story) fn speed_task_at(
        &mut self,
        e: usize,
        task: &SpeedTask,
        t1: f64,
    ) -> (f64, bool) {
        if task.profiled {
            self.drives[e].profile.step(t1)
        } else {
            task.step(t1, |r| self.actors[r].state.speed)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn profile(follow: bool, constraints: Option<m::DistanceConstraints>) -> m::SpeedProfile {
        m::SpeedProfile {
            entity: None,
            follow,
            constraints,
            entries: vec![
                (Some(0.0), 0.0),
                (Some(4.0), 10.0),
                (Some(4.0), 4.0),
                (Some(2.0), 8.0),
            ],
        }
    }

    fn run(p: &mut Profile, from: f64, to: f64) -> Vec<(f64, f64, bool)> {
        let mut out = Vec::new();
        let mut t = from;
        while t < to - 1e-9 {
            t += 0.01;
            let (v, over) = p.step(t);
            out.push((t, v, over));
            if over {
                break;
            }
        }
        out
    }

    /// In position mode the speed is linear between the entries (esmini's speed-profile
    /// `Car2`): 10 m/s at 4 s, 4 m/s at 8 s, 8 m/s at 10 s after the start, and the action
    /// ends there.
    #[test]
    fn position_mode_is_linear_between_entries() {
        let mut p = Profile::plan(
            &profile(false, None),
            (2.0, 0.0, 0.0, 0.0),
            m::Performance::UNBOUNDED,
        );
        let out = run(&mut p, 2.0, 20.0);
        let at = |t: f64| out.iter().find(|(s, _, _)| (s - t).abs() < 1e-6).unwrap().1;
        assert!((at(4.0) - 5.0).abs() < 1e-9, "{}", at(4.0));
        assert!((at(6.0) - 10.0).abs() < 1e-9);
        assert!((at(10.0) - 4.0).abs() < 1e-9);
        assert!((at(11.0) - 6.0).abs() < 1e-9);
        let (t_end, v_end, over) = *out.last().unwrap();
        assert!(
            over && (v_end - 8.0).abs() < 1e-12 && (t_end - 12.0).abs() < 0.02,
            "{t_end}"
        );
    }

    /// In follow mode the corners are rounded within the maximum rate of acceleration: the
    /// acceleration never changes faster than 4 m/s³ up or 3 m/s³ down, nor leaves
    /// [−10, 5] m/s², and the last speed is reached.
    #[test]
    fn follow_mode_rounds_corners_within_the_jerk() {
        let c = m::DistanceConstraints {
            max_acceleration_mps2: Some(5.0),
            max_deceleration_mps2: Some(10.0),
            max_acceleration_rate_mps3: Some(4.0),
            max_deceleration_rate_mps3: Some(3.0),
            max_speed_mps: Some(50.0),
        };
        let mut p = Profile::plan(
            &profile(true, Some(c)),
            (2.0, 0.0, 0.0, 0.0),
            m::Performance::UNBOUNDED,
        );
        let out = run(&mut p, 2.0, 40.0);
        let (_, v_end, over) = *out.last().unwrap();
        assert!(over && (v_end - 8.0).abs() < 1e-9, "{v_end}");
        let acc: Vec<f64> = out.windows(2).map(|w| (w[1].1 - w[0].1) / 0.01).collect();
        for w in acc.windows(2) {
            let jerk = (w[1] - w[0]) / 0.01;
            assert!((-3.0 - 1e-3..=4.0 + 1e-3).contains(&jerk), "{jerk}");
        }
        assert!(acc.iter().all(|a| (-10.0 - 1e-6..=5.0 + 1e-6).contains(a)));
        // It rose to nearly 10 m/s before turning down.
        let top = out.iter().map(|o| o.1).fold(0.0, f64::max);
        assert!(top > 8.0 && top <= 10.0 + 1e-9, "{top}");
    }

    /// An entry without a time is reached at the constraints' acceleration, also before the
    /// last (esmini's planning, reading the missing time as a negative duration, drops the
    /// vertex before such an entry: a jump, not followed): from 8 m/s, 5 m/s at 4 m/s² down
    /// (0.75 s), then 15 m/s at 2 m/s² up (5 s more).
    #[test]
    fn entries_without_time_are_reached_at_the_constraints_acceleration() {
        let c = m::DistanceConstraints {
            max_acceleration_mps2: Some(2.0),
            max_deceleration_mps2: Some(4.0),
            ..Default::default()
        };
        let sp = m::SpeedProfile {
            entity: None,
            follow: false,
            constraints: Some(c),
            entries: vec![(None, 5.0), (None, 15.0)],
        };
        let mut p = Profile::plan(&sp, (0.0, 8.0, 0.0, 0.0), m::Performance::UNBOUNDED);
        let out = run(&mut p, 0.0, 20.0);
        let at = |t: f64| out.iter().find(|(s, _, _)| (s - t).abs() < 1e-6).unwrap().1;
        assert!((at(0.37) - 6.52).abs() < 1e-9, "{}", at(0.37));
        assert!((at(0.75) - 5.0).abs() < 1e-9);
        assert!((at(3.25) - 10.0).abs() < 1e-9);
        let (t_end, v_end, over) = *out.last().unwrap();
        assert!(
            over && v_end == 15.0 && (t_end - 5.75).abs() < 0.015,
            "{t_end}"
        );
    }

    /// With an `entityRef`, each entry is relative to that entity's speed at the start: 3 m/s
    /// over a reference at 10 m/s is 13 m/s.
    #[test]
    fn entries_relative_to_an_entity_add_its_speed_at_the_start() {
        let sp = m::SpeedProfile {
            entity: Some(1),
            follow: false,
            constraints: None,
            entries: vec![(Some(2.0), 3.0)],
        };
        let mut p = Profile::plan(&sp, (0.0, 10.0, 0.0, 10.0), m::Performance::UNBOUNDED);
        let out = run(&mut p, 0.0, 5.0);
        let at = |t: f64| out.iter().find(|(s, _, _)| (s - t).abs() < 1e-6).unwrap().1;
        assert!((at(1.0) - 11.5).abs() < 1e-9, "{}", at(1.0));
        let (_, v_end, over) = *out.last().unwrap();
        assert!(over && v_end == 13.0);
    }

    /// A jerk limit too low to round a corner in time (esmini's own planning of 22 → 0 m/s
    /// in 2.5 s within 0.5 m/s³) overshoots below 0 m/s, reversing: the plan says so; with
    /// a jerk of 30 m/s³ it stays within its entries' speeds.
    #[test]
    fn a_plan_that_leaves_its_entries_speeds_is_found() {
        let sp = |jerk: f64| m::SpeedProfile {
            entity: None,
            follow: true,
            constraints: Some(m::DistanceConstraints {
                max_acceleration_mps2: Some(3.0),
                max_deceleration_mps2: Some(8.0),
                max_acceleration_rate_mps3: Some(jerk),
                max_deceleration_rate_mps3: Some(jerk),
                max_speed_mps: None,
            }),
            entries: vec![(Some(2.5), 0.0), (Some(2.0), 0.0), (None, 18.0)],
        };
        let low = Profile::plan(&sp(0.5), (3.0, 22.0, 0.0, 0.0), m::Performance::UNBOUNDED);
        let v = low.leaves((3.0, 0.0, 22.0)).expect("it leaves [0, 22] m/s");
        assert!(v < -30.0, "{v}");
        let high = Profile::plan(&sp(30.0), (3.0, 22.0, 0.0, 0.0), m::Performance::UNBOUNDED);
        assert_eq!(high.leaves((3.0, 0.0, 22.0)), None);
    }
}
