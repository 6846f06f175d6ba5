//! An OpenDRIVE map drawn top-down (`paracosm-fuzz map --png/--svg`, `report --on-map`):
//! every lane as a filled strip coloured by its type, connecting roads of junctions shaded
//! apart, a white arrow every ~90 px along each driving lane in its direction of travel, the
//! centre lane (lane 0) of each road in yellow with a tick every round number of metres and a
//! black dot where `s = 0`, each road's id in a box at its middle and each junction's id at
//! its centre; and, over it, points such as where each test's actor started, by outcome.
//!
//! Coordinates are the file's own (OpenDRIVE `x` right, `y` up, in metres): a map the importer
//! moved to the origin is drawn where the file puts it.

use std::path::{Path, PathBuf};

use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use paracosm_engine::network::{MapLane, RoadMap};

use super::{register_font, DrawError, PlotError, FAMILY};
use crate::record::Status;

/// The longer side of the drawing's plot area, px.
const LONG_SIDE_PX: f64 = 1400.0;
/// Pixels between two direction arrows along a lane.
const ARROW_EVERY_PX: f64 = 90.0;
/// The smallest gap between two ticks of a centre lane, px.
const TICK_GAP_PX: f64 = 45.0;

/// A point drawn over the map: where (world `[x, z]` m, as [`MapLane::centre`]) and the
/// outcome it is coloured by.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MapMark {
    /// Where, world `[x, z]` m.
    pub at_m: [f64; 2],
    /// The test's outcome: a red cross for `fail`, a blue circle for `pass`, a grey triangle
    /// for `error`.
    pub status: Status,
}

/// What a road-map drawing shows.
#[derive(Debug, Clone, Copy)]
pub struct RoadMapDrawing<'a> {
    /// The map.
    pub map: &'a RoadMap,
    /// The title above it.
    pub title: &'a str,
    /// Points drawn over it (none for a bare map).
    pub marks: &'a [MapMark],
    /// What the points are, for the legend (e.g. "where the ego starts").
    pub marks_label: &'a str,
}

/// Draws `d` into the PNG file `path` (through a temporary file and a rename).
///
/// # Errors
/// [`PlotError::Draw`] naming `path` when it cannot be drawn or written.
pub fn road_map_png(d: &RoadMapDrawing<'_>, path: &Path) -> Result<PathBuf, PlotError> {
    register_font();
    let frame = Frame::of(d.map);
    super::write_png(path, frame.size_px(), |root| render(root, d, &frame))?;
    Ok(path.to_path_buf())
}

/// Draws `d` into the SVG file `path` (through a temporary file and a rename).
///
/// # Errors
/// [`PlotError::Draw`] naming `path` when it cannot be drawn or written.
pub fn road_map_svg(d: &RoadMapDrawing<'_>, path: &Path) -> Result<PathBuf, PlotError> {
    register_font();
    let frame = Frame::of(d.map);
    super::write_svg(path, frame.size_px(), |root| render(root, d, &frame))?;
    Ok(path.to_path_buf())
}

/// The drawn region, in the file's coordinates (m), and the map's shift to them.
struct Frame {
    lo: [f64; 2],
    hi: [f64; 2],
    origin: [f64; 2],
}

impl Frame {
    /// Every lane of `map` with a margin, no side shorter than a third of the other.
    fn of(map: &RoadMap) -> Frame {
        let (lo, hi) = map.bounds_m();
        let origin = map.origin_m;
        // World (x, z) to the file's (x, y): y = -z.
        let (mut lo, mut hi) = (
            [lo[0] + origin[0], -hi[1] + origin[1]],
            [hi[0] + origin[0], -lo[1] + origin[1]],
        );
        let long = (hi[0] - lo[0]).max(hi[1] - lo[1]).max(10.0);
        for k in 0..2 {
            let want = (hi[k] - lo[k]).max(long / 3.0) + (0.04 * long).max(4.0);
            let mid = (lo[k] + hi[k]) / 2.0;
            (lo[k], hi[k]) = (mid - want / 2.0, mid + want / 2.0);
        }
        Frame { lo, hi, origin }
    }

    /// The image's size, px: the plot area's longer side [`LONG_SIDE_PX`], plus the title,
    /// legend and axes.
    fn size_px(&self) -> (u32, u32) {
        let (w, h) = (self.hi[0] - self.lo[0], self.hi[1] - self.lo[1]);
        let scale = LONG_SIDE_PX / w.max(h);
        ((w * scale) as u32 + 100, (h * scale) as u32 + 150)
    }

