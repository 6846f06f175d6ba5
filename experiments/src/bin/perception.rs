//! The paper's §4.1 perception studies (PARACOSM Figures 5–8) with networks trained on
//! paracosm's own labels ([`paracosm_experiments::perception`]):
//!
//! ```text
//! # train: road segmentation on masks, or a vehicle detector on COCO boxes
//! perception train --task road --data DIR --out experiments/models/road_seg
//! perception train --task vehicles --data DIR --out experiments/models/vehicle_det
//! # Figures 5-6: road true/false positive rates against the focal length
//! perception road-study --model experiments/models/road_seg.onnx --data 10=DIR10 --data 20=DIR20 ...
//! # Figures 7-8: vehicles found along a drive
//! perception drive-study --model experiments/models/vehicle_det.onnx --data DIR
//! ```
//!
//! `experiments/perception_study.py` runs the whole chain (data sets, training, studies).

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{bail, Context, Result};
use candle_core::{DType, Device, Tensor, Var};
use candle_nn::{AdamW, Optimizer, ParamsAdamW, VarBuilder, VarMap};
use clap::{Parser, Subcommand};
use paracosm::report::plot::{xy_plot, Series, XyStyle};
use paracosm_experiments::perception::{
    self, centre_targets, contains, detections, match_detections, road_counts, road_targets, BoxPx,
    Fcn, OnnxMap, Task, BLOCK, CAR_CATEGORY, HEIGHT, MIN_AREA, OBSTACLE_CATEGORY, OUT_H, OUT_W,
    WIDTH,
};
use rand::seq::SliceRandom;
use rand::SeedableRng;
use rayon::prelude::*;

#[derive(Debug, Parser)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Trains a network on a folder written by `paracosm-fuzz dataset` at 160 × 120.
    Train(TrainArgs),
    /// Road true and false positive rates per focal length (Figures 5-6).
    RoadStudy {
        /// The road network's ONNX file.
        #[arg(long)]
        model: PathBuf,
        /// `FOCAL_MM=DIR`: a data set of the same tests at that focal length; repeat.
        #[arg(long, required = true)]
        data: Vec<String>,
        /// Output prefix: PREFIX.csv, PREFIX.png and PREFIX.svg.
        #[arg(long, default_value = "experiments/out/road_focal")]
        out: PathBuf,
    },
    /// Cars visible, found and falsely found per frame of a drive (Figures 7-8).
    DriveStudy {
        /// The detector's ONNX file.
        #[arg(long)]
        model: PathBuf,
        /// The drive's data set (one test).
        #[arg(long)]
        data: PathBuf,
        /// Output prefix: PREFIX.csv, PREFIX.png and PREFIX.svg.
        #[arg(long, default_value = "experiments/out/vehicle_drive")]
        out: PathBuf,
    },
}

#[derive(Debug, clap::Args)]
struct TrainArgs {
    /// What the network learns.
    #[arg(long, value_enum)]
    task: Task,
    /// A folder written by `paracosm-fuzz dataset --width 160 --height 120`.
    #[arg(long)]
    data: PathBuf,
    /// Output prefix: writes PREFIX.onnx and PREFIX.md.
    #[arg(long)]
    out: PathBuf,
    /// Passes over the training frames (at most).
    #[arg(long, default_value_t = 12)]
    epochs: usize,
    /// Frames per gradient step.
    #[arg(long, default_value_t = 32)]
    batch: usize,
    /// AdamW's peak learning rate (a half cosine to a tenth of it after the warm-up).
    #[arg(long, default_value_t = 2e-3)]
    lr: f64,
    /// Gradient steps over which the learning rate rises linearly from 0 to `--lr`.
    #[arg(long, default_value_t = 100)]
    warmup_steps: usize,
    /// Seeds the initial weights and the shuffling (ChaCha8).
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Tests whose id modulo this is its last value are held out for validation.
    #[arg(long, default_value_t = 8)]
    holdout_every: u64,
    /// Weight of a positive block in the loss (vehicles: centres are about 1 block in 400).
    #[arg(long, default_value_t = 1.0)]
    positive_weight: f32,
    /// Stop after this many epochs without a better validation score.
    #[arg(long, default_value_t = 3)]
    patience: usize,
}

