//! The contract between a front end (a Starlark program, an OpenSCENARIO file, a Rust
//! function) and the rest of paracosm: a front end knows its open parameters, builds the
//! [`Scene`] of each test, and says what it read and what it found at load. Everything a
//! campaign judges a test by (its monitors, system under test, horizon and failure-map axes)
//! is read from the scenes by [`crate::Scenario::new`], the one constructor of a scenario.

use std::sync::Arc;

use paracosm_engine::rx::Host;
use paracosm_generators::{Assignment, ParamSpace};

use crate::scenario::{CameraOnly, InputFile, Warning};
use crate::scene::Scene;
use crate::ScenarioError;

/// A front end: the open parameters of a family of tests and the scene of each (paper §3.1:
/// a test case closes every open stream).
pub trait FrontEnd: Send + Sync {
    /// The open parameters, one coordinate each (a parameter that varies over time has
    /// several), named as the front end's file names them.
    fn space(&self) -> &ParamSpace;

    /// Builds the scene for `assignment` (`None`: the scene of the values the file declares,
    /// or each parameter's representative value, as a load probes it) and calls `run` with
    /// it and a host for its lambdas (a Starlark program's: each test gets its own
    /// evaluation of the program; an OpenSCENARIO file's: its storyboard), for the duration
    /// of the test.
    ///
    /// # Errors
    /// [`ScenarioError::MissingParam`] for an assignment that lacks a parameter;
    /// [`ScenarioError::Load`] or [`ScenarioError::Engine`] when these values give an
    /// impossible scene.
    fn with_scene(
        &self,
        assignment: Option<&Assignment>,
        run: &mut dyn FnMut(&Scene, &mut dyn Host),
    ) -> Result<(), ScenarioError>;

    /// What the front end read: its name, description, text and files.
    fn source(&self) -> Source;

    /// What the front end's own analyses found at load (see [`Findings`]).
    fn findings(&self) -> Findings;
}

/// What a front end read ([`FrontEnd::source`]).
#[derive(Debug, Clone, Default)]
pub struct Source {
    /// The scenario's name, e.g. `pedestrian-crossing` or `cut-in.xosc`.
    pub name: String,
    /// One-line description.
    pub description: String,
    /// The program or scenario text it was loaded from (empty for a scenario written in
    /// Rust): part of a campaign's fingerprint.
    pub text: Arc<str>,
    /// The files it read (maps, variation file, scenario, catalogs) with their SHA-256.
    pub files: Vec<InputFile>,
    /// The vehicle the system under test drives, as the summary names it, when the file
    /// chose it among its entities (OpenSCENARIO: `Ego, 5 × 2 × 1.8 m`); `None` for a
    /// program's `AutonomousVehicle`.
    pub ego: Option<String>,
    /// Whether a campaign's failure map is drawn over the two parameters its triage ranks
    /// most relevant, the scene's axes being the fallback (a file that names no axes).
    pub map_axes_by_relevance: bool,
}

/// What a front end's analyses found at load ([`FrontEnd::findings`]).
#[derive(Debug, Clone, Default)]
pub struct Findings {
    /// What the scenario loads with but checks or varies less than it seems to.
    pub warnings: Vec<Warning>,
    /// The coordinates of the space that nothing reads (by name): sampled and recorded,
    /// but left out of coverage.
    pub unused_params: Vec<String>,
    /// The open parameters that only a camera sees.
    pub camera_only: Vec<CameraOnly>,
}

/// Scenes declared by a Rust function, whose streams call no lambda: it receives an empty
/// scene whose open parameters take the test's values by name ([`Scene::for_assignment`])
/// and declares the test into it. Its space is read from the scene the function declares
/// with representative values ([`RustScenes::new`]).
pub struct RustScenes {
    build: SceneFn,
    space: ParamSpace,
    name: String,
    description: String,
    findings: Findings,
}

/// A Rust function that declares a scenario's scene into the empty scene it receives.
pub type SceneFn = fn(Scene) -> Result<Scene, ScenarioError>;

