//! paracosm's storyboard runtime against the reference simulator, esmini: every entity of a
//! scenario scripted (the ego too, at the speed its `Init` gives it), stepped at esmini's
//! step, and every entity's reference point and heading compared with esmini's own run of
//! the same file every 0.1 s. esmini's trajectories are fixtures
//! (`tests/data/xosc/esmini-trajectories`, made by `scripts/esmini-trajectories`; the esmini
//! commit and the command are in that folder's `PROVENANCE.md`).

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use paracosm_engine::network::roads::{wrap, Roads};
use paracosm_engine::network::{opendrive, MapRef};
use paracosm_openscenario::read_scenario;
use paracosm_scenarios::xosc::story::Storyboard;

/// esmini's step in the fixtures, s.
const STEP_S: f64 = 0.01;
/// The fixtures' sampling period, s.
const EVERY_S: f64 = 0.1;
/// Largest distance between paracosm's and esmini's reference points, m.
const POS_TOL_M: f64 = 0.10;
/// Largest difference of headings, rad.
const HEADING_TOL_RAD: f64 = 0.01;

fn data(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../tests/data/xosc")
        .join(rel)
}

/// One esmini sample: entity name → (x, y, h) every 0.1 s (index = t / 0.1).
type Track = HashMap<String, Vec<Option<[f64; 3]>>>;

fn fixture(path: &Path) -> Track {
    let mut rd = csv::Reader::from_path(path).expect("the fixture reads");
    let mut track: Track = HashMap::new();
    for rec in rd.records() {
        let rec = rec.expect("a fixture row");
        let num = |i: usize| rec[i].parse::<f64>().expect("a number");
        let k = (num(0) / EVERY_S).round() as usize;
        let v = track.entry(rec[1].to_owned()).or_default();
        if v.len() <= k {
            v.resize(k + 1, None);
        }
        v[k] = Some([num(2), num(3), num(4)]);
    }
    track
}

/// The largest deviation of each kind over the whole run, with where it happened.
#[derive(Debug, Default)]
struct Worst {
    pos_m: f64,
    pos_at: String,
    heading_rad: f64,
    heading_at: String,
    samples: usize,
    /// The first sample where an entity is in one simulator's scenario and not in the
    /// other's (esmini's CSV leaves an inactive entity out), empty when none.
    presence_at: String,
}

/// Steps the storyboard of `scenario` (every entity scripted), its parameters `overrides`
/// (name, value), at esmini's step and compares it with esmini's track `fixture_csv` (of the
/// file as written, or of one permutation of a variation file, as esmini's `--param_dist`
/// runs it).
fn compare_with(scenario: &Path, fixture_csv: &Path, overrides: &[(&str, &str)]) -> Worst {
    let track = fixture(fixture_csv);
    let overrides: Vec<(String, paracosm_openscenario::Value)> = overrides
        .iter()
        .map(|(n, v)| {
            (
                n.to_string(),
                paracosm_openscenario::Value::Str(v.to_string()),
            )
        })
        .collect();
    let model = read_scenario(scenario, &overrides).expect("the scenario reads");
    let map = match model.road_network.as_ref() {
        Some(road) => {
            let text = std::fs::read_to_string(&road.item).expect("the map reads");
            MapRef::new(
                opendrive::import(&road.item, &text)
                    .expect("the map imports")
                    .map,
            )
        }
        // No road network: the storyboard moves its entities on open ground.
        None => MapRef::new(std::sync::Arc::new(
            paracosm_engine::network::RoadMap::empty("no road network"),
        )),
    };
    let mut sb = Storyboard::new(&model, Roads::new(&map), None).expect("Init performs");
    let last = track.values().map(Vec::len).max().unwrap_or(0);
    let per_sample = (EVERY_S / STEP_S).round() as usize;
    let mut worst = Worst::default();
    let mut check = |k: usize, sb: &Storyboard| {
        for a in &sb.actors {
            let in_esmini = track
                .get(&a.name)
                .and_then(|v| v.get(k))
                .is_some_and(Option::is_some);
            if in_esmini != a.present && worst.presence_at.is_empty() {
                worst.presence_at = format!(
                    "{} at {:.1} s: in paracosm's scenario {}, in esmini's {in_esmini}",
                    a.name,
                    k as f64 * EVERY_S,
                    a.present
                );
            }
            let Some(Some([x, y, h])) = track.get(&a.name).and_then(|v| v.get(k)) else {
                continue;
            };
            let p = a.state.pose;
            let d = (p.x - x).hypot(p.y - y);
            let dh = wrap(p.h - h).abs();
            let at = format!(
                "{} at {:.1} s: paracosm ({:.3}, {:.3}, {:.4}), esmini ({x:.3}, {y:.3}, {h:.4})",
                a.name,
                k as f64 * EVERY_S,
                p.x,
                p.y,
                p.h
            );
            worst.samples += 1;
            if d > worst.pos_m {
                worst.pos_m = d;
                worst.pos_at = at.clone();
            }
            if dh > worst.heading_rad {
                worst.heading_rad = dh;
                worst.heading_at = at;
            }
        }
    };
    check(0, &sb);
    let mut step = 0usize;
    // esmini's last sample is where its storyboard ended: step to it.
    while step < (last - 1) * per_sample {
        sb.step(step as f64 * STEP_S, STEP_S)
            .expect("the storyboard steps");
        step += 1;
        if step.is_multiple_of(per_sample) {
            check(step / per_sample, &sb);
        }
    }
    worst
}

