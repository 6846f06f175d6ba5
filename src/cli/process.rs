//! What a command-line tool does with its process: Ctrl-C and SIGTERM, the environment the
//! GPU drivers want, and an exit past the drivers' exit handlers.

use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};

/// Set by SIGTERM (what Slurm and Kubernetes send to stop a job), besides [`STOP`]: the exit
/// code of an interrupted run is then 143 instead of 130.
static TERMINATED: AtomicBool = AtomicBool::new(false);

/// Ctrl-C (SIGINT) and SIGTERM: no new test starts; the tests in flight finish and are
/// written, and the tool says how to resume and exits 130 (SIGINT) or 143 (SIGTERM). A second
/// signal exits at once with that code.
pub fn stop_on_signals() {
    use signal_hook::consts::{SIGINT, SIGTERM};
    let Ok(mut signals) = signal_hook::iterator::Signals::new([SIGINT, SIGTERM]) else {
        return;
    };
    std::thread::spawn(move || {
        for signal in signals.forever() {
            if signal == SIGTERM {
                TERMINATED.store(true, Ordering::SeqCst);
            }
            if STOP.swap(true, Ordering::SeqCst) {
                std::process::exit(if signal == SIGTERM { 143 } else { 130 });
            }
        }
    });
}

/// The exit code of a run that ended with `code`: an interruption (130) by SIGTERM is 143.
pub fn interrupted_code(code: u8) -> u8 {
    if code == 130 && TERMINATED.load(Ordering::SeqCst) {
        143
    } else {
        code
    }
}

/// Gives Mesa's Vulkan loader the runtime folder it wants when the environment has none (a
/// sandbox, a batch job): without one it prints "error: XDG_RUNTIME_DIR is invalid or not
/// set" on every render, though rendering works. Set before any thread starts.
pub fn runtime_dir() {
    let valid =
        std::env::var_os("XDG_RUNTIME_DIR").is_some_and(|d| std::path::Path::new(&d).is_dir());
    if !valid {
        // One folder per user, kept between runs (as the loader's own would be).
        let user = std::env::var("USER").unwrap_or_else(|_| "user".into());
        let dir = std::env::temp_dir().join(format!("paracosm-xdg-{user}"));
        if std::fs::create_dir_all(&dir).is_ok() {
            #[cfg(unix)]
            {
                use std::os::unix::fs::PermissionsExt;
                let _ = std::fs::set_permissions(&dir, std::fs::Permissions::from_mode(0o700));
            }
            std::env::set_var("XDG_RUNTIME_DIR", &dir);
        }
    }
}

/// Mesa's CPU rasterisers (lavapipe, llvmpipe) render on the thread that submits unless
/// `LP_NUM_THREADS` asks for helper threads. Each camera frame is small and every worker
/// submits its own: helper threads only add hand-offs (about a tenth of a camera test's CPU
/// time, docs/performance.md, "The camera loop"). A value the user set is kept; a GPU ignores
/// it. Called first, before any thread starts.
pub fn render_on_the_calling_thread() {
    if std::env::var_os("LP_NUM_THREADS").is_none() {
        std::env::set_var("LP_NUM_THREADS", "0");
    }
}

/// Ends the process with `code`, stdout and stderr flushed, without the C library's exit
/// handlers. The camera's GPU device lives in a static that is never dropped, and Mesa's
/// lavapipe tears its driver down in those handlers while its worker threads may still run:
/// once, in CI, a campaign that had written every file aborted there ("corrupted size vs.
/// prev_size in fastbins", exit by signal 6 instead of 0). Every file is written, flushed and
/// closed before this (the campaign's writers are dropped when `run` returns).
pub fn exit_without_teardown(code: u8) -> ExitCode {
    use std::io::Write;
    let _ = std::io::stdout().flush();
    let _ = std::io::stderr().flush();
    #[cfg(unix)]
    // SAFETY: `_exit` ends the process at once; nothing runs after it.
    unsafe {
        libc::_exit(i32::from(code))
    }
    #[cfg(not(unix))]
    ExitCode::from(code)
}

/// Set by Ctrl-C or SIGTERM ([`stop_on_signals`]): no new test starts.
pub static STOP: AtomicBool = AtomicBool::new(false);
