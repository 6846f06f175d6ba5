//! The scatterplot matrix of every open parameter (`pairs.{png,svg}`): below the diagonal each
//! pair of parameters as a failure map (red crosses failed, blue circles passed, discrete
//! parameters as categorical columns with jitter), on the diagonal each parameter's failure
//! rate per bin, above it the failure rate per cell of the pair.

use std::path::{Path, PathBuf};

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use paracosm_generators::ParamSpace;

use super::axis::Axis;
use super::map::adaptive_bins;
use super::{png_and_svg, register_font, DrawError, PlotError, FAMILY};
use crate::record::{RunRecord, Status};

/// At most this many parameters are drawn; the others are named in a note on the figure.
pub const MAX_PAIRS: usize = 8;

const BLUE: RGBColor = RGBColor(31, 119, 180);
const RED: RGBColor = RGBColor(214, 39, 40);

/// The label of tick `v` on a categorical axis.
fn category_label(categories: &[String], v: f64) -> String {
    let i = v.round();
    if (v - i).abs() < 1e-6 && i >= 0.0 {
        categories.get(i as usize).cloned().unwrap_or_default()
    } else {
        String::new()
    }
}

/// White (0 %) to red (100 %); grey for an empty cell.
fn rate_color(failed: u32, n: u32) -> RGBColor {
    if n == 0 {
        return RGBColor(225, 225, 225);
    }
    let rate = f64::from(failed) / f64::from(n);
    let mix = |to: u8| (255.0 + rate * (f64::from(to) - 255.0)).round() as u8;
    RGBColor(mix(RED.0), mix(RED.1), mix(RED.2))
}

/// Draws the scatterplot matrix of `names` (parameters of `space`, at most [`MAX_PAIRS`], in
/// the order given) over `records` into `stem.png` and `stem.svg`, with `title` on top and
/// `note` (e.g. the parameters left out) under the matrix. Cell `(i, j)` has parameter `j`
/// along x and `i` along y: below the diagonal the tests, on the diagonal parameter `i`'s
/// failure rate per bin (`[0, 1]` up), above it the pair's failure rate per cell (white 0 % to
/// red 100 %, grey when empty). Bins adapt to the number of tests
/// ([`super::adaptive_bins`]). Axis titles with units and tick labels sit on the bottom row
/// and the left column. Size: 190 pixels per cell (230 with 3 parameters or fewer) plus
/// margins. Returns the two paths.
///
/// # Errors
/// [`PlotError::NotAnAxis`] when a name is not a parameter of `space`, [`PlotError::Axes`]
/// for no name or more than [`MAX_PAIRS`], [`PlotError::Draw`] when a file cannot be written.
pub fn pairs_plot(
    stem: &Path,
    space: &ParamSpace,
    names: &[String],
    title: &str,
    note: &str,
    records: &[RunRecord],
) -> Result<[PathBuf; 2], PlotError> {
    register_font();
    if names.is_empty() || names.len() > MAX_PAIRS {
        return Err(PlotError::Axes(names.len()));
    }
    let axes: Vec<Axis> = names
        .iter()
        .map(|n| Axis::of(space, n))
        .collect::<Result<_, _>>()?;
    let d = axes.len() as u32;
    let cell = if d <= 3 { 230 } else { 190 };
    let (left, bottom, top) = (95, 55, 70);
    let note_space = if note.is_empty() { 0 } else { 30 };
    // Wide enough for the key line above the matrix.
    let size = (
        (left + d * cell + 20).max(760),
        top + d * cell + bottom + note_space,
    );
    let n = records.len();
    // One continuous axis alone: about 5 tests per bin, at most 16.
    let diag_bins = (n / 5).clamp(2, 16);
    let pair_bins =
        |i: usize, j: usize| adaptive_bins(n, space, &[names[j].clone(), names[i].clone()]);
    let layout = Layout {
        axes: &axes,
        records,
        title,
        note,
        margins: (left, bottom + note_space, top),
        cell,
        diag_bins,
        pair_bins: &pair_bins,
    };
    png_and_svg(
        stem,
        size,
        |root| layout.draw(root),
        |root| layout.draw(root),
    )
}

struct Layout<'a> {
    axes: &'a [Axis],
    records: &'a [RunRecord],
    title: &'a str,
    note: &'a str,
    /// Left, bottom and top margins in pixels.
    margins: (u32, u32, u32),
    /// A cell's side in pixels.
    cell: u32,
    diag_bins: usize,
    pair_bins: &'a dyn Fn(usize, usize) -> usize,
}

