# Replays of the committed fuzz corpora as ordinary tests, in every build (not only with
# REBRAID_FUZZ): each fuzz target's LLVMFuzzerTestOneInput linked with replay_main.cpp instead
# of libFuzzer, run over tests/fuzz/corpus/TARGET (the minimised corpus, scripts/fuzz.sh merge)
# and tests/fuzz/seeds/TARGET. Label `asan`: scripts/run-sanitizer-tests.sh asan-ci (so the
# test command and CI) builds them through `asan_ci_tests` and runs them under AddressSanitizer
# + UBSan, where any report fails the test; a target's own checks abort on a wrong answer.
# Included by tests/CMakeLists.txt after `asan_ci_tests` is declared.
set(REBRAID_FUZZ_DIR ${CMAKE_CURRENT_LIST_DIR})

# rebraid_add_fuzz_replay(TARGET EXECUTABLE TEST): fuzz_TARGET.cpp as EXECUTABLE, test TEST.
function(rebraid_add_fuzz_replay target executable test)
    add_executable(${executable} ${REBRAID_FUZZ_DIR}/fuzz_${target}.cpp
                                 ${REBRAID_FUZZ_DIR}/replay_main.cpp)
    target_include_directories(${executable} PRIVATE ${REBRAID_FUZZ_DIR} ${REBRAID_FUZZ_DIR}/..)
    target_link_libraries(${executable} PRIVATE rebraid::rebraid rebraid::embree_glue
                                                rebraid_warnings)
    set(inputs "")
    foreach(dir corpus seeds)
        if(IS_DIRECTORY ${REBRAID_FUZZ_DIR}/${dir}/${target})
            list(APPEND inputs ${REBRAID_FUZZ_DIR}/${dir}/${target})
        endif()
    endforeach()
    add_test(NAME ${test} COMMAND ${executable} ${inputs})
    set_tests_properties(${test} PROPERTIES LABELS asan TIMEOUT 300)
    if(TARGET asan_ci_tests)
        add_dependencies(asan_ci_tests ${executable})
    endif()
endfunction()

rebraid_add_fuzz_replay(gltf_loader fuzz_gltf_replay Fuzz.GltfCorpusReplays)
rebraid_add_fuzz_replay(ray_file fuzz_ray_file_replay Fuzz.RayFileCorpusReplays)
rebraid_add_fuzz_replay(build_trace fuzz_build_trace_replay Fuzz.BuildTraceCorpusReplays)
