//! `paracosm-fuzz --points FILE`: tests chosen outside paracosm run as a campaign (strategy
//! `points`), resume and shard like any other, and bad files or settings are refused.

use std::path::Path;

mod common;
use common::{comparable, expect_code, fuzz};

const POINTS: &str = "\
lead_speed,brake_at,decel,friction,lead_color,oncoming,comment
5.5,2.25,9.0,0.15,white,true,ice and hard braking
14.0,11.0,2.5,0.85,red,false,dry and gentle
10.0,6.0,6.0,0.5,red,true,
15.0,2.0,10.0,0.1,white,false,the upper ends
";

#[test]
fn the_points_of_a_file_run_in_order_and_resume() {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("points.csv");
    std::fs::write(&csv, POINTS).unwrap();
    let out = dir.path().join("run");
    let args = |out: &Path| {
        vec![
            "follow-lead-car".to_owned(),
            "--points".into(),
            csv.display().to_string(),
            "--seed".into(),
            "7".into(),
            "--out".into(),
            out.display().to_string(),
        ]
    };
    let run = |a: Vec<String>| fuzz(&a.iter().map(String::as_str).collect::<Vec<_>>());
    let o = run(args(&out));
    assert!(matches!(o.status.code(), Some(0 | 1)), "{o:?}");
    let records: Vec<serde_json::Value> = std::fs::read_to_string(out.join("results.jsonl"))
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(records.len(), 4, "the budget is the row count");
    let speeds: Vec<f64> = records
        .iter()
        .map(|r| r["params"]["lead_speed"].as_f64().unwrap())
        .collect();
    assert_eq!(speeds[..3], [5.5, 14.0, 10.0]);
    // The interval's upper end is the largest value below it.
    assert!(speeds[3] > 14.999_999 && speeds[3] < 15.0);
    assert_eq!(records[0]["params"]["lead_color"], "white");
    assert_eq!(records[1]["params"]["oncoming"], false);
    assert!(records.iter().all(|r| r["strategy"] == "points"));
    let campaign: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("campaign.json")).unwrap()).unwrap();
    assert_eq!(campaign["strategy"], "points");
    assert_eq!(campaign["budget"], 4);
    assert_eq!(campaign["points"]["sha256"].as_str().unwrap().len(), 64);

    // Cut the campaign after two tests and resume it: the same records as a whole run.
    let whole = comparable(&out);
    let text = std::fs::read_to_string(out.join("results.jsonl")).unwrap();
    let two: String = text.lines().take(2).map(|l| format!("{l}\n")).collect();
    std::fs::write(out.join("results.jsonl"), two).unwrap();
    let mut resume = args(&out);
    resume.push("--resume".into());
    let o = run(resume.clone());
    assert!(matches!(o.status.code(), Some(0 | 1)), "{o:?}");
    assert_eq!(comparable(&out), whole);

    // A bare --resume (no scenario, no --points) reads the stored file again.
    std::fs::write(
        out.join("results.jsonl"),
        text.lines().next().unwrap().to_owned() + "\n",
    )
    .unwrap();
    let o = fuzz(&["--resume", "--out", out.to_str().unwrap()]);
    assert!(matches!(o.status.code(), Some(0 | 1)), "{o:?}");
    assert_eq!(comparable(&out), whole);

    // A changed file is refused on resume: its tests are not the campaign's.
    std::fs::write(&csv, POINTS.replace("5.5,", "6.5,")).unwrap();
    let o = run(resume);
    expect_code(&o, 2);
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("points file"),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let o = fuzz(&["--resume", "--out", out.to_str().unwrap()]);
    expect_code(&o, 2);
    assert!(String::from_utf8_lossy(&o.stderr).contains("changed since the campaign started"));
}

#[test]
fn bad_points_files_and_settings_are_refused_with_exit_2() {
    let dir = tempfile::tempdir().unwrap();
    let write = |name: &str, text: &str| {
        let p = dir.path().join(name);
        std::fs::write(&p, text).unwrap();
        p.display().to_string()
    };
    let good = write("good.csv", POINTS);
    let cases: Vec<(Vec<String>, &str)> = vec![
        (
            vec![
                "--points".into(),
                write("range.csv", "lead_speed,brake_at,decel,friction,lead_color,oncoming\n5,2,9,0.15,white,true\n20,2,9,0.15,white,true\n"),
            ],
            "range.csv:3: column 1 (`lead_speed`): value 20 is outside the domain [5, 15]",
        ),
        (
            vec![
                "--points".into(),
                write("level.csv", "lead_speed,brake_at,decel,friction,lead_color,oncoming\n5,2,9,0.15,green,true\n"),
            ],
            "`green` is not one of the levels red, white",
        ),
        (
            vec![
                "--points".into(),
                write("text.csv", "lead_speed,brake_at,decel,friction,lead_color,oncoming\nfast,2,9,0.15,red,true\n"),
            ],
            "`fast` is not a number",
        ),
        (
            vec!["--points".into(), write("missing.csv", "lead_speed,brake_at\n5,2\n")],
            "missing.csv",
        ),
        (vec!["--points".into(), write("empty.csv", "")], "empty"),
        (
            vec!["--points".into(), dir.path().join("absent.csv").display().to_string()],
            "absent.csv",
        ),
        (
            vec!["--points".into(), good.clone(), "--budget".into(), "3".into()],
            "--budget 3 differs from the 4 tests",
        ),
        (
            vec!["--points".into(), good.clone(), "--strategy".into(), "sobol".into()],
            "--strategy sobol cannot be used with it",
        ),
        (
            vec!["--strategy".into(), "points".into()],
            "give --points FILE",
        ),
    ];
    for (i, (extra, expected)) in cases.into_iter().enumerate() {
        let out = dir.path().join(format!("out{i}"));
        let mut args = vec![
            "follow-lead-car".to_owned(),
            "--out".into(),
            out.display().to_string(),
        ];
        args.extend(extra);
        let o = fuzz(&args.iter().map(String::as_str).collect::<Vec<_>>());
        expect_code(&o, 2);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert!(stderr.contains(expected), "case {i}: {stderr}");
        assert!(!out.join("results.jsonl").exists(), "case {i}: nothing ran");
    }
}
