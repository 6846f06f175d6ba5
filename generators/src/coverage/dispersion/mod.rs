//! Dispersion: the volume of the largest empty axis-parallel box (PARACOSM §3.1).

mod bracket;
mod plane;
mod sweep;

use serde::{Deserialize, Serialize};

use super::{check_unit_points, CoverageError};

/// An axis-parallel box `(lo_1, hi_1) × ... × (lo_d, hi_d)` inside `[0, 1]^d`, open: a point
/// on its boundary is not inside it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EmptyBox {
    /// Lower corner, `d` values in `[0, 1]`.
    pub lo: Vec<f64>,
    /// Upper corner, `d` values in `[0, 1]`, `hi[i] >= lo[i]`.
    pub hi: Vec<f64>,
}

impl EmptyBox {
    /// The box's volume `Π (hi_i - lo_i)`.
    pub fn volume(&self) -> f64 {
        self.lo.iter().zip(&self.hi).map(|(l, h)| h - l).product()
    }

    /// Whether `p` (length `d`) lies strictly inside.
    pub fn contains_strictly(&self, p: &[f64]) -> bool {
        p.iter()
            .zip(self.lo.iter().zip(&self.hi))
            .all(|(x, (l, h))| l < x && x < h)
    }

    /// Checks emptiness against an `n × d` row-major point set in `O(n d)`: the way anyone can
    /// verify a reported witness.
    pub fn is_empty_of(&self, points: &[f64]) -> bool {
        let d = self.lo.len();
        !points.chunks_exact(d).any(|p| self.contains_strictly(p))
    }

    fn unit(d: usize) -> Self {
        EmptyBox {
            lo: vec![0.0; d],
            hi: vec![1.0; d],
        }
    }
}

/// The dispersion of a point set: exact, or a certified bracket.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Dispersion {
    /// A lower bound: the volume of `witness`, an empty box anyone can check.
    pub lower: f64,
    /// A proven upper bound (equal to `lower` when `exact`).
    pub upper: f64,
    /// Whether `lower == upper` is the exact dispersion, proven by exhaustive enumeration.
    pub exact: bool,
    /// The largest empty box found.
    pub witness: EmptyBox,
    /// How the numbers were obtained, and which bound the upper one is.
    pub method: String,
}

/// Limits of [`dispersion`].
#[derive(Debug, Clone, PartialEq)]
pub struct DispersionOptions {
    /// For `d >= 3`, the largest `n` solved exactly, by dimension: index `d - 3` (`d = 3, 4,
    /// 5, ...`); past the table's end (by default `d > 6`) no `n` is, and the bracket
    /// applies. Default `[10_000, 1_000, 120, 60]`: each takes at most about 6 s on 2 cores
    /// (`d = 3`: 3.7 s for 10,000 uniform random points, 5.7 s for 10,000 Halton points, 70 s
    /// for 32,768; `d = 4`: 3.0 s for 1,000 Halton points; measured 2026-11-27).
    pub exact_max_points: Vec<usize>,
    /// Regions the branch and bound of the bracket may process. Default 20,000.
    pub bracket_regions: usize,
    /// Random starts of the greedy lower bound, per dimension. Default 64.
    pub greedy_starts_per_dim: usize,
    /// Seed of the greedy starts (ChaCha8). Default 0.
    pub seed: u64,
}

impl Default for DispersionOptions {
    fn default() -> Self {
        DispersionOptions {
            exact_max_points: vec![10_000, 1_000, 120, 60],
            bracket_regions: 20_000,
            greedy_starts_per_dim: 64,
            seed: 0,
        }
    }
}

