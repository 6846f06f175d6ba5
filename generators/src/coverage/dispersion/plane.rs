//! Exact largest empty rectangle in the unit square (`d = 2`).

use std::collections::BTreeSet;
use std::ops::Bound::{Excluded, Unbounded};
use std::sync::atomic::{AtomicU64, Ordering};

use super::{better, max_gap, EmptyBox};

/// Range-minimum segment tree over `y` ranks holding `(x, point index)`; absent leaves hold
/// `+inf`.
struct MinTree {
    size: usize,
    nodes: Vec<(f64, u32)>,
}

impl MinTree {
    fn new(n: usize) -> Self {
        let size = n.next_power_of_two().max(1);
        MinTree {
            size,
            nodes: vec![(f64::INFINITY, u32::MAX); 2 * size],
        }
    }

    fn set(&mut self, leaf: usize, value: (f64, u32)) {
        let mut i = leaf + self.size;
        self.nodes[i] = value;
        while i > 1 {
            i /= 2;
            self.nodes[i] = min(self.nodes[2 * i], self.nodes[2 * i + 1]);
        }
    }

    /// Minimum over leaves `[lo, hi)`.
    fn query(&self, lo: usize, hi: usize) -> (f64, u32) {
        let mut best = (f64::INFINITY, u32::MAX);
        let (mut l, mut r) = (lo + self.size, hi + self.size);
        while l < r {
            if l & 1 == 1 {
                best = min(best, self.nodes[l]);
                l += 1;
            }
            if r & 1 == 1 {
                r -= 1;
                best = min(best, self.nodes[r]);
            }
            l /= 2;
            r /= 2;
        }
        best
    }
}

fn min(a: (f64, u32), b: (f64, u32)) -> (f64, u32) {
    if b.0 < a.0 || (b.0 == a.0 && b.1 < a.1) {
        b
    } else {
        a
    }
}

/// Largest empty open rectangle among `points` (`n × 2`, all strictly inside the square).
pub(super) fn largest_empty_rectangle(points: &[f64]) -> EmptyBox {
    let xs: Vec<f64> = points.chunks_exact(2).map(|p| p[0]).collect();
    let xs = &xs[..];
    let ys: Vec<f64> = points.chunks_exact(2).map(|p| p[1]).collect();
    // Full-width strips: the largest gap in y, times 1.
    let gap = max_gap(&ys);
    let strip = EmptyBox {
        lo: vec![0.0, gap.lo[0]],
        hi: vec![1.0, gap.hi[0]],
    };
    // Rectangles whose left side holds a point: the sweep, split in two halves by x so both
    // cores work; the left half starts with the right half's points in its tree. Rectangles
    // on x = 0: one predecessor/successor query per point. Both prune against the best area
    // found so far, starting from the strip.
    let floor = AtomicU64::new(strip.volume().to_bits());
    let mut by_x: Vec<u32> = (0..xs.len() as u32).collect();
    by_x.sort_by(|&a, &b| xs[b as usize].total_cmp(&xs[a as usize]).then(a.cmp(&b)));
    // Split between two distinct x values, so that equal x stay in one half.
    let mut split = by_x.len() * 2 / 5;
    while split > 0
        && split < by_x.len()
        && xs[by_x[split] as usize] == xs[by_x[split - 1] as usize]
    {
        split += 1;
    }
    let (right_half, left_half) = by_x.split_at(split);
    let ((a, b), c) = rayon::join(
        || {
            rayon::join(
                || left_supported(xs, &ys, &[], right_half, &floor),
                || left_supported(xs, &ys, right_half, left_half, &floor),
            )
        },
        || left_at_zero(xs, &ys),
    );
    let mut best = strip;
    for cand in [a, b, c] {
        let (cv, bv) = (cand.volume(), best.volume());
        if better(&cand, cv, &best, bv) {
            best = cand;
        }
    }
    best
}

