//! Plots: the failure map (paper Figure 9), as PNG and SVG, drawn with `plotters` and a
//! bundled font so that it renders on machines without system fonts.

use std::path::{Path, PathBuf};
use std::sync::Once;

use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;
use thiserror::Error;

use paracosm_generators::{Domain, ParamSpace};

use crate::record::{RunRecord, Status};

/// DejaVu Sans (Bitstream Vera license, see `assets/fonts/LICENSE`), bundled so plots draw on
/// a machine with no fonts installed.
static FONT: &[u8] = include_bytes!("../assets/fonts/DejaVuSans.ttf");
const FAMILY: &str = "sans-serif";

/// Errors drawing a plot.
#[derive(Debug, Error)]
pub enum PlotError {
    /// An axis parameter is not a continuous parameter of the space.
    #[error("cannot plot `{0}`: it is not a continuous parameter of the scenario")]
    NotAnAxis(String),
    /// The drawing backend failed (usually: the file cannot be written).
    #[error("cannot draw `{path}`: {reason}")]
    Draw {
        /// The file being drawn.
        path: PathBuf,
        /// The backend's reason.
        reason: String,
    },
}

fn register_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // The bundled file is a valid TrueType font; a failure would only lose the labels.
        let _ = plotters::style::register_font(FAMILY, FontStyle::Normal, FONT);
    });
}

/// The `[lo, hi]` range and axis label of continuous parameter `name`.
fn axis(space: &ParamSpace, name: &str) -> Result<(f64, f64, String), PlotError> {
    match space.param(name) {
        Some(p) => match p.domain {
            Domain::Interval { lo, hi } => Ok((lo, hi, p.label())),
            Domain::Levels(_) => Err(PlotError::NotAnAxis(name.to_owned())),
        },
        None => Err(PlotError::NotAnAxis(name.to_owned())),
    }
}

/// A chart over the continuous parameters `axes = [x, y]` with `title`, axis labels with
/// units, and light grid lines when `grid`.
fn chart_on<'a, DB: DrawingBackend>(
    area: &'a DrawingArea<DB, Shift>,
    space: &ParamSpace,
    axes: &[String; 2],
    title: &str,
    grid: bool,
) -> Result<ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>, String> {
    let (x_lo, x_hi, x_label) = axis(space, &axes[0]).map_err(|e| e.to_string())?;
    let (y_lo, y_hi, y_label) = axis(space, &axes[1]).map_err(|e| e.to_string())?;
    let mut chart = ChartBuilder::on(area)
        .caption(title, (FAMILY, 20))
        .margin(12)
        .x_label_area_size(45)
        .y_label_area_size(55)
        .build_cartesian_2d(x_lo..x_hi, y_lo..y_hi)
        .map_err(|e| e.to_string())?;
    let mut mesh = chart.configure_mesh();
    mesh.x_desc(x_label)
        .y_desc(y_label)
        .label_style((FAMILY, 14))
        .axis_desc_style((FAMILY, 16))
        .light_line_style(WHITE.mix(0.0));
    if !grid {
        mesh.disable_mesh();
    }
    mesh.draw().map_err(|e| e.to_string())?;
    Ok(chart)
}

/// One panel: `title` on top, a red cross per failed test, a blue circle per passed test and
/// a grey triangle per error, at the tests' values of `axes = [x, y]`.
fn draw_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    records: &[RunRecord],
    space: &ParamSpace,
    axes: &[String; 2],
    title: &str,
) -> Result<(), String> {
    let mut chart = chart_on(area, space, axes, title, true)?;
    let at = |r: &RunRecord| -> Option<(f64, f64)> {
        let p = r.params.as_ref()?;
        Some((p.real(&axes[0])?, p.real(&axes[1])?))
    };
    let of = |status: Status| -> Vec<(f64, f64)> {
        records
            .iter()
            .filter(|r| r.status == status)
            .filter_map(at)
            .collect()
    };
    let (pass, fail, error) = (of(Status::Pass), of(Status::Fail), of(Status::Error));
    let blue = RGBColor(31, 119, 180);
    let red = RGBColor(214, 39, 40);
    chart
        .draw_series(
            pass.iter()
                .map(|&p| Circle::new(p, 3, blue.stroke_width(1))),
        )
        .map_err(|e| e.to_string())?
        .label(format!("pass ({})", pass.len()))
        .legend(move |p| Circle::new(p, 3, blue.stroke_width(1)));
    chart
        .draw_series(fail.iter().map(|&p| Cross::new(p, 4, red.stroke_width(2))))
        .map_err(|e| e.to_string())?
        .label(format!("fail ({})", fail.len()))
        .legend(move |p| Cross::new(p, 4, red.stroke_width(2)));
    if !error.is_empty() {
        chart
            .draw_series(
                error
                    .iter()
                    .map(|&p| TriangleMarker::new(p, 4, BLACK.mix(0.5))),
            )
            .map_err(|e| e.to_string())?
            .label(format!("error ({})", error.len()))
            .legend(|p| TriangleMarker::new(p, 4, BLACK.mix(0.5)));
    }
    chart
        .configure_series_labels()
        .label_font((FAMILY, 14))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(SeriesLabelPosition::UpperRight)
        .draw()
        .map_err(|e| e.to_string())?;
    Ok(())
}

