//! Box plots on a log axis (the falsification study's tests-until-failure per strategy).

use std::path::{Path, PathBuf};

use plotters::coord::Shift;
use plotters::prelude::*;

use super::{png_and_svg, register_font, DrawError, PlotError, FAMILY};

/// One panel of [`box_plot`]: a title and, per box, its label and its values.
pub type BoxPanel = (String, Vec<(String, Vec<f64>)>);

/// Box plots of positive values on a log axis, one panel per entry of `panels`, side by side
/// (each 760 × 600 pixels): per box the quartiles (linear interpolation, numpy's default), the
/// median, whiskers to the smallest and largest value, and every value as a dot beside it. Writes `stem.png` and `stem.svg` and returns their
/// paths. `y_label` names the values with their unit.
///
/// # Errors
/// [`PlotError::Draw`] when a file cannot be written.
pub fn box_plot(
    stem: &Path,
    y_label: &str,
    panels: &[BoxPanel],
) -> Result<[PathBuf; 2], PlotError> {
    register_font();
    png_and_svg(
        stem,
        (760 * panels.len().max(1) as u32, 600),
        |root| draw_boxes(root, y_label, panels),
        |root| draw_boxes(root, y_label, panels),
    )
}

fn draw_boxes<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    y_label: &str,
    panels: &[BoxPanel],
) -> Result<(), DrawError> {
    root.fill(&WHITE)?;
    let areas = root.split_evenly((1, panels.len().max(1)));
    let top = panels
        .iter()
        .flat_map(|(_, boxes)| boxes.iter().flat_map(|(_, v)| v.iter().copied()))
        .fold(10.0f64, f64::max);
    let blue = RGBColor(31, 119, 180);
    for ((title, boxes), area) in panels.iter().zip(&areas) {
        let n = boxes.len().max(1);
        let mut chart = ChartBuilder::on(area)
            .caption(title, (FAMILY, 20))
            .margin(12)
            .x_label_area_size(50)
            .y_label_area_size(60)
            .build_cartesian_2d(-0.5f64..n as f64 - 0.5, (0.8f64..top * 1.5).log_scale())?;
        let label_of = |x: &f64| {
            let i = x.round();
            match boxes.get(i as usize) {
                Some((l, _)) if (x - i).abs() < 1e-6 && i >= 0.0 => l.clone(),
                _ => String::new(),
            }
        };
        chart
            .configure_mesh()
            .y_desc(y_label)
            .x_labels(n)
            .x_label_formatter(&label_of)
            .y_label_formatter(&|v| format!("{v}"))
            .label_style((FAMILY, 13))
            .axis_desc_style((FAMILY, 16))
            .light_line_style(WHITE.mix(0.0))
            .disable_x_mesh()
            .draw()?;
        for (i, (_, values)) in boxes.iter().enumerate() {
            let mut v = values.clone();
            v.sort_by(f64::total_cmp);
            let Some((&lo, &hi)) = v.first().zip(v.last()) else {
                continue;
            };
            let q = |p: f64| {
                // Linear interpolation between order statistics (type 7, as numpy's default).
                let h = (v.len() - 1) as f64 * p;
                let (a, b) = (v[h.floor() as usize], v[h.ceil() as usize]);
                a + (h - h.floor()) * (b - a)
            };
            let (q1, med, q3) = (q(0.25), q(0.5), q(0.75));
            let x = i as f64;
            let line = |pts: Vec<(f64, f64)>| PathElement::new(pts, blue.stroke_width(2));
            let mut shapes = vec![
                line(vec![
                    (x - 0.2, q1),
                    (x + 0.2, q1),
                    (x + 0.2, q3),
                    (x - 0.2, q3),
                    (x - 0.2, q1),
                ]),
                line(vec![(x - 0.2, med), (x + 0.2, med)]),
                line(vec![(x, q3), (x, hi)]),
                line(vec![(x, q1), (x, lo)]),
                line(vec![(x - 0.1, hi), (x + 0.1, hi)]),
                line(vec![(x - 0.1, lo), (x + 0.1, lo)]),
            ];
            chart.draw_series(shapes.drain(..))?;
            chart.draw_series(
                v.iter()
                    .map(|&y| Circle::new((x + 0.28, y), 2, BLACK.mix(0.35).filled())),
            )?;
        }
    }
    root.present()?;
    Ok(())
}
