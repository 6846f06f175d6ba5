//! Plots of measured values rather than verdicts: points coloured by a value over two axes
//! ([`value_map`]), and series of `(x, y)` pairs as lines or points ([`xy_plot`]). The
//! figures of the paper's §4.2.2 studies with a learned driver (PARACOSM Figure 10) use them.

use std::path::{Path, PathBuf};

use plotters::coord::Shift;
use plotters::prelude::*;

use super::{png_and_svg, register_font, DrawError, PlotError, FAMILY};

/// One point of a [`value_map`]: its place `(x, y)`, the value its colour shows, and whether
/// it is marked (drawn as a red cross over the colour: a collision, say).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ValuePoint {
    /// Place on the x axis, in the axis' unit.
    pub x: f64,
    /// Place on the y axis, in the axis' unit.
    pub y: f64,
    /// The value shown by the colour; NaN is drawn grey.
    pub value: f64,
    /// Whether a red cross marks the point.
    pub marked: bool,
}

/// The axes and legends of a [`value_map`].
#[derive(Debug, Clone, PartialEq)]
pub struct ValueMapLabels {
    /// The caption on top.
    pub title: String,
    /// The x axis' name with its unit.
    pub x: String,
    /// The y axis' name with its unit.
    pub y: String,
    /// The colour bar's name with its unit.
    pub value: String,
    /// The legend of the red crosses.
    pub marked: String,
}

/// [`PlotError::Draw`] for `stem` unless every range `(lo, hi)` is finite with `lo < hi`.
fn check_ranges(stem: &Path, ranges: &[(f64, f64)]) -> Result<(), PlotError> {
    match ranges
        .iter()
        .find(|(lo, hi)| !(lo.is_finite() && hi.is_finite() && lo < hi))
    {
        Some((lo, hi)) => Err(PlotError::Draw {
            path: stem.to_path_buf(),
            reason: format!("the range [{lo}, {hi}] is empty or not finite"),
        }),
        None => Ok(()),
    }
}

