//! A car that stops before a scenario's point of interest never meets its danger, and a test in
//! which nothing happened must not pass: every shipped scenario's liveness check (a
//! `DistanceMonitor`, or `follow-lead-car`'s `closes_up`) fails such a car, and does not fail
//! the scenario's own system under test.

use paracosm_engine::sut::SutConfig;
use paracosm_generators::{Generator, Halton};
use paracosm_scenarios::{Scenario, TestOutcome};

/// Each built-in scenario, the distance from the ego's start to its point of interest, m, read
/// from the program (its comments say the same), and where the stopping car starts to brake,
/// m: early enough to come to rest short of the point on most of the scenario's surfaces
/// (from 12 m/s a full brake takes about 9 m on dry asphalt, 37 m at friction 0.2).
const POINTS_OF_INTEREST: &[(&str, f64, f64)] = &[
    // The crossing at 100 m; the ego starts at 10 m.
    ("pedestrian-crossing", 90.0, 75.0),
    // The lead stops at 51.25 m at the earliest (5 m/s, braking at 2 s at 10 m/s²); the ego
    // starts at 10 m and `closes_up` wants it within 15 m of the lead.
    ("follow-lead-car", 41.0, 10.0),
    // The slow car starts at 60 m, the ego at 10 m.
    ("fog-light", 50.0, 35.0),
    // The pedestrian's crossing on the south road, about 210 m round the loop.
    ("t-loop", 210.0, 150.0),
    // The junction (1, 1), the route's fourth, where the NPC cars cross.
    ("grid-world", 175.0, 150.0),
    // The cut-in ends by 5 s, 60 m at the ego's 12 m/s.
    ("cut-in", 60.0, 45.0),
    // The ring's entry, 45 m ahead.
    ("roundabout", 45.0, 30.0),
    // The crossing at 100 m; the ego starts at 10 m.
    ("family-of-worlds", 90.0, 50.0),
    // Where the third car, coming toward the ego, meets it.
    ("example-3-1", 72.0, 55.0),
    // The crossing on the bend at s = 150 m; the ego starts at s = 10 m.
    ("curve-pedestrian", 140.0, 120.0),
    // The junction, 45 m ahead.
    ("opendrive-junction", 45.0, 30.0),
];

/// The monitors that check that the ego got somewhere.
const LIVENESS: [&str; 2] = ["distance", "closes_up"];

/// `n` tests of `s` at the first Halton points of its space, with seeds 0, 1, ...
fn run_tests(s: &Scenario, n: usize) -> Vec<(String, TestOutcome)> {
    let points = Halton::new(s.space()).ask(n).unwrap();
    points
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let a = s.space().decode(p).unwrap();
            let o = s.run(&a, i as u64).unwrap();
            (format!("{a:?}"), o)
        })
        .collect()
}

/// How far the ego travelled, m (the `DistanceMonitor`'s measurement).
fn travelled_m(o: &TestOutcome) -> f64 {
    o.metrics
        .iter()
        .find(|(k, _)| *k == "distance_travelled_m")
        .map(|(_, v)| *v)
        .expect("every shipped scenario measures the distance travelled")
}

/// The liveness monitors that failed on their own (not cut short by another's failure).
fn liveness_failed(o: &TestOutcome) -> Vec<&str> {
    o.monitors
        .iter()
        .filter(|(n, v)| LIVENESS.contains(&n.as_str()) && !v.passed && !o.cut_short.contains(n))
        .map(|(n, _)| n.as_str())
        .collect()
}

#[test]
fn every_shipped_scenario_has_a_point_of_interest_here() {
    let mut named: Vec<&str> = POINTS_OF_INTEREST.iter().map(|(n, ..)| *n).collect();
    named.sort_unstable();
    let mut builtins = paracosm_scenarios::builtin_names();
    builtins.sort();
    assert_eq!(named, builtins);
}

#[test]
fn a_car_that_stops_before_the_point_of_interest_fails_every_shipped_scenario() {
    let mut decided_by_liveness = Vec::new();
    for &(name, poi_m, brake_at_m) in POINTS_OF_INTEREST {
        let own = paracosm_scenarios::builtin(name).unwrap();
        assert!(
            own.monitors().iter().any(|m| LIVENESS.contains(&m.name())),
            "{name} declares no liveness check"
        );
        let mut by_liveness = 0;
        for after_m in [0.0, brake_at_m] {
            let mut stops = own.clone();
            stops.set_sut(SutConfig::StopAfter {
                inner: Box::new(own.sut().clone()),
                after_m,
            });
            let runs = run_tests(&stops, 6);
            // On ice it may slide on into the danger; judged are the tests where it came to
            // rest short of the point, and those must be most of them.
            let short: Vec<_> = runs
                .iter()
                .filter(|(_, o)| travelled_m(o) < poi_m)
                .collect();
            assert!(
                short.len() * 2 > runs.len(),
                "{name}: stopping after {after_m} m, only {} of {} tests came to rest before \
                 {poi_m} m",
                short.len(),
                runs.len()
            );
            for (values, o) in &short {
                // Failed by the liveness check, or by something else first (a car that drives
                // into the parked ego), which cut the check short.
                let cut = o.cut_short.iter().any(|n| LIVENESS.contains(&n.as_str()));
                assert!(
                    !o.passed() && (!liveness_failed(o).is_empty() || cut),
                    "{name}: a car that stopped at {:.1} m was not failed by its liveness check \
                     ({values}): {:?}",
                    travelled_m(o),
                    o.monitors
                );
            }
            by_liveness += short
                .iter()
                .filter(|(_, o)| !liveness_failed(o).is_empty())
                .count();
        }
        if by_liveness > 0 {
            decided_by_liveness.push(name);
        }
    }
    // In `t-loop` the NPC car circles the loop (360 m, in at most 120 s of the 200) and runs
    // into a parked ego from behind: a collision fails it first. Everywhere else the
    // liveness check does.
    let mut rest: Vec<&str> = POINTS_OF_INTEREST.iter().map(|(n, ..)| *n).collect();
    rest.retain(|n| !decided_by_liveness.contains(n));
    assert_eq!(rest, ["t-loop"]);
}

#[test]
fn the_liveness_checks_do_not_fail_the_scenarios_own_systems() {
    for &(name, ..) in POINTS_OF_INTEREST {
        let own = paracosm_scenarios::builtin(name).unwrap();
        for (values, o) in run_tests(&own, 8) {
            let failed = liveness_failed(&o);
            let others_passed = o
                .monitors
                .iter()
                .all(|(n, v)| v.passed || LIVENESS.contains(&n.as_str()));
            assert!(
                failed.is_empty() || !others_passed,
                "{name}: {} failed only {failed:?} ({values}): {:?}",
                own.sut().name(),
                o.monitors
            );
        }
    }
}
