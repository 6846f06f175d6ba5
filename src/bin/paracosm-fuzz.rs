//! `paracosm-fuzz`: run a test campaign on a scenario and report the failures it finds.
//!
//! Exit codes: 0 no failure found, 1 a test failed, 2 bad input or usage, 3 a test in error,
//! an output that cannot be written or an internal error, 130 interrupted.

use std::io::Write;
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};

use anyhow::{Context, Result};

use paracosm::campaign::progress::Progress;
use paracosm::campaign::session::Plan;
use paracosm::cli::fuzz::{Cli, Command as Sub, ExportArgs, MapArgs, MergeArgs, ReplayArgs};
use paracosm::cli::process::{
    exit_without_teardown, interrupted_code, render_on_the_calling_thread, runtime_dir,
    stop_on_signals, STOP,
};
use paracosm::Error;

/// Counts what Starlark evaluation allocates, so one huge allocation of a program or lambda is a
/// clear error with exit code 2 instead of an abort (`paracosm_scenarios::memory`).
#[global_allocator]
static ALLOC: paracosm_scenarios::memory::CountingAlloc = paracosm_scenarios::memory::CountingAlloc;

fn main() -> ExitCode {
    render_on_the_calling_thread();
    runtime_dir();
    paracosm_scenarios::memory::set_tool_name("paracosm-fuzz");
    stop_on_signals();
    // What an external system under test leaves outside its process group (a `setsid`
    // helper, a double fork) is adopted by this process and killed with the program. Without
    // it (an old kernel) such helpers are only killed with the group, as documented.
    if let Err(e) = paracosm_engine::sut::track_orphans() {
        tracing::debug!("PR_SET_CHILD_SUBREAPER: {e}");
    }
    let cli = match paracosm::cli::parse_args::<Cli>("paracosm-fuzz") {
        Ok(cli) => cli,
        Err(code) => return code,
    };
    tracing_subscriber::fmt()
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env()
                .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new("warn")),
        )
        .with_writer(std::io::stderr)
        .init();
    let result = match &cli.command {
        Some(Sub::Replay(a)) => replay(a),
        Some(Sub::Merge(a)) => merge(a),
        Some(Sub::Report(a)) => paracosm::report::reread(&a.dir, &a.redraw)
            .map_err(anyhow::Error::new)
            .and_then(|(text, counts)| say(&text).map(|()| counts.exit_code())),
        Some(Sub::Dataset(a)) => a
            .request()
            .and_then(|r| paracosm::export::dataset::export(&r, Some(&STOP)))
            .map_err(anyhow::Error::new)
            .and_then(|s| say(&s.text()).map(|()| s.exit_code())),
        Some(Sub::Export(a)) => export(a),
        Some(Sub::Map(a)) => map(a),
        Some(Sub::Xosc(a)) => paracosm_scenarios::xosc::inspect_with_map(
            &a.file,
            &a.open,
            a.continuous,
            (a.maps.as_deref(), a.carla),
        )
        .map_err(|e| anyhow::Error::new(Error::from(e)))
        .and_then(|i| say(&i.text()).map(|()| 0)),
        None => run(&cli),
    };
    let code = match result {
        Ok(code) => interrupted_code(code),
        Err(e) => {
            paracosm::cli::to_stderr(&paracosm::cli::error_text(
                "paracosm-fuzz",
                &format!("{e:#}"),
            ));
            e.downcast_ref::<Error>().map_or(3, Error::exit_code)
        }
    };
    drop(cli);
    exit_without_teardown(code)
}

/// Writes `text` and a newline to stdout. A reader that has gone (`| head`) is not an
/// error: the rest of stdout is dropped and the process exits with the campaign's code, as
/// ripgrep does.
fn say(text: &str) -> Result<()> {
    static GONE: AtomicBool = AtomicBool::new(false);
    if GONE.load(Ordering::Relaxed) {
        return Ok(());
    }
    match writeln!(std::io::stdout().lock(), "{text}") {
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => {
            GONE.store(true, Ordering::Relaxed);
            Ok(())
        }
        other => other.context("cannot write to stdout"),
    }
}

/// `paracosm-fuzz map`: the listing on stdout, the importer's warnings on stderr, then the
/// drawings.
fn map(a: &MapArgs) -> Result<u8> {
    for (p, option) in [(&a.png, "--png"), (&a.svg, "--svg")] {
        if let Some(p) = p {
            paracosm::atomic::check_output(p, option, &[&a.file])?;
        }
    }
    let listing = paracosm::map::read(&a.file)?;
    for w in &listing.warnings {
        paracosm::cli::to_stderr(&format!("paracosm-fuzz: warning: {w}"));
    }
    let mut wrote = Vec::new();
    if let Some(p) = &a.png {
        wrote.push(listing.draw_png(p)?.display().to_string());
    }
    if let Some(p) = &a.svg {
        wrote.push(listing.draw_svg(p)?.display().to_string());
    }
    say(&listing.text())?;
    if !wrote.is_empty() {
        say(&format!("wrote: {}", wrote.join(", ")))?;
    }
    Ok(0)
}

