//! The frames of the data sets written by `paracosm-fuzz dataset` (`frames.csv` and its
//! images), pooled, as the network's inputs and the teacher's controls, and batches of them.

use std::path::Path;

use candle_core::{Device, Tensor};
use paracosm_engine::sut::{preprocess, Manifest};
use rayon::prelude::*;

use super::TrainConfig;
use crate::pilotnet::{PilotNet, HEIGHT, WIDTH};
use crate::training_error::TrainingError;

/// Values of one network image: `3 × 48 × 96`.
pub(super) const PIXELS: usize = 3 * HEIGHT * WIDTH;

/// The frames of one or more data sets.
pub(super) struct Frames {
    /// The images, [`PIXELS`] values a frame, row-major.
    pub(super) images: Vec<f32>,
    /// The ego's speed at each frame, m/s.
    pub(super) speeds: Vec<f32>,
    /// The teacher's throttle and steering at each frame, `n × 2` row-major.
    pub(super) targets: Vec<f32>,
    /// Each frame's test: the id within its data set, the data set's index in the upper 32
    /// bits.
    pub(super) tests: Vec<u64>,
    /// Each frame's time in its test, s.
    pub(super) times: Vec<f64>,
}

/// The frames of every data set of `args.data` (at least one), pooled, with the throttle
/// targets smoothed over `args.smooth_s` when positive.
pub(super) fn load_all(args: &TrainConfig, manifest: &Manifest) -> Result<Frames, TrainingError> {
    let mut frames = load(&args.data[0], manifest)?;
    for (k, more) in args.data.iter().enumerate().skip(1) {
        let f = load(more, manifest)?;
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
    Ok(frames)
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

/// The frames of the data set in `data`, its images preprocessed as `manifest` says (in
/// parallel).
fn load(data: &Path, manifest: &Manifest) -> Result<Frames, TrainingError> {
    let index = data.join("frames.csv");
    let mut reader = csv::Reader::from_path(&index).map_err(|source| TrainingError::CsvOpen {
        path: index.clone(),
        source,
    })?;
    let header = reader.headers()?.clone();
    let col = |n: &str| {
        header
            .iter()
            .position(|h| h == n)
            .ok_or_else(|| TrainingError::Data(format!("{}: no column `{n}`", index.display())))
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
                .map_err(|source| TrainingError::Image {
                    path: path.clone(),
                    source,
                })?
                .to_rgb8();
            Ok(preprocess(&rgb, &manifest.input))
        })
        .collect::<Result<_, TrainingError>>()?;
    let mut f = Frames {
        images: Vec::with_capacity(rows.len() * PIXELS),
        speeds: Vec::new(),
        targets: Vec::new(),
        tests: Vec::new(),
        times: Vec::new(),
    };
    for (r, x) in rows.iter().zip(images) {
        if x.len() != PIXELS {
            return Err(TrainingError::Data(format!(
                "an input has {} values, not {PIXELS}",
                x.len()
            )));
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

/// The frames `idx` of `f` as tensors: images `[n, 3, 48, 96]`, speeds `[n, 1]` (m/s) and
/// targets `[n, 2]` (throttle, steering).
pub(super) fn batch(
    f: &Frames,
    idx: &[usize],
    dev: &Device,
) -> Result<(Tensor, Tensor, Tensor), TrainingError> {
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
pub(super) fn evaluate(
    net: &PilotNet,
    f: &Frames,
    idx: &[usize],
    dev: &Device,
) -> Result<[f64; 3], TrainingError> {
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
