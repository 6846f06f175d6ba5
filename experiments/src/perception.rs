//! The perception networks of the paper's §4.1 studies: a small fully convolutional network
//! (after Long, Shelhamer & Darrell, "Fully Convolutional Networks for Semantic Segmentation",
//! 2015, scaled down for CPU) that reads a 160 × 120 camera image and answers one logit per
//! 4 × 4 block of pixels: a 30 × 40 map. Trained with `candle-nn` on paracosm's own masks
//! and boxes (`paracosm-fuzz dataset`), written as ONNX with [`crate::onnx_export`] and run
//! by tract ([`OnnxMap`]).
//!
//! - **Road segmentation** ([`Task::Road`], Figures 5–6): a block's target is the share of
//!   its pixels that are road (mask classes 2 road and 3 lane marking); a pixel is called road
//!   when its block's logit is above 0.
//! - **Vehicle detection** ([`Task::Vehicles`], Figures 7–8): a centre-point detector (the
//!   heat map of CenterNet, Zhou, Wang & Krähenbühl, "Objects as Points", 2019, without the
//!   size head): a block's target is 1 where the centre of a car's COCO box falls; a
//!   detection is a block whose logit is above 0 and is the largest of its 3 × 3
//!   neighbours ([`detections`]), and it finds the box it lies in ([`match_detections`]).
//!
//! Input `image` `[1, 3, 120, 160]`, RGB, each channel `(level / 255 - 0.5) / 0.25`; output
//! `logits` `[1, 1, 30, 40]`, row-major.
//!
//! [`train`] trains either network on a data set and writes it with its model card;
//! [`studies`] runs the studies of Figures 5–8 with a trained one.

use std::collections::HashMap;

use candle_core::{Module, Tensor};
use candle_nn::{Conv2d, Conv2dConfig, VarBuilder};
use rand::{Rng, SeedableRng};

use crate::onnx_export::Graph;

mod data;
pub mod studies;
pub mod train;

/// Height of the network's image, pixels.
pub const HEIGHT: usize = 120;
/// Width of the network's image, pixels.
pub const WIDTH: usize = 160;
/// Pixels per side of the block each output answers for.
pub const BLOCK: usize = 4;
/// Rows of the output map: `HEIGHT / BLOCK`.
pub const OUT_H: usize = HEIGHT / BLOCK;
/// Columns of the output map: `WIDTH / BLOCK`.
pub const OUT_W: usize = WIDTH / BLOCK;

/// The convolutions: `(name, in, out, kernel, stride, padding, dilation)`; a ReLU after each
/// but the last (`head`). The dilated ones widen what each output sees to 65 × 65 pixels.
pub const CONVS: [(&str, usize, usize, usize, usize, usize, usize); 6] = [
    ("conv1", 3, 16, 5, 2, 2, 1),
    ("conv2", 16, 32, 3, 2, 1, 1),
    ("conv3", 32, 32, 3, 1, 2, 2),
    ("conv4", 32, 32, 3, 1, 4, 4),
    ("conv5", 32, 32, 3, 1, 1, 1),
    ("head", 32, 1, 1, 1, 0, 1),
];

/// What a network is trained to find.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Task {
    /// Road pixels (mask classes 2 and 3).
    Road,
    /// Cars' box centres.
    Vehicles,
}

/// Mask class ids that count as road: road and lane marking (`paracosm-fuzz dataset`'s masks).
pub const ROAD_CLASSES: [u8; 2] = [2, 3];
/// The COCO category id of cars in `annotations.json`.
pub const CAR_CATEGORY: u64 = 5;
/// The COCO category id of obstacles (static boxes, such as the drive study's truck).
pub const OBSTACLE_CATEGORY: u64 = 7;
/// Boxes with fewer visible pixels than this are neither targets nor counted as visible
/// (at 160 × 120, a car about 60 m ahead shows 20 pixels).
pub const MIN_AREA: u64 = 12;

pub use crate::weights::{tensors, Weight};

/// The network.
pub struct Fcn {
    convs: Vec<Conv2d>,
}

/// The number of parameters.
pub fn parameter_count() -> usize {
    CONVS
        .iter()
        .map(|&(_, i, o, k, _, _, _)| o * i * k * k + o)
        .sum()
}

impl Fcn {
    /// The network over the variables of `vb` (`conv1.weight`, `conv1.bias`, ...).
    ///
    /// # Errors
    /// candle's, when a variable is missing or has another shape.
    pub fn new(vb: &VarBuilder<'_>) -> candle_core::Result<Self> {
        let convs = CONVS
            .iter()
            .map(|&(name, i, o, k, stride, padding, dilation)| {
                candle_nn::conv2d(
                    i,
                    o,
                    k,
                    Conv2dConfig {
                        padding,
                        stride,
                        dilation,
                        ..Default::default()
                    },
                    vb.pp(name),
                )
            })
            .collect::<candle_core::Result<Vec<_>>>()?;
        Ok(Fcn { convs })
    }