impl RustScenes {
    /// The front end of the scenes `build` declares, called `name`.
    ///
    /// # Errors
    /// What `build` returns; [`ScenarioError::Language`] for an open parameter without a
    /// name or one that varies over time (a Rust scene declares constant parameters);
    /// [`ScenarioError::Space`] for an invalid space.
    pub fn new(name: &str, description: &str, build: SceneFn) -> Result<Self, ScenarioError> {
        let probe = build(Scene::new(None))?;
        let mut params = Vec::new();
        let mut sites = Vec::new();
        for d in probe.params() {
            let bad = |why: &str| {
                ScenarioError::Language(format!("the parameter declared at {}: {why}", d.site))
            };
            let name = d.name.as_deref().ok_or_else(|| bad("it has no name"))?;
            if d.over_time != crate::scene::OverTime::Constant {
                return Err(bad(
                    "it varies over time, which a Rust scene does not declare",
                ));
            }
            sites.push((name.to_owned(), d.site.to_string()));
            params.push(match &d.domain {
                paracosm_generators::Domain::Interval { lo, hi } => {
                    paracosm_generators::Param::interval(
                        name,
                        *lo,
                        *hi,
                        d.unit.as_deref().unwrap_or(""),
                    )
                }
                paracosm_generators::Domain::Levels(levels) => {
                    paracosm_generators::Param::levels(name, levels.clone())
                }
            });
        }
        let mut scenes = RustScenes {
            build,
            space: ParamSpace::new(params)?,
            name: name.to_owned(),
            description: description.to_owned(),
            findings: Findings::default(),
        };
        // What each parameter changes, as a program's load finds it.
        let horizon_s = (probe.settings().horizon_s).unwrap_or(crate::scene::DEFAULT_HORIZON_S);
        scenes.findings = crate::analysis::findings_of(&scenes, &sites, horizon_s);
        Ok(scenes)
    }
}

impl FrontEnd for RustScenes {
    fn space(&self) -> &ParamSpace {
        &self.space
    }

    fn with_scene(
        &self,
        assignment: Option<&Assignment>,
        run: &mut dyn FnMut(&Scene, &mut dyn Host),
    ) -> Result<(), ScenarioError> {
        let empty = match assignment {
            Some(a) => Scene::for_assignment(a),
            None => Scene::new(None),
        };
        let scene = (self.build)(empty)?;
        run(&scene, &mut paracosm_engine::rx::NoHost);
        Ok(())
    }

    fn source(&self) -> Source {
        Source {
            name: self.name.clone(),
            description: self.description.clone(),
            ..Source::default()
        }
    }

    fn findings(&self) -> Findings {
        self.findings.clone()
    }
}

#[cfg(test)]
mod tests {
    use paracosm_generators::{Point, Value};

    use crate::reference::{self, TRIGGER_DISTANCE, WALKING_SPEED};
    use crate::scene::ParamValue;
    use crate::scene::{Scene, Site};
    use crate::{MonitorSpec, Scenario, ScenarioError};

    /// A walking speed above which a scene judges one more thing, m/s.
    const FAST_MPS: f64 = 5.0;

    /// The pedestrian study, whose scenes of walking speeds above [`FAST_MPS`] add a monitor
    /// that no test passes: the ego must travel 1,000 km.
    fn study_judging_fast_walkers_more(scene: Scene) -> Result<Scene, ScenarioError> {
        let mut scene = reference::scene(scene)?;
        let speed = match scene.param_value(0) {
            Some(ParamValue::Level(Value::Real(v))) => v,
            other => panic!("the study declares the walking speed first, got {other:?}"),
        };
        if speed > FAST_MPS {
            scene.add_monitor(
                MonitorSpec::Distance {
                    name: "far".into(),
                    min_distance_m: 1e6,
                },
                Site::of("front_end.rs"),
            );
        }
        Ok(scene)
    }

    #[test]
    fn scenario_new_reads_the_contract_from_the_declared_values_scene() {
        let s = Scenario::from_scenes("fast", "", study_judging_fast_walkers_more).unwrap();
        let probe = study_judging_fast_walkers_more(Scene::new(None)).unwrap();
        let expected = crate::monitors_of(&probe, "").unwrap();
        assert_eq!(s.monitors(), &expected[..]);
        assert_eq!(s.horizon_s(), reference::HORIZON_S);
        assert_eq!(Some(s.sut()), probe.ego().map(|(_, sut)| sut));
        assert_eq!(s.map_axes(), [WALKING_SPEED, TRIGGER_DISTANCE]);
    }

    #[test]
    fn each_test_is_judged_by_its_own_scenes_monitors() {
        let s = Scenario::from_scenes("fast", "", study_judging_fast_walkers_more).unwrap();
        for speed in [1.0, 8.0] {
            let u = |v: f64, (lo, hi): (f64, f64)| (v - lo) / (hi - lo);
            let a = s
                .space()
                .decode(&Point {
                    discrete: vec![],
                    continuous: vec![
                        u(speed, reference::WALKING_SPEED_RANGE_MPS),
                        u(30.0, reference::TRIGGER_DISTANCE_RANGE_M),
                    ],
                })
                .unwrap();
            let out = s.run(&a, 0).unwrap();
            let names: Vec<&str> = out.monitors.iter().map(|(n, _)| n.as_str()).collect();
            println!("walking speed {speed} m/s: judged by {names:?}");
            let far = out.monitors.iter().find(|(n, _)| n == "far");
            assert_eq!(far.is_some(), speed > FAST_MPS, "{names:?}");
            if let Some((_, verdict)) = far {
                assert!(!verdict.passed, "1,000 km in 15 s");
            }
        }
    }
}
