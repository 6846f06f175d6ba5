//! The reference line of a curved road piece (`Arc`, `Clothoid`): a clothoid, whose curvature
//! changes linearly with arc length, of which an arc (constant curvature) is the special case.
//!
//! In the piece's frame the line starts at the origin heading along `+x`; its heading after
//! `s` metres is `θ(s) = κ₀·s + (κ₁ − κ₀)·s² / (2L)` (rad, counter-clockwise seen from above:
//! positive curvature turns left), and its point is `∫₀ˢ (cos θ, −sin θ) du` in `[x, z]`
//! metres (`z` points to the right of `+x`, as everywhere in the engine). The integral is
//! evaluated with 8-point Gauss–Legendre quadrature on panels of at most 2 m, which is exact
//! to well below a micrometre for any curvature a road has: arcs and clothoids are checked
//! against their closed forms (circle, Fresnel integrals) in the tests. Curves are the
//! geometry of OpenDRIVE's `arc` and `spiral` records (ASAM OpenDRIVE 1.8, §9.3–9.5).

use serde::{Deserialize, Serialize};

/// Largest step between the points of [`RefLine::polyline`], in metres. The chord of a step
/// departs from the curve by `step² · κ / 8`: 0.8 mm at the tightest radius a piece may have
/// (10 m).
pub const POLYLINE_STEP_M: f64 = 0.25;

/// Stride of the coarse pass of [`SampledLine::project`], in samples (4 m).
const COARSE: usize = 16;

/// Gauss–Legendre nodes on `[-1, 1]` (positive half) and weights, 8 points.
const GL8: [(f64, f64); 4] = [
    (0.183_434_642_495_649_8, 0.362_683_783_378_362),
    (0.525_532_409_916_329, 0.313_706_645_877_887_3),
    (0.796_666_477_413_626_7, 0.222_381_034_453_374_5),
    (0.960_289_856_497_536_3, 0.101_228_536_290_376_3),
];

/// Largest quadrature panel, in metres.
const PANEL_M: f64 = 2.0;

/// A clothoid reference line of length `length_m` whose curvature goes linearly from
/// `curv_start` to `curv_end` (1/m, positive to the left).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RefLine {
    /// Arc length, metres, `> 0`.
    pub length_m: f64,
    /// Curvature at `s = 0`, 1/m.
    pub curv_start: f64,
    /// Curvature at `s = length_m`, 1/m.
    pub curv_end: f64,
}

impl RefLine {
    /// The circular arc of radius `radius_m` (> 0) turning through `angle_rad` (positive:
    /// left, counter-clockwise seen from above).
    pub fn arc(radius_m: f64, angle_rad: f64) -> RefLine {
        let k = angle_rad.signum() / radius_m;
        RefLine {
            length_m: radius_m * angle_rad.abs(),
            curv_start: k,
            curv_end: k,
        }
    }

    /// The curvature at `s` metres, 1/m.
    pub fn curvature(&self, s: f64) -> f64 {
        self.curv_start + (self.curv_end - self.curv_start) * s / self.length_m
    }

    /// The heading at `s` metres, rad (0 at the start).
    pub fn heading(&self, s: f64) -> f64 {
        self.curv_start * s + (self.curv_end - self.curv_start) * s * s / (2.0 * self.length_m)
    }

    /// The point at `s` metres (`0 ≤ s ≤ length_m`, not checked), `[x, z]` in the piece's frame:
    /// the quadrature from the start (its cost grows with `s`; [`RefLine::frames`] walks the
    /// whole line at the cost of one quadrature).
    pub fn point(&self, s: f64) -> [f64; 2] {
        self.chord(0.0, s)
    }

    /// The unit vector to the right of the direction of travel at `s` (`[sin θ, cos θ]`):
    /// where driving lanes `1, 2, …` lie.
    pub fn right(&self, s: f64) -> [f64; 2] {
        let (sin, cos) = self.heading(s).sin_cos();
        [sin, cos]
    }

