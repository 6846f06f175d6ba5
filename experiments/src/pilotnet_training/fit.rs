//! The training loop: AdamW with a linear warm-up and a half-cosine schedule, the gradient's
//! norm clipped, and early stopping on the validation score (and the closed-loop failures).

use std::time::Instant;

use candle_core::{DType, Device, Tensor, Var};
use candle_nn::{AdamW, Optimizer, VarMap};
use rand::seq::SliceRandom;
use rand::SeedableRng;

use super::closed_loop::{ClosedLoop, Failures};
use super::data::{batch, evaluate, Frames};
use super::TrainConfig;
use crate::pilotnet::{self, PilotNet};
use crate::training_error::{OrData, TrainingError};

/// The weights of `varmap`, in [`pilotnet::variables`]' order.
pub(super) fn weights_of(varmap: &VarMap) -> Result<Vec<pilotnet::Weight>, TrainingError> {
    let vars = varmap.data().lock().expect("no other user");
    pilotnet::variables()
        .into_iter()
        .map(|(name, shape)| {
            let v = vars[&name].as_tensor().flatten_all()?.to_vec1::<f32>()?;
            Ok((name, shape, v))
        })
        .collect()
}

/// The learning rate at gradient step `step` of `total`: a linear warm-up over
/// `args.warmup_steps`, then a half cosine from `args.lr` down to `args.lr * args.final_lr`.
fn learning_rate(args: &TrainConfig, step: usize, total: usize) -> f64 {
    if step < args.warmup_steps {
        return args.lr * (step + 1) as f64 / args.warmup_steps as f64;
    }
    let span = total.saturating_sub(args.warmup_steps).max(1);
    let done = ((step - args.warmup_steps) as f64 / span as f64).min(1.0);
    let floor = args.lr * args.final_lr;
    floor + (args.lr - floor) * 0.5 * (1.0 + (std::f64::consts::PI * done).cos())
}

/// `grads` scaled so that their L2 norm over `vars` is at most `clip`; returns the norm
/// before scaling.
fn clip_gradients(
    grads: &mut candle_core::backprop::GradStore,
    vars: &[Var],
    clip: f64,
) -> Result<f64, TrainingError> {
    let mut sum = 0.0f64;
    for v in vars {
        if let Some(g) = grads.get(v) {
            sum += f64::from(g.sqr()?.sum_all()?.to_scalar::<f32>()?);
        }
    }
    let norm = sum.sqrt();
    if norm > clip {
        let k = clip / norm;
        for v in vars {
            if let Some(g) = grads.get(v) {
                let scaled = (g * k)?;
                grads.insert(v, scaled);
            }
        }
    }
    Ok(norm)
}

/// The validation score early stopping minimises: throttle MSE + steering MSE + the share of
/// frames where the network and the teacher disagree about braking.
fn score([t, st, agree]: [f64; 3]) -> f64 {
    t + st + (1.0 - agree)
}

/// The best epoch so far: its closed-loop failures and [`score`], its number (from 1) and
/// its weights.
type Best = ((usize, f64), usize, Vec<Tensor>);

/// Trains `net` with `opt` for up to `args.epochs` passes over the `train` frames (shuffled
/// by a ChaCha8 seeded with `args.seed`), evaluating on `valid` (and in `closed_loop`, when
/// given) after each, and stops after `args.patience` epochs without a better one (fewer
/// closed-loop failures, then a lower [`score`]); leaves the best epoch's weights in `vars`.
/// Prints and returns the log, a line per epoch, and the best epoch (from 1).
pub(super) fn train_epochs(
    args: &TrainConfig,
    (net, opt, vars, varmap): (&PilotNet, &mut AdamW, &[Var], &VarMap),
    closed_loop: Option<&ClosedLoop>,
    frames: &Frames,
    (train, valid): (&[usize], &[usize]),
    dev: &Device,
    started: Instant,
) -> Result<(Vec<String>, usize), TrainingError> {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(args.seed);
    let mut order = train.to_vec();
    let mut log = Vec::new();
    let stepper = Stepper {
        args,
        net,
        vars,
        frames,
        weight: Tensor::new(&[1.0f32, args.steering_weight], dev)?.reshape((1, 2))?,
        dev,
        total_steps: args.epochs * train.len().div_ceil(args.batch),
    };
    let mut step = 0;
    let mut best: Option<Best> = None;
    for epoch in 0..args.epochs {
        order.shuffle(&mut rng);
        let (total, clipped) = stepper.epoch(opt, &order, &mut step)?;
        let metrics = evaluate(net, frames, valid, dev)?;
        // The epoch's weights, read once for the closed loop and --save-epochs.
        let weights = if closed_loop.is_some() || args.save_epochs {
            weights_of(varmap)?
        } else {
            Vec::new()
        };
        let failed = match closed_loop {
            Some(c) => Some(c.failures(&weights)?),
            None => None,
        };
        let line = epoch_line(
            epoch,
            total / train.len() as f64,
            metrics,
            closed_loop_note(failed.as_ref(), closed_loop),
            clipped,
            opt.learning_rate(),
            started,
        );
        eprintln!("{line}");
        log.push(line);
        if args.save_epochs {
            save_epoch(args, &weights, epoch)?;
        }
        let this = (failed.as_ref().map_or(0, |f| f.0), score(metrics));
        if best.as_ref().is_none_or(|(b, _, _)| this < *b) {
            let kept = vars
                .iter()
                .map(|v| v.as_tensor().copy())
                .collect::<candle_core::Result<Vec<_>>>()?;
            best = Some((this, epoch + 1, kept));
        } else if best
            .as_ref()
            .is_some_and(|(_, e, _)| epoch + 1 - e >= args.patience)
        {
            log.push(format!(
                "no better score for {} epochs: stopped",
                args.patience
            ));
            eprintln!("{}", log.last().expect("just pushed"));
            break;
        }
    }
    let (_, best_epoch, kept) = best.or_data("no epoch ran (--epochs 0)")?;
    for (v, t) in vars.iter().zip(kept) {
        v.set(&t)?;
    }
    log.push(format!("kept the weights of epoch {best_epoch}"));
    Ok((log, best_epoch))
}

