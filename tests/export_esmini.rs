//! The exports of the shipped studies' first collisions, run in esmini (the reference
//! OpenSCENARIO simulator): esmini's runs are fixtures (`tests/data/xosc/esmini-collisions.csv`,
//! recorded by `scripts/esmini-collisions` with esmini built as
//! `tests/data/xosc/esmini-trajectories/PROVENANCE.md` says). This test re-runs each study,
//! exports the same test, checks that the export is byte for byte the file esmini ran, and
//! compares esmini's first collision of the ego with paracosm's time to failure. It then reads
//! each export back in paracosm (`paracosm-fuzz test_N.xosc --scripted-ego`: every entity, the
//! ego too, where the test had it at every step) and checks that its verdicts are the test's.

use sha2::{Digest, Sha256};

mod common;
use common::{fuzz, records};

/// The largest difference between esmini's and paracosm's collision times, s.
const AGREE_S: f64 = 0.2;
/// The largest difference between a monitor's robustness in a test and in its export read
/// back in paracosm.
const READ_BACK_ROBUSTNESS: f64 = 1e-6;

/// Reads the export `xosc` back in paracosm with the ego scripted, and checks that each of its
/// monitors (collision, leaving the road) gives the verdict, robustness and time of first
/// violation the test `r` recorded; returns a line saying so.
fn read_back(study: &str, xosc: &std::path::Path, r: &serde_json::Value) -> String {
    let out = xosc.with_extension("read-back");
    let o = fuzz(&[
        xosc.to_str().unwrap(),
        "--scripted-ego",
        "--budget",
        "1",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(
        o.status.code(),
        Some(1),
        "{study}: the read-back fails: {o:?}"
    );
    let back = &records(&out)[0];
    assert_eq!(back["status"], "fail", "{study}: {back}");
    let monitors = back["monitors"].as_object().unwrap();
    assert_eq!(monitors.len(), 2, "{study}: collision and off-road: {back}");
    let mut worst = 0.0f64;
    for (name, m) in monitors {
        let recorded = &r["monitors"][name];
        assert_eq!(
            m["passed"], recorded["passed"],
            "{study} {name}: {back} vs {r}"
        );
        let d =
            (m["robustness"].as_f64().unwrap() - recorded["robustness"].as_f64().unwrap()).abs();
        assert!(
            d <= READ_BACK_ROBUSTNESS,
            "{study} {name}: {d} off: {back} vs {r}"
        );
        worst = worst.max(d);
        assert_eq!(
            m["first_violation_s"], recorded["first_violation_s"],
            "{study} {name}: {back} vs {r}"
        );
    }
    format!("{study}: read back, the same verdicts, robustness within {worst:e}")
}

#[test]
fn the_first_collisions_of_the_shipped_studies_happen_in_esmini_too() {
    let fixture = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/xosc/esmini-collisions.csv");
    let mut rd = csv::Reader::from_path(&fixture).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let mut report = Vec::new();
    let mut last = None;
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
        let exported = x.join(format!("test_{id}.xosc"));
        report.push(read_back(study, &exported, r));
        last = Some(exported);
        let gap = t_esmini - t_paracosm;
        report.push(format!(
            "{study}: paracosm {t_paracosm:.3} s, esmini {t_esmini:.3} s ({gap:+.3} s)"
        ));
        assert!(gap.abs() <= AGREE_S, "{}", report.join("\n"));
    }
    println!("{}", report.join("\n"));
    assert_eq!(
        report.len(),
        12,
        "the six studies of the fixture, read back too"
    );
    // A system under test for an ego that the storyboard moves would never drive: refused.
    let last = last.unwrap();
    let o = fuzz(&[
        last.to_str().unwrap(),
        "--scripted-ego",
        "--sut",
        "aeb",
        "--budget",
        "1",
        "--out",
        dir.path().join("refused").to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2), "{o:?}");
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("--scripted-ego"),
        "{o:?}"
    );
}