#[test]
fn every_alks_template_moves_its_entities_as_esmini_does() {
    let files = files_ending(&data("alks/concrete_scenarios"), "_template.xosc");
    assert_eq!(files.len(), 15, "the suite's 15 templates");
    check_all(&files);
}

/// The files of `dir` whose names end with `suffix`, sorted.
fn files_ending(dir: &Path, suffix: &str) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.to_string_lossy().ends_with(suffix))
        .collect();
    files.sort();
    files
}

/// Compares every file of `files` with its fixture; fails naming each that differs.
/// One comparison: a scenario, esmini's fixture of it, the parameters' values (name, value).
type Run<'a> = (PathBuf, PathBuf, Vec<(&'a str, &'a str)>);

fn check_all(files: &[PathBuf]) {
    let runs: Vec<Run> = files
        .iter()
        .map(|f| {
            let stem = f.file_stem().unwrap().to_str().unwrap();
            let csv = data("esmini-trajectories").join(format!("{stem}.csv"));
            (f.clone(), csv, vec![])
        })
        .collect();
    check_runs(&runs);
}

/// Compares each run (a scenario, its fixture, its parameters' values) with its fixture;
/// fails naming each that differs.
fn check_runs(runs: &[Run]) {
    let mut report = Vec::new();
    let mut failed = 0;
    for (f, csv, overrides) in runs {
        let w = compare_with(f, csv, overrides);
        let ok = w.pos_m <= POS_TOL_M
            && w.heading_rad <= HEADING_TOL_RAD
            && w.samples > 0
            && w.presence_at.is_empty();
        if !ok {
            failed += 1;
        }
        report.push(format!(
            "{} {}: {} samples, worst position {:.4} m ({}), worst heading {:.5} rad ({}){}",
            if ok { "ok  " } else { "FAIL" },
            csv.file_stem().unwrap().to_string_lossy(),
            w.samples,
            w.pos_m,
            w.pos_at,
            w.heading_rad,
            w.heading_at,
            if w.presence_at.is_empty() {
                String::new()
            } else {
                format!(", presence differs: {}", w.presence_at)
            }
        ));
    }
    let report = report.join("\n");
    println!("{report}");
    assert_eq!(failed, 0, "\n{report}");
}