    /// The point `t` metres right of the line at `s` (negative `t`: left), in the piece's frame.
    pub fn offset(&self, s: f64, t: f64) -> [f64; 2] {
        let p = self.point(s);
        let r = self.right(s);
        [p[0] + t * r[0], p[1] + t * r[1]]
    }

    /// Arc lengths from 0 to `length_m` in equal steps of at most `max_step_m` (at least two).
    pub fn stations(&self, max_step_m: f64) -> Vec<f64> {
        let n = (self.length_m / max_step_m).ceil().max(1.0) as usize;
        (0..=n)
            .map(|i| self.length_m * i as f64 / n as f64)
            .collect()
    }

    /// The line's frames at [`RefLine::stations`] of `max_step_m`, built incrementally (one
    /// quadrature per step).
    pub fn frames(&self, max_step_m: f64) -> Vec<Frame> {
        self.polyline(max_step_m)
            .into_iter()
            .map(|(s, point)| {
                let (sin, cos) = self.heading(s).sin_cos();
                Frame {
                    s,
                    point,
                    right: [sin, cos],
                }
            })
            .collect()
    }

    /// Points of the line at [`RefLine::stations`] of `max_step_m`, each with its station,
    /// built incrementally (one quadrature per step).
    pub fn polyline(&self, max_step_m: f64) -> Vec<(f64, [f64; 2])> {
        let stations = self.stations(max_step_m);
        let mut out = Vec::with_capacity(stations.len());
        let mut p = [0.0, 0.0];
        let mut prev = 0.0;
        for s in stations {
            if s > prev {
                let d = self.chord(prev, s);
                p = [p[0] + d[0], p[1] + d[1]];
            }
            out.push((s, p));
            prev = s;
        }
        out
    }

    /// `point(b) − point(a)`, integrated over `[a, b]` only.
    fn chord(&self, a: f64, b: f64) -> [f64; 2] {
        let panels = ((b - a).abs() / PANEL_M).ceil().max(1.0);
        let h = (b - a) / panels;
        let (mut x, mut z) = (0.0, 0.0);
        for i in 0..panels as usize {
            let mid = a + (i as f64 + 0.5) * h;
            for (node, w) in GL8 {
                for u in [mid - node * h / 2.0, mid + node * h / 2.0] {
                    let (sin, cos) = self.heading(u).sin_cos();
                    x += w * h / 2.0 * cos;
                    z -= w * h / 2.0 * sin;
                }
            }
        }
        [x, z]
    }

    /// The frame at station `s` (one quadrature from the start).
    pub fn frame(&self, s: f64) -> Frame {
        Frame {
            s,
            point: self.point(s),
            right: self.right(s),
        }
    }

    /// The largest `|κ|` along the line, 1/m.
    pub fn max_curvature(&self) -> f64 {
        self.curv_start.abs().max(self.curv_end.abs())
    }
}

/// A point of a [`RefLine`] with its station and the unit vector to its right.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frame {
    /// Station, metres from the start.
    pub s: f64,
    /// The point `[x, z]`, piece frame, metres.
    pub point: [f64; 2],
    /// Unit vector to the right of the direction of travel.
    pub right: [f64; 2],
}

impl Frame {
    /// The point `t` metres to the right (negative: left), piece frame.
    pub fn offset(&self, t: f64) -> [f64; 2] {
        [
            self.point[0] + t * self.right[0],
            self.point[1] + t * self.right[1],
        ]
    }
}

/// A [`RefLine`] sampled for point queries: stations every [`POLYLINE_STEP_M`] at most.
#[derive(Debug, Clone, PartialEq)]
pub struct SampledLine {
    /// Station (m) and point `[x, z]` (piece frame) of each sample, in order.
    pub samples: Vec<(f64, [f64; 2])>,
    /// The line's unit tangents at its start and its end, `[x, z]`: the ends' cross-sections
    /// are perpendicular to them (not to the first and last chords, which turn by half a
    /// step's angle less).
    pub end_tangents: [[f64; 2]; 2],
}

impl SampledLine {
    /// Samples `line`.
    pub fn new(line: &RefLine) -> Self {
        let tangent = |s: f64| {
            let (sin, cos) = line.heading(s).sin_cos();
            [cos, -sin]
        };
        SampledLine {
            samples: line.polyline(POLYLINE_STEP_M),
            end_tangents: [tangent(0.0), tangent(line.length_m)],
        }
    }

