//! A learned system under test: an ONNX model run in process by `tract` (pure Rust), fed the
//! ego camera's images through the preprocessing its manifest declares (feature `onnx`).
//!
//! The manifest is a TOML file beside the model with the same stem (`pilotnet.onnx` and
//! `pilotnet.toml`); docs/systems-under-test.md, "ONNX models", documents every key:
//!
//! ```toml
//! [camera]            # the camera the model sees (CameraSpec's keys; defaults as CameraSpec)
//! width = 320
//! height = 240
//! rate_hz = 10        # the model decides once per frame and holds its answer between frames
//!
//! [input]
//! crop = [96, 0, 0, 0]      # pixels cut off [top, bottom, left, right] before resizing
//! width = 64                # the model's image, after resizing (bilinear)
//! height = 32
//! channels = "rgb"          # "rgb", "bgr" or "gray" (the mean of r, g, b)
//! layout = "nchw"           # or "nhwc"
//! mean = [0.5, 0.5, 0.5]    # each channel: (level / 255 - mean) / std
//! std = [0.25, 0.25, 0.25]
//! frames = 1                # frames stacked along the channels, oldest first
//! speed = true              # a second input, shape [1, 1]: the ego speed in m/s
//!
//! [output]                  # indices into the model's first output, flattened
//! throttle = 0              # in [-1, 1], negative brakes
//! steering = 1              # in [-1, 1], positive left
//! # brake = 2, brake_threshold = 0.5: full braking when that output exceeds the threshold
//! # cruise_mps = 12: without `throttle`, hold this speed with the built-in cruise control
//! ```
//!
//! Inference is deterministic: one model per process, shared by the workers, each test
//! running its own state, so verdicts do not depend on `--jobs`.

use std::collections::VecDeque;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};
use thiserror::Error;
use tract_onnx::prelude::*;

use super::{Sensors, Sut, SutError};
use crate::{CameraFrame, CameraSpec, Control, Observation};

/// Why an ONNX model cannot be loaded or run; the message names the file or the model.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum ModelError {
    /// A manifest that is not valid TOML or has a value out of range: `path[:line:col]:` and
    /// what is wrong (the key, its value).
    #[error("{0}")]
    Manifest(String),
    /// A model or manifest file that cannot be read (missing, not a regular file,
    /// unreadable).
    #[error("{0}")]
    Read(String),
    /// A model tract cannot load, or whose inputs or outputs do not fit its manifest.
    #[error("{0}")]
    Model(String),
    /// A run of the model failed: tract's message.
    #[error("{0}")]
    Run(String),
}

/// Channel order of the model's image input.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Channels {
    /// Red, green, blue.
    #[default]
    Rgb,
    /// Blue, green, red (OpenCV's order).
    Bgr,
    /// One channel: the mean of red, green and blue.
    Gray,
}

impl Channels {
    /// How many channels one frame has: 3, or 1 for gray.
    pub fn count(self) -> usize {
        match self {
            Channels::Gray => 1,
            _ => 3,
        }
    }
}

/// Memory layout of the image input.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Layout {
    /// `[1, channels, height, width]`.
    #[default]
    Nchw,
    /// `[1, height, width, channels]`.
    Nhwc,
}

fn one() -> u32 {
    1
}

/// `[input]` of a manifest: how a camera frame becomes the model's input tensor.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InputSpec {
    /// Pixels cut off the camera image `[top, bottom, left, right]` before resizing.
    #[serde(default)]
    pub crop: [u32; 4],
    /// Width of the model's image in pixels, `>= 1`, after resizing (bilinear).
    pub width: u32,
    /// Height of the model's image in pixels, `>= 1`.
    pub height: u32,
    /// Channel order.
    #[serde(default)]
    pub channels: Channels,
    /// Memory layout.
    #[serde(default)]
    pub layout: Layout,
    /// Per-channel mean subtracted from `level / 255` (one value per channel).
    #[serde(default)]
    pub mean: Vec<f32>,
    /// Per-channel divisor after the mean (one value per channel, each `> 0`).
    #[serde(default)]
    pub std: Vec<f32>,
    /// Frames stacked along the channel axis, oldest first, `1..=16`. The first frames of a
    /// test repeat the first image.
    #[serde(default = "one")]
    pub frames: u32,
    /// Whether the model has a second input `[1, 1]`: the ego speed in m/s.
    #[serde(default)]
    pub speed: bool,
}

