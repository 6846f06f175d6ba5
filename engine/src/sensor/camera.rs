//! The camera: its pinhole model ([`CameraSpec`]), the frames it produces ([`CameraFrame`]),
//! and, with the `render` feature, the camera as a [`Sensor`] of one simulation (its renderer,
//! the world's uploaded geometry and its targets).

use serde::{Deserialize, Serialize};

use super::{Reading, Sensor, SettingError};
use crate::network::Network;
use crate::{EngineError, Observation};

/// Width of the camera's sensor in millimetres (a full-frame 36 × 24 mm sensor).
pub const SENSOR_WIDTH_MM: f64 = 36.0;
/// Height of the camera's sensor in millimetres.
pub const SENSOR_HEIGHT_MM: f64 = 24.0;

/// A camera mounted on the ego vehicle (paper §2, "Sensors"; §4.2 varies the focal length
/// 10–50 mm).
///
/// Intrinsics: square pixels, principal point at the image centre, and the sensor's 36 mm
/// width spread over the image width, so `fx = fy = focal_mm · width / 36` pixels (horizontal
/// sensor fit, as Blender's "sensor fit: horizontal"; at 4:3 the image shows 27 of the
/// sensor's 24 mm of height). The horizontal field of view is `2 · atan(18 / focal_mm)`:
/// 73.7° at 24 mm, 121.9° at 10 mm, 39.6° at 50 mm.
///
/// Mount: `mount_m` is `[forward, up, right]` from the ego chassis centre in metres; the camera
/// looks along the vehicle's heading, tilted down by `pitch_rad`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CameraSpec {
    /// Image width in pixels, `1..=4096`. Default 320.
    pub width: u32,
    /// Image height in pixels, `1..=4096`. Default 240.
    pub height: u32,
    /// Focal length in millimetres, `(0, 1000]`. Default 24 mm.
    pub focal_mm: f64,
    /// Mount point `[forward, up, right]` from the chassis centre, metres. Default
    /// `[0.5, 0.9, 0]` (behind the windscreen, 1.4 m above the road).
    pub mount_m: [f64; 3],
    /// Downward tilt in rad, `[-π/2, π/2]`. Default 0.05 rad (2.9°).
    pub pitch_rad: f64,
    /// Frames per second of simulated time: a whole number of physics steps per frame
    /// (`60 / k` at the 60 Hz step: 60, 30, 20, 15, 12, 10, 7.5, ...). Default 20 Hz.
    pub rate_hz: f64,
    /// Standard deviation of additive Gaussian pixel noise, in 8-bit levels (`0` off). Default 0.
    pub noise_sigma: f64,
    /// Standard deviation of a Gaussian blur, in pixels (`0` off). Default 0.
    pub blur_sigma_px: f64,
    /// Far clipping distance in metres: farther surfaces show sky and depth `+inf`. Default 500 m.
    pub far_m: f64,
}

impl Default for CameraSpec {
    fn default() -> Self {
        CameraSpec {
            width: 320,
            height: 240,
            focal_mm: 24.0,
            mount_m: [0.5, 0.9, 0.0],
            pitch_rad: 0.05,
            rate_hz: 20.0,
            noise_sigma: 0.0,
            blur_sigma_px: 0.0,
            far_m: 500.0,
        }
    }
}

