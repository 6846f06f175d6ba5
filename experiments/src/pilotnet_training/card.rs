//! The model card (Markdown) written beside a trained network.

use std::time::Instant;

use super::closed_loop::CLOSED_LOOP_FROM;
use super::TrainConfig;
use crate::pilotnet;

/// The model card (Markdown): the network, the data sets it was trained on (`datasets`, their
/// `dataset.json`; the first describes the table's rows, the others a row each), the training
/// and validation frame counts (`split`), the settings, the `[throttle MSE, steering MSE,
/// braking agreement]` on the validation frames, the ONNX file's size in bytes, the training
/// `log` and the epoch whose weights were kept.
pub(super) fn model_card(
    args: &TrainConfig,
    datasets: &[serde_json::Value],
    (ntrain, nvalid): (usize, usize),
    [t, st, agree]: [f64; 3],
    bytes: usize,
    (log, best_epoch): (&[String], usize),
    started: Instant,
) -> String {
    let n = ntrain + nvalid;
    let dataset = &datasets[0];
    let more = more_datasets(datasets);
    let stem = args
        .out
        .file_name()
        .map_or("pilotnet".into(), |n| n.to_string_lossy().into_owned());
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
        closed = closed_loop_setting(args),
        agree = 100.0 * agree,
        secs = started.elapsed().as_secs_f64(),
        threads = rayon::current_num_threads(),
        log = log.join("\n"),
        noise = noise_setting(dataset),
        sw = loss_settings(args),
    )
}

/// A table row for each data set after the first: its scenario, tests, frames, who drove and
/// the steering noise.
fn more_datasets(datasets: &[serde_json::Value]) -> String {
    datasets
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
        .collect::<String>()
}

/// The closed-loop validation in words, or `none`.
fn closed_loop_setting(args: &TrainConfig) -> String {
    match &args.closed_loop {
        Some(name) => format!(
            "after each epoch the network drove {} tests of `{name}` (Halton points from \
             {CLOSED_LOOP_FROM} on); the epoch with the fewest failures was kept",
            args.closed_loop_tests
        ),
        None => "none".to_owned(),
    }
}

/// The steering noise the first data set's teacher drove with, or nothing when none.
fn noise_setting(dataset: &serde_json::Value) -> String {
    let noise = dataset["steer_noise"].as_f64().unwrap_or(0.0);
    if noise > 0.0 {
        format!(
            ", steering noise ±{noise} held {} s injected while the teacher drove (DART)",
            dataset["noise_hold_s"]
        )
    } else {
        String::new()
    }
}

/// The loss's departures from plain MSE: steering weight, smoothed throttle targets, braking
/// frames' weight (each only when set).
fn loss_settings(args: &TrainConfig) -> String {
    (if args.steering_weight == 1.0 {
        String::new()
    } else {
        format!(", steering weighted {}", args.steering_weight)
    }) + &if args.smooth_s > 0.0 {
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
    }
}
