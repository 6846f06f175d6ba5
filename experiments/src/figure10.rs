//! The paper's Figure 10 studies with learned drivers (PARACOSM §4.2.2): a changing
//! environment (10a), a longer horizon (10b) and other 3-D components (10c). Each runs a
//! scenario program of `experiments/scenarios/` whose system under test is a network of
//! `experiments/models/` (trained by `train_pilotnet` on data that `paracosm-fuzz dataset`
//! exported from `follow_red_train.star` and `loop_train.star`), and draws its figure.

use std::path::{Path, PathBuf};

use paracosm::report::plot::{self, Series, ValueMapLabels, ValuePoint, XyStyle};
use paracosm::{Campaign, Error, RunRecord};
use paracosm_generators::{Strategy, Value};
use paracosm_scenarios::{RunOptions, Sample, Scenario};

use crate::Result;

/// `experiments/scenarios/NAME`.
pub fn scenario_path(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenarios")
        .join(name)
}

fn load(name: &str) -> Result<Scenario> {
    Ok(paracosm_scenarios::load(
        &scenario_path(name).display().to_string(),
    )?)
}

fn campaign(scenario: &Scenario, budget: u64, jobs: usize) -> Campaign<'_> {
    Campaign {
        scenario,
        strategy: Strategy::Halton,
        seed: 0,
        budget,
        strength: 2,
        jobs,
        stop_at_first_failure: false,
        points: None,
        trace: None,
    }
}

/// A real parameter of a record (NaN when absent).
fn real(r: &RunRecord, name: &str) -> f64 {
    match r.params.as_ref().and_then(|a| a.get(name)) {
        Some(Value::Real(x)) => *x,
        _ => f64::NAN,
    }
}

/// Whether monitor `name` of `r` failed.
fn failed(r: &RunRecord, name: &str) -> bool {
    r.monitors.iter().any(|(n, m)| n == name && !m.passed)
}

/// One test of Figure 10a.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LightFogTest {
    /// Light intensity, `[0, 1]`.
    pub light: f64,
    /// Fog density, `[0, 1]`.
    pub fog: f64,
    /// Distance the ego vehicle covered, m (up to a collision, if one ended the test).
    pub distance_m: f64,
    /// Whether it collided.
    pub collision: bool,
}

/// What [`figure10a`] measured and wrote.
#[derive(Debug, Clone)]
pub struct Figure10a {
    /// Every test, in id order.
    pub tests: Vec<LightFogTest>,
    /// Tests that ended in `error` (none expected; counted so none is silently dropped).
    pub errors: usize,
    /// The PNG and SVG.
    pub plots: [PathBuf; 2],
}

/// The distance monitor's threshold in `fig10a_light_fog.star`, m.
const MIN_DISTANCE_M: f64 = 30.0;

/// Figure 10a: `budget` Halton tests of `fig10a_light_fog.star` (the `follow` network behind a
/// slow red car, light × fog open), the campaign in `dir/campaign/`, the map of distance
/// covered (colour) and collisions (red crosses) over light × fog in `dir/figure10a.{png,svg}`.
///
/// # Errors
/// When the scenario does not load, or a campaign or the plot cannot be written.
pub fn figure10a(budget: u64, jobs: usize, dir: &Path) -> Result<Figure10a> {
    let scenario = load("fig10a_light_fog.star")?;
    let report = campaign(&scenario, budget, jobs).run(&dir.join("campaign"), |_| {})?;
    let mut tests = Vec::new();
    let mut errors = 0;
    for r in &report.records {
        let Some((_, distance)) = r.monitors.iter().find(|(n, _)| n == "distance") else {
            errors += 1;
            continue;
        };
        tests.push(LightFogTest {
            light: real(r, "light"),
            fog: real(r, "fog"),
            distance_m: distance.robustness + MIN_DISTANCE_M,
            collision: failed(r, "collision"),
        });
    }
    let top = tests
        .iter()
        .map(|t| t.distance_m)
        .fold(1.0f64, f64::max)
        .ceil();
    let collisions = tests.iter().filter(|t| t.collision).count();
    let plots = plot::value_map(
        &dir.join("figure10a"),
        &ValueMapLabels {
            title: format!(
                "follow network behind a slow red car: {} tests, {collisions} collisions \
                 (trained at light 0.5, no fog)",
                tests.len()
            ),
            x: "light intensity".into(),
            y: "fog density".into(),
            value: "distance covered, m (to the collision if one ended the test)".into(),
            marked: "collision".into(),
        },
        ((0.0, 1.0), (0.0, 1.0), (0.0, top)),
        &tests
            .iter()
            .map(|t| ValuePoint {
                x: t.light,
                y: t.fog,
                value: t.distance_m,
                marked: t.collision,
            })
            .collect::<Vec<_>>(),
    )?;
    Ok(Figure10a {
        tests,
        errors,
        plots,
    })
}

