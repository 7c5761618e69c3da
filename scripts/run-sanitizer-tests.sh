#!/usr/bin/env bash
# Builds the test suite with sanitizers and runs it:
#
#     bash scripts/run-sanitizer-tests.sh [asan|asan-ci|tsan]      (default asan)
#
# asan:    the `asan` preset of CMakePresets.json (AddressSanitizer + UndefinedBehaviorSanitizer,
#          every error fatal), the whole tree, and every test except the labels `slow` (long
#          runs; `ctest -L slow` in the same folder runs them) and `install` (it links an
#          outside project without sanitizer flags against the instrumented libraries).
# asan-ci: what scripts/run-tests.sh (so CI) runs after the Release suite: the same preset, but
#          only the test executables labelled `asan` (target `asan_ci_tests`, list
#          REBRAID_ASAN_CI_TESTS in tests/CMakeLists.txt) and their tests.
# tsan:    the `tsan` preset against a ThreadSanitizer build of Debian's oneTBB (built once
#          into <build>/tbb from `apt-get source onetbb`, which needs a deb-src line in the apt
#          sources), the executables labelled `tsan` (target `tsan_tests`: every one whose code
#          runs on several threads, and the canary tsan_canary) and their tests except the
#          labels `slow` and `memory`, with the tests made once per shared scene on the four
#          smallest scenes only. Not part of scripts/run-tests.sh, so not of CI (too long for
#          it): run it on a schedule and before a release.
# docs/testing.md explains the choices, the suppressions and the times.
# The build folder is build-asan/ or build-tsan/ ($REBRAID_SANITIZER_BUILD overrides it).
# Installs dependencies first, like scripts/run-tests.sh. Exits non-zero on any failure or
# sanitizer report.
set -euo pipefail
cd "$(dirname "$0")/.."
mode="${1:-asan}"
case "$mode" in
    asan | asan-ci) preset=asan ;;
    tsan) preset=tsan ;;
    *) echo "usage: bash scripts/run-sanitizer-tests.sh [asan|asan-ci|tsan]" >&2; exit 2 ;;
esac
build="${REBRAID_SANITIZER_BUILD:-build-$preset}"
# The asan-ci subset holds at least this many tests (tests/CMakeLists.txt, label `asan`);
# fewer means tests went missing, which fails the run.
min_asan_ci_tests=240
jobs="$(nproc)"
bash scripts/install-deps.sh

# A sanitizer report ends the process with a code no test expects (the tests check the
# `rebraid` command's exit codes 0 and 1), so a report inside a child process fails too.
export ASAN_OPTIONS="halt_on_error=1:detect_leaks=1:strict_string_checks=1:exitcode=86"
export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1"
# history_size=7 (the most): TSan keeps more of each thread's past accesses, so it can more
# often print the stack of a race's earlier access ("failed to restore the stack" otherwise),
# and only a printed stack can match the anchored suppressions in tests/tsan.supp.
export TSAN_OPTIONS="halt_on_error=1:exitcode=66:second_deadlock_stack=1:history_size=7:suppressions=$PWD/tests/tsan.supp"

# ThreadSanitizer only sees synchronisation in instrumented code: with Debian's libtbb every
# hand-off between TBB tasks would be reported as a race. Builds oneTBB (the installed
# version) with TBB_SANITIZE=thread; its libtbb.so.12 then also serves libembree3.
build_tsan_tbb() {
    local prefix="$1"
    local version
    version="$(dpkg-query -W -f='${Version}' libtbb12)"
    local work="$build/tbb-src"
    rm -rf "$work"
    mkdir -p "$work"
    if ! (cd "$work" && apt-get source --download-only "onetbb=$version" >/dev/null 2>&1); then
        echo "run-sanitizer-tests.sh: 'apt-get source onetbb=$version' failed; add a" \
             "'Types: deb-src' entry for bookworm to /etc/apt/sources.list.d/ and run" \
             "apt-get update" >&2
        exit 1
    fi
    tar -C "$work" -xf "$work"/onetbb_*.orig.tar.*
    cmake -S "$work"/oneTBB-* -B "$work/build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
        -DTBB_SANITIZE=thread -DTBB_TEST=OFF -DTBBMALLOC_BUILD=OFF -DTBB_STRICT=OFF \
        -DCMAKE_INSTALL_PREFIX="$prefix" -DCMAKE_INSTALL_LIBDIR=lib >/dev/null
    cmake --build "$work/build" --parallel "$jobs" >/dev/null
    cmake --install "$work/build" >/dev/null
}

case "$mode" in
    asan)
        cmake --preset asan -B "$build" >/dev/null
        cmake --build "$build" --parallel "$jobs"
        ctest --test-dir "$build" --output-on-failure --parallel "$jobs" -LE 'slow|install' \
            --no-tests=error
        ;;
    asan-ci)
        cmake --preset asan -B "$build" >/dev/null
        cmake --build "$build" --parallel "$jobs" --target asan_ci_tests
        # A label that matches nothing, or executables whose tests were not discovered, must
        # fail rather than pass with nothing run.
        listed="$(ctest --test-dir "$build" -N -L asan -LE slow | sed -n 's/^Total Tests: //p')"
        if [ "${listed:-0}" -lt "$min_asan_ci_tests" ]; then
            echo "run-sanitizer-tests.sh: only ${listed:-0} tests labelled asan" \
                 "(expected at least $min_asan_ci_tests)" >&2
            exit 1
        fi
        ctest --test-dir "$build" --output-on-failure --parallel "$jobs" -L asan -LE slow \
            --no-tests=error
        ;;
    tsan)
        mkdir -p "$build"
        build="$(cd "$build" && pwd)"
        tbb="$build/tbb"
        if [ ! -f "$tbb/lib/libtbb.so.12" ]; then
            build_tsan_tbb "$tbb"
        fi
        cmake --preset tsan -B "$build" -DTBB_DIR="$tbb/lib/cmake/TBB" >/dev/null
        cmake --build "$build" --parallel "$jobs" --target tsan_tests
        # Reduced scene set: the tests made once per shared scene skip the five largest
        # (ThreadSanitizer runs them many times slower; the same code runs on the others, and
        # the determinism tests still loop over every scene). Two `animate` tests run
        # Embree's methods and the project's in one process, where a TBB worker's late read
        # of a context Embree put on the stack is reported without a stack to suppress it
        # by (docs/testing.md); the other animate tests and dynamic_frames_test run
        # the same project code.
        large_scenes='/(armadillo|brainstem|bunny|cg57_cruiser|two_cylinder_engine)( |$)'
        embree_and_own='^AnimateCommand\.(JsonHasOneObjectPerMethodWithTheSummaryKeys|PlotWritesAPng)$'
        LD_LIBRARY_PATH="$tbb/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}" \
            ctest --test-dir "$build" --output-on-failure --parallel "$jobs" -L tsan \
            -LE 'slow|memory' -E "$large_scenes|$embree_and_own" --no-tests=error
        ;;
esac