    /// Logits `[n, 1, 30, 40]` for images `[n, 3, 120, 160]`.
    ///
    /// # Errors
    /// candle's, for tensors of other shapes.
    pub fn forward(&self, image: &Tensor) -> candle_core::Result<Tensor> {
        let mut x = image.clone();
        for (k, c) in self.convs.iter().enumerate() {
            x = c.forward(&x)?;
            if k + 1 < self.convs.len() {
                x = x.relu()?;
            }
        }
        Ok(x)
    }
}

/// Every variable's name and shape, in a fixed order.
pub fn variables() -> Vec<(String, Vec<usize>)> {
    let mut out = Vec::new();
    for &(name, i, o, k, _, _, _) in &CONVS {
        out.push((format!("{name}.weight"), vec![o, i, k, k]));
        out.push((format!("{name}.bias"), vec![o]));
    }
    out
}

/// Initial weights from ChaCha8 seeded with `seed`: He-uniform weights (bound
/// `sqrt(6 / fan_in)`), zero biases, the head's bound a tenth of that; the head's bias
/// `head_bias` (the logit of the targets' mean, so that training starts from the base rate).
pub fn initial_weights(seed: u64, head_bias: f32) -> Vec<Weight> {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    variables()
        .into_iter()
        .map(|(name, shape)| {
            let n: usize = shape.iter().product();
            let data = if name == "head.bias" {
                vec![head_bias; n]
            } else if name.ends_with(".bias") {
                vec![0.0; n]
            } else {
                let fan_in: usize = shape[1..].iter().product();
                let scale = if name == "head.weight" { 0.1 } else { 1.0 };
                let bound = (scale * (6.0 / fan_in as f64).sqrt()) as f32;
                (0..n).map(|_| rng.random_range(-bound..bound)).collect()
            };
            (name, shape, data)
        })
        .collect()
}

/// The network as an ONNX file: input `image` `[1, 3, 120, 160]`, output `logits`
/// `[1, 1, 30, 40]`; the weights are initializers named as the variables.
pub fn to_onnx(weights: &[Weight], name: &str, doc: &str) -> Vec<u8> {
    let by_name: HashMap<&str, (&Vec<usize>, &Vec<f32>)> = weights
        .iter()
        .map(|(n, s, d)| (n.as_str(), (s, d)))
        .collect();
    let mut g = Graph::new();
    let mut x = g.input("image", &[1, 3, HEIGHT, WIDTH]);
    for (k, &(layer, _, _, _, stride, pad, dilation)) in CONVS.iter().enumerate() {
        let mut w = |n: String| {
            let (shape, data) = by_name[n.as_str()];
            g.named_constant(&n, shape, data.clone())
        };
        let (wt, b) = (w(format!("{layer}.weight")), w(format!("{layer}.bias")));
        let c = g.conv_dilated(&x, &wt, &b, stride, pad, dilation);
        x = if k + 1 < CONVS.len() { g.relu(&c) } else { c };
    }
    let out = g.rename_output(&x, "logits");
    g.output(&out, &[1, 1, OUT_H, OUT_W]);
    g.encode(name, doc)
}

/// The network's input for an RGB image: `[3, 120, 160]` row-major, each channel
/// `(level / 255 - 0.5) / 0.25`; an image of another size is resized (bilinear) first.
pub fn preprocess(rgb: &image::RgbImage) -> Vec<f32> {
    let resized;
    let img = if rgb.dimensions() == (WIDTH as u32, HEIGHT as u32) {
        rgb
    } else {
        resized = image::imageops::resize(
            rgb,
            WIDTH as u32,
            HEIGHT as u32,
            image::imageops::FilterType::Triangle,
        );
        &resized
    };
    let mut out = vec![0.0f32; 3 * HEIGHT * WIDTH];
    for (x, y, p) in img.enumerate_pixels() {
        for c in 0..3 {
            out[(c * HEIGHT + y as usize) * WIDTH + x as usize] =
                (f32::from(p[c]) / 255.0 - 0.5) / 0.25;
        }
    }
    out
}

/// Per block of an `h × w` class mask (row-major, `h = 120`, `w = 160`), the share of its
/// pixels that are road: `[30 × 40]` row-major, each in `[0, 1]`.
pub fn road_targets(mask: &[u8]) -> Vec<f32> {
    let mut t = vec![0.0f32; OUT_H * OUT_W];
    for (i, &class) in mask.iter().enumerate() {
        if ROAD_CLASSES.contains(&class) {
            let (y, x) = (i / WIDTH, i % WIDTH);
            t[(y / BLOCK) * OUT_W + x / BLOCK] += 1.0 / (BLOCK * BLOCK) as f32;
        }
    }
    t
}