impl CameraSpec {
    /// Checks the documented ranges.
    ///
    /// # Errors
    /// A [`SettingError`] naming the first value out of range, or a `rate_hz` that is not a
    /// whole number of physics steps per frame ([`SettingError::Rate`]).
    pub fn validate(&self) -> Result<(), SettingError> {
        let range = |name: &'static str, value: f64, ok: bool| {
            if ok && value.is_finite() {
                Ok(())
            } else {
                Err(SettingError::CameraOutOfRange { name, value })
            }
        };
        if !(1..=4096).contains(&self.width) || !(1..=4096).contains(&self.height) {
            return Err(SettingError::CameraResolution {
                width: self.width,
                height: self.height,
            });
        }
        range(
            "focal_mm",
            self.focal_mm,
            self.focal_mm > 0.0 && self.focal_mm <= 1000.0,
        )?;
        range(
            "pitch_rad",
            self.pitch_rad,
            self.pitch_rad.abs() <= std::f64::consts::FRAC_PI_2,
        )?;
        range("rate_hz", self.rate_hz, self.rate_hz > 0.0)?;
        crate::steps_per_period("camera rate_hz", self.rate_hz, crate::DEFAULT_DT_S)?;
        range("noise_sigma", self.noise_sigma, self.noise_sigma >= 0.0)?;
        range(
            "blur_sigma_px",
            self.blur_sigma_px,
            self.blur_sigma_px >= 0.0,
        )?;
        range("far_m", self.far_m, self.far_m > 1.0)?;
        for v in self.mount_m {
            range("mount_m", v, true)?;
        }
        Ok(())
    }

    /// Focal length in pixels, `fx = fy = focal_mm · width / 36`.
    pub fn focal_px(&self) -> f64 {
        self.focal_mm * f64::from(self.width) / SENSOR_WIDTH_MM
    }

    /// Horizontal field of view in rad.
    pub fn hfov_rad(&self) -> f64 {
        2.0 * (SENSOR_WIDTH_MM / 2.0 / self.focal_mm).atan()
    }

    /// Vertical field of view in rad.
    pub fn vfov_rad(&self) -> f64 {
        2.0 * (f64::from(self.height) / 2.0 / self.focal_px()).atan()
    }

    /// The point seen at pixel `(u, v)` (column, row; pixel centres at `+0.5`) with z-depth
    /// `depth_m`, in the camera frame `[right, up, forward]` metres (the inverse of the
    /// projection the renderer uses).
    pub fn back_project(&self, u: f64, v: f64, depth_m: f64) -> [f64; 3] {
        let f = self.focal_px();
        let cx = f64::from(self.width) / 2.0;
        let cy = f64::from(self.height) / 2.0;
        [(u - cx) / f * depth_m, (cy - v) / f * depth_m, depth_m]
    }

    /// A camera-frame point `[right, up, forward]` in the vehicle frame `[forward, up,
    /// right]` relative to the chassis centre, metres: undoes the pitch and adds the mount.
    pub fn camera_to_vehicle(&self, p: [f64; 3]) -> [f64; 3] {
        self.back_projector().in_vehicle_frame(p)
    }

    /// [`CameraSpec::back_project`] then [`CameraSpec::camera_to_vehicle`] with the
    /// intrinsics and the pitch's sine and cosine worked out once, for many pixels.
    pub fn back_projector(&self) -> BackProjector {
        let (sin, cos) = self.pitch_rad.sin_cos();
        BackProjector {
            focal_px: self.focal_px(),
            centre: [f64::from(self.width) / 2.0, f64::from(self.height) / 2.0],
            sin,
            cos,
            mount_m: self.mount_m,
        }
    }
}

/// A camera's back-projection with its constants worked out once
/// ([`CameraSpec::back_projector`]): the same values as [`CameraSpec::back_project`] and
/// [`CameraSpec::camera_to_vehicle`], bit for bit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BackProjector {
    focal_px: f64,
    centre: [f64; 2],
    sin: f64,
    cos: f64,
    mount_m: [f64; 3],
}

impl BackProjector {
    /// The point seen at pixel `(u, v)` (pixel centres at `+0.5`) with z-depth `depth_m`, in
    /// the vehicle frame `[forward, up, right]` relative to the chassis centre, metres.
    pub fn vehicle_point(&self, u: f64, v: f64, depth_m: f64) -> [f64; 3] {
        let f = self.focal_px;
        let [cx, cy] = self.centre;
        self.in_vehicle_frame([(u - cx) / f * depth_m, (cy - v) / f * depth_m, depth_m])
    }

    /// A camera-frame point `[right, up, forward]` in the vehicle frame.
    fn in_vehicle_frame(&self, p: [f64; 3]) -> [f64; 3] {
        let (s, c) = (self.sin, self.cos);
        // The optical axis is (cos, -sin) in (forward, up); the camera's up is (sin, cos).
        let forward = c * p[2] + s * p[1];
        let up = -s * p[2] + c * p[1];
        [
            self.mount_m[0] + forward,
            self.mount_m[1] + up,
            self.mount_m[2] + p[0],
        ]
    }
}

/// What the consumer of a camera reads of each frame ([`crate::sut::Sensors::frame_use`]):
/// the renderer draws and reads back only that. Default ([`FrameUse::ALL`]): every plane of
/// the whole image.
///
/// A region is exact: its pixels are those of the whole frame bit for bit (the same
/// projection, drawn through a scissor rectangle; pixel noise drawn for the whole frame in
/// order). A camera with blur renders the whole image whatever the region asks (blur reads
/// beyond a region's edge).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct FrameUse {
    /// Whether it reads the depth map ([`CameraFrame::depth_m`]).
    pub depth: bool,
    /// Whether it reads the labels ([`CameraFrame::labels`]).
    pub labels: bool,
    /// The part of the image it reads, `[column, row, width, height]` in pixels (clipped to
    /// the image); `None`: all of it.
    pub region: Option<[u32; 4]>,
}

