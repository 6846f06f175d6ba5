//! Coverage of the valid space: a logical scenario's constraints (OpenSCENARIO's
//! `ConstraintGroup`s, a space file's `[[constraint]]`) keep every test on a valid point, the
//! summary says how much of the space is valid, and a space with no valid point is refused
//! at load.

use std::path::Path;
use std::process::Command;

fn fuzz(dir: &Path, args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_paracosm-fuzz"))
        .args(args)
        .current_dir(dir)
        .output()
        .unwrap()
}

fn alks() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/xosc/alks")
}

/// ALKS 4.3.2's variation gives lateral offsets (-1.75 m) and a deceleration (10 m/s²) its
/// template's constraint groups refuse: 175 of its 1,400 combinations. No campaign runs a
/// test on one (they were 21 and 20 errors of 150 before), the grid enumerates the valid
/// combinations only, and the summary gives the exact valid fraction.
#[test]
fn no_test_of_an_alks_campaign_runs_on_a_combination_its_template_refuses() {
    let out = tempfile::tempdir().unwrap();
    let file = "alks_scenario_4_3_2_follow_lead_vehicle_emergency_brake_variation.xosc";
    let scenario = paracosm::load_scenario(alks().join(file).to_str().unwrap()).unwrap();
    let space = scenario.space();
    assert!(space.is_constrained());
    for strategy in ["halton", "variation", "kwise"] {
        let folder = out.path().join(strategy);
        let o = fuzz(
            &alks(),
            &[
                file,
                "--strategy",
                strategy,
                "--budget",
                "40",
                "--out",
                folder.to_str().unwrap(),
            ],
        );
        let err = String::from_utf8_lossy(&o.stderr);
        let said = String::from_utf8_lossy(&o.stdout);
        assert!(matches!(o.status.code(), Some(0 | 1)), "{err}");
        assert!(
            said.contains("valid space: 87.5 % valid (1225 of 1400 combinations) under the template's constraint groups"),
            "{said}"
        );
        let summary: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(folder.join("summary.json")).unwrap())
                .unwrap();
        assert_eq!(summary["counts"]["error"], 0, "{strategy}: {err}");
        assert_eq!(summary["valid_space"]["fraction"]["valid"], 1225);
        assert_eq!(summary["valid_space"]["fraction"]["exact"], true);
        // 2-wise coverage counts the valid pairs only.
        let two = &summary["coverage"]["kwise"][1];
        assert_eq!(two["forbidden"], 18, "{two}");
        let results = std::fs::read_to_string(folder.join("results.jsonl")).unwrap();
        let mut n = 0;
        for line in results.lines() {
            let r = paracosm::RunRecord::from_line(line, space).unwrap();
            assert!(
                space.is_valid(&r.point).unwrap(),
                "{strategy}: test {} is forbidden",
                r.id
            );
            n += 1;
        }
        assert_eq!(n, 40);
    }
}

/// A variation whose every combination breaks its template's constraint groups tests
/// nothing: the load refuses it (exit 2), naming the constraint groups, before any test.
#[test]
fn a_variation_that_leaves_no_valid_combination_is_refused_at_load() {
    let dir = tempfile::tempdir().unwrap();
    let text = r#"<OpenSCENARIO><FileHeader revMajor="1" revMinor="3" date="2026-12-01T00:00:00" description="v" author="x"/>
<ParameterValueDistribution><ScenarioFile filepath="./concrete_scenarios/alks_scenario_4_3_1_follow_lead_vehicle_comfortable_template.xosc"/>
<Deterministic><DeterministicSingleParameterDistribution parameterName="LeadVehicle_Init_LateralOffset_m"><DistributionSet><Element value="-1.75"/><Element value="-3"/></DistributionSet></DeterministicSingleParameterDistribution></Deterministic>
</ParameterValueDistribution></OpenSCENARIO>"#;
    let copy = dir.path().join("alks");
    std::fs::create_dir(&copy).unwrap();
    copy_tree(
        &alks().join("concrete_scenarios"),
        &copy.join("concrete_scenarios"),
    );
    let file = copy.join("v.xosc");
    std::fs::write(&file, text).unwrap();
    let out = dir.path().join("out");
    let o = fuzz(
        &copy,
        &["v.xosc", "--budget", "5", "--out", out.to_str().unwrap()],
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("the constraints (the template's constraint groups) leave no valid point: none of 2 points tried is valid"),
        "{err}"
    );
    assert!(!out.join("results.jsonl").exists());
}

