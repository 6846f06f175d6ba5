//! Systems under test: the software that drives the ego vehicle, called once per physics step
//! with an [`Observation`] and answering a [`Control`].
//!
//! Built in: [`Aeb`] (cruise control with automatic emergency braking on lidar time to
//! collision), [`Vision`] (lane keeping and braking from the camera image and depth map) and
//! [`ConstantControl`] (open loop, for baselines and physics tests). [`ExternalSut`] runs a
//! system under test in another process, in any language (SUT_PROTOCOL.md).

mod aeb;
mod constant;
mod cruise;
mod dagger;
mod external;
#[cfg(feature = "onnx")]
mod onnx;
#[cfg(feature = "onnx")]
mod resample;
mod stop;
mod vision;

pub use aeb::{Aeb, AebConfig};
pub use constant::ConstantControl;
pub use cruise::Cruise;
pub use dagger::Dagger;
pub use external::{
    check_command, reap_orphans, track_orphans, CommandError, ExternalConfig, ExternalSut,
    ProcessPool, PROTOCOL_VERSION,
};
#[cfg(feature = "onnx")]
pub use onnx::{
    manifest_path, preprocess, Channels, InputSpec, Layout, Manifest, ModelError, OnnxConfig,
    OnnxSut, OutputSpec,
};
pub use stop::StopAfter;
pub use vision::{Perception, Vision, VisionConfig};

use thiserror::Error;

use crate::{Control, Observation};

/// A failure of the system under test itself (not of the world): the test is recorded as an
/// `error`, not as a pass or fail.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum SutError {
    /// The system could not produce a control (crashed, timed out, malformed answer).
    #[error("system under test failed: {0}")]
    Failed(String),
}

/// The sensors a system under test reads, beyond odometry and lidar (always present).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Sensors {
    /// A camera on the ego vehicle (RGB and depth), rendered at its `rate_hz`.
    pub camera: Option<crate::CameraSpec>,
    /// How often it decides, in Hz of simulated time; `None`: every physics step. Between
    /// decisions the last control is held.
    pub control_hz: Option<f64>,
    /// What it reads of each camera frame (planes, a region): the camera renders and reads
    /// back only that when nothing else watches the frames. Default: everything.
    pub frame_use: crate::FrameUse,
}

/// A system under test.
pub trait Sut: Send {
    /// The sensors it needs; asked after each [`Sut::reset`]. Default: odometry and lidar,
    /// deciding every step.
    fn sensors(&self) -> Sensors {
        Sensors::default()
    }

    /// Prepares a fresh run; `seed` drives any randomness of the system.
    ///
    /// # Errors
    /// [`SutError::Failed`] if the system cannot start.
    fn reset(&mut self, seed: u64) -> Result<(), SutError>;

