use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::{check_unit_points, CoverageError};

/// The L∞ star discrepancy of a point set: exact, or a certified bracket.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StarDiscrepancy {
    /// A lower bound: the local discrepancy at `witness`, which anyone can recompute in `O(nd)`.
    pub lower: f64,
    /// A proven upper bound (equal to `lower` when `exact`).
    pub upper: f64,
    /// Whether `lower == upper` is exact, proven by exhaustive enumeration.
    pub exact: bool,
    /// The anchored box's corner `y` (length `d`) of the largest local discrepancy found.
    pub witness: Vec<f64>,
    /// How the numbers were obtained.
    pub method: String,
}

/// Most dimensions in which [`star_discrepancy`] searches and covers; past it only the
/// one-axis lower bound is computed, and the upper bound is 1. A bracket's
/// [`StarDiscrepancy::method`] says how far it can be from the exact value (`upper / lower`).
pub const MAX_SEARCH_DIMS: usize = 64;

/// The largest `n² · d` for which [`star_discrepancy`] searches and covers past its exact
/// limits (measured on this project's 2-core machine: `d = 8, n = 2,000`, 3.2·10^7, takes 4 s;
/// `d = 4, n = 10,000`, 4·10^8, took 38 s); past it the lower bound is the one-axis one, and
/// the upper bound still the grid cover (which costs `O(n·d)` plus its cells).
pub const MAX_SEARCH_WORK: f64 = 5e7;

/// Limits of [`star_discrepancy`].
#[derive(Debug, Clone, PartialEq)]
pub struct StarOptions {
    /// Largest `n` solved exactly for `d = 1, 2, 3, 4`. Default
    /// `[usize::MAX, 20_000, 4_096, 256]`: in d = 3 the sweep takes about 7 s and 330 MB at
    /// 4,096 points and 44 s and 2 GB at 10,000, in d = 4 the prefix sweeps take 1.1 s at 256
    /// Halton points and 198 s at 1,024, on this project's 2-core machine with another job
    /// beside them (`cargo run --release -p paracosm-generators --example star3d -- 1024 halton
    /// 4`). The campaign summary computes it after every campaign; raise it for research sizes.
    pub exact_max_points: [usize; 4],
    /// Cells of the grid δ-cover of the upper bound, at most. Default 2,000,000.
    pub cover_cells: usize,
    /// Random starts of the lower-bound search. Default 8.
    pub search_starts: usize,
    /// Seed of the search (ChaCha8). Default 0.
    pub seed: u64,
}

impl Default for StarOptions {
    fn default() -> Self {
        StarOptions {
            exact_max_points: [usize::MAX, 20_000, 4_096, 256],
            cover_cells: 2_000_000,
            search_starts: 8,
            seed: 0,
        }
    }
}

/// The L∞ star discrepancy `D*(P) = sup_y |A(P, [0, y))/n − vol([0, y))|` of `points`
/// (`n × d`, row-major, values in `[0, 1]`).
///
/// The supremum is a maximum over the grid `Γ = Π_k ({x_ik} ∪ {1})` of
/// `max(vol([0,y)) − A([0,y))/n, A([0,y])/n − vol([0,y]))`, open boxes for the first term and
/// closed ones for the second (Niederreiter, "Discrepancy and convex programming", Ann. Mat.
/// Pura Appl. 93, 1972; see Gnewuch, Srivastav, Winzen, "Finding optimal volume subintervals
/// with k points and calculating the star discrepancy are NP-hard problems", J. Complexity 25,
/// 2009, §1).
///
/// - Exact for `d <= 4` within [`StarOptions::exact_max_points`], by enumerating `Γ` with
///   running counts, as in Bundschuh and Zhu ("A method for exact calculation of the
///   discrepancy of low-dimensional finite point sets I", Abh. Math. Sem. Univ. Hamburg 63,
///   1993): `O(n log n)` for `d = 1`, `O(n²)` for `d = 2`; for `d = 3` a sweep over the first
///   axis with blocked upper envelopes, `O(n^{5/2})` (Dobkin, Eppstein and Mitchell,
///   "Computing the discrepancy with applications to supersampling patterns", ACM TOG 15(4),
///   1996; `star3d.rs`); for `d = 4` one such sweep, volumes scaled, per prefix of the points
///   sorted along the first axis, `O(n^{7/2})` (`star4d.rs`).
/// - Otherwise a certified bracket. Lower: the best grid point found by coordinate ascent
///   from random starts. Upper: the δ-cover bound of Thiémard ("An algorithm to compute
///   bounds for the star discrepancy", J. Complexity 17, 2001) on the uniform grid with `m`
///   cells per axis: for `a <= y <= b` with `a` and `b = a + 1/m` grid points,
///   `vol(y) − A([0,y))/n <= vol(b) − A([0,a))/n` and
///   `A([0,y])/n − vol(y) <= A([0,b])/n − vol(a)`, maximised over the `m^d` cells with a
///   cumulative histogram (`m` as large as [`StarOptions::cover_cells`] allows).
///
/// # Errors
/// [`CoverageError::Shape`] for `d = 0`, a ragged length or `n = 0`;
/// [`CoverageError::OutsideUnitCube`] for NaN or a value outside `[0, 1]`;
/// [`CoverageError::OutOfMemory`] when its buffers (about `32d + 64` bytes a point) cannot be
/// allocated.
pub fn star_discrepancy(
    points: &[f64],
    d: usize,
    options: &StarOptions,
) -> Result<StarDiscrepancy, CoverageError> {
    star_discrepancy_with_progress(points, d, options, &super::no_progress)
}

