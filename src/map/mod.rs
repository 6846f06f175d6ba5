//! `paracosm-fuzz map`: an OpenDRIVE map's roads, lane sections and junctions, listed as text
//! and drawn top-down, so that a user can pick `onLane(road=, lane=, s=)`.
//!
//! The map is read by the engine's importer ([`paracosm_engine::network::opendrive::import`]),
//! the same one a program's `Map(...)` goes through: a file `map` lists is a file a program
//! can load, with the same checks and messages. The listing shows what the importer baked
//! (each road's length, its lane sections' station ranges, each lane's id, type and
//! direction); the file's order of roads and its `<junction>` connections (incoming,
//! connecting and outgoing road, contact point) are read from the document's XML tree, which
//! the importer has checked by then.

mod junctions;

use std::path::Path;
use std::sync::Arc;

use paracosm_engine::network::RoadMap;

use crate::Error;

pub use junctions::{Connection, Junction};

/// Largest map file read, bytes: the limit a program's `Map(...)` has.
pub const MAX_MAP_BYTES: u64 = paracosm_scenarios::map_files::MAX_MAP_BYTES;

/// A map read for listing and drawing ([`read`]).
#[derive(Debug, Clone)]
pub struct MapListing {
    /// The file, as given on the command line (for messages and the drawing's title).
    pub file: String,
    /// The map as the importer baked it.
    pub map: Arc<RoadMap>,
    /// Every `<road>` of the file, in the file's order.
    pub roads: Vec<RoadEntry>,
    /// Every `<junction>` of the file, in the file's order.
    pub junctions: Vec<Junction>,
    /// What the importer did not use (elements, records), one line each.
    pub warnings: Vec<String>,
}

/// One `<road>` of a map.
#[derive(Debug, Clone, PartialEq)]
pub struct RoadEntry {
    /// Its `<road id>`: what `onLane(road=)` takes.
    pub id: String,
    /// Its length along the reference line, m: `onLane(s=)` lies in `[0, length_m]`.
    pub length_m: f64,
    /// The `<junction id>` of a connecting road, `None` outside junctions.
    pub junction: Option<String>,
    /// Its index in [`RoadMap::roads`]; `None` for a road none of whose lanes has a width
    /// (the importer keeps no lane of it, so no `onLane` can stand on it).
    pub index: Option<usize>,
    /// Its lane sections with a lane, in order of `s`.
    pub sections: Vec<SectionEntry>,
}

/// One lane section of a road.
#[derive(Debug, Clone, PartialEq)]
pub struct SectionEntry {
    /// Zero-based index among the road's `<laneSection>`s.
    pub index: usize,
    /// The stations it spans, `[start, end]` m along the road's reference line.
    pub s_m: [f64; 2],
    /// Its lanes with a width, left to right as seen facing increasing `s` (descending id).
    pub lanes: Vec<LaneEntry>,
}

/// One lane of a lane section.
#[derive(Debug, Clone, PartialEq)]
pub struct LaneEntry {
    /// Its `<lane id>`: what `onLane(lane=)` takes (negative right of the reference line).
    pub id: i32,
    /// Its `type` (`driving`, `sidewalk`, `shoulder`...).
    pub kind: String,
    /// Whether cars drive on it.
    pub drivable: bool,
    /// Whether traffic runs along increasing `s`.
    pub forward: bool,
}

/// Reads the OpenDRIVE map at `path` through the engine's importer.
///
/// # Errors
/// [`Error::Input`] naming the file: it cannot be read, is not a regular file, is larger than
/// [`MAX_MAP_BYTES`] or not UTF-8 (with the line and column of the first bad byte), or is no
/// usable OpenDRIVE map (the importer's message, with `file:line:col` of the element at
/// fault).
pub fn read(path: &Path) -> Result<MapListing, Error> {
    let shown = path.display().to_string();
    let text = paracosm_scenarios::text_file::read_text(path, MAX_MAP_BYTES)
        .map_err(|e| Error::input(path, e))?;
    let imported = paracosm_scenarios::map_files::import_map(&shown, &text)
        .map_err(|e| Error::malformed(path, e.to_string()))?;
    let doc = roxmltree::Document::parse(&text)
        .map_err(|e| Error::malformed(path, format!("{shown}: malformed XML: {e}")))?;
    let map = imported.map;
    let roads = doc
        .root_element()
        .children()
        .filter(|n| n.has_tag_name("road"))
        .map(|n| road_entry(&map, n))
        .collect();
    let junctions = junctions::read(&map, &doc);
    Ok(MapListing {
        file: shown,
        map,
        roads,
        junctions,
        warnings: imported.warnings,
    })
}

/// The entry of the `<road>` element `node`, its length and lanes as `map` baked them.
fn road_entry(map: &RoadMap, node: roxmltree::Node<'_, '_>) -> RoadEntry {
    let id = node.attribute("id").unwrap_or_default().to_owned();
    let index = map.roads.iter().position(|r| r.od_id == id);
    let file_junction = node
        .attribute("junction")
        .filter(|j| j.trim() != "-1")
        .map(str::to_owned);
    let (length_m, junction) = match index {
        Some(i) => (map.roads[i].length_m, map.roads[i].junction.clone()),
        None => (
            node.attribute("length")
                .and_then(|l| l.trim().parse().ok())
                .unwrap_or(f64::NAN),
            file_junction,
        ),
    };
    RoadEntry {
        id,
        length_m,
        junction,
        index,
        sections: index.map(|i| sections(map, i)).unwrap_or_default(),
    }
}