    /// A world point `[x, z]` in the file's coordinates.
    fn xy(&self, p: [f64; 2]) -> (f64, f64) {
        (p[0] + self.origin[0], -p[1] + self.origin[1])
    }
}

type Chart<'a, DB> = ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// Draws the whole figure onto `root`.
fn render<DB: DrawingBackend>(
    root: DrawingArea<DB, Shift>,
    d: &RoadMapDrawing<'_>,
    frame: &Frame,
) -> Result<(), DrawError> {
    root.fill(&WHITE)?;
    let area = root.titled(d.title, (FAMILY, 22))?;
    let lines = legend_lines(d);
    let (legend, area) = area.split_vertically(8 + 18 * lines.len() as u32);
    for (i, line) in lines.iter().enumerate() {
        legend.draw(&Text::new(
            line.as_str(),
            (12, 4 + 18 * i as i32),
            (FAMILY, 14).into_font().color(&RGBColor(60, 60, 60)),
        ))?;
    }
    // Equal metres per pixel along both axes, whatever the label areas took.
    let (margin, x_labels, y_labels) = (12u32, 40u32, 70u32);
    let (w, h) = area.dim_in_pixel();
    let (pw, ph) = (
        f64::from(w.saturating_sub(2 * margin + y_labels).max(10)),
        f64::from(h.saturating_sub(2 * margin + x_labels).max(10)),
    );
    let m_per_px = ((frame.hi[0] - frame.lo[0]) / pw).max((frame.hi[1] - frame.lo[1]) / ph);
    let (cx, cy) = (
        (frame.lo[0] + frame.hi[0]) / 2.0,
        (frame.lo[1] + frame.hi[1]) / 2.0,
    );
    let mut chart = ChartBuilder::on(&area)
        .margin(margin)
        .x_label_area_size(x_labels)
        .y_label_area_size(y_labels)
        .build_cartesian_2d(
            (cx - pw * m_per_px / 2.0)..(cx + pw * m_per_px / 2.0),
            (cy - ph * m_per_px / 2.0)..(cy + ph * m_per_px / 2.0),
        )?;
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc("x (m)")
        .y_desc("y (m)")
        .label_style((FAMILY, 13))
        .axis_desc_style((FAMILY, 15))
        .draw()?;
    let px = 1.0 / m_per_px;
    draw_lanes(&mut chart, d.map, frame, px)?;
    draw_centre_lanes(&mut chart, d.map, frame, px)?;
    draw_labels(&mut chart, d.map, frame, px)?;
    if !d.marks.is_empty() {
        draw_marks(&mut chart, d, frame)?;
    }
    root.present()?;
    Ok(())
}

/// The lines under the title that say what the colours and marks are.
fn legend_lines(d: &RoadMapDrawing<'_>) -> Vec<String> {
    let mut lines = vec![format!(
        "dark grey: driving lanes, white arrows: direction of travel; brown: junctions' connecting roads; tan: sidewalks; light grey: other lanes; yellow: lane 0 (s = 0 at the black dot, a tick every {} m); boxes: road ids",
        tick_step_m(&Frame::of(d.map))
    )];
    if !d.marks.is_empty() {
        lines.push(format!("points: {}", d.marks_label));
    }
    lines
}

/// A lane's fill: by type, connecting roads of junctions in shades of brown.
fn fill(lane: &MapLane, in_junction: bool) -> RGBColor {
    match (in_junction, lane.drivable, lane.kind.as_str()) {
        (true, true, _) => RGBColor(140, 104, 52),
        (false, true, _) => RGBColor(78, 78, 84),
        (_, false, "sidewalk" | "walking" | "curb") => RGBColor(218, 204, 172),
        (_, false, "none") => RGBColor(232, 232, 232),
        (true, false, _) => RGBColor(214, 186, 140),
        (false, false, _) => RGBColor(176, 176, 176),
    }
}

/// The stations of `lane` at least `gap_m` apart (the first and last always).
fn thinned(lane: &MapLane, gap_m: f64) -> Vec<usize> {
    let mut kept = vec![0];
    let last = lane.centre.len() - 1;
    for i in 1..last {
        let a = lane.centre[kept[kept.len() - 1]];
        let b = lane.centre[i];
        if (b[0] - a[0]).hypot(b[1] - a[1]) >= gap_m {
            kept.push(i);
        }
    }
    if last > 0 {
        kept.push(last);
    }
    kept
}

