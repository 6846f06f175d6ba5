//! Issue 17: a campaign runs from the library, reports to observers, and its errors are typed;
//! the binary is a thin front end (a closed stdout pipe is not an error).

use std::io::Read;
use std::process::{Command, Stdio};
use std::sync::Arc;

use paracosm::campaign::session::{Plan, Request};
use paracosm::{CampaignReport, Error, Observer, RunRecord, Status};
use paracosm_generators::Assignment;
use paracosm_scenarios::front_end::{Findings, Source};
use paracosm_scenarios::{FrontEnd, ScenarioError};

/// An observer that checks the order of the calls and counts what it saw.
#[derive(Default)]
struct Tally {
    started: bool,
    ids: Vec<u64>,
    failed: u64,
    finished: Option<u64>,
}

impl Observer for Tally {
    fn started(&mut self, prior: &[RunRecord]) -> Result<(), Error> {
        assert!(!self.started && prior.is_empty());
        self.started = true;
        Ok(())
    }

    fn record(&mut self, r: &RunRecord) -> Result<(), Error> {
        assert!(self.started && self.finished.is_none());
        self.ids.push(r.id);
        self.failed += u64::from(r.status == Status::Fail);
        Ok(())
    }

    fn finished(&mut self, report: &CampaignReport) -> Result<(), Error> {
        self.finished = Some(report.counts.fail);
        Ok(())
    }
}

#[test]
fn a_campaign_runs_from_the_library_with_a_custom_observer() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let mut request = Request::new("pedestrian-crossing", &out);
    request.budget = Some(40);
    request.jobs = Some(2);
    let mut tally = Tally::default();
    let mut planned = 0;
    let outcome = paracosm::campaign::session::run(
        &request,
        None,
        &mut |p: &Plan<'_>| planned = p.to_run,
        &mut [&mut tally],
    )
    .unwrap();
    assert_eq!(planned, 40);
    assert_eq!(tally.ids, (0..40).collect::<Vec<_>>());
    let summary = outcome.summary.as_ref().unwrap();
    assert_eq!(tally.failed, summary.counts.fail);
    assert_eq!(tally.finished, Some(summary.counts.fail));
    assert!(summary.counts.fail > 0);
    assert_eq!(outcome.exit_code(), 1);
    let lines = std::fs::read_to_string(out.join("results.jsonl")).unwrap();
    assert_eq!(lines.lines().count(), 40);
    // summary.json reads back as the summary that was written.
    assert_eq!(
        &paracosm::report::summary::Summary::read(&out).unwrap(),
        summary
    );
    // The same folder again is refused with a typed error (exit code 2), keeping its files.
    let again = paracosm::campaign::session::run(&request, None, &mut |_: &Plan<'_>| {}, &mut []);
    let e = again.unwrap_err();
    assert!(matches!(e, Error::BadInput(_)), "{e}");
    assert_eq!(e.exit_code(), 2);
    assert_eq!(
        std::fs::read_to_string(out.join("results.jsonl")).unwrap(),
        lines
    );
}

/// The pedestrian study's front end, with a defect: a world with a walking speed above
/// 1.5 m/s panics while it is built.
struct Defective(Arc<dyn FrontEnd>);

impl FrontEnd for Defective {
    fn space(&self) -> &paracosm_generators::ParamSpace {
        self.0.space()
    }

    fn with_scene(
        &self,
        assignment: Option<&Assignment>,
        run: &mut dyn FnMut(&paracosm_scenarios::scene::Scene, &mut dyn paracosm_engine::rx::Host),
    ) -> Result<(), ScenarioError> {
        if let Some(speed) = assignment.and_then(|a| a.real("walking_speed")) {
            if speed > 1.5 {
                panic!("a defect at walking speed {speed:?}");
            }
        }
        self.0.with_scene(assignment, run)
    }

    fn source(&self) -> Source {
        self.0.source()
    }

    fn findings(&self) -> Findings {
        self.0.findings()
    }
}

#[test]
fn a_panic_in_a_simulation_is_an_internal_error_record_not_a_failure_of_the_system() {
    let study = paracosm_scenarios::reference::scenario();
    let scenario =
        paracosm_scenarios::Scenario::new(Arc::new(Defective(study.front_end().clone()))).unwrap();
    let campaign = paracosm::Campaign {
        scenario: &scenario,
        strategy: paracosm_generators::Strategy::Halton,
        seed: 0,
        budget: 8,
        strength: 2,
        jobs: 2,
        stop_at_first_failure: false,
        points: None,
        trace: None,
    };
    let dir = tempfile::tempdir().unwrap();
    let report = campaign.run(dir.path(), |_| {}).unwrap();
    let errors: Vec<&RunRecord> = report
        .records
        .iter()
        .filter(|r| r.status == Status::Error)
        .collect();
    let panicked = report
        .records
        .iter()
        .filter(|r| r.params.as_ref().unwrap().real("walking_speed").unwrap() > 1.5)
        .count();
    assert!(panicked > 0 && panicked < 8, "{panicked}");
    assert_eq!(errors.len(), panicked);
    for r in errors {
        let e = r.error.as_deref().unwrap();
        assert!(
            e.starts_with("internal error: the simulation panicked: a defect at walking speed"),
            "{e}"
        );
        assert!(!e.contains("system under test"), "{e}");
    }
    assert_eq!(report.counts.error as usize, panicked);
}

/// Runs paracosm-fuzz with `args` and its stdout closed before it writes anything; returns
/// the exit code and stderr.
fn with_closed_stdout(args: &[&str], out: &std::path::Path) -> (i32, String) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_paracosm-fuzz"))
        .args(args)
        .arg("--out")
        .arg(out)
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let mut stderr = String::new();
    child
        .stderr
        .take()
        .unwrap()
        .read_to_string(&mut stderr)
        .unwrap();
    (child.wait().unwrap().code().unwrap(), stderr)
}

#[test]
fn a_closed_pipe_ends_quietly_with_the_campaigns_exit_code() {
    let dir = tempfile::tempdir().unwrap();
    // 20 tests hold a failure (exit 1), 3 do not (exit 0).
    for (budget, code) in [("20", 1), ("3", 0)] {
        let out = dir.path().join(budget);
        let (got, stderr) = with_closed_stdout(&["pedestrian-crossing", "--budget", budget], &out);
        assert_eq!(got, code, "{stderr}");
        assert!(
            !stderr.contains("panicked") && !stderr.contains("Broken pipe"),
            "{stderr}"
        );
        assert!(out.join("summary.json").exists());
    }
    let (got, stderr) = with_closed_stdout(&["--list"], &dir.path().join("list"));
    assert_eq!(got, 0, "{stderr}");
    assert!(stderr.is_empty(), "{stderr}");
    // `| head -1`, as a user types it.
    let o = Command::new("bash")
        .arg("-c")
        .arg(format!(
            "set -o pipefail; {} pedestrian-crossing --budget 20 --out {} | head -1",
            env!("CARGO_BIN_EXE_paracosm-fuzz"),
            dir.path().join("head").display()
        ))
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1), "{o:?}");
    assert_eq!(String::from_utf8_lossy(&o.stdout).lines().count(), 1);
    assert!(!String::from_utf8_lossy(&o.stderr).contains("panicked"));
}
