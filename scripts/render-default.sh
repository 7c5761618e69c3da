#!/usr/bin/env bash
# README command 1: install dependencies, build in Release, render the built-in default
# scene to out/default.png.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
bash scripts/build.sh
mkdir -p out
./build/examples/rebraid render -o out/default.png
echo "wrote out/default.png"
