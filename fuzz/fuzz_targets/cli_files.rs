//! Fuzz target `cli_files`: the files a user hands to `nc-conform run` / `check`, through the command line.
//! The logic is `nc_conform::cli::fuzz_files::cli_files`, which `cargo test` replays on stable.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| nc_conform::cli::fuzz_files::cli_files(data));
