use std::ops::ControlFlow;

use paracosm_engine::rx::{Host, HostError};
use paracosm_engine::sut::SutConfig;
use paracosm_engine::{
    CameraFrame, CameraSpec, Control, EgoState, Simulation, Snapshot, SnapshotParts, WorldSpec,
};
use paracosm_generators::Assignment;
use paracosm_oracles::{Frame, Monitor, Signals, Verdict};

use crate::{MonitorSpec, Scenario, ScenarioError};

/// Names of the signals the runner publishes to monitors each step (defined with the scene
/// model, [`crate::scene::builtin_signals`]).
pub use crate::scene::builtin_signals as signal;

/// The result of one test.
#[derive(Debug, Clone, PartialEq)]
pub struct TestOutcome {
    /// Each monitor's name and verdict, in the scenario's order.
    pub monitors: Vec<(String, Verdict)>,
    /// The monitors whose observation was cut short: the test stopped early because another
    /// monitor failed while these had not settled, so their verdicts cover the run up to
    /// then only. Empty when the test ran to its horizon or every monitor had settled.
    pub cut_short: Vec<String>,
    /// Measurements: the monitors' metrics (e.g. `min_distance_m`, `distance_travelled_m`),
    /// then `time_to_failure_s` when a monitor failed and `simulated_s`.
    pub metrics: Vec<(&'static str, f64)>,
    /// What the program printed during the test (Starlark's `print`, in the program and in
    /// its lambdas), in order; never written to stdout during a campaign.
    pub log: Vec<String>,
}

impl TestOutcome {
    /// Whether every monitor passed.
    pub fn passed(&self) -> bool {
        self.monitors.iter().all(|(_, v)| v.passed)
    }

