//! Trains the PilotNet-style network ([`paracosm_experiments::pilotnet`]) on a data set
//! written by `paracosm-fuzz dataset`, on the CPU with candle-nn, and writes it as ONNX with
//! its manifest and a model card ([`paracosm_experiments::pilotnet_training`]).
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

use anyhow::Result;
use clap::Parser;
use paracosm_experiments::pilotnet_training::{self, TrainConfig};

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

impl Args {
    /// The library's settings for these options.
    fn config(self) -> TrainConfig {
        TrainConfig {
            data: self.data,
            out: self.out,
            epochs: self.epochs,
            batch: self.batch,
            lr: self.lr,
            seed: self.seed,
            holdout_every: self.holdout_every,
            steering_weight: self.steering_weight,
            smooth_s: self.smooth_s,
            brake_weight: self.brake_weight,
            warmup_steps: self.warmup_steps,
            final_lr: self.final_lr,
            clip: self.clip,
            patience: self.patience,
            closed_loop: self.closed_loop,
            save_epochs: self.save_epochs,
            closed_loop_tests: self.closed_loop_tests,
        }
    }
}

fn main() -> Result<()> {
    pilotnet_training::train(&Args::parse().config())?;
    Ok(())
}
