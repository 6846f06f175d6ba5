//! `paracosm-fuzz dataset`: training data from a campaign. Each test of a campaign (its
//! points from any non-adaptive strategy, so the data set has the strategy's coverage) runs
//! with a teacher (the scenario's system under test, or `--sut`), and every recorded camera
//! frame is written with its depth map, its segmentation mask, the 2-D boxes of the actors it
//! shows (COCO JSON), the ego's state and the teacher's control.
//!
//! Layout of the output folder (documented in docs/cli.md, "dataset"):
//!
//! | file | what |
//! |---|---|
//! | `images/tNNNNNN_fKKKK.png` | RGB, 8-bit, `height × width × 3` |
//! | `depth/tNNNNNN_fKKKK.npy` | z-depth in metres, `float32`, `height × width`, `inf` = sky |
//! | `masks/tNNNNNN_fKKKK.png` | 8-bit grey, each pixel a [`SemanticClass`] id `0..=7` |
//! | `annotations.json` | COCO: images, a box per visible actor, the 8 categories |
//! | `frames.csv` | one row per frame: test, time, parameters, files, ego state, control |
//! | `results.jsonl` | each test's record, as a campaign writes it |
//! | `dataset.json` | the settings, the camera, the class ids, the counts |
//!
//! Everything but `results.jsonl`'s `wall_ms` is bit-identical for any `--jobs`.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use ndarray::Array2;
use paracosm_engine::sut::SutConfig;
use paracosm_engine::Control;
use paracosm_engine::{CameraFrame, CameraSpec, ObjectBox, SemanticClass};
use paracosm_generators::{Strategy, Value};
use paracosm_scenarios::{RunOptions, Sample};
use rayon::prelude::*;
use serde::Serialize;

use crate::campaign::Campaign;
use crate::record::{RunRecord, Status};
use crate::Error;

/// The index of frames, one row per frame, in `(test, frame)` order.
pub const FRAMES_FILE: &str = "frames.csv";
/// The COCO annotations: images, boxes, categories.
pub const ANNOTATIONS_FILE: &str = "annotations.json";
/// The data set's settings and counts.
pub const MANIFEST_FILE: &str = "dataset.json";

/// What `paracosm-fuzz dataset` asks for.
#[derive(Debug, Clone)]
pub struct DatasetRequest {
    /// Scenario name or `.star` path.
    pub scenario: String,
    /// How test points are chosen (not an adaptive one).
    pub strategy: Strategy,
    /// Campaign seed.
    pub seed: u64,
    /// Number of tests, `>= 1`.
    pub budget: u64,
    /// Strength of `ipog` and `kwise`.
    pub strength: usize,
    /// Frames recorded per second of simulated time, `> 0`.
    pub rate_hz: f64,
    /// The camera to record with when the teacher has none (its `rate_hz` is replaced by
    /// [`DatasetRequest::rate_hz`]). A teacher with its own camera is recorded through it.
    pub camera: CameraSpec,
    /// The teacher, instead of the scenario's system under test.
    pub sut: Option<SutConfig>,
    /// Output folder.
    pub out: PathBuf,
    /// Replace what `out` holds.
    pub replace: bool,
    /// Worker threads, `>= 1`.
    pub jobs: usize,
    /// Steering noise injected into what the vehicle applies, in steering units (`[-1, 1]`
    /// is the full lock), `[0, 1]`; 0: none. See [`SteerNoise`].
    pub steer_noise: f64,
    /// How long each noise value is held, s, `> 0`.
    pub noise_hold_s: f64,
    /// A learner that drives while the teacher labels (DAgger, [`paracosm_engine::sut::Dagger`]):
    /// the frames are the learner's states, `throttle` and `steering` the teacher's answers.
    /// `None`: the teacher drives.
    pub learner: Option<SutConfig>,
    /// With a learner: the probability in `[0, 1]` that a decision applies the teacher's
    /// answer instead of the learner's (DAgger's β); 0: the learner always drives.
    pub teacher_share: f64,
}

