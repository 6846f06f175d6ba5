//! Training the PilotNet-style network ([`crate::pilotnet`]) on data sets written by
//! `paracosm-fuzz dataset`, on the CPU with candle-nn, and writing it as ONNX with its
//! manifest and a model card (the `train_pilotnet` binary).
//!
//! AdamW with a linear warm-up and a half-cosine schedule, the gradient's norm clipped, and
//! early stopping: after each epoch the validation frames are scored and, with
//! [`TrainConfig::closed_loop`], the network drives held-out tests of a scenario; the best
//! epoch's weights are kept (docs/experiments.md, "The shipped network").

mod card;
mod closed_loop;
mod data;
mod fit;

use std::path::{Path, PathBuf};
use std::time::Instant;

use candle_core::{DType, Device, Var};
use candle_nn::{AdamW, Optimizer, ParamsAdamW, VarBuilder, VarMap};
use paracosm_engine::sut::Manifest;

use self::closed_loop::ClosedLoop;
use self::data::{evaluate, load_all, Frames};
use self::fit::{train_epochs, weights_of};
use crate::pilotnet::{self, PilotNet};
use crate::training_error::TrainingError;

/// The settings of a training run (the options of `train_pilotnet`).
#[derive(Debug, Clone)]
pub struct TrainConfig {
    /// Folders written by `paracosm-fuzz dataset`, at least one, pooled (a teacher's drives
    /// and DAgger rounds); a test's id is taken within its folder (validation: the tests
    /// with id mod `holdout_every` its last value, in each).
    pub data: Vec<PathBuf>,
    /// Output prefix: PREFIX.onnx, PREFIX.toml and PREFIX.md are written.
    pub out: PathBuf,
    /// Passes over the training frames (at most).
    pub epochs: usize,
    /// Frames per gradient step, at least 1.
    pub batch: usize,
    /// AdamW's peak learning rate.
    pub lr: f64,
    /// Seeds the initial weights and the shuffling (ChaCha8).
    pub seed: u64,
    /// Tests whose id modulo this is its last value (`holdout_every - 1`) are held out for
    /// validation; at least 1.
    pub holdout_every: u64,
    /// Weight of the steering term of the loss against the throttle's (1: plain MSE).
    pub steering_weight: f32,
    /// Train on the teacher's throttle averaged over a window of this many seconds centred
    /// on each frame, within its test (0: as recorded).
    pub smooth_s: f64,
    /// Weight in the loss of the frames whose throttle target is negative (the teacher
    /// brakes), against 1 for the others (1: plain MSE).
    pub brake_weight: f32,
    /// Gradient steps over which the learning rate rises linearly from 0 to `lr`; after
    /// them it falls along a half cosine to `lr × final_lr` at the last epoch's end.
    pub warmup_steps: usize,
    /// The learning rate at the end, as a share of `lr` (in `[0, 1]`).
    pub final_lr: f64,
    /// Largest L2 norm of the gradient over all weights; a larger one is scaled down to it.
    pub clip: f64,
    /// Stop when this many epochs in a row have not improved the validation score
    /// (throttle MSE + steering MSE + share of frames where the network and the teacher
    /// disagree about braking, with `closed_loop` the failed tests first).
    pub patience: usize,
    /// Judge each epoch in closed loop as well: the network, exported as it stands, drives
    /// `closed_loop_tests` tests of this scenario (a built-in name or a `.star` file) at
    /// Halton points from index 4096 on, and the epoch with the fewest failed tests is kept
    /// (the validation score breaks ties).
    pub closed_loop: Option<String>,
    /// Also write each epoch's network as PREFIX-epochN.onnx (with its manifest).
    pub save_epochs: bool,
    /// How many closed-loop tests judge each epoch.
    pub closed_loop_tests: usize,
}