fn copy_tree(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        let target = to.join(e.file_name());
        if e.file_type().unwrap().is_dir() {
            copy_tree(&e.path(), &target);
        } else {
            std::fs::copy(e.path(), &target).unwrap();
        }
    }
}

/// `paracosm-cover` over a space file with `[[constraint]]`s: every design's points are
/// valid, the estimate gives the valid fraction with its interval and counts the valid
/// tuples, and a constraint naming no parameter is refused with its line and column.
#[test]
fn a_space_files_constraints_hold_in_every_design_and_the_estimate() {
    let dir = tempfile::tempdir().unwrap();
    let space = dir.path().join("space.toml");
    std::fs::write(
        &space,
        r#"[[param]]
name = "lane"
levels = [1, 2, 3]

[[param]]
name = "kind"
levels = ["car", "van", "truck", "bus"]

[[param]]
name = "speed"
interval = [0.0, 40.0]
unit = "m/s"

[[constraint]]
name = "slow_in_lane_2"
require = "lane != 2 or speed < 10"

[[constraint]]
name = "no_trucks_in_lane_1"
require = "not (lane == 1 and kind == 'truck')"
"#,
    )
    .unwrap();
    let cover = |args: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_paracosm-cover"))
            .args(args)
            .output()
            .unwrap()
    };
    let sp = space.to_str().unwrap();
    for strategy in ["random", "halton", "sobol", "ipog", "kwise"] {
        let o = cover(&[
            "generate",
            "--space",
            sp,
            "--strategy",
            strategy,
            "--budget",
            "300",
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let csv = String::from_utf8(o.stdout).unwrap();
        let rows: Vec<Vec<&str>> = csv
            .lines()
            .skip(1)
            .map(|l| l.split(',').collect())
            .collect();
        assert_eq!(rows.len(), 300, "{strategy}");
        for r in &rows {
            let speed: f64 = r[3].parse().unwrap();
            assert!(r[1] != "2" || speed < 10.0, "{strategy}: {r:?}");
            assert!(!(r[1] == "1" && r[2] == "truck"), "{strategy}: {r:?}");
        }
        let file = dir.path().join(format!("{strategy}.csv"));
        std::fs::write(&file, &csv).unwrap();
        let o = cover(&["estimate", "--space", sp, file.to_str().unwrap()]);
        let text = String::from_utf8_lossy(&o.stdout);
        assert!(o.status.success(), "{text}");
        // Valid: 1 - 1/12 - (1/3)(3/4) = 2/3, estimated from 4,096 points.
        assert!(
            text.contains("valid space       66.4 % valid (95 % interval 64.9–67.8 %"),
            "{text}"
        );
        assert!(
            text.contains("2-wise coverage     1.0000  (11 of 11 valid tuples; 1 forbidden)"),
            "{strategy}: {text}"
        );
        assert!(text.contains("valid-region gap"), "{text}");
    }
    let bad = dir.path().join("bad.toml");
    std::fs::write(
        &bad,
        "[[param]]\nname = \"lane\"\nlevels = [1, 2]\n\n[[constraint]]\nname = \"c\"\nrequire = \"lanes > 1\"\n",
    )
    .unwrap();
    let o = cover(&[
        "generate",
        "--space",
        bad.to_str().unwrap(),
        "--strategy",
        "halton",
        "--budget",
        "3",
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("bad.toml: line 7, column 11: constraint `c`"),
        "{err}"
    );
    assert!(err.contains("Variable `lanes` not found"), "{err}");
}

/// The pedestrian crossing with a `Require`: a fast walker is seen from far off. No test runs
/// where the constraint is false, the summary gives the valid fraction (analytically
/// 1 - (5/9.5)(15/55) = 85.6 %) inside its interval, and a `Require` that nothing meets, or
/// that reads a stream, is refused at load.
#[test]
fn a_programs_require_keeps_every_test_valid_and_is_refused_when_it_cannot_hold() {
    let dir = tempfile::tempdir().unwrap();
    let base = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/pedestrian_crossing.star"),
    )
    .unwrap();
    let with = |require: &str| base.replace("w = World", &format!("{require}\n\nw = World"));
    let write = |name: &str, text: String| {
        let f = dir.path().join(name);
        std::fs::write(&f, text).unwrap();
        f
    };
    let ok = write(
        "ok.star",
        with("Require(lambda p: p.walking_speed < 5 or p.trigger_distance >= 20, name = \"seen_far\")"),
    );
    let out = dir.path().join("out");
    let o = fuzz(
        dir.path(),
        &[
            ok.to_str().unwrap(),
            "--strategy",
            "halton",
            "--budget",
            "200",
            "--out",
            out.to_str().unwrap(),
        ],
    );
    let said = String::from_utf8_lossy(&o.stdout);
    assert!(
        matches!(o.status.code(), Some(0 | 1)),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["counts"]["error"], 0, "{said}");
    let f = &summary["valid_space"]["fraction"];
    let (lo, hi) = (f["lo"].as_f64().unwrap(), f["hi"].as_f64().unwrap());
    let truth = 1.0 - (5.0 / 9.5) * (15.0 / 55.0);
    assert!(lo <= truth && truth <= hi, "{f}");
    for line in std::fs::read_to_string(out.join("results.jsonl"))
        .unwrap()
        .lines()
    {
        let r: serde_json::Value = serde_json::from_str(line).unwrap();
        let (w, t) = (
            r["params"]["walking_speed"].as_f64().unwrap(),
            r["params"]["trigger_distance"].as_f64().unwrap(),
        );
        assert!(
            w < 5.0 || t >= 20.0,
            "test {} is forbidden: {w} m/s, {t} m",
            r["id"]
        );
    }
    for (name, require, needle) in [
        (
            "none.star",
            "Require(lambda p: p.walking_speed > 20, name = \"impossible\")",
            "leave no valid point",
        ),
        (
            "stream.star",
            "Require(lambda p: tick > 3)",
            "Operation `compare` not supported",
        ),
        (
            "typo.star",
            "Require(lambda p: p.speed > 3)",
            "p holds trigger_distance, walking_speed",
        ),
    ] {
        let f = write(name, with(require));
        let o = fuzz(
            dir.path(),
            &[
                f.to_str().unwrap(),
                "--budget",
                "3",
                "--out",
                dir.path()
                    .join(name)
                    .with_extension("out")
                    .to_str()
                    .unwrap(),
            ],
        );
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{name}: {err}");
        assert!(err.contains(needle), "{name}: {err}");
        assert!(err.contains(&format!("{name}:17:")), "{name}: {err}");
    }
}

/// `generate --model --optimise SECONDS` shrinks an IPOG array by simulated annealing, keeps
/// every allowed pair covered and no forbidden one, and gives the same array twice.
#[test]
fn the_post_optimisation_shrinks_a_pict_models_array() {
    let dir = tempfile::tempdir().unwrap();
    let model = dir.path().join("m.txt");
    let mut text = String::new();
    for p in 0..8 {
        text.push_str(&format!("P{p}: a, b, c, d\n"));
    }
    text.push_str("IF [P0] = \"a\" THEN [P1] <> \"b\";\n");
    std::fs::write(&model, text).unwrap();
    let rows = |seconds: &str| {
        let o = Command::new(env!("CARGO_BIN_EXE_paracosm-cover"))
            .args([
                "generate",
                "--model",
                model.to_str().unwrap(),
                "--optimise",
                seconds,
            ])
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        String::from_utf8(o.stdout).unwrap()
    };
    let plain = rows("0");
    let optimised = rows("1");
    assert_eq!(optimised, rows("1"), "the same budget gives the same array");
    let body = |t: &str| -> Vec<Vec<String>> {
        t.lines()
            .skip(1)
            .map(|l| l.split(',').map(str::to_owned).collect())
            .collect()
    };
    let (a, b) = (body(&plain), body(&optimised));
    println!("IPOG {} rows, optimised {}", a.len(), b.len());
    assert!(b.len() < a.len(), "{} -> {}", a.len(), b.len());
    for r in &b {
        assert!(!(r[0] == "a" && r[1] == "b"), "{r:?}");
    }
    for x in 0..8 {
        for y in x + 1..8 {
            for u in ["a", "b", "c", "d"] {
                for v in ["a", "b", "c", "d"] {
                    let forbidden = x == 0 && y == 1 && u == "a" && v == "b";
                    let seen = b.iter().any(|r| r[x] == u && r[y] == v);
                    assert_eq!(seen, !forbidden, "P{x}={u}, P{y}={v}");
                }
            }
        }
    }
}

/// A `Require` that forbids the representative values' neighbours (a speed tied to a kind)
/// does not make the load call a parameter unused: `speed` feeds the pedestrian, and
/// coverage keeps it.
#[test]
fn a_parameter_a_require_ties_to_another_is_not_called_unused() {
    let dir = tempfile::tempdir().unwrap();
    let base = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/pedestrian_crossing.star"),
    )
    .unwrap();
    let program = base.replace(
        "w = World",
        "kind = VarEnum([\"slow\", \"fast\"], name = \"kind\")\n\
         def matched(p):\n    if p.kind == \"fast\":\n        return p.walking_speed >= 3\n    \
         return p.walking_speed < 3\nRequire(matched)\n\nw = World",
    );
    let file = dir.path().join("tied.star");
    std::fs::write(&file, program).unwrap();
    let out = dir.path().join("out");
    let o = fuzz(
        dir.path(),
        &[
            file.to_str().unwrap(),
            "--budget",
            "64",
            "--out",
            out.to_str().unwrap(),
        ],
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(matches!(o.status.code(), Some(0 | 1)), "{err}");
    assert!(
        !err.contains("`walking_speed` is sampled but no object uses it"),
        "{err}"
    );
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let unused = summary["unused_params"].as_array().unwrap();
    assert!(!unused.iter().any(|u| u == "walking_speed"), "{unused:?}");
    assert_eq!(summary["counts"]["error"], 0);
}

/// A uniform model whose levels are a prime power starts the post-optimisation from Bush's
/// orthogonal array: 5^6 at strength 3 gets the 125 rows no array of strength 3 can go below,
/// every triple covered; with `--optimise 0` it stays IPOG's larger array.
#[test]
fn a_prime_power_model_gets_its_orthogonal_array() {
    let dir = tempfile::tempdir().unwrap();
    let model = dir.path().join("u5_6.txt");
    let text: String = (0..6).map(|p| format!("P{p}: a, b, c, d, e\n")).collect();
    std::fs::write(&model, text).unwrap();
    let rows = |seconds: &str| -> Vec<Vec<String>> {
        let o = Command::new(env!("CARGO_BIN_EXE_paracosm-cover"))
            .args(["generate", "--model", model.to_str().unwrap()])
            .args(["--strength", "3", "--optimise", seconds])
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        String::from_utf8(o.stdout)
            .unwrap()
            .lines()
            .skip(1)
            .map(|l| l.split(',').map(str::to_owned).collect())
            .collect()
    };
    let (plain, built) = (rows("0"), rows("0.1"));
    println!(
        "IPOG {} rows, from the construction {}",
        plain.len(),
        built.len()
    );
    assert_eq!(built.len(), 125);
    assert!(plain.len() > 125, "IPOG alone: {}", plain.len());
    let mut seen = std::collections::HashSet::new();
    for r in &built {
        for a in 0..6 {
            for b in a + 1..6 {
                for c in b + 1..6 {
                    seen.insert((a, b, c, r[a].clone(), r[b].clone(), r[c].clone()));
                }
            }
        }
    }
    assert_eq!(
        seen.len(),
        20 * 125,
        "every triple of levels in every 3 columns"
    );
}
