#!/usr/bin/env bash
# Runs one libFuzzer target for a number of seconds:
#
#     bash scripts/fuzz.sh TARGET SECONDS
#
# TARGET is gltf_loader, ray_file or build_trace (tests/fuzz/fuzz_TARGET.cpp). Configures and
# builds the `fuzz` preset (clang, ASan + UBSan + libFuzzer; scripts/install-fuzz-deps.sh
# installs clang) into $REBRAID_FUZZ_BUILD (default build-fuzz/), runs one fuzzing process
# (the machine may be shared), keeps the growing corpus in <build>/fuzz-corpus/TARGET (seeded
# from tests/fuzz/seeds/TARGET) and writes any crashing input to <build>/fuzz-artifacts/TARGET/.
# Prints libFuzzer's final statistics (executions, coverage) and exits non-zero on a crash.
set -euo pipefail
cd "$(dirname "$0")/.."
if [ $# -ne 2 ]; then
    echo "usage: bash scripts/fuzz.sh gltf_loader|ray_file|build_trace SECONDS" >&2
    exit 2
fi
target="$1"
seconds="$2"
case "$target" in
    gltf_loader | ray_file | build_trace) ;;
    *) echo "fuzz.sh: unknown target '$target' (gltf_loader, ray_file, build_trace)" >&2; exit 2 ;;
esac
build="${REBRAID_FUZZ_BUILD:-build-fuzz}"
if [ ! -f "$build/CMakeCache.txt" ]; then
    cmake --preset fuzz -B "$build" >/dev/null
fi
cmake --build "$build" --target "fuzz_$target" >/dev/null

corpus="$build/fuzz-corpus/$target"
artifacts="$build/fuzz-artifacts/$target"
mkdir -p "$corpus" "$artifacts"
if [ -d "tests/fuzz/seeds/$target" ]; then
    cp -n "tests/fuzz/seeds/$target"/* "$corpus"/ 2>/dev/null || true
fi
extra=()
if [ "$target" = gltf_loader ]; then
    extra+=(-dict=tests/fuzz/gltf.dict -max_len=16384)
    # A .glb twin of every text seed, so the binary container is explored from the start.
    for seed in tests/fuzz/seeds/gltf_loader/*.gltf; do
        python3 - "$seed" "$corpus/$(basename "$seed" .gltf).glb" <<'PY'
import base64, json, struct, sys
doc = json.load(open(sys.argv[1]))
prefix = "data:application/octet-stream;base64,"
bin_data = b""
if doc.get("buffers") and doc["buffers"][0].get("uri", "").startswith(prefix):
    bin_data = base64.b64decode(doc["buffers"][0].pop("uri")[len(prefix):])
    bin_data += b"\0" * (-len(bin_data) % 4)
text = json.dumps(doc).encode()
text += b" " * (-len(text) % 4)
chunks = struct.pack("<II", len(text), 0x4E4F534A) + text
if bin_data:
    chunks += struct.pack("<II", len(bin_data), 0x004E4942) + bin_data
open(sys.argv[2], "wb").write(b"glTF" + struct.pack("<II", 2, 12 + len(chunks)) + chunks)
PY
    done
fi
if [ "$target" = build_trace ]; then
    # Every input decodes to a whole scene, so full-length inputs are useful from the start.
    extra+=(-max_len=1024 -len_control=0)
fi
exec "$build/tests/fuzz/fuzz_$target" "$corpus" -max_total_time="$seconds" -timeout=20 \
    -rss_limit_mb=2048 -print_final_stats=1 -artifact_prefix="$artifacts/" "${extra[@]}"