/// Noise injected into the teacher's steering while it drives (DART: Laskey et al. 2017,
/// "DART: Noise Injection for Robust Imitation Learning"). A network cloned from a teacher that
/// never leaves the lane centre has seen no way back to it; with noise, the vehicle drifts and
/// the teacher's answers, which `frames.csv` records as `steering` (the label), steer back.
/// What the vehicle applied is the column `applied_steering`.
///
/// The noise is piecewise constant: a value drawn uniformly from `[-amplitude, amplitude]`
/// every `hold_s` seconds, from a ChaCha8 stream seeded by the test's seed, so a data set is
/// the same for any `--jobs`.
#[derive(Debug, Clone)]
pub struct SteerNoise {
    amplitude: f64,
    hold_s: f64,
    rng: rand_chacha::ChaCha8Rng,
    value: f64,
    next_s: f64,
}

impl SteerNoise {
    /// Noise of `amplitude` (steering units, `[0, 1]`) held `hold_s` seconds (`> 0`), drawn
    /// from `seed`.
    ///
    /// # Errors
    /// [`Error::BadInput`] for an amplitude outside `[0, 1]` or a hold that is not a positive
    /// number.
    pub fn new(amplitude: f64, hold_s: f64, seed: u64) -> Result<Self, Error> {
        if !(0.0..=1.0).contains(&amplitude) {
            return Err(Error::BadInput(format!(
                "--steer-noise {amplitude} must be in [0, 1] (steering units; 1 is full lock)"
            )));
        }
        if !(hold_s.is_finite() && hold_s > 0.0) {
            return Err(Error::BadInput(format!(
                "--noise-hold {hold_s} must be a positive number of seconds"
            )));
        }
        use rand::SeedableRng;
        Ok(Self {
            amplitude,
            hold_s,
            rng: rand_chacha::ChaCha8Rng::seed_from_u64(seed ^ 0x6e6f_6973_655f_7374),
            value: 0.0,
            next_s: 0.0,
        })
    }

    /// The control to apply at `t_s` for the teacher's `answer`: its steering plus the noise
    /// value current at `t_s`, clamped to `[-1, 1]`; throttle unchanged.
    pub fn apply(&mut self, t_s: f64, answer: Control) -> Control {
        use rand::Rng;
        while t_s + 1e-9 >= self.next_s {
            self.value = self.amplitude * (2.0 * self.rng.random::<f64>() - 1.0);
            self.next_s += self.hold_s;
        }
        Control {
            steering: (answer.steering + self.value).clamp(-1.0, 1.0),
            ..answer
        }
    }
}

/// What an export wrote.
#[derive(Debug, Clone, PartialEq)]
pub struct DatasetSummary {
    /// Tests run.
    pub tests: usize,
    /// Tests that ended in `error` (their frames up to the error are kept).
    pub errors: usize,
    /// Frames written.
    pub frames: usize,
    /// Boxes written.
    pub boxes: usize,
    /// Whether Ctrl-C ended it before every test ran.
    pub interrupted: bool,
    /// Wall-clock seconds.
    pub wall_s: f64,
    /// The output folder.
    pub out: PathBuf,
}

impl DatasetSummary {
    /// The lines `paracosm-fuzz dataset` prints.
    pub fn text(&self) -> String {
        format!(
            "{} frames of {} tests ({} in error{}) with {} boxes in {} \
             ({:.1} s, {:.1} frames/s)\n  index: {}\n  boxes: {}",
            self.frames,
            self.tests,
            self.errors,
            if self.interrupted {
                ", interrupted"
            } else {
                ""
            },
            self.boxes,
            self.out.display(),
            self.wall_s,
            self.frames as f64 / self.wall_s.max(1e-9),
            self.out.join(FRAMES_FILE).display(),
            self.out.join(ANNOTATIONS_FILE).display(),
        )
    }

    /// 0, or 3 when a test ended in error, 130 when interrupted.
    pub fn exit_code(&self) -> u8 {
        if self.interrupted {
            130
        } else if self.errors > 0 {
            3
        } else {
            0
        }
    }
}

/// One recorded frame: its files, the ego's state, the teacher's control and its boxes.
#[derive(Debug, Clone)]
struct FrameRow {
    test: u64,
    frame: usize,
    t_s: f64,
    stem: String,
    /// The image's size, pixels: the camera that took it (the teacher's own, if it has one).
    width: u32,
    height: u32,
    ego: paracosm_engine::EgoState,
    throttle: f64,
    steering: f64,
    applied_steering: f64,
    boxes: Vec<ObjectBox>,
}

