#!/usr/bin/env bash
# Builds the test suite with sanitizers and runs it:
#
#     bash scripts/run-sanitizer-tests.sh [asan|tsan]      (default asan)
#
# asan: the `asan` preset of CMakePresets.json (AddressSanitizer + UndefinedBehaviorSanitizer,
#       every error fatal) and the whole default suite (ctest -LE slow), as CI runs it.
# tsan: the `tsan` preset and the reduced set below (tests/RELIABILITY.md explains the
#       choice and the suppressions in tests/tsan.supp).
# The build folder is build-asan/ or build-tsan/ ($REBRAID_SANITIZER_BUILD overrides it).
# Installs dependencies first, like scripts/run-tests.sh.
set -euo pipefail
cd "$(dirname "$0")/.."
preset="${1:-asan}"
case "$preset" in
    asan | tsan) ;;
    *) echo "usage: bash scripts/run-sanitizer-tests.sh [asan|tsan]" >&2; exit 2 ;;
esac
build="${REBRAID_SANITIZER_BUILD:-build-$preset}"
jobs="$(nproc)"
bash scripts/install-deps.sh
cmake --preset "$preset" -B "$build" >/dev/null
cmake --build "$build" --parallel "$jobs"

if [ "$preset" = asan ]; then
    export ASAN_OPTIONS="halt_on_error=1:detect_leaks=1:strict_string_checks=1"
    export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1"
    ctest --test-dir "$build" --output-on-failure --parallel "$jobs" -LE slow
else
    export TSAN_OPTIONS="halt_on_error=1:second_deadlock_stack=1:suppressions=$PWD/tests/tsan.supp"
    # The parallel builders, traversal and the multi-threaded determinism tests on small
    # scenes; the shared-scene and CLI tests add time, not threading.
    tsan_tests='^(RebraidBuilder|WideBvhBuilder|TwoLevel|Traversal|AccelStructure|RandomizedScenes|BadInputScene|BadInputRays|EmbreeReference|EmbreeBvhBuilder)\.'
    ctest --test-dir "$build" --output-on-failure --parallel "$jobs" -LE 'slow|memory|install' \
        -R "$tsan_tests"
fi