/// [`star_discrepancy`], telling `progress` how far an exact computation has come (the
/// planes of the sweep in d = 3, the prefixes in d = 4; a bracket reports nothing).
///
/// # Errors
/// As [`star_discrepancy`].
pub fn star_discrepancy_with_progress(
    points: &[f64],
    d: usize,
    options: &StarOptions,
    progress: super::Progress<'_>,
) -> Result<StarDiscrepancy, CoverageError> {
    let n = check_unit_points(points, d)?;
    if n == 0 {
        return Err(CoverageError::Shape("the point set is empty".into()));
    }
    // Copies of the points and their columns, sorted.
    let per_point = d.saturating_mul(32).saturating_add(64);
    super::error::reserve_working("the star discrepancy", n, d, per_point)?;
    if d <= 4 && n <= options.exact_max_points[d - 1] {
        let (value, witness) = match d {
            1 => exact_1d(points),
            2 => plane_terms(points, points, 1.0, n),
            3 => super::star3d::exact_3d_sweep(points, progress),
            _ => super::star4d::exact_4d_prefixes(points, progress),
        };
        return Ok(StarDiscrepancy {
            lower: value,
            upper: value,
            exact: true,
            witness,
            method: if d == 3 {
                "exact: sweep of the critical grid with blocked envelopes (d = 3; Dobkin, \
                 Eppstein, Mitchell 1996)"
                    .to_owned()
            } else if d == 4 {
                "exact: one scaled d = 3 sweep per prefix along the first axis (d = 4; Dobkin, \
                 Eppstein, Mitchell 1996)"
                    .to_owned()
            } else {
                format!("exact: enumeration of the critical grid (d = {d})")
            },
        });
    }
    let work = (n as f64) * (n as f64) * d as f64;
    let searched = d <= MAX_SEARCH_DIMS && work <= MAX_SEARCH_WORK;
    let (lower, witness) = if searched {
        search(points, d, options)
    } else {
        // The search costs O(n²·d) per round; past its limit, the cheap lower bound of the
        // boxes `[0, 1)^(d-1) × [0, y)` along one axis (each axis's 1-D star discrepancy),
        // O(n d log n).
        let mut best = (0.0, vec![1.0; d]);
        for axis in 0..d {
            let column: Vec<f64> = points.chunks_exact(d).map(|p| p[axis]).collect();
            let (value, y) = exact_1d(&column);
            if value > best.0 {
                let mut witness = vec![1.0; d];
                witness[axis] = y[0];
                best = (value, witness);
            }
        }
        best
    };
    // The grid cover costs O(n·d + cells·d) whatever n is: past the search's limit it still
    // gives an upper bound (all but useless past a few dimensions, where it has 1 or 2 cells
    // per axis).
    let (upper, m) = if d <= MAX_SEARCH_DIMS {
        let (u, m) = cover_bound(points, d, options.cover_cells);
        (u.max(lower), Some(m))
    } else {
        (1.0, None)
    };
    let lower_how = if searched {
        format!(
            "coordinate ascent over the critical grid ({} starts)",
            options.search_starts
        )
    } else {
        format!(
            "the largest 1-D star discrepancy of one coordinate (n = {n}, d = {d}: past the \
             search limits of {MAX_SEARCH_DIMS} dimensions or n² · d = {MAX_SEARCH_WORK:.0e})"
        )
    };
    let upper_how = match m {
        Some(m) => format!("δ-cover bound on a uniform grid of {m}^{d} cells (Thiémard 2001)"),
        None => "1 (no grid cover past 64 dimensions)".to_owned(),
    };
    Ok(StarDiscrepancy {
        lower,
        upper,
        exact: false,
        witness,
        method: format!(
            "bracket: lower = {lower_how}, upper = {upper_how}; the exact value is at most {} \
             the lower end",
            bracket_factor(lower, upper)
        ),
    })
}

