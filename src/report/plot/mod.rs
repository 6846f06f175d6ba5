//! Plots, as PNG and SVG, drawn with `plotters` and a bundled font so that they render on
//! machines without system fonts: the failure map and the failure-rate heat map over any one
//! or two parameters, continuous or discrete ([`map`]), the scatterplot matrix of every
//! parameter ([`pairs_plot`]), contact sheets of camera frames
//! ([`sheet`]), box plots ([`boxes`]), and measured values over two axes or as series
//! ([`value_map`], [`xy_plot`]).

mod axis;
mod boxes;
mod map;
mod pairs;
mod road_map;
mod series;
mod sheet;

use std::path::{Path, PathBuf};
use std::sync::Once;

use image::ImageEncoder;
use plotters::coord::Shift;
use plotters::prelude::*;
use thiserror::Error;

pub use boxes::{box_plot, BoxPanel};
pub(crate) use map::robustness_span;
pub use map::{
    adaptive_bins, failure_map, failure_rate_map, failure_rates, Coloring, RateGrid,
    UnknownColoring,
};
pub use pairs::{pairs_plot, MAX_PAIRS};
pub use road_map::{road_map_png, road_map_svg, MapMark, RoadMapDrawing};
pub use series::{value_map, xy_plot, Series, ValueMapLabels, ValuePoint, XyStyle};
pub use sheet::contact_sheet;

/// DejaVu Sans (Bitstream Vera license, see `assets/fonts/LICENSE`), bundled so plots draw on
/// a machine with no fonts installed.
static FONT: &[u8] = include_bytes!("../../../assets/fonts/DejaVuSans.ttf");
const FAMILY: &str = "sans-serif";

/// Errors drawing a plot.
#[derive(Debug, Error)]
pub enum PlotError {
    /// An axis names no parameter of the space.
    #[error("cannot plot `{0}`: it is not a parameter of the scenario")]
    NotAnAxis(String),
    /// An interval so wide that `hi - lo` overflows (e.g. `[-1e308, 1e308]`): no axis can
    /// be drawn over it.
    #[error(
        "cannot plot `{name}`: its range [{lo:e}, {hi:e}] is wider than a 64-bit float can \
         measure (hi - lo overflows)"
    )]
    Span {
        /// The parameter.
        name: String,
        /// Its lower bound.
        lo: f64,
        /// Its upper bound.
        hi: f64,
    },
    /// A map over no parameter, or over more than two.
    #[error("a failure map has one or two axes, got {0}")]
    Axes(usize),
    /// The drawing backend failed (usually: the file cannot be written).
    #[error("cannot draw `{path}`: {reason}")]
    Draw {
        /// The file being drawn.
        path: PathBuf,
        /// The backend's reason.
        reason: String,
    },
}

impl From<PlotError> for crate::Error {
    fn from(e: PlotError) -> Self {
        crate::Error::Plot(e.to_string())
    }
}

/// Why drawing a figure onto a backend failed, before [`png_and_svg`] names the file
/// ([`PlotError::Draw`]).
#[derive(Debug, Error)]
enum DrawError {
    /// The backend's reason, as it words it (its error type is the backend's own, which the
    /// drawing code is generic over).
    #[error("{0}")]
    Backend(String),
    /// Cell `(row, column)` of a scatterplot matrix could not be drawn.
    #[error("cell ({row}, {column}): {source}")]
    Cell {
        /// The cell's row.
        row: usize,
        /// The cell's column.
        column: usize,
        /// Why.
        source: Box<DrawError>,
    },
}

impl<E: std::error::Error + Send + Sync> From<DrawingAreaErrorKind<E>> for DrawError {
    fn from(e: DrawingAreaErrorKind<E>) -> Self {
        DrawError::Backend(e.to_string())
    }
}

/// Draws a chart's series legend the one way every plot here draws it: upper right, on a
/// translucent white box with a black border.
fn draw_legend<'a, DB: DrawingBackend + 'a, CT: plotters::coord::CoordTranslate>(
    chart: &mut ChartContext<'a, DB, CT>,
) -> Result<(), DrawError> {
    chart
        .configure_series_labels()
        .label_font((FAMILY, 14))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(SeriesLabelPosition::UpperRight)
        .draw()?;
    Ok(())
}

fn register_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // The bundled file is a valid TrueType font; a failure would only lose the labels.
        let _ = plotters::style::register_font(FAMILY, FontStyle::Normal, FONT);
    });
}

/// Draws one figure of `size` pixels into `stem.png` and `stem.svg`, each through a temporary
/// file and a rename, so a failed write leaves any earlier plot whole. `png` and `svg` are the
/// same drawing code on the two backends. Returns the two paths.
fn png_and_svg(
    stem: &Path,
    size: (u32, u32),
    png: impl Fn(DrawingArea<BitMapBackend<'_>, Shift>) -> Result<(), DrawError>,
    svg: impl Fn(DrawingArea<SVGBackend<'_>, Shift>) -> Result<(), DrawError>,
) -> Result<[PathBuf; 2], PlotError> {
    let (png_path, svg_path) = (stem.with_extension("png"), stem.with_extension("svg"));
    write_png(&png_path, size, png)?;
    write_svg(&svg_path, size, svg)?;
    Ok([png_path, svg_path])
}

/// Draws one figure of `size` pixels with `draw` into the PNG file `path`, through a
/// temporary file and a rename.
fn write_png(
    path: &Path,
    size: (u32, u32),
    draw: impl FnOnce(DrawingArea<BitMapBackend<'_>, Shift>) -> Result<(), DrawError>,
) -> Result<(), PlotError> {
    let failed = |reason: String| PlotError::Draw {
        path: path.to_path_buf(),
        reason,
    };
    // Drawn into memory, then encoded with the best compression (plots are mostly flat
    // colour; this halves a busy pairs plot, which the web report embeds).
    let mut pixels = vec![0u8; size.0 as usize * size.1 as usize * 3];
    draw(BitMapBackend::with_buffer(&mut pixels, size).into_drawing_area())
        .map_err(|e| failed(e.to_string()))?;
    let mut encoded = Vec::new();
    image::codecs::png::PngEncoder::new_with_quality(
        &mut encoded,
        image::codecs::png::CompressionType::Best,
        image::codecs::png::FilterType::Adaptive,
    )
    .write_image(&pixels, size.0, size.1, image::ColorType::Rgb8)
    .map_err(|e| failed(e.to_string()))?;
    crate::atomic::write(path, &encoded).map_err(|e| failed(e.to_string()))
}

/// Draws one figure of `size` pixels with `draw` into the SVG file `path`, through a
/// temporary file and a rename.
fn write_svg(
    path: &Path,
    size: (u32, u32),
    draw: impl FnOnce(DrawingArea<SVGBackend<'_>, Shift>) -> Result<(), DrawError>,
) -> Result<(), PlotError> {
    crate::atomic::with_temp(path, |tmp| {
        draw(SVGBackend::new(tmp, size).into_drawing_area())
    })
    .map_err(|e| PlotError::Draw {
        path: path.to_path_buf(),
        reason: e.to_string(),
    })
}
