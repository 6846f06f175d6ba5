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
            params: _, // the values themselves
            scope: _,  // the same values, for constraint checks
            road_network,
            entities,
            init,
            stories,
            stop,
            notes,
        } = &*self.0;
        *file == b.file
            && *version == b.version
            && *road_network == b.road_network
            && *entities == b.entities
            && *init == b.init
            && *stories == b.stories
            && *stop == b.stop
            && *notes == b.notes
    }

    fn as_any(&self) -> &dyn std::any::Any {
        self
    }
}