    /// The smallest robustness over the monitors (`+inf` with none), but those cut short
    /// ([`TestOutcome::cut_short`]).
    pub fn robustness(&self) -> f64 {
        self.monitors
            .iter()
            .filter(|(n, _)| !self.cut_short.contains(n))
            .map(|(_, v)| v.robustness)
            .fold(f64::INFINITY, f64::min)
    }
}

/// Sets the runner's signals from `snap`; those `parts` leaves out (no monitor reads them)
/// are not set, so a monitor that read one would find it missing, never a NaN.
fn publish(snap: &Snapshot, parts: SnapshotParts, out: &mut Signals) {
    out.set(signal::EGO_X_M, snap.ego.pos_m[0]);
    out.set(signal::EGO_Z_M, snap.ego.pos_m[2]);
    out.set(signal::EGO_SPEED_MPS, snap.ego.speed_mps);
    out.set_bool(signal::EGO_CONTACT, snap.ego_contact);
    out.set(signal::EGO_SEPARATION_M, snap.min_separation_m);
    if parts.ttc {
        out.set(signal::EGO_TTC_S, snap.ttc_s);
    }
    out.set_bool(signal::EGO_OFFROAD, snap.ego_off_road);
    out.set(signal::EGO_ROAD_EDGE_M, snap.ego_road_edge_m);
    if parts.lane_offset {
        out.set(signal::EGO_LANE_OFFSET_M, snap.ego_lane_offset_m);
    }
    out.set(signal::FOG, snap.fog);
    out.set(signal::LIGHT, snap.light);
}

/// A stream the world publishes by name, with the names of its components when it carries
/// vectors (made once per test, not per step).
struct Published {
    name: String,
    components: [String; 3],
    id: paracosm_engine::rx::StreamId,
    /// For the stream of a `Monitor` or an `Assert`: whether it must carry bools (`Assert`)
    /// rather than numbers (`Monitor`).
    judged: Option<bool>,
}

/// Sets each published stream's latest value as a signal: a number as is, a bool as 0 or 1,
/// a vector as `name.x`, `name.y`, `name.z`; a stream with no event yet is left unset.
///
/// # Errors
/// [`ScenarioError::Language`] for a stream carrying something else (a string, a tuple).
fn publish_streams(
    sim: &Simulation,
    published: &[Published],
    out: &mut Signals,
) -> Result<(), ScenarioError> {
    use paracosm_engine::rx::Value as Rx;
    for p in published {
        if let (Some(bools), Some(value)) = (p.judged, sim.current(p.id)) {
            if let Some(why) = crate::scenario::judged_kind_error(value, bools) {
                let m = p.name.strip_prefix("monitor:").unwrap_or(&p.name);
                return Err(ScenarioError::Language(format!(
                    "at t = {:.3} s, monitor `{m}`: {why}",
                    sim.t_s()
                )));
            }
        }
        match sim.current(p.id) {
            None => out.unset(&p.name),
            Some(Rx::Num(x)) => out.set_named(&p.name, *x),
            Some(Rx::Bool(b)) => out.set_named(&p.name, f64::from(u8::from(*b))),
            Some(Rx::Vec3(v)) => {
                for (c, x) in p.components.iter().zip(v) {
                    out.set_named(c, *x);
                }
            }
            Some(other) => {
                let what = match p.name.strip_prefix("monitor:") {
                    Some(m) => format!("the stream of monitor `{m}`"),
                    None => format!("signal `{}`", p.name),
                };
                return Err(ScenarioError::Language(format!(
                    "at t = {:.3} s, {what} carried {}; monitors and signals read numbers, \
                     bools and vectors",
                    sim.t_s(),
                    paracosm_engine::rx::describe(other)
                )));
            }
        }
    }
    Ok(())
}

/// What judges one test: its scene's monitors ([`crate::scenario::monitors_of`]) and its
/// horizon, s.
struct Judged {
    monitors: Vec<MonitorSpec>,
    horizon_s: f64,
}

/// The monitors of one test and which of them have settled their verdict.
struct Watch {
    monitors: Vec<Box<dyn Monitor>>,
    settled: Vec<bool>,
    signals: Signals,
    published: Vec<Published>,
    /// The costlier runner signals some monitor reads.
    parts: SnapshotParts,
}

impl Watch {
    /// Feeds one snapshot to every monitor that has not settled yet. Returns whether the test
    /// may stop: every monitor has settled, or one has settled as failed. Monitors are
    /// independent: one settling (passed) never stops the others observing. A test without
    /// monitors runs to its horizon.
    fn observe(
        &mut self,
        sim: &Simulation,
        on_step: Option<&mut &mut dyn FnMut(&Snapshot)>,
    ) -> Result<bool, ScenarioError> {
        let snap = match on_step {
            Some(f) => {
                let snap = sim.snapshot();
                f(&snap);
                snap
            }
            None => sim.snapshot_of(self.parts),
        };
        publish(&snap, self.parts, &mut self.signals);
        publish_streams(sim, &self.published, &mut self.signals)?;
        let frame = Frame {
            t_s: snap.t_s,
            signals: &self.signals,
        };
        let mut failed = false;
        for (m, settled) in self.monitors.iter_mut().zip(&mut self.settled) {
            if *settled {
                continue;
            }
            if let ControlFlow::Break(()) = m.observe(&frame) {
                *settled = true;
                failed |= !m.verdict().passed;
            }
        }
        Ok(failed || (!self.settled.is_empty() && self.settled.iter().all(|&s| s)))
    }
}

/// One camera frame with what the system under test did on seeing the world: what
/// [`RunOptions::on_sample`] receives (a training sample of `paracosm-fuzz dataset`).
#[derive(Debug, Clone, Copy)]
pub struct Sample<'a> {
    /// The frame (RGB, depth, labels), taken at this step.
    pub frame: &'a CameraFrame,
    /// The camera that took it: the system under test's own when it has one, else
    /// [`RunOptions::camera`].
    pub camera: &'a CameraSpec,
    /// The ego vehicle's state at the frame.
    pub ego: EgoState,
    /// The control the system under test answered for this step (or the answer it holds
    /// between decisions), or its [`Sut::label`](paracosm_engine::sut::Sut::label) when it
    /// has one (a teacher's answer while a learner drives): the label of a training sample.
    pub control: Control,
    /// The control the vehicle applies from this step on: [`Sample::control`], or what
    /// [`RunOptions::perturb`] made of it.
    pub applied: Control,
}