/// One frame of a data set.
struct Frame {
    test: u64,
    t_s: f64,
    image: PathBuf,
    mask: PathBuf,
    /// The cars' visible boxes with at least [`MIN_AREA`] pixels.
    cars: Vec<BoxPx>,
    /// Each of `cars`' actor index among the scenario's cars.
    car_actors: Vec<u64>,
    /// Other boxes (pedestrians, obstacles) with at least [`MIN_AREA`] pixels: category and box.
    others: Vec<(u64, BoxPx)>,
}

/// The frames of a data set, in `frames.csv`'s order, with their boxes from
/// `annotations.json`.
fn frames(data: &Path) -> Result<Vec<Frame>> {
    let ann_path = data.join("annotations.json");
    let ann: serde_json::Value = serde_json::from_slice(
        &std::fs::read(&ann_path).with_context(|| format!("reading {}", ann_path.display()))?,
    )?;
    let mut by_image: std::collections::HashMap<String, Frame> = Default::default();
    let images = ann["images"]
        .as_array()
        .context("annotations.json: no images")?;
    let mut ids = std::collections::HashMap::new();
    for im in images {
        let (w, h) = (im["width"].as_u64(), im["height"].as_u64());
        if (w, h) != (Some(WIDTH as u64), Some(HEIGHT as u64)) {
            bail!(
                "{}: images are {w:?} × {h:?}; the networks read {WIDTH} × {HEIGHT} \
                 (paracosm-fuzz dataset --width {WIDTH} --height {HEIGHT})",
                ann_path.display()
            );
        }
        let file = im["file_name"]
            .as_str()
            .context("an image without file_name")?;
        ids.insert(
            im["id"].as_u64().context("an image without id")?,
            file.to_owned(),
        );
        by_image.insert(
            file.to_owned(),
            Frame {
                test: im["test"].as_u64().context("an image without test")?,
                t_s: im["t_s"].as_f64().context("an image without t_s")?,
                image: data.join(file),
                mask: data.join(im["mask_file"].as_str().context("no mask_file")?),
                cars: Vec::new(),
                car_actors: Vec::new(),
                others: Vec::new(),
            },
        );
    }
    for a in ann["annotations"].as_array().context("no annotations")? {
        let area = a["area"].as_u64().unwrap_or(0);
        if area < MIN_AREA {
            continue;
        }
        let b = a["bbox"].as_array().context("an annotation without bbox")?;
        let b: Vec<f64> = b.iter().filter_map(serde_json::Value::as_f64).collect();
        let b: BoxPx = b
            .try_into()
            .map_err(|_| anyhow::anyhow!("a bbox of other than 4"))?;
        let id = a["image_id"].as_u64().context("no image_id")?;
        let f = by_image
            .get_mut(&ids[&id])
            .context("an annotation of no image")?;
        match a["category_id"].as_u64() {
            Some(CAR_CATEGORY) => {
                f.cars.push(b);
                f.car_actors.push(a["actor"].as_u64().unwrap_or(u64::MAX));
            }
            Some(c) => f.others.push((c, b)),
            None => bail!("an annotation without category_id"),
        }
    }
    let mut out: Vec<Frame> = by_image.into_values().collect();
    out.sort_by(|a, b| {
        (a.test, a.t_s)
            .partial_cmp(&(b.test, b.t_s))
            .expect("finite")
    });
    Ok(out)
}

fn read_mask(path: &Path) -> Result<Vec<u8>> {
    let m = image::open(path)
        .with_context(|| format!("reading {}", path.display()))?
        .to_luma8();
    if m.dimensions() != (WIDTH as u32, HEIGHT as u32) {
        bail!("{}: not {WIDTH} × {HEIGHT}", path.display());
    }
    Ok(m.into_raw())
}

fn read_input(path: &Path) -> Result<Vec<f32>> {
    let rgb = image::open(path)
        .with_context(|| format!("reading {}", path.display()))?
        .to_rgb8();
    Ok(perception::preprocess(&rgb))
}

