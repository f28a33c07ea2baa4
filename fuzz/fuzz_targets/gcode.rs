//! Fuzz target `gcode`: G-code parser and engine: the bytes as a program for every dialect.
//! The logic is `nc_conform::fuzz::gcode`, which `cargo test` replays on stable.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| nc_conform::fuzz::gcode(data));