/// esmini's own examples (`resources/xosc` of esmini, MPL-2.0, `tests/data/xosc/esmini`)
/// that paracosm runs as esmini does. The others of that folder, each with what it lacks, are
/// listed in `tests/data/xosc/esmini/PROVENANCE.md`.
const ESMINI_EXAMPLES: [&str; 56] = [
    "acc-test",
    "alks_cut-in",
    "alks_cut-out",
    "alks_decelerate",
    "alks_pedestrian",
    "alks_r157_cut_in_quick_brake",
    "alks-test",
    "bicycle_fall_over",
    "cut-in",
    "cut-in_cr",
    "cut-in_environment",
    "cut-in_external",
    "cut-in_interactive",
    "cut-in_simple",
    "cut-in_sloppy",
    "cut-in_visibility",
    "distance_test",
    "drive_when_close",
    "drop-bike",
    "follow_reference",
    "follow_reference_interactive",
    "follow_trajectory_by_front_axle",
    "highway_driver",
    "highway_merge",
    "highway_merge_advanced",
    "keep_lateral_distance",
    "lane-change_clothoid_based_trajectory",
    "lane_change",
    "lane_change_crest",
    "lane_change_simple",
    "lane-change_trajectory_wp",
    "left-hand-traffic_by_heading",
    "left-hand-traffic_using_road_rule",
    "light_state",
    "long_dist_action_with_jerk",
    "ltap-od",
    "ltap-od-relative-speed",
    "offroad_follower",
    "override_bb",
    "parking_lot",
    "pedestrian",
    "pedestrian_collision",
    "pedestrian_traj_synch",
    "routing-test",
    "slow-lead-vehicle",
    "speed-profile",
    "straight_500m",
    "straight_500m_pedestrian",
    "synch_with_steady_state",
    "synchronize",
    "traffic_lights",
    "trailer_connect",
    "trajectory-test",
    "truck_with_rotating_axle",
    "tunnels",
    "two_plus_one_road",
];

#[test]
fn esminis_own_examples_move_their_entities_as_esmini_does() {
    let files: Vec<PathBuf> = ESMINI_EXAMPLES
        .iter()
        .map(|n| data("esmini/xosc").join(format!("{n}.xosc")))
        .collect();
    check_all(&files);
}

/// Scenarios written here in forms the shipped suites do not use
/// (`tests/data/xosc/written/README.md`).
#[test]
fn scenarios_written_here_move_as_in_esmini() {
    let files = files_ending(&data("written"), ".xosc");
    assert!(!files.is_empty());
    check_all(&files);
}

