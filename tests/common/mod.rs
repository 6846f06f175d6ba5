//! Helpers shared by the command-line integration tests.
#![allow(dead_code)] // each test crate uses its own subset

use std::process::{Command, Output};

/// Runs `paracosm-fuzz` with `args` (with a runtime folder for Mesa, which wants one).
pub fn fuzz(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_paracosm-fuzz"))
        .args(args)
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .output()
        .expect("paracosm-fuzz runs")
}

/// Asserts the exit code, showing stdout and stderr when it differs.
pub fn expect_code(o: &Output, code: i32) {
    assert_eq!(
        o.status.code(),
        Some(code),
        "stdout: {}\nstderr: {}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
}