impl FrameUse {
    /// Every plane of the whole image: what a frame callback, a dataset or a person gets.
    pub const ALL: FrameUse = FrameUse {
        depth: true,
        labels: true,
        region: None,
    };

    /// The image only (no depth, no labels), `region` of it or all.
    pub fn image(region: Option<[u32; 4]>) -> FrameUse {
        FrameUse {
            depth: false,
            labels: false,
            region,
        }
    }

    /// The region rendered for `camera`: `[column, row, width, height]`, the asked region
    /// clipped to the image (at least 1 × 1), or the whole image when none is asked or the
    /// camera blurs.
    pub fn region_in(&self, camera: &CameraSpec) -> [u32; 4] {
        let (w, h) = (camera.width, camera.height);
        match self.region {
            Some([x, y, rw, rh]) if camera.blur_sigma_px == 0.0 => {
                let (x, y) = (x.min(w - 1), y.min(h - 1));
                [x, y, rw.clamp(1, w - x), rh.clamp(1, h - y)]
            }
            _ => [0, 0, w, h],
        }
    }
}

impl Default for FrameUse {
    fn default() -> Self {
        FrameUse::ALL
    }
}

/// One camera frame: an RGB image, the matching depth map and the ground-truth labels.
///
/// Conventions: images are row-major, origin at the top-left pixel, rows top to bottom;
/// pixel `(u, v)` (column, row) is at index `v · width + u`.
///
/// A camera whose consumer reads less ([`FrameUse`]) renders less: outside
/// [`CameraFrame::region`] the image is black (0), and a plane it does not read is empty.
#[derive(Debug, Clone, PartialEq)]
pub struct CameraFrame {
    /// Simulated time of the frame, seconds.
    pub t_s: f64,
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// The pixels rendered, `[column, row, width, height]`: `[0, 0, width, height]` unless
    /// the camera's consumer reads a region only ([`FrameUse::region`]).
    pub region: [u32; 4],
    /// RGB8, `height × width × 3` bytes, row-major, top-left origin, sRGB-like 8-bit levels;
    /// 0 outside [`CameraFrame::region`].
    pub rgb: Vec<u8>,
    /// Depth in metres along the optical axis (z-depth, not range), `height × width`,
    /// row-major; `+inf` where the ray meets only sky (nothing within `far_m`) and outside
    /// [`CameraFrame::region`]. Empty when the camera's consumer does not read it
    /// ([`FrameUse::depth`]).
    pub depth_m: Vec<f32>,
    /// Ground-truth labels, `height × width`, row-major: each pixel's
    /// [`crate::SemanticClass`] id in the low 8 bits and its actor (`1 +` index in its
    /// kind's set, 0 for the world and the sky) above ([`crate::segmentation`]). Drawn by the
    /// renderer with the image; unaffected by fog, light, blur and noise; 0 outside
    /// [`CameraFrame::region`]. Empty when the camera's consumer does not read them
    /// ([`FrameUse::labels`]).
    pub labels: Vec<u32>,
}

impl CameraFrame {
    /// The `[r, g, b]` of pixel `(u, v)`.
    ///
    /// # Panics
    /// If `(u, v)` is outside the image.
    pub fn rgb_at(&self, u: u32, v: u32) -> [u8; 3] {
        let i = 3 * (v * self.width + u) as usize;
        [self.rgb[i], self.rgb[i + 1], self.rgb[i + 2]]
    }

    /// The depth of pixel `(u, v)` in metres.
    ///
    /// # Panics
    /// If `(u, v)` is outside the image.
    pub fn depth_at(&self, u: u32, v: u32) -> f32 {
        self.depth_m[(v * self.width + u) as usize]
    }

    /// The semantic class of pixel `(u, v)`.
    ///
    /// # Panics
    /// If `(u, v)` is outside the image.
    pub fn class_at(&self, u: u32, v: u32) -> crate::SemanticClass {
        crate::segmentation::class_of(self.labels[(v * self.width + u) as usize])
    }

    /// The segmentation mask as an 8-bit grey image whose values are the
    /// [`crate::SemanticClass`] ids `0..=7`.
    pub fn class_mask(&self) -> image::GrayImage {
        let px = self
            .labels
            .iter()
            .map(|&l| crate::segmentation::class_of(l).id())
            .collect();
        image::GrayImage::from_raw(self.width, self.height, px)
            .expect("labels hold width × height values")
    }