/// A sequential scale from pale yellow (`t = 0`) through green to dark blue (`t = 1`), close
/// to viridis read backwards; `t` is clamped to `[0, 1]`.
fn sequential(t: f64) -> RGBColor {
    const STOPS: [(f64, (f64, f64, f64)); 4] = [
        (0.0, (253.0, 231.0, 37.0)),
        (0.35, (94.0, 201.0, 98.0)),
        (0.7, (33.0, 145.0, 140.0)),
        (1.0, (59.0, 82.0, 139.0)),
    ];
    let t = t.clamp(0.0, 1.0);
    let k = STOPS.iter().rposition(|(s, _)| *s <= t).unwrap_or(0).min(2);
    let ((s0, a), (s1, b)) = (STOPS[k], STOPS[k + 1]);
    let u = (t - s0) / (s1 - s0);
    let mix = |p: f64, q: f64| (p + u * (q - p)).round() as u8;
    RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

/// Points over `x_range × y_range`, each a filled disc coloured by its value on a sequential
/// scale from `value_range.0` (pale yellow) to `value_range.1` (dark blue), with a red cross
/// over the marked ones and a colour bar on the right. Writes `stem.png` and `stem.svg`
/// (860 × 640 pixels) and returns their paths.
///
/// # Errors
/// [`PlotError::Draw`] when a file cannot be written or a range is empty or not finite.
pub fn value_map(
    stem: &Path,
    labels: &ValueMapLabels,
    (x_range, y_range, value_range): ((f64, f64), (f64, f64), (f64, f64)),
    points: &[ValuePoint],
) -> Result<[PathBuf; 2], PlotError> {
    register_font();
    check_ranges(stem, &[x_range, y_range, value_range])?;
    let ranges = (x_range, y_range, value_range);
    png_and_svg(
        stem,
        (860, 640),
        |root| draw_value_map(root, labels, ranges, points),
        |root| draw_value_map(root, labels, ranges, points),
    )
}

fn draw_value_map<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    labels: &ValueMapLabels,
    (x_range, y_range, (v0, v1)): ((f64, f64), (f64, f64), (f64, f64)),
    points: &[ValuePoint],
) -> Result<(), DrawError> {
    root.fill(&WHITE)?;
    let (main, bar) = root.split_horizontally(750);
    let mut chart = ChartBuilder::on(&main)
        .caption(&labels.title, (FAMILY, 18))
        .margin(12)
        .x_label_area_size(45)
        .y_label_area_size(55)
        .build_cartesian_2d(x_range.0..x_range.1, y_range.0..y_range.1)?;
    chart
        .configure_mesh()
        .x_desc(&labels.x)
        .y_desc(&labels.y)
        .label_style((FAMILY, 13))
        .axis_desc_style((FAMILY, 15))
        .light_line_style(WHITE.mix(0.0))
        .draw()?;
    let colour = |v: f64| {
        if v.is_nan() {
            RGBColor(160, 160, 160)
        } else {
            sequential((v - v0) / (v1 - v0))
        }
    };
    chart.draw_series(
        points
            .iter()
            .map(|p| Circle::new((p.x, p.y), 5, colour(p.value).filled())),
    )?;
    let marked: Vec<&ValuePoint> = points.iter().filter(|p| p.marked).collect();
    let red = RGBColor(214, 39, 40);
    chart
        .draw_series(
            marked
                .iter()
                .map(|p| Cross::new((p.x, p.y), 5, red.stroke_width(2))),
        )?
        .label(format!("{} ({})", labels.marked, marked.len()))
        .legend(move |p| Cross::new(p, 5, red.stroke_width(2)));
    super::draw_legend(&mut chart)?;
    let mut scale = ChartBuilder::on(&bar)
        .margin_top(45)
        .margin_bottom(57)
        .margin_right(8)
        .y_label_area_size(0)
        .right_y_label_area_size(60)
        .build_cartesian_2d(0.0..1.0, v0..v1)?;
    scale
        .configure_mesh()
        .disable_mesh()
        .disable_x_axis()
        .y_desc(&labels.value)
        .label_style((FAMILY, 12))
        .axis_desc_style((FAMILY, 13))
        .draw()?;
    let steps = 60;
    scale.draw_series((0..steps).map(|k| {
        let lo = v0 + (v1 - v0) * k as f64 / steps as f64;
        let hi = v0 + (v1 - v0) * (k + 1) as f64 / steps as f64;
        Rectangle::new(
            [(0.0, lo), (1.0, hi)],
            sequential((k as f64 + 0.5) / steps as f64).filled(),
        )
    }))?;
    root.present()?;
    Ok(())
}

/// How [`xy_plot`] draws its series.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum XyStyle {
    /// Each series a line through its pairs in order.
    Lines,
    /// Each pair a dot.
    Points,
}

/// One series of [`xy_plot`]: its legend and its `(x, y)` pairs, in the axes' units.
pub type Series = (String, Vec<(f64, f64)>);

/// Series of `(x, y)` pairs over `x_range × y_range`, in the category-10 colours in order,
/// with a legend; `title` on top and the axes named `x_label`, `y_label` (with their units).
/// Writes `stem.png` and `stem.svg` (860 × 600 pixels) and returns their paths.
///
/// # Errors
/// [`PlotError::Draw`] when a file cannot be written or a range is empty or not finite.
pub fn xy_plot(
    stem: &Path,
    (title, x_label, y_label): (&str, &str, &str),
    (x_range, y_range): ((f64, f64), (f64, f64)),
    series: &[Series],
    style: XyStyle,
) -> Result<[PathBuf; 2], PlotError> {
    register_font();
    check_ranges(stem, &[x_range, y_range])?;
    let texts = (title, x_label, y_label);
    png_and_svg(
        stem,
        (860, 600),
        |root| draw_xy(root, texts, (x_range, y_range), series, style),
        |root| draw_xy(root, texts, (x_range, y_range), series, style),
    )
}

/// The category-10 palette (matplotlib's default cycle).
const PALETTE: [RGBColor; 6] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(255, 127, 14),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
];

