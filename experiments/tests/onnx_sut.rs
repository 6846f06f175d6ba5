//! ONNX models in the loop (issue 20, requirements 2 and 3): models written with
//! `onnx_export` run as systems under test through tract; a NaN answer ends only its test as
//! `error`; missing manifests and shapes the model does not take are refused with the file's
//! name; the shipped `pilotnet` gives tract the outputs candle computes, to 1e-4.

use std::path::{Path, PathBuf};

use paracosm::record::Status;
use paracosm::Campaign;
use paracosm_engine::sut::{preprocess, Manifest, OnnxConfig, SutConfig};
use paracosm_experiments::onnx_export::Graph;
use paracosm_experiments::pilotnet;
use paracosm_generators::Strategy;

mod common;
use common::repo;

/// A model that ignores its image: `controls = tanh(0 · image + bias)`, with `bias` the
/// pre-tanh throttle and steering, on a `[1, 3, h, w]` input.
fn constant_model(bias: [f32; 2], h: usize, w: usize) -> Vec<u8> {
    model(bias, h, w, true)
}

/// As [`constant_model`], without the `tanh` when `bounded` is false (tract's `tanh` maps NaN
/// into `[-1, 1]`; a NaN must reach the output to test what the system under test does).
fn model(bias: [f32; 2], h: usize, w: usize, bounded: bool) -> Vec<u8> {
    let mut g = Graph::new();
    let x = g.input("image", &[1, 3, h, w]);
    let flat = g.flatten(&x);
    let weight = g.constant(&[2, 3 * h * w], vec![0.0; 2 * 3 * h * w]);
    let b = g.constant(&[2], bias.to_vec());
    let y = g.linear(&flat, &weight, &b);
    let out = if bounded { g.tanh(&y) } else { y };
    g.output(&out, &[1, 2]);
    g.encode("constant", "a test model")
}

const MANIFEST: &str = "\
[camera]
width = 160
height = 120
rate_hz = 10.0

[input]
width = 16
height = 8
crop = [40, 0, 0, 0]

[output]
throttle = 0
steering = 1
";

fn write_model(dir: &Path, name: &str, bytes: &[u8], manifest: Option<&str>) -> PathBuf {
    let path = dir.join(format!("{name}.onnx"));
    std::fs::write(&path, bytes).unwrap();
    if let Some(m) = manifest {
        std::fs::write(dir.join(format!("{name}.toml")), m).unwrap();
    }
    path
}

fn campaign_records(sut: SutConfig, budget: u64, jobs: usize) -> Vec<paracosm::RunRecord> {
    let mut scenario = paracosm_scenarios::load("pedestrian-crossing").unwrap();
    scenario.set_sut(sut);
    let campaign = Campaign {
        scenario: &scenario,
        strategy: Strategy::Halton,
        seed: 1,
        budget,
        strength: 2,
        jobs,
        stop_at_first_failure: false,
        points: None,
        trace: None,
    };
    let mut records = Vec::new();
    campaign
        .points_in_chunks(|first, points| {
            for (k, p) in points.iter().enumerate() {
                records.push(campaign.run_one(first + k as u64, p));
            }
            Ok(true)
        })
        .unwrap();
    records
}