/// One test of Figure 10b.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LoopTest {
    /// Fog density, `[0, 1]`.
    pub fog: f64,
    /// When the ego vehicle first left the driving surface, s; `None`: it stayed on it for
    /// the whole 200 s.
    pub time_to_failure_s: Option<f64>,
    /// Distance it covered, m, up to leaving the road or the time-out: under
    /// [`LOOP_MIN_DISTANCE_M`] on the road means it stopped or crawled.
    pub distance_m: f64,
}

/// The distance a `loop` test must cover in its 200 s to pass, m (the scenario's
/// `DistanceMonitor`): a network that stops stays on the road and must not pass.
pub const LOOP_MIN_DISTANCE_M: f64 = 1000.0;

/// What [`figure10b`] measured and wrote.
#[derive(Debug, Clone)]
pub struct Figure10b {
    /// Every test, in id order.
    pub tests: Vec<LoopTest>,
    /// Tests that ended in `error`.
    pub errors: usize,
    /// The PNG and SVG.
    pub plots: [PathBuf; 2],
}

/// The time-out of `fig10b_loop_fog.star`, s.
pub const LOOP_TIMEOUT_S: f64 = 200.0;

/// Figure 10b: `budget` Halton tests of `fig10b_loop_fog.star` (the `loop` network around a
/// loop of roads and T-intersections for up to 200 s, fog open), the campaign in
/// `dir/campaign/`, time to failure against fog density in `dir/figure10b.{png,svg}`.
/// `model`: another ONNX network (with its manifest beside it) in place of the shipped
/// `loop.onnx`, e.g. one of another training seed.
///
/// # Errors
/// When the scenario does not load, the model cannot be used ([`Error::BadInput`]), or a
/// campaign or the plot cannot be written.
pub fn figure10b(budget: u64, jobs: usize, dir: &Path, model: Option<&Path>) -> Result<Figure10b> {
    let mut scenario = load("fig10b_loop_fog.star")?;
    if let Some(m) = model {
        scenario.set_sut(
            paracosm_engine::sut::SutConfig::onnx(m)
                .map_err(|e| Error::BadInput(format!("--loop-onnx: {e}")))?,
        );
    }
    let report = campaign(&scenario, budget, jobs).run(&dir.join("campaign"), |_| {})?;
    let mut tests = Vec::new();
    let mut errors = 0;
    for r in &report.records {
        if r.status == paracosm::Status::Error {
            errors += 1;
            continue;
        }
        // When the off-road monitor first failed: the test's own `time_to_failure_s` is its
        // first failure of any monitor, and the distance monitor fails at the time-out.
        let ttf = r
            .monitors
            .iter()
            .find(|(n, _)| n == "time_to_failure")
            .and_then(|(_, m)| m.first_violation_s);
        let distance_m = r
            .monitors
            .iter()
            .find(|(n, _)| n == "distance")
            .map_or(f64::NAN, |(_, m)| m.robustness + LOOP_MIN_DISTANCE_M);
        tests.push(LoopTest {
            fog: real(r, "fog"),
            time_to_failure_s: ttf,
            distance_m,
        });
    }
    let (failed, survived): (Vec<&LoopTest>, Vec<&LoopTest>) =
        tests.iter().partition(|t| t.time_to_failure_s.is_some());
    let (drove, stopped): (Vec<&LoopTest>, Vec<&LoopTest>) = survived
        .iter()
        .partition(|t| t.distance_m >= LOOP_MIN_DISTANCE_M);
    let series: Vec<Series> = vec![
        (
            format!("left the road ({})", failed.len()),
            failed
                .iter()
                .map(|t| (t.fog, t.time_to_failure_s.unwrap_or(LOOP_TIMEOUT_S)))
                .collect(),
        ),
        (
            format!(
                "on the road at the 200 s time-out, {LOOP_MIN_DISTANCE_M:.0} m or more ({})",
                drove.len()
            ),
            drove.iter().map(|t| (t.fog, LOOP_TIMEOUT_S)).collect(),
        ),
        (
            format!(
                "on the road at 200 s, under {LOOP_MIN_DISTANCE_M:.0} m: stopped or crawled ({})",
                stopped.len()
            ),
            stopped.iter().map(|t| (t.fog, LOOP_TIMEOUT_S)).collect(),
        ),
    ];
    let plots = plot::xy_plot(
        &dir.join("figure10b"),
        (
            &format!(
                "loop network, {} tests: time to failure against fog (trained without fog)",
                tests.len()
            ),
            "fog density",
            "time to failure, s",
        ),
        ((0.0, 1.0), (0.0, LOOP_TIMEOUT_S * 1.12)),
        &series,
        XyStyle::Points,
    )?;
    Ok(Figure10b {
        tests,
        errors,
        plots,
    })
}

