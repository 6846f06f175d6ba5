//! Maps far from the origin, moved to it before they are baked.
//!
//! The `xodr` crate evaluates lane points in `f32`, and the physics (rapier) is `f32`: at
//! x = 10^8 m an `f32` resolves 8 m. Projected maps (UTM, national grids) routinely lie
//! 10^5 to 10^7 m from their origin. A map whose extent reaches past [`RESOLVED_M`] is
//! therefore shifted, in the document's text and before anything reads it, by the centre of
//! its extent rounded to a metre; [`super::RoadMap::origin_m`] keeps the shift, so exports
//! write positions in the file's own coordinates. A map that is itself wider than
//! `2 × RESOLVED_M` is refused.

use roxmltree::{Document, Node};

use super::{MapError, Reader};

/// The largest `|x|` or `|y|`, m, at which an `f32` resolves 1 cm (its spacing at
/// 2^16 m is 2^-7 m = 7.8 mm).
pub const RESOLVED_M: f64 = 65_536.0;

/// The shift to apply to a map, OpenDRIVE `[x, y]` m, or `None` when it lies within
/// [`RESOLVED_M`] of the origin already.
///
/// # Errors
/// A map whose geometry spans more than `2 × RESOLVED_M` on an axis, naming the span.
pub(super) fn shift(r: &Reader, root: Node) -> Result<Option<[f64; 2]>, MapError> {
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    for g in root.descendants().filter(|n| n.has_tag_name("geometry")) {
        let num = |k: &str| g.attribute(k).and_then(|v| v.trim().parse::<f64>().ok());
        let (Some(x), Some(y)) = (num("x"), num("y")) else {
            continue;
        };
        // A record stays within its length of its start.
        let reach = num("length").unwrap_or(0.0).max(0.0);
        for (k, v) in [x, y].into_iter().enumerate() {
            lo[k] = lo[k].min(v - reach);
            hi[k] = hi[k].max(v + reach);
        }
    }
    if !lo[0].is_finite() {
        return Ok(None);
    }
    let far = (0..2).any(|k| lo[k] < -RESOLVED_M || hi[k] > RESOLVED_M);
    if !far {
        return Ok(None);
    }
    let centre = [
        ((lo[0] + hi[0]) / 2.0).round(),
        ((lo[1] + hi[1]) / 2.0).round(),
    ];
    let span = [hi[0] - lo[0], hi[1] - lo[1]];
    if span.iter().any(|s| s / 2.0 > RESOLVED_M - 1.0) {
        return Err(r.error(
            None,
            format!(
                "the map spans {:.1} km × {:.1} km; the f32 physics resolves 1 cm only within {:.1} km of the origin, so a map is at most {:.1} km across",
                span[0] / 1e3,
                span[1] / 1e3,
                RESOLVED_M / 1e3,
                2.0 * RESOLVED_M / 1e3
            ),
        ));
    }
    Ok(Some(centre))
}

/// `text` with every `<geometry>`'s `x` and `y` moved by `-shift`: the same document,
/// byte for byte elsewhere, so lines and columns stay those of the file.
pub(super) fn apply(doc: &Document, text: &str, shift: [f64; 2]) -> String {
    let mut edits: Vec<(std::ops::Range<usize>, String)> = Vec::new();
    for g in doc.descendants().filter(|n| n.has_tag_name("geometry")) {
        for (k, name) in ["x", "y"].into_iter().enumerate() {
            let Some(a) = g.attribute_node(name) else {
                continue;
            };
            let Ok(v) = a.value().trim().parse::<f64>() else {
                continue;
            };
            edits.push((a.range_value(), format!("{}", v - shift[k])));
        }
    }
    edits.sort_by_key(|(r, _)| r.start);
    let mut out = String::with_capacity(text.len());
    let mut at = 0;
    for (range, value) in edits {
        out.push_str(&text[at..range.start]);
        out.push_str(&value);
        at = range.end;
    }
    out.push_str(&text[at..]);
    out
}
