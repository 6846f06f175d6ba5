//! A PilotNet-style driving network (Bojarski et al., "End to End Learning for Self-Driving
//! Cars", 2016; the system the paper tests in §4.2.2), scaled down for CPU training: four
//! convolutions and three fully connected layers, 183,192 parameters, on a 48 × 96 crop of the
//! camera image and the ego speed. Built and trained with `candle-nn`; written as ONNX with
//! [`crate::onnx_export`] and run in the loop by tract (`paracosm_engine::sut::OnnxSut`).
//!
//! Input: `image` `[n, 3, 48, 96]` (RGB, each channel `(level / 255 - 0.5) / 0.25`, the
//! manifest's `[input]`), `speed` `[n, 1]` in m/s. Output `[n, 2]`: throttle (negative
//! brakes) and steering (positive left), each `tanh`-bounded to `(-1, 1)`.

use std::collections::HashMap;

use candle_core::{DType, Device, Module, Tensor};
use candle_nn::{Conv2d, Conv2dConfig, Linear, VarBuilder};
use rand::{Rng, SeedableRng};

use crate::onnx_export::Graph;

/// Height of the network's image, pixels.
pub const HEIGHT: usize = 48;
/// Width of the network's image, pixels.
pub const WIDTH: usize = 96;
/// The speed enters the first dense layer scaled by this (m/s to about `[0, 1.5]`).
pub const SPEED_SCALE: f32 = 0.1;

/// The convolutions: `(name, in, out, kernel, stride, padding)`.
pub const CONVS: [(&str, usize, usize, usize, usize, usize); 4] = [
    ("conv1", 3, 24, 5, 2, 2),
    ("conv2", 24, 32, 5, 2, 2),
    ("conv3", 32, 48, 3, 2, 1),
    ("conv4", 48, 64, 3, 2, 1),
];

/// Features after the convolutions: 64 channels of 3 × 6.
pub const FEATURES: usize = 64 * 3 * 6;

/// The dense layers: `(name, in, out)`; the first takes the features and the scaled speed.
pub const DENSE: [(&str, usize, usize); 3] =
    [("fc1", FEATURES + 1, 100), ("fc2", 100, 50), ("fc3", 50, 2)];

/// The manifest shipped beside the model (`paracosm_engine::sut::Manifest`).
pub const MANIFEST: &str = r#"# The input and outputs of pilotnet.onnx (docs/systems-under-test.md, "ONNX models").
[camera]
width = 320
height = 240
focal_mm = 24.0
rate_hz = 10.0

[input]
crop = [96, 40, 60, 60]
width = 96
height = 48
channels = "rgb"
layout = "nchw"
mean = [0.5, 0.5, 0.5]
std = [0.25, 0.25, 0.25]
frames = 1
speed = true

[output]
throttle = 0
steering = 1
"#;

pub use crate::weights::{tensors, Weight};

/// The network.
pub struct PilotNet {
    convs: Vec<Conv2d>,
    dense: Vec<Linear>,
}

/// The number of parameters: 183,192.
pub fn parameter_count() -> usize {
    CONVS
        .iter()
        .map(|&(_, i, o, k, _, _)| o * i * k * k + o)
        .chain(DENSE.iter().map(|&(_, i, o)| o * i + o))
        .sum()
}

impl PilotNet {
    /// The network over the variables of `vb` (`conv1.weight`, `conv1.bias`, ...,
    /// `fc3.bias`).
    ///
    /// # Errors
    /// candle's, when a variable is missing or has another shape.
    pub fn new(vb: &VarBuilder<'_>) -> candle_core::Result<Self> {
        let convs = CONVS
            .iter()
            .map(|&(name, i, o, k, stride, padding)| {
                candle_nn::conv2d(
                    i,
                    o,
                    k,
                    Conv2dConfig {
                        padding,
                        stride,
                        ..Default::default()
                    },
                    vb.pp(name),
                )
            })
            .collect::<candle_core::Result<Vec<_>>>()?;
        let dense = DENSE
            .iter()
            .map(|&(name, i, o)| candle_nn::linear(i, o, vb.pp(name)))
            .collect::<candle_core::Result<Vec<_>>>()?;
        Ok(PilotNet { convs, dense })
    }

    /// Outputs `[n, 2]` for images `[n, 3, 48, 96]` and speeds `[n, 1]` (m/s).
    ///
    /// # Errors
    /// candle's, for tensors of other shapes.
    pub fn forward(&self, image: &Tensor, speed: &Tensor) -> candle_core::Result<Tensor> {
        let mut x = image.clone();
        for c in &self.convs {
            x = c.forward(&x)?.relu()?;
        }
        let x = x.flatten_from(1)?;
        let s = (speed * f64::from(SPEED_SCALE))?;
        let mut x = Tensor::cat(&[&x, &s], 1)?;
        for (k, d) in self.dense.iter().enumerate() {
            x = d.forward(&x)?;
            x = if k + 1 < self.dense.len() {
                x.relu()?
            } else {
                x.tanh()?
            };
        }
        Ok(x)
    }
}

/// Every variable's name and shape, in a fixed order.
pub fn variables() -> Vec<(String, Vec<usize>)> {
    let mut out = Vec::new();
    for &(name, i, o, k, _, _) in &CONVS {
        out.push((format!("{name}.weight"), vec![o, i, k, k]));
        out.push((format!("{name}.bias"), vec![o]));
    }
    for &(name, i, o) in &DENSE {
        out.push((format!("{name}.weight"), vec![o, i]));
        out.push((format!("{name}.bias"), vec![o]));
    }
    out
}