/// Extras for one run: a camera to watch it with, and callbacks for every camera frame
/// (what `paracosm-fuzz replay --frames` and `paracosm-fuzz dataset` use).
#[derive(Default)]
pub struct RunOptions<'a> {
    /// A camera to mount when the system under test has none (frames for looking at; the
    /// system does not see them). Ignored when the system has its own camera.
    pub camera: Option<CameraSpec>,
    /// Called with every frame the camera takes.
    pub on_frame: Option<&'a mut dyn FnMut(&CameraFrame)>,
    /// Called with every frame the camera takes, with the ego's state and the control the
    /// system under test applies at that step.
    pub on_sample: Option<&'a mut dyn FnMut(&Sample<'_>)>,
    /// Called each time the system under test decides, with the simulated time (s) and its
    /// answer; the vehicle applies what it returns until the next decision. For noise
    /// injection into training data (DART: Laskey et al. 2017, "DART: Noise Injection for
    /// Robust Imitation Learning"): the vehicle drifts off the teacher's path and the
    /// teacher's answers, recorded as [`Sample::control`], show how to recover. `None`: the
    /// answer is applied as it is.
    pub perturb: Option<&'a mut dyn FnMut(f64, Control) -> Control>,
    /// Called once with the test's world as it was built (its roads, actors and routes),
    /// before the first step: what `paracosm-fuzz export` writes out.
    pub on_world: Option<&'a mut dyn FnMut(&WorldSpec)>,
    /// Called with the state of the world at the start and after every physics step.
    pub on_step: Option<&'a mut dyn FnMut(&Snapshot)>,
}

/// Every how many physics steps something at `hz` happens (at least every step).
fn period_ticks(hz: Option<f64>, dt_s: f64) -> u64 {
    hz.map_or(1, |hz| ((1.0 / (hz * dt_s)).round() as u64).max(1))
}

impl Scenario {
    /// Runs one test: instantiates the world for `assignment`, resets the system under test with
    /// `seed`, and steps until the horizon or until a monitor settles its verdict.
    ///
    /// Deterministic: the same scenario, assignment and seed give bit-identical outcomes.
    ///
    /// # Errors
    /// [`ScenarioError`] when the world cannot be built or the system under test fails.
    pub fn run(&self, assignment: &Assignment, seed: u64) -> Result<TestOutcome, ScenarioError> {
        self.run_with(assignment, seed, &mut RunOptions::default())
    }

    /// As [`Scenario::run`], with a viewing camera and a frame callback.
    ///
    /// # Errors
    /// As [`Scenario::run`].
    pub fn run_with(
        &self,
        assignment: &Assignment,
        seed: u64,
        options: &mut RunOptions<'_>,
    ) -> Result<TestOutcome, ScenarioError> {
        let mut out = None;
        self.with_scene(assignment, &mut |scene, host| {
            // Each test is judged by its own scene's monitors, over its own horizon.
            let judged = crate::scenario::monitors_of(scene, self.name())
                .map_err(ScenarioError::Load)
                .map(|monitors| Judged {
                    monitors,
                    horizon_s: scene.horizon_s(),
                });
            out = Some(judged.and_then(|judged| {
                crate::scenario::world_of(scene)
                    .and_then(|spec| self.run_world(&spec, &judged, seed, host, options))
            }));
        })?;
        out.ok_or_else(|| ScenarioError::Language("no world was built".into()))?
    }

