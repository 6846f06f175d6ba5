//! OpenDRIVE maps as `OpenDrive(...)` reads them: checked, baked, indexed and routed; it
//! returns errors, never panics, loops or overflows the stack.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    paracosm::fuzz::opendrive(data);
});
