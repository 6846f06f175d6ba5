//! `LongitudinalDistanceAction`: an entity kept at a distance or time gap from another.

use super::super::*;

/// A continuous `LongitudinalDistanceAction` in progress on one entity: placed each step at
/// the distance from its reference, with the reference's speed (esmini's
/// `LongDistanceAction::Step` without dynamic constraints).
#[derive(Debug, Clone)]
pub(in crate::xosc::story) struct Keep {
    /// The entity it keeps its distance to.
    pub(in crate::xosc::story) reference: usize,
    /// Distance, m, or time gap, s (one of the two), and whether between bounding boxes.
    pub(in crate::xosc::story) gap: (Option<f64>, Option<f64>, bool),
    /// `displacement` as written.
    pub(in crate::xosc::story) displacement: String,
    /// Its action (`usize::MAX` in `Init`).
    pub(in crate::xosc::story) action: usize,
    /// Where the action is written, `file:line:col`.
    pub(in crate::xosc::story) at: String,
    /// With `DynamicConstraints`: the gap approached by a damped spring within them.
    pub(in crate::xosc::story) spring: Option<Spring>,
}

/// A `LongitudinalDistanceAction` approached within its `DynamicConstraints` (esmini's
/// `LongDistanceAction::Step`): each step the entity's acceleration is the critically damped
/// spring `a = k·e − 2√k·Δv` on the gap's error `e` (m) and the speeds' difference `Δv` (m/s),
/// with `k = 0.4·a_max` (`a_max` the maximum acceleration when the gap is too short, the
/// maximum deceleration when too long), cut to the maximum acceleration or deceleration and
/// moved towards more acceleration (or more deceleration) by at most its maximum rate times
/// the step (eased off at once); its speed is then cut to the maximum speed. A continuous one holds the gap until stopped or overridden; another ends once its
/// error is under [`DISTANCE_REACHED_M`].
#[derive(Debug, Clone, Copy)]
pub(in crate::xosc::story) struct Spring {
    /// Maximum acceleration and deceleration, m/s² (magnitudes).
    pub(in crate::xosc::story) acc: [f64; 2],
    /// Maximum rates of acceleration and deceleration, m/s³ (magnitudes; infinite when free).
    pub(in crate::xosc::story) rate: [f64; 2],
    /// Maximum speed, m/s.
    pub(in crate::xosc::story) max_speed: f64,
    /// The acceleration it took in the last step, m/s².
    pub(in crate::xosc::story) acceleration: f64,
    /// Whether it keeps behind its reference (else ahead), as resolved when it starts.
    pub(in crate::xosc::story) trailing: bool,
    /// Whether it holds the gap once reached.
    pub(in crate::xosc::story) continuous: bool,
    /// The frame the gap is measured in (`coordinateSystem`: `entity`, `lane`, `road`).
    pub(in crate::xosc::story) frame: &'static str,
}

/// The gap error under which a `LongitudinalDistanceAction` that is not continuous ends, m
/// (esmini's `LONGITUDINAL_DISTANCE_THRESHOLD`).
pub(in crate::xosc::story) const DISTANCE_REACHED_M: f64 = 0.1;

/// The stiffness of [`Spring`] per unit of its maximum acceleration, 1/m (esmini's
/// `spring_constant`).
const SPRING_PER_ACC: f64 = 0.4;

impl Spring {
    /// The acceleration (m/s²) for gap error `error` (m, the gap less the one asked: positive
    /// when it must close in) and speed difference `dv` (m/s, its speed less its reference's)
    /// over a step of `dt` s, within the limits, kept as the last acceleration.
    pub(in crate::xosc::story) fn accelerate(&mut self, error: f64, dv: f64, dt: f64) -> f64 {
        let tension = if error < 0.0 {
            self.acc[0]
        } else {
            self.acc[1]
        };
        let k = tension * SPRING_PER_ACC;
        let mut acc = error * k - dv * 2.0 * k.sqrt();
        let jerk = if acc < 0.0 {
            acc = acc.max(-self.acc[1]);
            -self.rate[1]
        } else {
            acc = acc.min(self.acc[0]);
            self.rate[0]
        };
        if jerk < 0.0 && acc < self.acceleration {
            acc = acc.max(self.acceleration + jerk * dt);
        } else if jerk > 0.0 && acc > self.acceleration {
            acc = acc.min(self.acceleration + jerk * dt);
        }
        self.acceleration = acc;
        acc
    }
}