/// One case of Figure 10c: its name, its record and the ego's speed over time.
#[derive(Debug, Clone)]
pub struct ComponentCase {
    /// What differs from training, e.g. "red lead, oncoming red car".
    pub name: String,
    /// The lead car's colour.
    pub lead_color: String,
    /// Whether the oncoming red car was there.
    pub oncoming: bool,
    /// Whether the ego collided.
    pub collision: bool,
    /// `(t, speed)` at each camera frame (10 Hz), s and m/s.
    pub speed: Vec<(f64, f64)>,
}

/// What [`figure10c`] measured and wrote.
#[derive(Debug, Clone)]
pub struct Figure10c {
    /// The four cases: red or white lead, with or without the oncoming red car.
    pub cases: Vec<ComponentCase>,
    /// The PNG and SVG.
    pub plots: [PathBuf; 2],
}

/// Figure 10c: the four tests of `fig10c_components.star` (lead red or white, the oncoming
/// red car there or not; the `follow` network), each run once with its speed recorded at
/// every camera frame; the speed over time of all four in `dir/figure10c.{png,svg}`.
///
/// # Errors
/// When the scenario does not load, a test ends in error, or the plot cannot be written.
pub fn figure10c(dir: &Path) -> Result<Figure10c> {
    let scenario = load("fig10c_components.star")?;
    std::fs::create_dir_all(dir).map_err(|e| Error::write(dir, e))?;
    let run = campaign(&scenario, 1, 1);
    let space = scenario.space();
    let level = |param: &str, want: &Value| -> Result<u32> {
        let p = space
            .param(param)
            .ok_or_else(|| Error::Internal(format!("no parameter `{param}`")))?;
        match &p.domain {
            paracosm_generators::Domain::Levels(levels) => levels
                .iter()
                .position(|l| l == want)
                .map(|i| i as u32)
                .ok_or_else(|| Error::Internal(format!("`{param}` has no level {want:?}"))),
            _ => Err(Error::Internal(format!("`{param}` is not a VarEnum"))),
        }
    };
    let order: Vec<String> = space.discrete().map(|p| p.name.clone()).collect::<Vec<_>>();
    let mut cases = Vec::new();
    for (color, oncoming) in [
        ("red", false),
        ("red", true),
        ("white", false),
        ("white", true),
    ] {
        let mut discrete = Vec::new();
        for name in &order {
            discrete.push(match name.as_str() {
                "lead_color" => level(name, &Value::Text(color.into()))?,
                "oncoming" => level(name, &Value::Bool(oncoming))?,
                other => return Err(Error::Internal(format!("unexpected parameter `{other}`"))),
            });
        }
        let point = paracosm_generators::Point {
            discrete,
            continuous: Vec::new(),
        };
        let mut speed = Vec::new();
        let mut on_sample = |s: &Sample<'_>| speed.push((s.frame.t_s, s.ego.speed_mps));
        let record = run.run_one_with(
            cases.len() as u64,
            &point,
            &mut RunOptions {
                on_sample: Some(&mut on_sample),
                ..Default::default()
            },
        );
        if let Some(e) = &record.error {
            return Err(Error::Internal(format!(
                "{color} lead, oncoming {oncoming}: {e}"
            )));
        }
        let name = match (color, oncoming) {
            ("red", false) => "red lead (as trained)".to_owned(),
            ("red", true) => "red lead, oncoming red car".to_owned(),
            ("white", false) => "white lead".to_owned(),
            _ => "white lead, oncoming red car".to_owned(),
        };
        let collision = failed(&record, "collision");
        cases.push(ComponentCase {
            name: if collision {
                format!("{name}: collision")
            } else {
                name
            },
            lead_color: color.into(),
            oncoming,
            collision,
            speed,
        });
    }
    let top = cases
        .iter()
        .flat_map(|c| c.speed.iter().map(|p| p.1))
        .fold(1.0f64, f64::max);
    let series: Vec<Series> = cases
        .iter()
        .map(|c| (c.name.clone(), c.speed.clone()))
        .collect();
    let plots = plot::xy_plot(
        &dir.join("figure10c"),
        (
            "follow network: ego speed behind a lead car at 8 m/s",
            "time, s",
            "ego speed, m/s",
        ),
        ((0.0, 20.0), (0.0, (top * 1.3).ceil())),
        &series,
        XyStyle::Lines,
    )?;
    Ok(Figure10c { cases, plots })
}

