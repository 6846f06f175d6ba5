//! `paracosm-fuzz export`: one recorded test as an ASAM OpenSCENARIO 1.2 scenario (`.xosc`)
//! with its road network as OpenDRIVE (`.xodr`), for a team that runs esmini or CARLA.
//!
//! The test is replayed from its campaign (as `replay` does: its recorded point and seed), and
//! its world and the states it went through are written out ([`xosc`]). The network is the
//! program's OpenDRIVE map, copied as it is, or else written from its pieces ([`xodr`]).

pub mod dataset;
pub mod replay;
pub mod trace;
pub mod xml;
pub mod xodr;
pub mod xosc;

use std::path::{Path, PathBuf};

use paracosm_engine::network::PieceKind;
use paracosm_engine::{Snapshot, WorldSpec};

use crate::campaign::file::CampaignFile;
use crate::Error;

/// What an export wrote.
#[derive(Debug)]
pub struct Exported {
    /// The OpenSCENARIO file.
    pub xosc: PathBuf,
    /// The OpenDRIVE file beside it.
    pub xodr: PathBuf,
    /// Whether the replayed verdict equals the recorded one (the export is of the replay).
    pub matches: bool,
    /// The test's monitors that the file cannot carry (OpenSCENARIO has none): read back
    /// (`paracosm-fuzz FILE.xosc --scripted-ego`), a test is judged by collision and leaving
    /// the road only. Their names, in the scenario's order.
    pub not_in_file: Vec<String>,
}

fn input(e: impl std::fmt::Display) -> Error {
    Error::BadInput(e.to_string())
}

/// The OpenDRIVE document of `world`'s network: its pieces written out when it holds no map
/// (`maps`), the map's own file (read again from the program `program`) when it is a single
/// map.
///
/// # Errors
/// [`Error::BadInput`] for a network that mixes a map with other pieces, a map that is not
/// among the files the program read or can no longer be read, or pieces [`xodr::write`]
/// refuses.
fn network_document(
    world: &WorldSpec,
    scenario: &paracosm_scenarios::Scenario,
    program: &crate::ScenarioRef,
    maps: &[&PieceKind],
) -> Result<String, Error> {
    if maps.is_empty() {
        xodr::write(&world.network, scenario.name()).map_err(input)
    } else if maps.len() == 1 && world.network.pieces().len() == 1 {
        // The map the test ran on (a variation may choose among several): its source path
        // ends with the input file's path, both without `.` components.
        let plain = |p: &str| -> std::path::PathBuf {
            Path::new(p)
                .components()
                .filter(|c| !matches!(c, std::path::Component::CurDir))
                .collect()
        };
        let source = match maps[0] {
            PieceKind::Map { map, .. } => plain(&map.0.source),
            _ => std::path::PathBuf::new(),
        };
        let inputs = scenario.input_files();
        let xodr: Vec<_> = inputs
            .iter()
            .filter(|f| f.path.to_ascii_lowercase().ends_with(".xodr"))
            .collect();
        let read = inputs
            .iter()
            .find(|f| source.ends_with(plain(&f.path)))
            .or(match xodr[..] {
                [one] => Some(one),
                _ => None,
            })
            .ok_or_else(|| {
                input(format!(
                    "the test's map {} is not among the files the campaign read",
                    source.display()
                ))
            })?;
        if program.xosc().is_some() {
            // An OpenSCENARIO campaign names its files relative to the folder of its file.
            let folder = Path::new(program.path()).parent().unwrap_or(Path::new(""));
            paracosm_scenarios::text_file::read_text(
                &folder.join(&read.path),
                paracosm_scenarios::map_files::MAX_MAP_BYTES,
            )
            .map_err(|e| input(format!("cannot read {}: {e}", read.path)))
        } else {
            paracosm_scenarios::map_files::read_input_file(program.path(), &read.path)
                .map_err(input)
        }
    } else {
        Err(input(
            "the test's network mixes an OpenDRIVE map with other pieces, which cannot be exported as one OpenDRIVE file",
        ))
    }
}

