//! Training a perception network ([`Fcn`]) on a data set written by `paracosm-fuzz dataset`
//! at 160 × 120 (`perception train`): AdamW with a linear warm-up and a half cosine, early
//! stopping on the validation score, and the ONNX file and model card it leaves.

use std::path::PathBuf;
use std::time::Instant;

use candle_core::{DType, Device, Tensor, Var};
use candle_nn::{AdamW, Optimizer, ParamsAdamW, VarBuilder, VarMap};
use rand::seq::SliceRandom;
use rand::SeedableRng;

use super::data::{batch, frames, load, Set, CELLS};
use super::{detections, match_detections, road_counts, Fcn, Task};
use crate::perception;
use crate::training_error::{OrData, TrainingError};

/// The settings of a training run (the options of `perception train`).
#[derive(Debug, Clone)]
pub struct TrainConfig {
    /// What the network learns.
    pub task: Task,
    /// A folder written by `paracosm-fuzz dataset --width 160 --height 120`.
    pub data: PathBuf,
    /// Output prefix: PREFIX.onnx and PREFIX.md are written.
    pub out: PathBuf,
    /// Passes over the training frames (at most).
    pub epochs: usize,
    /// Frames per gradient step, at least 1.
    pub batch: usize,
    /// AdamW's peak learning rate (a half cosine to a tenth of it after the warm-up).
    pub lr: f64,
    /// Gradient steps over which the learning rate rises linearly from 0 to `lr`.
    pub warmup_steps: usize,
    /// Seeds the initial weights and the shuffling (ChaCha8).
    pub seed: u64,
    /// Tests whose id modulo this is its last value (`holdout_every - 1`) are held out for
    /// validation; at least 1.
    pub holdout_every: u64,
    /// Weight of a positive block in the loss (1: unweighted; vehicles: centres are about 1
    /// block in 400).
    pub positive_weight: f32,
    /// Stop after this many epochs without a better validation score.
    pub patience: usize,
}

/// Trains a network as `args` says, prints its progress to stderr, and writes PREFIX.onnx
/// and its model card PREFIX.md (printing where to stdout).
///
/// # Errors
/// [`TrainingError`] when the data set cannot be read or has too few tests for a training
/// and a validation part, when candle fails, when no epoch ran (`epochs` 0), or when an
/// output cannot be written.
pub fn train(args: &TrainConfig) -> Result<(), TrainingError> {
    let started = Instant::now();
    let all = frames(&args.data)?;
    let set = load(args.task, &all)?;
    let n = all.len();
    let (train, valid): (Vec<usize>, Vec<usize>) =
        (0..n).partition(|&i| set.tests[i] % args.holdout_every != args.holdout_every - 1);
    if train.is_empty() || valid.is_empty() {
        return Err(TrainingError::Data(format!(
            "{n} frames: too few tests for a training and a validation part"
        )));
    }
    let p = base_rate(&set, n, (&train, &valid), started);
    let dev = Device::Cpu;
    let varmap = VarMap::new();
    initialise(&varmap, args.seed, p, &dev)?;
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
    let run = Run {
        args,
        set: &set,
        net: &net,
        dev: &dev,
        started,
    };
    let (log, best_epoch, v) = run.fit(&mut opt, &vars, (&train, &valid))?;
    save(
        args,
        &varmap,
        &log,
        best_epoch,
        (train.len(), valid.len(), v),
        started,
    )
}

/// The mean target over the `train` frames, clamped to `[1e-4, 1 − 1e-4]`; prints the split
/// and the unclamped mean.
fn base_rate(set: &Set, n: usize, (train, valid): (&[usize], &[usize]), started: Instant) -> f32 {
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
    p
}

/// Fills `varmap` with [`perception::initial_weights`] of `seed`, the head's bias the logit
/// of the base rate `p`.
fn initialise(varmap: &VarMap, seed: u64, p: f32, dev: &Device) -> Result<(), TrainingError> {
    let mut vars = varmap.data().lock().expect("a fresh lock");
    let init = perception::initial_weights(seed, (p / (1.0 - p)).ln());
    for (name, t) in perception::tensors(&init, dev)? {
        vars.insert(name, Var::from_tensor(&t)?);
    }
    Ok(())
}

/// The best epoch so far: its score, number (from 1), weights and validation figures.
type Best = (f64, usize, Vec<Tensor>, [f64; 2]);

/// What the epochs of a training run work with.
struct Run<'a> {
    args: &'a TrainConfig,
    set: &'a Set,
    net: &'a Fcn,
    dev: &'a Device,
    started: Instant,
}