    /// The 2-D bounding boxes of every visible actor, from the labels (pixels, occlusion
    /// included), ordered by class then actor.
    pub fn boxes(&self) -> Vec<crate::ObjectBox> {
        crate::segmentation::boxes(&self.labels, self.width)
    }

    /// The image as an `image` crate buffer (for PNG output and image processing).
    pub fn to_image(&self) -> image::RgbImage {
        image::RgbImage::from_raw(self.width, self.height, self.rgb.clone())
            .expect("rgb holds width × height × 3 bytes")
    }

    /// The depth map as an 8-bit grey image: `255` at 0 m falling linearly to `0` at
    /// `max_m` and beyond (sky black), for looking at.
    pub fn depth_image(&self, max_m: f32) -> image::GrayImage {
        let px = self
            .depth_m
            .iter()
            .map(|&d| {
                if d.is_finite() {
                    (255.0 * (1.0 - (d / max_m).clamp(0.0, 1.0))).round() as u8
                } else {
                    0
                }
            })
            .collect();
        image::GrayImage::from_raw(self.width, self.height, px)
            .expect("depth holds width × height values")
    }

    /// Writes the RGB image as PNG.
    ///
    /// # Errors
    /// [`SavePngError`]: the encoder's or the file system's message, naming the file.
    pub fn save_png(&self, path: &std::path::Path) -> Result<(), SavePngError> {
        self.to_image()
            .save_with_format(path, image::ImageFormat::Png)
            .map_err(|e| SavePngError {
                path: path.to_owned(),
                message: e.to_string(),
            })
    }
}

/// A frame that cannot be written as PNG ([`CameraFrame::save_png`]).
#[derive(Debug, thiserror::Error, Clone, PartialEq, Eq)]
#[error("cannot write `{}`: {message}", .path.display())]
pub struct SavePngError {
    /// The file.
    pub path: std::path::PathBuf,
    /// The encoder's or the file system's message.
    pub message: String,
}

impl<'a> Observation<'a> {
    /// The latest frame of the sensor named `camera` (RGB and depth), `None` when no camera
    /// is mounted ([`crate::Simulation::attach_camera`], [`crate::SensorSpec::Camera`]) or it
    /// has not captured one.
    pub fn camera(&self) -> Option<&'a CameraFrame> {
        match self.reading("camera") {
            Some(Reading::Camera(frame)) => Some(frame),
            _ => None,
        }
    }
}

/// The camera `spec` as a sensor of a world on `network` whose physics step is `dt_s`
/// seconds, rendering through the process's shared [`crate::render::Renderer`] what `usage`
/// says its consumer reads; `seed` drives its pixel noise.
///
/// # Errors
/// [`EngineError::Sensor`] when the camera's values are out of range, no GPU adapter is
/// found, or this build lacks the `render` feature.
pub(crate) fn sensor(
    network: &Network,
    spec: &CameraSpec,
    usage: FrameUse,
    seed: u64,
    dt_s: f64,
) -> Result<Box<dyn Sensor>, EngineError> {
    spec.validate()
        .map_err(|e| EngineError::Sensor(e.to_string()))?;
    #[cfg(feature = "render")]
    {
        let renderer =
            crate::render::Renderer::shared().map_err(|e| EngineError::Sensor(e.to_string()))?;
        let rig = rig::CameraRig::new(renderer, network, spec, usage, seed, dt_s)?;
        Ok(Box::new(rig))
    }
    #[cfg(not(feature = "render"))]
    {
        let _ = (network, usage, seed, dt_s);
        Err(EngineError::Sensor(
            "this build has no camera: paracosm-engine was built without its `render` \
             feature"
                .into(),
        ))
    }
}

/// A camera mounted on one simulation's ego vehicle.
#[cfg(feature = "render")]
mod rig {
    use std::sync::Arc;

    use super::{CameraFrame, CameraSpec, FrameUse};
    use crate::network::Network;
    use crate::render::{CameraPose, RenderJob, RenderObject, Renderer, SceneGeometry, View};
    use crate::EngineError;

    /// The renderer, the world's uploaded geometry and the camera's targets, for one simulation:
    /// the camera as a [`crate::sensor::Sensor`].
    pub(crate) struct CameraRig {
        renderer: Arc<Renderer>,
        scene: SceneGeometry,
        view: View,
        seed: u64,
        frames: u64,
        period: u64,
        frame: Option<CameraFrame>,
    }

