//! Empty: cargo resolves a package's build-dependencies only when it has a build script, and
//! the build-dependencies are what pins the host crates' features (see Cargo.toml).
fn main() {}
