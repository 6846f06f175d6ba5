//! The `results.jsonl` readers (`--resume`, `merge`, `report`, `replay`, `paracosm-cover`) on
//! arbitrary text: they return errors, never panic.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    paracosm::fuzz::results(data);
});
