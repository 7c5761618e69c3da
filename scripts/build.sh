#!/usr/bin/env bash
# Configures and builds rebraid in Release into build/ (the folder the README's commands use).
# Arguments name the targets to build (all of them when none is given), e.g. rebraid_cli.
set -euo pipefail
cd "$(dirname "$0")/.."
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
targets=()
for target in "$@"; do targets+=(--target "$target"); done
cmake --build build --parallel "$(nproc)" "${targets[@]}"
