//! Fuzz target `scenario_yaml`: scenario files: the bytes as a scenario YAML file, loaded, run and rendered.
//! The logic is `nc_conform::fuzz::scenario_yaml`, which `cargo test` replays on stable.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| nc_conform::fuzz::scenario_yaml(data));
