//! The scenario language front end (parse, check, evaluate with limits) on arbitrary
//! programs: it returns errors, never panics or overflows the stack.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    paracosm::fuzz::scenario(data);
});