/// How far a bracket `[lower, upper]` can be from the exact value, as words: "1.7 times",
/// or "unbounded times" when `lower` is 0.
pub(super) fn bracket_factor(lower: f64, upper: f64) -> String {
    if lower > 0.0 {
        format!("{:.3} times", upper / lower)
    } else {
        "unbounded times".to_owned()
    }
}

/// Local discrepancy at `y`: `max(vol − open count / n, closed count / n − vol)`.
fn local(points: &[f64], d: usize, y: &[f64]) -> f64 {
    let n = points.len() / d;
    let (mut open, mut closed) = (0usize, 0usize);
    for p in points.chunks_exact(d) {
        if p.iter().zip(y).all(|(a, b)| a < b) {
            open += 1;
        }
        if p.iter().zip(y).all(|(a, b)| a <= b) {
            closed += 1;
        }
    }
    let vol: f64 = y.iter().product();
    (vol - open as f64 / n as f64).max(closed as f64 / n as f64 - vol)
}

fn exact_1d(points: &[f64]) -> (f64, Vec<f64>) {
    let n = points.len();
    let mut xs = points.to_vec();
    xs.sort_by(f64::total_cmp);
    let mut best = (-1.0, 1.0);
    let mut i = 0;
    let candidates = xs.iter().copied().chain(std::iter::once(1.0));
    let mut last = f64::NAN;
    for y in candidates {
        if y == last {
            continue;
        }
        last = y;
        while i < n && xs[i] < y {
            i += 1;
        }
        let open = i;
        let mut closed = i;
        while closed < n && xs[closed] <= y {
            closed += 1;
        }
        let v = (y - open as f64 / n as f64).max(closed as f64 / n as f64 - y);
        if v > best.0 {
            best = (v, y);
        }
    }
    (best.0, vec![best.1])
}

/// The enumeration of the critical grid in `O(n³ log n)`: the reference the sweep of
/// [`super::star3d`] is tested against.
#[cfg(test)]
fn exact_3d(points: &[f64]) -> (f64, Vec<f64>) {
    let n = points.len() / 3;
    let mut zs: Vec<f64> = points.chunks_exact(3).map(|p| p[0]).collect();
    zs.push(1.0);
    zs.sort_by(f64::total_cmp);
    zs.dedup();
    let mut best = (-1.0, vec![1.0; 3]);
    for &y0 in &zs {
        // Open term: points with x0 < y0; closed term: points with x0 <= y0. The two need
        // different subsets, so evaluate both and keep the larger per grid point.
        let open: Vec<f64> = points
            .chunks_exact(3)
            .filter(|p| p[0] < y0)
            .flat_map(|p| [p[1], p[2]])
            .collect();
        let closed: Vec<f64> = points
            .chunks_exact(3)
            .filter(|p| p[0] <= y0)
            .flat_map(|p| [p[1], p[2]])
            .collect();
        let (v, w) = plane_terms(&open, &closed, y0, n);
        if v > best.0 {
            best = (v, std::iter::once(y0).chain(w).collect());
        }
    }
    best
}