    impl crate::sensor::Sensor for CameraRig {
        fn name(&self) -> &'static str {
            "camera"
        }

        fn period_ticks(&self) -> u64 {
            self.period
        }

        fn draws(&self) -> bool {
            true
        }

        fn physics_reach_m(&self) -> f64 {
            // It draws the scene's boxes; it casts nothing into the physics world.
            0.0
        }

        fn capture(&mut self, scene: &crate::sensor::Scene<'_>) -> Result<(), EngineError> {
            let pose = CameraPose {
                chassis_m: scene.ego.pos_m,
                heading_rad: scene.ego.heading_rad,
            };
            // The last frame's buffers take the new one.
            if let Some(old) = self.frame.take() {
                self.view.recycle(old);
            }
            let frame = self.render(pose, scene.boxes, (scene.light, scene.fog), scene.t_s)?;
            self.frame = Some(frame);
            Ok(())
        }

        fn reading(&self) -> Option<crate::sensor::Reading<'_>> {
            self.frame.as_ref().map(crate::sensor::Reading::Camera)
        }
    }

    impl CameraRig {
        pub(crate) fn new(
            renderer: Arc<Renderer>,
            network: &Network,
            camera: &CameraSpec,
            usage: FrameUse,
            seed: u64,
            dt_s: f64,
        ) -> Result<Self, EngineError> {
            let view = renderer
                .view_for(camera, usage)
                .map_err(|e| EngineError::Sensor(e.to_string()))?;
            Ok(CameraRig {
                scene: renderer.scene(network),
                renderer,
                view,
                seed,
                frames: 0,
                period: ((1.0 / (camera.rate_hz * dt_s)).round() as u64).max(1),
                frame: None,
            })
        }

        fn render(
            &mut self,
            pose: CameraPose,
            objects: &[RenderObject],
            light_fog: (f64, f64),
            t_s: f64,
        ) -> Result<CameraFrame, EngineError> {
            // Each frame's noise has its own stream: (test seed, frame number).
            let noise_seed = self.seed ^ self.frames.wrapping_mul(0x9E37_79B9_7F4A_7C15);
            self.frames += 1;
            self.renderer
                .render_one(RenderJob {
                    scene: &self.scene,
                    view: &mut self.view,
                    pose,
                    objects,
                    light: light_fog.0,
                    fog: light_fog.1,
                    t_s,
                    noise_seed,
                })
                .map_err(|e| EngineError::Sensor(e.to_string()))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn intrinsics_follow_the_36_mm_sensor() {
        let c = CameraSpec::default();
        assert!((c.focal_px() - 24.0 * 320.0 / 36.0).abs() < 1e-12);
        assert!((c.hfov_rad().to_degrees() - 73.74).abs() < 0.01);
        let wide = CameraSpec {
            focal_mm: 10.0,
            ..c.clone()
        };
        assert!(wide.hfov_rad() > c.hfov_rad());
        // The centre pixel looks straight ahead.
        let p = c.back_project(160.0, 120.0, 10.0);
        assert_eq!(p, [0.0, 0.0, 10.0]);
        assert!(c.validate().is_ok());
        assert!(CameraSpec {
            width: 0,
            ..c.clone()
        }
        .validate()
        .is_err());
        assert!(CameraSpec {
            focal_mm: f64::NAN,
            ..c
        }
        .validate()
        .is_err());
    }

    #[test]
    fn back_projection_with_pitch_lands_on_the_ground() {
        // A camera 1.4 m above the road, pitched down: the centre ray meets the road at
        // 1.4 / tan(pitch) ahead.
        let c = CameraSpec {
            mount_m: [0.0, 1.4, 0.0],
            pitch_rad: 0.1,
            ..CameraSpec::default()
        };
        let ground = 1.4 / 0.1f64.tan();
        let depth = ground * 0.1f64.cos() + 1.4 * 0.1f64.sin();
        let p = c.camera_to_vehicle(c.back_project(160.0, 120.0, depth));
        assert!(p[1].abs() < 1e-9, "{p:?}");
        // The back-projector gives the same bits.
        let b = c.back_projector();
        for (u, v, d) in [
            (160.0, 120.0, depth),
            (3.5, 200.5, 7.25),
            (319.5, 0.5, 80.0),
        ] {
            assert_eq!(
                b.vehicle_point(u, v, d),
                c.camera_to_vehicle(c.back_project(u, v, d))
            );
        }
        assert!((p[0] - ground).abs() < 1e-9, "{p:?}");
    }
}
