//! A camera mounted on one simulation's ego vehicle.

use std::sync::Arc;

use super::gpu::{CameraPose, RenderJob, RenderObject, Renderer, SceneGeometry, View};
use crate::camera::{CameraFrame, CameraSpec};

use crate::network::Network;
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
        seed: u64,
        dt_s: f64,
    ) -> Result<Self, EngineError> {
        let view = renderer
            .view(camera)
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
