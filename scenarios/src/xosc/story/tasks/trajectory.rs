//! `FollowTrajectoryAction`: a polyline, clothoid or NURBS trajectory, timed or followed at
//! the entity's speed.

use super::super::*;

/// A `FollowTrajectoryAction` in progress: its vertices' times kept (`timing` given and every
/// vertex timed), or followed at the entity's speed.
#[derive(Debug, Clone)]
pub(in crate::xosc::story) enum Path {
    /// Where the entity is at each time.
    Timed(Timed),
    /// The path the entity follows at its own speed.
    Untimed(Untimed),
}

impl Path {
    /// Where the entity is after a step ending at `t1` (s) in which it travels `dist` (m) at
    /// its speed, and whether the trajectory is over.
    pub(in crate::xosc::story) fn step(&mut self, t1: f64, dist: f64) -> (Pose, bool) {
        match self {
            Path::Timed(p) => p.at(t1),
            Path::Untimed(u) => u.advance(dist),
        }
    }
}

impl Storyboard {
    /// The path of trajectory `shape` sampled into `points`, followed by entity `e` at its
    /// speed from `offset` m along it, its heading turned as `turn` says; facing it as esmini's
    /// `FollowTrajectoryAction::Start` has the entity face it: a path that gives no headings
    /// is faced along, or against at a negative speed (a car reversing along a path laid
    /// behind it, facing away from the way it goes); one that gives its headings is faced as
    /// they say, and a heading against the path's direction moves it along the path at a
    /// negative speed.
    fn untimed(
        &self,
        e: usize,
        (shape, points): (&TrajectoryShape, Vec<(Option<f64>, Pose)>),
        offset: f64,
        turn: crate::xosc::motion::Turn,
    ) -> Untimed {
        let mut u = Untimed {
            vertices: points.into_iter().map(|(_, p)| p).collect(),
            gone_m: offset,
            turn,
            facing: 1.0,
            explicit: match shape {
                TrajectoryShape::Polyline(v) => v.iter().all(|(_, p)| gives_heading(p)),
                _ => false,
            },
        };
        let against = if u.explicit {
            let h = u.clone().advance(0.0).0.h;
            wrap(h - u.direction_at(offset)).abs() > std::f64::consts::FRAC_PI_2 + 1e-6
        } else {
            // Its speed now: a step started before it in the same step is taken at once
            // (esmini sets a step's speed when the action starts).
            let v = match self.drives[e].speed {
                Some(s) if !s.profiled && s.tr.duration_s <= 0.0 => s.tr.to,
                _ => self.actors[e].state.speed,
            };
            v < 0.0
        };
        if against {
            u.facing = -1.0;
        }
        u
    }

    /// Starts a `FollowTrajectoryAction` on `e`: its shape, timing, following mode and
    /// `initialDistanceOffset` (m; untimed only, the entity placed there as esmini's
    /// `SetTrajectoryS` places it).
    #[allow(clippy::type_complexity)]
    pub(in crate::xosc::story) fn start_trajectory(
        &mut self,
        e: usize,
        (shape, timing, position_mode, offset): (
            &TrajectoryShape,
            &Option<(bool, f64, f64)>,
            bool,
            f64,
        ),
        (a, pos): (Option<usize>, &paracosm_openscenario::Pos),
        t: f64,
    ) -> Result<(), StoryError> {
        let scripted = self.actors[e].scripted;
        let begin = |sb: &mut Storyboard| {
            if let Some(a) = a {
                sb.elems[a].pending += 1;
            }
        };

        if !scripted {
            return self.hand_trajectory(e, (shape, offset), (a, pos));
        }
        let points = self.trajectory_points(e, shape, pos)?;
        let timed = points.iter().all(|(time, _)| time.is_some());
        let turn = turn_of(shape, position_mode);
        let path = match timing {
            Some((absolute, scale, offset)) if timed => {
                let base = if *absolute { 0.0 } else { t };
                let vertices: Vec<(f64, Pose)> = points
                    .iter()
                    .map(|(time, p)| (base + time.unwrap_or(0.0) * scale + offset, *p))
                    .collect();
                // A polyline in `follow` mode: each leg at a constant acceleration from the
                // entity's speed now, as esmini's `PolyLineShape::CalculatePolyLine` plans it.
                let legs = (matches!(shape, TrajectoryShape::Polyline(_)) && !position_mode)
                    .then(|| Legs::new(&vertices, self.actors[e].state.speed));
                Path::Timed(Timed {
                    vertices,
                    turn,
                    legs,
                })
            }
            _ => Path::Untimed(self.untimed(e, (shape, points), offset, turn)),
        };
        // On the trajectory from the start (esmini's reading): a timed one where it is at `t`,
        // one started in `Init` at its first vertex, one with an offset there.
        let here = match &path {
            Path::Timed(p) => Some(p.at(t).0),
            Path::Untimed(u) if offset > 0.0 => Some(u.clone().advance(0.0).0),
            Path::Untimed(u) if a.is_none() => u.vertices.first().copied(),
            Path::Untimed(_) => None,
        };
        if let Some(p) = here {
            let lane = self.facing(self.roads.anchor(p.x, p.y), p.h);
            let st = &mut self.actors[e].state;
            st.pose = p;
            st.lane = lane;
        }
        let d = &mut self.drives[e];
        let old = [
            d.path.take().map(|p| p.1),
            d.lateral.take().map(|l| l.action),
        ];
        for o in old {
            self.override_task(o);
        }
        begin(self);
        self.drives[e].path = Some((path, a.unwrap_or(usize::MAX)));
        self.drives[e].path_at = site(pos);

        Ok(())
    }