const PIXELS: usize = 3 * HEIGHT * WIDTH;
const CELLS: usize = OUT_H * OUT_W;

fn main() -> Result<()> {
    match Cli::parse().command {
        Command::Train(args) => train(&args),
        Command::RoadStudy { model, data, out } => road_study(&model, &data, &out),
        Command::DriveStudy { model, data, out } => drive_study(&model, &data, &out),
    }
}

/// Inputs `[n × 3·120·160]` and targets `[n × 30·40]`, row-major.
struct Set {
    inputs: Vec<f32>,
    targets: Vec<f32>,
    tests: Vec<u64>,
    masks: Vec<Vec<u8>>,
    cars: Vec<Vec<BoxPx>>,
}

fn load(task: Task, frames: &[Frame]) -> Result<Set> {
    let rows: Vec<(Vec<f32>, Vec<f32>, Vec<u8>)> = frames
        .par_iter()
        .map(|f| {
            let x = read_input(&f.image)?;
            let mask = read_mask(&f.mask)?;
            let y = match task {
                Task::Road => road_targets(&mask),
                Task::Vehicles => centre_targets(&f.cars),
            };
            Ok((x, y, mask))
        })
        .collect::<Result<_>>()?;
    let mut s = Set {
        inputs: Vec::with_capacity(rows.len() * PIXELS),
        targets: Vec::with_capacity(rows.len() * CELLS),
        tests: frames.iter().map(|f| f.test).collect(),
        masks: Vec::new(),
        cars: frames.iter().map(|f| f.cars.clone()).collect(),
    };
    for (x, y, m) in rows {
        s.inputs.extend(x);
        s.targets.extend(y);
        s.masks.push(m);
    }
    Ok(s)
}

/// Binary cross-entropy with logits, positives weighted `pw`: the mean over blocks of
/// `w · (softplus(x) − y·x)` with `w = 1 + (pw − 1)·y`, in the stable form
/// `softplus(x) = max(x, 0) + ln(1 + e^{−|x|})`.
fn bce(logits: &Tensor, y: &Tensor, pw: f32) -> candle_core::Result<Tensor> {
    let softplus = (logits.relu()? + (logits.abs()?.neg()?.exp()? + 1.0)?.log()?)?;
    let per = (softplus - (y * logits)?)?;
    let w = ((y * f64::from(pw - 1.0))? + 1.0)?;
    (per * w)?.mean_all()
}

fn batch(s: &Set, idx: &[usize], dev: &Device) -> Result<(Tensor, Tensor)> {
    let mut x = Vec::with_capacity(idx.len() * PIXELS);
    let mut y = Vec::with_capacity(idx.len() * CELLS);
    for &i in idx {
        x.extend_from_slice(&s.inputs[i * PIXELS..(i + 1) * PIXELS]);
        y.extend_from_slice(&s.targets[i * CELLS..(i + 1) * CELLS]);
    }
    let n = idx.len();
    Ok((
        Tensor::from_vec(x, (n, 3, HEIGHT, WIDTH), dev)?,
        Tensor::from_vec(y, (n, 1, OUT_H, OUT_W), dev)?,
    ))
}

/// Validation figures: road `[TPR, FPR]` over pixels; vehicles `[recall, false positives per
/// frame]`.
fn validate(task: Task, net: &Fcn, s: &Set, idx: &[usize], dev: &Device) -> Result<[f64; 2]> {
    let (mut counts, mut found, mut visible, mut fps) = ([0u64; 4], 0usize, 0usize, 0usize);
    for chunk in idx.chunks(64) {
        let (x, _) = batch(s, chunk, dev)?;
        let out = net.forward(&x)?.flatten_from(1)?.to_vec2::<f32>()?;
        for (&i, logits) in chunk.iter().zip(&out) {
            match task {
                Task::Road => {
                    for (c, n) in counts.iter_mut().zip(road_counts(logits, &s.masks[i])) {
                        *c += n;
                    }
                }
                Task::Vehicles => {
                    let (f, fp) = match_detections(&detections(logits), &s.cars[i]);
                    found += f.iter().filter(|&&x| x).count();
                    fps += fp;
                    visible += s.cars[i].len();
                }
            }
        }
    }
    Ok(match task {
        Task::Road => [
            counts[0] as f64 / (counts[0] + counts[1]).max(1) as f64,
            counts[2] as f64 / (counts[2] + counts[3]).max(1) as f64,
        ],
        Task::Vehicles => [
            found as f64 / visible.max(1) as f64,
            fps as f64 / idx.len().max(1) as f64,
        ],
    })
}

