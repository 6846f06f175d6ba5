//! What a test's storyboard reads ([`StoryInputs`]): the scenario as resolved with the test's
//! values, kept with its scene so that the load's analyses see a parameter that only the
//! storyboard reads (a speed, a trigger's distance, a route).

use std::sync::Arc;

use paracosm_openscenario::model as m;

use crate::scene::HostInputs;

/// The scenario resolved with one test's values.
#[derive(Debug)]
pub(crate) struct StoryInputs(pub(crate) Arc<m::Scenario>);

impl HostInputs for StoryInputs {
    /// The same when everything the storyboard and the scene's build read is equal: the map,
    /// the entities, the `Init`, the stories and the stop trigger. The parameters' own values
    /// (and the scope holding them) are not compared: a parameter that nothing reads changes
    /// only them. Every field is named, so a field added to the model fails to compile here
    /// until it is compared or said not to be.
    fn same_as(&self, other: &dyn HostInputs) -> bool {
        let Some(StoryInputs(b)) = other.as_any().downcast_ref::<StoryInputs>() else {
            return false;
        };
        let m::Scenario {
            file,
            version,
            carla,
            params: _, // the values themselves
            scope: _,  // the same values, for constraint checks
            road_network,
            entities,
            init,
            init_global,
            variables,
            stories,
            stop,
            notes,
            tilts,
        } = &*self.0;
        // A parameter that a condition reads while the test runs is read by the storyboard.
        let read_by_conditions = |a: &m::Scenario, b: &m::Scenario| {
            a.params
                .iter()
                .zip(&b.params)
                .all(|((d, va), (_, vb))| va == vb || !condition_reads(a, &d.name))
        };
        *file == b.file
            && *version == b.version
            && *carla == b.carla
            && *road_network == b.road_network
            && *entities == b.entities
            && *init == b.init
            && *init_global == b.init_global
            && *variables == b.variables
            && read_by_conditions(&self.0, b)
            && *stories == b.stories
            && *stop == b.stop
            && *notes == b.notes
            && *tilts == b.tilts
    }

    fn as_any(&self) -> &dyn std::any::Any {
        self
    }
}

/// Whether a `ParameterCondition` of `s` (in its stories or its stop trigger) reads the
/// parameter `name`.
fn condition_reads(s: &m::Scenario, name: &str) -> bool {
    let reads = |t: &m::Trigger| {
        t.0.iter()
            .flatten()
            .any(|c| matches!(&c.kind, m::ConditionKind::Parameter { name: n, .. } if n == name))
    };
    s.stop.as_ref().is_some_and(reads)
        || s.stories.iter().flat_map(|st| &st.acts).any(|act| {
            act.start.as_ref().is_some_and(reads)
                || act.stop.as_ref().is_some_and(reads)
                || act
                    .groups
                    .iter()
                    .flat_map(|g| &g.maneuvers)
                    .flat_map(|m| &m.events)
                    .any(|e| e.start.as_ref().is_some_and(reads))
        })
}
