//! Every fuzz target's entry point (`paracosm::fuzz`) on mutations of its seed corpus, in the
//! release build the other tests use: a deterministic smoke run of the readers of user input
//! (a panic is a bug, a stack overflow aborts the test). Coverage-guided fuzzing with
//! sanitizers is `scripts/fuzz` (cargo fuzz, a build of its own), run by hand.
//!
//! The corpus of each target is the one `scripts/fuzz` gives cargo fuzz. Each input is a seed
//! with one to four mutations drawn by a ChaCha8 generator seeded per target (bit flips,
//! interesting bytes, deleted, repeated and spliced ranges, numbers swapped for extreme ones),
//! so a failure reproduces: `PARACOSM_FUZZ_SEED` and `PARACOSM_FUZZ_RUNS` change the draw and
//! the count, `PARACOSM_FUZZ_VERBOSE=1` prints each input's index before it runs (for an input
//! that overflows the stack), and a panicking input is written to
//! `target/fuzz-smoke/<target>-<index>.bin`.

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The files under `dir` (recursively) whose names end with one of `ends` (all files when
/// empty), leaving out names starting with `skip`.
fn files(dir: &str, ends: &[&str], skip: Option<&str>, depth: usize) -> Vec<PathBuf> {
    fn walk(dir: &Path, depth: usize, out: &mut Vec<PathBuf>) {
        let Ok(entries) = std::fs::read_dir(dir) else {
            return;
        };
        for e in entries.flatten() {
            let p = e.path();
            if p.is_dir() {
                if depth > 1 {
                    walk(&p, depth - 1, out);
                }
            } else {
                out.push(p);
            }
        }
    }
    let mut out = Vec::new();
    walk(&root().join(dir), depth, &mut out);
    out.retain(|p| {
        let name = p.file_name().and_then(|n| n.to_str()).unwrap_or("");
        (ends.is_empty() || ends.iter().any(|e| name.ends_with(e)))
            && skip.is_none_or(|s| !name.starts_with(s))
    });
    out.sort();
    out
}

/// Numbers a mutation may put in place of one in the input.
const EXTREMES: [&str; 10] = [
    "0",
    "-1",
    "1e308",
    "-1e308",
    "NaN",
    "inf",
    "1e-320",
    "99999999999",
    "4294967296",
    "0.5",
];
/// Bytes a mutation may write.
const INTERESTING: [u8; 12] = [
    0, 0xff, b'<', b'>', b'"', b'\'', b'9', b'-', b'.', b'e', b'\n', b'(',
];

/// One mutation of `data`, with `other` (another seed) for splicing.
fn mutate(rng: &mut ChaCha8Rng, data: &mut Vec<u8>, other: &[u8]) {
    let n = data.len();
    let range = |rng: &mut ChaCha8Rng, n: usize| {
        let a = rng.random_range(0..=n);
        let b = (a + rng.random_range(1..=16)).min(n);
        (a, b)
    };
    match rng.random_range(0..6) {
        0 if n > 0 => {
            let i = rng.random_range(0..n);
            data[i] ^= 1 << rng.random_range(0..8);
        }
        1 if n > 0 => {
            let i = rng.random_range(0..n);
            data[i] = INTERESTING[rng.random_range(0..INTERESTING.len())];
        }
        2 => {
            let (a, b) = range(rng, n);
            data.drain(a..b);
        }
        3 => {
            let (a, b) = range(rng, n);
            let chunk: Vec<u8> = data[a..b].to_vec();
            for _ in 0..rng.random_range(1..=8) {
                data.splice(b..b, chunk.iter().copied());
            }
        }
        4 if !other.is_empty() => {
            let (a, b) = range(rng, other.len());
            let at = rng.random_range(0..=n);
            data.splice(at..at, other[a..b].iter().copied());
        }
        _ => {
            // A number (a run of digits) swapped for an extreme one.
            let digits: Vec<usize> = (0..n).filter(|&i| data[i].is_ascii_digit()).collect();
            if let Some(&i) = digits.get(rng.random_range(0..digits.len().max(1))) {
                let mut j = i;
                while j < n && (data[j].is_ascii_digit() || data[j] == b'.') {
                    j += 1;
                }
                let x = EXTREMES[rng.random_range(0..EXTREMES.len())];
                data.splice(i..j, x.bytes());
            }
        }
    }
}

/// Runs `target` on `runs` mutated seeds (after each seed as it is) and fails, naming the
/// saved inputs, when any panicked.
fn smoke(name: &str, target: fn(&[u8]), seeds: Vec<PathBuf>, runs: usize, salt: u64) {
    let seeds: Vec<Vec<u8>> = seeds.iter().map(|p| std::fs::read(p).unwrap()).collect();
    assert!(!seeds.is_empty(), "{name}: no seeds");
    let env = |k: &str| std::env::var(k).ok().and_then(|v| v.parse::<u64>().ok());
    let runs = env("PARACOSM_FUZZ_RUNS").map_or(runs, |r| r as usize);
    let seed = env("PARACOSM_FUZZ_SEED").unwrap_or(0) ^ salt;
    let verbose = std::env::var("PARACOSM_FUZZ_VERBOSE").is_ok_and(|v| v == "1");
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let out = root().join("target/fuzz-smoke");
    let mut failed = Vec::new();
    // Panics are caught and reported here; the default hook would print each one.
    let hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    for i in 0..seeds.len() + runs {
        let data = if i < seeds.len() {
            seeds[i].clone()
        } else {
            let mut d = seeds[rng.random_range(0..seeds.len())].clone();
            let other = &seeds[rng.random_range(0..seeds.len())];
            for _ in 0..rng.random_range(1..=4) {
                mutate(&mut rng, &mut d, other);
            }
            d
        };
        if verbose {
            eprintln!("{name} input {i} ({} bytes)", data.len());
        }
        if catch_unwind(AssertUnwindSafe(|| target(&data))).is_err() {
            std::fs::create_dir_all(&out).unwrap();
            let path = out.join(format!("{name}-{i}.bin"));
            std::fs::write(&path, &data).unwrap();
            failed.push(path);
        }
    }
    std::panic::set_hook(hook);
    assert!(
        failed.is_empty(),
        "{name}: {} inputs panicked (kept for fuzz/regressions/{name}/): {failed:?}",
        failed.len()
    );
}

#[test]
fn the_inputs_target_survives_mutated_seeds() {
    let mut seeds = files("tests/bad_inputs/spaces", &[], None, 8);
    seeds.extend(files("tests/bad_inputs/csv", &[], None, 8));
    seeds.extend(files("fuzz/regressions/inputs", &[], None, 8));
    smoke("inputs", paracosm::fuzz::inputs, seeds, 20_000, 1);
}

#[test]
fn the_results_target_survives_mutated_seeds() {
    let mut seeds = files("tests/bad_inputs/results", &[], None, 8);
    seeds.extend(files("tests/fixtures", &[], None, 8));
    seeds.extend(files("fuzz/regressions/results", &[], None, 8));
    smoke("results", paracosm::fuzz::results, seeds, 10_000, 2);
}

/// Programs and maps; `heap_*` programs allocate gigabytes on purpose and are run against
/// the binary (tests/bad_inputs.rs), as in `scripts/fuzz`.
#[test]
fn the_scenario_target_survives_mutated_seeds() {
    let mut seeds = files("scenarios", &[".star"], None, 1);
    seeds.extend(files("scenarios/maps", &[".xodr"], None, 8));
    seeds.extend(files("tests/bad_inputs/maps", &[".xodr"], None, 8));
    seeds.extend(files("tests/bad_inputs/scenarios", &[], Some("heap_"), 8));
    seeds.extend(files("fuzz/regressions/scenario", &[], None, 8));
    smoke("scenario", paracosm::fuzz::scenario, seeds, 600, 3);
}

#[test]
fn the_opendrive_target_survives_mutated_seeds() {
    let mut seeds = files("scenarios/maps", &[".xodr"], None, 8);
    seeds.extend(files("tests/bad_inputs/maps", &[".xodr"], None, 8));
    seeds.extend(files("fuzz/regressions/opendrive", &[], None, 8));
    smoke("opendrive", paracosm::fuzz::opendrive, seeds, 2_000, 4);
}

#[test]
fn the_openscenario_target_survives_mutated_seeds() {
    let mut seeds = files("tests/data/xosc", &[".xosc"], None, 8);
    seeds.extend(files("tests/bad_inputs/xosc", &[".xosc"], None, 8));
    seeds.extend(files("fuzz/regressions/openscenario", &[], None, 8));
    smoke(
        "openscenario",
        paracosm::fuzz::openscenario,
        seeds,
        5_000,
        5,
    );
}
