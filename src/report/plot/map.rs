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
use super::{png_and_svg, register_font, DrawError, PlotError, FAMILY};
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
) -> Result<ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>, DrawError> {
    let ((x_lo, x_hi), (y_lo, y_hi)) = (x.range(), y.range());
    let mut chart = ChartBuilder::on(area)
        .caption(title, (FAMILY, 20))
        .margin(12)
        .x_label_area_size(45)
        .y_label_area_size(70)
        .build_cartesian_2d(x_lo..x_hi, y_lo..y_hi)?;
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
    mesh.draw()?;
    Ok(chart)
}

/// What the points of a failure map are coloured by.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Coloring {
    /// Red crosses for failed tests, blue circles for passed ones, grey triangles for errors.
    #[default]
    Outcome,
    /// The same shapes, coloured by the test's robustness (the smallest over its monitors) on a
    /// diverging scale centred at 0: red below, blue above, grey at 0, so near misses show.
    /// The scale spans ± the 95th percentile of |robustness| over the tests (clipped beyond).
    Robustness,
}

/// A name that is no [`Coloring`] (`--color`'s value): the name as given.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("`{0}` is not a colouring: use `outcome` or `robustness`")]
pub struct UnknownColoring(pub String);

impl std::str::FromStr for Coloring {
    type Err = UnknownColoring;
    fn from_str(s: &str) -> Result<Self, UnknownColoring> {
        match s {
            "outcome" => Ok(Coloring::Outcome),
            "robustness" => Ok(Coloring::Robustness),
            other => Err(UnknownColoring(other.to_owned())),
        }
    }
}

const BLUE: RGBColor = RGBColor(31, 119, 180);
const RED: RGBColor = RGBColor(214, 39, 40);
const MID: RGBColor = RGBColor(200, 200, 200);

/// The colour of robustness `r` on the diverging scale spanning `±m`: red at `-m` and below,
/// grey at 0, blue at `+m` and above.
pub(crate) fn diverging(r: f64, m: f64) -> RGBColor {
    let t = (r / m).clamp(-1.0, 1.0);
    let to = if t < 0.0 { RED } else { BLUE };
    let a = t.abs();
    let mix =
        |from: u8, to: u8| (f64::from(from) + a * (f64::from(to) - f64::from(from))).round() as u8;
    RGBColor(mix(MID.0, to.0), mix(MID.1, to.1), mix(MID.2, to.2))
}

/// Half the span of the robustness scale: the 95th percentile of |robustness| over the tests
/// with a finite one (1 when there is none or it is 0).
pub(crate) fn robustness_span(records: &[RunRecord]) -> f64 {
    let mut a: Vec<f64> = records
        .iter()
        .map(|r| r.robustness().abs())
        .filter(|x| x.is_finite())
        .collect();
    if a.is_empty() {
        return 1.0;
    }
    a.sort_by(f64::total_cmp);
    let m = a[((a.len() - 1) as f64 * 0.95).round() as usize];
    if m > 0.0 {
        m
    } else {
        1.0
    }
}

/// One panel: `title` on top, a red cross per failed test, a blue circle per passed test and
/// a grey triangle per error, at the tests' places on `x` and `y`; with
/// [`Coloring::Robustness`], the crosses and circles take the colour of their robustness on
/// the scale `±span`.
fn draw_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    records: &[RunRecord],
    (x, y): (&Axis, &Axis),
    title: &str,
    color: Coloring,
    span: f64,
) -> Result<(), DrawError> {
    let mut chart = chart_on(area, x, y, title, true)?;
    let at = |r: &RunRecord| -> Option<(f64, f64)> { Some((x.coord(r, 1)?, y.coord(r, 2)?)) };
    let of = |status: Status| -> Vec<((f64, f64), RGBColor)> {
        records
            .iter()
            .filter(|r| r.status == status)
            .filter_map(|r| {
                let c = match (color, status) {
                    (Coloring::Robustness, Status::Pass | Status::Fail) => {
                        let rob = r.robustness();
                        if rob.is_nan() {
                            MID
                        } else {
                            diverging(rob, span)
                        }
                    }
                    (_, Status::Fail) => RED,
                    _ => BLUE,
                };
                Some((at(r)?, c))
            })
            .collect()
    };
    let (pass, fail, error) = (of(Status::Pass), of(Status::Fail), of(Status::Error));
    let (pass_key, fail_key) = match color {
        Coloring::Outcome => (BLUE, RED),
        Coloring::Robustness => (RGBColor(90, 90, 90), RGBColor(90, 90, 90)),
    };
    chart
        .draw_series(
            pass.iter()
                .map(|&(p, c)| Circle::new(p, 3, c.stroke_width(1))),
        )?
        .label(format!("pass ({})", pass.len()))
        .legend(move |p| Circle::new(p, 3, pass_key.stroke_width(1)));
    chart
        .draw_series(
            fail.iter()
                .map(|&(p, c)| Cross::new(p, 4, c.stroke_width(2))),
        )?
        .label(format!("fail ({})", fail.len()))
        .legend(move |p| Cross::new(p, 4, fail_key.stroke_width(2)));
    if !error.is_empty() {
        chart
            .draw_series(
                error
                    .iter()
                    .map(|&(p, _)| TriangleMarker::new(p, 4, BLACK.mix(0.5))),
            )?
            .label(format!("error ({})", error.len()))
            .legend(|p| TriangleMarker::new(p, 4, BLACK.mix(0.5)));
    }
    super::draw_legend(&mut chart)?;
    Ok(())
}