/// Files nobody here wrote (`tests/data/xosc/third_party/`, PROVENANCE.md there): ASAM's
/// examples, the Euro NCAP car-to-car rear files the `scenariogeneration` package writes
/// (CCRb keeps its target 12 m ahead of the ego by a continuous `LongitudinalDistanceAction`
/// until the target brakes) and Vector's Euro NCAP files whose entities move as esmini moves
/// them (the cyclists of CBNA and CBNAO timed to the ego by a `SynchronizeAction` on route
/// positions, CBLA's cyclist accelerating within its `Performance`, the pedestrians of CPNA
/// and CPNCO timed to a `TrajectoryPosition`, the turning ego of CCFtap and CPTA and the
/// oncoming car of CCFhol on clothoid splines, one with an `initialDistanceOffset`), each as
/// esmini moves it.
#[test]
fn the_fields_files_move_as_in_esmini() {
    let files: Vec<PathBuf> = [
        "asam_examples/CutIn.xosc",
        "asam_examples/DoubleLaneChanger.xosc",
        "asam_examples/EndOfTrafficJam.xosc",
        "asam_examples/FastOvertakeWithReInitialization.xosc",
        "asam_examples/SequentialEvents_0-100-0kph_Explicit.xosc",
        "asam_examples/SequentialEvents_0-100-0kph_Implicit.xosc",
        "asam_examples/SimpleOvertake.xosc",
        "asam_examples/SlowPrecedingVehicle.xosc",
        "asam_examples/SynchronizedArrivalToIntersection.xosc",
        "asam_examples/TrafficJam.xosc",
        "scenariogeneration/CCRb_scenarios/xosc/CCRb0.xosc",
        "scenariogeneration/CCRb_scenarios/xosc/CCRb1.xosc",
        "scenariogeneration/CCRb_scenarios/xosc/CCRb2.xosc",
        "scenariogeneration/CCRb_scenarios/xosc/CCRb3.xosc",
        "scenariogeneration/CCRm_scenarios/xosc/CCRm22.xosc",
        "scenariogeneration/CCRs_scenarios/xosc/CCRs42.xosc",
        "scenariogeneration/CCRs_scenarios/xosc/CCRs44.xosc",
        "vector/OpenSCENARIO/NCAP/CA-FC_2026/CBNA.xosc",
        "vector/OpenSCENARIO/NCAP/CA-FC_2026/CBNAO.xosc",
        "vector/OpenSCENARIO/NCAP/CA-FC_2026/CBLA.xosc",
        "vector/OpenSCENARIO/NCAP/CA-FC_2026/CCRs.xosc",
        "vector/OpenSCENARIO/NCAP/CA-FC_2026/CCFhos.xosc",
        "vector/OpenSCENARIO/NCAP/CA-FC_2026/CCFtap.xosc",
        "vector/OpenSCENARIO/NCAP/CA-FC_2026/CPNA.xosc",
        "vector/OpenSCENARIO/NCAP/CA-FC_2026/CPNCO.xosc",
        "vector/OpenSCENARIO/NCAP/AEB_C2C_2023/NCAP_AEB_C2C_CCFtap_2023.xosc",
        "vector/OpenSCENARIO/NCAP/AEB_C2C_2023/NCAP_AEB_C2C_CCFhol_2023.xosc",
        "vector/OpenSCENARIO/NCAP/AEB_VRU_2023/NCAP_AEB_VRU_CPNA_2023.xosc",
        "vector/OpenSCENARIO/NCAP/AEB_VRU_2023/NCAP_AEB_VRU_CPNCO_2023.xosc",
        "vector/OpenSCENARIO/NCAP/AEB_VRU_2023/NCAP_AEB_VRU_CPTA_2023.xosc",
        "vector/OpenSCENARIO/NCAP/AEB_VRU_2023/NCAP_AEB_VRU_CBNA_2023.xosc",
        "vector/OpenSCENARIO/NCAP/AEB_VRU_2023/NCAP_AEB_VRU_CBNAO_2023.xosc",
        "vector/OpenSCENARIO/NCAP/AEB_VRU_2023/NCAP_AEB_VRU_CBLA_2023.xosc",
        "vector/OpenSCENARIO/NCAP/AEB_C2C_2023/NCAP_AEB_C2C_CCR_2023.xosc",
        "vector/OpenSCENARIO/NCAP/AEB_C2C_2023/NCAP_AEB_C2C_CCFhos_2023.xosc",
        "vector/OpenSCENARIO/NCAP/CA-FC_2026/CCCscp.xosc",
    ]
    .iter()
    .map(|f| data("third_party").join(f))
    .collect();
    check_all(&files);
}

/// Vector's CCCscp with the target at 70 km/h, the first permutation of its ExtendedRange
/// variation as esmini runs it (`--param_dist`, `--param_permutation 0`): its storyboard
/// deletes the three obstruction vehicles (`DeleteEntityAction`) when a speed exceeds
/// 60 km/h, and they leave paracosm's scenario when they leave esmini's.
#[test]
fn an_entity_deleted_leaves_the_scenario_as_in_esmini() {
    let file = data("third_party/vector/OpenSCENARIO/NCAP/CA-FC_2026/CCCscp.xosc");
    let csv = data("esmini-trajectories/CCCscp_extended_0.csv");
    let track = fixture(&csv);
    assert_eq!(
        track["ObstructionVehicle_Large"].iter().flatten().count(),
        1,
        "in esmini's first sample only"
    );
    check_runs(&[(
        file,
        csv,
        vec![("Ego_speed_kph", "20"), ("Target_final_speed_kph", "70")],
    )]);
}