    /// The control for the coming step, given what the vehicle senses now.
    ///
    /// # Errors
    /// [`SutError::Failed`] if the system cannot answer.
    fn act(&mut self, obs: &Observation<'_>) -> Result<Control, SutError>;

    /// The label of the last decision when it is not the answer: a teacher's answer while a
    /// learner drives ([`Dagger`]), what `paracosm-fuzz dataset` records. `None` (the
    /// default): the answer is its own label.
    fn label(&self) -> Option<Control> {
        None
    }
}

/// A system under test by configuration: what a scenario names and a campaign builds per test.
#[derive(Debug, Clone, PartialEq)]
pub enum SutConfig {
    /// The built-in `aeb`.
    Aeb(AebConfig),
    /// The built-in `vision`.
    Vision(VisionConfig),
    /// Open-loop constant control.
    Constant(Control),
    /// No system under test: a script places the ego at every step (an OpenSCENARIO
    /// storyboard replaying an exported test, [`crate::EgoSpec::scripted`]); its control is
    /// never read.
    Scripted,
    /// A program in another process (`--sut-cmd`).
    External(ExternalConfig),
    /// An ONNX model run in process (`--sut-onnx`, `sut = "onnx:PATH"`).
    #[cfg(feature = "onnx")]
    Onnx(Box<OnnxConfig>),
    /// `inner` until the ego has travelled `after_m` metres, then a full brake for good
    /// ([`StopAfter`]): a vacuity check of a scenario's monitors (tests/liveness.rs).
    StopAfter {
        /// The system that drives until then.
        inner: Box<SutConfig>,
        /// Distance after which it brakes, m, `>= 0`.
        after_m: f64,
    },
    /// `learner` drives and `teacher` labels ([`Dagger`]): training data on the learner's
    /// own states (`paracosm-fuzz dataset --learner-onnx`).
    Dagger {
        /// The system that drives.
        learner: Box<SutConfig>,
        /// The system whose answers are the labels.
        teacher: Box<SutConfig>,
        /// Probability in `[0, 1]` that a decision applies the teacher's answer instead.
        beta: f64,
    },
}

/// The name of the shipped network (`--sut pilotnet`), and its [`OnnxConfig`]'s `source`.
pub const PILOTNET: &str = "pilotnet";

/// Names of the built-in systems under test, for `--sut` and `AutonomousVehicle(sut=)`.
pub const BUILTIN_SUTS: [&str; 3] = ["aeb", "vision", PILOTNET];

/// Why a system under test cannot be configured ([`SutConfig::named`], [`SutConfig::onnx`]).
#[derive(Debug, Error, Clone, PartialEq)]
pub enum SutConfigError {
    /// A name that is no built-in system ([`BUILTIN_SUTS`]).
    #[error("unknown system under test `{0}`; built in: {known}", known = BUILTIN_SUTS.join(", "))]
    Unknown(String),
    /// An ONNX model or its manifest that cannot be used; the message names the file.
    #[cfg(feature = "onnx")]
    #[error(transparent)]
    Model(#[from] ModelError),
    /// `pilotnet` in a build without the ONNX runtime (cargo feature `onnx`).
    #[error(
        "`pilotnet` is an ONNX model: this build of paracosm has no ONNX runtime (cargo \
         feature `onnx`)"
    )]
    PilotnetWithoutOnnx,
    /// An ONNX model in a build without the ONNX runtime (cargo feature `onnx`).
    #[error(
        "cannot run the ONNX model `{}`: this build of paracosm has no ONNX runtime (cargo \
         feature `onnx`)",
        .0.display()
    )]
    WithoutOnnx(std::path::PathBuf),
}

/// The shipped network (`assets/models/pilotnet.onnx` and its manifest, compiled in), loaded
/// once per process.
///
/// # Errors
/// The compiled-in model's [`ModelError`], or [`SutConfigError::PilotnetWithoutOnnx`].
fn pilotnet() -> Result<SutConfig, SutConfigError> {
    #[cfg(feature = "onnx")]
    {
        use std::sync::OnceLock;
        static MODEL: OnceLock<Result<OnnxConfig, ModelError>> = OnceLock::new();
        MODEL
            .get_or_init(|| {
                let manifest = Manifest::parse(
                    include_str!("../../../assets/models/pilotnet.toml"),
                    std::path::Path::new("assets/models/pilotnet.toml"),
                )?;
                OnnxConfig::from_bytes(
                    PILOTNET,
                    include_bytes!("../../../assets/models/pilotnet.onnx"),
                    manifest,
                )
            })
            .clone()
            .map(|c| SutConfig::Onnx(Box::new(c)))
            .map_err(SutConfigError::from)
    }
    #[cfg(not(feature = "onnx"))]
    {
        Err(SutConfigError::PilotnetWithoutOnnx)
    }
}

impl SutConfig {
    /// The built-in system called `name` (see [`BUILTIN_SUTS`]) with default settings.
    ///
    /// # Errors
    /// [`SutConfigError::Unknown`] (its message lists the known names), or the shipped
    /// model's error.
    fn lookup(name: &str) -> Result<SutConfig, SutConfigError> {
        match name {
            "aeb" => Ok(SutConfig::Aeb(AebConfig::default())),
            "vision" => Ok(SutConfig::Vision(VisionConfig::default())),
            PILOTNET => pilotnet(),
            _ => Err(SutConfigError::Unknown(name.to_owned())),
        }
    }

    /// The built-in system called `name` (see [`BUILTIN_SUTS`]) with default settings.
    ///
    /// # Errors
    /// [`SutConfigError::Unknown`] for a name that is not built in (its message lists the
    /// known names), or the shipped model's problem.
    pub fn builtin(name: &str) -> Result<SutConfig, SutConfigError> {
        Self::lookup(name)
    }