/// What each gradient step of [`train_epochs`] works with.
struct Stepper<'a> {
    args: &'a TrainConfig,
    net: &'a PilotNet,
    vars: &'a [Var],
    frames: &'a Frames,
    /// `[1, 2]`: the loss's weights of throttle (1) and steering (`args.steering_weight`).
    weight: Tensor,
    dev: &'a Device,
    /// Gradient steps over all epochs, for the learning-rate schedule.
    total_steps: usize,
}

impl Stepper<'_> {
    /// One pass over `order` in batches of `args.batch`, one gradient step each (`step`
    /// counts them over the epochs); returns the sum over frames of the loss and how many
    /// steps had their gradient clipped.
    fn epoch(
        &self,
        opt: &mut AdamW,
        order: &[usize],
        step: &mut usize,
    ) -> Result<(f64, usize), TrainingError> {
        let args = self.args;
        let (mut total, mut clipped) = (0.0, 0usize);
        for chunk in order.chunks(args.batch) {
            let (x, s, y) = batch(self.frames, chunk, self.dev)?;
            let mut err = (self.net.forward(&x, &s)? - &y)?
                .sqr()?
                .broadcast_mul(&self.weight)?;
            if args.brake_weight != 1.0 {
                // 1 for a frame where the teacher does not brake, brake_weight where it does.
                let brakes = y.narrow(1, 0, 1)?.lt(0.0)?.to_dtype(DType::F32)?;
                let rows = ((brakes * f64::from(args.brake_weight - 1.0))? + 1.0)?;
                err = err.broadcast_mul(&rows)?;
            }
            let loss = err.mean_all()?;
            opt.set_learning_rate(learning_rate(args, *step, self.total_steps));
            let mut grads = loss.backward()?;
            clipped += usize::from(clip_gradients(&mut grads, self.vars, args.clip)? > args.clip);
            opt.step(&grads)?;
            *step += 1;
            total += f64::from(loss.to_scalar::<f32>()?) * chunk.len() as f64;
        }
        Ok((total, clipped))
    }
}

/// The closed-loop part of an epoch's log line: the failed tests and, by monitor, the
/// failures; empty without a closed loop.
fn closed_loop_note(failed: Option<&Failures>, closed_loop: Option<&ClosedLoop>) -> String {
    match (failed, closed_loop) {
        (Some((f, by)), Some(c)) => format!(
            "; closed loop: {f} of {} tests failed{}",
            c.points.len(),
            if by.is_empty() {
                String::new()
            } else {
                format!(
                    " ({})",
                    by.iter()
                        .map(|(m, k)| format!("{m} {k}"))
                        .collect::<Vec<_>>()
                        .join(", ")
                )
            }
        ),
        _ => String::new(),
    }
}

/// An epoch's log line: epoch `epoch` (from 0), its mean training loss `train_mse`, the
/// validation `[throttle MSE, steering MSE, braking agreement]`, the closed-loop `note`, the
/// steps clipped, the learning rate `lr` at its end, and the time since `started`.
fn epoch_line(
    epoch: usize,
    train_mse: f64,
    metrics: [f64; 3],
    note: String,
    clipped: usize,
    lr: f64,
    started: Instant,
) -> String {
    let [t, st, agree] = metrics;
    format!(
        "epoch {}: training MSE {:.4}; validation MSE throttle {t:.4}, steering {st:.5}, \
         braking agreement {:.1} %, score {:.4}{}; lr {:.2e}, {clipped} steps clipped \
         ({:.0} s)",
        epoch + 1,
        train_mse,
        100.0 * agree,
        score(metrics),
        note,
        lr,
        started.elapsed().as_secs_f64()
    )
}

/// Writes the network of `weights` after epoch `epoch` (from 0) as PREFIX-epochN.onnx (N from
/// 1), with its manifest PREFIX-epochN.toml (`--save-epochs`).
fn save_epoch(
    args: &TrainConfig,
    weights: &[pilotnet::Weight],
    epoch: usize,
) -> Result<(), TrainingError> {
    let onnx = pilotnet::to_onnx(weights, "an epoch kept by --save-epochs");
    let stem = args
        .out
        .file_name()
        .map_or_else(Default::default, |n| n.to_os_string());
    let mut name = stem;
    name.push(format!("-epoch{}", epoch + 1));
    let path = args.out.with_file_name(name).with_extension("onnx");
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir)?;
    }
    paracosm::atomic::write(&path, &onnx)?;
    paracosm::atomic::write(&path.with_extension("toml"), pilotnet::MANIFEST.as_bytes())?;
    Ok(())
}
