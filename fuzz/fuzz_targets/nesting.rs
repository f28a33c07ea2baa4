//! Fuzz target `nesting`: deep nesting (LinuxCNC expressions, o-words, recursion, VCD scopes) from a structured input.
//! The logic is `nc_conform::fuzz::nesting`, which `cargo test` replays on stable.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| nc_conform::fuzz::nesting(data));
