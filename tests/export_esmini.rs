//! The exports of the shipped studies' first collisions, run in esmini (the reference
//! OpenSCENARIO simulator): esmini's runs are fixtures (`tests/data/xosc/esmini-collisions.csv`,
//! recorded by `scripts/esmini-collisions` with esmini built as
//! `tests/data/xosc/esmini-trajectories/PROVENANCE.md` says). This test re-runs each study,
//! exports the same test, checks that the export is byte for byte the file esmini ran, and
//! compares esmini's first collision of the ego with paracosm's time to failure.

use sha2::{Digest, Sha256};

mod common;
use common::{fuzz, records};

/// The largest difference between esmini's and paracosm's collision times, s.
const AGREE_S: f64 = 0.2;

#[test]
fn the_first_collisions_of_the_shipped_studies_happen_in_esmini_too() {
    let fixture = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/xosc/esmini-collisions.csv");
    let mut rd = csv::Reader::from_path(&fixture).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let mut report = Vec::new();
    for rec in rd.records() {
        let rec = rec.unwrap();
        let (study, budget, id) = (&rec[0], &rec[1], &rec[2]);
        let t_paracosm: f64 = rec[3].parse().unwrap();
        let t_esmini: f64 = rec[4].parse().expect("esmini saw the collision");
        let out = dir.path().join(format!("c-{study}"));
        let o = fuzz(&[study, "--budget", budget, "--out", out.to_str().unwrap()]);
        assert!(matches!(o.status.code(), Some(0 | 1)), "{study}: {o:?}");
        let r = &records(&out)[id.parse::<usize>().unwrap()];
        assert_eq!(r["status"], "fail", "{study} test {id}: {r}");
        let ttf = r["metrics"]["time_to_failure_s"].as_f64().unwrap();
        assert!(
            (ttf - t_paracosm).abs() < 1e-3,
            "{study}: {ttf} s, recorded {t_paracosm} s"
        );
        let x = dir.path().join(format!("x-{study}"));
        let o = fuzz(&[
            "export",
            out.join("results.jsonl").to_str().unwrap(),
            "--id",
            id,
            "--out",
            x.to_str().unwrap(),
        ]);
        assert_eq!(o.status.code(), Some(0), "{study}: {o:?}");
        let bytes = std::fs::read(x.join(format!("test_{id}.xosc"))).unwrap();
        let digest: String = Sha256::digest(&bytes)
            .iter()
            .map(|b| format!("{b:02x}"))
            .collect();
        assert_eq!(
            digest, &rec[6],
            "{study}: the export is not the file esmini ran; rerun scripts/esmini-collisions"
        );
        let gap = t_esmini - t_paracosm;
        report.push(format!(
            "{study}: paracosm {t_paracosm:.3} s, esmini {t_esmini:.3} s ({gap:+.3} s)"
        ));
        assert!(gap.abs() <= AGREE_S, "{}", report.join("\n"));
    }
    println!("{}", report.join("\n"));
    assert_eq!(report.len(), 6, "the six studies of the fixture");
}
