# Runs one case of the ThreadSanitizer canary (tests/tsan/tsan_canary.cpp) with the project's
# suppressions and passes only when ThreadSanitizer reported the planted race:
#
#     cmake -DCANARY=<tsan_canary> -DCASE=<case> -DMARKER=<function name>
#           -DSUPPRESSIONS=<tests/tsan.supp> -P expect_report.cmake
#
# The run must end with exit code 66 (TSAN_OPTIONS below, as in
# scripts/run-sanitizer-tests.sh) and print a data-race report whose stacks contain MARKER,
# the function that holds the race: a report of some other race, or none, fails.
foreach(variable CANARY CASE MARKER SUPPRESSIONS)
    if(NOT DEFINED ${variable})
        message(FATAL_ERROR "expect_report.cmake: -D${variable}=... is missing")
    endif()
endforeach()
if(NOT EXISTS "${SUPPRESSIONS}")
    message(FATAL_ERROR "expect_report.cmake: no suppressions file ${SUPPRESSIONS}")
endif()

# The options of the tsan run, whatever the caller's environment holds.
set(ENV{TSAN_OPTIONS}
    "halt_on_error=1:exitcode=66:second_deadlock_stack=1:history_size=7:suppressions=${SUPPRESSIONS}")
execute_process(COMMAND "${CANARY}" "${CASE}"
                RESULT_VARIABLE code OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT 120)

set(problems "")
if(NOT code STREQUAL "66")
    string(APPEND problems "exit code ${code}, expected 66 (a ThreadSanitizer report); ")
endif()
if(NOT err MATCHES "WARNING: ThreadSanitizer: data race")
    string(APPEND problems "no data-race report; ")
endif()
string(FIND "${err}" "${MARKER}" marker_at)
if(marker_at EQUAL -1)
    string(APPEND problems "the report does not name ${MARKER}; ")
endif()
if(problems)
    message(FATAL_ERROR "tsan_canary ${CASE}: ${problems}the suppressions in ${SUPPRESSIONS} "
                        "may hide this race in project code.\nstdout:\n${out}\nstderr:\n${err}")
endif()
string(REGEX MATCH "SUMMARY: ThreadSanitizer: [^\n]*" summary "${err}")
message(STATUS "tsan_canary ${CASE}: reported as expected (exit code 66, race in ${MARKER})\n"
               "${summary}")
