//! Trains the PilotNet-style network ([`paracosm_experiments::pilotnet`]) on a data set
//! written by `paracosm-fuzz dataset`, on the CPU with candle-nn, and writes it as ONNX with
//! its manifest and a model card.
//!
//! ```text
//! paracosm-fuzz dataset experiments/scenarios/pilotnet_train.star --budget 128 --rate 10 \
//!     --steer-noise 0.08 --noise-hold 0.5 --out experiments/out/pilotnet-data
//! cargo run --release -p paracosm-experiments --bin train_pilotnet -- \
//!     --data experiments/out/pilotnet-data --out assets/models/pilotnet --epochs 8 --seed 0 \
//!     --steering-weight 10 --closed-loop pedestrian-crossing
//! ```
//!
//! AdamW with a linear warm-up and a half-cosine schedule, the gradient's norm clipped, and
//! early stopping: after each epoch the validation frames are scored and, with
//! `--closed-loop`, the network drives held-out tests of a scenario; the best epoch's weights
//! are kept (docs/experiments.md, "The shipped network").

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{bail, Context, Result};
use candle_core::{DType, Device, Tensor, Var};
use candle_nn::{AdamW, Optimizer, ParamsAdamW, VarBuilder, VarMap};
use clap::Parser;
use paracosm_engine::sut::{preprocess, Manifest};
use paracosm_experiments::pilotnet::{self, PilotNet, HEIGHT, WIDTH};
use rand::seq::SliceRandom;
use rand::SeedableRng;
use rayon::prelude::*;

#[derive(Debug, Parser)]
struct Args {
    /// A folder written by `paracosm-fuzz dataset`. Repeat it to pool several (a teacher's
    /// drives and DAgger rounds, `dataset --learner-onnx`); a test's id is then taken within
    /// its folder (validation: the tests with id mod `--holdout-every` its last value, in each).
    #[arg(long, required = true)]
    data: Vec<PathBuf>,
    /// Output prefix: writes PREFIX.onnx, PREFIX.toml and PREFIX.md.
    #[arg(long, default_value = "experiments/out/pilotnet")]
    out: PathBuf,
    /// Passes over the training frames.
    #[arg(long, default_value_t = 8)]
    epochs: usize,
    /// Frames per gradient step.
    #[arg(long, default_value_t = 64)]
    batch: usize,
    /// AdamW learning rate.
    #[arg(long, default_value_t = 1e-3)]
    lr: f64,
    /// Seeds the initial weights and the shuffling (ChaCha8).
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Tests whose id modulo this is its last value are held out for validation.
    #[arg(long, default_value_t = 8)]
    holdout_every: u64,
    /// Weight of the steering term of the loss against the throttle's (1: plain MSE). Raise
    /// it for a network that must steer (the `loop` network), whose steering labels are small.
    #[arg(long, default_value_t = 1.0)]
    steering_weight: f32,
    /// Train on the teacher's throttle averaged over a window of this many seconds centred
    /// on each frame, within its test (0: as recorded). A braking rule that switches between
    /// full brake and full throttle from one step to the next (`aeb` following a car) gives
    /// labels that flip on near-identical images; their average over a window is the share
    /// of braking, a smooth function of what the camera sees, which a network can learn.
    #[arg(long, default_value_t = 0.0)]
    smooth_s: f64,
    /// Weight of the frames whose throttle target is negative (the teacher brakes) in the
    /// loss, against 1 for the others (1: plain MSE). Braking frames are few (about one in
    /// seven when following a car), and a network can score well by never braking.
    #[arg(long, default_value_t = 1.0)]
    brake_weight: f32,
    /// Gradient steps over which the learning rate rises linearly from 0 to `--lr`; after
    /// them it falls along a half cosine to `--lr` × `--final-lr` at the last epoch's end.
    #[arg(long, default_value_t = 200)]
    warmup_steps: usize,
    /// The learning rate at the end, as a share of `--lr`.
    #[arg(long, default_value_t = 0.1)]
    final_lr: f64,
    /// Largest L2 norm of the gradient over all weights; a larger one is scaled down to it.
    #[arg(long, default_value_t = 1.0)]
    clip: f64,
    /// Stop when this many epochs in a row have not improved the validation score (throttle
    /// MSE + steering MSE + share of frames where the network and the teacher disagree about
    /// braking); the weights kept are those of the best epoch.
    #[arg(long, default_value_t = 3)]
    patience: usize,
    /// Judge each epoch in closed loop as well: the network, exported as it stands, drives
    /// `--closed-loop-tests` tests of this scenario (a built-in name or a `.star` file) at
    /// Halton points from index 4096 on (a data set's tests are the first points), and the
    /// epoch with the fewest failed tests is kept (the validation score breaks ties).
    #[arg(long, value_name = "SCENARIO")]
    closed_loop: Option<String>,
    /// Also write each epoch's network as PREFIX-epochN.onnx (with its manifest), to drive
    /// and compare them after training.
    #[arg(long)]
    save_epochs: bool,
    /// How many closed-loop tests judge each epoch.
    #[arg(long, default_value_t = 24)]
    closed_loop_tests: usize,
}

