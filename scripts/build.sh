#!/usr/bin/env bash
# Configures and builds rebraid in Release into build/ (the folder the README's commands use).
set -euo pipefail
cd "$(dirname "$0")/.."
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release "$@" >/dev/null
cmake --build build --parallel "$(nproc)"