/// The strip of `lane` as a closed outline in the file's coordinates: its left edge, then its
/// right edge backwards.
fn strip(lane: &MapLane, frame: &Frame, gap_m: f64) -> Vec<(f64, f64)> {
    let stations = thinned(lane, gap_m);
    let edge = |i: usize, side: f64| {
        let (c, r, w) = (lane.centre[i], lane.right(i), lane.width[i] / 2.0);
        frame.xy([c[0] + side * r[0] * w, c[1] + side * r[1] * w])
    };
    let mut outline: Vec<(f64, f64)> = stations.iter().map(|&i| edge(i, -1.0)).collect();
    outline.extend(stations.iter().rev().map(|&i| edge(i, 1.0)));
    outline
}

/// Every lane's strip (roads outside junctions first, connecting roads over them), and the
/// direction arrows of the driving lanes outside junctions. `px`: pixels per metre.
fn draw_lanes<DB: DrawingBackend>(
    chart: &mut Chart<'_, DB>,
    map: &RoadMap,
    frame: &Frame,
    px: f64,
) -> Result<(), DrawError> {
    let in_junction = |l: &MapLane| map.roads[l.road].junction.is_some();
    let gap_m = 1.5 / px;
    for junctions in [false, true] {
        let lanes: Vec<&MapLane> = map
            .lanes
            .iter()
            .filter(|l| in_junction(l) == junctions && l.centre.len() >= 2)
            .collect();
        chart.draw_series(
            lanes
                .iter()
                .map(|l| Polygon::new(strip(l, frame, gap_m), fill(l, junctions).filled())),
        )?;
        chart.draw_series(lanes.iter().map(|l| {
            let mut outline = strip(l, frame, gap_m);
            outline.push(outline[0]);
            PathElement::new(outline, WHITE.mix(0.35).stroke_width(1))
        }))?;
    }
    let arrows: Vec<Vec<(f64, f64)>> = map
        .lanes
        .iter()
        .filter(|l| l.drivable && !in_junction(l) && l.centre.len() >= 2)
        .flat_map(|l| arrows(l, frame, px))
        .collect();
    chart.draw_series(
        arrows
            .into_iter()
            .map(|a| PathElement::new(a, WHITE.stroke_width(2))),
    )?;
    Ok(())
}

/// The direction arrows of `lane`, each a polyline (barb, tip, barb, tip, tail), about one
/// every [`ARROW_EVERY_PX`], an even number of them on a lane longer than 60 px and one on a
/// lane longer than 12 px.
fn arrows(lane: &MapLane, frame: &Frame, px: f64) -> Vec<Vec<(f64, f64)>> {
    let (a, b) = lane.s_range();
    let length_px = (b - a) * px;
    let width_px = lane.width.iter().copied().fold(0.0, f64::max) * px;
    if length_px < 12.0 || width_px < 4.0 {
        return Vec::new();
    }
    let half_m = (0.32 * width_px).clamp(2.5, 9.0) / px;
    // An even count leaves the middle, where the road's label goes, free.
    let count = if length_px < 60.0 {
        1.0
    } else {
        2.0 * (length_px / ARROW_EVERY_PX / 2.0).floor().max(1.0)
    };
    let step = (b - a) / count;
    (0..count as usize)
        .map(|k| {
            let s = a + step * (k as f64 + 0.5);
            let (p, heading) = lane.pose(s);
            let (x, y) = frame.xy(p);
            let (dx, dy) = (heading.cos(), heading.sin());
            let tip = (x + dx * half_m, y + dy * half_m);
            let tail = (x - dx * half_m, y - dy * half_m);
            let barb = |side: f64| {
                (
                    tip.0 - dx * half_m * 0.8 - side * dy * half_m * 0.6,
                    tip.1 - dy * half_m * 0.8 + side * dx * half_m * 0.6,
                )
            };
            vec![barb(1.0), tip, barb(-1.0), tip, tail]
        })
        .collect()
}

/// The points of road `road`'s lane 0 (where `s` is measured, offset by any `<laneOffset>`)
/// as `(s, world [x, z])`, from the inner edge of its lane -1 or else lane 1, section by
/// section.
fn centre_lane(map: &RoadMap, road: usize) -> Vec<(f64, [f64; 2])> {
    let mut sections: Vec<&MapLane> = Vec::new();
    for l in map
        .lanes
        .iter()
        .filter(|l| l.road == road && l.od_id.abs() == 1)
    {
        match sections.iter_mut().find(|s| s.section == l.section) {
            Some(s) if s.od_id == 1 && l.od_id == -1 => *s = l,
            Some(_) => {}
            None => sections.push(l),
        }
    }
    sections.sort_by_key(|l| l.section);
    sections
        .iter()
        .flat_map(|l| {
            // Lane -1 lies right of lane 0 (its inner edge is to its left), lane 1 left of it.
            let side = if l.od_id < 0 { -1.0 } else { 1.0 };
            (0..l.centre.len()).map(move |i| {
                let (c, r, w) = (l.centre[i], l.right(i), l.width[i] / 2.0);
                (l.s[i], [c[0] + side * r[0] * w, c[1] + side * r[1] * w])
            })
        })
        .collect()
}

