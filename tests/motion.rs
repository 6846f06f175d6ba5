//! One source of truth for motion: every actor of every shipped scenario, every `examples/`
//! program and the generated programs of `tests/scenarios/motion/` (lane changes on straights
//! and bends, junction turns, roundabout circuits, pedestrians) reports, at every step, the
//! motion it makes. Read as a program reads them (`Simulation::read`, the probes behind
//! `a.pos`, `a.vel`, `a.speed`, `a.heading`):
//! - its velocity is its move over the last step: `|vel − Δpos/Δt| ≤ 1e-9 m/s` for NPC cars
//!   and pedestrians (their velocity is measured so), `≤ 0.05 m/s` for the ego vehicle (a
//!   rigid body integrated by rapier);
//! - its speed is the size of its velocity (negative backwards: the ego, a reversed car);
//! - its heading is continuous and turns no faster than the actor can: an NPC car at most
//!   `v / MIN_PATH_RADIUS_M` (4 m, the tightest lane path) plus the turn of a lane change,
//!   the ego at most `v / 5.3 m` (its steering limit), a pedestrian never (it walks a
//!   straight line, facing its target).

mod common;

use std::path::{Path, PathBuf};

use paracosm_engine::behaviour::{ActorRef, Output};
use paracosm_engine::network::{wrap, MIN_PATH_RADIUS_M};
use paracosm_engine::rx::Value;
use paracosm_engine::sut::SutConfig;
use paracosm_engine::Simulation;
use paracosm_generators::Strategy;

/// The ego vehicle's tightest turn, m (its 0.5 rad steering limit on its wheelbase; the
/// comment at `JUNCTION_APRON_M` gives the same 5.3 m).
const EGO_MIN_RADIUS_M: f64 = 5.3;

/// Simulated seconds checked per test (shorter than the longest horizons, to keep the suite
/// quick).
const CHECK_S: f64 = 12.0;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).to_path_buf()
}

fn star_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            star_files(&p, out);
        } else if p.extension().is_some_and(|e| e == "star") {
            out.push(p);
        }
    }
}

/// One actor's outputs at one step.
#[derive(Debug, Clone, Copy)]
struct Reading {
    pos: [f64; 3],
    vel: [f64; 3],
    speed: f64,
    heading: f64,
    collided: bool,
}

fn read(sim: &Simulation, actor: ActorRef) -> Option<Reading> {
    let vec = |o| match sim.read(actor, o) {
        Value::Vec3(v) => Some(v),
        _ => None,
    };
    let num = |o| sim.read(actor, o).as_num();
    Some(Reading {
        pos: vec(Output::Pos)?,
        vel: vec(Output::Vel)?,
        speed: num(Output::Speed)?,
        heading: num(Output::Heading)?,
        collided: matches!(sim.read(actor, Output::Collided), Value::Bool(true)),
    })
}

/// The worst figures over one program's tests, for the message.
#[derive(Debug, Default)]
struct Worst {
    steps: usize,
    vel_error: f64,
    /// The largest yaw rate over its limit, as a share of it.
    yaw_share: f64,
    /// The largest angle between a car's heading and the way it moves, rad.
    slip: f64,
}

