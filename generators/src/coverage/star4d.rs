//! Exact star discrepancy in four dimensions by prefixes along the first axis, each solved by
//! the three-dimensional sweep of [`super::star3d`].
//!
//! On the critical grid `Γ = Γ₀ × Γ'`, fix the first coordinate `y₀`. An open box
//! `[0, y₀) × [0, y')` holds the points of the prefix `P = {x : x₀ < y₀}` whose other three
//! coordinates lie in `[0, y')`, so its local discrepancy is `y₀·vol(y') − A(P, [0, y'))/n`: a
//! three-dimensional problem over `P` with the volume scaled by `y₀` and the counts divided by
//! the whole set's `n`. The same holds for the closed term with `P = {x : x₀ <= y₀}`. Every
//! prefix (by the sorted first coordinates, ties kept together) serves both: its open term is
//! largest at the smallest `y₀` above it (the next first coordinate, or 1), its closed term at
//! the largest `y₀` inside it (its own last first coordinate), and the supremum over `y'` is
//! reached on the prefix's own critical grid. So `D*` is the largest of `n + 1` scaled
//! three-dimensional sweeps, `O(n · n^{5/2})` in all (Dobkin, Eppstein and Mitchell's
//! reduction of dimension `d` to `n` problems of dimension `d − 1`, ACM TOG 15(4), 1996, §4,
//! with the `d = 3` sweep below it).

use rayon::prelude::*;

use super::star3d::scaled_3d_sweep;

/// The exact star discrepancy of `points` (`n × 4`, row-major, in `[0, 1]`, `n < 2^32`) and its
/// witness corner (length 4), the same quantity as the enumeration of the critical grid. Time
/// `O(n^{7/2})`, memory `O(n²)` per thread: on this project's 2-core machine, with another job
/// beside it, 256 Halton points took 1.1 s, 384 took 4.1 s and 1,024 took 198 s
/// (`cargo run --release -p paracosm-generators --example star3d -- 1024 halton 4`).
pub(super) fn exact_4d_prefixes(points: &[f64], progress: super::Progress<'_>) -> (f64, Vec<f64>) {
    let n = points.len() / 4;
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| points[4 * a].total_cmp(&points[4 * b]));
    let first = |k: usize| points[4 * order[k]];
    // Prefix ends: 0 and the end of every run of equal first coordinates.
    let mut ends = vec![0];
    for k in 1..=n {
        if k == n || first(k) != first(k - 1) {
            ends.push(k);
        }
    }
    // Prefixes done, for `progress` (each prefix's own sweep reports nothing).
    let done = std::sync::atomic::AtomicU64::new(0);
    let total = ends.len() as u64;
    progress(0, total);
    let best = ends
        .par_iter()
        .map(|&end| {
            // Open boxes take the prefix up to the next first coordinate (or 1), closed boxes
            // up to the prefix's own last one (an empty prefix has no closed term: its count
            // is 0, so a zero volume makes the term 0, never above the true value).
            let open_y0 = if end < n { first(end) } else { 1.0 };
            let closed_y0 = if end > 0 { first(end - 1) } else { 0.0 };
            let rest: Vec<f64> = order[..end]
                .iter()
                .flat_map(|&i| points[4 * i + 1..4 * i + 4].iter().copied())
                .collect();
            let (value, corner, term) =
                scaled_3d_sweep(&rest, [open_y0, closed_y0], n as f64, &super::no_progress);
            progress(
                done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1,
                total,
            );
            let y0 = if term == 0 { open_y0 } else { closed_y0 };
            (
                value,
                std::iter::once(y0).chain(corner).collect::<Vec<f64>>(),
            )
        })
        .collect::<Vec<_>>();
    // In prefix order, ties to the first, so that any thread count gives the same witness.
    best.into_iter()
        .fold((f64::NEG_INFINITY, vec![1.0; 4]), |a, b| {
            if b.0 > a.0 {
                b
            } else {
                a
            }
        })
}