/// The enumeration in `d = 4`: every pair of the first two grid coordinates, the plane of the
/// last two by [`plane_terms`]; `O(n⁴ log n)`, the reference of [`super::star4d`].
#[cfg(test)]
fn exact_4d(points: &[f64]) -> f64 {
    let n = points.len() / 4;
    let grid = |k: usize| {
        let mut g: Vec<f64> = points.chunks_exact(4).map(|p| p[k]).collect();
        g.push(1.0);
        g.sort_by(f64::total_cmp);
        g.dedup();
        g
    };
    let (g0, g1) = (grid(0), grid(1));
    let mut best: f64 = -1.0;
    for &y0 in &g0 {
        for &y1 in &g1 {
            let subset = |inside: &dyn Fn(f64, f64) -> bool| -> Vec<f64> {
                points
                    .chunks_exact(4)
                    .filter(|p| inside(p[0], y0) && inside(p[1], y1))
                    .flat_map(|p| [p[2], p[3]])
                    .collect()
            };
            let open = subset(&|x, y| x < y);
            let closed = subset(&|x, y| x <= y);
            best = best.max(plane_terms(&open, &closed, y0 * y1, n).0);
        }
    }
    best
}

/// Max over the critical grid of the plane of `vol − open/n` (from `open`) and
/// `closed/n − vol` (from `closed`), with volumes scaled by `scale`.
fn plane_terms(open: &[f64], closed: &[f64], scale: f64, n: usize) -> (f64, Vec<f64>) {
    let grid = |c: usize| -> Vec<f64> {
        let mut v: Vec<f64> = open
            .chunks_exact(2)
            .chain(closed.chunks_exact(2))
            .map(|p| p[c])
            .collect();
        v.push(1.0);
        v.sort_by(f64::total_cmp);
        v.dedup();
        v
    };
    let (g1, g2) = (grid(0), grid(1));
    let per_row: Vec<(f64, f64, f64)> = g1
        .par_iter()
        .map(|&y1| {
            // Histograms over g2: open points with x < y1, closed points with x <= y1.
            let mut o = vec![0u32; g2.len()];
            let mut c = vec![0u32; g2.len()];
            for p in open.chunks_exact(2).filter(|p| p[0] < y1) {
                o[g2.partition_point(|&v| v < p[1])] += 1;
            }
            for p in closed.chunks_exact(2).filter(|p| p[0] <= y1) {
                c[g2.partition_point(|&v| v < p[1])] += 1;
            }
            let mut best = (-1.0, y1, 1.0);
            let (mut below_open, mut upto_closed) = (0u32, 0u32);
            for (k, &y2) in g2.iter().enumerate() {
                upto_closed += c[k];
                let vol = scale * y1 * y2;
                let v = (vol - f64::from(below_open) / n as f64)
                    .max(f64::from(upto_closed) / n as f64 - vol);
                if v > best.0 {
                    best = (v, y1, y2);
                }
                below_open += o[k];
            }
            best
        })
        .collect();
    // Reduce in grid order so ties resolve the same way on any thread count.
    let best = per_row
        .into_iter()
        .fold((-1.0, 1.0, 1.0), |a, b| if b.0 > a.0 { b } else { a });
    (best.0, vec![best.1, best.2])
}

/// Lower bound: coordinate ascent over the critical grid from random grid points.
fn search(points: &[f64], d: usize, options: &StarOptions) -> (f64, Vec<f64>) {
    let mut grids: Vec<Vec<f64>> = (0..d)
        .map(|k| {
            let mut g: Vec<f64> = points.chunks_exact(d).map(|p| p[k]).collect();
            g.push(1.0);
            g.sort_by(f64::total_cmp);
            g.dedup();
            g
        })
        .collect();
    let mut rng = ChaCha8Rng::seed_from_u64(options.seed);
    let mut best = (local(points, d, &vec![1.0; d]), vec![1.0; d]);
    for _ in 0..options.search_starts {
        let mut y: Vec<f64> = grids
            .iter_mut()
            .map(|g| g[rng.random_range(0..g.len())])
            .collect();
        let mut value = local(points, d, &y);
        loop {
            let mut improved = false;
            for k in 0..d {
                let (v, c) = grids[k]
                    .par_iter()
                    .map(|&c| {
                        let mut t = y.clone();
                        t[k] = c;
                        (local(points, d, &t), c)
                    })
                    .reduce(
                        || (-1.0, 1.0),
                        |a, b| {
                            if b.0 > a.0 || (b.0 == a.0 && b.1 < a.1) {
                                b
                            } else {
                                a
                            }
                        },
                    );
                if v > value {
                    value = v;
                    y[k] = c;
                    improved = true;
                }
            }
            if !improved {
                break;
            }
        }
        if value > best.0 {
            best = (value, y);
        }
    }
    best
}

