//! The offscreen camera (feature `render`): RGB images and depth maps of the world as the
//! ego vehicle's camera sees it, rendered with `wgpu` (paper §2, "Sensors").
//!
//! What is drawn: a grass ground plane, the road pieces of the network (asphalt, raised
//! sidewalks with curbs, white edge lines and dashed lane dividers, a double yellow centre
//! line, stop lines at junctions, the grass island of a roundabout), cars as boxes in their
//! scenario colour, pedestrians as red boxes 1.75 m tall, and the sky.
//!
//! Light and fog: surfaces are lit by a fixed sun (ambient 0.45 + diffuse 0.55); the image is
//! scaled by the exposure `light / NOMINAL_LIGHT` (calibrated at light 0.5, clipped at 255).
//! Fog is Koschmieder's exponential extinction toward the sky colour: a surface `d` metres
//! away keeps `exp(-σ d)` of its own colour, with `σ = fog · 0.5 /m`, the same σ that caps the
//! lidar ([`crate::visibility_m`]: fog 0.1 is 78 m of visibility, 0.5 is 15.6 m, 1 is 7.8 m).
//!
//! Depth is written by the shader, as the bits of an `f32`, into a second colour target
//! (`R32Uint`): the same path works on Vulkan and on GL, which cannot copy depth buffers
//! (`DownlevelFlags::DEPTH_TEXTURE_AND_BUFFER_COPIES`) nor render to `R32Float`.
//!
//! One [`Renderer`] (device and pipeline) serves the whole process ([`Renderer::shared`]);
//! every simulation uploads its static [`SceneGeometry`] once and owns a [`View`] per camera.
//! [`Renderer::render`] renders a batch of views in one submission.

mod gpu;
mod mesh;
mod post;

pub use crate::sensor::camera::{CameraFrame, CameraSpec};
pub use crate::NOMINAL_LIGHT;
pub use gpu::{CameraPose, RenderJob, RenderObject, Renderer, SceneGeometry, View};
pub use mesh::color_albedo;
pub use wgpu::Backends;

use thiserror::Error;

/// Why the camera cannot render.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum RenderError {
    /// No GPU adapter: neither Vulkan nor GL is available.
    #[error(
        "no GPU adapter for the camera renderer ({0}); on Debian install mesa-vulkan-drivers \
         (lavapipe) or run without camera sensors"
    )]
    NoAdapter(String),
    /// The adapter refused to create a device.
    #[error("cannot create the GPU device: {0}")]
    Device(String),
    /// A camera setting is out of range.
    #[error("{0}")]
    Camera(crate::SettingError),
    /// Rendering or reading a frame back failed.
    #[error("cannot read a camera frame back from the GPU: {0}")]
    Readback(String),
}