    /// The test's simulation of `spec`: with its sensors mounted, or with none when no system
    /// under test drives (a script places the ego at every step, `--scripted-ego`), since
    /// nothing would read them.
    ///
    /// # Errors
    /// [`ScenarioError::Engine`] when the world cannot be built.
    fn simulation(&self, spec: &WorldSpec) -> Result<Simulation, ScenarioError> {
        if matches!(self.sut(), SutConfig::Scripted) && !spec.sensors.is_empty() {
            let unsensed = WorldSpec {
                sensors: Vec::new(),
                ..spec.clone()
            };
            return Ok(Simulation::new(&unsensed)?);
        }
        Ok(Simulation::new(spec)?)
    }

    fn run_world(
        &self,
        spec: &WorldSpec,
        judged: &Judged,
        seed: u64,
        host: &mut dyn Host,
        options: &mut RunOptions<'_>,
    ) -> Result<TestOutcome, ScenarioError> {
        if let Some(f) = options.on_world.as_mut() {
            f(spec);
        }
        let mut sim = self.simulation(spec)?;
        let mut sut = self.sut().build();
        sut.reset(seed)?;
        let sensors = sut.sensors();
        // The system's own camera, or else the viewing camera, whose frames it never sees.
        let (camera, sut_sees) = match (sensors.camera, options.camera.clone()) {
            (Some(c), _) => (Some(c), true),
            (None, viewer) => (viewer, false),
        };
        // The camera renders only what its system reads, unless a callback watches the
        // frames (a person, a dataset): then every plane of the whole image.
        let watched = options.on_frame.is_some() || options.on_sample.is_some();
        let usage = if sut_sees && !watched {
            sensors.frame_use
        } else {
            paracosm_engine::FrameUse::ALL
        };
        let frame_every = match &camera {
            Some(c) => {
                sim.attach_camera_for(c, usage, seed)?;
                period_ticks(Some(c.rate_hz), spec.dt_s)
            }
            None => 0,
        };
        let control_every = period_ticks(sensors.control_hz, spec.dt_s);
        let monitors: Vec<Box<dyn Monitor>> = judged
            .monitors
            .iter()
            .map(|m| m.build(judged.horizon_s))
            .collect();
        let mut watch = watch(spec, &judged.monitors, monitors);
        let ticks = steps_covering(judged.horizon_s, spec.dt_s);
        // Streams are evaluated for the state a snapshot shows, so a published stream's value
        // and the runner's own signals describe the same moment.
        sim.evaluate(host)?;
        let mut stopped = watch.observe(&sim, options.on_step.as_mut())?;
        let mut tick = 0;
        let mut control = Control::default();
        let mut applied = Control::default();
        while !stopped && tick < ticks {
            if frame_every > 0 && tick % frame_every == 0 {
                if let (Some(f), Some(frame)) = (options.on_frame.as_mut(), sim.camera_frame()) {
                    f(frame);
                }
            }
            if tick % control_every == 0 {
                let mut obs = sim.observation();
                if !sut_sees {
                    // A viewing camera's frames are for people, not for the system.
                    obs.readings.retain(|(name, _)| *name != "camera");
                }
                let answer = sut.act(&obs)?;
                applied = match options.perturb.as_mut() {
                    Some(p) => p(tick as f64 * spec.dt_s, answer),
                    None => answer,
                };
                control = sut.label().unwrap_or(answer);
            }
            if frame_every > 0 && tick % frame_every == 0 {
                if let (Some(f), Some(frame), Some(camera)) = (
                    options.on_sample.as_mut(),
                    sim.camera_frame(),
                    camera.as_ref(),
                ) {
                    f(&Sample {
                        frame,
                        camera,
                        ego: sim.ego_state(),
                        control,
                        applied,
                    });
                }
            }
            sim.step(applied, host)?;
            tick += 1;
            sim.evaluate(host)?;
            stopped = watch.observe(&sim, options.on_step.as_mut())?;
            if host.ended() {
                // The scenario's own end (a storyboard's stop trigger): the monitors judge
                // the run as at a horizon.
                return Ok(outcome(watch, false, sim.t_s(), host.log()));
            }
        }

        if !stopped {
            return at_horizon(watch, sim.t_s(), host);
        }
        Ok(outcome(watch, tick < ticks, sim.t_s(), host.log()))
    }
}

