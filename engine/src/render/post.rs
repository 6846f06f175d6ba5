//! Sensor effects applied to a frame after readback: Gaussian blur, then Gaussian pixel noise.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::sensor::camera::{CameraFrame, CameraSpec};

/// Applies the camera's blur (`image`'s Gaussian blur, σ in pixels) and additive noise (σ in
/// 8-bit levels, clipped to `[0, 255]`, drawn from ChaCha8 seeded with `seed` by [`Noise`]).
/// The depth map and the labels are left exact. Noise is drawn for every byte of the frame
/// in order and written inside `frame.region` only, so the pixels a region shows are those
/// of the whole frame.
pub(crate) fn apply(
    frame: &mut CameraFrame,
    noise: Option<&Noise>,
    camera: &CameraSpec,
    seed: u64,
) {
    if camera.blur_sigma_px > 0.0 {
        let blurred = image::imageops::blur(&frame.to_image(), camera.blur_sigma_px as f32);
        frame.rgb = blurred.into_raw();
    }
    if let Some(noise) = noise {
        let mut words = Words::new(seed);
        if frame.region == [0, 0, frame.width, frame.height] {
            for v in &mut frame.rgb {
                *v = noise.add(*v, &mut words);
            }
        } else {
            // The same draws as for the whole frame, written inside the region only.
            let [x0, y0, w, h] = frame.region.map(|v| v as usize);
            let row = 3 * frame.width as usize;
            let (first, last) = (3 * x0, 3 * (x0 + w));
            for (i, v) in frame.rgb.iter_mut().enumerate() {
                let noisy = noise.add(*v, &mut words);
                let (y, x) = (i / row, i % row);
                if y >= y0 && y < y0 + h && x >= first && x < last {
                    *v = noisy;
                }
            }
        }
    }
}

/// ChaCha8's output as a stream of 16-bit words (little-endian halves of its bytes).
struct Words {
    rng: ChaCha8Rng,
    buffer: [u16; 128],
    at: usize,
}

impl Words {
    fn new(seed: u64) -> Self {
        Words {
            rng: ChaCha8Rng::seed_from_u64(seed),
            buffer: [0; 128],
            at: 128,
        }
    }

    #[inline(always)]
    fn next(&mut self) -> u16 {
        if self.at == self.buffer.len() {
            self.rng.fill(&mut self.buffer[..]);
            self.at = 0;
        }
        self.at += 1;
        self.buffer[self.at - 1]
    }
}

/// Additive Gaussian noise of σ levels on 8-bit values.
///
/// The noisy value is `round(v + n)` with `n ~ N(0, σ²)`, clipped to `[0, 255]`. For a whole
/// `v` that is `v + k` with `k = round(n)`, whose law is `P(k) = Φ((k + ½)/σ) − Φ((k − ½)/σ)`:
/// [`Noise`] draws `k` by inverting that discrete distribution's CDF, tabulated once per σ
/// with 32-bit resolution (offsets beyond ±12σ, of probability below 2⁻³², are not drawn).
/// A draw reads one 16-bit word, which settles `k` but for the few words that straddle a
/// step of the CDF (under 0.1 % for σ = 2); those read a second word for the low 16 bits.
/// The law is that of rounding a normal draw, as before this table; the bits are not those of
/// `rand_distr`'s ziggurat, which took a 64-bit word and a logarithm per value and was a
/// third of a `vision` test's time (docs/performance.md, "The camera loop").
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Noise {
    /// The smallest offset `k`.
    low: i32,
    /// `cdf[i]`: `2³² · P(k ≤ low + i)`, saturating; the last is `u32::MAX`.
    cdf: Vec<u32>,
    /// `fast[a]`: the offset of every 32-bit word whose high half is `a`, or [`STRADDLES`].
    fast: Box<[i16; 1 << 16]>,
}

/// In [`Noise::fast`]: the words of this high half fall in two steps of the CDF.
const STRADDLES: i16 = i16::MIN;

impl Noise {
    /// The table for σ levels, shared by the process (one per σ); `None` when σ is 0.
    pub(crate) fn shared(sigma: f64) -> Option<std::sync::Arc<Noise>> {
        use std::collections::HashMap;
        use std::sync::{Arc, Mutex, OnceLock};
        static TABLES: OnceLock<Mutex<HashMap<u64, Arc<Noise>>>> = OnceLock::new();
        if !(sigma > 0.0 && sigma.is_finite()) {
            return None;
        }
        let tables = TABLES.get_or_init(Default::default);
        let mut tables = tables.lock().unwrap_or_else(|p| p.into_inner());
        let noise = tables
            .entry(sigma.to_bits())
            .or_insert_with(|| Arc::new(Noise::new(sigma)));
        Some(Arc::clone(noise))
    }