fn draw_xy<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    (title, x_label, y_label): (&str, &str, &str),
    (x_range, y_range): ((f64, f64), (f64, f64)),
    series: &[Series],
    style: XyStyle,
) -> Result<(), DrawError> {
    root.fill(&WHITE)?;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, (FAMILY, 18))
        .margin(12)
        .x_label_area_size(45)
        .y_label_area_size(55)
        .build_cartesian_2d(x_range.0..x_range.1, y_range.0..y_range.1)?;
    chart
        .configure_mesh()
        .x_desc(x_label)
        .y_desc(y_label)
        .label_style((FAMILY, 13))
        .axis_desc_style((FAMILY, 15))
        .light_line_style(WHITE.mix(0.0))
        .draw()?;
    for (k, (name, pairs)) in series.iter().enumerate() {
        let c = PALETTE[k % PALETTE.len()];
        let drawn = match style {
            XyStyle::Lines => {
                chart.draw_series(LineSeries::new(pairs.iter().copied(), c.stroke_width(2)))?
            }
            XyStyle::Points => {
                chart.draw_series(pairs.iter().map(|&p| Circle::new(p, 4, c.filled())))?
            }
        };
        drawn
            .label(name.as_str())
            .legend(move |(x, y)| Rectangle::new([(x, y - 4), (x + 14, y + 4)], c.filled()));
    }
    super::draw_legend(&mut chart)?;
    root.present()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_sequential_scale_runs_from_yellow_to_blue_and_clamps() {
        assert_eq!(sequential(0.0), RGBColor(253, 231, 37));
        assert_eq!(sequential(1.0), RGBColor(59, 82, 139));
        assert_eq!(sequential(-3.0), sequential(0.0));
        assert_eq!(sequential(7.0), sequential(1.0));
        // Monotone in blue-ness along the way: red falls from the first stop on.
        let reds: Vec<u8> = (0..=10).map(|k| sequential(k as f64 / 10.0).0).collect();
        assert!(reds.windows(2).take(7).all(|w| w[0] >= w[1]), "{reds:?}");
    }

    #[test]
    fn both_plots_write_png_and_svg_and_refuse_empty_ranges() {
        let dir = tempfile::tempdir().unwrap();
        let labels = ValueMapLabels {
            title: "t".into(),
            x: "light".into(),
            y: "fog".into(),
            value: "distance covered, m".into(),
            marked: "collision".into(),
        };
        let points: Vec<ValuePoint> = (0..20)
            .map(|k| ValuePoint {
                x: k as f64 / 20.0,
                y: (k * 7 % 20) as f64 / 20.0,
                value: k as f64,
                marked: k % 3 == 0,
            })
            .collect();
        let [png, svg] = value_map(
            &dir.path().join("m"),
            &labels,
            ((0.0, 1.0), (0.0, 1.0), (0.0, 19.0)),
            &points,
        )
        .unwrap();
        assert!(std::fs::metadata(&png).unwrap().len() > 3_000);
        assert!(std::fs::read_to_string(&svg)
            .unwrap()
            .contains("collision (7)"));
        let series = vec![
            ("series-alpha".to_owned(), vec![(0.0, 1.0), (1.0, 2.0)]),
            ("series-beta".to_owned(), vec![(0.0, 2.0), (1.0, 0.5)]),
        ];
        for style in [XyStyle::Lines, XyStyle::Points] {
            let [png, svg] = xy_plot(
                &dir.path().join("s"),
                ("t", "time, s", "speed, m/s"),
                ((0.0, 1.0), (0.0, 3.0)),
                &series,
                style,
            )
            .unwrap();
            assert!(std::fs::metadata(&png).unwrap().len() > 3_000);
            let text = std::fs::read_to_string(&svg).unwrap();
            assert!(text.contains("series-alpha") && text.contains("series-beta"));
        }
        let e = xy_plot(
            &dir.path().join("e"),
            ("t", "x", "y"),
            ((1.0, 1.0), (0.0, 1.0)),
            &series,
            XyStyle::Lines,
        )
        .unwrap_err();
        assert!(e.to_string().contains("[1, 1] is empty"), "{e}");
    }
}