/// The whole steps of `dt_s` (s) covering a horizon of `horizon_s` (s): a horizon between two
/// steps is rounded up (a horizon of 0.005 s is one step, not none), within 1e-9 of a step it
/// is that step.
fn steps_covering(horizon_s: f64, dt_s: f64) -> u64 {
    ((horizon_s / dt_s - 1e-9).ceil() as u64).max(1)
}

/// The outcome of a test that reached its horizon at `t_s` (s) before the scenario's own end:
/// the monitors' verdicts, unless every monitor passed and the host says the test did not
/// play (a storyboard still waiting to start its events, [`Host::finish`]).
///
/// # Errors
/// [`ScenarioError::Unplayed`] with the host's reason.
fn at_horizon(watch: Watch, t_s: f64, host: &mut dyn Host) -> Result<TestOutcome, ScenarioError> {
    let end = outcome(watch, false, t_s, Vec::new());
    if end.passed() {
        host.finish(t_s)
            .map_err(|HostError(message)| ScenarioError::Unplayed { t_s, message })?;
    }
    Ok(TestOutcome {
        log: host.log(),
        ..end
    })
}

/// The monitors of one test and what they read: the published streams, and the runner's
/// signals that only some monitors need.
fn watch(spec: &WorldSpec, specs: &[MonitorSpec], monitors: Vec<Box<dyn Monitor>>) -> Watch {
    Watch {
        settled: vec![false; monitors.len()],
        monitors,
        signals: Signals::new(),
        published: spec
            .published
            .iter()
            .map(|(name, id)| Published {
                components: [".x", ".y", ".z"].map(|c| format!("{name}{c}")),
                name: name.clone(),
                id: *id,
                judged: specs
                    .iter()
                    .filter_map(MonitorSpec::judged_stream)
                    .find(|(_, signal, _)| *signal == name)
                    .map(|(_, _, bools)| bools),
            })
            .collect(),
        parts: SnapshotParts {
            ttc: specs
                .iter()
                .any(|m| m.reads_runner_signal(signal::EGO_TTC_S)),
            lane_offset: specs
                .iter()
                .any(|m| m.reads_runner_signal(signal::EGO_LANE_OFFSET_M)),
        },
    }
}

