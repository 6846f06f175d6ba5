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
        let mut roads = Vec::new();
        for (p, _) in waypoints {
            if let (_, Some(lp)) = self.resolve(p, at)? {
                roads.push(self.roads.ids(lp.lane).1);
            }
        }
        self.drives[e].prefer_roads = roads;
        if !scripted {
            // The driven ego's route, planned again from where it is.
            if let Some(lp) = self.actors[e].state.lane {
                self.route = Some(RouteAsk {
                    join: lp,
                    ahead_m: 0.0,
                });
            }
        }
        Ok(())
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
