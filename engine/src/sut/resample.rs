//! The crop-and-resize an ONNX model's input goes through ([`super::preprocess`]), with its
//! filter weights worked out once per camera instead of once per frame.
//!
//! The shipped networks were trained on images resized by `image` 0.24's
//! `imageops::resize(.., FilterType::Triangle)`: a vertical pass into `f32` rows, then a
//! horizontal pass rounded to 8 bits, each output's weights the triangle kernel at the source
//! pixels' distances (scaled by the ratio when shrinking), normalised to sum 1. [`Resampler`]
//! does the same arithmetic in the same order, so its bytes are `image`'s bit for bit (the
//! test below compares them), but it reads the crop straight from the frame and keeps its
//! weights and its intermediate rows: `image` recomputes every weight for every frame, which
//! was a quarter of a `pilotnet` test's time (docs/performance.md, "The camera loop").

/// One axis's filter: output `k` reads `weights[k]` from source index `first[k]` on.
#[derive(Debug, Clone, PartialEq)]
struct Axis {
    first: Vec<usize>,
    weights: Vec<Vec<f32>>,
}

impl Axis {
    /// `image`'s triangle filter from `src` to `dst` pixels (its `vertical_sample` and
    /// `horizontal_sample` compute the same weights in `f32`).
    fn triangle(src: u32, dst: u32) -> Axis {
        let ratio = src as f32 / dst as f32;
        let sratio = if ratio < 1.0 { 1.0 } else { ratio };
        let support = sratio; // the triangle kernel's support is 1
        let mut first = Vec::with_capacity(dst as usize);
        let mut weights = Vec::with_capacity(dst as usize);
        for out in 0..dst {
            let centre = (out as f32 + 0.5) * ratio;
            let left = ((centre - support).floor() as i64).clamp(0, i64::from(src) - 1);
            let right = ((centre + support).ceil() as i64).clamp(left + 1, i64::from(src));
            let centre = centre - 0.5;
            let mut ws: Vec<f32> = (left..right)
                .map(|i| {
                    let x = ((i as f32 - centre) / sratio).abs();
                    if x < 1.0 {
                        1.0 - x
                    } else {
                        0.0
                    }
                })
                .collect();
            let mut sum = 0.0;
            for w in &ws {
                sum += w;
            }
            ws.iter_mut().for_each(|w| *w /= sum);
            first.push(left as usize);
            weights.push(ws);
        }
        Axis { first, weights }
    }
}

/// Resizes an RGB8 region of `src_w × src_h` pixels to `dst_w × dst_h` as `image`'s triangle
/// filter does, bit for bit; the weights and the intermediate rows are kept between frames.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Resampler {
    src: (u32, u32),
    dst: (u32, u32),
    rows: Axis,
    cols: Axis,
    /// The crop as f32: `src_h × src_w × 3` values.
    rows_f32: Vec<f32>,
    /// One row of the vertical pass: `src_w × 3` values.
    line: Vec<f32>,
    /// The vertical pass, transposed: `(src_w × 3) × dst_h` values.
    tmp: Vec<f32>,
    /// One column of the horizontal pass: `dst_h` values.
    column: Vec<f32>,
}

impl Resampler {
    /// A resampler from `src` to `dst` (width, height), both at least 1 × 1.
    pub(crate) fn new(src: (u32, u32), dst: (u32, u32)) -> Self {
        Resampler {
            src,
            dst,
            rows: Axis::triangle(src.1, dst.1),
            cols: Axis::triangle(src.0, dst.0),
            rows_f32: Vec::with_capacity(src.1 as usize * src.0 as usize * 3),
            line: vec![0.0; src.0 as usize * 3],
            tmp: vec![0.0; dst.1 as usize * src.0 as usize * 3],
            column: vec![0.0; dst.1 as usize],
        }
    }