/// The colour bar of [`Coloring::Robustness`]: the scale from `-span` to `+span`.
fn draw_color_bar<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    span: f64,
) -> Result<(), DrawError> {
    let mut chart = ChartBuilder::on(area)
        .margin_top(50)
        .margin_bottom(57)
        .margin_right(8)
        .y_label_area_size(0)
        .right_y_label_area_size(52)
        .build_cartesian_2d(0.0..1.0, -span..span)?;
    chart
        .configure_mesh()
        .disable_mesh()
        .disable_x_axis()
        .y_desc("robustness (smallest over monitors)")
        .label_style((FAMILY, 12))
        .axis_desc_style((FAMILY, 13))
        .draw()?;
    let steps = 60;
    chart.draw_series((0..steps).map(|k| {
        let lo = -span + 2.0 * span * k as f64 / steps as f64;
        let hi = -span + 2.0 * span * (k + 1) as f64 / steps as f64;
        Rectangle::new(
            [(0.0, lo), (1.0, hi)],
            diverging((lo + hi) / 2.0, span).filled(),
        )
    }))?;
    Ok(())
}

/// Draws `panels` side by side (each: title and records) into `stem.png` and `stem.svg`, and
/// returns the two paths. `axes` names one parameter (a strip plot of it against the outcome,
/// pass / fail / error, jittered within each band) or two (x and y); a discrete parameter has
/// a column per level with the points jittered within it. `color` picks what the points are
/// coloured by; with [`Coloring::Robustness`] a colour bar is drawn on the right (one scale for
/// all panels). Size: 760 × 600 pixels per panel, plus 110 for the colour bar.
///
/// # Errors
/// [`PlotError::NotAnAxis`] when an axis is not a parameter of `space`, [`PlotError::Axes`]
/// for no axis or more than two, [`PlotError::Draw`] when a file cannot be written.
pub fn failure_map(
    stem: &Path,
    space: &ParamSpace,
    axes: &[String],
    panels: &[(&str, &[RunRecord])],
    color: Coloring,
) -> Result<[PathBuf; 2], PlotError> {
    register_font();
    let (x, y) = scatter_axes(space, axes)?;
    let bar = if color == Coloring::Robustness {
        110
    } else {
        0
    };
    let size = (760 * panels.len().max(1) as u32 + bar, 600);
    let all: Vec<RunRecord> = panels.iter().flat_map(|(_, r)| r.iter().cloned()).collect();
    let span = robustness_span(&all);
    png_and_svg(
        stem,
        size,
        |root| render(root, (&x, &y), panels, color, span, bar),
        |root| render(root, (&x, &y), panels, color, span, bar),
    )
}

/// Fills `root` with the panels side by side (and the colour bar, `bar` pixels wide) and writes
/// it out.
fn render<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    axes: (&Axis, &Axis),
    panels: &[(&str, &[RunRecord])],
    color: Coloring,
    span: f64,
    bar: u32,
) -> Result<(), DrawError> {
    root.fill(&WHITE)?;
    let (w, _) = root.dim_in_pixel();
    let (maps, scale) = root.split_horizontally(w - bar);
    let areas = maps.split_evenly((1, panels.len().max(1)));
    for (area, (title, records)) in areas.iter().zip(panels) {
        draw_panel(area, records, axes, title, color, span)?;
    }
    if bar > 0 {
        draw_color_bar(&scale, span)?;
    }
    root.present()?;
    Ok(())
}

