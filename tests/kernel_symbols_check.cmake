# Checks that the AVX-512 kernel unit shares no code with the rest of the program: every
# symbol it defines as weak (inline functions and templates, of which the linker keeps one
# copy for the whole program) lies in the kernels' own namespace simd_avx512. A weak symbol
# outside it would be compiled for AVX-512 and could be the copy other units call, faulting on
# a CPU without AVX-512 (see rebraid/top_level/trace_kernel_prelude.h).
# Run by ctest as Layout.Avx512KernelsShareNoCode; input: -DOBJECTS=<the top_level layer's
# objects, ;-separated> -DNM=<nm>.
cmake_minimum_required(VERSION 3.25)
set(kernel_object "")
foreach(object IN LISTS OBJECTS)
    if(object MATCHES "trace_kernels_avx512\\.cpp\\.o$")
        set(kernel_object ${object})
    endif()
endforeach()
if(kernel_object STREQUAL "")
    message(FATAL_ERROR "no trace_kernels_avx512 object among: ${OBJECTS}")
endif()
execute_process(COMMAND ${NM} -C --defined-only ${kernel_object} OUTPUT_VARIABLE symbols
                RESULT_VARIABLE result)
if(NOT result EQUAL 0)
    message(FATAL_ERROR "${NM} failed on ${kernel_object}")
endif()
string(REPLACE "\n" ";" lines "${symbols}")
set(shared "")
set(kernel_count 0)
foreach(line IN LISTS lines)
    if(line MATCHES "simd_avx512")
        math(EXPR kernel_count "${kernel_count} + 1")
    elseif(line MATCHES "^[0-9a-f]+ [WVu] ")
        string(APPEND shared "\n  ${line}")
    endif()
endforeach()
if(kernel_count EQUAL 0)
    message(FATAL_ERROR "${kernel_object} defines nothing in simd_avx512: the kernels are missing")
endif()
if(NOT shared STREQUAL "")
    message(FATAL_ERROR "the AVX-512 kernel unit defines weak symbols outside simd_avx512 "
                        "(include their headers before the target pragma):${shared}")
endif()
message(STATUS "${kernel_count} kernel symbols, none shared")
