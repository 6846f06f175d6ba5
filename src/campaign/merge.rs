//! `paracosm-fuzz merge`: shard folders into one campaign folder.

use std::collections::BTreeMap;
use std::io::Write;
use std::path::{Path, PathBuf};

use crate::campaign::file::CampaignFile;
use crate::campaign::RESULTS_FILE;
use crate::record::RunRecord;
use crate::Error;

/// A merged campaign, written to its folder (results and `campaign.json`; the caller writes
/// the summary and plots with [`crate::report::write_outputs`]).
#[derive(Debug)]
pub struct Merged {
    /// The whole campaign's settings (no shard).
    pub file: CampaignFile,
    /// Every record, by id.
    pub records: Vec<RunRecord>,
    /// The scenario.
    pub scenario: paracosm_scenarios::Scenario,
}

/// Checks that `dirs` are the complete, non-overlapping shards of one campaign and writes
/// their records, in id order, to `out/results.jsonl` with the whole campaign's
/// `campaign.json`.
///
/// # Errors
/// [`Error::BadInput`] when a folder is not a shard, the shards belong to different campaigns
/// (fingerprints), one is missing, given twice or incomplete; [`Error::Input`] when a file
/// cannot be read; [`Error::Write`] when the merged folder cannot be written.
pub fn merge(dirs: &[PathBuf], out: &Path) -> Result<Merged, Error> {
    let (template, shards) = read_shards(dirs)?;
    let mut scenario = template.scenario.load()?;
    if let Some(sut) = template.sut.config()? {
        scenario.set_sut(sut);
    }
    let mut records = Vec::with_capacity(template.budget as usize);
    for (dir, file) in shards.values() {
        records.extend(shard_records(dir, file, &scenario)?);
    }
    std::fs::create_dir_all(out).map_err(|e| Error::write(out, e))?;
    let mut whole = CampaignFile {
        shard: None,
        ..template
    }
    .checked();
    whole.tool = format!("paracosm {}", env!("CARGO_PKG_VERSION"));
    let results = out.join(RESULTS_FILE);
    let lines: Vec<Vec<u8>> = shards
        .values()
        .map(|(dir, _)| crate::campaign::results::whole_lines(dir))
        .collect::<Result<_, _>>()?;
    crate::atomic::with_temp(&results, |tmp| -> std::io::Result<()> {
        let mut f = std::io::BufWriter::new(std::fs::File::create(tmp)?);
        for bytes in &lines {
            f.write_all(bytes)?;
        }
        f.flush()
    })?;
    whole.write(out)?;
    Ok(Merged {
        file: whole,
        records,
        scenario,
    })
}

/// Shard folders by shard index, with their settings.
type Shards = BTreeMap<u64, (PathBuf, CampaignFile)>;

/// The shards of one campaign in `dirs`, by index, with the first one's settings.
///
/// # Errors
/// As [`merge`], for the folders and their `campaign.json`.
fn read_shards(dirs: &[PathBuf]) -> Result<(CampaignFile, Shards), Error> {
    let bad = |m: String| Error::BadInput(m);
    let mut shards: Shards = BTreeMap::new();
    let mut first: Option<(PathBuf, CampaignFile)> = None;
    for dir in dirs {
        let file = CampaignFile::read(dir)?;
        let edited = file.edited_fields();
        if !edited.is_empty() {
            return Err(bad(format!(
                "{}: edited by hand ({} no longer as the shard wrote {})",
                dir.join(crate::campaign::file::CAMPAIGN_FILE).display(),
                edited.join(", "),
                if edited.len() == 1 { "it" } else { "them" }
            )));
        }
        let Some(shard) = file.shard else {
            return Err(bad(format!(
                "`{}` holds a whole campaign, not a shard (run shards with --shard I/N)",
                dir.display()
            )));
        };
        if let Some((first_dir, f)) = &first {
            let their_count = f.shard.map_or(1, |s| s.count);
            if f.fingerprint != file.fingerprint || their_count != shard.count {
                let mut diff = f.differences(&file);
                diff.retain(|d| !d.starts_with("shard: "));
                if their_count != shard.count {
                    diff.push(format!("shard counts: {their_count} vs {}", shard.count));
                }
                return Err(bad(format!(
                    "`{}` and `{}` are shards of different campaigns ({})",
                    first_dir.display(),
                    dir.display(),
                    diff.join("; ")
                )));
            }
        } else {
            first = Some((dir.clone(), file.clone()));
        }
        if let Some((other, _)) = shards.get(&shard.index) {
            return Err(bad(format!(
                "shard {shard} is given twice: `{}` and `{}`",
                other.display(),
                dir.display()
            )));
        }
        shards.insert(shard.index, (dir.clone(), file));
    }
    let Some((_, template)) = first else {
        return Err(bad("no shard folders given".into()));
    };
    let count = template.shard.map_or(1, |s| s.count);
    let missing: Vec<String> = (0..count)
        .filter(|i| !shards.contains_key(i))
        .map(|i| format!("{i}/{count}"))
        .collect();
    if !missing.is_empty() {
        return Err(bad(format!(
            "shard {} of the campaign {} missing",
            missing.join(", "),
            if missing.len() == 1 { "is" } else { "are" }
        )));
    }
    Ok((template, shards))
}

