#!/usr/bin/env bash
# Installs what the fuzz targets (tests/fuzz/, scripts/fuzz.sh) and the sanitizer presets
# (CMakePresets.json, scripts/run-sanitizer-tests.sh) need on top of scripts/install-deps.sh:
# Debian 12's clang 14 with its libFuzzer and sanitizer runtimes.
# Uses sudo when not run as root. Safe to run again: apt-get skips what is installed.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
packages=(clang libfuzzer-14-dev libclang-rt-14-dev)
missing=()
for p in "${packages[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
    exit 0
fi
sudo=""
if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$sudo apt-get update -qq
$sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