/// One case of the Figure 10c sweep: the lead's colour and whether the oncoming car is there,
/// with what its tests did.
#[derive(Debug, Clone, PartialEq)]
pub struct SweepCase {
    /// The lead car's colour (`red`, as in training, or `white`).
    pub lead_color: String,
    /// Whether the oncoming red car was there.
    pub oncoming: bool,
    /// Tests of this case (errors excluded).
    pub tests: u64,
    /// Tests that ended in a collision.
    pub collisions: u64,
    /// Tests in which the ego covered less than the 45 m the scenario asks for: it fell far
    /// behind a moving lead (a follower covers about 55 m or more).
    pub fell_behind: u64,
    /// Mean distance covered, m.
    pub mean_distance_m: f64,
}

/// The distance monitor's threshold in `fig10c_sweep.star`, m.
const SWEEP_MIN_DISTANCE_M: f64 = 45.0;

/// Figure 10c over `budget` Halton tests of `fig10c_sweep.star` (the four cases of
/// [`figure10c`] over open lead speeds, 3–8 m/s, and gaps, 15–40 m), the campaign in `dir`;
/// returns the cases in the order red, red + oncoming, white, white + oncoming, and the
/// number of tests in error.
///
/// # Errors
/// When the scenario does not load or the campaign cannot be written.
pub fn figure10c_sweep(budget: u64, jobs: usize, dir: &Path) -> Result<(Vec<SweepCase>, usize)> {
    let scenario = load("fig10c_sweep.star")?;
    let report = campaign(&scenario, budget, jobs).run(dir, |_| {})?;
    let mut cases: Vec<SweepCase> = [
        ("red", false),
        ("red", true),
        ("white", false),
        ("white", true),
    ]
    .iter()
    .map(|&(c, o)| SweepCase {
        lead_color: c.into(),
        oncoming: o,
        tests: 0,
        collisions: 0,
        fell_behind: 0,
        mean_distance_m: 0.0,
    })
    .collect();
    let mut errors = 0;
    for r in &report.records {
        let param = |name: &str| r.params.as_ref().and_then(|a| a.get(name)).cloned();
        let (Some(Value::Text(color)), Some(Value::Bool(oncoming))) =
            (param("lead_color"), param("oncoming"))
        else {
            errors += 1;
            continue;
        };
        let Some((_, distance)) = r.monitors.iter().find(|(n, _)| n == "distance") else {
            errors += 1;
            continue;
        };
        let Some(case) = cases
            .iter_mut()
            .find(|c| c.lead_color == color && c.oncoming == oncoming)
        else {
            errors += 1;
            continue;
        };
        case.tests += 1;
        case.collisions += u64::from(failed(r, "collision"));
        case.fell_behind += u64::from(!distance.passed);
        case.mean_distance_m += distance.robustness + SWEEP_MIN_DISTANCE_M;
    }
    for c in &mut cases {
        c.mean_distance_m /= c.tests.max(1) as f64;
    }
    Ok((cases, errors))
}
