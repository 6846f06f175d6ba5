//! Sensor effects applied to a frame after readback: Gaussian blur, then Gaussian pixel noise.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

use crate::sensor::camera::{CameraFrame, CameraSpec};

/// Applies the camera's blur (`image`'s Gaussian blur, σ in pixels) and additive noise (σ in
/// 8-bit levels, drawn from ChaCha8 seeded with `seed`, clipped to `[0, 255]`). The depth map
/// and the labels are left exact.
pub(crate) fn apply(mut frame: CameraFrame, camera: &CameraSpec, seed: u64) -> CameraFrame {
    if camera.blur_sigma_px > 0.0 {
        let blurred = image::imageops::blur(&frame.to_image(), camera.blur_sigma_px as f32);
        frame.rgb = blurred.into_raw();
    }
    if camera.noise_sigma > 0.0 {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let normal = Normal::new(0.0, camera.noise_sigma).expect("σ validated as finite >= 0");
        for v in &mut frame.rgb {
            let noisy = f64::from(*v) + normal.sample(&mut rng);
            *v = noisy.round().clamp(0.0, 255.0) as u8;
        }
    }
    frame
}

#[cfg(test)]
mod tests {
    use super::*;

    fn flat(v: u8) -> CameraFrame {
        CameraFrame {
            t_s: 0.0,
            width: 8,
            height: 4,
            rgb: vec![v; 8 * 4 * 3],
            depth_m: vec![1.0; 32],
            labels: vec![2; 32],
        }
    }

    #[test]
    fn noise_has_the_asked_spread_and_is_reproducible() {
        let camera = CameraSpec {
            noise_sigma: 10.0,
            ..CameraSpec::default()
        };
        let a = apply(flat(128), &camera, 3);
        let b = apply(flat(128), &camera, 3);
        let c = apply(flat(128), &camera, 4);
        assert_eq!(a, b);
        assert_ne!(a.rgb, c.rgb);
        let n = a.rgb.len() as f64;
        let mean = a.rgb.iter().map(|&v| f64::from(v)).sum::<f64>() / n;
        let var = a
            .rgb
            .iter()
            .map(|&v| (f64::from(v) - mean).powi(2))
            .sum::<f64>()
            / n;
        assert!((mean - 128.0).abs() < 3.0, "{mean}");
        assert!((var.sqrt() - 10.0).abs() < 2.5, "{}", var.sqrt());
        assert_eq!(a.depth_m, flat(128).depth_m);
    }

    #[test]
    fn blur_keeps_a_flat_image_flat_and_off_changes_nothing() {
        let camera = CameraSpec {
            blur_sigma_px: 1.5,
            ..CameraSpec::default()
        };
        assert_eq!(apply(flat(90), &camera, 0).rgb, flat(90).rgb);
        assert_eq!(apply(flat(90), &CameraSpec::default(), 0), flat(90));
    }
}
