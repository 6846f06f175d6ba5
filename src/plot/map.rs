//! The failure map (paper Figure 9) and the failure-rate heat map (Figure 10a), over one or two
//! parameters of any kind: a continuous parameter spans its interval, a discrete one has a
//! column per level; with one parameter the map is a strip plot of the parameter against the
//! outcome.

use std::path::{Path, PathBuf};

use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use paracosm_generators::ParamSpace;

use super::axis::Axis;
use super::{png_and_svg, register_font, PlotError, FAMILY};
use crate::record::{RunRecord, Status};

/// The axes of a map over `names`: one name gives the parameter against the outcome (a strip
/// plot), two a scatter of the first against the second.
fn scatter_axes(space: &ParamSpace, names: &[String]) -> Result<(Axis, Axis), PlotError> {
    match names {
        [x] => Ok((Axis::of(space, x)?, Axis::Outcome)),
        [x, y] => Ok((Axis::of(space, x)?, Axis::of(space, y)?)),
        _ => Err(PlotError::Axes(names.len())),
    }
}

/// The axes of a heat map over `names`: one name gives a single row.
fn grid_axes(space: &ParamSpace, names: &[String]) -> Result<(Axis, Axis), PlotError> {
    match names {
        [x] => Ok((Axis::of(space, x)?, Axis::All)),
        [x, y] => Ok((Axis::of(space, x)?, Axis::of(space, y)?)),
        _ => Err(PlotError::Axes(names.len())),
    }
}

/// The label of tick `v` on a categorical axis: the category's name at whole positions.
fn category_label(categories: &[String], v: f64) -> String {
    let i = v.round();
    if (v - i).abs() < 1e-6 && i >= 0.0 {
        categories.get(i as usize).cloned().unwrap_or_default()
    } else {
        String::new()
    }
}

/// A chart over axes `x` and `y` with `title`, axis titles with units, category names on
/// categorical axes, and light grid lines when `grid`.
fn chart_on<'a, DB: DrawingBackend>(
    area: &'a DrawingArea<DB, Shift>,
    x: &Axis,
    y: &Axis,
    title: &str,
    grid: bool,
) -> Result<ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>, String> {
    let ((x_lo, x_hi), (y_lo, y_hi)) = (x.range(), y.range());
    let mut chart = ChartBuilder::on(area)
        .caption(title, (FAMILY, 20))
        .margin(12)
        .x_label_area_size(45)
        .y_label_area_size(70)
        .build_cartesian_2d(x_lo..x_hi, y_lo..y_hi)
        .map_err(|e| e.to_string())?;
    let (x_cats, y_cats) = (x.categories(), y.categories());
    let fx = |v: &f64| category_label(x_cats.as_deref().unwrap_or_default(), *v);
    let fy = |v: &f64| category_label(y_cats.as_deref().unwrap_or_default(), *v);
    let mut mesh = chart.configure_mesh();
    mesh.x_desc(x.label())
        .y_desc(y.label())
        .label_style((FAMILY, 14))
        .axis_desc_style((FAMILY, 16))
        .light_line_style(WHITE.mix(0.0));
    if let Some(c) = &x_cats {
        mesh.x_labels(c.len())
            .x_label_formatter(&fx)
            .disable_x_mesh();
    }
    if let Some(c) = &y_cats {
        mesh.y_labels(c.len())
            .y_label_formatter(&fy)
            .disable_y_mesh();
    }
    if !grid {
        mesh.disable_mesh();
    }
    mesh.draw().map_err(|e| e.to_string())?;
    Ok(chart)
}