/// Initial weights from ChaCha8 seeded with `seed`: He-uniform weights (bound
/// `sqrt(6 / fan_in)`), zero biases; the output layer's bound a tenth of that, so that the
/// network starts near 0 on both outputs, in the linear part of its `tanh` (started at full
/// scale, the first steps could drive both outputs into saturation, where the gradient
/// vanishes and training stalls at "always brake, steer fully"). candle's own initialisation
/// draws from an unseeded generator; these are reproducible.
pub fn initial_weights(seed: u64) -> Vec<Weight> {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    variables()
        .into_iter()
        .map(|(name, shape)| {
            let n: usize = shape.iter().product();
            let data = if name.ends_with(".bias") {
                vec![0.0; n]
            } else {
                let fan_in: usize = shape[1..].iter().product();
                let output = if name == "fc3.weight" { 0.1 } else { 1.0 };
                let bound = (output * (6.0 / fan_in as f64).sqrt()) as f32;
                (0..n)
                    .map(|_| rng.random_range(-bound..bound))
                    .collect::<Vec<f32>>()
            };
            (name, shape, data)
        })
        .collect()
}

/// The network as an ONNX file: inputs `image` `[1, 3, 48, 96]` and `speed` `[1, 1]`, output
/// `controls` `[1, 2]`; the weights are initializers named as the variables.
pub fn to_onnx(weights: &[Weight], doc: &str) -> Vec<u8> {
    let by_name: HashMap<&str, (&Vec<usize>, &Vec<f32>)> = weights
        .iter()
        .map(|(n, s, d)| (n.as_str(), (s, d)))
        .collect();
    let mut g = Graph::new();
    let w = |g: &mut Graph, name: String| {
        let (shape, data) = by_name[name.as_str()];
        g.named_constant(&name, shape, data.clone())
    };
    let mut x = g.input("image", &[1, 3, HEIGHT, WIDTH]);
    let speed = g.input("speed", &[1, 1]);
    for &(name, _, _, _, stride, pad) in &CONVS {
        let (wt, b) = (
            w(&mut g, format!("{name}.weight")),
            w(&mut g, format!("{name}.bias")),
        );
        let c = g.conv(&x, &wt, &b, stride, pad);
        x = g.relu(&c);
    }
    let flat = g.flatten(&x);
    let scale = g.named_constant("speed_scale", &[1], vec![SPEED_SCALE]);
    let s = g.mul(&speed, &scale);
    x = g.concat(&[&flat, &s], 1);
    for (k, &(name, _, _)) in DENSE.iter().enumerate() {
        let (wt, b) = (
            w(&mut g, format!("{name}.weight")),
            w(&mut g, format!("{name}.bias")),
        );
        let y = g.linear(&x, &wt, &b);
        x = if k + 1 < DENSE.len() {
            g.relu(&y)
        } else {
            g.tanh(&y)
        };
    }
    let out = g.rename_output(&x, "controls");
    g.output(&out, &[1, 2]);
    g.encode("pilotnet", doc)
}

/// Why an ONNX file's weights cannot be read back ([`weights_of_onnx`], [`from_onnx`]).
#[derive(Debug, thiserror::Error)]
pub enum OnnxWeightsError {
    /// The bytes are not an ONNX model.
    #[error(transparent)]
    Decode(#[from] prost::DecodeError),
    /// The model has no graph.
    #[error("the model has no graph")]
    NoGraph,
    /// A variable of [`variables`] has no initializer (its name).
    #[error("no initializer `{0}`")]
    Missing(String),
    /// A variable's initializer holds the wrong number of values.
    #[error("`{name}` holds {values} values")]
    Size {
        /// The variable.
        name: String,
        /// How many values it holds.
        values: usize,
    },
    /// candle cannot build the network from the weights.
    #[error(transparent)]
    Candle(#[from] candle_core::Error),
}

/// The weights stored in an ONNX file written by [`to_onnx`], by variable name.
///
/// # Errors
/// [`OnnxWeightsError`] when the bytes are not an ONNX model or a variable is missing or of
/// the wrong size.
pub fn weights_of_onnx(bytes: &[u8]) -> Result<Vec<Weight>, OnnxWeightsError> {
    use prost::Message;
    let model = tract_onnx::pb::ModelProto::decode(bytes)?;
    let graph = model.graph.ok_or(OnnxWeightsError::NoGraph)?;
    variables()
        .into_iter()
        .map(|(name, shape)| {
            let t = graph
                .initializer
                .iter()
                .find(|t| t.name == name)
                .ok_or_else(|| OnnxWeightsError::Missing(name.clone()))?;
            let data: Vec<f32> = t
                .raw_data
                .chunks_exact(4)
                .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                .collect();
            if data.len() != shape.iter().product::<usize>() {
                return Err(OnnxWeightsError::Size {
                    name,
                    values: data.len(),
                });
            }
            Ok((name, shape, data))
        })
        .collect()
}

/// The network with the weights of an ONNX file written by [`to_onnx`], on the CPU.
///
/// # Errors
/// As [`weights_of_onnx`], and [`OnnxWeightsError::Candle`] for candle's.
pub fn from_onnx(bytes: &[u8]) -> Result<PilotNet, OnnxWeightsError> {
    let weights = weights_of_onnx(bytes)?;
    let device = Device::Cpu;
    let map = tensors(&weights, &device)?;
    let vb = VarBuilder::from_tensors(map, DType::F32, &device);
    Ok(PilotNet::new(&vb)?)
}
