#!/usr/bin/env bash
# Runs one libFuzzer target for a number of seconds, or minimises its corpus:
#
#     bash scripts/fuzz.sh TARGET SECONDS
#     bash scripts/fuzz.sh merge TARGET
#
# TARGET is gltf_loader, ray_file or build_trace (tests/fuzz/fuzz_TARGET.cpp). Configures and
# builds the `fuzz` preset (clang, ASan + UBSan + libFuzzer; scripts/install-fuzz-deps.sh
# installs clang) into $REBRAID_FUZZ_BUILD (default build-fuzz/).
#
# Fuzzing runs one process (the machine may be shared), keeps the growing corpus in
# <build>/fuzz-corpus/TARGET (started from the seeds in tests/fuzz/seeds/TARGET and the
# committed corpus in tests/fuzz/corpus/TARGET) and writes any crashing input to
# <build>/fuzz-artifacts/TARGET/. Prints libFuzzer's final statistics (executions, coverage)
# and exits non-zero on a crash.
#
# `merge` minimises (libFuzzer -merge=1) the committed corpus and the grown corpus into a fresh
# folder that replaces tests/fuzz/corpus/TARGET: a small set of inputs that adds to the seeds'
# coverage everything the two corpora reach. The `asan` tests replay the seeds and that
# corpus (tests/fuzz/replay.cmake).
set -euo pipefail
cd "$(dirname "$0")/.."
usage="usage: bash scripts/fuzz.sh gltf_loader|ray_file|build_trace SECONDS
       bash scripts/fuzz.sh merge gltf_loader|ray_file|build_trace"
if [ $# -ne 2 ]; then
    echo "$usage" >&2
    exit 2
fi
mode=fuzz
if [ "$1" = merge ]; then
    mode=merge
    target="$2"
else
    target="$1"
    seconds="$2"
fi
case "$target" in
    gltf_loader | ray_file | build_trace) ;;
    *) echo "fuzz.sh: unknown target '$target' (gltf_loader, ray_file, build_trace)" >&2; exit 2 ;;
esac
build="${REBRAID_FUZZ_BUILD:-build-fuzz}"
if [ ! -f "$build/CMakeCache.txt" ]; then
    cmake --preset fuzz -B "$build" >/dev/null
fi
cmake --build "$build" --target "fuzz_$target" >/dev/null

seeds="tests/fuzz/seeds/$target"
committed="tests/fuzz/corpus/$target"
corpus="$build/fuzz-corpus/$target"
artifacts="$build/fuzz-artifacts/$target"
mkdir -p "$corpus" "$artifacts"
extra=()
if [ "$target" = gltf_loader ]; then
    # The seeds (tests/fuzz/make_gltf_seeds.py) come in both containers and stay below 12 KiB:
    # longer inputs would be truncated on loading.
    extra+=(-dict=tests/fuzz/gltf.dict -max_len=16384)
fi
if [ "$target" = build_trace ]; then
    # Every input decodes to a whole scene, so full-length inputs are useful from the start.
    extra+=(-max_len=1024 -len_control=0)
fi

if [ "$mode" = merge ]; then
    fresh="$build/fuzz-merged/$target"
    rm -rf "$fresh"
    mkdir -p "$fresh"
    # The seeds go in first, as inputs libFuzzer takes as already there, and out again after:
    # the committed corpus keeps only what adds coverage beyond the seeds (the replay tests
    # run both).
    if [ -d "$seeds" ]; then cp "$seeds"/* "$fresh"/; fi
    sources=()
    for dir in "$committed" "$corpus"; do
        if [ -d "$dir" ]; then sources+=("$dir"); fi
    done
    "$build/tests/fuzz/fuzz_$target" -merge=1 -timeout=20 -rss_limit_mb=2048 \
        "${extra[@]}" "$fresh" "${sources[@]}"
    if [ -d "$seeds" ]; then
        for seed in "$seeds"/*; do rm -f "$fresh/$(basename "$seed")"; done
    fi
    rm -rf "$committed"
    mkdir -p "$(dirname "$committed")"
    cp -r "$fresh" "$committed"
    echo "fuzz.sh: $committed: $(find "$committed" -type f | wc -l) files," \
         "$(du -sb "$committed" | cut -f1) bytes"
    exit 0
fi

for dir in "$seeds" "$committed"; do
    if [ -d "$dir" ]; then
        cp -n "$dir"/* "$corpus"/ 2>/dev/null || true
    fi
done
exec "$build/tests/fuzz/fuzz_$target" "$corpus" -max_total_time="$seconds" -timeout=20 \
    -rss_limit_mb=2048 -print_final_stats=1 -artifact_prefix="$artifacts/" "${extra[@]}"
