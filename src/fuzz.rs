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
    SPACE.get_or_init(|| paracosm_scenarios::reference::scenario().space)
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

/// A scenario program, or (an input that starts with `<`) an OpenDRIVE map as
/// `OpenDrive(...)` reads it: checked, baked, and its surface indexed.
pub fn scenario(data: &[u8]) {
    let Some(s) = text(data) else { return };
    if s.trim_start().starts_with('<') {
        if let Ok(imported) = paracosm_engine::network::opendrive::import("fuzz.xodr", s) {
            let mut network = paracosm_engine::Network::new();
            if network.add_map("OpenDrive fuzz", imported.map, 0.8).is_ok() {
                let surface = paracosm_engine::network::Surface::new(&network);
                let _ = surface.edge_distance_m([0.0, 0.0]);
            }
        }
        return;
    }
    let _ = paracosm_scenarios::lang::load_source("fuzz.star", s, "fuzz");
}