/// A car's box `[x, y, w, h]` in pixels of the 160 × 120 image.
pub type BoxPx = [f64; 4];

/// The centre-point targets for `boxes`: `[30 × 40]` row-major, 1 in the block holding each
/// box's centre, 0 elsewhere.
pub fn centre_targets(boxes: &[BoxPx]) -> Vec<f32> {
    let mut t = vec![0.0f32; OUT_H * OUT_W];
    for b in boxes {
        let (cx, cy) = (b[0] + b[2] / 2.0, b[1] + b[3] / 2.0);
        let col = ((cx / BLOCK as f64) as usize).min(OUT_W - 1);
        let row = ((cy / BLOCK as f64) as usize).min(OUT_H - 1);
        t[row * OUT_W + col] = 1.0;
    }
    t
}

/// Pixel counts of a road prediction against a mask: `[true positive, false negative,
/// false positive, true negative]`; the prediction is `logits` (`[30 × 40]`) above 0, each
/// block's answer taken for its 4 × 4 pixels; the truth is the mask's road classes.
pub fn road_counts(logits: &[f32], mask: &[u8]) -> [u64; 4] {
    let mut c = [0u64; 4];
    for (i, &class) in mask.iter().enumerate() {
        let (y, x) = (i / WIDTH, i % WIDTH);
        let said = logits[(y / BLOCK) * OUT_W + x / BLOCK] > 0.0;
        let road = ROAD_CLASSES.contains(&class);
        c[match (road, said) {
            (true, true) => 0,
            (true, false) => 1,
            (false, true) => 2,
            (false, false) => 3,
        }] += 1;
    }
    c
}

/// The detections of a centre-point map: the blocks whose logit is above 0 and at least each
/// of their 3 × 3 neighbours', as pixel centres `(x, y)` of the 160 × 120 image.
pub fn detections(logits: &[f32]) -> Vec<(f64, f64)> {
    let at = |r: isize, c: isize| {
        if r < 0 || c < 0 || r >= OUT_H as isize || c >= OUT_W as isize {
            f32::NEG_INFINITY
        } else {
            logits[r as usize * OUT_W + c as usize]
        }
    };
    let mut out = Vec::new();
    for r in 0..OUT_H as isize {
        for c in 0..OUT_W as isize {
            let v = at(r, c);
            let peak = (-1..=1).all(|dr| (-1..=1).all(|dc| at(r + dr, c + dc) <= v));
            if v > 0.0 && peak {
                let b = BLOCK as f64;
                out.push(((c as f64 + 0.5) * b, (r as f64 + 0.5) * b));
            }
        }
    }
    out
}

/// Whether the pixel `(x, y)` lies in box `b` widened by `slack` pixels on each side.
pub fn contains(b: &BoxPx, (x, y): (f64, f64), slack: f64) -> bool {
    x >= b[0] - slack && x <= b[0] + b[2] + slack && y >= b[1] - slack && y <= b[1] + b[3] + slack
}

/// Detections against the visible boxes: `(whether each box is found, false positives)`. A box is found
/// when a detection lies inside it (one block of slack each side, as a detection is a
/// block's centre); each detection finds at most one box (the nearest centre), and a
/// detection inside no box is a false positive.
pub fn match_detections(dets: &[(f64, f64)], boxes: &[BoxPx]) -> (Vec<bool>, usize) {
    let slack = BLOCK as f64;
    let mut found = vec![false; boxes.len()];
    let mut false_positives = 0;
    for &(x, y) in dets {
        let best = boxes
            .iter()
            .enumerate()
            .filter(|(k, b)| !found[*k] && contains(b, (x, y), slack))
            .min_by(|(_, a), (_, b)| {
                let d = |b: &&BoxPx| (b[0] + b[2] / 2.0 - x).hypot(b[1] + b[3] / 2.0 - y);
                d(a).total_cmp(&d(b))
            });
        match best {
            Some((k, _)) => found[k] = true,
            None => {
                // Inside a box already found counts as a duplicate, not a false positive.
                let inside = boxes.iter().any(|b| contains(b, (x, y), slack));
                false_positives += usize::from(!inside);
            }
        }
    }
    (found, false_positives)
}

/// An ONNX map network ([`to_onnx`]'s interface) run by tract.
pub struct OnnxMap {
    plan: std::sync::Arc<tract_onnx::prelude::TypedRunnableModel>,
}

/// Why an ONNX map network cannot be loaded or run.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct OnnxMapError(String);