    /// Hands the trajectory `shape` of a `FollowTrajectoryAction` (action `a`, written at
    /// `pos`; `None` in `Init`) on the ego `e` a system under test drives to that system as
    /// its route: the trajectory's points, then its lanes on from where the trajectory ends
    /// (in `Init`, the ego starts at the trajectory's start). The speed stays the system's (a timed trajectory is refused at load); the action ends
    /// once the ego is within [`PATH_END_REACHED_M`] of the trajectory's end.
    ///
    /// # Errors
    /// [`StoryError`] for a point off the map, or a trajectory that ends on no lane.
    fn hand_trajectory(
        &mut self,
        e: usize,
        (shape, offset): (&TrajectoryShape, f64),
        (a, pos): (Option<usize>, &paracosm_openscenario::Pos),
    ) -> Result<(), StoryError> {
        let points: Vec<Pose> = self
            .trajectory_points(e, shape, pos)?
            .into_iter()
            .map(|(_, p)| p)
            .collect();
        let path = from_offset(&points, offset);
        let end = *path.last().expect("a trajectory has points");
        let Some(join) = self.facing(self.roads.anchor(end.x, end.y), end.h) else {
            return Err(StoryError {
                at: site(pos),
                message: format!(
                    "the trajectory handed to the system under test driving {} ends off the \
                     map's lanes, at ({:.2}, {:.2}): its route could not go on from there",
                    self.actors[e].name, end.x, end.y
                ),
            });
        };
        if a.is_none() {
            // Started in `Init`: the ego starts where the trajectory does (esmini's reading).
            let first = path[0];
            let lane = self.facing(self.roads.anchor(first.x, first.y), first.h);
            let st = &mut self.actors[e].state;
            st.pose = first;
            st.lane = lane;
        }
        self.route = Some(RouteAsk {
            join,
            ahead_m: 0.0,
            path,
        });
        // A trajectory handed before ends: the new one is the route now.
        let old = self.drives[e].path_goal.take().map(|g| g.1);
        self.override_task(old);
        if let Some(a) = a {
            self.elems[a].pending += 1;
            self.drives[e].path_goal = Some((end, a));
        }
        Ok(())
    }

    /// Ends the driven ego `e`'s `FollowTrajectoryAction` once it is within
    /// [`PATH_END_REACHED_M`] of its trajectory's end.
    pub(in crate::xosc::story) fn ask_path(&mut self, e: usize) {
        let Some((end, a)) = self.drives[e].path_goal else {
            return;
        };
        let p = self.actors[e].state.pose;
        if (p.x - end.x).hypot(p.y - end.y) <= PATH_END_REACHED_M {
            self.drives[e].path_goal = None;
            self.task_done(Some(a));
        }
    }

    /// The route asked of the driven ego by its `Init` (a trajectory handed to it), which
    /// the host gives its system from the start.
    pub fn init_route(&self) -> Option<&RouteAsk> {
        self.route.as_ref()
    }