/// What one test wrote.
struct TestData {
    record: RunRecord,
    rows: Vec<FrameRow>,
    /// The camera that took the test's frames, if it took any.
    camera: Option<CameraSpec>,
}

fn write_error(path: &Path, e: impl std::fmt::Display) -> Error {
    Error::Write {
        path: path.to_owned(),
        reason: e.to_string(),
    }
}

/// Writes the three files of one frame under `out`, named by `stem`.
fn write_frame(out: &Path, stem: &str, frame: &CameraFrame) -> Result<(), Error> {
    // Each through a temporary file and a rename (`atomic::with_temp`): a link planted at a
    // frame's name is refused, never followed.
    let image = out.join("images").join(format!("{stem}.png"));
    crate::atomic::with_temp(&image, |tmp| {
        frame
            .to_image()
            .save_with_format(tmp, image::ImageFormat::Png)
    })?;
    let mask = out.join("masks").join(format!("{stem}.png"));
    crate::atomic::with_temp(&mask, |tmp| {
        frame
            .class_mask()
            .save_with_format(tmp, image::ImageFormat::Png)
    })?;
    let depth = out.join("depth").join(format!("{stem}.npy"));
    let shape = (frame.height as usize, frame.width as usize);
    let array =
        Array2::from_shape_vec(shape, frame.depth_m.clone()).map_err(|e| write_error(&depth, e))?;
    crate::atomic::with_temp(&depth, |tmp| ndarray_npy::write_npy(tmp, &array))
}

/// Refuses a non-empty `out` unless `replace`, and creates the folders.
fn prepare(out: &Path, replace: bool) -> Result<(), Error> {
    if out.exists() && !out.is_dir() {
        return Err(Error::BadInput(format!(
            "--out `{}` is not a folder",
            out.display()
        )));
    }
    let non_empty = std::fs::read_dir(out).is_ok_and(|mut d| d.next().is_some());
    if non_empty && !replace {
        return Err(Error::BadInput(format!(
            "`{}` is not empty; pass --force to replace it, or choose another --out",
            out.display()
        )));
    }
    if non_empty {
        std::fs::remove_dir_all(out).map_err(|e| write_error(out, e))?;
    }
    // An output folder that cannot be made or written is bad input (exit 2), found before
    // any test runs.
    crate::atomic::make_output_folder(out)?;
    for sub in ["images", "depth", "masks"] {
        let dir = out.join(sub);
        std::fs::create_dir_all(&dir).map_err(|e| write_error(&dir, e))?;
    }
    Ok(())
}

/// Runs the campaign of `req` with its teacher and writes the data set.
///
/// # Errors
/// [`Error::Scenario`] when the scenario does not load, [`Error::BadInput`] for an adaptive
/// strategy, a rate that is not a positive number, a camera out of range or a non-empty
/// folder without `replace`; [`Error::Generator`] when the strategy cannot serve the budget;
/// [`Error::Write`] when a file cannot be written (what was written stays).
pub fn export(req: &DatasetRequest, stop: Option<&AtomicBool>) -> Result<DatasetSummary, Error> {
    let started = Instant::now();
    if !(req.rate_hz.is_finite() && req.rate_hz > 0.0) {
        return Err(Error::BadInput(format!(
            "--rate {} must be a positive number of frames per second",
            req.rate_hz
        )));
    }
    SteerNoise::new(req.steer_noise, req.noise_hold_s, 0)?;
    if !(0.0..=1.0).contains(&req.teacher_share) {
        return Err(Error::BadInput(format!(
            "--teacher-share {} must be in [0, 1] (a probability)",
            req.teacher_share
        )));
    }
    let camera = CameraSpec {
        rate_hz: req.rate_hz,
        ..req.camera.clone()
    };
    camera
        .validate()
        .map_err(|e| Error::BadInput(format!("dataset camera: {e}")))?;
    let mut scenario = crate::load_scenario(&req.scenario)?;
    if let Some(sut) = &req.sut {
        scenario.set_sut(sut.clone());
    }
    if let Some(learner) = &req.learner {
        scenario.set_sut(SutConfig::Dagger {
            learner: Box::new(learner.clone()),
            teacher: Box::new(scenario.sut().clone()),
            beta: req.teacher_share,
        });
    }
    let campaign = Campaign {
        scenario: &scenario,
        strategy: req.strategy,
        seed: req.seed,
        budget: req.budget,
        strength: req.strength,
        jobs: req.jobs,
        stop_at_first_failure: false,
        points: None,
        trace: None,
    };
    prepare(&req.out, req.replace)?;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(req.jobs.max(1))
        .build()
        .map_err(|e| Error::Internal(format!("cannot start the worker pool: {e}")))?;
    let out = req.out.as_path();
    let mut done = Vec::new();
    let mut interrupted = false;
    // The points come in chunks as the tests run (`--budget 1e12` starts at once).
    campaign.points_in_chunks(|first, points| {
        let tests: Vec<Result<Option<TestData>, Error>> = pool.install(|| {
            points
                .par_iter()
                .enumerate()
                .map(|(k, point)| {
                    if stop.is_some_and(|s| s.load(Ordering::SeqCst)) {
                        return Ok(None);
                    }
                    let id = first + k as u64;
                    record_test(&campaign, id, point, &camera, req, out).map(Some)
                })
                .collect()
        });
        for t in tests {
            match t? {
                Some(t) => done.push(t),
                None => interrupted = true,
            }
        }
        Ok(!interrupted)
    })?;
    let summary = write_index(req, &scenario, &camera, &done, interrupted, started)?;
    Ok(summary)
}