fn half() -> f64 {
    0.5
}

/// `[output]` of a manifest: which outputs drive the vehicle.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OutputSpec {
    /// Index of the throttle (`[-1, 1]`, negative brakes) in the first output.
    pub throttle: Option<usize>,
    /// Index of the steering (`[-1, 1]`, positive left).
    pub steering: Option<usize>,
    /// Index of a brake score: full braking when it exceeds `brake_threshold`.
    pub brake: Option<usize>,
    /// Threshold of `brake`. Default 0.5.
    #[serde(default = "half")]
    pub brake_threshold: f64,
    /// Without `throttle`: the speed in m/s the built-in cruise control holds.
    pub cruise_mps: Option<f64>,
}

/// A model's manifest: its camera, its input and its outputs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Manifest {
    /// The camera the model sees.
    #[serde(default)]
    pub camera: CameraSpec,
    /// How a frame becomes the input.
    pub input: InputSpec,
    /// What the outputs mean.
    pub output: OutputSpec,
}

impl Manifest {
    /// Reads and checks a manifest.
    ///
    /// # Errors
    /// [`ModelError::Manifest`] naming `path` and the key: TOML syntax (with line and
    /// column), an unknown key, a value out of range, no way to set the throttle.
    pub fn parse(text: &str, path: &Path) -> Result<Manifest, ModelError> {
        let m: Manifest = toml::from_str(text).map_err(|e| {
            let at = e
                .span()
                .map(|s| {
                    let before = &text[..s.start.min(text.len())];
                    let line = before.matches('\n').count() + 1;
                    let col = before.len() - before.rfind('\n').map_or(0, |i| i + 1) + 1;
                    format!(":{line}:{col}")
                })
                .unwrap_or_default();
            ModelError::Manifest(format!("{}{at}: {}", path.display(), e.message()))
        })?;
        m.check()
            .map_err(|e| ModelError::Manifest(format!("{}: {e}", path.display())))?;
        Ok(m)
    }

    /// Checks the ranges the manifest's keys document.
    ///
    /// # Errors
    /// [`ModelError::Manifest`] naming the first key out of range (without the file).
    fn check(&self) -> Result<(), ModelError> {
        self.camera
            .validate()
            .map_err(|e| ModelError::Manifest(e.to_string()))?;
        let i = &self.input;
        let [top, bottom, left, right] = i.crop;
        if u64::from(top) + u64::from(bottom) >= u64::from(self.camera.height)
            || u64::from(left) + u64::from(right) >= u64::from(self.camera.width)
        {
            return Err(ModelError::Manifest(format!(
                "input.crop {:?} leaves nothing of the {}x{} camera image",
                i.crop, self.camera.width, self.camera.height
            )));
        }
        if !(1..=4096).contains(&i.width) || !(1..=4096).contains(&i.height) {
            return Err(ModelError::Manifest(format!(
                "input size {}x{} is outside 1..=4096",
                i.width, i.height
            )));
        }
        if !(1..=16).contains(&i.frames) {
            return Err(ModelError::Manifest(format!(
                "input.frames {} is outside 1..=16",
                i.frames
            )));
        }
        let c = i.channels.count();
        for (name, v) in [("mean", &i.mean), ("std", &i.std)] {
            if !v.is_empty() && v.len() != c {
                return Err(ModelError::Manifest(format!(
                    "input.{name} has {} values for {c} channels",
                    v.len()
                )));
            }
            if v.iter().any(|x| !x.is_finite()) {
                return Err(ModelError::Manifest(format!(
                    "input.{name} {v:?} is not finite"
                )));
            }
        }
        if i.std.iter().any(|&s| s <= 0.0) {
            return Err(ModelError::Manifest(format!(
                "input.std {:?} must be > 0",
                i.std
            )));
        }
        let o = &self.output;
        match (o.throttle, o.cruise_mps) {
            (None, None) => {
                return Err(ModelError::Manifest(
                    "output needs `throttle` (an index) or `cruise_mps` (a speed to hold)".into(),
                ))
            }
            (_, Some(v)) if !(v.is_finite() && v >= 0.0) => {
                return Err(ModelError::Manifest(format!(
                    "output.cruise_mps {v} must be >= 0"
                )))
            }
            _ => {}
        }
        if !o.brake_threshold.is_finite() {
            return Err(ModelError::Manifest(
                "output.brake_threshold is not finite".into(),
            ));
        }
        Ok(())
    }

