//! Contact sheets of camera frames (what `paracosm-fuzz replay --frames` writes).

use std::path::Path;

use plotters::prelude::*;

use super::{register_font, PlotError, FAMILY};

/// Width of one tile of a contact sheet, in pixels.
const TILE_W: u32 = 240;

/// Draws a contact sheet of camera frames: at most 36 of `frames` (`(time s, image)`,
/// evenly spaced, always the last), 6 per row, each scaled to 240 pixels wide with its time
/// under it, and `title` on top. Writes PNG to `path`.
///
/// # Errors
/// [`PlotError::Draw`] when the file cannot be written.
pub fn contact_sheet(
    path: &Path,
    frames: &[(f64, image::RgbImage)],
    title: &str,
) -> Result<(), PlotError> {
    register_font();
    const COLS: usize = 6;
    const MAX: usize = 36;
    let Some((_, first)) = frames.first() else {
        return Ok(());
    };
    let step = frames.len().div_ceil(MAX).max(1);
    let mut picked: Vec<usize> = (0..frames.len()).step_by(step).collect();
    if picked.last() != Some(&(frames.len() - 1)) {
        if picked.len() == MAX {
            picked.pop();
        }
        picked.push(frames.len() - 1);
    }
    let tile_h = (f64::from(TILE_W) * f64::from(first.height()) / f64::from(first.width()))
        .round()
        .max(1.0) as u32;
    let rows = picked.len().div_ceil(COLS) as u32;
    let (label, top) = (20u32, 36u32);
    let size = (COLS as u32 * TILE_W, top + rows * (tile_h + label));
    let root = BitMapBackend::new(path, size).into_drawing_area();
    let fail = |e: &dyn std::fmt::Display| PlotError::Draw {
        path: path.to_path_buf(),
        reason: e.to_string(),
    };
    root.fill(&WHITE).map_err(|e| fail(&e))?;
    root.draw(&Text::new(title, (8, 8), (FAMILY, 18).into_font()))
        .map_err(|e| fail(&e))?;
    for (k, &i) in picked.iter().enumerate() {
        let (t, img) = &frames[i];
        let tile =
            image::imageops::resize(img, TILE_W, tile_h, image::imageops::FilterType::Triangle);
        let x = (k % COLS) as i32 * TILE_W as i32;
        let y = (top + (k / COLS) as u32 * (tile_h + label)) as i32;
        let element = plotters::element::BitMapElement::with_owned_buffer(
            (x, y),
            (TILE_W, tile_h),
            tile.into_raw(),
        )
        .ok_or_else(|| fail(&"tile buffer size"))?;
        root.draw(&element).map_err(|e| fail(&e))?;
        root.draw(&Text::new(
            format!("t = {t:.2} s"),
            (x + 6, y + tile_h as i32 + 3),
            (FAMILY, 13).into_font(),
        ))
        .map_err(|e| fail(&e))?;
    }
    root.present().map_err(|e| fail(&e))
}
