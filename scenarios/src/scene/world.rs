//! A finished scene as the engine's world for its test ([`Scene::world`]).

use paracosm_engine::rx::{Node, OpenStream, Value};
use paracosm_engine::{EnvironmentSpec, WorldSpec, DEFAULT_DT_S};

use super::{level_value, LoadError, LoadErrorKind, ParamValue, Scene};

impl Scene {
    /// The engine's world for this scene's test: its network (pieces whose friction is
    /// constant carry it; the others read their stream each step), its actors, environment,
    /// stream graph with the parameters that vary over time bound to this test's values, the
    /// streams published to the monitors (each actor output a monitor reads by name added as
    /// a probe) and its sensors.
    ///
    /// # Errors
    /// [`LoadErrorKind::Worlds`] when the scene places no ego vehicle, sets no light and fog,
    /// or its graph is invalid; [`LoadErrorKind::Declarations`] when a monitor reads a signal
    /// nothing publishes, or reads a car this world leaves out.
    pub fn world(&self) -> Result<WorldSpec, LoadError> {
        let worlds = |message: &str| LoadError::new(LoadErrorKind::Worlds, message);
        let (ego, _) = self
            .ego()
            .ok_or_else(|| worlds("the program places no AutonomousVehicle: nothing to test"))?;
        let (light, fog) = self
            .environment()
            .ok_or_else(|| worlds("the program has no World(...)"))?;
        let mut nodes = self.graph().clone();
        let published = self.published(&mut nodes)?;
        self.refuse_monitors_of_absent_cars(nodes.nodes(), &published)?;
        let graph = nodes.finish().map_err(|e| worlds(&e.to_string()))?;
        let streams = graph
            .bind(&self.over_time_streams())
            .map_err(|e| worlds(&e.to_string()))?;
        // Pieces whose friction is constant carry it; the others get it from their stream
        // each step.
        let mut network = self.roads().clone();
        let mut friction_streams = Vec::new();
        for &(piece, stream) in self.frictions() {
            match streams.nodes().get(stream.0) {
                Some(Node::Const(Value::Num(mu))) => network
                    .set_friction(piece, *mu)
                    .map_err(|e| LoadError::new(LoadErrorKind::Worlds, engine_reason(e)))?,
                _ => friction_streams.push((piece, stream)),
            }
        }
        Ok(WorldSpec {
            dt_s: DEFAULT_DT_S,
            network,
            frictions: friction_streams,
            ego: ego.clone(),
            pedestrians: self.pedestrians().values().cloned().collect(),
            cars: self.cars().values().cloned().collect(),
            obstacles: self.obstacles().values().cloned().collect(),
            environment: EnvironmentSpec { light, fog },
            streams,
            published,
            sensors: self.sensors().to_vec(),
        })
    }

    /// The streams of the parameters that vary over time, by declaration index, for
    /// [`paracosm_engine::rx::Graph::bind`]; constant ones get an unused placeholder.
    fn over_time_streams(&self) -> Vec<OpenStream> {
        (0..self.params().len())
            .filter_map(|k| self.param_value(k))
            .map(|v| match v {
                ParamValue::Over(s) => s,
                ParamValue::Level(l) => OpenStream::Constant(level_value(&l)),
            })
            .collect()
    }
}

/// The reason an engine error gives, without the engine's prefix for an invalid world.
pub fn engine_reason(e: paracosm_engine::EngineError) -> String {
    match e {
        paracosm_engine::EngineError::InvalidWorld(reason) => reason,
        other => other.to_string(),
    }
}