impl Layout<'_> {
    fn draw<DB: DrawingBackend>(&self, root: DrawingArea<DB, Shift>) -> Result<(), DrawError> {
        root.fill(&WHITE)?;
        let (w, h) = root.dim_in_pixel();
        let (left, bottom, top) = self.margins;
        let d = self.axes.len();
        let fail = self
            .records
            .iter()
            .filter(|r| r.status == Status::Fail)
            .count();
        let pass = self
            .records
            .iter()
            .filter(|r| r.status == Status::Pass)
            .count();
        root.draw(&Text::new(
            self.title.to_owned(),
            (left as i32, 14),
            (FAMILY, 19).into_font(),
        ))?;
        root.draw(&Text::new(
            format!(
                "× failed ({fail})   ○ passed ({pass})   diagonal: failure rate per bin   above: failure rate per cell"
            ),
            (left as i32, 42),
            (FAMILY, 14).into_font().color(&BLACK.mix(0.8)),
        ))
        ?;
        if !self.note.is_empty() {
            root.draw(&Text::new(
                self.note.to_owned(),
                (left as i32, h as i32 - 22),
                (FAMILY, 14).into_font().color(&BLACK.mix(0.8)),
            ))?;
        }
        let right = w - left - d as u32 * self.cell;
        let matrix = root.margin(top, bottom, left, right);
        let cells = matrix.split_evenly((d, d));
        for (k, area) in cells.iter().enumerate() {
            let (i, j) = (k / d, k % d);
            self.cell(area, i, j).map_err(|m| DrawError::Cell {
                row: i,
                column: j,
                source: Box::new(m),
            })?;
        }
        let cw = f64::from(self.cell);
        let ch = f64::from(h - top - bottom) / d as f64;
        self.edges(&root, (f64::from(left), f64::from(top)), (cw, ch))?;
        root.present()?;
        Ok(())
    }

    /// Tick labels and axis titles along the bottom row and the left column, in the figure's
    /// pixels: the matrix starts at `origin` and its cells are `cell` pixels (a cell's plot
    /// sits 4 pixels inside it).
    fn edges<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        origin: (f64, f64),
        cell: (f64, f64),
    ) -> Result<(), DrawError> {
        let d = self.axes.len();
        let small = (FAMILY, 12).into_font().color(&BLACK);
        let title = (FAMILY, 14).into_font().color(&BLACK);
        let bottom = origin.1 + d as f64 * cell.1;
        let text = |t: String, at: (f64, f64), style: TextStyle<'_>| {
            root.draw(&Text::new(
                t,
                (at.0.round() as i32, at.1.round() as i32),
                style,
            ))
            .map_err(DrawError::from)
        };
        for (j, x) in self.axes.iter().enumerate() {
            let (x0, x1) = x.range();
            let left = origin.0 + j as f64 * cell.0 + 4.0;
            for (v, label) in ticks(x) {
                // A tick at the right end would run into the next column's first one.
                if j + 1 < d && v > x1 - 0.03 * (x1 - x0) {
                    continue;
                }
                let px = left + (v - x0) / (x1 - x0) * (cell.0 - 8.0);
                text(
                    label,
                    (px, bottom + 4.0),
                    small.clone().pos(Pos::new(HPos::Center, VPos::Top)),
                )?;
            }
            let centre = origin.0 + (j as f64 + 0.5) * cell.0;
            text(
                x.label(),
                (centre, bottom + 24.0),
                title.clone().pos(Pos::new(HPos::Center, VPos::Top)),
            )?;
        }
        for (i, y) in self.axes.iter().enumerate() {
            let (marks, label, (y0, y1)) = if i == 0 {
                (
                    vec![
                        (0.0, "0".to_owned()),
                        (0.5, "0.5".to_owned()),
                        (1.0, "1".to_owned()),
                    ],
                    "failure rate".to_owned(),
                    (0.0, 1.0),
                )
            } else {
                (ticks(y), y.label(), y.range())
            };
            let top = origin.1 + i as f64 * cell.1 + 4.0;
            for (v, t) in marks {
                // A tick at the top would run into the row above's last one.
                if i > 0 && v > y1 - 0.03 * (y1 - y0) {
                    continue;
                }
                let py = top + (cell.1 - 8.0) * (1.0 - (v - y0) / (y1 - y0));
                text(
                    t,
                    (origin.0 - 6.0, py),
                    small.clone().pos(Pos::new(HPos::Right, VPos::Center)),
                )?;
            }
            let centre = origin.1 + (i as f64 + 0.5) * cell.1;
            text(
                label,
                (origin.0 - 62.0, centre),
                title
                    .clone()
                    .transform(FontTransform::Rotate270)
                    .pos(Pos::new(HPos::Center, VPos::Center)),
            )?;
        }
        Ok(())
    }

    /// One cell: its frame, content, and the tick labels and titles of the edges it is on.
    fn cell<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        i: usize,
        j: usize,
    ) -> Result<(), DrawError> {
        let (x, y) = (&self.axes[j], &self.axes[i]);
        let ((x0, x1), (y0, y1)) = (x.range(), if i == j { (0.0, 1.0) } else { y.range() });
        let inner = area.margin(4, 4, 4, 4);
        let mut chart = ChartBuilder::on(&inner).build_cartesian_2d(x0..x1, y0..y1)?;
        chart.plotting_area().fill(&RGBColor(250, 250, 250))?;
        if i == j {
            self.histogram(&mut chart, x)?;
        } else if i > j {
            self.scatter(&mut chart, x, y)?;
        } else {
            self.rates(&mut chart, x, y, (self.pair_bins)(i, j))?;
        }
        // Frame.
        chart.draw_series(std::iter::once(Rectangle::new(
            [(x0, y0), (x1, y1)],
            BLACK.mix(0.5).stroke_width(1),
        )))?;
        // The diagonal names its parameter inside the cell.
        if i == j {
            inner.draw(&Text::new(
                x.label(),
                (6, 6),
                (FAMILY, 13).into_font().color(&BLACK),
            ))?;
        }
        Ok(())
    }

    fn scatter<DB: DrawingBackend>(
        &self,
        chart: &mut ChartContext<
            '_,
            DB,
            Cartesian2d<
                plotters::coord::types::RangedCoordf64,
                plotters::coord::types::RangedCoordf64,
            >,
        >,
        x: &Axis,
        y: &Axis,
    ) -> Result<(), DrawError> {
        let at = |r: &RunRecord| -> Option<(f64, f64)> { Some((x.coord(r, 1)?, y.coord(r, 2)?)) };
        let of = |s: Status| -> Vec<(f64, f64)> {
            self.records
                .iter()
                .filter(|r| r.status == s)
                .filter_map(at)
                .collect()
        };
        // Dense campaigns get smaller, lighter marks so that the cells do not fill up.
        let dense = self.records.len() > 2000;
        let (r_pass, r_fail, a_pass) = if dense { (1, 2, 0.35) } else { (2, 3, 0.8) };
        chart.draw_series(
            of(Status::Pass)
                .into_iter()
                .map(|p| Circle::new(p, r_pass, BLUE.mix(a_pass).stroke_width(1))),
        )?;
        chart.draw_series(
            of(Status::Fail)
                .into_iter()
                .map(|p| Cross::new(p, r_fail, RED.stroke_width(1))),
        )?;
        Ok(())
    }

    fn histogram<DB: DrawingBackend>(
        &self,
        chart: &mut ChartContext<
            '_,
            DB,
            Cartesian2d<
                plotters::coord::types::RangedCoordf64,
                plotters::coord::types::RangedCoordf64,
            >,
        >,
        x: &Axis,
    ) -> Result<(), DrawError> {
        let bins = x.bins(self.diag_bins);
        let mut cells = vec![(0u32, 0u32); bins];
        for r in self.records {
            if let Some(b) = x.bin(r, self.diag_bins) {
                cells[b].0 += u32::from(r.status == Status::Fail);
                cells[b].1 += 1;
            }
        }
        chart.draw_series(cells.iter().enumerate().map(|(k, &(f, n))| {
            let (a, b) = x.bin_span(k, bins);
            let rate = if n == 0 {
                0.0
            } else {
                f64::from(f) / f64::from(n)
            };
            Rectangle::new([(a, 0.0), (b, rate)], RED.mix(0.75).filled())
        }))?;
        chart.draw_series(cells.iter().enumerate().map(|(k, &(f, n))| {
            let (a, b) = x.bin_span(k, bins);
            let rate = if n == 0 {
                0.0
            } else {
                f64::from(f) / f64::from(n)
            };
            Rectangle::new([(a, 0.0), (b, rate)], WHITE.stroke_width(1))
        }))?;
        Ok(())
    }

    fn rates<DB: DrawingBackend>(
        &self,
        chart: &mut ChartContext<
            '_,
            DB,
            Cartesian2d<
                plotters::coord::types::RangedCoordf64,
                plotters::coord::types::RangedCoordf64,
            >,
        >,
        x: &Axis,
        y: &Axis,
        bins: usize,
    ) -> Result<(), DrawError> {
        let (columns, rows) = (x.bins(bins), y.bins(bins));
        let mut cells = vec![(0u32, 0u32); columns * rows];
        for r in self.records {
            if let (Some(cx), Some(cy)) = (x.bin(r, bins), y.bin(r, bins)) {
                cells[cy * columns + cx].0 += u32::from(r.status == Status::Fail);
                cells[cy * columns + cx].1 += 1;
            }
        }
        chart.draw_series(cells.iter().enumerate().map(|(k, &(f, n))| {
            let (a, b) = x.bin_span(k % columns, columns);
            let (c, e) = y.bin_span(k / columns, rows);
            Rectangle::new([(a, c), (b, e)], rate_color(f, n).filled())
        }))?;
        Ok(())
    }
}