    /// The shape of the image input: `[1, c·frames, h, w]` or `[1, h, w, c·frames]`.
    pub fn input_shape(&self) -> [usize; 4] {
        let i = &self.input;
        let c = i.channels.count() * i.frames as usize;
        let (h, w) = (i.height as usize, i.width as usize);
        match i.layout {
            Layout::Nchw => [1, c, h, w],
            Layout::Nhwc => [1, h, w, c],
        }
    }

    /// The largest output index the manifest reads.
    fn max_index(&self) -> usize {
        [
            self.output.throttle,
            self.output.steering,
            self.output.brake,
        ]
        .into_iter()
        .flatten()
        .max()
        .unwrap_or(0)
    }
}

/// One frame preprocessed as the manifest's `[input]` says: cropped, resized (bilinear,
/// `image`'s triangle filter), channels reordered and normalised, as `channels × height ×
/// width` (planar, row-major) whatever the layout. The same function prepares training data.
pub fn preprocess(rgb: &image::RgbImage, input: &InputSpec) -> Vec<f32> {
    let mut p = Preprocessor::new(rgb.width(), rgb.height(), input);
    let mut out = Vec::new();
    p.run(rgb.as_raw(), input, &mut out);
    out
}

impl InputSpec {
    /// The region of a `width × height` frame the model reads: `(column, row, width,
    /// height)` of its crop in pixels, clipped to the frame (at least 1 × 1).
    pub fn crop_region(&self, width: u32, height: u32) -> (u32, u32, u32, u32) {
        let [top, bottom, left, right] = self.crop;
        let (x0, y0) = (left.min(width - 1), top.min(height - 1));
        // As `image::imageops::crop_imm` clips a crop that runs past the image.
        let w = width.saturating_sub(left + right).max(1).min(width - x0);
        let h = height.saturating_sub(top + bottom).max(1).min(height - y0);
        (x0, y0, w, h)
    }
}

/// [`preprocess`] for frames of one size: the crop's place, the resize weights and the
/// resized image are worked out once and kept between frames ([`super::resample`]); the
/// values are [`preprocess`]'s bit for bit.
#[derive(Debug, Clone)]
pub(crate) struct Preprocessor {
    frame: (u32, u32),
    origin: (u32, u32),
    resampler: super::resample::Resampler,
    small: Vec<u8>,
    /// Per channel, the input value of each byte (RGB and BGR inputs).
    table: Option<Vec<Vec<f32>>>,
}

impl Preprocessor {
    /// For `width × height` frames and the model's `input`.
    pub(crate) fn new(width: u32, height: u32, input: &InputSpec) -> Self {
        let (x0, y0, w, h) = input.crop_region(width, height);
        // For RGB and BGR each value depends on one byte: `(v / 255 − mean) / std`, as below.
        let table = (input.channels != Channels::Gray).then(|| {
            (0..input.channels.count())
                .map(|ch| {
                    let mean = input.mean.get(ch).copied().unwrap_or(0.0);
                    let std = input.std.get(ch).copied().unwrap_or(1.0);
                    (0..=255u8)
                        .map(|v| (f32::from(v) / 255.0 - mean) / std)
                        .collect()
                })
                .collect()
        });
        Preprocessor {
            frame: (width, height),
            origin: (x0, y0),
            table,
            resampler: super::resample::Resampler::new((w, h), (input.width, input.height)),
            small: vec![0; (input.width * input.height * 3) as usize],
        }
    }