/// Runs test `id` and writes its frames; returns its record and frame rows.
fn record_test(
    campaign: &Campaign<'_>,
    id: u64,
    point: &paracosm_generators::Point,
    camera: &CameraSpec,
    req: &DatasetRequest,
    out: &Path,
) -> Result<TestData, Error> {
    let rate_hz = req.rate_hz;
    let mut noise = SteerNoise::new(
        req.steer_noise,
        req.noise_hold_s,
        crate::campaign::seed::test_seed(req.seed, id),
    )?;
    let mut perturb = |t_s: f64, c: Control| noise.apply(t_s, c);
    let mut rows = Vec::new();
    let mut failed = None;
    let mut used: Option<CameraSpec> = None;
    // Frames are kept on the grid k / rate_hz: a teacher's own camera may be faster.
    let period_s = 1.0 / rate_hz;
    let mut next_s = 0.0;
    let mut on_sample = |s: &Sample<'_>| {
        if failed.is_some() || s.frame.t_s + 1e-9 < next_s {
            return;
        }
        while next_s <= s.frame.t_s + 1e-9 {
            next_s += period_s;
        }
        let stem = format!("t{id:06}_f{:04}", rows.len());
        if let Err(e) = write_frame(out, &stem, s.frame) {
            failed = Some(e);
            return;
        }
        used.get_or_insert_with(|| s.camera.clone());
        rows.push(FrameRow {
            test: id,
            frame: rows.len(),
            t_s: s.frame.t_s,
            stem,
            width: s.frame.width,
            height: s.frame.height,
            ego: s.ego,
            throttle: s.control.throttle,
            steering: s.control.steering,
            applied_steering: s.applied.steering,
            boxes: s.frame.boxes(),
        });
    };
    let record = campaign.run_one_with(
        id,
        point,
        &mut RunOptions {
            camera: Some(camera.clone()),
            on_frame: None,
            on_sample: Some(&mut on_sample),
            perturb: (req.steer_noise > 0.0).then_some(&mut perturb as &mut dyn FnMut(_, _) -> _),
            on_world: None,
            on_step: None,
        },
    );
    match failed {
        Some(e) => Err(e),
        None => Ok(TestData {
            record,
            rows,
            camera: used,
        }),
    }
}

fn status_name(s: Status) -> &'static str {
    match s {
        Status::Pass => "pass",
        Status::Fail => "fail",
        Status::Error => "error",
    }
}

/// A parameter's value as a CSV cell, in its unit (levels as written).
fn cell(v: Option<&Value>) -> String {
    match v {
        None => String::new(),
        Some(Value::Int(i)) => i.to_string(),
        Some(Value::Real(x)) => x.to_string(),
        Some(Value::Bool(b)) => b.to_string(),
        Some(Value::Text(t)) => t.clone(),
    }
}

