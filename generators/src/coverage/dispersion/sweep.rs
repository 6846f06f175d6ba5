//! Exact largest empty box for `d >= 2` by a sweep over the first axis.

use std::sync::atomic::{AtomicU64, Ordering};

use rayon::prelude::*;

use super::{better, max_gap, plane, EmptyBox};

/// Largest empty open box among `points` (`n × d`, all strictly inside the cube).
///
/// Decomposition on axis 0: a maximal box's lower face on that axis holds a point (found by
/// [`lower_supported`]), or lies on `0` with the upper face on a point (the same sweep on the
/// mirrored set), or the box spans `[0, 1]` on axis 0 (the largest empty box of the points
/// projected on the other axes, times 1). `progress` hears of each supporting point walked,
/// `2n` in all (the projection's own sweep reports nothing).
pub(super) fn largest_empty_box(
    points: &[f64],
    d: usize,
    progress: super::super::Progress<'_>,
) -> EmptyBox {
    let n = points.len() / d;
    let mirrored: Vec<f64> = points
        .chunks_exact(d)
        .flat_map(|p| std::iter::once(-p[0]).chain(p[1..].iter().copied()))
        .collect();
    let projected: Vec<f64> = points
        .chunks_exact(d)
        .flat_map(|p| p[1..].iter().copied())
        .collect();
    let span = match d - 1 {
        1 => max_gap(&projected),
        2 => plane::largest_empty_rectangle(&projected),
        _ => largest_empty_box(&projected, d - 1, &super::super::no_progress),
    };
    let span = EmptyBox {
        lo: std::iter::once(0.0).chain(span.lo).collect(),
        hi: std::iter::once(1.0).chain(span.hi).collect(),
    };
    let floor = AtomicU64::new(span.volume().to_bits());
    // Mirror by negation (exact in floating point); the mirrored axis ends at 0.
    let walked = AtomicU64::new(0);
    let total = 2 * n as u64;
    progress(0, total);
    let step = || progress(walked.fetch_add(1, Ordering::Relaxed) + 1, total);
    let right = lower_supported(points, d, n, (1.0, &floor), usize::MAX, &step);
    let left = lower_supported(&mirrored, d, n, (0.0, &floor), usize::MAX, &step);
    let left = left.map(|mut b| {
        let (lo, hi) = (-b.hi[0], -b.lo[0]);
        b.lo[0] = lo;
        b.hi[0] = hi;
        b
    });
    let mut best = span;
    for cand in [right, left].into_iter().flatten() {
        let (cv, bv) = (cand.volume(), best.volume());
        if better(&cand, cv, &best, bv) {
            best = cand;
        }
    }
    best
}