#[test]
fn a_model_drives_the_ego_and_a_nan_answer_ends_only_its_test() {
    let dir = tempfile::tempdir().unwrap();
    // tanh(0.6) = 0.537 throttle: the car drives on.
    let go = write_model(
        dir.path(),
        "go",
        &constant_model([0.6, 0.0], 8, 16),
        Some(MANIFEST),
    );
    let records = campaign_records(SutConfig::onnx(&go).unwrap(), 3, 1);
    for r in &records {
        assert_ne!(r.status, Status::Error, "{:?}", r.error);
        let travelled = r
            .metrics
            .iter()
            .find(|(n, _)| n == "distance_travelled_m")
            .map(|(_, v)| *v)
            .unwrap();
        assert!(
            travelled > 30.0,
            "the model's throttle moved the car: {travelled} m"
        );
    }
    // tanh(-3) = -0.995: full braking from the start; the car barely moves.
    let stop = write_model(
        dir.path(),
        "stop",
        &constant_model([-3.0, 0.0], 8, 16),
        Some(MANIFEST),
    );
    let records = campaign_records(SutConfig::onnx(&stop).unwrap(), 2, 1);
    for r in &records {
        let travelled = r
            .metrics
            .iter()
            .find(|(n, _)| n == "distance_travelled_m")
            .map(|(_, v)| *v)
            .unwrap();
        assert!(travelled < 20.0, "braking from the start: {travelled} m");
    }
    // A NaN throttle: every test ends in error naming the output; the campaign goes on.
    let nan = write_model(
        dir.path(),
        "nan",
        &model([f32::NAN, 0.0], 8, 16, false),
        Some(MANIFEST),
    );
    let records = campaign_records(SutConfig::onnx(&nan).unwrap(), 3, 1);
    assert_eq!(records.len(), 3);
    for r in &records {
        assert_eq!(r.status, Status::Error);
        let e = r.error.as_deref().unwrap();
        assert!(e.contains("NaN for throttle"), "{e}");
        assert!(e.contains("nan.onnx"), "{e}");
    }
    // A throttle of 1.7, outside [-1, 1]: an error as for an external system (it was clamped
    // to 1 without a word).
    let wild = write_model(
        dir.path(),
        "wild",
        &model([1.7, 0.0], 8, 16, false),
        Some(MANIFEST),
    );
    let records = campaign_records(SutConfig::onnx(&wild).unwrap(), 2, 1);
    for r in &records {
        assert_eq!(r.status, Status::Error);
        let e = r.error.as_deref().unwrap();
        assert!(e.contains("1.7") && e.contains("outside [-1, 1]"), "{e}");
    }
}

#[test]
fn bad_models_and_manifests_are_refused_with_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let err = |path: &Path| SutConfig::onnx(path).unwrap_err().to_string();
    // No manifest beside the model.
    let lone = write_model(dir.path(), "lone", &constant_model([0.0; 2], 8, 16), None);
    let e = err(&lone);
    assert!(e.contains("lone.toml") && e.contains("manifest"), "{e}");
    // Each manifest edit is refused with what its message must name.
    let refused = |name: &str, manifest: String, wanted: &[&str]| {
        let path = write_model(
            dir.path(),
            name,
            &constant_model([0.0; 2], 8, 16),
            Some(&manifest),
        );
        let e = err(&path);
        assert!(wanted.iter().all(|w| e.contains(w)), "{name}: {e}");
    };
    // The model takes 8 × 16; the manifest promises 48 × 96: refused from the input the
    // model declares, before tract is given the manifest's (it ran a model declaring
    // [1, 1, 10, 10] on [1, 3, 48, 96]).
    refused(
        "shape",
        MANIFEST.replace("width = 16\nheight = 8", "width = 96\nheight = 48"),
        &[
            "shape.onnx",
            "declares its input of shape [1, 3, 8, 16]",
            "[1, 3, 48, 96]",
        ],
    );
    // An unknown key, with its line and column.
    refused(
        "typo",
        MANIFEST.replace("throttle = 0", "throttel = 0"),
        &["typo.toml:12:1", "throttel"],
    );
    // An output index the model does not have.
    refused(
        "far",
        MANIFEST.replace("steering = 1", "steering = 5"),
        &["2 outputs", "index 5"],
    );
    // A crop that leaves nothing.
    refused(
        "crop",
        MANIFEST.replace("crop = [40, 0, 0, 0]", "crop = [60, 60, 0, 0]"),
        &["leaves nothing"],
    );
    // Not an ONNX file.
    let junk = write_model(dir.path(), "junk", b"not a model", Some(MANIFEST));
    assert!(err(&junk).contains("junk.onnx"));
}