/// What early stopping minimises: road `1 − TPR + FPR`; vehicles `1 − recall + 0.1 · false
/// positives per frame`.
fn score(task: Task, [a, b]: [f64; 2]) -> f64 {
    match task {
        Task::Road => 1.0 - a + b,
        Task::Vehicles => 1.0 - a + 0.1 * b,
    }
}

fn weights_of(varmap: &VarMap) -> Result<Vec<perception::Weight>> {
    let vars = varmap.data().lock().expect("no other user");
    perception::variables()
        .into_iter()
        .map(|(name, shape)| {
            let v = vars[&name].as_tensor().flatten_all()?.to_vec1::<f32>()?;
            Ok((name, shape, v))
        })
        .collect()
}

fn train(args: &TrainArgs) -> Result<()> {
    let started = Instant::now();
    let all = frames(&args.data)?;
    let set = load(args.task, &all)?;
    let n = all.len();
    let (train, valid): (Vec<usize>, Vec<usize>) =
        (0..n).partition(|&i| set.tests[i] % args.holdout_every != args.holdout_every - 1);
    if train.is_empty() || valid.is_empty() {
        bail!("{n} frames: too few tests for a training and a validation part");
    }
    let mean = train
        .iter()
        .map(|&i| set.targets[i * CELLS..(i + 1) * CELLS].iter().sum::<f32>())
        .sum::<f32>()
        / (train.len() * CELLS) as f32;
    let p = mean.clamp(1e-4, 1.0 - 1e-4);
    eprintln!(
        "{n} frames ({} training, {} validation), mean target {mean:.4}, loaded in {:.1} s",
        train.len(),
        valid.len(),
        started.elapsed().as_secs_f64()
    );
    let dev = Device::Cpu;
    let varmap = VarMap::new();
    {
        let mut vars = varmap.data().lock().expect("a fresh lock");
        let init = perception::initial_weights(args.seed, (p / (1.0 - p)).ln());
        for (name, t) in perception::tensors(&init, &dev)? {
            vars.insert(name, Var::from_tensor(&t)?);
        }
    }
    let vb = VarBuilder::from_varmap(&varmap, DType::F32, &dev);
    let net = Fcn::new(&vb)?;
    let vars = varmap.all_vars();
    let mut opt = AdamW::new(
        vars.clone(),
        ParamsAdamW {
            lr: args.lr,
            weight_decay: 0.0,
            ..Default::default()
        },
    )?;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(args.seed);
    let mut order = train.clone();
    let total = args.epochs * train.len().div_ceil(args.batch);
    let warmup = args.warmup_steps;
    let mut step = 0usize;
    let mut log = Vec::new();
    let mut best: Option<(f64, usize, Vec<Tensor>, [f64; 2])> = None;
    for epoch in 1..=args.epochs {
        order.shuffle(&mut rng);
        let mut sum = 0.0;
        for chunk in order.chunks(args.batch) {
            let lr = if step < warmup {
                args.lr * (step + 1) as f64 / warmup as f64
            } else {
                let done =
                    ((step - warmup) as f64 / total.saturating_sub(warmup).max(1) as f64).min(1.0);
                args.lr * (0.1 + 0.9 * 0.5 * (1.0 + (std::f64::consts::PI * done).cos()))
            };
            opt.set_learning_rate(lr);
            let (x, y) = batch(&set, chunk, &dev)?;
            let loss = bce(&net.forward(&x)?, &y, args.positive_weight)?;
            opt.backward_step(&loss)?;
            sum += f64::from(loss.to_scalar::<f32>()?) * chunk.len() as f64;
            step += 1;
        }
        let v = validate(args.task, &net, &set, &valid, &dev)?;
        let line = format!(
            "epoch {epoch}: training loss {:.4}; validation {} ({:.0} s)",
            sum / train.len() as f64,
            describe(args.task, v),
            started.elapsed().as_secs_f64()
        );
        eprintln!("{line}");
        log.push(line);
        let sc = score(args.task, v);
        if best.as_ref().is_none_or(|(b, ..)| sc < *b) {
            let kept = vars
                .iter()
                .map(|v| v.as_tensor().copy())
                .collect::<candle_core::Result<Vec<_>>>()?;
            best = Some((sc, epoch, kept, v));
        } else if best
            .as_ref()
            .is_some_and(|(_, e, ..)| epoch - e >= args.patience)
        {
            log.push(format!(
                "no better validation score for {} epochs: stopped",
                args.patience
            ));
            break;
        }
    }
    let (_, best_epoch, kept, v) = best.context("no epoch ran (--epochs 0)")?;
    for (var, t) in vars.iter().zip(kept) {
        var.set(&t)?;
    }
    log.push(format!("kept the weights of epoch {best_epoch}"));
    save(
        args,
        &varmap,
        &log,
        best_epoch,
        (train.len(), valid.len(), v),
        started,
    )
}