    /// Whether it was made for `width × height` frames.
    pub(crate) fn fits(&self, width: u32, height: u32) -> bool {
        self.frame == (width, height)
    }

    /// Preprocesses `rgb` (RGB8, the frame size it was made for) into `out` (`channels ×
    /// height × width`, replaced).
    pub(crate) fn run(&mut self, rgb: &[u8], input: &InputSpec, out: &mut Vec<f32>) {
        self.resampler
            .resize(rgb, self.frame.0, self.origin, &mut self.small);
        let c = input.channels.count();
        let n = (input.width * input.height) as usize;
        out.clear();
        out.resize(c * n, 0.0);
        if let Some(table) = &self.table {
            // One look-up per value: the table holds the same arithmetic's results.
            for (k, px) in self.small.chunks_exact(3).enumerate() {
                for ch in 0..c {
                    let source = match input.channels {
                        Channels::Bgr => 2 - ch,
                        _ => ch,
                    };
                    out[ch * n + k] = table[ch][usize::from(px[source])];
                }
            }
            return;
        }
        // Grey: one value from three bytes, `((r + g + b) / 3 − mean) / std`.
        let mean = input.mean.first().copied().unwrap_or(0.0);
        let std = input.std.first().copied().unwrap_or(1.0);
        for (k, px) in self.small.chunks_exact(3).enumerate() {
            let [r, g, b] = [px[0], px[1], px[2]].map(|v| f32::from(v) / 255.0);
            out[k] = ((r + g + b) / 3.0 - mean) / std;
        }
    }
}

type Plan = TypedRunnableModel;

/// A loaded model and its manifest: what `--sut-onnx`, `sut = "onnx:PATH"` and `--sut
/// pilotnet` configure. Cloning shares the model.
#[derive(Clone)]
pub struct OnnxConfig {
    /// Where the model came from (a path, or `builtin:pilotnet`).
    pub source: String,
    /// SHA-256 of the model's bytes, hex (enters the campaign's fingerprint).
    pub sha256: String,
    /// Its manifest.
    pub manifest: Manifest,
    plan: Arc<Plan>,
}

impl std::fmt::Debug for OnnxConfig {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("OnnxConfig")
            .field("source", &self.source)
            .field("sha256", &self.sha256)
            .field("manifest", &self.manifest)
            .finish()
    }
}

impl PartialEq for OnnxConfig {
    fn eq(&self, other: &Self) -> bool {
        self.sha256 == other.sha256 && self.manifest == other.manifest
    }
}