/// The largest empty box whose lower face on axis 0 holds a point strictly inside the box's
/// cross-section (axis 0 ends at `x_end`: 1, or 0 for the mirrored set), if any beats the shared
/// `floor` (an `f64` volume stored as bits; volumes are
/// non-negative, so their bit patterns order like the values).
///
/// For each supporting point `p` the sweep walks the points right of `p` in `x` order and
/// keeps every maximal empty `(d-1)`-box of the cross-section that contains `p`'s projection.
/// Adding a point splits each box containing it into the parts on either side along every
/// axis (the parts still containing `p`); every empty box is inside one of the kept boxes, so
/// the largest box with right face at each step is among `width × kept`. Boxes that cannot
/// beat the floor even at full width are dropped, and the walk ends when none is left.
fn lower_supported(
    points: &[f64],
    d: usize,
    n: usize,
    (x_end, floor): (f64, &AtomicU64),
    max_steps: usize,
    walked: &(dyn Fn() + Sync),
) -> Option<EmptyBox> {
    // A capped walk also keeps only the largest boxes, so that high dimensions stay cheap.
    let max_boxes = if max_steps == usize::MAX {
        usize::MAX
    } else {
        16
    };
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| points[a * d].total_cmp(&points[b * d]).then(a.cmp(&b)));
    let pt = |i: usize| &points[i * d..(i + 1) * d];
    let found: Vec<Option<(EmptyBox, f64)>> = (0..n)
        .into_par_iter()
        .map_init(
            || (Boxes::new(d - 1), Boxes::new(d - 1), Vec::new()),
            |(boxes, spare, keep), k| {
                let p = pt(order[k]);
                let px = p[0];
                boxes.clear();
                boxes.push_unit();
                let mut best: Option<(EmptyBox, f64)> = None;
                let consider =
                    |right: f64, boxes: &Boxes, b: usize, best: &mut Option<(EmptyBox, f64)>| {
                        let v = (right - px) * boxes.volume(b);
                        if v < f64::from_bits(floor.load(Ordering::Relaxed)) {
                            return;
                        }
                        let cand = EmptyBox {
                            lo: std::iter::once(px)
                                .chain(boxes.lo(b).iter().copied())
                                .collect(),
                            hi: std::iter::once(right)
                                .chain(boxes.hi(b).iter().copied())
                                .collect(),
                        };
                        let v = cand.volume();
                        let wins = match best {
                            Some((b, bv)) => better(&cand, v, b, *bv),
                            None => true,
                        };
                        if wins {
                            floor.fetch_max(v.to_bits(), Ordering::Relaxed);
                            *best = Some((cand, v));
                        }
                    };
                // Skip points on p's own plane: they lie on the box's face.
                let mut j = k + 1;
                while j < n && pt(order[j])[0] == px {
                    j += 1;
                }
                let mut steps = 0;
                while j < n && !boxes.is_empty() && steps < max_steps {
                    steps += 1;
                    let gx = pt(order[j])[0];
                    for b in 0..boxes.len() {
                        consider(gx, boxes, b, &mut best);
                    }
                    let mut end = j;
                    while end < n && pt(order[end])[0] == gx {
                        split(boxes, spare, keep, &pt(order[end])[1..], &p[1..]);
                        end += 1;
                    }
                    let f = f64::from_bits(floor.load(Ordering::Relaxed));
                    boxes.retain(|v| (x_end - px) * v >= f);
                    if boxes.len() > max_boxes {
                        boxes.keep_largest(max_boxes, spare);
                    }
                    j = end;
                }
                // Boxes reach the end of the axis only if the walk was not cut short.
                if j >= n {
                    for b in 0..boxes.len() {
                        consider(x_end, boxes, b, &mut best);
                    }
                }
                walked();
                best
            },
        )
        .collect();
    let mut best: Option<(EmptyBox, f64)> = None;
    for (cand, v) in found.into_iter().flatten() {
        let wins = match &best {
            Some((b, bv)) => better(&cand, v, b, *bv),
            None => true,
        };
        if wins {
            best = Some((cand, v));
        }
    }
    best.map(|(b, _)| b)
}

/// The open `k`-boxes of a sweep's cross-section, stored flat: box `i` is
/// `data[2ki..2ki + k]` (lower corner) then `data[2ki + k..2k(i + 1)]` (upper corner), with
/// its volume `Π (hi − lo)` (in axis order, as [`EmptyBox::volume`]) in `volumes[i]`. Flat
/// storage keeps the sweep from allocating two vectors per box it splits off.
struct Boxes {
    k: usize,
    data: Vec<f64>,
    volumes: Vec<f64>,
}

impl Boxes {
    fn new(k: usize) -> Self {
        Boxes {
            k,
            data: Vec::new(),
            volumes: Vec::new(),
        }
    }

    fn len(&self) -> usize {
        self.volumes.len()
    }

    fn is_empty(&self) -> bool {
        self.volumes.is_empty()
    }

    fn clear(&mut self) {
        self.data.clear();
        self.volumes.clear();
    }

    fn lo(&self, i: usize) -> &[f64] {
        &self.data[2 * self.k * i..2 * self.k * i + self.k]
    }

    fn hi(&self, i: usize) -> &[f64] {
        &self.data[2 * self.k * i + self.k..2 * self.k * (i + 1)]
    }

    fn corners(&self, i: usize) -> &[f64] {
        &self.data[2 * self.k * i..2 * self.k * (i + 1)]
    }

    fn volume(&self, i: usize) -> f64 {
        self.volumes[i]
    }

    /// Appends the unit box `(0, 1)^k`.
    fn push_unit(&mut self) {
        self.data.extend(std::iter::repeat_n(0.0, self.k));
        self.data.extend(std::iter::repeat_n(1.0, self.k));
        self.volumes.push(1.0);
    }

