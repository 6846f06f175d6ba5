//! `AssignRouteAction`: the roads an entity prefers at junctions, and the route asked of the
//! driven ego.

use super::super::*;

impl Storyboard {
    /// Performs an `AssignRouteAction` (written at `at`) on entity `e`: the roads of its
    /// `waypoints` become the roads it prefers at junctions; for the driven ego (not
    /// `scripted`), a route planned again from where it is.
    ///
    /// # Errors
    /// [`StoryError`] for a waypoint off the map.
    pub(in crate::xosc::story) fn assign_route(
        &mut self,
        e: usize,
        waypoints: &[(Position, String)],
        at: &paracosm_openscenario::Pos,
        scripted: bool,
    ) -> Result<(), StoryError> {
        let mut points = Vec::new();
        for (p, _) in waypoints {
            if let (_, Some(lp)) = self.resolve(p, at)? {
                points.push(LanePos { rev: false, ..lp });
            }
        }
        self.set_route(e, &points, scripted);
        Ok(())
    }

    /// Gives entity `e` the route through `points` ([`Storyboard::route_through`]): the
    /// roads it prefers where lanes fork; for the driven ego (not `scripted`), a route
    /// planned again from where it is, which the host hands its system.
    fn set_route(&mut self, e: usize, points: &[LanePos], scripted: bool) {
        self.drives[e].prefer_roads = self.route_through(points);
        self.drives[e].route_at = 0;
        if !scripted {
            // A trajectory handed before ends: this route replaces it.
            let old = self.drives[e].path_goal.take().map(|g| g.1);
            self.override_task(old);
            if let Some(lp) = self.actors[e].state.lane {
                self.route = Some(RouteAsk {
                    join: lp,
                    ahead_m: 0.0,
                    path: Vec::new(),
                });
            }
        }
    }

    /// Performs an `AcquirePositionAction` (written at `at`) on entity `e`: a route from the
    /// road it is on to the road of `target` (esmini's: a route of two waypoints, where the
    /// entity is and the target), whose roads it prefers where lanes fork; for the driven ego,
    /// the route handed to its system.
    ///
    /// # Errors
    /// [`StoryError`] for a target off the map.
    pub(in crate::xosc::story) fn acquire_position(
        &mut self,
        e: usize,
        target: &Position,
        at: &paracosm_openscenario::Pos,
        scripted: bool,
    ) -> Result<(), StoryError> {
        let mut points = Vec::new();
        if let Some(lp) = self.actors[e].state.lane {
            points.push(lp);
        }
        if let (_, Some(lp)) = self.resolve(target, at)? {
            points.push(LanePos { rev: false, ..lp });
        }
        self.set_route(e, &points, scripted);
        Ok(())
    }

    /// The roads of a route through `points` in order: the shortest way between each two
    /// ([`Roads::route_roads`], as esmini plans a route between its waypoints), or where no
    /// way leads from one to the next, their own roads.
    fn route_through(&self, points: &[LanePos]) -> Vec<usize> {
        let mut roads: Vec<usize> = Vec::new();
        let mut add = |r: usize| {
            if roads.last() != Some(&r) {
                roads.push(r);
            }
        };
        if let [only] = points {
            add(self.roads.ids(only.lane).1);
        }
        for w in points.windows(2) {
            match self.roads.route_roads(&w[0], &w[1]) {
                Some(way) => way.into_iter().for_each(&mut add),
                None => {
                    add(self.roads.ids(w[0].lane).1);
                    add(self.roads.ids(w[1].lane).1);
                }
            }
        }
        roads
    }

    /// Whether entity `e`'s route (its `AssignRouteAction`) takes lane `lane`: a lane of a
    /// road it names, or a junction's connecting lane that leads to one (false without a
    /// route).
    pub fn route_takes(&self, e: usize, lane: usize) -> bool {
        let roads = &self.drives[e].prefer_roads;
        roads.contains(&self.roads.ids(lane).1) || roads.contains(&self.roads.exit_road(lane))
    }

    /// The route asked of the driven ego since the last call, if any (a `LaneChangeAction`
    /// or an `AssignRouteAction` on it): the host hands it to the system under test.
    pub fn take_route(&mut self) -> Option<RouteAsk> {
        self.route.take()
    }
}