/// Draws `panels` side by side (each: title and records) into `stem.png` and `stem.svg`, and
/// returns the two paths. Size: 760 × 600 pixels per panel.
///
/// # Errors
/// [`PlotError::NotAnAxis`] when an axis is not a continuous parameter of `space`;
/// [`PlotError::Draw`] when a file cannot be written.
pub fn failure_map(
    stem: &Path,
    space: &ParamSpace,
    axes: &[String; 2],
    panels: &[(&str, &[RunRecord])],
) -> Result<[PathBuf; 2], PlotError> {
    register_font();
    for a in axes {
        axis(space, a)?;
    }
    let size = (760 * panels.len().max(1) as u32, 600);
    png_and_svg(
        stem,
        size,
        |root| render(root, space, axes, panels),
        |root| render(root, space, axes, panels),
    )
}

/// Draws one figure of `size` pixels into `stem.png` and `stem.svg`, each through a temporary
/// file and a rename, so a failed write leaves any earlier plot whole. `png` and `svg` are the
/// same drawing code on the two backends. Returns the two paths.
fn png_and_svg(
    stem: &Path,
    size: (u32, u32),
    png: impl Fn(DrawingArea<BitMapBackend<'_>, Shift>) -> Result<(), String>,
    svg: impl Fn(DrawingArea<SVGBackend<'_>, Shift>) -> Result<(), String>,
) -> Result<[PathBuf; 2], PlotError> {
    let (png_path, svg_path) = (stem.with_extension("png"), stem.with_extension("svg"));
    let failed = |path: &Path| {
        let path = path.to_path_buf();
        move |reason| PlotError::Draw { path, reason }
    };
    crate::atomic::with_temp(&png_path, |tmp| {
        png(BitMapBackend::new(tmp, size).into_drawing_area())
    })
    .map_err(failed(&png_path))?;
    crate::atomic::with_temp(&svg_path, |tmp| {
        svg(SVGBackend::new(tmp, size).into_drawing_area())
    })
    .map_err(failed(&svg_path))?;
    Ok([png_path, svg_path])
}

/// Fills `root` with the panels side by side and writes it out.
fn render<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    space: &ParamSpace,
    axes: &[String; 2],
    panels: &[(&str, &[RunRecord])],
) -> Result<(), String> {
    root.fill(&WHITE).map_err(|e| e.to_string())?;
    let areas = root.split_evenly((1, panels.len().max(1)));
    for (area, (title, records)) in areas.iter().zip(panels) {
        draw_panel(area, records, space, axes, title)?;
    }
    root.present().map_err(|e| e.to_string())
}

/// Width of one tile of a contact sheet, in pixels.
const TILE_W: u32 = 240;

/// Draws a contact sheet of camera frames: at most 36 of `frames` (`(time s, image)`,
/// evenly spaced, always the last), 6 per row, each scaled to 240 pixels wide with its time
/// under it, and `title` on top. Writes PNG to `path`.
///
/// # Errors
/// The backend's message when the file cannot be written.
pub fn contact_sheet(
    path: &Path,
    frames: &[(f64, image::RgbImage)],
    title: &str,
) -> Result<(), String> {
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
    let fail = |e: &dyn std::fmt::Display| format!("cannot draw `{}`: {e}", path.display());
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

/// Failure rate per cell of a `bins × bins` grid over `axes`: `(failed, tests)` per cell,
/// row-major from the lowest `y` bin, `x` fastest. Errors count as tests, not failures.
pub fn failure_rates(
    records: &[RunRecord],
    space: &ParamSpace,
    axes: &[String; 2],
    bins: usize,
) -> Result<Vec<(u32, u32)>, PlotError> {
    let (x_lo, x_hi, _) = axis(space, &axes[0])?;
    let (y_lo, y_hi, _) = axis(space, &axes[1])?;
    let cell = |v: f64, lo: f64, hi: f64| {
        (((v - lo) / (hi - lo) * bins as f64).floor() as usize).min(bins - 1)
    };
    let mut cells = vec![(0u32, 0u32); bins * bins];
    for r in records {
        let Some(p) = r.params.as_ref() else { continue };
        let (Some(x), Some(y)) = (p.real(&axes[0]), p.real(&axes[1])) else {
            continue;
        };
        let c = &mut cells[cell(y, y_lo, y_hi) * bins + cell(x, x_lo, x_hi)];
        c.0 += u32::from(r.status == Status::Fail);
        c.1 += 1;
    }
    Ok(cells)
}

/// The failure-rate heat map (paper Figure 10a): the share of failed tests in each cell of a
/// `bins × bins` grid over `axes`, white (0 %) to red (100 %), with each cell's `failed/tests`
/// written in it; empty cells are grey. Writes `stem.png` and `stem.svg` (760 × 600 pixels)
/// and returns their paths.
///
/// # Errors
/// As [`failure_map`].
pub fn failure_rate_map(
    stem: &Path,
    space: &ParamSpace,
    axes: &[String; 2],
    title: &str,
    records: &[RunRecord],
    bins: usize,
) -> Result<[PathBuf; 2], PlotError> {
    register_font();
    let bins = bins.max(1);
    let cells = failure_rates(records, space, axes, bins)?;
    png_and_svg(
        stem,
        (760, 600),
        |root| draw_rates(root, space, axes, title, &cells, bins),
        |root| draw_rates(root, space, axes, title, &cells, bins),
    )
}

fn draw_rates<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    space: &ParamSpace,
    axes: &[String; 2],
    title: &str,
    cells: &[(u32, u32)],
    bins: usize,
) -> Result<(), String> {
    let (x_lo, x_hi, _) = axis(space, &axes[0]).map_err(|e| e.to_string())?;
    let (y_lo, y_hi, _) = axis(space, &axes[1]).map_err(|e| e.to_string())?;
    root.fill(&WHITE).map_err(|e| e.to_string())?;
    let mut chart = chart_on(&root, space, axes, title, false)?;
    let (dx, dy) = ((x_hi - x_lo) / bins as f64, (y_hi - y_lo) / bins as f64);
    let rects = cells.iter().enumerate().map(|(i, &(failed, n))| {
        let (cx, cy) = ((i % bins) as f64, (i / bins) as f64);
        let color = if n == 0 {
            RGBColor(220, 220, 220)
        } else {
            // White at 0 % to the failure red (214, 39, 40) at 100 %.
            let rate = f64::from(failed) / f64::from(n);
            let mix = |to: f64| (255.0 + rate * (to - 255.0)).round() as u8;
            RGBColor(mix(214.0), mix(39.0), mix(40.0))
        };
        Rectangle::new(
            [
                (x_lo + cx * dx, y_lo + cy * dy),
                (x_lo + (cx + 1.0) * dx, y_lo + (cy + 1.0) * dy),
            ],
            color.filled(),
        )
    });
    chart.draw_series(rects).map_err(|e| e.to_string())?;
    let labels = cells
        .iter()
        .enumerate()
        .filter(|(_, c)| c.1 > 0)
        .map(|(i, &(failed, n))| {
            let (cx, cy) = ((i % bins) as f64, (i / bins) as f64);
            Text::new(
                format!("{failed}/{n}"),
                (x_lo + (cx + 0.3) * dx, y_lo + (cy + 0.6) * dy),
                (FAMILY, 13).into_font().color(&BLACK),
            )
        });
    chart.draw_series(labels).map_err(|e| e.to_string())?;
    root.present().map_err(|e| e.to_string())
}

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
) -> Result<(), String> {
    root.fill(&WHITE).map_err(|e| e.to_string())?;
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
            .build_cartesian_2d(-0.5f64..n as f64 - 0.5, (0.8f64..top * 1.5).log_scale())
            .map_err(|e| e.to_string())?;
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
            .draw()
            .map_err(|e| e.to_string())?;
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
            chart
                .draw_series(shapes.drain(..))
                .map_err(|e| e.to_string())?;
            chart
                .draw_series(
                    v.iter()
                        .map(|&y| Circle::new((x + 0.28, y), 2, BLACK.mix(0.35).filled())),
                )
                .map_err(|e| e.to_string())?;
        }
    }
    root.present().map_err(|e| e.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;
    use paracosm_generators::{Param, Point, Value};

    fn record(id: u64, space: &ParamSpace, u: [f64; 2], status: Status) -> RunRecord {
        let point = Point {
            discrete: vec![0],
            continuous: u.to_vec(),
        };
        RunRecord {
            id,
            seed: 0,
            strategy: "random".into(),
            params: space.decode(&point).ok(),
            point,
            status,
            monitors: vec![],
            metrics: vec![],
            error: None,
            wall_ms: 0.0,
        }
    }

    fn space() -> ParamSpace {
        ParamSpace::new(vec![
            Param::interval("speed", 0.0, 10.0, "m/s"),
            Param::levels("colour", vec![Value::Text("red".into())]),
            Param::interval("dist", 5.0, 60.0, "m"),
        ])
        .unwrap()
    }

    #[test]
    fn draws_png_and_svg_with_labelled_axes_and_counts() {
        let s = space();
        let records = vec![
            record(0, &s, [0.1, 0.1], Status::Pass),
            record(1, &s, [0.5, 0.5], Status::Fail),
            record(2, &s, [0.9, 0.2], Status::Fail),
        ];
        let dir = tempfile::tempdir().unwrap();
        let axes = ["speed".to_owned(), "dist".to_owned()];
        let [png, svg] =
            failure_map(&dir.path().join("map"), &s, &axes, &[("t", &records)]).unwrap();
        assert_eq!(&std::fs::read(&png).unwrap()[..4], b"\x89PNG");
        let svg = std::fs::read_to_string(svg).unwrap();
        for text in ["speed [m/s]", "dist [m]", "pass (1)", "fail (2)"] {
            assert!(svg.contains(text), "missing {text}");
        }
    }

    #[test]
    fn failure_rates_bin_the_tests_and_the_heat_map_draws() {
        let s = space();
        let records = vec![
            record(0, &s, [0.1, 0.1], Status::Pass),
            record(1, &s, [0.2, 0.2], Status::Fail),
            record(2, &s, [0.9, 0.9], Status::Fail),
            record(3, &s, [0.9, 0.1], Status::Error),
        ];
        let axes = ["speed".to_owned(), "dist".to_owned()];
        let cells = failure_rates(&records, &s, &axes, 2).unwrap();
        // Row 0 (low dist): x low has 1 fail of 2, x high has 1 error; row 1: 1 fail of 1.
        assert_eq!(cells, vec![(1, 2), (0, 1), (0, 0), (1, 1)]);
        let dir = tempfile::tempdir().unwrap();
        let [png, svg] =
            failure_rate_map(&dir.path().join("rate"), &s, &axes, "t", &records, 2).unwrap();
        assert_eq!(&std::fs::read(&png).unwrap()[..4], b"\x89PNG");
        let svg = std::fs::read_to_string(svg).unwrap();
        assert!(svg.contains("1/2") && svg.contains("dist [m]"));
    }

    #[test]
    fn a_discrete_or_unknown_axis_is_an_error() {
        let s = space();
        let dir = tempfile::tempdir().unwrap();
        for bad in ["colour", "nope"] {
            let axes = ["speed".to_owned(), bad.to_owned()];
            let err = failure_map(&dir.path().join("m"), &s, &axes, &[]).unwrap_err();
            assert!(matches!(err, PlotError::NotAnAxis(ref n) if n == bad));
        }
        assert!(!dir.path().join("m.png").exists());
    }
}
