//! Fuzz target `import_csv`: the csv importer on arbitrary bytes, strict and lenient.
//! The logic is `nc_conform::import::fuzz::import_csv`, which `cargo test` replays on stable.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| nc_conform::import::fuzz::import_csv(data));