/// Writes the trained network (PREFIX.onnx) and its model card (PREFIX.md), and prints where.
fn save(
    args: &TrainArgs,
    varmap: &VarMap,
    log: &[String],
    best_epoch: usize,
    (ntrain, nvalid, v): (usize, usize, [f64; 2]),
    started: Instant,
) -> Result<()> {
    let weights = weights_of(varmap)?;
    let stem = args
        .out
        .file_name()
        .map_or("perception".into(), |n| n.to_string_lossy().into_owned());
    // The graph is named after the task, not the file, so that a network trained again
    // under another name is the same file byte for byte.
    let onnx = perception::to_onnx(
        &weights,
        match args.task {
            Task::Road => "road_seg",
            Task::Vehicles => "vehicle_det",
        },
        &format!(
            "{:?} network trained by paracosm-experiments perception",
            args.task
        ),
    );
    if let Some(dir) = args.out.parent() {
        std::fs::create_dir_all(dir)?;
    }
    paracosm::atomic::write(&args.out.with_extension("onnx"), &onnx)?;
    let dataset: serde_json::Value = serde_json::from_slice(
        &std::fs::read(args.data.join("dataset.json")).context("reading dataset.json")?,
    )?;
    let card = model_card(
        args,
        &stem,
        &dataset,
        (ntrain, nvalid),
        v,
        (log, best_epoch),
        onnx.len(),
        started,
    );
    paracosm::atomic::write(&args.out.with_extension("md"), card.as_bytes())?;
    println!(
        "wrote {} ({} bytes) and {} in {:.0} s; validation {}",
        args.out.with_extension("onnx").display(),
        onnx.len(),
        args.out.with_extension("md").display(),
        started.elapsed().as_secs_f64(),
        describe(args.task, v)
    );
    Ok(())
}

fn describe(task: Task, [a, b]: [f64; 2]) -> String {
    match task {
        Task::Road => format!("road TPR {:.1} %, FPR {:.1} %", 100.0 * a, 100.0 * b),
        Task::Vehicles => format!("recall {:.1} %, {b:.2} false positives a frame", 100.0 * a),
    }
}

