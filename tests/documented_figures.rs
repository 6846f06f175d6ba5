//! The documented numbers are the measured ones: each figure docs/systems-under-test.md and
//! LANGUAGE.md give about how the built-in actors move is read here from the running engine
//! (or from the constant it is), and the docs must state it as measured. A change to the
//! engine that moves a figure fails this test until the docs say the new figure.

use std::path::Path;

use paracosm_engine::network::{LANE_WIDTH_M, MIN_PATH_RADIUS_M};
use paracosm_engine::sut::SutConfig;
use paracosm_engine::{LidarSpec, Simulation, Size, VehicleParams, WorldSpec};

fn doc(name: &str) -> String {
    std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join(name)).unwrap()
}

/// Asserts that `file` says `phrase` (the figure in its words).
fn says(file: &str, phrase: &str) {
    let text = doc(file).split_whitespace().collect::<Vec<_>>().join(" ");
    assert!(
        text.contains(phrase),
        "{file} does not say \"{phrase}\" (the figure the engine gives)"
    );
}

/// The speed `aeb` holds on a clear straight road, m/s: its cruise control's setpoint is 12
/// m/s, and its proportional gain settles where the throttle balances the body's drag.
fn aeb_cruise_mps() -> f64 {
    let spec = WorldSpec::straight_road(3000.0, 10.0, 12.0, &[]).unwrap();
    let mut sim = Simulation::new(&spec).unwrap();
    let mut sut = SutConfig::builtin("aeb").unwrap().build();
    sut.reset(0).unwrap();
    let mut host = paracosm_engine::rx::NoHost;
    for _ in 0..(60.0 / spec.dt_s) as usize {
        let control = sut.act(&sim.observation()).unwrap();
        sim.step(control, &mut host).unwrap();
    }
    sim.ego_state().speed_mps
}

#[test]
fn the_aeb_cruise_speed_in_the_docs_is_the_one_it_holds() {
    let v = aeb_cruise_mps();
    // Settled: it was 11.84 m/s (1.3 % under the 12 m/s the docs said before).
    let figure = format!("{v:.2} m/s");
    says(
        "docs/systems-under-test.md",
        &format!("settles at {figure}"),
    );
    says("LANGUAGE.md", &format!("settles at {figure}"));
}

#[test]
fn sizes_limits_and_the_lidar_in_the_docs_are_the_engines() {
    let car = Size::CAR;
    says(
        "LANGUAGE.md",
        &format!(
            "({} × {} × {} m, length × width × height",
            car.length_m, car.width_m, car.height_m
        ),
    );
    let ego = VehicleParams::default().size;
    says(
        "LANGUAGE.md",
        &format!(
            "Its footprint is {} × {} m (length × width)",
            ego.length_m, ego.width_m
        ),
    );
    says(
        "LANGUAGE.md",
        &format!("tightest turn any lane path has, {MIN_PATH_RADIUS_M} m"),
    );
    says("LANGUAGE.md", &format!("lanes {LANE_WIDTH_M} m, sidewalks"));
    let lidar = LidarSpec::default();
    says(
        "LANGUAGE.md",
        &format!(
            "one horizontal plane of {} beams over {}°, {} m, {} Hz",
            lidar.beams,
            lidar.horizontal_fov_rad.to_degrees().round(),
            lidar.range_m,
            lidar.rate_hz
        ),
    );
}

// The braking figures (measured 1.12 m/s² on ice, the default friction's 7.85 m/s²) are read
// from LANGUAGE.md by `engine/tests/surface.rs`, which measures them.
