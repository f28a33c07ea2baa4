//! Fuzz target `adapter_lines`: the adapter runner of `conform` against a fuzzed fake adapter process.
//! The logic is `nc_conform::fuzz::adapter_lines`, which `cargo test` replays on stable.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| nc_conform::fuzz::adapter_lines(data));
