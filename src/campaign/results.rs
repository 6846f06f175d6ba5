//! Reading a folder's `results.jsonl` back: for `--resume`, `merge` and `report`.

use std::ops::Range;
use std::path::Path;

use crate::campaign::RESULTS_FILE;
use crate::record::RunRecord;
use crate::Error;

/// The records found in a folder.
#[derive(Debug)]
pub struct Existing {
    /// The records, in id order.
    pub records: Vec<RunRecord>,
    /// Bytes of a half-written last line that were cut off (0 when the file was whole).
    pub repaired_bytes: usize,
}

/// Reads `results.jsonl` in `dir`, written for a campaign of `scenario` whose folder runs
/// `ids` (its parameter space reads the points; its passive monitors are set on each record,
/// [`RunRecord::robustness`]). A last line without its newline (the process was killed while
/// writing it) is cut off the file when `repair`, and ignored otherwise. Every other line must
/// be a record, and the records must be `ids.start, ids.start + 1, ...` in order, since the
/// runner writes them so. A missing file reads as no records.
///
/// # Errors
/// [`Error::Input`] with `file:line:column` for a line that is not a record, or naming the
/// first id out of sequence, or with the file system's reason.
pub fn load(
    dir: &Path,
    scenario: &paracosm_scenarios::Scenario,
    ids: Range<u64>,
    repair: bool,
) -> Result<Existing, Error> {
    let space = scenario.space();
    let passive = scenario.passive_monitors();
    let path = dir.join(RESULTS_FILE);
    paracosm_engine::files::regular_file(&path).map_err(|e| Error::input(&path, e))?;
    let bytes = match std::fs::read(&path) {
        Ok(b) => b,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Vec::new(),
        Err(e) => return Err(Error::input(&path, e)),
    };
    let bad = |message: String| Error::malformed(&path, message);
    let whole = bytes.iter().rposition(|&b| b == b'\n').map_or(0, |i| i + 1);
    let repaired_bytes = bytes.len() - whole;
    if repaired_bytes > 0 && repair {
        let f = crate::atomic::open_regular(&path, true)?;
        f.set_len(whole as u64)
            .and_then(|()| f.sync_all())
            .map_err(|e| Error::write(&path, e))?;
    }
    let text = std::str::from_utf8(&bytes[..whole]).map_err(|e| {
        bad(format!(
            "{}: {}; is it a results file?",
            path.display(),
            paracosm_scenarios::text_file::not_utf8(&bytes[..whole], e)
        ))
    })?;
    let mut records = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let mut r = RunRecord::from_line(line, space).map_err(|e| {
            bad(format!(
                "{}: not a results record: {e}",
                crate::error::located(&path, n + 1, e.column())
            ))
        })?;
        let expected = ids.start + records.len() as u64;
        if r.id != expected || !ids.contains(&r.id) {
            return Err(bad(format!(
                "{}:{}: test id {} where {} was expected (this folder runs ids {}..{}); the file \
                 was not written by this campaign",
                path.display(),
                n + 1,
                r.id,
                expected,
                ids.start,
                ids.end
            )));
        }
        r.passive.clone_from(&passive);
        records.push(r);
    }
    Ok(Existing {
        records,
        repaired_bytes,
    })
}

/// The whole lines of `src`'s `results.jsonl`, as bytes.
///
/// # Errors
/// [`Error::Input`] when the file cannot be read.
pub fn whole_lines(src: &Path) -> Result<Vec<u8>, Error> {
    let path = src.join(RESULTS_FILE);
    paracosm_engine::files::regular_file(&path).map_err(|e| Error::input(&path, e))?;
    let mut bytes = std::fs::read(&path).map_err(|e| Error::input(&path, e))?;
    let whole = bytes.iter().rposition(|&b| b == b'\n').map_or(0, |i| i + 1);
    bytes.truncate(whole);
    Ok(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_half_written_last_line_is_cut_off_and_ids_must_follow_in_order() {
        let s = paracosm_scenarios::reference::scenario();
        let dir = tempfile::tempdir().unwrap();
        let c = crate::Campaign {
            scenario: &s,
            strategy: paracosm_generators::Strategy::Halton,
            seed: 0,
            budget: 4,
            strength: 2,
            jobs: 1,
            stop_at_first_failure: false,
            points: None,
            trace: None,
        };
        c.run(dir.path(), |_| {}).unwrap();
        let path = dir.path().join(RESULTS_FILE);
        let full = std::fs::read_to_string(&path).unwrap();
        let cut = full.len() - 20;
        std::fs::write(&path, &full[..cut]).unwrap();
        let e = load(dir.path(), &s, 0..4, true).unwrap();
        assert_eq!(e.records.len(), 3);
        assert!(e.repaired_bytes > 0);
        let repaired = std::fs::read_to_string(&path).unwrap();
        assert!(repaired.ends_with('\n') && full.starts_with(&repaired));
        // A shard that should start at id 2 does not accept ids 0..3.
        let err = load(dir.path(), &s, 2..4, false).unwrap_err().to_string();
        assert!(err.contains(":1: test id 0 where 2 was expected"), "{err}");
        std::fs::write(&path, "{\"id\": 0, oops\n").unwrap();
        let err = load(dir.path(), &s, 0..4, false).unwrap_err().to_string();
        assert!(err.contains("results.jsonl:1:"), "{err}");
    }
}
