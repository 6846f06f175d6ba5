//! Hostile input, second round, requirement 3: a model declaring an absurd tensor is named.
//! `Expand` of a constant to `[100000, 100000]` (40 GB of f32) inside an otherwise small model:
//! tract allocates it while it optimises or first runs the model, and the counting allocator
//! (`paracosm_engine::memory`, installed here as in the binaries) refuses that allocation
//! before it is attempted: exit 2 and a message naming the model, not an abort.
//!
//! The load runs in a child process (this test binary, re-run with `PARACOSM_LOAD_MODEL`),
//! since the refusal ends the process.

use std::path::Path;
use std::process::Command;

use paracosm_engine::memory::CountingAlloc;
use paracosm_engine::sut::OnnxConfig;
use paracosm_experiments::onnx_export::Graph;

#[global_allocator]
static ALLOC: CountingAlloc = CountingAlloc;

const MANIFEST: &str = "\
[camera]
width = 160
height = 120
rate_hz = 10.0

[input]
width = 16
height = 8
crop = [40, 0, 0, 0]

[output]
throttle = 0
steering = 1
";

/// A `[1, 3, 8, 16] -> [1, 2]` model whose output adds the sum of a constant expanded to
/// `[side, side]`.
fn model(side: i64) -> Vec<u8> {
    let mut g = Graph::new();
    let x = g.input("image", &[1, 3, 8, 16]);
    let flat = g.flatten(&x);
    let weight = g.constant(&[2, 384], vec![0.0; 768]);
    let bias = g.constant(&[2], vec![0.1, 0.0]);
    let y = g.linear(&flat, &weight, &bias);
    let one = g.constant(&[1, 1], vec![1e-12]);
    let shape = g.int64_constant(&[2], vec![side, side]);
    let big = g.expand(&one, &shape);
    let sum = g.reduce_sum(&big);
    let out = g.add(&y, &sum);
    g.output(&out, &[1, 2]);
    g.encode("absurd", "a model with an absurd intermediate tensor")
}

fn write(dir: &Path, name: &str, bytes: &[u8]) -> std::path::PathBuf {
    let p = dir.join(format!("{name}.onnx"));
    std::fs::write(&p, bytes).unwrap();
    std::fs::write(dir.join(format!("{name}.toml")), MANIFEST).unwrap();
    p
}

#[test]
fn a_model_declaring_an_absurd_tensor_is_refused_naming_it() {
    if let Ok(path) = std::env::var("PARACOSM_LOAD_MODEL") {
        // The child: load, and say how it went.
        match OnnxConfig::load(Path::new(&path)) {
            Ok(_) => println!("LOADED"),
            Err(e) => println!("REFUSED: {e}"),
        }
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let run = |path: &Path| {
        Command::new(std::env::current_exe().unwrap())
            .args([
                "--exact",
                "a_model_declaring_an_absurd_tensor_is_refused_naming_it",
                "--nocapture",
                "--test-threads",
                "1",
            ])
            .env("PARACOSM_LOAD_MODEL", path)
            .output()
            .unwrap()
    };
    // The same model with a small intermediate loads.
    let small = write(dir.path(), "small", &model(100));
    let o = run(&small);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(
        out.contains("LOADED"),
        "{out}\n{}",
        String::from_utf8_lossy(&o.stderr)
    );
    // 10^10 elements: refused by its size, naming the model, exit 2.
    let huge = write(dir.path(), "huge", &model(100_000));
    let o = run(&huge);
    let stderr = String::from_utf8_lossy(&o.stderr);
    println!("{stderr}");
    assert_eq!(o.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("the ONNX model exceeded the heap limit of 2048 MiB")
            && stderr.contains("huge.onnx"),
        "{stderr}"
    );
}
