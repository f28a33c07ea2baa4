//! Fuzz target `adapter_lines`: the adapter runner of `conform` against a fuzzed fake adapter process.
//! The logic is `nc_conform::fuzz::adapter_lines`, which `cargo test` replays on stable.
#![no_main]

libfuzzer_sys::fuzz_target!(
    init: {
        // As in the `nc-conform` binary (Rust's runtime does this before `main`, which libFuzzer
        // replaces): writing to an adapter that has gone gives EPIPE, not a deadly SIGPIPE.
        // SAFETY: setting a signal disposition at start-up, before any thread exists.
        unsafe { libc::signal(libc::SIGPIPE, libc::SIG_IGN) };
    },
    |data: &[u8]| nc_conform::fuzz::adapter_lines(data)
);