/// Dispersion of `points` (`n × d`, row-major, values in `[0, 1]`): the largest volume of an
/// open axis-parallel box inside `[0, 1]^d` that contains no point; boxes touching the cube's
/// boundary count (PARACOSM §3.1; Niederreiter, "Random Number Generation and Quasi-Monte
/// Carlo Methods", SIAM 1992, ch. 6, with axis-parallel boxes as the neighbourhoods).
///
/// - `d = 1`: exact, the largest gap between sorted values and the ends, `O(n log n)`.
/// - `d = 2`: exact. Every maximal empty rectangle has its left side on a point, or on
///   `x = 0`, or spans `[0, 1]` in `x`. For each point `p` a sweep to the right finds the next
///   point whose `y` lies in the current open band with a range-minimum segment tree over `y`,
///   and shrinks the band (Naamad, Lee, Hsu, "On the maximum empty rectangle problem",
///   Discrete Appl. Math. 8, 1984, with pruning by the best area so far). Rectangles on `x = 0`
///   need one predecessor/successor query per point, and full-width strips the largest `y`
///   gap. `O(log n)` per visited point; 0.28–0.46 s for `n = 65,536` to `100,000` random,
///   Halton or Sobol points on 2 cores.
/// - `d >= 3`, `n` within [`DispersionOptions::exact_max_points`]: exact, by the same
///   decomposition on the first axis, keeping the maximal empty `(d-1)`-boxes around each
///   supporting point as the sweep adds points, pruned by the best volume so far; the boxes
///   spanning the first axis recurse on the other `d - 1` axes.
/// - Otherwise: a certified bracket. Lower: the largest of the boxes found by the exact sweep
///   with each walk cut after 32 steps, many greedily grown maximal empty boxes, and the boxes
///   met by the branch and bound. Upper: a branch and bound over the box
///   corners (each region fixes an interval for every `lo_i` and `hi_i`; a region is dropped
///   when a point lies strictly inside its smallest box, since then every box of the region
///   contains it; an empty box of a region must leave each point of the region's union box
///   out along some axis, which caps its volume; the largest cap over the regions left bounds
///   every empty box). The bound is proven by that partition and case argument (the
///   subdivision follows Breuel's branch and bound for maximal empty rectangles, "Two
///   geometric algorithms for layout analysis", DAS 2002), and tightens with
///   [`DispersionOptions::bracket_regions`].
///
/// Points on the cube's boundary lie in no open box and never count. Deterministic: the same
/// input and options give the same result and witness on any thread count.
///
/// # Errors
/// [`CoverageError::Shape`] for `d = 0` or a length not a multiple of `d`;
/// [`CoverageError::OutsideUnitCube`] for a value that is NaN or outside `[0, 1]`;
/// [`CoverageError::OutOfMemory`] when its buffers (about `32d + 64` bytes a point) cannot be
/// allocated.
pub fn dispersion(
    points: &[f64],
    d: usize,
    options: &DispersionOptions,
) -> Result<Dispersion, CoverageError> {
    dispersion_with_progress(points, d, options, &super::no_progress)
}

/// [`dispersion`], telling `progress` how far the exact sweep in `d >= 3` has come (its
/// supporting points, each side; the plane's sweep and a bracket report nothing).
///
/// # Errors
/// As [`dispersion`].
pub fn dispersion_with_progress(
    points: &[f64],
    d: usize,
    options: &DispersionOptions,
    progress: super::Progress<'_>,
) -> Result<Dispersion, CoverageError> {
    let n = check_unit_points(points, d)?;
    // Copies of the points and their columns, sorted.
    let per_point = d.saturating_mul(32).saturating_add(64);
    super::error::reserve_working("the dispersion", n, d, per_point)?;
    // Points with a coordinate on the boundary are inside no open box.
    let inner: Vec<f64> = points
        .chunks_exact(d)
        .filter(|p| p.iter().all(|&x| 0.0 < x && x < 1.0))
        .flatten()
        .copied()
        .collect();
    let m = inner.len() / d;
    // Past the table's end nothing is solved exactly: the sweep's work grows like n^(d/2) and
    // 60 points in d = 8 did not finish in 2 minutes.
    let limit = options
        .exact_max_points
        .get(d.saturating_sub(3))
        .copied()
        .unwrap_or(0);
    let past_exact = d >= 3 && m > limit;
    if d > MAX_SEARCH_DIMS || (past_exact && m.saturating_mul(d * d) > MAX_BRACKET_WORK) {
        // The sweep's and the bracket's work grows with d (boxes of d sides, greedy starts
        // per dimension): past this, only the cheap lower bound of the widest empty slab.
        return Ok(widest_slab(&inner, d, n));
    }
    let (witness, method) = match d {
        1 => (max_gap(&inner), "exact: largest gap (d = 1)".to_owned()),
        2 => (
            plane::largest_empty_rectangle(&inner),
            "exact: maximal-empty-rectangle sweep (d = 2)".to_owned(),
        ),
        _ if m <= limit => (
            sweep::largest_empty_box(&inner, d, progress),
            format!("exact: maximal-empty-box sweep (d = {d}, n = {n})"),
        ),
        _ => {
            let b = bracket::bracket(&inner, d, options);
            let exact = b.upper <= b.witness.volume();
            let lower = b.witness.volume();
            let method = format!(
                "bracket (d = {d}, n = {n} is past the exact limit {limit}): lower = largest \
                 empty box found (capped sweep, greedy maximal boxes), upper = branch and bound \
                 over box corners after {} regions; the exact value is at most {} the lower end",
                b.regions,
                super::star::bracket_factor(lower, b.upper.max(lower))
            );
            return Ok(Dispersion {
                lower,
                upper: b.upper.max(lower),
                exact,
                witness: b.witness,
                method,
            });
        }
    };
    let v = witness.volume();
    Ok(Dispersion {
        lower: v,
        upper: v,
        exact: true,
        witness,
        method,
    })
}

