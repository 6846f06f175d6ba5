//! The space (TOML) and test-set (CSV) readers of `paracosm-cover` on arbitrary text: they
//! return errors, never panic.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    paracosm::fuzz::inputs(data);
});