/// The largest empty rectangle whose left side holds one of `todo`'s points strictly inside
/// its `y` range. `todo` is in decreasing `x`; `inserted` are the points right of all of
/// `todo` (to be in the tree from the start).
///
/// The tree holds exactly the points to the right of the current one. From `p` the band
/// `(b, t)` starts as `(0, 1)`; the next point to meet is the one of least `x` with `y` in the
/// band. Every maximal rectangle with `p` on its left side is met this way: its right side is
/// that point (or `x = 1`) and its top and bottom are the band at that moment.
fn left_supported(
    xs: &[f64],
    ys: &[f64],
    inserted: &[u32],
    todo: &[u32],
    floor: &AtomicU64,
) -> EmptyBox {
    let n = xs.len();
    let x_end = 1.0;
    let mut by_y: Vec<u32> = (0..n as u32).collect();
    by_y.sort_by(|&a, &b| ys[a as usize].total_cmp(&ys[b as usize]).then(a.cmp(&b)));
    let mut rank = vec![0usize; n];
    for (r, &i) in by_y.iter().enumerate() {
        rank[i as usize] = r;
    }
    let sorted_y: Vec<f64> = by_y.iter().map(|&i| ys[i as usize]).collect();
    // For each rank, the first and one-past-last rank holding the same y (ties).
    let mut first_eq = vec![0usize; n];
    let mut end_eq = vec![0usize; n];
    let mut s = 0;
    while s < n {
        let mut e = s;
        while e < n && sorted_y[e] == sorted_y[s] {
            e += 1;
        }
        for r in s..e {
            first_eq[r] = s;
            end_eq[r] = e;
        }
        s = e;
    }
    let by_x = todo;
    let mut tree = MinTree::new(n);
    for &pi in inserted {
        tree.set(rank[pi as usize], (xs[pi as usize], pi));
    }
    let mut best = EmptyBox {
        lo: vec![0.0, 0.0],
        hi: vec![0.0, 0.0],
    };
    let mut best_v: f64 = 0.0;
    let n_todo = by_x.len();
    let mut g = 0;
    while g < n_todo {
        let gx = xs[by_x[g] as usize];
        let mut end = g;
        while end < n_todo && xs[by_x[end] as usize] == gx {
            end += 1;
        }
        for &pi in &by_x[g..end] {
            let (px, py) = (xs[pi as usize], ys[pi as usize]);
            // The band (b, t) and the ranks [lo, hi) of the y values strictly inside it.
            let (mut b, mut t) = (0.0f64, 1.0f64);
            let (mut lo, mut hi) = (0usize, n);
            loop {
                // Volumes are non-negative, so their bits order like their values.
                if (x_end - px) * (t - b)
                    < best_v.max(f64::from_bits(floor.load(Ordering::Relaxed)))
                {
                    break;
                }
                let (qx, qi) = if lo < hi {
                    tree.query(lo, hi)
                } else {
                    (f64::INFINITY, u32::MAX)
                };
                let right = if qx.is_finite() { qx } else { x_end };
                let cand = EmptyBox {
                    lo: vec![px, b],
                    hi: vec![right, t],
                };
                let v = cand.volume();
                if better(&cand, v, &best, best_v) {
                    best = cand;
                    best_v = v;
                    floor.fetch_max(v.to_bits(), Ordering::Relaxed);
                }
                if !qx.is_finite() {
                    break;
                }
                let qy = ys[qi as usize];
                let qr = rank[qi as usize];
                if qy > py {
                    t = qy;
                    hi = first_eq[qr];
                } else if qy < py {
                    b = qy;
                    lo = end_eq[qr];
                } else {
                    break;
                }
            }
        }
        for &pi in &by_x[g..end] {
            tree.set(rank[pi as usize], (xs[pi as usize], pi));
        }
        g = end;
    }
    best
}

/// The largest empty rectangle with its left side on `x = 0` and its right side holding a point
/// `q` strictly inside its `y` range: its band is bounded by the nearest `y` below and above
/// `q.y` among the points strictly left of `q`. Points are visited by increasing `x`, with the
/// `y` values seen so far in an ordered set.
fn left_at_zero(xs: &[f64], ys: &[f64]) -> EmptyBox {
    let n = xs.len();
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| xs[a].total_cmp(&xs[b]).then(a.cmp(&b)));
    // y in (0, 1) is positive, so its bit pattern orders like its value.
    let mut seen: BTreeSet<(u64, usize)> = BTreeSet::new();
    let mut best = EmptyBox {
        lo: vec![0.0, 0.0],
        hi: vec![0.0, 0.0],
    };
    let mut best_v: f64 = 0.0;
    let mut g = 0;
    while g < n {
        let gx = xs[order[g]];
        let mut end = g;
        while end < n && xs[order[end]] == gx {
            end += 1;
        }
        for &q in &order[g..end] {
            let key = ys[q].to_bits();
            // A point to the left at the same height blocks every band around q.y.
            if seen.range((key, 0)..=(key, usize::MAX)).next().is_some() {
                continue;
            }
            let b = seen
                .range(..(key, 0))
                .next_back()
                .map_or(0.0, |&(k, _)| f64::from_bits(k));
            let t = seen
                .range((Excluded((key, usize::MAX)), Unbounded))
                .next()
                .map_or(1.0, |&(k, _)| f64::from_bits(k));
            let cand = EmptyBox {
                lo: vec![0.0, b],
                hi: vec![gx, t],
            };
            let v = cand.volume();
            if better(&cand, v, &best, best_v) {
                best = cand;
                best_v = v;
            }
        }
        for &q in &order[g..end] {
            seen.insert((ys[q].to_bits(), q));
        }
        g = end;
    }
    best
}