/// The dispersion's bracket past the search limits: the widest empty slab (a box spanning
/// every axis but one whole) of the `inner` points (`m × d`, row-major, none on the
/// boundary; `n` points in all), O(n d log n), as the lower end and 1 as the upper.
fn widest_slab(inner: &[f64], d: usize, n: usize) -> Dispersion {
    let mut best = (
        0.0,
        0,
        EmptyBox {
            lo: vec![],
            hi: vec![],
        },
    );
    for axis in 0..d {
        let column: Vec<f64> = inner.chunks_exact(d).map(|p| p[axis]).collect();
        let gap = max_gap(&column);
        let width = gap.hi[0] - gap.lo[0];
        if width > best.0 {
            best = (width, axis, gap);
        }
    }
    let (width, axis, gap) = best;
    let mut lo = vec![0.0; d];
    let mut hi = vec![1.0; d];
    lo[axis] = gap.lo[0];
    hi[axis] = gap.hi[0];
    Dispersion {
        lower: width,
        upper: 1.0,
        exact: width >= 1.0,
        witness: EmptyBox { lo, hi },
        method: format!(
            "bracket (d = {d}, n = {n}: past the search limits of {MAX_SEARCH_DIMS} \
             dimensions or n × d² = {MAX_BRACKET_WORK}): lower = the widest empty slab, \
             upper = 1; the sweep and the branch and bound were skipped; the exact value is \
             at most {} the lower end",
            super::star::bracket_factor(width, 1.0)
        ),
    }
}

/// Most dimensions in which [`dispersion`] searches for empty boxes (the exact sweep or the
/// bracket); past it only the widest empty slab bounds it from below, and the upper bound is 1.
pub const MAX_SEARCH_DIMS: usize = 32;

/// The largest `n × d²` for which [`dispersion`] runs the bracket (past the exact limits);
/// past it, as past [`MAX_SEARCH_DIMS`]. Measured on this project's 2-core machine: `d = 4,
/// n = 10,000` (160,000) takes 4 s; `d = 32, n = 500` (512,000) took 26 s and `n = 5,000`
/// more than 100 s.
pub const MAX_BRACKET_WORK: usize = 400_000;

/// `d = 1`: the largest gap between consecutive sorted values, `0` and `1`.
fn max_gap(xs: &[f64]) -> EmptyBox {
    let mut v: Vec<f64> = xs.to_vec();
    v.sort_by(f64::total_cmp);
    let mut best = (0.0, 0.0, 0.0);
    let mut prev = 0.0;
    for &x in v.iter().chain(std::iter::once(&1.0)) {
        if x - prev > best.0 {
            best = (x - prev, prev, x);
        }
        prev = x;
    }
    EmptyBox {
        lo: vec![best.1],
        hi: vec![best.2],
    }
}

/// Deterministic choice between two candidate boxes: larger volume, then lexicographically
/// smaller corners.
pub(crate) fn better(a: &EmptyBox, av: f64, b: &EmptyBox, bv: f64) -> bool {
    match av.total_cmp(&bv) {
        std::cmp::Ordering::Greater => true,
        std::cmp::Ordering::Less => false,
        std::cmp::Ordering::Equal => {
            let ka = a.lo.iter().chain(&a.hi);
            let kb = b.lo.iter().chain(&b.hi);
            ka.zip(kb)
                .map(|(x, y)| x.total_cmp(y))
                .find(|o| o.is_ne())
                .is_some_and(|o| o.is_lt())
        }
    }
}

#[cfg(test)]
mod tests;
