#!/usr/bin/env bash
# README command 1: install dependencies, build the `rebraid` command (only what rendering
# needs) in Release, render the built-in default scene to out/default.png (it says so).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
bash scripts/build.sh rebraid_cli
mkdir -p out
./build/examples/rebraid render -o out/default.png
