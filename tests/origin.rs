//! Issue 22, requirement 4: records prove their origin. `--resume` and `merge` check each
//! record's campaign tag, seed, strategy and point against the campaign and refuse a foreign
//! one, naming its line; a hand-edited campaign.json is refused naming the field.

use std::path::Path;

mod common;
use common::{expect_code, fuzz, ran};

fn lines(dir: &Path) -> Vec<String> {
    std::fs::read_to_string(dir.join("results.jsonl"))
        .unwrap()
        .lines()
        .map(str::to_owned)
        .collect()
}

fn campaign(out: &Path, extra: &[&str]) {
    let mut args = vec!["pedestrian-crossing", "--budget", "60", "--out"];
    args.push(out.to_str().unwrap());
    args.extend(extra);
    ran(&fuzz(&args));
}

/// `line` without its `campaign` tag, as a line written by hand (or by an older version)
/// would be: the seed, strategy and point checks must catch it on their own.
fn untagged(line: &str) -> String {
    let mut v: serde_json::Value = serde_json::from_str(line).unwrap();
    assert!(v.as_object_mut().unwrap().remove("campaign").is_some());
    v.to_string()
}

/// A copy of `base` whose results are its first `keep` lines, with line `at` (from 1)
/// replaced by `line` (or `line` appended when `at == keep + 1`).
fn forged(base: &Path, to: &Path, keep: usize, at: usize, line: &str) {
    std::fs::create_dir_all(to).unwrap();
    std::fs::copy(base.join("campaign.json"), to.join("campaign.json")).unwrap();
    let mut l: Vec<String> = lines(base)[..keep].to_vec();
    if at == keep + 1 {
        l.push(line.to_owned());
    } else {
        l[at - 1] = line.to_owned();
    }
    std::fs::write(to.join("results.jsonl"), l.join("\n") + "\n").unwrap();
}

#[test]
fn resume_refuses_a_record_of_another_seed_strategy_or_point() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b, c) = (
        dir.path().join("a"),
        dir.path().join("b"),
        dir.path().join("c"),
    );
    campaign(&a, &[]);
    campaign(&b, &["--seed", "8"]);
    campaign(&c, &["--strategy", "random"]);
    let seed8 = lines(&b);
    let random = lines(&c);
    // The same id's record with another point (the next test's point and params).
    let mut moved: serde_json::Value = serde_json::from_str(&lines(&a)[49]).unwrap();
    let next: serde_json::Value = serde_json::from_str(&lines(&a)[50]).unwrap();
    moved["point"] = next["point"].clone();
    moved["params"] = next["params"].clone();
    let tag = |l: &str| {
        let v: serde_json::Value = serde_json::from_str(l).unwrap();
        v["campaign"].as_str().unwrap().to_owned()
    };
    let ours = tag(&lines(&a)[0]);
    assert_eq!(ours.len(), 16);
    assert!(lines(&a).iter().all(|l| tag(l) == ours));
    assert_ne!(tag(&seed8[0]), ours);
    let tagged = format!(
        "test 49 carries campaign tag `{}`, this campaign's is `{ours}`",
        tag(&seed8[0])
    );
    let cases = [
        ("tagged", 55, 50, seed8[49].clone(), tagged.as_str()),
        ("seed8", 55, 50, untagged(&seed8[49]), "has seed"),
        (
            "random",
            55,
            50,
            untagged(&random[49]),
            "has strategy `random`",
        ),
        ("appended", 50, 51, untagged(&seed8[50]), "has seed"),
        (
            "moved",
            55,
            50,
            moved.to_string(),
            "point is not the one halton proposes",
        ),
    ];
    for (name, keep, at, line, phrase) in cases {
        let d = dir.path().join(name);
        forged(&a, &d, keep, at, &line);
        let before = std::fs::read(d.join("results.jsonl")).unwrap();
        let o = fuzz(&["--resume", "--out", d.to_str().unwrap()]);
        expect_code(&o, 2);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            err.contains(&format!("results.jsonl:{at}: ")),
            "{name}: {err}"
        );
        assert!(err.contains(phrase), "{name}: {err}");
        // Refused before any test: the file is as it was.
        assert_eq!(
            std::fs::read(d.join("results.jsonl")).unwrap(),
            before,
            "{name}"
        );
    }
    // The untouched prefix resumes to the clean run's results.
    let d = dir.path().join("clean");
    forged(&a, &d, 50, 50, &lines(&a)[49]);
    ran(&fuzz(&["--resume", "--out", d.to_str().unwrap()]));
    assert_eq!(common::comparable(&d), common::comparable(&a));
}