/// The records of the shard in `dir` with settings `file`, checked to be the complete shard
/// of its campaign.
///
/// # Errors
/// As [`merge`], for the shard's records.
fn shard_records(
    dir: &Path,
    file: &CampaignFile,
    scenario: &paracosm_scenarios::Scenario,
) -> Result<Vec<RunRecord>, Error> {
    let bad = |m: String| Error::BadInput(m);
    let ids = file.ids();
    let existing = crate::campaign::results::load(dir, scenario, ids.clone(), false)?;
    let strategy: paracosm_generators::Strategy =
        file.strategy.parse().map_err(|e| bad(format!("{e}")))?;
    let campaign = crate::campaign::Campaign {
        scenario,
        strategy,
        seed: file.seed,
        budget: file.budget,
        strength: file.strength,
        jobs: 1,
        stop_at_first_failure: false,
        points: None,
        trace: None,
    };
    campaign.check_origin(
        &existing.records,
        ids.start,
        &dir.join(RESULTS_FILE),
        Some(&file.tag()),
    )?;
    let done = existing.records.len() as u64;
    if done != ids.end - ids.start {
        return Err(bad(format!(
            "shard {} in `{}` is incomplete: {} of {} tests; finish it with \
             `paracosm-fuzz --resume --out {}`",
            file.shard.expect("checked"),
            dir.display(),
            done,
            ids.end - ids.start,
            dir.display()
        )));
    }
    Ok(existing.records)
}

/// `paracosm-fuzz merge`: [`merge`]s `dirs` into `out` (which must be empty unless
/// `replace`), writes the summary, plots and JUnit (when `junit`), and returns the human
/// summary, the counts and the plots that could not be drawn. The wall time is the shards'
/// own, added up.
///
/// # Errors
/// As [`merge`]; [`Error::BadInput`] for a non-empty `out`; [`Error::Write`] when a file
/// cannot be written.
pub fn merge_folders(
    dirs: &[PathBuf],
    out: &Path,
    replace: bool,
    junit: Option<&Path>,
) -> Result<(String, crate::report::summary::Counts, Vec<String>), Error> {
    if let Some(junit) = junit {
        crate::atomic::check_side_output(junit, "--junit", out)?;
    }
    crate::campaign::session::prepare_out_dir(out, replace, false)?;
    let _lock = crate::campaign::lock::CampaignLock::acquire(out)?;
    let m = merge(dirs, out)?;
    // The shards' own times (0, not -0, when none has a summary).
    let wall_s: f64 = dirs
        .iter()
        .filter_map(|d| crate::report::summary::Summary::read(d).ok())
        .map(|s| s.wall_s)
        .fold(0.0, |a, b| a + b);
    let written = crate::report::write_outputs(&crate::report::Finished {
        out,
        scenario: &m.scenario,
        file: &m.file,
        records: &m.records,
        jobs: 1,
        wall_s,
        junit,
        warnings: crate::report::warnings_of(&m.scenario),
    })?;
    if let Some(path) = junit {
        crate::report::junit::write(path, m.scenario.name(), &m.records, out)?;
    }
    let text = format!(
        "merged {} shards into {}\n{}",
        dirs.len(),
        out.display(),
        crate::report::human(&written.summary, &m.scenario, out, m.file.budget, Some(0))
    );
    Ok((text, written.summary.counts, written.plot_warnings))
}