    /// Resizes the region of `rgb` (an RGB8 image `stride` pixels wide, row-major) whose
    /// top-left pixel is `origin` (column, row) and whose size is the resampler's source
    /// size, into `out` (`dst_h × dst_w × 3` bytes, row-major).
    ///
    /// # Panics
    /// If the region lies outside `rgb` or `out` has the wrong length.
    pub(crate) fn resize(&mut self, rgb: &[u8], stride: u32, origin: (u32, u32), out: &mut [u8]) {
        let (sw, sh) = (self.src.0 as usize, self.src.1 as usize);
        let (dw, dh) = (self.dst.0 as usize, self.dst.1 as usize);
        let stride = stride as usize;
        let (x0, y0) = (origin.0 as usize, origin.1 as usize);
        assert_eq!(out.len(), dw * dh * 3, "output size");
        if (sw, sh) == (dw, dh) {
            // `image` copies an image whose size does not change.
            for y in 0..sh {
                let from = 3 * ((y0 + y) * stride + x0);
                out[3 * y * dw..3 * (y + 1) * dw].copy_from_slice(&rgb[from..from + 3 * sw]);
            }
            return;
        }
        // The crop's rows as f32, once.
        let values = 3 * sw;
        self.rows_f32.clear();
        for y in 0..sh {
            let from = 3 * ((y0 + y) * stride + x0);
            self.rows_f32
                .extend(rgb[from..from + values].iter().map(|&v| f32::from(v)));
        }
        // The vertical pass, row by row (vectorised along the row), stored transposed:
        // `tmp[value · dh + oy]`, so the horizontal pass runs along columns.
        for (oy, (&top, ws)) in self.rows.first.iter().zip(&self.rows.weights).enumerate() {
            let line = &mut self.line;
            line.iter_mut().for_each(|t| *t = 0.0);
            for (i, &w) in ws.iter().enumerate() {
                let row = &self.rows_f32[(top + i) * values..(top + i + 1) * values];
                for (t, &v) in line.iter_mut().zip(row) {
                    *t += v * w;
                }
            }
            for (k, &t) in line.iter().enumerate() {
                self.tmp[k * dh + oy] = t;
            }
        }
        // The horizontal pass, one output column at a time (vectorised along the column).
        for (ox, (&left, ws)) in self.cols.first.iter().zip(&self.cols.weights).enumerate() {
            for c in 0..3 {
                let acc = &mut self.column;
                acc.iter_mut().for_each(|t| *t = 0.0);
                for (i, &w) in ws.iter().enumerate() {
                    let k = 3 * (left + i) + c;
                    for (t, &v) in acc.iter_mut().zip(&self.tmp[k * dh..(k + 1) * dh]) {
                        *t += v * w;
                    }
                }
                for (y, &t) in acc.iter().enumerate() {
                    out[3 * (y * dw + ox) + c] = round_to_u8(t);
                }
            }
        }
    }
}

/// `v.clamp(0, 255).round() as u8` (halves away from zero), without a call to `roundf`: the
/// whole part of a value in `[0, 255]` and its fraction are exact in `f32`.
fn round_to_u8(v: f32) -> u8 {
    let v = v.clamp(0.0, 255.0);
    let whole = v as u32; // truncates: v ≥ 0
    let up = v - whole as f32 >= 0.5;
    (whole + u32::from(up)).min(255) as u8
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    #[test]
    fn rounding_is_roundf_on_every_float_of_a_quarter_to_256() {
        // Every f32 from 0.25 (83 million), where halves and their neighbours lie.
        let mut v = 0.25f32;
        while v <= 256.0 {
            assert_eq!(round_to_u8(v), v.clamp(0.0, 255.0).round() as u8, "{v}");
            v = f32::from_bits(v.to_bits() + 1);
        }
        for v in [
            -1.0,
            -0.4,
            0.0,
            1e-30,
            0.2,
            f32::NEG_INFINITY,
            300.0,
            f32::INFINITY,
        ] {
            assert_eq!(round_to_u8(v), v.clamp(0.0, 255.0).round() as u8, "{v}");
        }
    }

    /// Every size the shipped networks use and others (shrinking, growing, one axis each,
    /// odd ratios, a 1-pixel side): the same bytes as `image`'s own resize.
    #[test]
    fn matches_image_triangle_resize_bit_for_bit() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let cases = [
            ((320, 240), (60, 96, 200, 104), (96, 48)),
            ((160, 120), (0, 0, 160, 120), (66, 200)),
            ((50, 40), (3, 5, 41, 33), (17, 9)),
            ((50, 40), (0, 0, 50, 40), (50, 40)),
            ((50, 40), (10, 1, 13, 7), (31, 22)),
            ((9, 9), (0, 0, 9, 1), (4, 3)),
            ((64, 48), (0, 8, 64, 32), (64, 16)),
        ];
        for ((w, h), (x0, y0, cw, ch), (dw, dh)) in cases {
            let img = image::RgbImage::from_fn(w, h, |_, _| image::Rgb(rng.random::<[u8; 3]>()));
            let want = image::imageops::resize(
                &image::imageops::crop_imm(&img, x0, y0, cw, ch).to_image(),
                dw,
                dh,
                image::imageops::FilterType::Triangle,
            );
            let mut r = Resampler::new((cw, ch), (dw, dh));
            let mut got = vec![0; (dw * dh * 3) as usize];
            r.resize(img.as_raw(), w, (x0, y0), &mut got);
            assert_eq!(got, want.into_raw(), "{w}×{h} crop {cw}×{ch} → {dw}×{dh}");
            // Reused: the same bytes again.
            let mut again = vec![0; got.len()];
            r.resize(img.as_raw(), w, (x0, y0), &mut again);
            assert_eq!(got, again);
        }
    }
}