#[test]
fn a_program_names_its_model_relative_to_its_own_file() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir(dir.path().join("models")).unwrap();
    write_model(
        &dir.path().join("models"),
        "go",
        &constant_model([0.6, 0.0], 8, 16),
        Some(MANIFEST),
    );
    let program = "\
w = World(light = Const(0.5), fog = Const(0.0))
r = RoadSegment(friction = Const(0.8), len = Const(120.0), nlanes = Const(2))
v = AutonomousVehicle(loc = r.onLane(1, 10), sut = \"onnx:models/go.onnx\")
w.place(r, v)
DistanceMonitor(v, minD = 20.0)
test(horizon = 5.0)
";
    let star = dir.path().join("learned.star");
    std::fs::write(&star, program).unwrap();
    let s = paracosm_scenarios::load(star.to_str().unwrap()).unwrap();
    assert!(
        s.sut().name().ends_with("models/go.onnx"),
        "{}",
        s.sut().name()
    );
    let o = s
        .run(&s.space().decode(&Default::default()).unwrap(), 0)
        .unwrap();
    assert!(o.passed(), "{o:?}");
    // A missing model is an error at load, at the call.
    std::fs::write(&star, program.replace("go.onnx", "gone.onnx")).unwrap();
    let e = paracosm_scenarios::load(star.to_str().unwrap())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("gone.onnx") && e.contains("learned.star:3:"),
        "{e}"
    );
}

/// Requirement 3: tract's outputs for the shipped model equal candle's for the same weights
/// (read back from the ONNX file) on 100 camera frames of the training scenario.
#[test]
fn the_shipped_pilotnet_gives_tract_the_outputs_candle_computes() {
    let model = repo().join("assets/models/pilotnet.onnx");
    let bytes = std::fs::read(&model).unwrap();
    assert!(bytes.len() < 2_000_000, "{} bytes", bytes.len());
    let net = pilotnet::from_onnx(&bytes).unwrap();
    let config = OnnxConfig::load(&model).unwrap();
    let manifest = Manifest::parse(pilotnet::MANIFEST, Path::new("pilotnet.toml")).unwrap();
    assert_eq!(
        config.manifest, manifest,
        "the shipped manifest is MANIFEST"
    );
    let dir = tempfile::tempdir().unwrap();
    let draw = common::Draw {
        strategy: Strategy::Halton,
        seed: 0,
        budget: 2,
        rate_hz: 4.0,
        steer_noise: 0.0,
        noise_hold_s: 1.0,
    };
    let summary = common::dataset(
        "experiments/scenarios/pilotnet_train.star",
        &draw,
        manifest.camera.clone(),
        &dir.path().join("d"),
    );
    assert!(summary.frames >= 100, "{} frames", summary.frames);
    let mut rows = csv::Reader::from_path(dir.path().join("d/frames.csv")).unwrap();
    let header = rows.headers().unwrap().clone();
    let col = |n: &str| header.iter().position(|h| h == n).unwrap();
    let (c_image, c_speed) = (col("image"), col("ego_speed_mps"));
    let rows: Vec<csv::StringRecord> = rows.records().take(100).map(Result::unwrap).collect();
    let device = candle_core::Device::Cpu;
    let mut worst = 0f32;
    for r in &rows {
        let rgb = image::open(dir.path().join("d").join(&r[c_image]))
            .unwrap()
            .to_rgb8();
        let x = preprocess(&rgb, &manifest.input);
        let speed: f32 = r[c_speed].parse().unwrap();
        let ours = config.run(&x, speed).unwrap();
        let image =
            candle_core::Tensor::from_vec(x, (1, 3, pilotnet::HEIGHT, pilotnet::WIDTH), &device)
                .unwrap();
        let s = candle_core::Tensor::from_vec(vec![speed], (1, 1), &device).unwrap();
        let theirs = net.forward(&image, &s).unwrap().to_vec2::<f32>().unwrap();
        for (a, b) in ours.iter().zip(&theirs[0]) {
            worst = worst.max((a - b).abs());
        }
    }
    assert!(worst <= 1e-4, "largest difference {worst}");
    eprintln!("largest difference between tract and candle on 100 frames: {worst:e}");
}