impl OnnxMap {
    /// Loads an ONNX file whose input is `[1, 3, 120, 160]` and whose first output has
    /// 30 × 40 values.
    ///
    /// # Errors
    /// [`OnnxMapError`] with tract's message when it cannot read or plan the model.
    pub fn load(path: &std::path::Path) -> Result<Self, OnnxMapError> {
        use tract_onnx::prelude::*;
        let fail = |e: TractError| OnnxMapError(format!("{}: {e:#}", path.display()));
        let plan = tract_onnx::onnx()
            .model_for_path(path)
            .and_then(|m| m.with_input_fact(0, f32::fact([1, 3, HEIGHT, WIDTH]).into()))
            .and_then(|m| m.into_optimized())
            .and_then(|m| m.into_runnable())
            .map_err(fail)?;
        Ok(OnnxMap { plan })
    }

    /// The logits `[30 × 40]` for one input from [`preprocess`].
    ///
    /// # Errors
    /// [`OnnxMapError`] with tract's message, or when the output has another size.
    pub fn run(&self, input: &[f32]) -> Result<Vec<f32>, OnnxMapError> {
        use tract_onnx::prelude::*;
        let t = Tensor::from_shape(&[1, 3, HEIGHT, WIDTH], input)
            .map_err(|e| OnnxMapError(format!("{e:#}")))?;
        let out = self
            .plan
            .run(tvec!(t.into()))
            .map_err(|e| OnnxMapError(format!("{e:#}")))?;
        let v: Vec<f32> = out[0]
            .to_plain_array_view::<f32>()
            .map_err(|e| OnnxMapError(format!("{e:#}")))?
            .iter()
            .copied()
            .collect();
        if v.len() != OUT_H * OUT_W {
            return Err(OnnxMapError(format!(
                "the output has {} values, not {}",
                v.len(),
                OUT_H * OUT_W
            )));
        }
        Ok(v)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_block_counts_for_its_pixels_and_a_peak_is_one_detection() {
        let mut mask = vec![0u8; WIDTH * HEIGHT];
        // The top-left block all road, the next half road.
        for y in 0..4 {
            for x in 0..6 {
                mask[y * WIDTH + x] = 2;
            }
        }
        let t = road_targets(&mask);
        assert_eq!((t[0], t[1], t[2]), (1.0, 0.5, 0.0));
        let mut logits = vec![-1.0f32; OUT_H * OUT_W];
        logits[0] = 1.0;
        logits[1] = 1.0;
        // 16 + 16 pixels said road, of which 16 + 8 are.
        assert_eq!(
            road_counts(&logits, &mask),
            [24, 0, 8, (WIDTH * HEIGHT - 32) as u64]
        );
        let dets = detections(&logits);
        // Two equal neighbours: both are peaks (ties kept), and both find the same box once.
        assert_eq!(dets.len(), 2);
        let boxes = [[0.0, 0.0, 8.0, 4.0], [100.0, 100.0, 10.0, 10.0]];
        assert_eq!(match_detections(&dets, &boxes), (vec![true, false], 0));
        assert_eq!(
            match_detections(&[(50.0, 50.0)], &boxes),
            (vec![false, false], 1)
        );
        let c = centre_targets(&boxes);
        assert_eq!(c.iter().filter(|&&v| v == 1.0).count(), 2);
        // Centres (4, 2) and (105, 105): blocks (row 0, column 1) and (26, 26).
        assert_eq!((c[0], c[1]), (0.0, 1.0));
        assert_eq!(c[26 * OUT_W + 26], 1.0);
    }

    #[test]
    fn the_onnx_file_computes_what_candle_computes() {
        use candle_core::DType;
        let weights = initial_weights(3, -0.5);
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("fcn.onnx");
        std::fs::write(&path, to_onnx(&weights, "fcn", "test")).unwrap();
        let onnx = OnnxMap::load(&path).unwrap();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
        let input: Vec<f32> = (0..3 * HEIGHT * WIDTH)
            .map(|_| rng.random_range(-2.0..2.0))
            .collect();
        let a = onnx.run(&input).unwrap();
        let dev = candle_core::Device::Cpu;
        let vb = VarBuilder::from_tensors(tensors(&weights, &dev).unwrap(), DType::F32, &dev);
        let net = Fcn::new(&vb).unwrap();
        let x = Tensor::from_vec(input, (1, 3, HEIGHT, WIDTH), &dev).unwrap();
        let b: Vec<f32> = net
            .forward(&x)
            .unwrap()
            .flatten_all()
            .unwrap()
            .to_vec1()
            .unwrap();
        assert_eq!(a.len(), b.len());
        let worst = a
            .iter()
            .zip(&b)
            .map(|(p, q)| (p - q).abs())
            .fold(0.0f32, f32::max);
        assert!(worst < 1e-4, "tract and candle differ by {worst}");
    }
}
