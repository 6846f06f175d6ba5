//! OpenSCENARIO files as `paracosm-fuzz xosc` reads them: parameters, expressions,
//! distributions and the storyboard; it returns errors, never panics, loops or overflows the
//! stack.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    paracosm::fuzz::openscenario(data);
});