/// The test's outcome from its monitors: `stopped_early` when a monitor ended it before the
/// horizon (a monitor not yet decided then is cut short), `simulated_s` the simulated time,
/// s, `log` what the program printed.
fn outcome(
    mut watch: Watch,
    stopped_early: bool,
    simulated_s: f64,
    log: Vec<String>,
) -> TestOutcome {
    if stopped_early {
        // Stopped early: a monitor that checks only every few frames may already be
        // decided by the frames it saw (an `Stl` violation since its last check).
        for (m, settled) in watch.monitors.iter_mut().zip(&mut watch.settled) {
            if !*settled && m.settle_now() {
                *settled = true;
            }
        }
    }
    let cut_short: Vec<String> = if stopped_early {
        watch
            .monitors
            .iter()
            .zip(&watch.settled)
            .filter(|(_, &settled)| !settled)
            .map(|(m, _)| m.name().to_owned())
            .collect()
    } else {
        Vec::new()
    };
    let monitors: Vec<(String, Verdict)> = watch
        .monitors
        .iter()
        .map(|m| (m.name().to_owned(), m.verdict()))
        .collect();
    let mut metrics: Vec<(&'static str, f64)> = monitors
        .iter()
        .flat_map(|(_, v)| v.metrics.iter().copied())
        .collect();
    // The test's failure time: the earliest of the monitors that failed it. A monitor that
    // passed may still carry a time (a `TimeToFailure` whose monitor failed after `minT`),
    // and one cut short did not fail the test.
    if let Some(ttf) = monitors
        .iter()
        .filter(|(n, v)| !v.passed && !cut_short.contains(n))
        .filter_map(|(_, v)| v.first_violation_s)
        .reduce(f64::min)
    {
        metrics.push(("time_to_failure_s", ttf));
    }
    metrics.push(("simulated_s", simulated_s));
    TestOutcome {
        monitors,
        cut_short,
        metrics,
        log,
    }
}

#[cfg(test)]
mod tests {
    use paracosm_generators::Point;

    use crate::reference::{self as pedestrian_crossing, TRIGGER_DISTANCE, WALKING_SPEED};

    fn run(speed: f64, trigger: f64) -> crate::TestOutcome {
        let s = pedestrian_crossing::scenario();
        let u = |v: f64, (lo, hi): (f64, f64)| (v - lo) / (hi - lo);
        let a = s
            .space()
            .decode(&Point {
                discrete: vec![],
                continuous: vec![
                    u(speed, pedestrian_crossing::WALKING_SPEED_RANGE_MPS),
                    u(trigger, pedestrian_crossing::TRIGGER_DISTANCE_RANGE_M),
                ],
            })
            .unwrap();
        assert_eq!(a.real(WALKING_SPEED).unwrap(), speed);
        assert!((a.real(TRIGGER_DISTANCE).unwrap() - trigger).abs() < 1e-9);
        s.run(&a, 1).unwrap()
    }

    #[test]
    fn slow_pedestrian_far_trigger_is_safe() {
        let o = run(1.0, 55.0);
        assert!(o.passed(), "{o:?}");
        assert!(o.robustness() > 0.0);
    }

    #[test]
    fn pedestrian_triggered_10_m_ahead_at_3_mps_is_hit_and_the_run_stops_early() {
        let o = run(3.0, 10.0);
        assert!(!o.passed(), "{o:?}");
        let (_, collision) = &o.monitors[0];
        assert!(!collision.passed && collision.robustness <= 0.0);
        let ttf = o
            .metrics
            .iter()
            .find(|(n, _)| *n == "time_to_failure_s")
            .unwrap()
            .1;
        let simulated = o
            .metrics
            .iter()
            .find(|(n, _)| *n == "simulated_s")
            .unwrap()
            .1;
        assert_eq!(ttf, simulated, "the run stops at the contact");
        assert!(simulated < pedestrian_crossing::HORIZON_S);
    }

    /// Requirement: the failure boundary is not a straight line. Along the vertical line
    /// walking_speed = 1 m/s the outcome goes safe -> collision -> safe; a single straight
    /// boundary would split any line into at most two runs.
    #[test]
    fn outcome_changes_twice_along_one_line_so_the_boundary_is_not_straight() {
        let outcomes: Vec<bool> = [6.0, 20.0, 50.0]
            .iter()
            .map(|&trigger| run(1.0, trigger).passed())
            .collect();
        assert_eq!(outcomes, [true, false, true]);
    }

    #[test]
    fn instantiate_uses_the_assignment() {
        let s = pedestrian_crossing::scenario();
        let a = s
            .space()
            .decode(&Point {
                discrete: vec![],
                continuous: vec![0.0, 0.5],
            })
            .unwrap();
        let w = s.instantiate(&a).unwrap();
        let value = |id: paracosm_engine::rx::StreamId| match &w.streams.nodes()[id.0] {
            paracosm_engine::rx::Node::Const(v) => v.as_num().unwrap(),
            n => panic!("{n:?}"),
        };
        assert_eq!(value(w.pedestrians[0].speed), 0.5);
        // The trigger distance is the constant zipped with the car's position.
        let dist = w.streams.nodes().iter().find_map(|n| match n {
            paracosm_engine::rx::Node::Zip(_, d) => Some(*d),
            _ => None,
        });
        assert_eq!(value(dist.unwrap()), 32.5);
    }
}
