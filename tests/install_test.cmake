# The installed package, used from an outside project (run by ctest as
# InstallPackage.OutsideProjectBuildsAndRuns, label `install`):
#   1. cmake --install the build tree into a scratch prefix;
#   2. configure examples/dropin against it with find_package(rebraid CONFIG REQUIRED);
#   3. build it and run `dropin_example --check`, which traces the same rays through Embree,
#      EmbreeAccel and the user-geometry scene, before and after an update; its --help and a
#      bad --mode;
#   4. configure, build and run examples/minimal (the library alone, <rebraid/rebraid.h>);
#   5. run the installed `rebraid` command (the preload library is installed in lib/ too).
# Only public headers are installed: a builder internal must be missing from the prefix.
# Inputs: REBRAID_BUILD_DIR, REBRAID_SOURCE_DIR, REBRAID_WORK_DIR, REBRAID_GENERATOR.
foreach(variable REBRAID_BUILD_DIR REBRAID_SOURCE_DIR REBRAID_WORK_DIR REBRAID_GENERATOR)
    if(NOT DEFINED ${variable})
        message(FATAL_ERROR "install_test.cmake: -D${variable}=... is required")
    endif()
endforeach()

set(prefix ${REBRAID_WORK_DIR}/prefix)
set(consumer ${REBRAID_WORK_DIR}/consumer)
file(REMOVE_RECURSE ${REBRAID_WORK_DIR})
file(MAKE_DIRECTORY ${REBRAID_WORK_DIR})

function(run step)
    execute_process(COMMAND ${ARGN} RESULT_VARIABLE result OUTPUT_VARIABLE output
                    ERROR_VARIABLE output)
    if(NOT result EQUAL 0)
        message(FATAL_ERROR "${step} failed (${result}):\n${output}")
    endif()
    message(STATUS "${step}: ok")
    set(last_output "${output}" PARENT_SCOPE)
endfunction()

run("install" ${CMAKE_COMMAND} --install ${REBRAID_BUILD_DIR} --prefix ${prefix})
foreach(installed include/rebraid/embree.h include/rebraid/rebraid.h include/rebraid/core/scene.h
        include/rebraid/rebraiding/rebraid_accel.h include/embree_glue/dropin/embree_accel.h
        lib/cmake/rebraid/rebraidConfig.cmake bin/rebraid lib/librebraid_preload.so)
    if(NOT EXISTS ${prefix}/${installed})
        message(FATAL_ERROR "install: ${prefix}/${installed} is missing")
    endif()
endforeach()

foreach(internal include/rebraid/rebraiding/bref_opening.h include/rebraid/bvh/binned_split.h
        include/rebraid/bvh/wide_tree_grower.h)
    if(EXISTS ${prefix}/${internal})
        message(FATAL_ERROR "install: the internal header ${internal} was installed")
    endif()
endforeach()

run("configure the outside project" ${CMAKE_COMMAND} -S ${REBRAID_SOURCE_DIR}/examples/dropin
    -B ${consumer} -G ${REBRAID_GENERATOR} -DCMAKE_BUILD_TYPE=Release
    -DCMAKE_PREFIX_PATH=${prefix})
run("build the outside project" ${CMAKE_COMMAND} --build ${consumer})
run("run the outside project" ${consumer}/dropin_example --check)
if(NOT last_output MATCHES "check passed")
    message(FATAL_ERROR "dropin_example --check did not pass:\n${last_output}")
endif()
message(STATUS "${last_output}")
# Its command line: --help is an answer, not an error; a bad mode is refused, not replaced.
run("dropin_example --help" ${consumer}/dropin_example --help)
if(NOT last_output MATCHES "usage: dropin_example")
    message(FATAL_ERROR "dropin_example --help printed no usage:\n${last_output}")
endif()
execute_process(COMMAND ${consumer}/dropin_example --mode foo RESULT_VARIABLE result
                OUTPUT_VARIABLE output ERROR_VARIABLE output)
if(NOT result EQUAL 2 OR NOT output MATCHES "--mode foo: expected embree, rebraid or user-geometry")
    message(FATAL_ERROR "dropin_example --mode foo gave ${result}:\n${output}")
endif()
set(minimal ${REBRAID_WORK_DIR}/minimal)
run("configure the minimal example" ${CMAKE_COMMAND} -S ${REBRAID_SOURCE_DIR}/examples/minimal
    -B ${minimal} -G ${REBRAID_GENERATOR} -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=${prefix})
run("build the minimal example" ${CMAKE_COMMAND} --build ${minimal})
run("run the minimal example" ${minimal}/minimal_example)
if(NOT last_output MATCHES "t 1, instance 0, primitive 1")
    message(FATAL_ERROR "minimal_example printed something else:\n${last_output}")
endif()
run("run the installed rebraid command" ${prefix}/bin/rebraid --help)