/// Tick positions and labels of an axis: its levels, or about 4 round values of its interval.
fn ticks(a: &Axis) -> Vec<(f64, String)> {
    if let Some(c) = a.categories() {
        return (0..c.len())
            .map(|k| (k as f64, category_label(&c, k as f64)))
            .collect();
    }
    let (lo, hi) = a.range();
    let raw = (hi - lo) / 4.0;
    if !(raw.is_finite() && raw > 0.0) {
        return Vec::new();
    }
    let mag = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 2.5, 5.0, 10.0]
        .iter()
        .map(|m| m * mag)
        .find(|s| *s >= raw)
        .unwrap_or(10.0 * mag);
    let decimals =
        (-step.log10().floor()).max(0.0) as usize + usize::from((step / mag - 2.5).abs() < 1e-9);
    let mut out = Vec::new();
    let mut v = (lo / step).ceil() * step;
    while v <= hi + 1e-9 * step {
        out.push((v, format!("{v:.decimals$}")));
        v += step;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use paracosm_generators::{Param, Point, Value};

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

    fn records(s: &ParamSpace, n: u64) -> Vec<RunRecord> {
        (0..n)
            .map(|id| {
                let u = [(id as f64 * 0.618) % 1.0, (id as f64 * 0.382) % 1.0];
                let point = Point {
                    discrete: vec![(id % 2) as u32],
                    continuous: u.to_vec(),
                };
                RunRecord {
                    passive: Vec::new(),
                    campaign: None,
                    id,
                    seed: 0,
                    strategy: "random".into(),
                    params: s.decode(&point).ok(),
                    point,
                    status: if u[0] > 0.7 {
                        Status::Fail
                    } else {
                        Status::Pass
                    },
                    monitors: vec![],
                    metrics: vec![],
                    error: None,
                    log: Vec::new(),
                    wall_ms: 0.0,
                }
            })
            .collect()
    }

    #[test]
    fn draws_every_pair_with_labelled_edges_and_the_note() {
        let s = space();
        let r = records(&s, 60);
        let dir = tempfile::tempdir().unwrap();
        let names: Vec<String> = ["speed", "colour", "dist"].map(String::from).to_vec();
        let [png, svg] = pairs_plot(
            &dir.path().join("pairs"),
            &s,
            &names,
            "t",
            "not shown: x, y",
            &r,
        )
        .unwrap();
        assert!(png.exists());
        let svg = std::fs::read_to_string(svg).unwrap();
        for text in [
            "speed [m/s]",
            "dist [m]",
            "colour",
            "red",
            "white",
            "not shown: x, y",
            "failure rate",
        ] {
            assert!(svg.contains(text), "missing {text}");
        }
        let fails = r.iter().filter(|r| r.status == Status::Fail).count();
        assert!(svg.contains(&format!("× failed ({fails})")));
        // Three cells below the diagonal each draw every test.
        let circles = svg.matches("<circle").count();
        assert_eq!(circles, 3 * (60 - fails));
    }

    #[test]
    fn too_many_or_unknown_names_are_errors() {
        let s = space();
        let dir = tempfile::tempdir().unwrap();
        let nine: Vec<String> = (0..9).map(|_| "speed".to_owned()).collect();
        let stem = dir.path().join("p");
        assert!(matches!(
            pairs_plot(&stem, &s, &nine, "", "", &[]),
            Err(PlotError::Axes(9))
        ));
        assert!(matches!(
            pairs_plot(&stem, &s, &["nope".to_owned()], "", "", &[]),
            Err(PlotError::NotAnAxis(_))
        ));
    }

    #[test]
    fn ticks_are_round_numbers_inside_the_range() {
        let s = space();
        let t = ticks(&Axis::of(&s, "dist").unwrap());
        let labels: Vec<&str> = t.iter().map(|(_, l)| l.as_str()).collect();
        assert_eq!(labels, ["20", "40", "60"]);
        let t = ticks(&Axis::of(&s, "speed").unwrap());
        let labels: Vec<&str> = t.iter().map(|(_, l)| l.as_str()).collect();
        assert_eq!(labels, ["0.0", "2.5", "5.0", "7.5", "10.0"]);
    }
}
