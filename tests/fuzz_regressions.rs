//! Replays every input kept in `fuzz/regressions/<target>/` through the fuzz targets' entry
//! points (`paracosm::fuzz`): inputs that once crashed a reader, or that fuzzing or the
//! hostile-input corpus found interesting, must now return errors without panicking.

use std::path::Path;

#[test]
fn kept_fuzz_inputs_no_longer_crash() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz/regressions");
    type Target = fn(&[u8]);
    let targets: [(&str, Target); 5] = [
        ("inputs", paracosm::fuzz::inputs),
        ("results", paracosm::fuzz::results),
        ("scenario", paracosm::fuzz::scenario),
        ("opendrive", paracosm::fuzz::opendrive),
        ("openscenario", paracosm::fuzz::openscenario),
    ];
    let mut n = 0;
    for (target, run) in targets {
        for entry in std::fs::read_dir(root.join(target)).unwrap() {
            let path = entry.unwrap().path();
            run(&std::fs::read(&path).unwrap());
            n += 1;
        }
    }
    assert!(n >= 3, "{n} inputs");
}
