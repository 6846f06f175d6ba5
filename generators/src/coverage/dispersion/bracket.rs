//! A certified bracket on the dispersion when exact enumeration is too costly.

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use rand::seq::SliceRandom;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::{better, DispersionOptions, EmptyBox};

/// The bracket's result.
pub(super) struct Bracket {
    pub(super) witness: EmptyBox,
    pub(super) upper: f64,
    pub(super) regions: usize,
}

/// A set of boxes: `lo_i ∈ [a_i, b_i]`, `hi_i ∈ [c_i, e_i]`, with the points that lie strictly
/// inside its union box `(a, e)` (the only ones that can lie inside any of its boxes).
struct Region {
    a: Vec<f64>,
    b: Vec<f64>,
    c: Vec<f64>,
    e: Vec<f64>,
    points: Vec<u32>,
    /// No box of the region that is empty is larger: see [`region_bound`].
    bound: f64,
}

impl PartialEq for Region {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}
impl Eq for Region {}
impl PartialOrd for Region {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Region {
    fn cmp(&self, other: &Self) -> Ordering {
        // Max-heap on the bound; ties broken by corners so the order is total and repeatable.
        self.bound
            .total_cmp(&other.bound)
            .then_with(|| cmp_slices(&other.a, &self.a))
            .then_with(|| cmp_slices(&other.e, &self.e))
            .then_with(|| cmp_slices(&other.b, &self.b))
            .then_with(|| cmp_slices(&other.c, &self.c))
    }
}

fn cmp_slices(x: &[f64], y: &[f64]) -> Ordering {
    x.iter()
        .zip(y)
        .map(|(p, q)| p.total_cmp(q))
        .find(|o| o.is_ne())
        .unwrap_or(Ordering::Equal)
}

/// An upper bound on the volume of every empty box of region `r`.
///
/// Every box `B` of the region lies inside the union box `U = (a, e)` and contains the
/// smallest box `I = (b, c)`. To contain no point `p` of `U`, `B` must leave `p` out along some
/// axis `j`: either `p_j <= lo_j <= b_j`, and then `B` lies in `U` with `a_j` raised to `p_j`,
/// or `p_j >= hi_j >= c_j`, and then `B` lies in `U` with `e_j` lowered to `p_j`. So
/// `vol(B) <= max_j vol(U clipped at p_j)` for every such `p`, and the bound is the least of
/// these over the points (and `vol(U)` itself). Proof by this case split; `O(|points| · d)`.
fn region_bound(r: &Region, points: &[f64], d: usize) -> f64 {
    let widths: Vec<f64> = (0..d).map(|k| (r.e[k] - r.a[k]).max(0.0)).collect();
    let vol_u: f64 = widths.iter().product();
    if vol_u <= 0.0 {
        return 0.0;
    }
    let mut bound = vol_u;
    for &i in &r.points {
        let p = &points[i as usize * d..(i as usize + 1) * d];
        let mut best_clip: f64 = 0.0;
        for k in 0..d {
            if p[k] <= r.b[k] {
                best_clip = best_clip.max(vol_u * (r.e[k] - p[k]) / widths[k]);
            }
            if p[k] >= r.c[k] {
                best_clip = best_clip.max(vol_u * (p[k] - r.a[k]) / widths[k]);
            }
        }
        bound = bound.min(best_clip);
    }
    bound
}

/// Grows the empty box `b` to a maximal empty box, axis by axis in `axes` order: on each axis
/// the faces move out to the nearest point that lies strictly inside the box on every other
/// axis (or to the cube's boundary).
pub(super) fn grow(points: &[f64], d: usize, mut b: EmptyBox, axes: &[usize]) -> EmptyBox {
    for &j in axes {
        let (mut lo, mut hi) = (0.0f64, 1.0f64);
        for p in points.chunks_exact(d) {
            let blocks = (0..d).all(|k| k == j || (b.lo[k] < p[k] && p[k] < b.hi[k]));
            if blocks {
                if p[j] <= b.lo[j] {
                    lo = lo.max(p[j]);
                }
                if p[j] >= b.hi[j] {
                    hi = hi.min(p[j]);
                }
            }
        }
        b.lo[j] = lo;
        b.hi[j] = hi;
    }
    b
}

/// Lower bound by greedy maximal boxes from random starts, then a branch and bound over the
/// box corners for a proven upper bound (see [`super::dispersion`]).
pub(super) fn bracket(points: &[f64], d: usize, options: &DispersionOptions) -> Bracket {
    let n = points.len() / d;
    let (mut best, mut best_v) = lower_bound(points, d, options);
    let mut heap = BinaryHeap::new();
    heap.push(Region {
        a: vec![0.0; d],
        b: vec![1.0; d],
        c: vec![0.0; d],
        e: vec![1.0; d],
        points: (0..n as u32).collect(),
        bound: 1.0,
    });
    let identity: Vec<usize> = (0..d).collect();
    let mut regions = 0;
    while regions < options.bracket_regions {
        let Some(r) = heap.pop() else { break };
        if r.bound <= best_v {
            heap.push(r);
            break;
        }
        regions += 1;
        let pt = |i: u32| &points[i as usize * d..(i as usize + 1) * d];
        // The smallest box of the region: if a point is strictly inside, every box is blocked.
        let blocked = r.points.iter().any(|&i| {
            let p = pt(i);
            (0..d).all(|k| r.b[k] < p[k] && p[k] < r.c[k])
        });
        if blocked {
            continue;
        }
        if (0..d).all(|k| r.b[k] < r.c[k]) {
            // The smallest box is empty: grow it for a lower bound.
            let seed = EmptyBox {
                lo: r.b.clone(),
                hi: r.c.clone(),
            };
            let cand = grow(points, d, seed, &identity);
            let v = cand.volume();
            if better(&cand, v, &best, best_v) {
                best = cand;
                best_v = v;
            }
        }
        for child in split(&r, points, d) {
            if child.bound <= best_v {
                continue;
            }
            heap.push(child);
        }
    }
    let upper = heap.peek().map_or(best_v, |r| r.bound.max(best_v));
    Bracket {
        witness: best,
        upper,
        regions,
    }
}

/// The largest empty box found by greedy growth from random starts (seeded by
/// `options.seed`), and by the exact sweep cut short, with its volume.
fn lower_bound(points: &[f64], d: usize, options: &DispersionOptions) -> (EmptyBox, f64) {
    let mut rng = ChaCha8Rng::seed_from_u64(options.seed);
    let mut best = EmptyBox::unit(d);
    let mut best_v = -1.0;
    let mut axes: Vec<usize> = (0..d).collect();
    for _ in 0..options.greedy_starts_per_dim * d {
        let c: Vec<f64> = (0..d).map(|_| rng.random::<f64>()).collect();
        axes.shuffle(&mut rng);
        let start = EmptyBox {
            lo: c.clone(),
            hi: c,
        };
        let cand = grow(points, d, start, &axes);
        let v = cand.volume();
        if better(&cand, v, &best, best_v) {
            best = cand;
            best_v = v;
        }
    }

    // The exact sweep, each walk cut short, usually finds the largest box or close to it.
    if let Some(cand) = super::sweep::capped_lower_bound(points, d, 32) {
        let v = cand.volume();
        if better(&cand, v, &best, best_v) {
            best = cand;
            best_v = v;
        }
    }
    (best, best_v)
}

/// The two halves of region `r` split at the middle of its widest corner interval, each with
/// its points and bound; none when every interval is a point (a single box).
fn split(r: &Region, points: &[f64], d: usize) -> Vec<Region> {
    let (mut axis, mut upper_face, mut width) = (0, false, -1.0);
    for k in 0..d {
        if r.b[k] - r.a[k] > width {
            (axis, upper_face, width) = (k, false, r.b[k] - r.a[k]);
        }
        if r.e[k] - r.c[k] > width {
            (axis, upper_face, width) = (k, true, r.e[k] - r.c[k]);
        }
    }
    if width <= 0.0 {
        return Vec::new(); // a single box, already handled by the caller
    }
    let pt = |i: u32| &points[i as usize * d..(i as usize + 1) * d];
    (0..2)
        .map(|half| {
            let mut child = Region {
                a: r.a.clone(),
                b: r.b.clone(),
                c: r.c.clone(),
                e: r.e.clone(),
                points: Vec::new(),
                bound: 0.0,
            };
            if upper_face {
                let mid = 0.5 * (r.c[axis] + r.e[axis]);
                if half == 0 {
                    child.e[axis] = mid;
                } else {
                    child.c[axis] = mid;
                }
            } else {
                let mid = 0.5 * (r.a[axis] + r.b[axis]);
                if half == 0 {
                    child.b[axis] = mid;
                } else {
                    child.a[axis] = mid;
                }
            }
            child.points = r
                .points
                .iter()
                .copied()
                .filter(|&i| {
                    let p = pt(i);
                    (0..d).all(|k| child.a[k] < p[k] && p[k] < child.e[k])
                })
                .collect();
            child.bound = region_bound(&child, points, d);
            child
        })
        .collect()
}