#[test]
fn merge_refuses_a_shard_with_a_foreign_record() {
    let dir = tempfile::tempdir().unwrap();
    let shard = |i: usize, seed: &str| {
        let out = dir.path().join(format!("s{i}-{seed}"));
        let s = format!("{i}/2");
        ran(&fuzz(&[
            "pedestrian-crossing",
            "--budget",
            "40",
            "--seed",
            seed,
            "--shard",
            &s,
            "--out",
            out.to_str().unwrap(),
        ]));
        out
    };
    let (s0, s1, other) = (shard(0, "0"), shard(1, "0"), shard(1, "8"));
    let clean = lines(&s1);
    let out = dir.path().join("merged");
    for (line, phrase) in [
        (
            lines(&other)[3].clone(),
            "results.jsonl:4: test 23 carries campaign tag",
        ),
        (
            untagged(&lines(&other)[3]),
            "results.jsonl:4: test 23 has seed",
        ),
    ] {
        let mut l = clean.clone();
        l[3] = line;
        std::fs::write(s1.join("results.jsonl"), l.join("\n") + "\n").unwrap();
        let o = fuzz(&[
            "merge",
            s0.to_str().unwrap(),
            s1.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ]);
        expect_code(&o, 2);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.contains(phrase), "{err}");
        assert!(!out.join("results.jsonl").exists());
    }
    // A shard whose campaign.json was edited is refused naming the field.
    std::fs::write(s1.join("results.jsonl"), clean.join("\n") + "\n").unwrap();
    let path = s1.join("campaign.json");
    let mut c: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    c["strength"] = 3.into();
    std::fs::write(&path, c.to_string()).unwrap();
    let o = fuzz(&[
        "merge",
        s0.to_str().unwrap(),
        s1.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    expect_code(&o, 2);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("edited by hand (strength no longer"), "{err}");
}

#[test]
fn resume_names_what_changed_the_program_or_a_hand_edited_campaign_json() {
    let dir = tempfile::tempdir().unwrap();
    let program = dir.path().join("walk.star");
    let source = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/pedestrian_crossing.star"),
    )
    .unwrap();
    std::fs::write(&program, &source).unwrap();
    let run = |out: &Path| {
        ran(&fuzz(&[
            program.to_str().unwrap(),
            "--budget",
            "10",
            "--out",
            out.to_str().unwrap(),
        ]))
    };
    let resume = |out: &Path| {
        let o = fuzz(&["--resume", "--out", out.to_str().unwrap()]);
        expect_code(&o, 2);
        String::from_utf8_lossy(&o.stderr).into_owned()
    };
    // A field of campaign.json edited by hand: the message names it.
    for (name, field, value) in [
        ("seed", "seed", serde_json::json!(5)),
        ("budget", "budget", serde_json::json!(11)),
        (
            "shard",
            "shard",
            serde_json::json!({"index": 0, "count": 2}),
        ),
        ("fp", "fingerprint", serde_json::json!("0".repeat(64))),
    ] {
        let edited = dir.path().join(name);
        run(&edited);
        let path = edited.join("campaign.json");
        let mut c: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
        c[field] = value;
        std::fs::write(&path, c.to_string()).unwrap();
        let err = resume(&edited);
        assert!(
            err.contains(&format!(
                "campaign.json was edited by hand: `{field}` no longer matches"
            )),
            "{err}"
        );
    }
    // A file without the checks (older versions) still says what it can.
    let legacy = dir.path().join("legacy");
    run(&legacy);
    let path = legacy.join("campaign.json");
    let mut c: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    c.as_object_mut().unwrap().remove("checks");
    c["seed"] = 5.into();
    std::fs::write(&path, c.to_string()).unwrap();
    let err = resume(&legacy);
    assert!(err.contains("campaign.json was edited"), "{err}");
    assert!(err.contains("the scenario program is unchanged"), "{err}");
    // The program's text changed (a comment added).
    let changed = dir.path().join("changed");
    run(&changed);
    std::fs::write(&program, format!("# a new comment\n{source}")).unwrap();
    let err = resume(&changed);
    assert!(
        err.contains("walk.star` changed since the campaign started (its SHA-256 differs)"),
        "{err}"
    );
}
