//! Entry points of the fuzz targets (`fuzz/`, run by `cargo fuzz`) and of their regression
//! test (`tests/fuzz_regressions.rs`, which replays the inputs kept in `fuzz/regressions/`).
//! Each feeds arbitrary bytes to a reader of user input; a panic or a stack overflow is a bug.

use std::sync::OnceLock;

use paracosm_generators::ParamSpace;

fn text(data: &[u8]) -> Option<&str> {
    std::str::from_utf8(data).ok()
}

fn study_space() -> &'static ParamSpace {
    static SPACE: OnceLock<ParamSpace> = OnceLock::new();
    SPACE.get_or_init(|| paracosm_scenarios::reference::scenario().space().clone())
}

/// A space file (TOML), a CSV test set (with and without a space), and an STL formula (as
/// `paracosm-cover stl` and `Stl(...)` read it).
pub fn inputs(data: &[u8]) {
    let Some(s) = text(data) else { return };
    let _ = paracosm_oracles::stl::parse(s);
    let _ = crate::cover::parse_space("fuzz.toml", s);
    let _ = crate::cover::parse_tests("fuzz.csv", s, false, None);
    let _ = crate::cover::parse_tests("fuzz.csv", s, false, Some(study_space()));
}

/// Lines of `results.jsonl`, as `--resume`/`report` and `paracosm-cover` read them.
pub fn results(data: &[u8]) {
    let Some(s) = text(data) else { return };
    for line in s.lines() {
        let _ = crate::record::RunRecord::from_line(line, study_space());
    }
    let _ = crate::cover::parse_tests("fuzz.jsonl", s, true, None);
    let _ = crate::cover::parse_tests("fuzz.jsonl", s, true, Some(study_space()));
}

/// A scenario program, or (an input that starts with `<`) an OpenDRIVE map ([`opendrive`]).
pub fn scenario(data: &[u8]) {
    let Some(s) = text(data) else { return };
    if s.trim_start().starts_with('<') {
        opendrive(data);
        return;
    }
    let _ = paracosm_scenarios::lang::load_source("fuzz.star", s, "fuzz");
}

/// An OpenDRIVE map as `OpenDrive(...)` reads it: checked, baked, its surface indexed, and a
/// route of up to 200 m planned from the middle of each of its first 16 driving lanes, each
/// turn taken in turn (the `opendrive` fuzz target; the repository's maps are its seeds).
pub fn opendrive(data: &[u8]) {
    use paracosm_engine::network::Turn;
    let Some(s) = text(data) else { return };
    let Ok(imported) = paracosm_engine::network::opendrive::import("fuzz.xodr", s) else {
        return;
    };
    let map = imported.map.clone();
    let mut network = paracosm_engine::Network::new();
    if network
        .add_map("OpenDrive fuzz", imported.map, 0.8)
        .is_err()
    {
        return;
    }
    let surface = paracosm_engine::network::Surface::new(&network);
    let _ = surface.edge_distance_m([0.0, 0.0]);
    let turns = [Turn::Straight, Turn::Left, Turn::Right];
    for (i, lane) in map
        .lanes
        .iter()
        .enumerate()
        .filter(|(_, l)| l.drivable)
        .take(16)
    {
        let (Some(first), Some(last)) = (lane.s.first(), lane.s.last()) else {
            continue;
        };
        let _ = map.route(i, 0.5 * (first + last), &turns[i % 3..i % 3 + 1], 200.0);
    }
}

/// An OpenSCENARIO file as `paracosm-fuzz xosc` reads it: as a parameter value distribution
/// when it is one, else as a scenario (its relative paths from an empty folder, so catalogs
/// and maps are not found); it returns errors, never panics, loops or overflows the stack
/// (the `openscenario` fuzz target; the ALKS suite and the hostile files are its seeds).
pub fn openscenario(data: &[u8]) {
    let Some(s) = text(data) else { return };
    let text = paracosm_openscenario::Text::new("fuzz.xosc", s);
    let is_variation = match text.parse() {
        Ok(doc) => paracosm_openscenario::distribution::is_variation(&doc),
        Err(_) => return,
    };
    if is_variation {
        if let Ok(v) = paracosm_openscenario::distribution::read_variation(&text) {
            for p in &v.params {
                let _ = p.dist.levels();
            }
        }
    } else {
        let _ = paracosm_openscenario::read_scenario_text(&text, std::path::Path::new(""), &[]);
    }
}