impl Storyboard {
    /// Starts a `LongitudinalDistanceAction` on scripted entity `e` for action `a`: placed at
    /// the distance now, and, `continuous`, kept there each step ([`Storyboard::keep_distances`])
    /// until its action is stopped or a `SpeedAction` (the same longitudinal domain) replaces
    /// it, the action running meanwhile.
    ///
    /// # Errors
    /// What [`Storyboard::place_at_distance`] returns.
    pub(in crate::xosc::story) fn start_distance(
        &mut self,
        e: usize,
        keep: Keep,
        continuous: bool,
    ) -> Result<(), RoadError> {
        if keep.spring.is_some() {
            self.end_longitudinal(e);
            if keep.action != usize::MAX {
                self.elems[keep.action].pending += 1;
            }
            self.drives[e].keep = Some(keep);
            return Ok(());
        }
        self.place_at_distance(e, keep.reference, keep.gap, &keep.displacement)?;
        if continuous {
            self.end_longitudinal(e);
            if keep.action != usize::MAX {
                self.elems[keep.action].pending += 1;
            }
            self.drives[e].keep = Some(keep);
        }
        Ok(())
    }

    /// Places every scripted entity that keeps a distance, against where its reference is at
    /// the start of this step, before any entity moves (esmini steps every action, then moves
    /// the entities), with its reference's speed at the end of the step `t1` (s).
    ///
    /// # Errors
    /// What [`Storyboard::place_at_distance`] returns, at the action.
    pub(in crate::xosc::story) fn keep_distances(
        &mut self,
        t1: f64,
        dt: f64,
    ) -> Result<(), StoryError> {
        for e in 0..self.actors.len() {
            if !self.actors[e].scripted {
                continue;
            }
            // Taken out for the step and put back: no copy of its texts each step.
            let Some(mut k) = self.drives[e].keep.take() else {
                continue;
            };
            if let Some(spring) = &mut k.spring {
                let reached = self.spring_step(e, k.reference, k.gap, spring, (t1, dt));
                let (at, action, reference) = (k.at.clone(), k.action, k.reference);
                if !reached {
                    self.drives[e].keep = Some(k);
                } else {
                    self.override_task(Some(action));
                }
                if self.actors[e].state.speed < 0.0 {
                    return Err(StoryError {
                        at,
                        message: format!(
                            "LongitudinalDistanceAction: {} backs up to keep its gap to {} \
                             ({:.2} m/s), which paracosm does not do: its storyboard moves \
                             forward only (esmini reverses)",
                            self.actors[e].name,
                            self.actors[reference].name,
                            self.actors[e].state.speed
                        ),
                    });
                }
                continue;
            }
            let placed = self.place_at_distance(e, k.reference, k.gap, &k.displacement);
            // With the speed a scripted reference's `SpeedAction` gives it over this step,
            // which esmini has stepped by then (an action before this one). A reference the
            // system under test drives has the speed it drives at: its `SpeedAction` is
            // only the speed asked of that system.
            let stepped =
                self.actors[k.reference].scripted && self.drives[k.reference].speed.is_some();
            if placed.is_ok() && stepped {
                self.actors[e].state.speed = self.reference_speed(k.reference, t1).max(0.0);
            }
            let result = placed.map_err(|err| StoryError {
                at: k.at.clone(),
                message: format!(
                    "LongitudinalDistanceAction of {}: {err}",
                    self.actors[e].name
                ),
            });
            self.drives[e].keep = Some(k);
            result?;
        }
        Ok(())
    }

    /// The [`Spring`] of a `LongitudinalDistanceAction` of entity `e` to `reference` within
    /// `c`, with its `displacement`, `coordinateSystem` and `continuous` as written: a limit
    /// left out is `e`'s performance (a rate: unbounded) and one above it is cut to it
    /// (esmini's `parseDynamicConstraints`); `any` resolved by where the reference is now,
    /// behind or ahead along `e`'s heading (esmini's `LongDistanceAction::Start`).
    pub(in crate::xosc::story) fn spring_for(
        &self,
        e: usize,
        reference: usize,
        c: &m::DistanceConstraints,
        (displacement, frame, continuous): (&str, &str, bool),
    ) -> Spring {
        let p = self.actors[e].performance;
        let cut = |v: Option<f64>, most: f64| v.map_or(most, |v| v.min(most));
        let trailing = match displacement {
            "leadingReferencedEntity" => false,
            "trailingReferencedEntity" => true,
            _ => {
                let (a, r) = (self.actors[e].state.pose, self.actors[reference].state.pose);
                (r.x - a.x) * a.h.cos() + (r.y - a.y) * a.h.sin() >= 0.0
            }
        };
        Spring {
            acc: [
                cut(c.max_acceleration_mps2, p.max_acceleration_mps2),
                cut(c.max_deceleration_mps2, p.max_deceleration_mps2),
            ],
            rate: [
                c.max_acceleration_rate_mps3.unwrap_or(f64::INFINITY),
                c.max_deceleration_rate_mps3.unwrap_or(f64::INFINITY),
            ],
            max_speed: cut(c.max_speed_mps, p.max_speed_mps),
            acceleration: 0.0,
            trailing,
            continuous,
            frame: match frame {
                "lane" => "lane",
                "road" => "road",
                _ => "entity",
            },
        }
    }