/// One panel: `title` on top, a red cross per failed test, a blue circle per passed test and
/// a grey triangle per error, at the tests' places on `x` and `y`.
fn draw_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    records: &[RunRecord],
    (x, y): (&Axis, &Axis),
    title: &str,
) -> Result<(), String> {
    let mut chart = chart_on(area, x, y, title, true)?;
    let at = |r: &RunRecord| -> Option<(f64, f64)> { Some((x.coord(r, 1)?, y.coord(r, 2)?)) };
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
/// returns the two paths. `axes` names one parameter (a strip plot of it against the outcome,
/// pass / fail / error, jittered within each band) or two (x and y); a discrete parameter has
/// a column per level with the points jittered within it. Size: 760 × 600 pixels per panel.
///
/// # Errors
/// [`PlotError::NotAnAxis`] when an axis is not a parameter of `space`, [`PlotError::Axes`]
/// for no axis or more than two, [`PlotError::Draw`] when a file cannot be written.
pub fn failure_map(
    stem: &Path,
    space: &ParamSpace,
    axes: &[String],
    panels: &[(&str, &[RunRecord])],
) -> Result<[PathBuf; 2], PlotError> {
    register_font();
    let (x, y) = scatter_axes(space, axes)?;
    let size = (760 * panels.len().max(1) as u32, 600);
    png_and_svg(
        stem,
        size,
        |root| render(root, (&x, &y), panels),
        |root| render(root, (&x, &y), panels),
    )
}

/// Fills `root` with the panels side by side and writes it out.
fn render<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    axes: (&Axis, &Axis),
    panels: &[(&str, &[RunRecord])],
) -> Result<(), String> {
    root.fill(&WHITE).map_err(|e| e.to_string())?;
    let areas = root.split_evenly((1, panels.len().max(1)));
    for (area, (title, records)) in areas.iter().zip(panels) {
        draw_panel(area, records, axes, title)?;
    }
    root.present().map_err(|e| e.to_string())
}

/// Failure counts on a grid over one or two parameters: `cells[row * columns + column]` is
/// `(failed, tests)` (errors count as tests, not failures), rows from the lowest `y` cell,
/// columns from the lowest `x` cell.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RateGrid {
    /// `(failed, tests)` per cell, row-major.
    pub cells: Vec<(u32, u32)>,
    /// Cells along `x`: `bins` for a continuous parameter, one per level of a discrete one.
    pub columns: usize,
    /// Cells along `y`: likewise; 1 for a map over one parameter.
    pub rows: usize,
}

/// The failure rate grid of `records` over `axes` (one or two parameter names), with `bins`
/// equal cells along each continuous parameter and one per level of a discrete one.
///
/// # Errors
/// As [`failure_map`], but for drawing.
pub fn failure_rates(
    records: &[RunRecord],
    space: &ParamSpace,
    axes: &[String],
    bins: usize,
) -> Result<RateGrid, PlotError> {
    let (x, y) = grid_axes(space, axes)?;
    grid(records, &x, &y, bins)
}

fn grid(records: &[RunRecord], x: &Axis, y: &Axis, bins: usize) -> Result<RateGrid, PlotError> {
    let (columns, rows) = (x.bins(bins), y.bins(bins));
    let mut cells = vec![(0u32, 0u32); columns * rows];
    for r in records {
        let (Some(cx), Some(cy)) = (x.bin(r, bins), y.bin(r, bins)) else {
            continue;
        };
        let c = &mut cells[cy * columns + cx];
        c.0 += u32::from(r.status == Status::Fail);
        c.1 += 1;
    }
    Ok(RateGrid {
        cells,
        columns,
        rows,
    })
}

/// The failure-rate heat map (paper Figure 10a): the share of failed tests in each cell of the
/// grid of [`failure_rates`], white (0 %) to red (100 %), with each cell's `failed/tests`
/// written in it; empty cells are grey. Writes `stem.png` and `stem.svg` (760 × 600 pixels)
/// and returns their paths.
///
/// # Errors
/// As [`failure_map`].
pub fn failure_rate_map(
    stem: &Path,
    space: &ParamSpace,
    axes: &[String],
    title: &str,
    records: &[RunRecord],
    bins: usize,
) -> Result<[PathBuf; 2], PlotError> {
    register_font();
    let (x, y) = grid_axes(space, axes)?;
    let g = grid(records, &x, &y, bins)?;
    png_and_svg(
        stem,
        (760, 600),
        |root| draw_rates(root, (&x, &y), title, &g),
        |root| draw_rates(root, (&x, &y), title, &g),
    )
}