/// Runs `tests` tests of the program at `path` (Halton points; `aeb` drives, whatever the
/// program's system: motion does not depend on it) and checks every actor at every step.
fn check_program(path: &Path, tests: usize) -> Worst {
    let scenario = paracosm_scenarios::load(path.to_str().unwrap())
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let points = Strategy::Halton
        .build(scenario.space(), 0)
        .unwrap()
        .ask(tests)
        .unwrap();
    let mut worst = Worst::default();
    let name = path
        .strip_prefix(root())
        .unwrap_or(path)
        .display()
        .to_string();
    for (k, point) in points.iter().enumerate() {
        let assignment = scenario.space().decode(point).unwrap();
        scenario
            .with_world(&assignment, &mut |spec, host| {
                let mut sim = Simulation::new(spec).unwrap();
                let mut sut = SutConfig::builtin("aeb").unwrap().build();
                sut.reset(0).unwrap();
                let dt = spec.dt_s;
                let actors: Vec<ActorRef> = std::iter::once(ActorRef::Ego)
                    .chain(sim.pedestrians().map(ActorRef::Pedestrian))
                    .chain(sim.cars().map(ActorRef::Car))
                    .collect();
                let mut last: Vec<Option<Reading>> = vec![None; actors.len()];
                let steps = ((CHECK_S.min(scenario.horizon_s())) / dt).round() as usize;
                for step in 0..=steps {
                    if sim.evaluate(host).is_err() {
                        break;
                    }
                    let now: Vec<Option<Reading>> = actors.iter().map(|&a| read(&sim, a)).collect();
                    // Contacts move bodies by impulses: the check ends at the first one.
                    if now.iter().flatten().any(|r| r.collided) {
                        break;
                    }
                    for (j, (&actor, r)) in actors.iter().zip(&now).enumerate() {
                        let Some(r) = r else { continue };
                        let at =
                            || format!("{name} test {k} {assignment:?}: {actor:?} at step {step}");
                        let norm = r.vel[0].hypot(r.vel[1]).hypot(r.vel[2]);
                        let speed_ok = match actor {
                            ActorRef::Ego => (r.speed.abs() - norm).abs() <= 1e-9 * norm.max(1.0),
                            _ => (r.speed.abs() - norm).abs() <= 1e-9 * norm.max(1.0),
                        };
                        assert!(speed_ok, "{}: speed {} but |vel| {norm}", at(), r.speed);
                        let Some(p) = last[j] else { continue };
                        let moved = [0, 1, 2].map(|i| (r.pos[i] - p.pos[i]) / dt);
                        let err = [0, 1, 2]
                            .map(|i| r.vel[i] - moved[i])
                            .iter()
                            .map(|e| e * e)
                            .sum::<f64>()
                            .sqrt();
                        let tolerance = if actor == ActorRef::Ego { 0.05 } else { 1e-9 };
                        assert!(
                            err <= tolerance,
                            "{}: vel {:?} but it moved {moved:?} m/s",
                            at(),
                            r.vel
                        );
                        worst.vel_error = worst.vel_error.max(err);
                        // A car moves the way it faces (to the chord of a 0.5 m leg of its
                        // tightest path, and a lane change's crab).
                        if matches!(actor, ActorRef::Car(_)) && norm > 0.5 {
                            let course = (-r.vel[2]).atan2(r.vel[0]);
                            let off = wrap(course - r.heading).abs();
                            worst.slip = worst.slip.max(off);
                            assert!(
                                off <= 0.07,
                                "{}: moves at {course} rad, faces {}",
                                at(),
                                r.heading
                            );
                        }
                        let yaw = wrap(r.heading - p.heading).abs() / dt;
                        let v = r.speed.abs().max(p.speed.abs());
                        let limit = match actor {
                            ActorRef::Ego => v / EGO_MIN_RADIUS_M + 0.05,
                            ActorRef::Pedestrian(_) | ActorRef::Obstacle(_) => 0.0,
                            // A lane change turns the car by atan(sideways / forward speed)
                            // on top of its path's curvature: at most 1 rad/s for the
                            // lane changes of these programs.
                            ActorRef::Car(_) => v / MIN_PATH_RADIUS_M + 1.0,
                        };
                        if limit > 0.0 {
                            worst.yaw_share = worst.yaw_share.max(yaw / limit);
                        }
                        assert!(
                            yaw <= limit + 1e-9,
                            "{}: heading {} -> {} rad in one step, {yaw} rad/s at {v} m/s (limit \
                             {limit})",
                            at(),
                            p.heading,
                            r.heading
                        );
                    }
                    last = now;
                    worst.steps += 1;
                    let control = sut.act(&sim.observation()).unwrap();
                    if sim.step(control, host).is_err() {
                        break;
                    }
                }
            })
            .unwrap_or_else(|e| panic!("{name}: {e}"));
    }
    worst
}

