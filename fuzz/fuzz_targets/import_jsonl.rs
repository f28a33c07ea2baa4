//! Fuzz target `import_jsonl`: the jsonl importer on arbitrary bytes, strict and lenient.
//! The logic is `nc_conform::import::fuzz::import_jsonl`, which `cargo test` replays on stable.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| nc_conform::import::fuzz::import_jsonl(data));