    /// The speed (m/s) of `reference` over the step ending at `t1` (s): a scripted one's
    /// `SpeedAction` has set it by then (esmini steps it before the distance action), a
    /// reference the system under test drives has the speed it drives at.
    fn reference_speed(&self, reference: usize, t1: f64) -> f64 {
        let r = &self.actors[reference];
        match self.drives[reference].speed {
            Some(task) if r.scripted && task.profiled => {
                self.drives[reference].profile.clone().step(t1).0
            }
            Some(task) if r.scripted => task.step(t1, |o| self.actors[o].state.speed).0,
            _ => r.state.speed,
        }
    }

    /// One step of `spring` on entity `e` keeping `gap` (distance m, time gap s, freespace)
    /// to `reference`, the step ending at `t1` and `dt` s long: its speed set for the step
    /// (the move follows, as esmini's default controller moves it after every action);
    /// whether a spring that is not continuous has reached its gap.
    fn spring_step(
        &mut self,
        e: usize,
        reference: usize,
        (distance, gap_s, freespace): (Option<f64>, Option<f64>, bool),
        spring: &mut Spring,
        (t1, dt): (f64, f64),
    ) -> bool {
        let g = m::Gap {
            entity: reference,
            rule: m::Rule::Lt,
            value: 0.0,
            freespace,
            frame: spring.frame.into(),
            kind: "longitudinal".into(),
        };
        let measured = self.gap(e, &g).0;
        let v_ref = self.reference_speed(reference, t1);
        let asked = match (distance, gap_s) {
            (Some(d), _) => d.abs(),
            (None, Some(s)) => (v_ref.abs() * s).abs(),
            (None, None) => 0.0,
        };
        let asked = if spring.trailing { asked } else { -asked };
        let error = measured - asked;
        let reached = !spring.continuous && error.abs() < DISTANCE_REACHED_M;
        let v0 = self.actors[e].state.speed;
        let acc = spring.accelerate(error, v0 - v_ref, dt);
        let v = (v0 + acc * dt).clamp(-spring.max_speed, spring.max_speed);
        self.drives[e].speed_before = Some(v0);
        self.actors[e].state.speed = v;
        reached
    }

