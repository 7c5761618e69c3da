#!/usr/bin/env bash
# README command 2 (and CI, .ci/run): install dependencies, build in Release and run the
# whole test suite except the label `slow`; then build the `asan` preset (AddressSanitizer +
# UndefinedBehaviorSanitizer) into build-asan/ and run the tests labelled `asan` there
# (scripts/run-sanitizer-tests.sh asan-ci; docs/testing.md has the choice and the times).
# Any failing test or sanitizer report fails the run.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
bash scripts/build.sh
ctest --test-dir build --output-on-failure --parallel "$(nproc)" -LE slow --no-tests=error
bash scripts/run-sanitizer-tests.sh asan-ci
