//! No items. paracosm-python depends on this crate so that the Python wheel's build turns on
//! the same features of shared third-party crates as `cargo test --workspace` does, and cargo
//! reuses those compiled crates instead of building them again (see this crate's Cargo.toml).
#![warn(missing_docs)]