#[derive(Serialize)]
struct CocoImage {
    id: usize,
    file_name: String,
    width: u32,
    height: u32,
    test: u64,
    t_s: f64,
    depth_file: String,
    mask_file: String,
}

#[derive(Serialize)]
struct CocoAnnotation {
    id: usize,
    image_id: usize,
    category_id: u8,
    /// `[x, y, width, height]`, pixels, top-left origin.
    bbox: [u32; 4],
    /// Visible pixels.
    area: u64,
    iscrowd: u8,
    /// The actor's index in its kind's set.
    actor: usize,
}

#[derive(Serialize)]
struct CocoCategory {
    id: u8,
    name: &'static str,
    supercategory: &'static str,
}

/// Writes `frames.csv`, `annotations.json`, `results.jsonl` and `dataset.json`.
fn write_index(
    req: &DatasetRequest,
    scenario: &paracosm_scenarios::Scenario,
    camera: &CameraSpec,
    done: &[TestData],
    interrupted: bool,
    started: Instant,
) -> Result<DatasetSummary, Error> {
    let out = &req.out;
    let names: Vec<String> = scenario
        .space()
        .params()
        .iter()
        .map(|p| p.name.clone())
        .collect();
    let (images, annotations) = write_frames_csv(&out.join(FRAMES_FILE), &names, done)?;
    let categories: Vec<CocoCategory> = SemanticClass::ALL
        .iter()
        .map(|c| CocoCategory {
            id: c.id(),
            name: c.name(),
            supercategory: if c.is_actor() { "actor" } else { "scene" },
        })
        .collect();
    let coco = serde_json::json!({
        "info": {
            "description": format!("paracosm-fuzz dataset {}", req.scenario),
            "version": env!("CARGO_PKG_VERSION"),
        },
        "images": images,
        "annotations": annotations,
        "categories": categories,
    });
    let coco_path = out.join(ANNOTATIONS_FILE);
    crate::atomic::write(&coco_path, coco.to_string().as_bytes())?;
    let results_path = out.join(crate::campaign::RESULTS_FILE);
    let mut lines = String::new();
    for t in done {
        lines.push_str(
            &serde_json::to_string(&t.record).map_err(|e| write_error(&results_path, e))?,
        );
        lines.push('\n');
    }
    crate::atomic::write(&results_path, lines.as_bytes())?;
    let errors = done
        .iter()
        .filter(|t| t.record.status == Status::Error)
        .count();
    let frames: usize = done.iter().map(|t| t.rows.len()).sum();
    let counts = (errors, frames, annotations.len());
    let manifest = manifest(req, scenario, camera, done, counts, interrupted);
    let manifest_path = out.join(MANIFEST_FILE);
    crate::atomic::write(
        &manifest_path,
        serde_json::to_string_pretty(&manifest)
            .expect("a JSON value serialises")
            .as_bytes(),
    )?;
    Ok(DatasetSummary {
        tests: done.len(),
        errors,
        frames,
        boxes: annotations.len(),
        interrupted,
        wall_s: started.elapsed().as_secs_f64(),
        out: out.clone(),
    })
}

