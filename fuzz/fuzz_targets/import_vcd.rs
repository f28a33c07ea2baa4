//! Fuzz target `import_vcd`: the vcd importer on arbitrary bytes, strict and lenient.
//! The logic is `nc_conform::import::fuzz::import_vcd`, which `cargo test` replays on stable.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| nc_conform::import::fuzz::import_vcd(data));