/// The tick spacing of the centre lanes, m: the smallest of 1, 2, 5 × 10^k at least
/// [`TICK_GAP_PX`] apart.
fn tick_step_m(frame: &Frame) -> f64 {
    let (w, h) = (frame.hi[0] - frame.lo[0], frame.hi[1] - frame.lo[1]);
    let px = LONG_SIDE_PX / w.max(h);
    let want = TICK_GAP_PX / px;
    let mut step = 10f64.powf(want.log10().floor());
    for k in [1.0, 2.0, 5.0, 10.0] {
        if step * k >= want {
            step *= k;
            break;
        }
    }
    step
}

/// Each road's lane 0 outside junctions, in yellow, with its ticks and its `s = 0` dot.
fn draw_centre_lanes<DB: DrawingBackend>(
    chart: &mut Chart<'_, DB>,
    map: &RoadMap,
    frame: &Frame,
    px: f64,
) -> Result<(), DrawError> {
    let yellow = RGBColor(246, 200, 40);
    let step = tick_step_m(frame);
    let tick_m = 5.0 / px;
    for (i, _) in map
        .roads
        .iter()
        .enumerate()
        .filter(|(_, r)| r.junction.is_none())
    {
        let points = centre_lane(map, i);
        if points.len() < 2 {
            continue;
        }
        let line: Vec<(f64, f64)> = points.iter().map(|(_, p)| frame.xy(*p)).collect();
        chart.draw_series(std::iter::once(PathElement::new(
            line.clone(),
            yellow.stroke_width(2),
        )))?;
        let mut ticks = Vec::new();
        let mut next = step;
        for w in points.windows(2) {
            let ((s0, a), (s1, b)) = (w[0], w[1]);
            if s1 <= s0 {
                continue;
            }
            while next <= s0 {
                next += step;
            }
            while next <= s1 {
                let u = (next - s0) / (s1 - s0);
                let (p, q) = (frame.xy(a), frame.xy(b));
                let (x, y) = (p.0 + u * (q.0 - p.0), p.1 + u * (q.1 - p.1));
                let len = (q.0 - p.0).hypot(q.1 - p.1).max(1e-9);
                let (nx, ny) = (-(q.1 - p.1) / len * tick_m, (q.0 - p.0) / len * tick_m);
                ticks.push(vec![(x - nx, y - ny), (x + nx, y + ny)]);
                next += step;
            }
        }
        chart.draw_series(
            ticks
                .into_iter()
                .map(|t| PathElement::new(t, yellow.stroke_width(2))),
        )?;
        chart.draw_series(std::iter::once(Circle::new(line[0], 4, BLACK.filled())))?;
    }
    Ok(())
}

/// A label: its text, centre (file coordinates), text height (px) and colours (fill,
/// border).
struct Label {
    text: String,
    at: (f64, f64),
    size: f64,
    colours: (RGBAColor, RGBColor),
}

impl Label {
    /// Its box, `[lower left, upper right]` in the file's coordinates, at `px` pixels per
    /// metre.
    fn corners(&self, px: f64) -> [(f64, f64); 2] {
        let (hw, hh) = (
            (self.text.chars().count() as f64 * 0.6 * self.size + 8.0) / 2.0 / px,
            (self.size + 6.0) / 2.0 / px,
        );
        [
            (self.at.0 - hw, self.at.1 - hh),
            (self.at.0 + hw, self.at.1 + hh),
        ]
    }

    /// Draws it: the box, then the text centred in it.
    fn draw<DB: DrawingBackend>(
        &self,
        chart: &mut Chart<'_, DB>,
        px: f64,
    ) -> Result<(), DrawError> {
        let corners = self.corners(px);
        chart.draw_series([
            Rectangle::new(corners, self.colours.0.filled()),
            Rectangle::new(corners, self.colours.1.stroke_width(1)),
        ])?;
        let style = (FAMILY, self.size)
            .into_font()
            .color(&BLACK)
            .pos(Pos::new(HPos::Center, VPos::Center));
        chart.draw_series(std::iter::once(Text::new(
            self.text.clone(),
            self.at,
            style,
        )))?;
        Ok(())
    }
}