/// The held-out closed-loop tests that judge an epoch ([`Args::closed_loop`]).
struct ClosedLoop {
    scenario: paracosm_scenarios::Scenario,
    points: Vec<paracosm_generators::Assignment>,
    manifest: Manifest,
}

/// Index of the first Halton point of the closed-loop tests.
const CLOSED_LOOP_FROM: u64 = 4096;

impl ClosedLoop {
    fn new(name: &str, tests: usize, manifest: &Manifest) -> Result<Self> {
        use paracosm_generators::{Generator, Halton};
        let scenario = paracosm_scenarios::load(name).map_err(|e| anyhow::anyhow!("{e}"))?;
        let mut halton = Halton::new(&scenario.space);
        halton.skip(CLOSED_LOOP_FROM)?;
        let points = halton
            .ask(tests)?
            .iter()
            .map(|p| scenario.space.decode(p))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(ClosedLoop {
            scenario,
            points,
            manifest: manifest.clone(),
        })
    }

    /// How many of the tests fail with the network of `weights` driving, and how many times
    /// each monitor failed (a test can fail several), by name.
    fn failures(
        &self,
        weights: &[pilotnet::Weight],
    ) -> Result<(usize, std::collections::BTreeMap<String, usize>)> {
        let onnx = pilotnet::to_onnx(weights, "an epoch under closed-loop validation");
        let config =
            paracosm_engine::sut::OnnxConfig::from_bytes("training", &onnx, self.manifest.clone())?;
        let mut s = self.scenario.clone();
        s.sut = paracosm_engine::sut::SutConfig::Onnx(Box::new(config));
        let (mut failed, mut by_monitor) = (0, std::collections::BTreeMap::new());
        for (i, a) in self.points.iter().enumerate() {
            let o = s
                .run(a, CLOSED_LOOP_FROM + i as u64)
                .map_err(|e| anyhow::anyhow!("{e}"))?;
            failed += usize::from(!o.passed());
            for (name, v) in &o.monitors {
                if !v.passed {
                    *by_monitor.entry(name.clone()).or_insert(0) += 1;
                }
            }
        }
        Ok((failed, by_monitor))
    }
}

/// The weights of `varmap`, in [`pilotnet::variables`]' order.
fn weights_of(varmap: &VarMap) -> Result<Vec<pilotnet::Weight>> {
    let vars = varmap.data().lock().expect("no other user");
    pilotnet::variables()
        .into_iter()
        .map(|(name, shape)| {
            let v = vars[&name].as_tensor().flatten_all()?.to_vec1::<f32>()?;
            Ok((name, shape, v))
        })
        .collect()
}

struct Frames {
    images: Vec<f32>,
    speeds: Vec<f32>,
    targets: Vec<f32>,
    tests: Vec<u64>,
    times: Vec<f64>,
}