    /// Puts entity `e` on `reference`'s lane at a distance `(distance, time gap, freespace)`
    /// ahead of it (`leadingReferencedEntity`; `any` with a negative distance, or when ahead
    /// now) or behind it, with the reference's speed.
    pub(in crate::xosc::story) fn place_at_distance(
        &mut self,
        e: usize,
        reference: usize,
        (distance, gap_s, freespace): (Option<f64>, Option<f64>, bool),
        displacement: &str,
    ) -> Result<(), RoadError> {
        let r = self.actors[reference].clone();
        let me = self.actors[e].clone();
        let Some(rl) = r.state.lane else {
            return Err(RoadError(format!(
                "a LongitudinalDistanceAction to {}, which is not on a lane",
                r.name
            )));
        };
        let gap = match (distance, gap_s) {
            (Some(d), _) => d,
            (None, Some(g)) => g * r.state.speed.abs(),
            (None, None) => 0.0,
        };
        // The standard's distance is at least 0; a negative one with `any` (the
        // `scenariogeneration` package's Euro NCAP CCRb files write -12) puts the entity ahead,
        // as esmini reads it (its requested distance from the entity to its reference keeps
        // the sign); with `leading` or `trailing` only its magnitude counts.
        let (gap, ahead) = match displacement {
            "trailingReferencedEntity" => (gap.abs(), false),
            "leadingReferencedEntity" => (gap.abs(), true),
            _ if gap < 0.0 => (-gap, true),
            _ => (gap, {
                let p = me.state.pose;
                let (dx, dy) = (p.x - r.state.pose.x, p.y - r.state.pose.y);
                dx * r.state.pose.h.cos() + dy * r.state.pose.h.sin() >= 0.0
            }),
        };
        let ds = match (freespace, ahead) {
            (false, true) => gap,
            (false, false) => -gap,
            (true, true) => {
                gap + (r.centre_m[0] + r.size_m[0] / 2.0) - (me.centre_m[0] - me.size_m[0] / 2.0)
            }
            (true, false) => {
                -(gap + (me.centre_m[0] + me.size_m[0] / 2.0) - (r.centre_m[0] - r.size_m[0] / 2.0))
            }
        };
        let mut lp = rl;
        if ds >= 0.0 {
            let prefer = |_: usize| false;
            self.roads.advance(&mut lp, ds, &prefer);
        } else {
            let up = lp.along_s(&self.roads);
            let s = lp.s + if up { ds } else { -ds };
            let (id, road) = self.roads.ids(lp.lane);
            let road = self.roads.map().roads[road].od_id.clone();
            let rev = lp.rev;
            lp = self.roads.lane_pos(&road, id, s, lp.d)?;
            lp.rev = rev;
        }
        // On a lane of the same road, it keeps its own lane and offset there (esmini moves
        // it along `s`); elsewhere it takes the reference's.
        if let Some(own) = me.state.lane {
            let (id, road) = self.roads.ids(own.lane);
            if road == self.roads.ids(lp.lane).1 {
                let name = self.roads.map().roads[road].od_id.clone();
                if let Ok(mut mine) = self.roads.lane_pos(&name, id, lp.s, own.d) {
                    mine.rev = own.rev;
                    lp = mine;
                }
            }
        }
        // Facing as it faced its lane (esmini's motion along `s` keeps the heading relative
        // to the road: a bicycle carried sideways on a rack stays sideways).
        let mut pose = self.roads.pose_of(&lp);
        pose.h = wrap(self.roads.travel_heading(&lp) + self.drives[e].rel_h);
        let st = &mut self.actors[e].state;
        st.pose = pose;
        st.lane = Some(lp);
        // And it takes the reference's speed.
        st.speed = r.state.speed;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A minute of `spring` 20 m too far behind a reference at 10 m/s, steps of 1/60 s:
    /// the gap's error at the end and its most negative value (m), each acceleration checked
    /// against the limits `[−4, 3]` m/s² and the spring's rates (raised towards more
    /// acceleration, or more deceleration, by at most the rate over a step; eased off at once).
    fn close_in(mut spring: Spring) -> (f64, f64) {
        let dt = 1.0 / 60.0;
        let (v_ref, asked) = (10.0, 15.0);
        let (mut gap, mut v) = (asked + 20.0, 10.0);
        let (mut last, mut shortest) = (0.0, f64::INFINITY);
        for _ in 0..3600 {
            let acc = spring.accelerate(gap - asked, v - v_ref, dt);
            assert!((-4.0..=3.0).contains(&acc), "{acc}");
            if acc >= 0.0 && acc > last {
                assert!(
                    acc - last <= spring.rate[0] * dt + 1e-12,
                    "{acc} after {last}"
                );
            }
            if acc < 0.0 && acc < last {
                assert!(
                    last - acc <= spring.rate[1] * dt + 1e-12,
                    "{acc} after {last}"
                );
            }
            last = acc;
            v = (v + acc * dt).clamp(-spring.max_speed, spring.max_speed);
            gap += (v_ref - v) * dt;
            shortest = shortest.min(gap - asked);
        }
        (gap - asked, shortest)
    }

    /// Without rates the spring closes its gap critically damped (never 0.5 m short of it)
    /// and holds it within 0.1 m after a minute; with rates of 1 m/s³ it swings past the gap
    /// and settles all the same; the first step without rates takes the whole cut
    /// acceleration or deceleration.
    #[test]
    fn a_spring_closes_its_gap_within_its_limits() {
        let free = Spring {
            acc: [3.0, 4.0],
            rate: [f64::INFINITY; 2],
            max_speed: 30.0,
            acceleration: 0.0,
            trailing: true,
            continuous: true,
            frame: "entity",
        };
        let (error, shortest) = close_in(free);
        assert!(error.abs() < 0.1 && shortest > -0.5, "{error} {shortest}");
        let (error, shortest) = close_in(Spring {
            rate: [1.0, 1.0],
            ..free
        });
        assert!(error.abs() < 0.1 && shortest < -0.5, "{error} {shortest}");
        let dt = 1.0 / 60.0;
        assert_eq!({ free }.accelerate(20.0, 0.0, dt), 3.0);
        assert_eq!({ free }.accelerate(-20.0, 0.0, dt), -4.0);
    }
}