impl Run<'_> {
    /// Up to `args.epochs` passes over the `train` frames (shuffled by a ChaCha8 seeded with
    /// `args.seed`), each validated on `valid`, stopping after `args.patience` epochs without
    /// a better [`score`]; leaves the best epoch's weights in `vars` and returns the log, the
    /// best epoch (from 1) and its validation figures.
    fn fit(
        &self,
        opt: &mut AdamW,
        vars: &[Var],
        (train, valid): (&[usize], &[usize]),
    ) -> Result<(Vec<String>, usize, [f64; 2]), TrainingError> {
        let args = self.args;
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(args.seed);
        let mut order = train.to_vec();
        let total = args.epochs * train.len().div_ceil(args.batch);
        let mut step = 0usize;
        let mut log = Vec::new();
        let mut best: Option<Best> = None;
        for epoch in 1..=args.epochs {
            order.shuffle(&mut rng);
            let sum = self.epoch(opt, &order, &mut step, total)?;
            let v = validate(args.task, self.net, self.set, valid, self.dev)?;
            let line = format!(
                "epoch {epoch}: training loss {:.4}; validation {} ({:.0} s)",
                sum / train.len() as f64,
                describe(args.task, v),
                self.started.elapsed().as_secs_f64()
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
        let (_, best_epoch, kept, v) = best.or_data("no epoch ran (--epochs 0)")?;
        for (var, t) in vars.iter().zip(kept) {
            var.set(&t)?;
        }
        log.push(format!("kept the weights of epoch {best_epoch}"));
        Ok((log, best_epoch, v))
    }

    /// One pass over `order` in batches of `args.batch`, one gradient step each (`step`
    /// counts them, of `total`); returns the sum over frames of the loss.
    fn epoch(
        &self,
        opt: &mut AdamW,
        order: &[usize],
        step: &mut usize,
        total: usize,
    ) -> Result<f64, TrainingError> {
        let args = self.args;
        let mut sum = 0.0;
        for chunk in order.chunks(args.batch) {
            let lr = learning_rate(args, *step, total);
            opt.set_learning_rate(lr);
            let (x, y) = batch(self.set, chunk, self.dev)?;
            let loss = bce(&self.net.forward(&x)?, &y, args.positive_weight)?;
            opt.backward_step(&loss)?;
            sum += f64::from(loss.to_scalar::<f32>()?) * chunk.len() as f64;
            *step += 1;
        }
        Ok(sum)
    }
}

/// The learning rate at gradient step `step` of `total`: a linear warm-up over
/// `args.warmup_steps`, then a half cosine from `args.lr` down to a tenth of it.
fn learning_rate(args: &TrainConfig, step: usize, total: usize) -> f64 {
    let warmup = args.warmup_steps;
    if step < warmup {
        args.lr * (step + 1) as f64 / warmup as f64
    } else {
        let done = ((step - warmup) as f64 / total.saturating_sub(warmup).max(1) as f64).min(1.0);
        args.lr * (0.1 + 0.9 * 0.5 * (1.0 + (std::f64::consts::PI * done).cos()))
    }
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

/// Validation figures: road `[TPR, FPR]` over pixels; vehicles `[recall, false positives per
/// frame]`.
fn validate(
    task: Task,
    net: &Fcn,
    s: &Set,
    idx: &[usize],
    dev: &Device,
) -> Result<[f64; 2], TrainingError> {
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

/// The weights of `varmap`, in [`perception::variables`]' order.
fn weights_of(varmap: &VarMap) -> Result<Vec<perception::Weight>, TrainingError> {
    let vars = varmap.data().lock().expect("no other user");
    perception::variables()
        .into_iter()
        .map(|(name, shape)| {
            let v = vars[&name].as_tensor().flatten_all()?.to_vec1::<f32>()?;
            Ok((name, shape, v))
        })
        .collect()
}

/// Writes the trained network (PREFIX.onnx) and its model card (PREFIX.md), and prints where.
fn save(
    args: &TrainConfig,
    varmap: &VarMap,
    log: &[String],
    best_epoch: usize,
    (ntrain, nvalid, v): (usize, usize, [f64; 2]),
    started: Instant,
) -> Result<(), TrainingError> {
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
    let dataset_json = args.data.join("dataset.json");
    let dataset: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&dataset_json).map_err(|source| {
            TrainingError::DatasetJson {
                path: dataset_json.clone(),
                source,
            }
        })?)?;
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

/// The validation figures in words: road TPR and FPR in %, or vehicle recall in % and false
/// positives a frame.
fn describe(task: Task, [a, b]: [f64; 2]) -> String {
    match task {
        Task::Road => format!("road TPR {:.1} %, FPR {:.1} %", 100.0 * a, 100.0 * b),
        Task::Vehicles => format!("recall {:.1} %, {b:.2} false positives a frame", 100.0 * a),
    }
}

/// The model card (Markdown) of a network trained as `args` says: its file `stem`, the data
/// set (`dataset`, its `dataset.json`), the frame counts, the validation figures `v`, the
/// training log and kept epoch, and the ONNX file's size in bytes.
#[allow(clippy::too_many_arguments)]
fn model_card(
    args: &TrainConfig,
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