    /// The points of trajectory `shape` for entity `e`, with their times in the file (none
    /// untimed): a polyline's vertices (a world vertex without a heading facing along its leg,
    /// the next vertex, or for the last the one before, as esmini aligns what a file omits); a
    /// clothoid sampled from its start (`e`'s pose without a `Position`), its times linear in
    /// the distance along it; a NURBS sampled along its parameter.
    ///
    /// # Errors
    /// [`StoryError`] for a position that cannot be resolved (`pos`: the action's).
    pub(in crate::xosc::story) fn trajectory_points(
        &self,
        e: usize,
        shape: &TrajectoryShape,
        pos: &paracosm_openscenario::Pos,
    ) -> Result<Vec<(Option<f64>, Pose)>, StoryError> {
        Ok(match shape {
            TrajectoryShape::Polyline(vertices) => {
                let mut poses = Vec::new();
                for (_, p) in vertices {
                    poses.push(self.resolve(p, pos)?.0);
                }
                for k in 0..poses.len() {
                    if !gives_heading(&vertices[k].1) {
                        let (a, b) = match (poses.get(k), poses.get(k + 1)) {
                            (Some(a), Some(b)) => (*a, *b),
                            _ if k > 0 => (poses[k - 1], poses[k]),
                            _ => continue,
                        };
                        if (b.x - a.x).hypot(b.y - a.y) > 1e-9 {
                            poses[k].h = (b.y - a.y).atan2(b.x - a.x);
                        }
                    }
                }
                vertices.iter().map(|(t, _)| *t).zip(poses).collect()
            }
            TrajectoryShape::Clothoid {
                start,
                curvature,
                curvature_prime,
                length,
                times,
            } => {
                let from = match start {
                    Some(p) => self.resolve(p, pos)?.0,
                    None => self.actors[e].state.pose,
                };
                clothoid_poses(from, *curvature, *curvature_prime, *length)
                    .into_iter()
                    .map(|(d, p)| (times.map(|(a, b)| a + (b - a) * d / length), p))
                    .collect()
            }
            TrajectoryShape::ClothoidSpline {
                start,
                segments,
                restarts,
                times,
            } => {
                let from = match start {
                    Some(p) => self.resolve(p, pos)?.0,
                    None => self.actors[e].state.pose,
                };
                let mut starts = Vec::new();
                for (k, p) in restarts {
                    starts.push((*k, self.resolve(p, pos)?.0));
                }
                let poses = spline_poses(from, segments, &starts);
                match times {
                    Some((begins, end)) => spline_times(poses, segments, begins, *end),
                    None => poses,
                }
            }
            TrajectoryShape::Nurbs {
                order,
                points,
                knots,
            } => {
                let mut at = Vec::new();
                for (time, weight, p) in points {
                    let q = self.resolve(p, pos)?.0;
                    let given = gives_heading(p);
                    at.push((*time, *weight, [q.x, q.y], given.then_some(q.h)));
                }
                nurbs_poses(*order, &at, knots)
            }
        })
    }
}

/// The part of the path through `points` from `offset` m along it: the point there, then the
/// points after it (the last point alone when the path is shorter).
fn from_offset(points: &[Pose], offset: f64) -> Vec<Pose> {
    if offset <= 0.0 {
        return points.to_vec();
    }
    let mut left = offset;
    for (k, w) in points.windows(2).enumerate() {
        let len = (w[1].x - w[0].x).hypot(w[1].y - w[0].y);
        if left < len {
            let u = left / len;
            let start = Pose {
                x: w[0].x + u * (w[1].x - w[0].x),
                y: w[0].y + u * (w[1].y - w[0].y),
                h: w[0].h,
            };
            return std::iter::once(start)
                .chain(points[k + 1..].iter().copied())
                .collect();
        }
        left -= len;
    }
    points.last().copied().into_iter().collect()
}

/// The poses along clothoid spline `segments` (`[curvature at start, at end, length,
/// heading offset]`) laid end to end from `from`, each segment from where the one before
/// ends (or from its own start in `restarts`, by index), turned by its heading offset
/// (OpenSCENARIO 1.3, `ClothoidSpline`; esmini's `ClothoidSplineShape::Freeze`); untimed. Sampled
/// as esmini's `ClothoidSplineShape::CalculatePolyLine` samples it: every metre along the
/// whole spline and its end, a vertex's heading the curve's there (followed with the heading
/// turning along each leg, [`crate::xosc::motion::Turn::Segment`]).
/// How a trajectory's heading turns between its points: esmini turns a polyline's heading at
/// its corners in `position` mode, along each leg in `follow`; a curve it samples (clothoid,
/// clothoid spline, NURBS) turns along each leg between its samples' headings in either mode
/// (esmini's `CalculatePolyLine` of those shapes sets the segment interpolation after the
/// action has set its mode).
fn turn_of(shape: &TrajectoryShape, position_mode: bool) -> crate::xosc::motion::Turn {
    match (shape, position_mode) {
        (TrajectoryShape::Polyline(_), true) => crate::xosc::motion::Turn::Corner,
        _ => crate::xosc::motion::Turn::Segment,
    }
}