/// The lane sections of road `road` (its index in `map.roads`) that hold a lane.
fn sections(map: &RoadMap, road: usize) -> Vec<SectionEntry> {
    let mut out: Vec<SectionEntry> = Vec::new();
    for lane in map.lanes.iter().filter(|l| l.road == road) {
        let (a, b) = lane.s_range();
        let entry = LaneEntry {
            id: lane.od_id,
            kind: lane.kind.clone(),
            drivable: lane.drivable,
            forward: lane.forward,
        };
        match out.iter_mut().find(|s| s.index == lane.section) {
            Some(s) => {
                s.s_m = [s.s_m[0].min(a), s.s_m[1].max(b)];
                s.lanes.push(entry);
            }
            None => out.push(SectionEntry {
                index: lane.section,
                s_m: [a, b],
                lanes: vec![entry],
            }),
        }
    }
    out.sort_by_key(|s| s.index);
    for s in &mut out {
        s.lanes.sort_by_key(|l| std::cmp::Reverse(l.id));
    }
    out
}

impl MapListing {
    /// The listing as text: a header with the counts, one line per road (id, length,
    /// junction, and per lane section its station range and lanes as `id:type`, a driving
    /// lane marked `>` when traffic runs along increasing `s` and `<` against it), then each
    /// junction with one line per connection.
    pub fn text(&self) -> String {
        let in_junctions = self.roads.iter().filter(|r| r.junction.is_some()).count();
        let connections: usize = self.junctions.iter().map(|j| j.connections.len()).sum();
        let mut lines = vec![
            format!(
                "{}: {} ({in_junctions} of them connecting roads in junctions), {} with {}, {}",
                self.file,
                counted(self.roads.len(), "road"),
                counted(self.junctions.len(), "junction"),
                counted(connections, "connection"),
                counted(self.map.lanes.len(), "lane"),
            ),
            "roads: id, length, junction (- outside one), then per lane section its range of s and its lanes left to right as id:type (a driving lane's > is along increasing s, < against it); place an actor with onLane(road=\"ID\", lane=ID, s=S)".to_owned(),
        ];
        lines.extend(self.roads.iter().map(road_line));
        if !self.junctions.is_empty() {
            lines.push(
                "junctions: each connection as incoming road -> connecting road -> outgoing road, the contact point on the connecting road, its lane links (incoming:connecting) and the turn a route names it by"
                    .to_owned(),
            );
            lines.extend(self.junctions.iter().flat_map(Junction::lines));
        }
        lines.join("\n")
    }
}

/// `n` and `noun`, plural unless `n` is 1 (`1 road`, `0 junctions`).
fn counted(n: usize, noun: &str) -> String {
    if n == 1 {
        format!("1 {noun}")
    } else {
        format!("{n} {noun}s")
    }
}

/// One road's line of [`MapListing::text`].
fn road_line(r: &RoadEntry) -> String {
    let sections: Vec<String> = r
        .sections
        .iter()
        .map(|s| {
            let lanes: Vec<String> = s
                .lanes
                .iter()
                .map(|l| {
                    let arrow = match (l.drivable, l.forward) {
                        (false, _) => "",
                        (true, true) => ">",
                        (true, false) => "<",
                    };
                    format!("{}:{}{arrow}", l.id, l.kind)
                })
                .collect();
            format!("s {:.2}-{:.2}: {}", s.s_m[0], s.s_m[1], lanes.join(" "))
        })
        .collect();
    let sections = if sections.is_empty() {
        "no lane with a width".to_owned()
    } else {
        sections.join(" | ")
    };
    format!(
        "road {}  {:.2} m  junction {}  {sections}",
        r.id,
        r.length_m,
        r.junction.as_deref().unwrap_or("-"),
    )
}

impl MapListing {
    /// The drawing's title: the file and its counts.
    fn title(&self) -> String {
        format!(
            "{}: {}, {}",
            self.file,
            counted(self.roads.len(), "road"),
            counted(self.junctions.len(), "junction")
        )
    }

    /// Draws the map top-down into the PNG file `path` (see
    /// [`crate::report::plot::road_map_png`]) and returns the path.
    ///
    /// # Errors
    /// [`Error::BadInput`] when `path` is neither absent nor a regular file; [`Error::Plot`]
    /// when it cannot be drawn or written.
    pub fn draw_png(&self, path: &Path) -> Result<std::path::PathBuf, Error> {
        crate::atomic::check_target(path)?;
        let title = self.title();
        Ok(crate::report::plot::road_map_png(
            &self.drawing(&title),
            path,
        )?)
    }

    /// Draws the map top-down into the SVG file `path`, as [`MapListing::draw_png`].
    ///
    /// # Errors
    /// As [`MapListing::draw_png`].
    pub fn draw_svg(&self, path: &Path) -> Result<std::path::PathBuf, Error> {
        crate::atomic::check_target(path)?;
        let title = self.title();
        Ok(crate::report::plot::road_map_svg(
            &self.drawing(&title),
            path,
        )?)
    }

    fn drawing<'a>(&'a self, title: &'a str) -> crate::report::plot::RoadMapDrawing<'a> {
        crate::report::plot::RoadMapDrawing {
            map: &self.map,
            title,
            marks: &[],
            marks_label: "",
        }
    }
}