    /// The nearest point of the line to the piece-frame point `p`: its station `s` (in
    /// `[0, L]`, m), the signed lateral offset of `p` (m, positive to the right of the
    /// direction of travel) and the distance past either end along the line (m, 0 between
    /// them).
    pub fn project(&self, p: [f64; 2]) -> (f64, f64, f64) {
        let n = self.samples.len();
        // Coarse to fine: the nearest of every COARSE-th sample, then the chords around it.
        // Points within a road's width of the line (whose radius is at least 10 m) have one
        // nearest stretch, which the coarse pass finds.
        let d2 = |q: [f64; 2]| (q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2);
        let nearest = (0..n)
            .step_by(COARSE)
            .chain([n - 1])
            .min_by(|&a, &b| d2(self.samples[a].1).total_cmp(&d2(self.samples[b].1)))
            .unwrap_or(0);
        let lo = nearest.saturating_sub(COARSE);
        let hi = (nearest + COARSE).min(n - 1);
        let mut best = (f64::INFINITY, 0.0, 0.0, 0.0);
        for (i, w) in self.samples[lo..=hi].windows(2).enumerate() {
            let i = lo + i;
            let ((s0, a), (s1, b)) = (w[0], w[1]);
            let d = [b[0] - a[0], b[1] - a[1]];
            let rel = [p[0] - a[0], p[1] - a[1]];
            let len2 = d[0] * d[0] + d[1] * d[1];
            let raw = (rel[0] * d[0] + rel[1] * d[1]) / len2;
            let u = raw.clamp(0.0, 1.0);
            let (ex, ez) = (rel[0] - u * d[0], rel[1] - u * d[1]);
            let dist2 = ex * ex + ez * ez;
            if dist2 < best.0 {
                let len = len2.sqrt();
                // Right of travel along d: (-d_z, d_x) in the (x, z) plane.
                let lateral = (rel[1] * d[0] - rel[0] * d[1]) / len;
                // Past an end: beyond the end's cross-section, perpendicular to the line's
                // tangent there (the chord's perpendicular would leave a wedge of up to
                // |t|·κ·step/2 between this piece and the next one at the outer lanes).
                let along =
                    |end: [f64; 2], t: [f64; 2]| (p[0] - end[0]) * t[0] + (p[1] - end[1]) * t[1];
                let past = if i == 0 && raw <= 0.5 {
                    (-along(a, self.end_tangents[0])).max(0.0)
                } else if i == n - 2 && raw >= 0.5 {
                    along(b, self.end_tangents[1]).max(0.0)
                } else {
                    0.0
                };
                best = (dist2, s0 + u * (s1 - s0), lateral, past);
            }
        }
        // Rounding at an end is not "past" it.
        let past = if best.3 < 1e-9 { 0.0 } else { best.3 };
        (best.1, best.2, past)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    /// Fresnel integrals `C(x) = ∫₀ˣ cos(πt²/2) dt` and `S(x)` by their power series
    /// (Abramowitz and Stegun 7.3.11–7.3.13), for `|x| ≤ 3`.
    fn fresnel(x: f64) -> (f64, f64) {
        let (mut c, mut s) = (0.0, 0.0);
        let a = PI / 2.0;
        let mut term = 1.0; // (−1)^n a^(2n) / (2n)!, then a^(2n+1)/(2n+1)!
        for n in 0..60 {
            let k = n as f64;
            let even = term * x.powi(4 * n + 1) / (4.0 * k + 1.0);
            let odd_term = term * a / (2.0 * k + 1.0);
            let odd = odd_term * x.powi(4 * n + 3) / (4.0 * k + 3.0);
            c += even;
            s += odd;
            term = -odd_term * a / (2.0 * k + 2.0);
        }
        (c, s)
    }

    #[test]
    fn an_arc_ends_where_the_circle_says_with_its_heading() {
        for (radius, angle) in [
            (30.0, PI / 2.0),
            (12.5, -PI / 3.0),
            (200.0, 0.4),
            (15.0, -PI),
        ] {
            let line = RefLine::arc(radius, angle);
            let k: f64 = angle.signum() / radius;
            let expected = [angle.abs().sin() * radius, -(1.0 - angle.cos()) / k];
            let end = line.point(line.length_m);
            assert!((end[0] - expected[0]).abs() < 1e-9, "{end:?} {expected:?}");
            assert!((end[1] - expected[1]).abs() < 1e-9, "{end:?} {expected:?}");
            assert!((line.heading(line.length_m) - angle).abs() < 1e-12);
            // Every point lies on the circle about the centre (0, -1/k).
            for (_, p) in line.polyline(1.0) {
                let r = p[0].hypot(p[1] + 1.0 / k);
                assert!((r - radius).abs() < 1e-9, "{r}");
            }
        }
    }

    #[test]
    fn a_clothoid_ends_where_the_fresnel_integrals_say_to_a_millimetre_over_100_m() {
        // From curvature 0: θ = κ₁ s² / (2L) = π u² / 2 with s = a·u, a = √(πL/κ₁).
        for (length, k1) in [(100.0, 0.02), (100.0, -0.05), (60.0, 0.1)] {
            let line = RefLine {
                length_m: length,
                curv_start: 0.0,
                curv_end: k1,
            };
            let a = (PI * length / k1.abs()).sqrt();
            let (c, s) = fresnel(length / a);
            let expected = [a * c, -k1.signum() * a * s];
            let end = line.point(length);
            let err = (end[0] - expected[0]).hypot(end[1] - expected[1]);
            assert!(err < 1e-3, "{err} m: {end:?} vs {expected:?}");
            assert!(err < 1e-9, "quadrature is far better than required: {err}");
            let walked = line.polyline(POLYLINE_STEP_M).last().unwrap().1;
            assert!((walked[0] - end[0]).hypot(walked[1] - end[1]) < 1e-9);
        }
        // From κ₀ ≠ 0: θ = (c/2)(s + κ₀/c)² − κ₀²/(2c), c = (κ₁ − κ₀)/L: a difference of
        // Fresnel integrals, rotated by the constant.
        let (length, k0, k1) = (100.0, 0.01, 0.03);
        let line = RefLine {
            length_m: length,
            curv_start: k0,
            curv_end: k1,
        };
        let cc = (k1 - k0) / length;
        let a = (PI / cc).sqrt();
        let (u0, u1) = (k0 / cc / a, (length + k0 / cc) / a);
        let ((c0, s0), (c1, s1)) = (fresnel(u0), fresnel(u1));
        let (dx, dz) = (a * (c1 - c0), a * (s1 - s0));
        let phi = -k0 * k0 / (2.0 * cc);
        let (sin, cos) = phi.sin_cos();
        let expected = [dx * cos - dz * sin, -(dx * sin + dz * cos)];
        let end = line.point(length);
        let err = (end[0] - expected[0]).hypot(end[1] - expected[1]);
        assert!(err < 1e-3, "{err} m: {end:?} vs {expected:?}");
    }

    #[test]
    fn projection_finds_the_station_and_the_signed_offset() {
        let line = RefLine::arc(40.0, PI / 2.0);
        let sampled = SampledLine::new(&line);
        for s in [0.5, 10.0, 31.4, 60.0] {
            for t in [-5.0, 0.0, 3.0] {
                let (ps, pt, past) = sampled.project(line.offset(s, t));
                // Chords place a point |t| m off the line up to |t|·κ·step/2 along it.
                let tolerance = t.abs() / 40.0 * POLYLINE_STEP_M / 2.0 + 1e-6;
                assert!((ps - s).abs() <= tolerance, "{ps} vs {s}");
                assert!((pt - t).abs() < 0.005, "{pt} vs {t}");
                assert_eq!(past, 0.0);
            }
        }
        let (s, _, past) = sampled.project([-3.0, 0.0]);
        assert_eq!(s, 0.0);
        assert!((past - 3.0).abs() < 1e-4, "{past}");
    }
}