#[allow(clippy::too_many_arguments)]
fn model_card(
    args: &TrainArgs,
    stem: &str,
    dataset: &serde_json::Value,
    (ntrain, nvalid): (usize, usize),
    v: [f64; 2],
    (log, best_epoch): (&[String], usize),
    bytes: usize,
    started: Instant,
) -> String {
    let (what, target) = match args.task {
        Task::Road => (
            "road segmentation",
            "per 4 × 4 block, the share of its pixels that are road or lane marking in the \
             renderer's mask; binary cross-entropy with logits",
        ),
        Task::Vehicles => (
            "vehicle detection (centre points)",
            "1 in the block holding the centre of each car's COCO box with at least 12 visible \
             pixels, 0 elsewhere; binary cross-entropy with logits",
        ),
    };
    format!(
        "# Model card: {stem}\n\n\
         A fully convolutional network for {what} (paper §4.1), {params} parameters: six \
         convolutions (two of stride 2, two dilated), input a 160 × 120 RGB camera image, \
         output one logit per 4 × 4 block (30 × 40). `experiments/src/perception.rs`.\n\n\
         | | |\n|---|---|\n\
         | training scenario | `{scenario}` |\n\
         | tests | {tests} ({strategy} points, seed {dseed}) at {rate} frames/s, camera {focal} mm |\n\
         | frames | {n} ({ntrain} training, {nvalid} validation: tests with id mod {h} = {hl}) |\n\
         | target | {target}{pw} |\n\
         | training | candle-nn 0.11, AdamW lr {lr} ({warmup} warm-up steps, then a half cosine \
         to a tenth), batch {batch}, at most {epochs} epochs, early stopping after {patience} \
         without a better validation score (weights of epoch {best_epoch} kept), seed {seed} |\n\
         | validation | {valid} |\n\
         | training time | {secs:.0} s on {threads} threads |\n\
         | file | `{stem}.onnx`, {bytes} bytes, ONNX opset 13, input `image` [1, 3, 120, 160] \
         ((level / 255 − 0.5) / 0.25), output `logits` [1, 1, 30, 40] |\n\n\
         Training log:\n\n```\n{log}\n```\n",
        params = perception::parameter_count(),
        scenario = dataset["scenario"].as_str().unwrap_or("?"),
        tests = dataset["tests"],
        strategy = dataset["strategy"].as_str().unwrap_or("?"),
        dseed = dataset["seed"],
        rate = dataset["rate_hz"],
        focal = dataset["camera"]["focal_mm"],
        n = ntrain + nvalid,
        h = args.holdout_every,
        hl = args.holdout_every - 1,
        pw = if args.positive_weight == 1.0 {
            String::new()
        } else {
            format!(", positive blocks weighted {}", args.positive_weight)
        },
        lr = args.lr,
        warmup = args.warmup_steps,
        batch = args.batch,
        epochs = args.epochs,
        patience = args.patience,
        seed = args.seed,
        valid = describe(args.task, v),
        secs = started.elapsed().as_secs_f64(),
        threads = rayon::current_num_threads(),
        log = log.join("\n"),
    )
}

/// The logits of `model` for each frame, in order.
fn run_model(model: &OnnxMap, frames: &[Frame]) -> Result<Vec<Vec<f32>>> {
    frames
        .iter()
        .map(|f| Ok(model.run(&read_input(&f.image)?)?))
        .collect()
}

