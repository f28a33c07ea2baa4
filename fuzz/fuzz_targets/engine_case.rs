//! Fuzz target `engine_case`: the engine under a structured `Arbitrary` campaign case, checked against every invariant.
//! The logic is `nc_conform::fuzz::engine_case`, which `cargo test` replays on stable.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| nc_conform::fuzz::engine_case(data));
