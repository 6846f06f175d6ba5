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

use std::path::PathBuf;

use anyhow::Result;
use clap::{Parser, Subcommand};
use paracosm_experiments::perception::train::TrainConfig;
use paracosm_experiments::perception::{studies, train, Task};

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

impl TrainArgs {
    /// The library's settings for these options.
    fn config(self) -> TrainConfig {
        TrainConfig {
            task: self.task,
            data: self.data,
            out: self.out,
            epochs: self.epochs,
            batch: self.batch,
            lr: self.lr,
            warmup_steps: self.warmup_steps,
            seed: self.seed,
            holdout_every: self.holdout_every,
            positive_weight: self.positive_weight,
            patience: self.patience,
        }
    }
}

fn main() -> Result<()> {
    match Cli::parse().command {
        Command::Train(args) => train::train(&args.config())?,
        Command::RoadStudy { model, data, out } => studies::road_study(&model, &data, &out)?,
        Command::DriveStudy { model, data, out } => studies::drive_study(&model, &data, &out)?,
    }
    Ok(())
}