fn road_study(model: &Path, data: &[String], out: &Path) -> Result<()> {
    let net = OnnxMap::load(model)?;
    let mut rows = Vec::new();
    for d in data {
        let (focal, dir) = d
            .split_once('=')
            .with_context(|| format!("--data {d}: not FOCAL_MM=DIR"))?;
        let focal: f64 = focal
            .parse()
            .with_context(|| format!("--data {d}: focal"))?;
        let frames = frames(Path::new(dir))?;
        let logits = run_model(&net, &frames)?;
        let (mut c, mut per_frame) = ([0u64; 4], Vec::new());
        for (f, l) in frames.iter().zip(&logits) {
            let k = road_counts(l, &read_mask(&f.mask)?);
            if k[0] + k[1] > 0 {
                per_frame.push(k[0] as f64 / (k[0] + k[1]) as f64);
            }
            for (a, b) in c.iter_mut().zip(k) {
                *a += b;
            }
        }
        per_frame.sort_by(f64::total_cmp);
        let worst = per_frame.first().copied().unwrap_or(f64::NAN);
        let tpr = c[0] as f64 / (c[0] + c[1]).max(1) as f64;
        let fpr = c[2] as f64 / (c[2] + c[3]).max(1) as f64;
        // False positives as a share of the road pixels: the paper's "percentage of non-road
        // (compared to baseline) identified as road".
        let fp_of_road = c[2] as f64 / (c[0] + c[1]).max(1) as f64;
        println!(
            "focal {focal:>4} mm: {} frames, road {:.1} % of pixels; TPR {:.1} % (worst frame \
             {:.1} %), FPR {:.1} % of non-road, false road {:.1} % of the road",
            frames.len(),
            100.0 * (c[0] + c[1]) as f64 / c.iter().sum::<u64>() as f64,
            100.0 * tpr,
            100.0 * worst,
            100.0 * fpr,
            100.0 * fp_of_road
        );
        rows.push((focal, frames.len(), tpr, fpr, fp_of_road, worst));
    }
    if let Some(dir) = out.parent() {
        std::fs::create_dir_all(dir)?;
    }
    let mut w = csv::Writer::from_path(out.with_extension("csv"))?;
    w.write_record([
        "focal_mm",
        "frames",
        "tpr",
        "fpr",
        "false_road_of_road",
        "worst_frame_tpr",
    ])?;
    for r in &rows {
        w.write_record([r.0, r.1 as f64, r.2, r.3, r.4, r.5].map(|v| v.to_string()))?;
    }
    w.flush()?;
    plot_road(&rows, out)?;
    println!(
        "wrote {} and {}",
        out.with_extension("csv").display(),
        out.with_extension("png").display()
    );
    Ok(())
}

fn plot_road(rows: &[(f64, usize, f64, f64, f64, f64)], stem: &Path) -> Result<()> {
    let lo = rows.iter().map(|r| r.0).fold(f64::INFINITY, f64::min);
    let hi = rows.iter().map(|r| r.0).fold(f64::NEG_INFINITY, f64::max);
    let series: Vec<Series> = vec![
        (
            "true positive: road found, % of the road".into(),
            rows.iter().map(|r| (r.0, 100.0 * r.2)).collect(),
        ),
        (
            "true positive in the worst frame".into(),
            rows.iter().map(|r| (r.0, 100.0 * r.5)).collect(),
        ),
        (
            "false positive: % of the non-road pixels".into(),
            rows.iter().map(|r| (r.0, 100.0 * r.3)).collect(),
        ),
        (
            "false positive: as a % of the road".into(),
            rows.iter().map(|r| (r.0, 100.0 * r.4)).collect(),
        ),
    ];
    xy_plot(
        stem,
        (
            "road segmentation against focal length (trained at 24 mm)",
            "focal length, mm",
            "%",
        ),
        // Room above 100 % for the legend.
        ((lo - 2.0, hi + 2.0), (0.0, 130.0)),
        &series,
        XyStyle::Lines,
    )?;
    Ok(())
}