/// Cells along each continuous axis of a failure-rate grid over `axes` for `tests` tests, so
/// that the cells hold about 5 tests on average: `(tests / (5 L))^(1/c)` rounded, within
/// `[2, 16]`, where `c` is the number of continuous axes and `L` the product of the discrete
/// axes' level counts. An unknown axis counts as continuous.
pub fn adaptive_bins(tests: usize, space: &ParamSpace, axes: &[String]) -> usize {
    let (mut c, mut levels) = (0i32, 1.0f64);
    for a in axes {
        match space.param(a).map(|p| &p.domain) {
            Some(paracosm_generators::Domain::Levels(l))
                if l.len() <= super::axis::MAX_CATEGORIES =>
            {
                levels *= l.len().max(1) as f64
            }
            _ => c += 1,
        }
    }
    if c == 0 {
        return 2;
    }
    let per_axis = (tests as f64 / (5.0 * levels)).powf(1.0 / f64::from(c));
    (per_axis.round() as usize).clamp(2, 16)
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
) -> Result<(), DrawError> {
    root.fill(&WHITE)?;
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
    chart.draw_series(rects)?;
    // White lines between the cells, so neighbours of one colour stay apart.
    let borders = (0..g.cells.len()).map(|i| {
        let (x0, x1, y0, y1) = span(i);
        Rectangle::new([(x0, y0), (x1, y1)], WHITE.stroke_width(2))
    });
    chart.draw_series(borders)?;
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
    chart.draw_series(labels)?;
    root.present()?;
    Ok(())
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
            passive: Vec::new(),
            campaign: None,
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
            Coloring::Outcome,
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
            Coloring::Outcome,
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
            Coloring::Outcome,
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
    fn parameters_of_a_million_levels_give_bounded_plots() {
        // Two parameters of 10^6 levels asked for 10^12 heat-map cells and drew a label per
        // level (a 495 MB SVG for 4 tests): numbers are drawn as an interval over their
        // values, texts by their level index, each binned.
        let s = ParamSpace::new(vec![
            Param::levels("lane", (0..1_000_000).map(Value::Int).collect()),
            Param::levels(
                "name",
                (0..1_000_000)
                    .map(|i| Value::Text(format!("n{i}")))
                    .collect(),
            ),
        ])
        .unwrap();
        let records: Vec<RunRecord> = (0..4u32)
            .map(|i| {
                let point = Point {
                    discrete: vec![i * 250_000, 999_999 - i * 250_000],
                    continuous: vec![],
                };
                RunRecord {
                    params: s.decode(&point).ok(),
                    point,
                    status: if i % 2 == 0 {
                        Status::Pass
                    } else {
                        Status::Fail
                    },
                    ..record(u64::from(i), &space(), 0, [0.5, 0.5], Status::Pass)
                }
            })
            .collect();
        let axes = names(&["lane", "name"]);
        let bins = adaptive_bins(records.len(), &s, &axes);
        let g = failure_rates(&records, &s, &axes, bins).unwrap();
        assert_eq!((g.columns, g.rows), (bins, bins));
        assert_eq!(g.cells.iter().map(|c| c.1).sum::<u32>(), 4);
        let dir = tempfile::tempdir().unwrap();
        let [_, rate] =
            failure_rate_map(&dir.path().join("rate"), &s, &axes, "t", &records, bins).unwrap();
        let [_, map] = failure_map(
            &dir.path().join("m"),
            &s,
            &axes,
            &[("t", &records)],
            Coloring::Outcome,
        )
        .unwrap();
        for svg in [rate, map] {
            let text = std::fs::read_to_string(&svg).unwrap();
            assert!(
                text.len() < 1 << 20,
                "{}: {} bytes",
                svg.display(),
                text.len()
            );
            assert!(text.contains("name (level index)"), "{}", svg.display());
        }
    }

    #[test]
    fn an_unknown_axis_or_no_axis_is_an_error_and_writes_nothing() {
        let s = space();
        let dir = tempfile::tempdir().unwrap();
        let err = failure_map(
            &dir.path().join("m"),
            &s,
            &names(&["speed", "nope"]),
            &[],
            Coloring::Outcome,
        )
        .unwrap_err();
        assert!(matches!(err, PlotError::NotAnAxis(ref n) if n == "nope"));
        let err = failure_map(&dir.path().join("m"), &s, &[], &[], Coloring::Outcome).unwrap_err();
        assert!(matches!(err, PlotError::Axes(0)));
        assert!(!dir.path().join("m.png").exists());
    }

    #[test]
    fn bins_adapt_to_about_five_tests_per_cell_up_to_sixteen() {
        let s = space();
        assert_eq!(adaptive_bins(50, &s, &names(&["speed", "dist"])), 3);
        assert_eq!(adaptive_bins(500, &s, &names(&["speed", "dist"])), 10);
        assert_eq!(adaptive_bins(100_000, &s, &names(&["speed", "dist"])), 16);
        assert_eq!(adaptive_bins(4, &s, &names(&["speed"])), 2);
        // A two-level axis halves the tests per column: 200 / (5 * 2) = 20, capped at 16.
        assert_eq!(adaptive_bins(200, &s, &names(&["speed", "colour"])), 16);
        assert_eq!(adaptive_bins(100, &s, &names(&["speed", "colour"])), 10);
    }

    #[test]
    fn the_robustness_scale_is_centred_at_zero_and_clipped() {
        let m = 2.0;
        assert_eq!(diverging(0.0, m), MID);
        assert_eq!(diverging(-m, m), RED);
        assert_eq!(diverging(5.0 * m, m), BLUE);
        let near = diverging(-0.1, m);
        assert!(
            near.0 > near.2 && near.0 < RED.0 + 1,
            "slightly red: {near:?}"
        );
        assert_eq!("robustness".parse::<Coloring>(), Ok(Coloring::Robustness));
        assert_eq!(
            "blue".parse::<Coloring>().unwrap_err().to_string(),
            "`blue` is not a colouring: use `outcome` or `robustness`"
        );
    }
}