fn hex(bytes: &[u8]) -> String {
    Sha256::digest(bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

/// The manifest's path for a model's: the same stem with `.toml`.
pub fn manifest_path(model: &Path) -> PathBuf {
    model.with_extension("toml")
}

impl OnnxConfig {
    /// Loads `model` (an `.onnx` file) and the manifest beside it ([`manifest_path`]),
    /// checks that the model takes the manifest's input and has the outputs it reads.
    ///
    /// # Errors
    /// A [`ModelError`] naming the file: missing or unreadable model or manifest
    /// ([`ModelError::Read`]), a manifest error ([`ModelError::Manifest`]), a model tract cannot
    /// load, an input shape the model does not take, too few outputs ([`ModelError::Model`]),
    /// a failed trial run ([`ModelError::Run`]).
    pub fn load(model: &Path) -> Result<OnnxConfig, ModelError> {
        let manifest_file = manifest_path(model);
        for f in [model, manifest_file.as_path()] {
            crate::files::regular_file(f)
                .map_err(|e| ModelError::Read(format!("cannot read `{}`: {e}", f.display())))?;
        }
        let bytes = std::fs::read(model).map_err(|e| {
            ModelError::Read(format!("cannot read the model `{}`: {e}", model.display()))
        })?;
        let text = std::fs::read_to_string(&manifest_file).map_err(|e| {
            ModelError::Read(format!(
                "cannot read the model's manifest `{}` ({e}); every model needs a TOML \
                 manifest beside it with the same stem (docs/systems-under-test.md, \"ONNX models\")",
                manifest_file.display()
            ))
        })?;
        let manifest = Manifest::parse(&text, &manifest_file)?;
        let source = model.display().to_string();
        // tract allocates the tensors the model declares while it analyses and first runs
        // it: one absurdly large is refused by the counting allocator (exit 2, naming the
        // model) rather than attempted (an abort).
        let _budget = crate::memory::Budget::start(
            usize::MAX,
            crate::memory::HARD_MODEL_BYTES,
            &source,
            "the ONNX model",
        );
        Self::from_bytes(&source, &bytes, manifest)
    }

    /// As [`OnnxConfig::load`], from the model's bytes and a parsed manifest.
    ///
    /// # Errors
    /// As [`OnnxConfig::load`].
    pub fn from_bytes(source: &str, bytes: &[u8], manifest: Manifest) -> Result<Self, ModelError> {
        let fail = |what: &str, e: TractError| {
            ModelError::Model(format!("model `{source}`: {what}: {e:#}"))
        };
        let shape = manifest.input_shape();
        let mut model = tract_onnx::onnx()
            .model_for_read(&mut &bytes[..])
            .map_err(|e| fail("not an ONNX model tract can load", e))?;
        let inputs = model.inputs.len();
        let wanted = 1 + usize::from(manifest.input.speed);
        if inputs != wanted {
            return Err(ModelError::Model(format!(
                "model `{source}` has {inputs} inputs; its manifest describes {wanted} (the \
                 image{})",
                if manifest.input.speed {
                    " and the speed"
                } else {
                    ""
                }
            )));
        }
        declared_input_matches(&model, source, &shape)?;
        model = model
            .with_input_fact(0, f32::fact(shape).into())
            .map_err(|e| fail("input", e))?;
        if manifest.input.speed {
            model = model
                .with_input_fact(1, f32::fact([1, 1]).into())
                .map_err(|e| fail("speed input", e))?;
        }
        let plan = model
            .into_optimized()
            .and_then(|m| m.into_runnable())
            .map_err(|e| {
                fail(
                    &format!("does not take the manifest's input of shape {shape:?}"),
                    e,
                )
            })?;
        let config = OnnxConfig {
            source: source.to_owned(),
            sha256: hex(bytes),
            manifest,
            plan,
        };
        // One run on a grey image: the outputs the manifest reads exist.
        let n = config.run(&vec![0.0; shape.iter().product()], 0.0)?.len();
        if config.manifest.max_index() >= n {
            return Err(ModelError::Model(format!(
                "model `{source}` has {n} outputs; its manifest reads index {}",
                config.manifest.max_index()
            )));
        }
        Ok(config)
    }

    /// Runs the model on one input (`image` as the input tensor's elements in its layout)
    /// and returns its first output, flattened.
    ///
    /// # Errors
    /// [`ModelError::Run`] with tract's message.
    pub fn run(&self, image: &[f32], speed_mps: f32) -> Result<Vec<f32>, ModelError> {
        let shape = self.manifest.input_shape();
        let tensor =
            Tensor::from_shape(&shape, image).map_err(|e| ModelError::Run(format!("{e:#}")))?;
        let mut inputs: TVec<TValue> = tvec!(tensor.into());
        if self.manifest.input.speed {
            let s = Tensor::from_shape(&[1, 1], &[speed_mps])
                .map_err(|e| ModelError::Run(format!("{e:#}")))?;
            inputs.push(s.into());
        }
        let out = self.plan.run(inputs);
        crate::simd::clear_upper_vector_state();
        let out = out.map_err(|e| ModelError::Run(format!("{e:#}")))?;
        let first = out
            .first()
            .ok_or_else(|| ModelError::Run("the model has no output".to_owned()))?;
        let view = first
            .to_plain_array_view::<f32>()
            .map_err(|e| ModelError::Run(format!("its first output is not f32: {e:#}")))?;
        Ok(view.iter().copied().collect())
    }

    /// The input tensor for `frames` (oldest first, `frames.len() == input.frames`), each from
    /// [`preprocess`], in the manifest's layout.
    pub fn tensor(&self, frames: &[Vec<f32>]) -> Vec<f32> {
        let i = &self.manifest.input;
        let planar: Vec<f32> = frames.iter().flatten().copied().collect();
        match i.layout {
            Layout::Nchw => planar,
            Layout::Nhwc => {
                let c = i.channels.count() * frames.len();
                let n = (i.width * i.height) as usize;
                let mut out = vec![0.0; planar.len()];
                for ch in 0..c {
                    for k in 0..n {
                        out[k * c + ch] = planar[ch * n + k];
                    }
                }
                out
            }
        }
    }
}

/// Metadata that tells whether a file changed: modification time and length.
fn stamp(path: &Path) -> Option<(std::time::SystemTime, u64)> {
    let m = std::fs::metadata(path).ok()?;
    Some((m.modified().ok()?, m.len()))
}

type Stamps = [Option<(std::time::SystemTime, u64)>; 2];

/// [`OnnxConfig::load`], once per process per model: a scenario names its model in every
/// evaluation, and loading optimises the graph. A model or manifest whose modification time
/// or length changed is loaded again.
///
/// # Errors
/// As [`OnnxConfig::load`].
pub(crate) fn cached(path: &Path) -> Result<OnnxConfig, ModelError> {
    use std::collections::HashMap;
    use std::sync::{Mutex, OnceLock};
    static CACHE: OnceLock<Mutex<HashMap<PathBuf, (Stamps, OnnxConfig)>>> = OnceLock::new();
    let key = std::fs::canonicalize(path).unwrap_or_else(|_| path.to_owned());
    let stamps = [stamp(&key), stamp(&manifest_path(&key))];
    let cache = CACHE.get_or_init(Default::default);
    if let Some((s, c)) = cache.lock().unwrap_or_else(|p| p.into_inner()).get(&key) {
        if *s == stamps && stamps.iter().all(Option::is_some) {
            return Ok(c.clone());
        }
    }
    let config = OnnxConfig::load(path)?;
    cache
        .lock()
        .unwrap_or_else(|p| p.into_inner())
        .insert(key, (stamps, config.clone()));
    Ok(config)
}

/// The ONNX system under test: one model, its frame history and its last decision.
pub struct OnnxSut {
    config: OnnxConfig,
    /// The crop and resize for the frames' size, made at the first frame.
    pre: Option<Preprocessor>,
    history: VecDeque<Vec<f32>>,
    last_frame_t: Option<f64>,
    decision: Control,
}

impl OnnxSut {
    /// A system running `config`'s model.
    pub fn new(config: OnnxConfig) -> Self {
        OnnxSut {
            config,
            pre: None,
            history: VecDeque::new(),
            last_frame_t: None,
            decision: Control::default(),
        }
    }

    /// The model's control for `frame` at `speed_mps` (m/s); `set_speed_mps` (the scenario's
    /// set speed, [`Observation::set_speed_mps`]) replaces the manifest's `cruise_mps` for a
    /// model without a `throttle` output, and is not seen by one with it.
    fn decide(
        &mut self,
        frame: &CameraFrame,
        speed_mps: f64,
        set_speed_mps: Option<f64>,
    ) -> Result<Control, SutError> {
        let m = &self.config.manifest;
        let pre = match &mut self.pre {
            Some(p) if p.fits(frame.width, frame.height) => p,
            slot => slot.insert(Preprocessor::new(frame.width, frame.height, &m.input)),
        };
        let depth = m.input.frames as usize;
        // The oldest frame's buffer takes the new one (no allocation once the history is full).
        let mut x = if self.history.len() == depth {
            self.history.pop_front().unwrap_or_default()
        } else {
            Vec::new()
        };
        pre.run(&frame.rgb, &m.input, &mut x);
        if self.history.is_empty() {
            self.history
                .extend(std::iter::repeat_n(x.clone(), depth - 1));
        }
        self.history.push_back(x);
        let y = self
            .config
            .run(
                &self.config.tensor(self.history.make_contiguous()),
                speed_mps as f32,
            )
            .map_err(|e| SutError::Failed(format!("model `{}`: {e}", self.config.source)))?;
        // `bounded`: a control the model gives directly, in [-1, 1] (an external system
        // answering outside it gets `error` too; clamping it would hide a broken model).
        let read = |i: Option<usize>, what: &str, bounded: bool| -> Result<Option<f64>, SutError> {
            match i.map(|i| f64::from(y[i])) {
                Some(v) if !v.is_finite() || (bounded && v.abs() > 1.0 + 1e-6) => {
                    Err(SutError::Failed(format!(
                        "model `{}` answered {v} for {what} (output {}) at t = {:.3} s{}",
                        self.config.source,
                        i.unwrap_or(0),
                        frame.t_s,
                        if v.is_finite() {
                            ", outside [-1, 1]"
                        } else {
                            ""
                        }
                    )))
                }
                v => Ok(v),
            }
        };
        let o = &m.output;
        let steering = read(o.steering, "steering", true)?.unwrap_or(0.0);
        let throttle = match (read(o.throttle, "throttle", true)?, o.cruise_mps) {
            (Some(t), _) => t,
            (None, Some(target)) => {
                super::Cruise::default().throttle(speed_mps, set_speed_mps.unwrap_or(target), None)
            }
            (None, None) => 0.0,
        };
        let braking = read(o.brake, "brake", false)?.is_some_and(|b| b > o.brake_threshold);
        Ok(Control {
            throttle: if braking { -1.0 } else { throttle },
            steering,
        }
        .clamped())
    }
}

/// Checks the image input a model declares (element type and the dimensions it fixes)
/// against the manifest's `shape`: tract runs a model on whatever input fact it is given, so a
/// model declaring `[1, 1, 10, 10]` ran on `[1, 3, 48, 96]`. Dimensions the model leaves open
/// (a symbolic batch) take the manifest's.
///
/// # Errors
/// A message naming the model, what it declares and what its manifest says.
fn declared_input_matches(
    model: &tract_onnx::prelude::InferenceModel,
    source: &str,
    shape: &[usize],
) -> Result<(), ModelError> {
    use tract_onnx::prelude::DatumType;
    use tract_onnx::tract_core::internal::DimLike;
    use tract_onnx::tract_hir::infer::Factoid;
    let fact = model
        .input_fact(0)
        .map_err(|e| ModelError::Model(format!("model `{source}`: no input: {e:#}")))?;
    if let Some(t) = fact.datum_type.concretize() {
        if t != DatumType::F32 {
            return Err(ModelError::Model(format!(
                "model `{source}` declares its input of type {t:?}; paracosm feeds it f32 \
                 images (its manifest's [input])"
            )));
        }
    }
    if fact.shape.is_open() {
        return Ok(());
    }
    let declared: Vec<Option<usize>> = fact
        .shape
        .dims()
        .map(|d| d.concretize().and_then(|d| d.as_usize()))
        .collect();
    let fits = declared.len() == shape.len()
        && declared
            .iter()
            .zip(shape)
            .all(|(d, &s)| d.is_none_or(|d| d == s));
    if fits {
        Ok(())
    } else {
        let show: Vec<String> = declared
            .iter()
            .map(|d| d.map_or("?".to_owned(), |d| d.to_string()))
            .collect();
        Err(ModelError::Model(format!(
            "model `{source}` declares its input of shape [{}], and its manifest describes \
             {shape:?} (camera, crop and channels): they must agree",
            show.join(", ")
        )))
    }
}

impl Sut for OnnxSut {
    fn sensors(&self) -> Sensors {
        let camera = &self.config.manifest.camera;
        let (x, y, w, h) = self
            .config
            .manifest
            .input
            .crop_region(camera.width, camera.height);
        Sensors {
            camera: Some(camera.clone()),
            control_hz: None,
            // It reads its crop of the image: the rest is never drawn.
            frame_use: crate::FrameUse::image(Some([x, y, w, h])),
        }
    }

    fn reset(&mut self, _seed: u64) -> Result<(), SutError> {
        self.history.clear();
        self.last_frame_t = None;
        self.decision = Control::default();
        Ok(())
    }

    fn act(&mut self, obs: &Observation<'_>) -> Result<Control, SutError> {
        let frame = obs.camera().ok_or_else(|| {
            SutError::Failed(
                "an ONNX model needs camera frames but the observation has none".into(),
            )
        })?;
        if self.last_frame_t != Some(frame.t_s) {
            self.last_frame_t = Some(frame.t_s);
            self.decision = self.decide(frame, obs.ego.speed_mps, obs.set_speed_mps)?;
        }
        Ok(self.decision)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    /// The preprocessing as it was written before `Preprocessor` (crop with `image`, resize
    /// with `image`, normalise per pixel): the reference the shipped networks were trained on.
    fn reference(rgb: &image::RgbImage, input: &InputSpec) -> Vec<f32> {
        let [top, bottom, left, right] = input.crop;
        let (w, h) = (rgb.width(), rgb.height());
        let cropped = image::imageops::crop_imm(
            rgb,
            left.min(w - 1),
            top.min(h - 1),
            w.saturating_sub(left + right).max(1),
            h.saturating_sub(top + bottom).max(1),
        )
        .to_image();
        let small = image::imageops::resize(
            &cropped,
            input.width,
            input.height,
            image::imageops::FilterType::Triangle,
        );
        let c = input.channels.count();
        let n = (input.width * input.height) as usize;
        let mut out = vec![0f32; c * n];
        for (k, px) in small.pixels().enumerate() {
            let [r, g, b] = px.0.map(|v| f32::from(v) / 255.0);
            let values: [f32; 3] = match input.channels {
                Channels::Rgb => [r, g, b],
                Channels::Bgr => [b, g, r],
                Channels::Gray => [(r + g + b) / 3.0, 0.0, 0.0],
            };
            for ch in 0..c {
                let mean = input.mean.get(ch).copied().unwrap_or(0.0);
                let std = input.std.get(ch).copied().unwrap_or(1.0);
                out[ch * n + k] = (values[ch] - mean) / std;
            }
        }
        out
    }

    /// Crops inside, at and past the frame's edges (clipped as `crop_imm` clips), every
    /// channel order, a crop the size of the input (copied, not resized): the same bits as
    /// the reference, frame after frame with one `Preprocessor`.
    #[test]
    fn the_preprocessor_gives_the_references_bits() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let cases: [([u32; 4], (u32, u32), Channels); 6] = [
            ([96, 40, 60, 60], (96, 48), Channels::Rgb),
            ([0, 0, 0, 0], (64, 32), Channels::Bgr),
            ([230, 0, 310, 0], (8, 8), Channels::Gray),
            ([10, 300, 5, 400], (12, 6), Channels::Rgb),
            ([20, 20, 40, 40], (240, 200), Channels::Rgb),
            ([0, 40, 0, 0], (320, 200), Channels::Bgr),
        ];
        for (crop, (width, height), channels) in cases {
            let input = InputSpec {
                crop,
                width,
                height,
                channels,
                layout: Layout::Nchw,
                mean: vec![0.5, 0.4, 0.3],
                std: vec![0.25, 0.2, 0.3],
                frames: 1,
                speed: false,
            };
            let mut pre = Preprocessor::new(320, 240, &input);
            let mut out = Vec::new();
            for _ in 0..2 {
                let frame =
                    image::RgbImage::from_fn(320, 240, |_, _| image::Rgb(rng.random::<[u8; 3]>()));
                pre.run(frame.as_raw(), &input, &mut out);
                let want = reference(&frame, &input);
                assert_eq!(out.len(), want.len(), "{crop:?}");
                assert!(
                    out.iter()
                        .zip(&want)
                        .all(|(a, b)| a.to_bits() == b.to_bits()),
                    "{crop:?} → {width}×{height} {channels:?}"
                );
                assert_eq!(preprocess(&frame, &input), want);
            }
        }
    }
}