fn drive_study(model: &Path, data: &Path, out: &Path) -> Result<()> {
    let net = OnnxMap::load(model)?;
    let frames = frames(data)?;
    let logits = run_model(&net, &frames)?;
    let index = data.join("frames.csv");
    let mut reader = csv::Reader::from_path(&index)?;
    let header = reader.headers()?.clone();
    let col = |n: &str| {
        header
            .iter()
            .position(|h| h == n)
            .with_context(|| format!("no column {n}"))
    };
    let (cx, cz) = (col("ego_x_m")?, col("ego_z_m")?);
    let pos: Vec<(f64, f64)> = reader
        .records()
        .map(|r| {
            let r = r?;
            Ok((r[cx].parse()?, r[cz].parse()?))
        })
        .collect::<Result<_>>()?;
    if pos.len() != frames.len() {
        bail!(
            "{}: {} rows for {} frames",
            index.display(),
            pos.len(),
            frames.len()
        );
    }
    let mut w = csv::Writer::from_path(out.with_extension("csv"))?;
    w.write_record([
        "t_s",
        "travelled_m",
        "cars_visible",
        "cars_found",
        "false_positives",
        "truck_visible",
        "truck_detections",
        "detections_px",
    ])?;
    let mut rows = Vec::new();
    let (mut travelled, mut total_vis, mut total_found, mut total_fp) = (0.0, 0, 0, 0);
    let mut per_actor = std::collections::BTreeMap::new();
    for (k, (f, l)) in frames.iter().zip(&logits).enumerate() {
        if k > 0 {
            travelled += (pos[k].0 - pos[k - 1].0).hypot(pos[k].1 - pos[k - 1].1);
        }
        let dets = detections(l);
        // Detections on the truck (an obstacle box, class 7) are counted apart, neither as a
        // car found nor as a false positive: the truck is a vehicle, but not one the detector
        // was taught (the paper's detectors missed theirs).
        let trucks: Vec<BoxPx> = f
            .others
            .iter()
            .filter(|(c, _)| *c == OBSTACLE_CATEGORY)
            .map(|(_, b)| *b)
            .collect();
        // A car is matched with the slack `match_detections` allows; the truck exactly.
        let in_car = |&d: &(f64, f64)| f.cars.iter().any(|b| contains(b, d, BLOCK as f64));
        let on_truck = |&d: &(f64, f64)| trucks.iter().any(|b| contains(b, d, 0.0));
        let truck_hits = dets.iter().filter(|d| !in_car(d) && on_truck(d)).count();
        let kept: Vec<(f64, f64)> = dets
            .iter()
            .copied()
            .filter(|d| in_car(d) || !on_truck(d))
            .collect();
        let (hits, fp) = match_detections(&kept, &f.cars);
        let found = hits.iter().filter(|&&x| x).count();
        for (&actor, &hit) in f.car_actors.iter().zip(&hits) {
            let e = per_actor.entry(actor).or_insert((0usize, 0usize));
            e.0 += 1;
            e.1 += usize::from(hit);
        }
        println!(
            "t {:>4.1} s, {travelled:>5.1} m: {} cars visible, {found} found, {fp} false positives; truck {}",
            f.t_s,
            f.cars.len(),
            if trucks.is_empty() { "not visible".to_owned() } else { format!("visible, {truck_hits} detections on it") }
        );
        let at: Vec<String> = dets.iter().map(|(x, y)| format!("{x}:{y}")).collect();
        w.write_record([
            f.t_s.to_string(),
            format!("{travelled:.2}"),
            f.cars.len().to_string(),
            found.to_string(),
            fp.to_string(),
            (!trucks.is_empty()).to_string(),
            truck_hits.to_string(),
            at.join(" "),
        ])?;
        rows.push((travelled, f.cars.len(), found, fp));
        total_vis += f.cars.len();
        total_found += found;
        total_fp += fp;
    }
    w.flush()?;
    for (actor, (seen, hit)) in &per_actor {
        println!("car {actor}: visible in {seen} frames, found in {hit}");
    }
    println!(
        "{} frames: {total_found} of {total_vis} visible cars found ({:.1} %), {total_fp} false positives",
        frames.len(),
        100.0 * total_found as f64 / total_vis.max(1) as f64
    );
    plot_drive(&rows, out)?;
    println!(
        "wrote {} and {}",
        out.with_extension("csv").display(),
        out.with_extension("png").display()
    );
    Ok(())
}

fn plot_drive(rows: &[(f64, usize, usize, usize)], stem: &Path) -> Result<()> {
    let top = rows.iter().map(|r| r.1.max(r.3)).max().unwrap_or(1) as f64 + 1.0;
    let end = rows.last().map_or(1.0, |r| r.0) + 5.0;
    let series: Vec<Series> = vec![
        (
            "cars visible (baseline)".into(),
            rows.iter().map(|r| (r.0, r.1 as f64)).collect(),
        ),
        (
            "false positive (not the truck)".into(),
            rows.iter().map(|r| (r.0, r.3 as f64)).collect(),
        ),
        (
            "true positive: cars found".into(),
            rows.iter().map(|r| (r.0, r.2 as f64)).collect(),
        ),
    ];
    xy_plot(
        stem,
        (
            "vehicle detection along the drive into the crossing",
            "distance driven, m",
            "cars",
        ),
        ((0.0, end), (0.0, top)),
        &series,
        XyStyle::Lines,
    )?;
    Ok(())
}