fn draw_rates<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    (x, y): (&Axis, &Axis),
    title: &str,
    g: &RateGrid,
) -> Result<(), String> {
    root.fill(&WHITE).map_err(|e| e.to_string())?;
    let mut chart = chart_on(&root, x, y, title, false)?;
    let span = |i: usize| {
        let (x0, x1) = x.bin_span(i % g.columns, g.columns);
        let (y0, y1) = y.bin_span(i / g.columns, g.rows);
        (x0, x1, y0, y1)
    };
    let rects = g.cells.iter().enumerate().map(|(i, &(failed, n))| {
        let (x0, x1, y0, y1) = span(i);
        let color = if n == 0 {
            RGBColor(220, 220, 220)
        } else {
            // White at 0 % to the failure red (214, 39, 40) at 100 %.
            let rate = f64::from(failed) / f64::from(n);
            let mix = |to: f64| (255.0 + rate * (to - 255.0)).round() as u8;
            RGBColor(mix(214.0), mix(39.0), mix(40.0))
        };
        Rectangle::new([(x0, y0), (x1, y1)], color.filled())
    });
    chart.draw_series(rects).map_err(|e| e.to_string())?;
    // White lines between the cells, so neighbours of one colour stay apart.
    let borders = (0..g.cells.len()).map(|i| {
        let (x0, x1, y0, y1) = span(i);
        Rectangle::new([(x0, y0), (x1, y1)], WHITE.stroke_width(2))
    });
    chart.draw_series(borders).map_err(|e| e.to_string())?;
    let labels = g
        .cells
        .iter()
        .enumerate()
        .filter(|(_, c)| c.1 > 0)
        .map(|(i, &(failed, n))| {
            let (x0, x1, y0, y1) = span(i);
            let centred = Pos::new(HPos::Center, VPos::Center);
            Text::new(
                format!("{failed}/{n}"),
                ((x0 + x1) / 2.0, (y0 + y1) / 2.0),
                (FAMILY, 13).into_font().color(&BLACK).pos(centred),
            )
        });
    chart.draw_series(labels).map_err(|e| e.to_string())?;
    root.present().map_err(|e| e.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;
    use paracosm_generators::{Param, Point, Value};

    fn record(id: u64, space: &ParamSpace, level: u32, u: [f64; 2], status: Status) -> RunRecord {
        let point = Point {
            discrete: vec![level],
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
            log: Vec::new(),
            wall_ms: 0.0,
        }
    }

    fn space() -> ParamSpace {
        ParamSpace::new(vec![
            Param::interval("speed", 0.0, 10.0, "m/s"),
            Param::levels(
                "colour",
                vec![Value::Text("red".into()), Value::Text("white".into())],
            ),
            Param::interval("dist", 5.0, 60.0, "m"),
        ])
        .unwrap()
    }

    /// The texts an SVG shows, trimmed.
    fn texts(svg: &str) -> Vec<String> {
        let re = regex::Regex::new(r"<text[^>]*>\s*([^<]*?)\s*</text>").unwrap();
        re.captures_iter(svg).map(|c| c[1].to_owned()).collect()
    }

    fn names(a: &[&str]) -> Vec<String> {
        a.iter().map(|s| s.to_string()).collect()
    }

    #[test]
    fn draws_png_and_svg_with_labelled_axes_and_counts() {
        let s = space();
        let records = vec![
            record(0, &s, 0, [0.1, 0.1], Status::Pass),
            record(1, &s, 1, [0.5, 0.5], Status::Fail),
            record(2, &s, 0, [0.9, 0.2], Status::Fail),
        ];
        let dir = tempfile::tempdir().unwrap();
        let [png, svg] = failure_map(
            &dir.path().join("map"),
            &s,
            &names(&["speed", "dist"]),
            &[("t", &records)],
        )
        .unwrap();
        assert_eq!(&std::fs::read(&png).unwrap()[..4], b"\x89PNG");
        let svg = std::fs::read_to_string(svg).unwrap();
        for text in ["speed [m/s]", "dist [m]", "pass (1)", "fail (2)"] {
            assert!(svg.contains(text), "missing {text}");
        }
    }

    #[test]
    fn a_discrete_axis_has_a_column_per_level_named_by_it() {
        let s = space();
        let records: Vec<RunRecord> = (0..20)
            .map(|i| {
                let status = if i % 3 == 0 {
                    Status::Fail
                } else {
                    Status::Pass
                };
                record(i, &s, (i % 2) as u32, [0.05 * i as f64, 0.5], status)
            })
            .collect();
        let dir = tempfile::tempdir().unwrap();
        let [_, svg] = failure_map(
            &dir.path().join("m"),
            &s,
            &names(&["colour", "speed"]),
            &[("t", &records)],
        )
        .unwrap();
        let shown = texts(&std::fs::read_to_string(svg).unwrap());
        for text in [
            "red",
            "white",
            "colour",
            "speed [m/s]",
            "fail (7)",
            "pass (13)",
        ] {
            assert!(
                shown.iter().any(|t| t == text),
                "missing {text} in {shown:?}"
            );
        }
        // Rates: one column per colour, 4 bins of speed.
        let g = failure_rates(&records, &s, &names(&["colour", "speed"]), 4).unwrap();
        assert_eq!((g.columns, g.rows), (2, 4));
        let total: u32 = g.cells.iter().map(|c| c.1).sum();
        assert_eq!(total, 20);
        let red: u32 = (0..4).map(|row| g.cells[row * 2].1).sum();
        assert_eq!(red, 10);
    }

    #[test]
    fn one_parameter_gives_a_strip_plot_against_the_outcome_and_a_one_row_heat_map() {
        let s = space();
        let records = vec![
            record(0, &s, 0, [0.1, 0.1], Status::Pass),
            record(1, &s, 0, [0.6, 0.5], Status::Fail),
            record(2, &s, 0, [0.9, 0.2], Status::Error),
        ];
        let dir = tempfile::tempdir().unwrap();
        let [_, svg] = failure_map(
            &dir.path().join("strip"),
            &s,
            &names(&["speed"]),
            &[("t", &records)],
        )
        .unwrap();
        let shown = texts(&std::fs::read_to_string(svg).unwrap());
        for text in [
            "outcome",
            "pass",
            "fail",
            "error",
            "speed [m/s]",
            "error (1)",
        ] {
            assert!(
                shown.iter().any(|t| t == text),
                "missing {text} in {shown:?}"
            );
        }
        let g = failure_rates(&records, &s, &names(&["speed"]), 2).unwrap();
        assert_eq!(g.cells, vec![(0, 1), (1, 2)]);
        failure_rate_map(
            &dir.path().join("rate"),
            &s,
            &names(&["speed"]),
            "t",
            &records,
            2,
        )
        .unwrap();
    }

    #[test]
    fn failure_rates_bin_the_tests_and_the_heat_map_draws() {
        let s = space();
        let records = vec![
            record(0, &s, 0, [0.1, 0.1], Status::Pass),
            record(1, &s, 0, [0.2, 0.2], Status::Fail),
            record(2, &s, 0, [0.9, 0.9], Status::Fail),
            record(3, &s, 0, [0.9, 0.1], Status::Error),
        ];
        let axes = names(&["speed", "dist"]);
        let g = failure_rates(&records, &s, &axes, 2).unwrap();
        // Row 0 (low dist): x low has 1 fail of 2, x high has 1 error; row 1: 1 fail of 1.
        assert_eq!(g.cells, vec![(1, 2), (0, 1), (0, 0), (1, 1)]);
        let dir = tempfile::tempdir().unwrap();
        let [png, svg] =
            failure_rate_map(&dir.path().join("rate"), &s, &axes, "t", &records, 2).unwrap();
        assert_eq!(&std::fs::read(&png).unwrap()[..4], b"\x89PNG");
        let svg = std::fs::read_to_string(svg).unwrap();
        assert!(svg.contains("1/2") && svg.contains("dist [m]"));
    }

    #[test]
    fn an_unknown_axis_or_no_axis_is_an_error_and_writes_nothing() {
        let s = space();
        let dir = tempfile::tempdir().unwrap();
        let err =
            failure_map(&dir.path().join("m"), &s, &names(&["speed", "nope"]), &[]).unwrap_err();
        assert!(matches!(err, PlotError::NotAnAxis(ref n) if n == "nope"));
        let err = failure_map(&dir.path().join("m"), &s, &[], &[]).unwrap_err();
        assert!(matches!(err, PlotError::Axes(0)));
        assert!(!dir.path().join("m.png").exists());
    }
}
