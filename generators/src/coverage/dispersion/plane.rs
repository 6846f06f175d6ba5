//! Exact largest empty rectangle in the unit square (`d = 2`).

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
    let ys: Vec<f64> = points.chunks_exact(2).map(|p| p[1]).collect();
    // Full-width strips: the largest gap in y, times 1.
    let gap = max_gap(&ys);
    let strip = EmptyBox {
        lo: vec![0.0, gap.lo[0]],
        hi: vec![1.0, gap.hi[0]],
    };
    // Mirror by negation, which is exact in floating point (1 - x is not): the mirrored
    // points lie in (-1, 0) and their right end is 0.
    let mirrored: Vec<f64> = xs.iter().map(|x| -x).collect();
    // Both sweeps prune against the best area either has found, starting from the strip.
    let floor = AtomicU64::new(strip.volume().to_bits());
    let (right, left) = rayon::join(
        || left_supported(&xs, &ys, 1.0, &floor),
        || left_supported(&mirrored, &ys, 0.0, &floor),
    );
    let left = EmptyBox {
        lo: vec![-left.hi[0], left.lo[1]],
        hi: vec![-left.lo[0], left.hi[1]],
    };
    let mut best = strip;
    for cand in [right, left] {
        let (cv, bv) = (cand.volume(), best.volume());
        if better(&cand, cv, &best, bv) {
            best = cand;
        }
    }
    best
}

/// The largest empty rectangle whose left side holds a point strictly inside its `y` range;
/// `x_end` is the right end of the `x` range (1, or 0 for the mirrored set).
///
/// Points are visited by decreasing `x`; the tree holds exactly the points to the right of
/// the current one. From `p` the band `(b, t)` starts as `(0, 1)`; the next point to meet is
/// the one of least `x` with `y` in the band. Every maximal rectangle with `p` on its left
/// side is met this way: its right side is that point (or `x = 1`) and its top and bottom are
/// the band at that moment.
fn left_supported(xs: &[f64], ys: &[f64], x_end: f64, floor: &AtomicU64) -> EmptyBox {
    let n = xs.len();
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
    let mut by_x: Vec<u32> = (0..n as u32).collect();
    by_x.sort_by(|&a, &b| xs[b as usize].total_cmp(&xs[a as usize]).then(a.cmp(&b)));

    let mut tree = MinTree::new(n);
    let mut best = EmptyBox {
        lo: vec![0.0, 0.0],
        hi: vec![0.0, 0.0],
    };
    let mut best_v: f64 = 0.0;
    let mut g = 0;
    while g < n {
        let gx = xs[by_x[g] as usize];
        let mut end = g;
        while end < n && xs[by_x[end] as usize] == gx {
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