/// Upper bound of the δ-cover on the uniform grid with `m` cells per axis; returns `(bound, m)`.
fn cover_bound(points: &[f64], d: usize, max_cells: usize) -> (f64, usize) {
    let n = points.len() / d;
    let m = ((max_cells as f64).powf(1.0 / d as f64).floor() as usize).max(1);
    let cells = m.pow(d as u32);
    let mut hist = vec![0u64; cells];
    for p in points.chunks_exact(d) {
        let mut idx = 0;
        for &x in p {
            idx = idx * m + ((x * m as f64) as usize).min(m - 1);
        }
        hist[idx] += 1;
    }
    // Inclusive cumulative sums: hist[k] = #points with cell index <= k on every axis.
    // Axis by axis, from the last (stride 1): within each block of `m · stride` cells, the
    // cells at coordinate c >= 1 on this axis add those at c - 1.
    let mut stride = 1;
    for _ in 0..d {
        for block in (0..cells).step_by(m * stride) {
            for idx in block + stride..block + m * stride {
                hist[idx] += hist[idx - stride];
            }
        }
        stride *= m;
    }
    let inv = 1.0 / m as f64;
    let mut best: f64 = 0.0;
    let mut k = vec![0usize; d];
    for _ in 0..cells {
        // a = k/m, b = (k+1)/m. A([0,a)) counts cells < k: inclusive sums at k-1, none when
        // some k_i = 0. A([0,b]) may include points on the face x_i = b_i: count cells
        // <= k+1 (capped). Volumes are products over the axes in order.
        let (mut below, mut empty_below, mut upto) = (0usize, false, 0usize);
        let (mut vol_a, mut vol_b) = (1.0f64, 1.0f64);
        for &c in &k {
            match c.checked_sub(1) {
                Some(b) => below = below * m + b,
                None => empty_below = true,
            }
            upto = upto * m + (c + 1).min(m - 1);
            vol_a *= c as f64 * inv;
            vol_b *= ((c + 1) as f64 * inv).min(1.0);
        }
        let open_a = if empty_below { 0 } else { hist[below] } as f64 / n as f64;
        let closed_b = hist[upto] as f64 / n as f64;
        best = best.max(vol_b - open_a).max(closed_b - vol_a);
        // next cell
        for c in k.iter_mut().rev() {
            *c += 1;
            if *c < m {
                break;
            }
            *c = 0;
        }
    }
    (best.min(1.0), m)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn past_the_search_limits_the_bracket_is_the_largest_one_axis_discrepancy() {
        // 2 points in d = 70, all coordinates 0.5 but axis 3 at 0.9 and 0.95.
        let d = 70;
        let mut pts = vec![0.5; 2 * d];
        pts[3] = 0.9;
        pts[d + 3] = 0.95;
        let r = star_discrepancy(&pts, d, &StarOptions::default()).unwrap();
        // Axis 3 alone: [0, 0.9) holds no point but has volume 0.9.
        assert!((r.lower - 0.9).abs() < 1e-12, "{r:?}");
        assert_eq!(r.upper, 1.0);
        assert!(r.method.contains("search limits"), "{}", r.method);
        assert!(r.method.contains("at most 1.111 times"), "{}", r.method);
    }

    /// The exact computations tell their progress, up to their whole work (the planes of the
    /// sweep in d = 3, the prefixes in d = 4), and give what they give without it.
    #[test]
    fn the_exact_sweeps_report_their_progress_to_the_end() {
        for d in [3, 4] {
            let pts = crate::Halton::new(&crate::ParamSpace::unit_cube(d)).unit_points(0, 60);
            let seen = std::sync::Mutex::new(Vec::new());
            let with = star_discrepancy_with_progress(&pts, d, &StarOptions::default(), &|a, b| {
                seen.lock().unwrap().push((a, b));
            })
            .unwrap();
            let without = star_discrepancy(&pts, d, &StarOptions::default()).unwrap();
            assert!(with.exact);
            assert_eq!(with.lower, without.lower, "d = {d}");
            let seen = seen.into_inner().unwrap();
            let total = seen[0].1;
            // 60 distinct first coordinates and the cube's end: 61 planes, or 61 prefixes.
            assert_eq!(total, 61, "d = {d}");
            assert!(
                seen.iter().all(|&(a, b)| b == total && a <= total),
                "d = {d}: {seen:?}"
            );
            assert_eq!(seen.iter().map(|s| s.0).max(), Some(total), "d = {d}");
        }
    }

    #[test]
    fn past_the_search_work_the_cover_still_bounds_and_the_bracket_says_how_far() {
        // 5,000 random points in d = 3 with no exact solve: n² · d = 7.5e7 is past the search,
        // but the grid cover (125³ cells) bounds it well below 1.
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let pts: Vec<f64> = (0..15_000)
            .map(|_| rand::Rng::random::<f64>(&mut rng))
            .collect();
        let options = StarOptions {
            exact_max_points: [0; 4],
            ..StarOptions::default()
        };
        let r = star_discrepancy(&pts, 3, &options).unwrap();
        assert!(!r.exact);
        assert!(r.upper < 0.1 && r.lower > 0.0, "{r:?}");
        let factor = format!("at most {:.3} times the lower end", r.upper / r.lower);
        assert!(r.method.contains(&factor), "{}", r.method);
        assert!(r.method.contains("125^3 cells"), "{}", r.method);
    }

    /// Brute force over the critical grid.
    fn brute(points: &[f64], d: usize) -> f64 {
        let grids: Vec<Vec<f64>> = (0..d)
            .map(|k| {
                let mut g: Vec<f64> = points.chunks_exact(d).map(|p| p[k]).collect();
                g.push(1.0);
                g
            })
            .collect();
        let total: usize = grids.iter().map(Vec::len).product();
        let mut best: f64 = 0.0;
        for mut idx in 0..total {
            let y: Vec<f64> = grids
                .iter()
                .map(|g| {
                    let v = g[idx % g.len()];
                    idx /= g.len();
                    v
                })
                .collect();
            best = best.max(local(points, d, &y));
        }
        best
    }

    #[test]
    fn one_dimensional_formula() {
        // D* of the centred grid (2i-1)/(2n) is 1/(2n) (Niederreiter 1992, Thm 2.6).
        let n = 10;
        let pts: Vec<f64> = (1..=n)
            .map(|i| (2 * i - 1) as f64 / (2 * n) as f64)
            .collect();
        let s = star_discrepancy(&pts, 1, &StarOptions::default()).unwrap();
        assert!((s.upper - 0.05).abs() < 1e-12 && s.exact);
    }

    /// The δ-cover bound counted directly: for every grid cell, the points in `[0, a)` and
    /// in `[0, b]` by a scan of the set (no cumulative sums).
    fn cover_bound_by_counting(points: &[f64], d: usize, max_cells: usize) -> f64 {
        let n = points.len() / d;
        let m = ((max_cells as f64).powf(1.0 / d as f64).floor() as usize).max(1);
        let cell = |x: f64| ((x * m as f64) as usize).min(m - 1);
        let mut best: f64 = 0.0;
        for mut idx in 0..m.pow(d as u32) {
            let mut k = vec![0; d];
            for c in k.iter_mut().rev() {
                *c = idx % m;
                idx /= m;
            }
            let inside = |p: &[f64], upper: &dyn Fn(usize, usize) -> bool| {
                p.iter().zip(&k).all(|(&x, &c)| upper(cell(x), c))
            };
            let open_a = points
                .chunks_exact(d)
                .filter(|p| inside(p, &|i, c| i < c))
                .count();
            let closed_b = points
                .chunks_exact(d)
                .filter(|p| inside(p, &|i, c| i <= (c + 1).min(m - 1)))
                .count();
            let inv = 1.0 / m as f64;
            let vol_a: f64 = k.iter().map(|&c| c as f64 * inv).product();
            let vol_b: f64 = k.iter().map(|&c| ((c + 1) as f64 * inv).min(1.0)).product();
            best = best
                .max(vol_b - open_a as f64 / n as f64)
                .max(closed_b as f64 / n as f64 - vol_a);
        }
        best.min(1.0)
    }

    proptest! {
        #[test]
        fn the_cover_bound_equals_counting_each_cell(
            d in 1usize..5,
            cells in 1usize..3000,
            raw in prop::collection::vec(0u8..=255, 4..80),
        ) {
            let n = raw.len() / d;
            prop_assume!(n >= 1);
            // Values 0, 1 and cell boundaries included.
            let pts: Vec<f64> = raw[..n * d].iter().map(|&v| f64::from(v.min(250)) / 250.0).collect();
            let (bound, _) = cover_bound(&pts, d, cells);
            prop_assert_eq!(bound.to_bits(), cover_bound_by_counting(&pts, d, cells).to_bits());
        }

        #[test]
        fn exact_matches_brute_force(
            d in 1usize..5,
            raw in prop::collection::vec(0u8..9, 3..30),
        ) {
            // Coordinates on a coarse grid (ties and boundary values included).
            let n = raw.len() / d;
            prop_assume!(n >= 1);
            let pts: Vec<f64> = raw[..n * d].iter().map(|&v| v as f64 / 8.0).collect();
            let s = star_discrepancy(&pts, d, &StarOptions::default()).unwrap();
            let b = brute(&pts, d);
            prop_assert!(s.exact);
            prop_assert!((s.upper - b).abs() < 1e-12, "{} vs {}", s.upper, b);
            prop_assert!((local(&pts, d, &s.witness) - s.lower).abs() < 1e-12);
        }

        #[test]
        fn the_sweep_equals_the_enumeration(
            raw in prop::collection::vec(0u16..=1000, 3..600),
            coarse in any::<bool>(),
        ) {
            // Up to 200 points: several blocks of the sweep's plane per axis; on a coarse grid,
            // ties along every axis and the values 0 and 1.
            let n = raw.len() / 3;
            let pts: Vec<f64> = raw[..n * 3]
                .iter()
                .map(|&v| if coarse { f64::from(v % 11) / 10.0 } else { f64::from(v) / 1000.0 })
                .collect();
            let (a, wa) = super::super::star3d::exact_3d_sweep(&pts, &super::super::no_progress);
            let (b, _) = exact_3d(&pts);
            prop_assert!((a - b).abs() < 1e-12, "sweep {} vs enumeration {}", a, b);
            prop_assert!((local(&pts, 3, &wa) - a).abs() < 1e-12);
        }

        #[test]
        fn the_prefix_sweeps_equal_the_enumeration_in_d4(
            raw in prop::collection::vec(0u16..=1000, 4..160),
            coarse in any::<bool>(),
        ) {
            // Up to 40 points: planes of several blocks in the larger prefixes; on a coarse
            // grid, ties along every axis and the values 0 and 1.
            let n = raw.len() / 4;
            let pts: Vec<f64> = raw[..n * 4]
                .iter()
                .map(|&v| if coarse { f64::from(v % 7) / 6.0 } else { f64::from(v) / 1000.0 })
                .collect();
            let s = star_discrepancy(&pts, 4, &StarOptions::default()).unwrap();
            let b = exact_4d(&pts);
            prop_assert!(s.exact);
            prop_assert!((s.upper - b).abs() < 1e-12, "prefix sweeps {} vs enumeration {}", s.upper, b);
            prop_assert!((local(&pts, 4, &s.witness) - s.upper).abs() < 1e-12);
        }

        #[test]
        fn bracket_contains_the_exact_value(
            raw in prop::collection::vec(0u8..=255, 6..60),
        ) {
            let d = 3;
            let n = raw.len() / d;
            let pts: Vec<f64> = raw[..n * d].iter().map(|&v| v as f64 / 255.0).collect();
            let exact = star_discrepancy(&pts, d, &StarOptions::default()).unwrap();
            let opts = StarOptions { exact_max_points: [0; 4], cover_cells: 20_000, ..StarOptions::default() };
            let b = star_discrepancy(&pts, d, &opts).unwrap();
            prop_assert!(!b.exact);
            prop_assert!(b.lower <= exact.upper + 1e-12 && exact.upper <= b.upper + 1e-12,
                "{} <= {} <= {}", b.lower, exact.upper, b.upper);
        }
    }
}
