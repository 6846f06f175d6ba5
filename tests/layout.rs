//! The workspace's dependency rules (DESIGN.md): `generators` and `oracles` depend on neither
//! rapier, wgpu, nor each other (nor any other crate of the workspace), even transitively; the
//! engine depends on no crate of the workspace but `paracosm-files`, the one door for input
//! files, which depends on none.

use std::process::Command;

fn normal_dependencies(package: &str) -> Vec<String> {
    let out = Command::new(env!("CARGO"))
        .args([
            "tree", "--locked", "-p", package, "-e", "normal", "--prefix", "none",
        ])
        .args(["--format", "{p}"])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("cargo tree runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout)
        .unwrap()
        .lines()
        .skip(1) // the package itself
        .filter_map(|l| l.split_whitespace().next().map(str::to_owned))
        .collect()
}

#[test]
fn generators_and_oracles_stay_free_of_physics_rendering_and_each_other() {
    for package in ["paracosm-generators", "paracosm-oracles"] {
        let deps = normal_dependencies(package);
        assert!(!deps.is_empty(), "{package} has dependencies");
        for dep in &deps {
            assert!(
                !dep.starts_with("rapier")
                    && !dep.starts_with("wgpu")
                    && !dep.starts_with("paracosm"),
                "{package} depends on {dep}"
            );
        }
    }
}

#[test]
fn the_engine_does_not_depend_on_generators_or_scenarios() {
    let deps = normal_dependencies("paracosm-engine");
    assert!(deps.iter().any(|d| d == "rapier3d"));
    assert!(
        deps.iter()
            .all(|d| !d.starts_with("paracosm") || d == "paracosm-files"),
        "{deps:?}"
    );
    let files = normal_dependencies("paracosm-files");
    assert!(
        files.iter().all(|d| !d.starts_with("paracosm")),
        "{files:?}"
    );
}
