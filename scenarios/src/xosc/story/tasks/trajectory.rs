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
    /// Starts a `FollowTrajectoryAction` on `e`.
    #[allow(clippy::type_complexity)]
    pub(in crate::xosc::story) fn start_trajectory(
        &mut self,
        e: usize,
        (shape, timing, position_mode): (&TrajectoryShape, &Option<(bool, f64, f64)>, bool),
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
            return Ok(());
        }
        let points = self.trajectory_points(e, shape, pos)?;
        let timed = points.iter().all(|(time, _)| time.is_some());
        // esmini turns a polyline's heading at its corners in `position` mode, along each leg
        // in `follow`; a sampled curve faces along itself at each sample.
        let turn = match (shape, position_mode) {
            (TrajectoryShape::Polyline(_), true) => crate::xosc::motion::Turn::Corner,
            (TrajectoryShape::Polyline(_), false) => crate::xosc::motion::Turn::Segment,
            _ => crate::xosc::motion::Turn::None,
        };
        let path = match timing {
            Some((absolute, scale, offset)) if timed => {
                let base = if *absolute { 0.0 } else { t };
                Path::Timed(Timed {
                    vertices: points
                        .iter()
                        .map(|(time, p)| (base + time.unwrap_or(0.0) * scale + offset, *p))
                        .collect(),
                    turn,
                })
            }
            _ => Path::Untimed(Untimed {
                vertices: points.into_iter().map(|(_, p)| p).collect(),
                gone_m: 0.0,
                turn,
            }),
        };
        // On the trajectory from the start (esmini's reading): a timed one where it is at `t`,
        // one started in `Init` at its first vertex.
        let here = match &path {
            Path::Timed(p) => Some(p.at(t).0),
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

        Ok(())
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
        | Position::Route { orientation, .. } => orientation.is_some(),
    }
}