fn run(cli: &Cli) -> Result<u8> {
    if cli.list {
        for name in paracosm_scenarios::builtin_names() {
            let s =
                paracosm_scenarios::builtin(&name).context("a built-in scenario fails to load")?;
            let params: Vec<String> = s.space().params().iter().map(|p| p.label()).collect();
            say(&format!(
                "{name}\n    {}\n    parameters: {}",
                s.description(),
                params.join(", ")
            ))?;
        }
        return Ok(0);
    }
    let mut progress = Progress::new(cli.verbose);
    let bar = progress.clone();
    let mut plan = |p: &Plan<'_>| {
        bar.hold(
            p.notes()
                .iter()
                .map(|n| format!("paracosm-fuzz: {n}"))
                .collect(),
        );
        bar.start(p.to_run);
    };
    let held = progress.clone();
    let outcome = paracosm::campaign::session::run(
        &cli.request()?,
        Some(&STOP),
        &mut plan,
        &mut [&mut progress],
    );
    let outcome = match outcome {
        Ok(o) => o,
        Err(e) => {
            // The bar cleared, the error first, then the warnings the load found.
            held.finish();
            paracosm::cli::to_stderr(&paracosm::cli::error_text("paracosm-fuzz", &e.to_string()));
            held.release();
            return Ok(e.exit_code());
        }
    };
    progress.finish();
    outcome
        .notes()
        .iter()
        .for_each(|n| paracosm::cli::to_stderr(&format!("paracosm-fuzz: {n}")));
    if let Some(r) = paracosm_engine::render::Renderer::in_use() {
        // Which adapter drew the camera frames: a GPU, or lavapipe on the CPU.
        paracosm::cli::to_stderr(&format!("paracosm-fuzz: camera renderer: {}", r.adapter()));
    }
    if let Some(text) = outcome.human() {
        say(&text)?;
    }
    Ok(outcome.exit_code())
}

/// `paracosm-fuzz replay`: exit 0 when the replayed verdict equals the recorded one, 3 when not.
fn replay(a: &ReplayArgs) -> Result<u8> {
    let sut = a.sut.config();
    let trace = a
        .trace
        .clone()
        .map(|path| paracosm::export::trace::TraceSpec {
            path,
            every_s: a
                .trace_every
                .unwrap_or(paracosm::export::trace::DEFAULT_EVERY_S),
        });
    sut.and_then(|s| {
        paracosm::export::replay::replay_traced(&a.results, a.id, a.frames.as_deref(), s, trace)
    })
    .map_err(anyhow::Error::new)
    .and_then(|r| say(&r.text(a.id, a.frames.as_deref())).map(|()| r))
    .map(|r| if r.matches { 0 } else { 3 })
}

/// `paracosm-fuzz merge`: the merged campaign's summary on stdout, its warnings on stderr.
fn merge(a: &MergeArgs) -> Result<u8> {
    paracosm::campaign::merge::merge_folders(&a.dirs, &a.out, a.force, a.junit.as_deref())
        .map_err(anyhow::Error::new)
        .and_then(|(text, counts, warnings)| {
            warnings
                .iter()
                .for_each(|w| paracosm::cli::to_stderr(&format!("paracosm-fuzz: warning: {w}")));
            say(&text).map(|()| counts.exit_code())
        })
}

/// `paracosm-fuzz export`: exit 0, or 3 when the replayed verdict differs from the recorded one.
fn export(a: &ExportArgs) -> Result<u8> {
    let motion = if a.ego_route {
        paracosm::export::xosc::EgoMotion::Route
    } else {
        paracosm::export::xosc::EgoMotion::Trajectory
    };
    let e = paracosm::export::export(&a.results, a.id, &a.out, motion)?;
    let mut text = format!(
        "wrote {} (OpenSCENARIO 1.2) and {} (OpenDRIVE){}",
        e.xosc.display(),
        e.xodr.display(),
        if e.matches {
            ""
        } else {
            "\nwarning: the replayed verdict differs from the recorded one; the files describe the replay"
        }
    );
    if !e.not_in_file.is_empty() {
        text.push_str(&format!(
            "\nnote: OpenSCENARIO has no monitors: read back (paracosm-fuzz {} \
             --scripted-ego), the test is judged by collision and leaving the road; \
             its monitors {} are not in the file",
            e.xosc.display(),
            e.not_in_file.join(", ")
        ));
    }
    say(&text)?;
    Ok(if e.matches { 0 } else { 3 })
}
