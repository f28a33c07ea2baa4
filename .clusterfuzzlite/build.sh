#!/bin/bash -eu
# Builds every cargo-fuzz target of fuzz/ for ClusterFuzzLite and ships, beside each binary, its
# seed corpus (fuzz/corpus/<target>/ plus the stored regressions), its dictionary and its
# libFuzzer options: input size; 60 s per input and no single allocation above 512 MiB (the
# project's promise for any hostile input); the whole process under the address sanitizer may
# grow to 2.5 GiB (its quarantine and shadow memory count too: at 512 MiB cli_files stopped on
# an "out-of-memory" after 1 129 inputs each under 80 MiB).
cd "$SRC/nc-conform"

# Debug assertions and overflow checks, as in the `cargo test` build that replays the inputs.
cargo fuzz build -O --debug-assertions

release=fuzz/target/x86_64-unknown-linux-gnu/release
for src in fuzz/fuzz_targets/*.rs; do
    t=$(basename "$src" .rs)
    cp "$release/$t" "$OUT/"
    # Seed corpus: the committed seeds and every regression input.
    seeds=$(mktemp -d)
    cp fuzz/corpus/"$t"/* "$seeds"/ 2>/dev/null || true
    find "fuzz/regressions/$t" -maxdepth 1 -type f ! -name README.md -exec cp {} "$seeds"/ \; 2>/dev/null || true
    (cd "$seeds" && zip -q -r "$OUT/${t}_seed_corpus.zip" .) || true
    rm -rf "$seeds"
    case "$t" in
        gcode) max_len=16384; cp fuzz/gcode.dict "$OUT/$t.dict" ;;
        scenario_yaml) max_len=16384; cp fuzz/scenario_yaml.dict "$OUT/$t.dict" ;;
        cli_files|nesting) max_len=65536 ;;
        *) max_len=4096 ;;
    esac
    cat > "$OUT/$t.options" <<OPTIONS
[libfuzzer]
max_len = $max_len
timeout = 60
rss_limit_mb = 2560
malloc_limit_mb = 512
close_fd_mask = 3
OPTIONS
done