    /// Appends box `i` of `from`, with its upper (`upper`) or lower corner on `axis` moved
    /// to `at`; `axis = None` copies it as it is.
    fn push_from(&mut self, from: &Boxes, i: usize, cut: Option<(usize, bool, f64)>) {
        let start = self.data.len();
        self.data.extend_from_slice(from.corners(i));
        let volume = match cut {
            None => from.volume(i),
            Some((axis, upper, at)) => {
                self.data[start + axis + if upper { self.k } else { 0 }] = at;
                let c = &self.data[start..];
                c[..self.k]
                    .iter()
                    .zip(&c[self.k..])
                    .map(|(l, h)| h - l)
                    .product()
            }
        };
        self.volumes.push(volume);
    }

    /// Keeps the boxes whose volume passes `keep`, in order.
    fn retain(&mut self, keep: impl Fn(f64) -> bool) {
        let w = 2 * self.k;
        let mut kept = 0;
        for i in 0..self.len() {
            if keep(self.volumes[i]) {
                self.data.copy_within(w * i..w * (i + 1), w * kept);
                self.volumes[kept] = self.volumes[i];
                kept += 1;
            }
        }
        self.data.truncate(w * kept);
        self.volumes.truncate(kept);
    }

    /// Keeps the `m` largest boxes, largest first (a stable sort: equal volumes keep their
    /// order).
    fn keep_largest(&mut self, m: usize, spare: &mut Boxes) {
        let mut by_volume: Vec<usize> = (0..self.len()).collect();
        by_volume.sort_by(|&a, &b| self.volumes[b].total_cmp(&self.volumes[a]));
        spare.clear();
        for &i in by_volume.iter().take(m) {
            spare.push_from(self, i, None);
        }
        std::mem::swap(self, spare);
    }
}

/// Splits every box containing `s` strictly into its parts below and above `s` on each axis
/// that still contain `p` strictly, then drops boxes inside other boxes (of two equal boxes,
/// the later one). `spare` and `keep` are scratch space.
///
/// Only a part split off can be inside another box. The boxes come in with none inside
/// another (the sweep starts with one box, and every split and filter keeps that so), and a
/// box `u` left whole cannot be inside a part `c` of a box `b`: `c` lies inside `b` and is not
/// `b` (its new face cuts `b` strictly), so `u` would be inside `b`. So the parts are checked
/// against every box, and the boxes left whole are kept without a check.
fn split(boxes: &mut Boxes, spare: &mut Boxes, keep: &mut Vec<bool>, s: &[f64], p: &[f64]) {
    let k = boxes.k;
    spare.clear();
    // Here `keep` first marks the parts split off.
    keep.clear();
    for b in 0..boxes.len() {
        let (lo, hi) = (boxes.lo(b), boxes.hi(b));
        let contains = s
            .iter()
            .zip(lo.iter().zip(hi))
            .all(|(x, (l, h))| l < x && x < h);
        if !contains {
            spare.push_from(boxes, b, None);
            keep.push(false);
            continue;
        }
        for axis in 0..k {
            if p[axis] < s[axis] {
                spare.push_from(boxes, b, Some((axis, true, s[axis])));
                keep.push(true);
            } else if p[axis] > s[axis] {
                spare.push_from(boxes, b, Some((axis, false, s[axis])));
                keep.push(true);
            }
        }
    }
    let out = &*spare;
    let inside = |a: usize, b: usize| {
        out.lo(a).iter().zip(out.lo(b)).all(|(x, y)| x >= y)
            && out.hi(a).iter().zip(out.hi(b)).all(|(x, y)| x <= y)
    };
    let parts: Vec<usize> = (0..out.len()).filter(|&i| keep[i]).collect();
    keep.iter_mut().for_each(|kept| *kept = true);
    for i in parts {
        for j in 0..out.len() {
            // Of two equal boxes keep the first.
            if i != j && keep[j] && inside(i, j) && (out.corners(i) != out.corners(j) || j < i) {
                keep[i] = false;
                break;
            }
        }
    }
    boxes.clear();
    for (i, &kept) in keep.iter().enumerate() {
        if kept {
            boxes.push_from(out, i, None);
        }
    }
}

/// A lower bound for the bracket: the sweep of [`largest_empty_box`] with each supporting
/// point's walk cut after `max_steps` point groups. Every box it reports is empty; the walk
/// just stops looking.
pub(super) fn capped_lower_bound(points: &[f64], d: usize, max_steps: usize) -> Option<EmptyBox> {
    let n = points.len() / d;
    let floor = AtomicU64::new(0f64.to_bits());
    lower_supported(points, d, n, (1.0, &floor), max_steps, &|| {})
}
