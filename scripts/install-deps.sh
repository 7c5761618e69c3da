#!/usr/bin/env bash
# Installs rebraid's build and test dependencies from Debian 12's archive.
# Uses sudo when not run as root. Safe to run again: apt-get skips what is installed.
set -euo pipefail
packages=(
    cmake ninja-build g++ pkg-config
    libembree-dev libtbb-dev libopenimageio-dev openimageio-tools libtinygltf-dev nlohmann-json3-dev
    libdraco-dev libmeshoptimizer-dev
    libcli11-dev libgtest-dev libbenchmark-dev
    python3 python3-matplotlib valgrind
    embree-tools
)
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