/// Replaces each frame's throttle target by the mean of its test's throttle over the frames
/// within `window_s / 2` seconds of it (centred moving average, in place).
fn smooth_throttle(f: &mut Frames, window_s: f64) {
    let raw: Vec<f32> = (0..f.tests.len()).map(|i| f.targets[2 * i]).collect();
    let n = raw.len();
    let mut start = 0;
    while start < n {
        let mut end = start;
        while end < n && f.tests[end] == f.tests[start] {
            end += 1;
        }
        for i in start..end {
            let near: Vec<f32> = (start..end)
                .filter(|&j| (f.times[j] - f.times[i]).abs() <= window_s / 2.0 + 1e-9)
                .map(|j| raw[j])
                .collect();
            f.targets[2 * i] = near.iter().sum::<f32>() / near.len() as f32;
        }
        start = end;
    }
}

const PIXELS: usize = 3 * HEIGHT * WIDTH;

fn load(data: &std::path::Path, manifest: &Manifest) -> Result<Frames> {
    let index = data.join("frames.csv");
    let mut reader =
        csv::Reader::from_path(&index).with_context(|| format!("reading {}", index.display()))?;
    let header = reader.headers()?.clone();
    let col = |n: &str| {
        header
            .iter()
            .position(|h| h == n)
            .with_context(|| format!("{}: no column `{n}`", index.display()))
    };
    let c_time = col("t_s")?;
    let (c_test, c_image, c_speed, c_throttle, c_steering) = (
        col("test")?,
        col("image")?,
        col("ego_speed_mps")?,
        col("throttle")?,
        col("steering")?,
    );
    let rows: Vec<csv::StringRecord> = reader.records().collect::<Result<_, _>>()?;
    let images: Vec<Vec<f32>> = rows
        .par_iter()
        .map(|r| {
            let path = data.join(&r[c_image]);
            let rgb = image::open(&path)
                .with_context(|| format!("reading {}", path.display()))?
                .to_rgb8();
            Ok(preprocess(&rgb, &manifest.input))
        })
        .collect::<Result<_>>()?;
    let mut f = Frames {
        images: Vec::with_capacity(rows.len() * PIXELS),
        speeds: Vec::new(),
        targets: Vec::new(),
        tests: Vec::new(),
        times: Vec::new(),
    };
    for (r, x) in rows.iter().zip(images) {
        if x.len() != PIXELS {
            bail!("an input has {} values, not {PIXELS}", x.len());
        }
        f.images.extend(x);
        f.speeds.push(r[c_speed].parse()?);
        f.targets.push(r[c_throttle].parse()?);
        f.targets.push(r[c_steering].parse()?);
        f.tests.push(r[c_test].parse()?);
        f.times.push(r[c_time].parse()?);
    }
    Ok(f)
}

fn batch(f: &Frames, idx: &[usize], dev: &Device) -> Result<(Tensor, Tensor, Tensor)> {
    let mut x = Vec::with_capacity(idx.len() * PIXELS);
    let (mut s, mut y) = (Vec::new(), Vec::new());
    for &i in idx {
        x.extend_from_slice(&f.images[i * PIXELS..(i + 1) * PIXELS]);
        s.push(f.speeds[i]);
        y.extend_from_slice(&f.targets[2 * i..2 * i + 2]);
    }
    let n = idx.len();
    Ok((
        Tensor::from_vec(x, (n, 3, HEIGHT, WIDTH), dev)?,
        Tensor::from_vec(s, (n, 1), dev)?,
        Tensor::from_vec(y, (n, 2), dev)?,
    ))
}