/// A clothoid spline's samples (`poses`, one every [`SPLINE_STEP_M`] along its `segments`)
/// with their times, as esmini's `ClothoidSplineShape::Evaluate` reads a time: on each
/// segment the distance is linear in time from its `timeStart` (`begins`) to the next
/// one's (the last segment's: the spline's `end`), s.
fn spline_times(
    poses: Vec<(Option<f64>, Pose)>,
    segments: &[[f64; 4]],
    begins: &[f64],
    end: f64,
) -> Vec<(Option<f64>, Pose)> {
    let total: f64 = segments.iter().map(|g| g[2]).sum();
    let n = poses.len();
    poses
        .into_iter()
        .enumerate()
        .map(|(i, (_, p))| {
            let s = if i + 1 < n {
                i as f64 * SPLINE_STEP_M
            } else {
                total
            };
            // The segment holding `s` (the last one at the spline's end).
            let (mut k, mut before) = (0usize, 0.0);
            while k + 1 < segments.len() && s > before + segments[k][2] - 1e-6 {
                before += segments[k][2];
                k += 1;
            }
            let until = begins.get(k + 1).copied().unwrap_or(end);
            let u = ((s - before) / segments[k][2]).clamp(0.0, 1.0);
            (Some(begins[k] + u * (until - begins[k])), p)
        })
        .collect()
}

fn spline_poses(
    from: Pose,
    segments: &[[f64; 4]],
    restarts: &[(usize, Pose)],
) -> Vec<(Option<f64>, Pose)> {
    use paracosm_engine::network::RefLine;
    // Each segment's start pose and line.
    let mut lines: Vec<(Pose, RefLine)> = Vec::new();
    let mut at = from;
    for (k, &[k0, k1, length, h_offset]) in segments.iter().enumerate() {
        if let Some((_, p)) = restarts.iter().find(|(j, _)| *j == k) {
            at = *p;
        }
        at.h = wrap(at.h + h_offset);
        let line = RefLine {
            length_m: length,
            curv_start: k0,
            curv_end: k1,
        };
        lines.push((at, line));
        at = pose_on(at, &line, length);
    }
    let total: f64 = segments.iter().map(|g| g[2]).sum();
    let steps = (total / SPLINE_STEP_M) as usize;
    let mut out = Vec::with_capacity(steps + 1);
    let (mut j, mut before) = (0usize, 0.0);
    for i in 0..=steps {
        let s = if i < steps {
            i as f64 * SPLINE_STEP_M
        } else {
            total
        };
        while i < steps && s > before + lines[j].1.length_m - 1e-6 && j + 1 < lines.len() {
            before += lines[j].1.length_m;
            j += 1;
        }
        let k = if i < steps { j } else { lines.len() - 1 };
        let local = if i < steps {
            s - before
        } else {
            total - segments[..k].iter().map(|g| g[2]).sum::<f64>()
        };
        out.push((None, pose_on(lines[k].0, &lines[k].1, local)));
    }
    out
}

/// The distance between the vertices of a sampled clothoid spline, m (esmini's).
const SPLINE_STEP_M: f64 = 1.0;

/// The pose `d` m along `line` laid from `start` (its heading along the line's start).
fn pose_on(start: Pose, line: &paracosm_engine::network::RefLine, d: f64) -> Pose {
    let [x, z] = line.point(d);
    // The engine's frame has +z to the right of travel; OpenSCENARIO's +y is left.
    let (lx, ly) = (x, -z);
    let (c, s) = (start.h.cos(), start.h.sin());
    Pose {
        x: start.x + c * lx - s * ly,
        y: start.y + s * lx + c * ly,
        h: wrap(start.h + line.heading(d)),
    }
}

/// Whether position `p` gives a heading of its own (a world position's `h`, an
/// `Orientation` with `h`): a trajectory's vertex without one faces along its leg, as esmini
/// aligns a vertex whose position sets no heading mode.
fn gives_heading(p: &Position) -> bool {
    match p {
        Position::World { h, .. } => h.is_some(),
        Position::RelativeWorld { orientation, .. }
        | Position::RelativeObject { orientation, .. }
        | Position::Road { orientation, .. }
        | Position::Lane { orientation, .. }
        | Position::RelativeRoad { orientation, .. }
        | Position::RelativeLane { orientation, .. }
        | Position::Route { orientation, .. }
        | Position::Trajectory { orientation, .. } => orientation.is_some(),
    }
}