/// Whether two boxes `[lower left, upper right]` overlap.
fn overlap(a: [(f64, f64); 2], b: [(f64, f64); 2]) -> bool {
    a[0].0 < b[1].0 && b[0].0 < a[1].0 && a[0].1 < b[1].1 && b[0].1 < a[1].1
}

/// The middle of road `road`'s lane 0 (or of its first lane), file coordinates.
fn road_middle(map: &RoadMap, road: usize, frame: &Frame) -> Option<(f64, f64)> {
    let points = centre_lane(map, road);
    match points.get(points.len() / 2) {
        Some((_, p)) => Some(frame.xy(*p)),
        None => map.lanes.iter().find(|l| l.road == road).map(|l| {
            let (a, b) = l.s_range();
            frame.xy(l.pose((a + b) / 2.0).0)
        }),
    }
}

/// Each road's id at its middle (roads outside junctions), and each junction's id at the
/// mean of its connecting roads' middles where that does not hide another label.
fn draw_labels<DB: DrawingBackend>(
    chart: &mut Chart<'_, DB>,
    map: &RoadMap,
    frame: &Frame,
    px: f64,
) -> Result<(), DrawError> {
    let mut sums: Vec<(String, (f64, f64), usize)> = Vec::new();
    let mut roads = Vec::new();
    for (i, r) in map.roads.iter().enumerate() {
        let Some(middle) = road_middle(map, i, frame) else {
            continue;
        };
        match &r.junction {
            None => roads.push(Label {
                text: r.od_id.clone(),
                at: middle,
                size: 16.0,
                colours: (WHITE.mix(0.9), BLACK),
            }),
            Some(j) => match sums.iter_mut().find(|(id, _, _)| id == j) {
                Some((_, sum, n)) => {
                    (sum.0, sum.1, *n) = (sum.0 + middle.0, sum.1 + middle.1, *n + 1);
                }
                None => sums.push((j.clone(), middle, 1)),
            },
        }
    }
    let mut placed: Vec<[(f64, f64); 2]> = roads.iter().map(|l| l.corners(px)).collect();
    let mut junctions = Vec::new();
    for (id, sum, n) in sums {
        let label = Label {
            text: format!("junction {id}"),
            at: (sum.0 / n as f64, sum.1 / n as f64),
            size: 13.0,
            colours: (RGBColor(255, 236, 190).mix(0.92), RGBColor(140, 104, 52)),
        };
        let corners = label.corners(px);
        if !placed.iter().any(|&p| overlap(p, corners)) {
            placed.push(corners);
            junctions.push(label);
        }
    }
    for label in junctions.iter().chain(&roads) {
        label.draw(chart, px)?;
    }
    Ok(())
}

/// The points of `d` by outcome, with a legend.
fn draw_marks<'a, DB: DrawingBackend + 'a>(
    chart: &mut Chart<'a, DB>,
    d: &RoadMapDrawing<'_>,
    frame: &Frame,
) -> Result<(), DrawError> {
    let of = |s: Status| -> Vec<(f64, f64)> {
        d.marks
            .iter()
            .filter(|m| m.status == s)
            .map(|m| frame.xy(m.at_m))
            .collect()
    };
    let (pass, fail, error) = (of(Status::Pass), of(Status::Fail), of(Status::Error));
    let blue = RGBColor(30, 110, 255);
    let red = RGBColor(235, 20, 20);
    chart
        .draw_series(pass.iter().flat_map(|&p| {
            [
                Circle::new(p, 5, WHITE.stroke_width(3)),
                Circle::new(p, 5, blue.stroke_width(2)),
            ]
        }))?
        .label(format!("pass ({})", pass.len()))
        .legend(move |p| Circle::new(p, 5, blue.stroke_width(2)));
    chart
        .draw_series(fail.iter().flat_map(|&p| {
            [
                Cross::new(p, 5, WHITE.stroke_width(4)),
                Cross::new(p, 5, red.stroke_width(2)),
            ]
        }))?
        .label(format!("fail ({})", fail.len()))
        .legend(move |p| Cross::new(p, 5, red.stroke_width(2)));
    if !error.is_empty() {
        chart
            .draw_series(
                error
                    .iter()
                    .map(|&p| TriangleMarker::new(p, 5, RGBColor(120, 120, 120).filled())),
            )?
            .label(format!("error ({})", error.len()))
            .legend(|p| TriangleMarker::new(p, 5, RGBColor(120, 120, 120).filled()));
    }
    super::draw_legend(chart)
}