/// Writes `frames.csv` to `frames_path`: a row per frame of `done`, with the test's
/// parameters `names`; returns the frames as COCO images and their boxes as annotations.
fn write_frames_csv(
    frames_path: &Path,
    names: &[String],
    done: &[TestData],
) -> Result<(Vec<CocoImage>, Vec<CocoAnnotation>), Error> {
    let mut csv = csv::Writer::from_path(frames_path).map_err(|e| write_error(frames_path, e))?;
    let mut header: Vec<String> = ["test", "frame", "t_s", "status"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    header.extend(names.iter().cloned());
    header.extend(
        [
            "image",
            "depth",
            "mask",
            "ego_x_m",
            "ego_z_m",
            "ego_heading_rad",
            "ego_speed_mps",
            "throttle",
            "steering",
            "applied_steering",
        ]
        .map(String::from),
    );
    csv.write_record(&header)
        .map_err(|e| write_error(frames_path, e))?;
    let (mut images, mut annotations) = (Vec::new(), Vec::new());
    for t in done {
        for r in &t.rows {
            let files = [
                format!("images/{}.png", r.stem),
                format!("depth/{}.npy", r.stem),
                format!("masks/{}.png", r.stem),
            ];
            csv.write_record(frame_row(t, r, names, &files))
                .map_err(|e| write_error(frames_path, e))?;
            let image_id = images.len();
            for b in &r.boxes {
                annotations.push(CocoAnnotation {
                    id: annotations.len() + 1,
                    image_id,
                    category_id: b.class.id(),
                    bbox: [b.x0, b.y0, b.x1 - b.x0, b.y1 - b.y0],
                    area: b.pixels,
                    iscrowd: 0,
                    actor: b.actor,
                });
            }
            let [image, depth, mask] = files;
            images.push(CocoImage {
                id: image_id,
                file_name: image,
                width: r.width,
                height: r.height,
                test: r.test,
                t_s: r.t_s,
                depth_file: depth,
                mask_file: mask,
            });
        }
    }
    csv.flush().map_err(|e| write_error(frames_path, e))?;
    Ok((images, annotations))
}

/// The `frames.csv` row of frame `r` of test `t`: its test, frame, time and status, the
/// test's parameters `names`, its `files` and the ego's state and controls.
fn frame_row(t: &TestData, r: &FrameRow, names: &[String], files: &[String; 3]) -> Vec<String> {
    let mut row = vec![
        r.test.to_string(),
        r.frame.to_string(),
        r.t_s.to_string(),
        status_name(t.record.status).to_owned(),
    ];
    row.extend(
        names
            .iter()
            .map(|n| cell(t.record.params.as_ref().and_then(|a| a.get(n)))),
    );
    row.extend(files.iter().cloned());
    row.extend(
        [
            r.ego.pos_m[0],
            r.ego.pos_m[2],
            r.ego.heading_rad,
            r.ego.speed_mps,
            r.throttle,
            r.steering,
            r.applied_steering,
        ]
        .map(|v| v.to_string()),
    );
    row
}

/// `dataset.json`: the settings, the camera, the counts (`(errors, frames, boxes)`) and what
/// the files hold.
fn manifest(
    req: &DatasetRequest,
    scenario: &paracosm_scenarios::Scenario,
    camera: &CameraSpec,
    done: &[TestData],
    (errors, frames, boxes): (usize, usize, usize),
    interrupted: bool,
) -> serde_json::Value {
    serde_json::json!({
        "scenario": req.scenario,
        "strategy": req.strategy.name(),
        "seed": req.seed,
        "budget": req.budget,
        "rate_hz": req.rate_hz,
        "steer_noise": req.steer_noise,
        "noise_hold_s": req.noise_hold_s,
        "teacher": match scenario.sut() {
            SutConfig::Dagger { teacher, .. } => teacher.name(),
            other => other.name(),
        },
        // DAgger: the learner that drove while the teacher labelled (null: the teacher drove).
        "learner": req.learner.as_ref().map(|l| serde_json::json!({
            "name": l.name(),
            "sha256": l.model_sha256(),
            "teacher_share": req.teacher_share,
        })),
        // The camera that took the frames: the teacher's own when it has one (a 64 × 48
        // teacher camera was written up as the 320 × 240 default), else --camera's.
        "camera": done.iter().find_map(|t| t.camera.as_ref()).unwrap_or(camera),
        "camera_of": if done.iter().any(|t| t.camera.as_ref().is_some_and(|c| c != camera)) {
            "teacher"
        } else {
            "dataset"
        },
        "tests": done.len(),
        "tests_in_error": errors,
        "frames": frames,
        "boxes": boxes,
        "interrupted": interrupted,
        "depth": "z-depth along the optical axis in metres, float32 .npy, height x width; inf where only sky",
        "mask": "8-bit PNG, each pixel a class id",
        "classes": SemanticClass::ALL.iter().map(|c| (c.name(), c.id())).collect::<std::collections::BTreeMap<_, _>>(),
        "control": "throttle in [-1, 1] (negative: brake), steering in [-1, 1] (positive: left), as the teacher answered for the frame's step; applied_steering: what the vehicle applied (the answer, or the learner's when one drove, plus the injected steer_noise)",
    })
}
