#!/usr/bin/env bash
# The test suite on a machine without Rust (a GPU machine): pack the test binaries here, carry
# the repository with the archive there, run them there.
#
#   scripts/gpu-tests.sh pack [ARCHIVE]          here: builds the tests and writes the stripped
#                                                binaries into one archive (default
#                                                target/gpu-tests.tar.xz, about 20 MB)
#   scripts/gpu-tests.sh run ARCHIVE [LOG_DIR]   there, from the repository's root: runs every
#                                                binary (four at a time), one log each in LOG_DIR
#                                                (default target/gpu-tests), and prints a summary
#
# The binaries find `fixtures/` and the command-line binary (`cli`, `hostile`) through the path
# they were built at; `run` links that path to the repository it runs from when they differ and
# puts the packed command-line binary at target/debug/deep-gbuffer where none is.
set -euo pipefail
cd "$(dirname "$0")/.."

case "${1:-}" in
pack)
    archive=${2:-target/gpu-tests.tar.xz}
    cargo test --all-features --no-run
    staging=$(mktemp -d)
    mkdir -p "$staging/t/bin"
    for file in tests/*.rs; do
        name=$(basename "$file" .rs)
        binary=$(ls -t target/debug/deps/"$name"-* | grep -v '\.d$' | head -n 1)
        cp "$binary" "$staging/t/$name"
    done
    cp target/debug/deep-gbuffer "$staging/t/bin/"
    find "$staging/t" -type f -exec strip {} +
    # Where the binaries look for the fixtures.
    pwd > "$staging/t/built-at"
    tar cf - -C "$staging" t | xz -T0 -9 > "$archive"
    rm -rf "$staging"
    echo "wrote $archive"
    ;;
run)
    archive=${2:?usage: scripts/gpu-tests.sh run ARCHIVE [LOG_DIR]}
    logs=${3:-target/gpu-tests}
    mkdir -p "$logs" target/tmp
    unpacked=$(mktemp -d)
    tar xJf "$archive" -C "$unpacked"
    built=$(cat "$unpacked/t/built-at")
    if [ "$built" != "$PWD" ] && [ ! -e "$built" ]; then
        mkdir -p "$(dirname "$built")"
        ln -s "$PWD" "$built"
    fi
    mkdir -p target/debug
    [ -e target/debug/deep-gbuffer ] || cp "$unpacked/t/bin/deep-gbuffer" target/debug/
    for binary in "$unpacked"/t/*; do
        name=$(basename "$binary")
        [ -f "$binary" ] && [ "$name" != built-at ] || continue
        ("$binary" --test-threads 8 > "$logs/$name.log" 2>&1; echo "rc=$?" >> "$logs/$name.log") &
        while [ "$(jobs -r | wc -l)" -ge 4 ]; do sleep 0.2; done
    done
    wait
    for log in "$logs"/*.log; do
        echo "$(basename "$log" .log): $(grep -E '^test result' "$log" | tail -n 1) $(tail -n 1 "$log")"
    done
    grep -h -E '^test .* FAILED' "$logs"/*.log || true
    rm -rf "$unpacked"
    ;;
*)
    echo "usage: scripts/gpu-tests.sh pack [ARCHIVE] | run ARCHIVE [LOG_DIR]" >&2
    exit 2
    ;;
esac