    /// The system a scenario names: a built-in name, or `onnx:PATH` with `PATH` relative to
    /// `base` (the program's folder).
    ///
    /// # Errors
    /// As [`SutConfig::builtin`] and [`SutConfig::onnx`].
    pub fn named(spec: &str, base: &std::path::Path) -> Result<SutConfig, SutConfigError> {
        match spec.strip_prefix("onnx:") {
            Some(path) => SutConfig::onnx(&base.join(path)),
            None => SutConfig::lookup(spec),
        }
    }

    /// The ONNX model at `path` with its manifest beside it (`--sut-onnx`).
    ///
    /// # Errors
    /// The model's or the manifest's problem, naming the file ([`SutConfigError::Model`]);
    /// or that this build has no ONNX runtime ([`SutConfigError::WithoutOnnx`]).
    pub fn onnx(path: &std::path::Path) -> Result<SutConfig, SutConfigError> {
        #[cfg(feature = "onnx")]
        {
            onnx::cached(path)
                .map(|c| SutConfig::Onnx(Box::new(c)))
                .map_err(SutConfigError::from)
        }
        #[cfg(not(feature = "onnx"))]
        {
            Err(SutConfigError::WithoutOnnx(path.to_owned()))
        }
    }

    /// SHA-256 of an ONNX model's bytes (hex), `None` for every other system.
    pub fn model_sha256(&self) -> Option<&str> {
        match self {
            #[cfg(feature = "onnx")]
            SutConfig::Onnx(c) => Some(&c.sha256),
            SutConfig::StopAfter { inner, .. } => inner.model_sha256(),
            SutConfig::Dagger { learner, .. } => learner.model_sha256(),
            _ => None,
        }
    }

    /// A short name for reports: `aeb`, `vision`, `constant`, `scripted`, the external command line, or
    /// `onnx:PATH`.
    pub fn name(&self) -> String {
        match self {
            SutConfig::Aeb(_) => "aeb".into(),
            SutConfig::Vision(_) => "vision".into(),
            SutConfig::Constant(_) => "constant".into(),
            SutConfig::Scripted => "scripted".into(),
            SutConfig::External(e) => e.command.join(" "),
            #[cfg(feature = "onnx")]
            SutConfig::Onnx(c) if c.source == PILOTNET => PILOTNET.into(),
            #[cfg(feature = "onnx")]
            SutConfig::Onnx(c) => format!("onnx:{}", c.source),
            SutConfig::StopAfter { inner, after_m } => {
                format!("{} stopping after {after_m} m", inner.name())
            }
            SutConfig::Dagger {
                learner,
                teacher,
                beta,
            } => format!(
                "{} driving, {} labelling (teacher's share {beta})",
                learner.name(),
                teacher.name()
            ),
        }
    }

    /// Whether the system reads a camera: `Some(false)` for `aeb` and constant control,
    /// `Some(true)` for `vision`, `None` for an external program (it declares its sensors in
    /// its handshake, when a test starts).
    pub fn has_camera(&self) -> Option<bool> {
        match self {
            SutConfig::Aeb(_) | SutConfig::Constant(_) | SutConfig::Scripted => Some(false),
            SutConfig::Vision(_) => Some(true),
            #[cfg(feature = "onnx")]
            SutConfig::Onnx(_) => Some(true),
            SutConfig::External(_) => None,
            SutConfig::StopAfter { inner, .. } => inner.has_camera(),
            SutConfig::Dagger { learner, .. } => learner.has_camera(),
        }
    }

    /// A fresh instance of the configured system.
    pub fn build(&self) -> Box<dyn Sut> {
        match self {
            SutConfig::Aeb(c) => Box::new(Aeb::new(c.clone())),
            SutConfig::Vision(c) => Box::new(Vision::new(c.clone())),
            SutConfig::Constant(c) => Box::new(ConstantControl(*c)),
            SutConfig::Scripted => Box::new(ConstantControl(Control::default())),
            SutConfig::External(c) => Box::new(ExternalSut::new(c.clone())),
            #[cfg(feature = "onnx")]
            SutConfig::Onnx(c) => Box::new(OnnxSut::new((**c).clone())),
            SutConfig::StopAfter { inner, after_m } => {
                Box::new(StopAfter::new(inner.build(), *after_m))
            }
            SutConfig::Dagger {
                learner,
                teacher,
                beta,
            } => Box::new(Dagger::new(learner.build(), teacher.build(), *beta)),
        }
    }
}