/// Trains the network as `args` says, printing each epoch to stderr, and writes
/// PREFIX.onnx, its manifest PREFIX.toml and its model card PREFIX.md (printing where to
/// stdout).
///
/// # Errors
/// [`TrainingError`] when a data set cannot be read, the closed-loop scenario cannot load or
/// run, candle fails, no epoch ran (`epochs` 0), or an output cannot be written.
pub fn train(args: &TrainConfig) -> Result<(), TrainingError> {
    let started = Instant::now();
    let manifest = Manifest::parse(pilotnet::MANIFEST, Path::new("pilotnet.toml"))?;
    let frames = load_all(args, &manifest)?;
    let (train, valid) = split(args, &frames, started);
    let dev = Device::Cpu;
    let varmap = VarMap::new();
    {
        let mut vars = varmap.data().lock().expect("a fresh lock");
        for (name, t) in pilotnet::tensors(&pilotnet::initial_weights(args.seed), &dev)? {
            vars.insert(name, Var::from_tensor(&t)?);
        }
    }
    let vb = VarBuilder::from_varmap(&varmap, DType::F32, &dev);
    let net = PilotNet::new(&vb)?;
    let mut opt = AdamW::new(
        varmap.all_vars(),
        ParamsAdamW {
            lr: args.lr,
            weight_decay: 0.0,
            ..Default::default()
        },
    )?;
    let vars = varmap.all_vars();
    let closed_loop = args
        .closed_loop
        .as_deref()
        .map(|name| ClosedLoop::new(name, args.closed_loop_tests, &manifest))
        .transpose()?;
    let (log, best_epoch) = train_epochs(
        args,
        (&net, &mut opt, &vars, &varmap),
        closed_loop.as_ref(),
        &frames,
        (&train, &valid),
        &dev,
        started,
    )?;
    // The trained weights, in the order of `pilotnet::variables`.
    drop(vars);
    let weights = weights_of(&varmap)?;
    let validation = evaluate(&net, &frames, &valid, &dev)?;
    save(
        args,
        &weights,
        (train.len(), valid.len()),
        validation,
        (&log, best_epoch),
        started,
    )
}

/// The training and validation frames (indices into `frames`), printed with their braking
/// frames.
fn split(args: &TrainConfig, frames: &Frames, started: Instant) -> (Vec<usize>, Vec<usize>) {
    let n = frames.speeds.len();
    let (train, valid): (Vec<usize>, Vec<usize>) = (0..n).partition(|&i| {
        (frames.tests[i] & u64::from(u32::MAX)) % args.holdout_every != args.holdout_every - 1
    });
    let braking = |idx: &[usize]| {
        idx.iter()
            .filter(|&&i| frames.targets[2 * i] < -0.5)
            .count()
    };
    eprintln!(
        "{n} frames ({} training, {} braking; {} validation, {} braking) loaded in {:.1} s",
        train.len(),
        braking(&train),
        valid.len(),
        braking(&valid),
        started.elapsed().as_secs_f64()
    );
    (train, valid)
}

/// Writes the network of `weights` (PREFIX.onnx), its manifest (PREFIX.toml) and its model
/// card (PREFIX.md), and prints where.
fn save(
    args: &TrainConfig,
    weights: &[pilotnet::Weight],
    split: (usize, usize),
    validation: [f64; 3],
    (log, best_epoch): (&[String], usize),
    started: Instant,
) -> Result<(), TrainingError> {
    let datasets = args
        .data
        .iter()
        .map(|d| {
            let path = d.join("dataset.json");
            let text = std::fs::read(&path).map_err(|source| TrainingError::Read {
                path: path.clone(),
                source,
            })?;
            Ok(serde_json::from_slice::<serde_json::Value>(&text)?)
        })
        .collect::<Result<Vec<_>, TrainingError>>()?;
    let dataset = &datasets[0];
    let doc = format!(
        "PilotNet-style driver trained by paracosm-experiments train_pilotnet on {}",
        dataset["scenario"]
    );
    let onnx = pilotnet::to_onnx(weights, &doc);
    if let Some(dir) = args.out.parent() {
        std::fs::create_dir_all(dir)?;
    }
    let path = |ext: &str| args.out.with_extension(ext);
    // Through a temporary file and a rename: a link planted at a path is refused, not followed.
    paracosm::atomic::write(&path("onnx"), &onnx)?;
    paracosm::atomic::write(&path("toml"), pilotnet::MANIFEST.as_bytes())?;
    let card = card::model_card(
        args,
        &datasets,
        split,
        validation,
        onnx.len(),
        (log, best_epoch),
        started,
    );
    paracosm::atomic::write(&path("md"), card.as_bytes())?;
    println!(
        "wrote {} ({} bytes), {} and {} in {:.0} s",
        path("onnx").display(),
        onnx.len(),
        path("toml").display(),
        path("md").display(),
        started.elapsed().as_secs_f64()
    );
    Ok(())
}