/// Writes test `id` of the campaign whose results are `results` into `out` as `test_ID.xosc`
/// and `test_ID.xodr`, the ego's motion as `ego` says (its trajectory, or its route).
///
/// # Errors
/// [`Error::BadInput`] as for [`crate::export::replay::replay`], for a network that mixes an
/// OpenDRIVE map with pieces of the program, or a map that can no longer be read;
/// [`Error::Write`] when `out` or a file cannot be written.
pub fn export(
    results: &Path,
    id: u64,
    out: &Path,
    ego: xosc::EgoMotion,
) -> Result<Exported, Error> {
    check_out_folder(out, id)?;
    let dir = results.parent().unwrap_or(Path::new("."));
    let campaign = CampaignFile::read(dir).map_err(input)?;
    let scenario = campaign.scenario.load()?;
    let (world, states, replayed) = replay_recording(results, id)?;
    let stem = format!("test_{id}");
    let xodr_name = format!("{stem}.xodr");
    // The network: the program's map as it is, or the pieces written out.
    let maps: Vec<&PieceKind> = world
        .network
        .pieces()
        .iter()
        .map(|p| &p.kind)
        .filter(|k| matches!(k, PieceKind::Map { .. }))
        .collect();
    let network = network_document(&world, &scenario, &campaign.scenario, &maps)?;
    let origin_m = map_origin_m(&maps);
    let params: Vec<(String, serde_json::Value)> = replayed.recorded["params"]
        .as_object()
        .map(|m| m.iter().map(|(k, v)| (k.clone(), v.clone())).collect())
        .unwrap_or_default();
    let description = format!(
        "paracosm test {id} of {} (campaign {}, seed {}): {}",
        scenario.name(),
        &campaign.fingerprint[..16.min(campaign.fingerprint.len())],
        campaign.seed,
        replayed.recorded["status"].as_str().unwrap_or("?")
    );
    let document = xosc::write(&xosc::Test {
        ego,
        description,
        params,
        network_file: xodr_name.clone(),
        world: &world,
        states: &states,
        horizon_s: scenario.horizon_s(),
        origin_m,
    });
    let xosc_path = out.join(format!("{stem}.xosc"));
    let xodr_path = out.join(&xodr_name);
    for (path, text) in [(&xodr_path, &network), (&xosc_path, &document)] {
        crate::atomic::write(path, text.as_bytes())?;
    }
    let not_in_file = monitors_not_in_file(&scenario);
    Ok(Exported {
        xosc: xosc_path,
        xodr: xodr_path,
        matches: replayed.matches,
        not_in_file,
    })
}

/// Refuses an `out` that is a file, then makes the folder and checks that test `id`'s two
/// files can be written there: all before the replay (exit 2, before any work).
///
/// # Errors
/// [`Error::BadInput`] for a file where the folder should be; the folder's or the targets'
/// errors.
fn check_out_folder(out: &Path, id: u64) -> Result<(), Error> {
    // A file where the folder should be is the user's mistake, refused before the replay.
    if out.exists() && !out.is_dir() {
        return Err(Error::BadInput(format!(
            "--out `{}` is a file, not a folder: give a folder for the exported files",
            out.display()
        )));
    }
    // The folder and the two files are checked before the replay (exit 2, before any work).
    crate::atomic::make_output_folder(out)?;
    crate::atomic::check_targets(
        out,
        [format!("test_{id}.xosc"), format!("test_{id}.xodr")]
            .iter()
            .map(String::as_str),
    )?;
    Ok(())
}

/// Replays test `id` of the campaign whose results are `results`, keeping its world as built
/// and its state at the start and after every step.
///
/// # Errors
/// As [`replay::replay_with`]; [`Error::BadInput`] when the test built no world.
fn replay_recording(
    results: &Path,
    id: u64,
) -> Result<(WorldSpec, Vec<Snapshot>, replay::Replay), Error> {
    let mut world: Option<WorldSpec> = None;
    let mut states: Vec<Snapshot> = Vec::new();
    let mut on_world = |w: &WorldSpec| world = Some(w.clone());
    let mut on_step = |s: &Snapshot| states.push(s.clone());
    let replayed = crate::export::replay::replay_with(
        results,
        id,
        (None, None),
        None,
        Some(&mut on_world),
        Some(&mut on_step),
    )?;
    let world = world.ok_or_else(|| {
        input(format!(
            "test {id} built no world: {}",
            replayed.replayed.error.clone().unwrap_or_default()
        ))
    })?;
    Ok((world, states, replayed))
}

/// The origin `[x, z]` (m) of the first of `maps`, `[0, 0]` without a map.
fn map_origin_m(maps: &[&PieceKind]) -> [f64; 2] {
    maps.first()
        .and_then(|k| match k {
            PieceKind::Map { map, .. } => Some(map.0.origin_m),
            _ => None,
        })
        .unwrap_or([0.0, 0.0])
}

/// The names of `scenario`'s monitors that an OpenSCENARIO file cannot carry (all but
/// collision and leaving the road), in the scenario's order.
fn monitors_not_in_file(scenario: &paracosm_scenarios::Scenario) -> Vec<String> {
    scenario
        .monitors()
        .iter()
        .filter(|m| {
            !matches!(
                m,
                paracosm_scenarios::MonitorSpec::Collision { .. }
                    | paracosm_scenarios::MonitorSpec::OffRoad { .. }
            )
        })
        .map(|m| m.name().to_owned())
        .collect()
}
