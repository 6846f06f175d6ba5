//! Plots: the failure map (paper Figure 9), as PNG and SVG, drawn with `plotters` and a
//! bundled font so that it renders on machines without system fonts.

use std::path::{Path, PathBuf};
use std::sync::Once;

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

/// One panel: `title` on top, a red cross per failed test, a blue circle per passed test and
/// a grey triangle per error, at the tests' values of `axes = [x, y]`.
fn draw_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    records: &[RunRecord],
    space: &ParamSpace,
    axes: &[String; 2],
    title: &str,
) -> Result<(), String> {
    let (x_lo, x_hi, x_label) = axis(space, &axes[0]).map_err(|e| e.to_string())?;
    let (y_lo, y_hi, y_label) = axis(space, &axes[1]).map_err(|e| e.to_string())?;
    let mut chart = ChartBuilder::on(area)
        .caption(title, (FAMILY, 20))
        .margin(12)
        .x_label_area_size(45)
        .y_label_area_size(55)
        .build_cartesian_2d(x_lo..x_hi, y_lo..y_hi)
        .map_err(|e| e.to_string())?;
    chart
        .configure_mesh()
        .x_desc(x_label)
        .y_desc(y_label)
        .label_style((FAMILY, 14))
        .axis_desc_style((FAMILY, 16))
        .light_line_style(WHITE.mix(0.0))
        .draw()
        .map_err(|e| e.to_string())?;
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
    let png = stem.with_extension("png");
    let svg = stem.with_extension("svg");
    render(
        BitMapBackend::new(&png, size).into_drawing_area(),
        &png,
        space,
        axes,
        panels,
    )?;
    render(
        SVGBackend::new(&svg, size).into_drawing_area(),
        &svg,
        space,
        axes,
        panels,
    )?;
    Ok([png, svg])
}

/// Fills `root` with the panels side by side and writes it out.
fn render<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    path: &Path,
    space: &ParamSpace,
    axes: &[String; 2],
    panels: &[(&str, &[RunRecord])],
) -> Result<(), PlotError> {
    let fail = |reason: String| PlotError::Draw {
        path: path.to_path_buf(),
        reason,
    };
    root.fill(&WHITE).map_err(|e| fail(e.to_string()))?;
    let areas = root.split_evenly((1, panels.len().max(1)));
    for (area, (title, records)) in areas.iter().zip(panels) {
        draw_panel(area, records, space, axes, title).map_err(fail)?;
    }
    root.present().map_err(|e| fail(e.to_string()))
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
