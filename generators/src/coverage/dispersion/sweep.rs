//! Exact largest empty box for `d >= 2` by a sweep over the first axis.

use std::sync::atomic::{AtomicU64, Ordering};

use rayon::prelude::*;

use super::{better, max_gap, plane, EmptyBox};

/// Largest empty open box among `points` (`n × d`, all strictly inside the cube).
///
/// Decomposition on axis 0: a maximal box's lower face on that axis holds a point (found by
/// [`lower_supported`]), or lies on `0` with the upper face on a point (the same sweep on the
/// mirrored set), or the box spans `[0, 1]` on axis 0 (the largest empty box of the points
/// projected on the other axes, times 1).
pub(super) fn largest_empty_box(points: &[f64], d: usize) -> EmptyBox {
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
        _ => largest_empty_box(&projected, d - 1),
    };
    let span = EmptyBox {
        lo: std::iter::once(0.0).chain(span.lo).collect(),
        hi: std::iter::once(1.0).chain(span.hi).collect(),
    };
    let floor = AtomicU64::new(span.volume().to_bits());
    // Mirror by negation (exact in floating point); the mirrored axis ends at 0.
    let right = lower_supported(points, d, n, 1.0, &floor, usize::MAX);
    let left = lower_supported(&mirrored, d, n, 0.0, &floor, usize::MAX);
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
    x_end: f64,
    floor: &AtomicU64,
    max_steps: usize,
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
        .map(|k| {
            let p = pt(order[k]);
            let px = p[0];
            let mut boxes: Vec<EmptyBox> = vec![EmptyBox::unit(d - 1)];
            let mut best: Option<(EmptyBox, f64)> = None;
            let consider = |right: f64, cross: &EmptyBox, best: &mut Option<(EmptyBox, f64)>| {
                let v = (right - px) * cross.volume();
                if v < f64::from_bits(floor.load(Ordering::Relaxed)) {
                    return;
                }
                let cand = EmptyBox {
                    lo: std::iter::once(px)
                        .chain(cross.lo.iter().copied())
                        .collect(),
                    hi: std::iter::once(right)
                        .chain(cross.hi.iter().copied())
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
                for b in &boxes {
                    consider(gx, b, &mut best);
                }
                let mut end = j;
                while end < n && pt(order[end])[0] == gx {
                    split(&mut boxes, &pt(order[end])[1..], &p[1..]);
                    end += 1;
                }
                let f = f64::from_bits(floor.load(Ordering::Relaxed));
                boxes.retain(|b| (x_end - px) * b.volume() >= f);
                if boxes.len() > max_boxes {
                    boxes.sort_by(|a, b| b.volume().total_cmp(&a.volume()));
                    boxes.truncate(max_boxes);
                }
                j = end;
            }
            // Boxes reach the end of the axis only if the walk was not cut short.
            if j >= n {
                for b in &boxes {
                    consider(x_end, b, &mut best);
                }
            }
            best
        })
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

/// Splits every box containing `s` strictly into its parts below and above `s` on each axis
/// that still contain `p` strictly, then drops boxes inside other boxes.
fn split(boxes: &mut Vec<EmptyBox>, s: &[f64], p: &[f64]) {
    let mut out: Vec<EmptyBox> = Vec::with_capacity(boxes.len() + 4);
    for b in boxes.drain(..) {
        if !b.contains_strictly(s) {
            out.push(b);
            continue;
        }
        for axis in 0..s.len() {
            if p[axis] < s[axis] {
                let mut c = b.clone();
                c.hi[axis] = s[axis];
                out.push(c);
            } else if p[axis] > s[axis] {
                let mut c = b.clone();
                c.lo[axis] = s[axis];
                out.push(c);
            }
        }
    }
    let inside = |a: &EmptyBox, b: &EmptyBox| {
        a.lo.iter().zip(&b.lo).all(|(x, y)| x >= y) && a.hi.iter().zip(&b.hi).all(|(x, y)| x <= y)
    };
    let mut keep = vec![true; out.len()];
    for i in 0..out.len() {
        for j in 0..out.len() {
            // Of two equal boxes keep the first.
            if i != j && keep[j] && inside(&out[i], &out[j]) && (out[i] != out[j] || j < i) {
                keep[i] = false;
                break;
            }
        }
    }
    let mut k = keep.iter();
    out.retain(|_| *k.next().unwrap_or(&false));
    *boxes = out;
}

/// A lower bound for the bracket: the sweep of [`largest_empty_box`] with each supporting
/// point's walk cut after `max_steps` point groups. Every box it reports is empty; the walk
/// just stops looking.
pub(super) fn capped_lower_bound(points: &[f64], d: usize, max_steps: usize) -> Option<EmptyBox> {
    let n = points.len() / d;
    let floor = AtomicU64::new(0f64.to_bits());
    lower_supported(points, d, n, 1.0, &floor, max_steps)
}