    /// The table for σ > 0 levels.
    fn new(sigma: f64) -> Noise {
        let phi = |x: f64| 0.5 * libm::erfc(-x / (sigma * std::f64::consts::SQRT_2));
        let reach = (12.0 * sigma).ceil().min(300.0) as i32;
        let low = -reach;
        let scale = 4_294_967_296.0;
        let mut cdf: Vec<u32> = (low..=reach)
            .map(|k| {
                (phi(f64::from(k) + 0.5) * scale)
                    .floor()
                    .min(f64::from(u32::MAX)) as u32
            })
            .collect();
        if let Some(last) = cdf.last_mut() {
            *last = u32::MAX;
        }
        let mut noise = Noise {
            low,
            cdf,
            fast: Box::new([0; 1 << 16]),
        };
        for a in 0..=u16::MAX {
            let from = u32::from(a) << 16;
            let k = noise.offset(from);
            noise.fast[usize::from(a)] = if noise.offset(from | 0xFFFF) == k {
                k as i16
            } else {
                STRADDLES
            };
        }
        noise
    }

    /// The offset for the uniform 32-bit word `u`: the first `k` with `u < 2³² · P(K ≤ k)`,
    /// or the largest.
    fn offset(&self, u: u32) -> i32 {
        let i = self
            .cdf
            .partition_point(|&c| c <= u)
            .min(self.cdf.len() - 1);
        self.low + i as i32
    }

    /// `v` with noise drawn from `words`, clipped to `[0, 255]`.
    #[inline(always)]
    fn add(&self, v: u8, words: &mut Words) -> u8 {
        let high = words.next();
        let k = match self.fast[usize::from(high)] {
            STRADDLES => self.offset(u32::from(high) << 16 | u32::from(words.next())),
            k => i32::from(k),
        };
        (i32::from(v) + k).clamp(0, 255) as u8
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn flat(v: u8) -> CameraFrame {
        CameraFrame {
            t_s: 0.0,
            width: 8,
            height: 4,
            region: [0, 0, 8, 4],
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
        let run = |seed| {
            let mut f = flat(128);
            apply(
                &mut f,
                Noise::shared(camera.noise_sigma).as_deref(),
                &camera,
                seed,
            );
            f
        };
        let (a, b, c) = (run(3), run(3), run(4));
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

    /// The 16-bit fast path agrees with the 32-bit search, few words straddle a step, and
    /// two million draws follow `P(k) = Φ((k + ½)/σ) − Φ((k − ½)/σ)` within 5 standard
    /// deviations for every `k` in ±4σ.
    #[test]
    fn offsets_follow_the_rounded_normal() {
        let sigma = 2.0;
        let noise = Noise::new(sigma);
        for (a, &k) in noise.fast.iter().enumerate() {
            if k != STRADDLES {
                for low in [0, 0x7FFF, 0xFFFF] {
                    assert_eq!(noise.offset((a as u32) << 16 | low), i32::from(k));
                }
            }
        }
        let straddling = noise.fast.iter().filter(|&&k| k == STRADDLES).count();
        assert!((1..100).contains(&straddling), "{straddling}");
        let mut words = Words::new(5);
        let n = 2_000_000;
        let mut counts = std::collections::BTreeMap::new();
        for _ in 0..n {
            *counts
                .entry(i32::from(noise.add(128, &mut words)) - 128)
                .or_insert(0usize) += 1;
        }
        let phi = |x: f64| 0.5 * libm::erfc(-x / (sigma * std::f64::consts::SQRT_2));
        for k in -8..=8 {
            let p = phi(f64::from(k) + 0.5) - phi(f64::from(k) - 0.5);
            let expected = n as f64 * p;
            let sd = (n as f64 * p * (1.0 - p)).sqrt();
            let got = counts.get(&k).copied().unwrap_or(0) as f64;
            assert!(
                (got - expected).abs() < 5.0 * sd + 1.0,
                "k = {k}: {got} vs {expected}"
            );
        }
    }

    #[test]
    fn blur_keeps_a_flat_image_flat_and_off_changes_nothing() {
        let camera = CameraSpec {
            blur_sigma_px: 1.5,
            ..CameraSpec::default()
        };
        let mut f = flat(90);
        apply(&mut f, None, &camera, 0);
        assert_eq!(f.rgb, flat(90).rgb);
        let mut f = flat(90);
        apply(&mut f, None, &CameraSpec::default(), 0);
        assert_eq!(f, flat(90));
    }
}