#[test]
fn every_actor_of_every_shipped_and_generated_program_moves_as_it_reports() {
    let mut files = Vec::new();
    for dir in ["scenarios", "examples", "tests/scenarios/motion"] {
        star_files(&root().join(dir), &mut files);
    }
    // Benchmark copies of shipped scenarios add nothing.
    files.retain(|f| !f.to_string_lossy().contains("/benches/"));
    assert!(files.len() >= 20, "{files:?}");
    let mut checked = 0;
    for f in &files {
        let motion = f.to_string_lossy().contains("motion");
        let w = check_program(f, if motion { 12 } else { 3 });
        assert!(w.steps > 0, "{}: no step checked", f.display());
        checked += w.steps;
        eprintln!(
            "{}: {} steps, worst velocity error {:.2e} m/s, yaw rate at most {:.1} % of the \
             limit, a car's course at most {:.4} rad off its heading",
            f.display(),
            w.steps,
            w.vel_error,
            100.0 * w.yaw_share,
            w.slip
        );
    }
    assert!(checked > 10_000, "{checked} steps");
}

/// Golden number: a car round a roundabout's ring turns at `v / R` (`R` its distance from
/// the centre there), within 2 % (it turned at up to 50 rad/s where its polyline met the
/// ring, and by 0.836 rad in one step at the entry and exit).
#[test]
fn the_yaw_rate_round_a_roundabout_ring_is_speed_over_radius() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("ring.star");
    std::fs::write(
        &path,
        r#"
w = World(light = 0.5, fog = 0.0)
rb = Roundabout(nlanes = 2, radius = 20.0)
e = RoadSegment(len = 60.0, nlanes = 2)
s = RoadSegment(len = 60.0, nlanes = 2)
wr = RoadSegment(len = 60.0, nlanes = 2)
n = RoadSegment(len = 60.0, nlanes = 2)
net = rb.connect((rb.ONE, e, e.ONE), (rb.TWO, s, s.ONE), (rb.THREE, wr, wr.ONE), (rb.FOUR, n, n.ONE))
v = AutonomousVehicle(loc = e.onLane(1, 50), sut = "aeb", speed = 0.0)
c = Car(loc = wr.onLane(-1, 40), speed = 6.0, route = ["left"])
w.place(net, v, c)
CollisionMonitor(v)
test(horizon = 20.0, offroad = False)
"#,
    )
    .unwrap();
    let scenario = paracosm_scenarios::load(path.to_str().unwrap()).unwrap();
    let a = common::no_params(&scenario);
    let mut on_ring = Vec::new();
    scenario
        .with_world(&a, &mut |spec, host| {
            let centre = spec.network.pieces()[0].pose;
            let mut sim = Simulation::new(spec).unwrap();
            let dt = spec.dt_s;
            let mut last: Option<(f64, f64)> = None;
            for _ in 0..(15.0 / dt) as usize {
                sim.evaluate(host).unwrap();
                let Value::Vec3(p) =
                    sim.read(ActorRef::Car(sim.cars().next().unwrap()), Output::Pos)
                else {
                    panic!()
                };
                let h = sim
                    .read(ActorRef::Car(sim.cars().next().unwrap()), Output::Heading)
                    .as_num()
                    .unwrap();
                let v = sim
                    .read(ActorRef::Car(sim.cars().next().unwrap()), Output::Speed)
                    .as_num()
                    .unwrap();
                let r = (p[0] - centre.x).hypot(p[2] - centre.z);
                if let Some((r0, h0)) = last {
                    // On the ring (16.75 m; the chords of its 0.5 m legs come 2 mm inside).
                    if (16.74..=16.7501).contains(&r) && (16.74..=16.7501).contains(&r0) {
                        on_ring.push((wrap(h - h0) / dt, v / 16.75));
                    }
                }
                last = Some((r, h));
                sim.step(paracosm_engine::Control::default(), host).unwrap();
            }
        })
        .unwrap();
    // Three quarters of a 16.75 m ring at 6 m/s, less the arcs onto and off it: about 2.5 s.
    assert!(on_ring.len() > 120, "{} steps on the ring", on_ring.len());
    // Away from where the arcs onto and off the ring meet it (their turn is the other way).
    let n = on_ring.len();
    let worst = on_ring[5..n - 5]
        .iter()
        .map(|(yaw, expected)| (yaw - expected).abs() / expected)
        .fold(0.0, f64::max);
    eprintln!(
        "{n} steps on the ring, yaw rate within {:.3} % of v/R",
        100.0 * worst
    );
    for &(yaw, expected) in &on_ring[5..n - 5] {
        assert!(
            (yaw - expected).abs() <= 0.02 * expected,
            "yaw rate {yaw} rad/s, v/R {expected}"
        );
    }
}