/// Mean squared error of throttle and steering, and the share of frames on which the network
/// and the teacher agree about braking (throttle < -0.5), over `idx`.
fn evaluate(net: &PilotNet, f: &Frames, idx: &[usize], dev: &Device) -> Result<[f64; 3]> {
    let (mut se, mut agree) = ([0.0f64; 2], 0usize);
    for chunk in idx.chunks(256) {
        let (x, s, y) = batch(f, chunk, dev)?;
        let p = net.forward(&x, &s)?.to_vec2::<f32>()?;
        let y = y.to_vec2::<f32>()?;
        for (p, y) in p.iter().zip(&y) {
            for k in 0..2 {
                se[k] += f64::from(p[k] - y[k]).powi(2);
            }
            agree += usize::from((p[0] < -0.5) == (y[0] < -0.5));
        }
    }
    let n = idx.len().max(1) as f64;
    Ok([se[0] / n, se[1] / n, agree as f64 / n])
}

fn main() -> Result<()> {
    let args = Args::parse();
    let started = Instant::now();
    let manifest = Manifest::parse(pilotnet::MANIFEST, std::path::Path::new("pilotnet.toml"))
        .map_err(anyhow::Error::msg)?;
    let mut frames = load(&args.data[0], &manifest)?;
    for (k, more) in args.data.iter().enumerate().skip(1) {
        let f = load(more, &manifest)?;
        frames.images.extend(f.images);
        frames.speeds.extend(f.speeds);
        frames.targets.extend(f.targets);
        frames
            .tests
            .extend(f.tests.iter().map(|t| ((k as u64) << 32) | t));
        frames.times.extend(f.times);
    }
    if args.smooth_s > 0.0 {
        smooth_throttle(&mut frames, args.smooth_s);
    }
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
        &args,
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
    let datasets = args
        .data
        .iter()
        .map(|d| {
            let path = d.join("dataset.json");
            let text =
                std::fs::read(&path).with_context(|| format!("reading {}", path.display()))?;
            Ok(serde_json::from_slice::<serde_json::Value>(&text)?)
        })
        .collect::<Result<Vec<_>>>()?;
    let dataset = &datasets[0];
    let doc = format!(
        "PilotNet-style driver trained by paracosm-experiments train_pilotnet on {}",
        dataset["scenario"]
    );
    let onnx = pilotnet::to_onnx(&weights, &doc);
    if let Some(dir) = args.out.parent() {
        std::fs::create_dir_all(dir)?;
    }
    let path = |ext: &str| args.out.with_extension(ext);
    // Through a temporary file and a rename: a link planted at a path is refused, not followed.
    paracosm::atomic::write(&path("onnx"), &onnx)?;
    paracosm::atomic::write(&path("toml"), pilotnet::MANIFEST.as_bytes())?;
    let card = model_card(
        &args,
        &datasets,
        (train.len(), valid.len()),
        validation,
        onnx.len(),
        (&log, best_epoch),
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

/// The learning rate at gradient step `step` of `total`: a linear warm-up over
/// `args.warmup_steps`, then a half cosine from `args.lr` down to `args.lr * args.final_lr`.
fn learning_rate(args: &Args, step: usize, total: usize) -> f64 {
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
) -> Result<f64> {
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

/// Trains `net` with `opt` for up to `args.epochs` passes over the `train` frames (shuffled
/// by a ChaCha8 seeded with `args.seed`), evaluating on `valid` (and in `closed_loop`, when
/// given) after each, and stops after `args.patience` epochs without a better one (fewer
/// closed-loop failures, then a lower [`score`]); leaves the best epoch's weights in `vars`. Prints and returns the log, a line per epoch, and the best epoch (from 1).
fn train_epochs(
    args: &Args,
    (net, opt, vars, varmap): (&PilotNet, &mut AdamW, &[Var], &VarMap),
    closed_loop: Option<&ClosedLoop>,
    frames: &Frames,
    (train, valid): (&[usize], &[usize]),
    dev: &Device,
    started: Instant,
) -> Result<(Vec<String>, usize)> {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(args.seed);
    let mut order = train.to_vec();
    let mut log = Vec::new();
    let weight = Tensor::new(&[1.0f32, args.steering_weight], dev)?.reshape((1, 2))?;
    let total_steps = args.epochs * train.len().div_ceil(args.batch);
    let mut step = 0;
    let mut best: Option<((usize, f64), usize, Vec<Tensor>)> = None;
    for epoch in 0..args.epochs {
        order.shuffle(&mut rng);
        let (mut total, mut clipped) = (0.0, 0usize);
        for chunk in order.chunks(args.batch) {
            let (x, s, y) = batch(frames, chunk, dev)?;
            let mut err = (net.forward(&x, &s)? - &y)?.sqr()?.broadcast_mul(&weight)?;
            if args.brake_weight != 1.0 {
                // 1 for a frame where the teacher does not brake, brake_weight where it does.
                let brakes = y.narrow(1, 0, 1)?.lt(0.0)?.to_dtype(DType::F32)?;
                let rows = ((brakes * f64::from(args.brake_weight - 1.0))? + 1.0)?;
                err = err.broadcast_mul(&rows)?;
            }
            let loss = err.mean_all()?;
            opt.set_learning_rate(learning_rate(args, step, total_steps));
            let mut grads = loss.backward()?;
            clipped += usize::from(clip_gradients(&mut grads, vars, args.clip)? > args.clip);
            opt.step(&grads)?;
            step += 1;
            total += f64::from(loss.to_scalar::<f32>()?) * chunk.len() as f64;
        }
        let metrics = evaluate(net, frames, valid, dev)?;
        let [t, st, agree] = metrics;
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
        let line = format!(
            "epoch {}: training MSE {:.4}; validation MSE throttle {t:.4}, steering {st:.5}, \
             braking agreement {:.1} %, score {:.4}{}; lr {:.2e}, {clipped} steps clipped \
             ({:.0} s)",
            epoch + 1,
            total / train.len() as f64,
            100.0 * agree,
            score(metrics),
            match (&failed, closed_loop) {
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
            },
            opt.learning_rate(),
            started.elapsed().as_secs_f64()
        );
        eprintln!("{line}");
        log.push(line);
        if args.save_epochs {
            let onnx = pilotnet::to_onnx(&weights, "an epoch kept by --save-epochs");
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
    let (_, best_epoch, kept) = best.context("no epoch ran (--epochs 0)")?;
    for (v, t) in vars.iter().zip(kept) {
        v.set(&t)?;
    }
    log.push(format!("kept the weights of epoch {best_epoch}"));
    Ok((log, best_epoch))
}

/// The model card (Markdown): the network, the data sets it was trained on (`datasets`, their
/// `dataset.json`; the first describes the table's rows, the others a row each), the training
/// and validation frame counts (`split`), the settings, the `[throttle MSE, steering MSE,
/// braking agreement]` on the validation frames, the ONNX file's size in bytes, the training
/// `log` and the epoch whose weights were kept.
fn model_card(
    args: &Args,
    datasets: &[serde_json::Value],
    (ntrain, nvalid): (usize, usize),
    [t, st, agree]: [f64; 3],
    bytes: usize,
    (log, best_epoch): (&[String], usize),
    started: Instant,
) -> String {
    let n = ntrain + nvalid;
    let dataset = &datasets[0];
    let more = datasets
        .iter()
        .skip(1)
        .map(|d| {
            let driver =
                match d["learner"]["name"].as_str() {
                    Some(l) => format!(
                    "`{l}` drove (SHA-256 {}…, teacher's share {}) while `{}` labelled (DAgger)",
                    d["learner"]["sha256"].as_str().unwrap_or("?").get(..8).unwrap_or("?"),
                    d["learner"]["teacher_share"],
                    d["teacher"].as_str().unwrap_or("?")
                ),
                    None => format!("`{}` drove", d["teacher"].as_str().unwrap_or("?")),
                };
            format!(
                "| more data | `{}`: {} tests ({} points, seed {}), {} frames; {driver}; steering \
                 noise ±{} |\n",
                d["scenario"].as_str().unwrap_or("?"),
                d["tests"],
                d["strategy"].as_str().unwrap_or("?"),
                d["seed"],
                d["frames"],
                d["steer_noise"]
            )
        })
        .collect::<String>();
    let stem = args
        .out
        .file_name()
        .map_or("pilotnet".into(), |n| n.to_string_lossy().into_owned());
    let noise = dataset["steer_noise"].as_f64().unwrap_or(0.0);
    format!(
        "# Model card: {stem}\n\n\
         A PilotNet-style network (Bojarski et al. 2016, the system PARACOSM §4.2.2 tests), \
         scaled down for CPU: 4 convolutions, 3 dense layers, {params} parameters; input a \
         48 × 96 crop of the 320 × 240 camera (rows 96–200, columns 60–260) and the ego speed; \
         output throttle and steering in (-1, 1).\n\n\
         | | |\n|---|---|\n\
         | training scenario | `{scenario}` |\n\
         | teacher | `{teacher}` (lidar time-to-collision braking, lane keeping) |\n\
         | tests | {tests} ({strategy} points, seed {dseed}) at {rate} frames/s{noise} |\n\
         {more}\
         | frames | {n} ({ntrain} training, {nvalid} validation: tests with id mod {h} = {hl}) |\n\
         | training | candle-nn {cv}, AdamW lr {lr} (linear warm-up over {warm} steps, then a \
         half cosine to {flr} of it), gradient norm clipped at {clip}, batch {batch}, at most \
         {epochs} epochs with early stopping after {patience} without a better validation score \
         (weights of epoch {best} kept), seed {seed}, MSE on (throttle, steering){sw} |\n\
         | validation MSE | throttle {t:.4}, steering {st:.5} |\n\
         | closed-loop validation | {closed} |\n\
         | braking agreement | {agree:.1} % of validation frames (throttle < -0.5 on both or \
         neither) |\n\
         | training time | {secs:.0} s on {threads} threads |\n\
         | file | `{stem}.onnx`, {bytes} bytes, ONNX opset 13; manifest `{stem}.toml` |\n\n\
         Parameter ranges of the training data are those of the scenario (see its header). \
         Outside them the network has seen nothing: that is what the studies in \
         docs/experiments.md, \"Learned drivers\", probe.\n\n\
         Training log:\n\n```\n{log}\n```\n",
        params = pilotnet::parameter_count(),
        scenario = dataset["scenario"].as_str().unwrap_or("?"),
        teacher = dataset["teacher"].as_str().unwrap_or("?"),
        tests = dataset["tests"],
        strategy = dataset["strategy"].as_str().unwrap_or("?"),
        dseed = dataset["seed"],
        rate = dataset["rate_hz"],
        h = args.holdout_every,
        hl = args.holdout_every - 1,
        cv = "0.11",
        lr = args.lr,
        batch = args.batch,
        epochs = args.epochs,
        warm = args.warmup_steps,
        flr = args.final_lr,
        clip = args.clip,
        patience = args.patience,
        best = best_epoch,
        seed = args.seed,
        closed = match &args.closed_loop {
            Some(name) => format!(
                "after each epoch the network drove {} tests of `{name}` (Halton points from \
                 {CLOSED_LOOP_FROM} on); the epoch with the fewest failures was kept",
                args.closed_loop_tests
            ),
            None => "none".to_owned(),
        },
        agree = 100.0 * agree,
        secs = started.elapsed().as_secs_f64(),
        threads = rayon::current_num_threads(),
        log = log.join("\n"),
        noise = if noise > 0.0 {
            format!(
                ", steering noise ±{noise} held {} s injected while the teacher drove (DART)",
                dataset["noise_hold_s"]
            )
        } else {
            String::new()
        },
        sw = if args.steering_weight == 1.0 {
            String::new()
        } else {
            format!(", steering weighted {}", args.steering_weight)
        } + &if args.smooth_s > 0.0 {
            format!(
                ", throttle targets averaged over {} s centred on each frame (validation too)",
                args.smooth_s
            )
        } else {
            String::new()
        } + &if args.brake_weight == 1.0 {
            String::new()
        } else {
            format!(", braking frames weighted {}", args.brake_weight)
        },
    )
}
