# ctest test_precision_f32_vs_f64: runs the precision program against the
# float and the double library and compares the final position estimates.
#   cmake -DRUN_F32=... -DRUN_F64=... -DTOL_UM=500000 -P compare_precision.cmake
# Positions are printed with 6 decimals and compared as integer micrometres
# (CMake's math() is integer only). The compared quantity is the blended
# position estimate (final_estimate_m). So that the comparison is between
# two working filters, the declared model's own position (declared_model_m)
# must lie within SANE_UM (1 m: 10 sd of the 0.1 m measurement noise) of the
# true position in both builds.
if(NOT DEFINED SANE_UM)
  set(SANE_UM 1000000)
endif()

function(run_one exe prefix)
  execute_process(COMMAND ${exe} OUTPUT_VARIABLE out ERROR_VARIABLE err RESULT_VARIABLE rc)
  message("---- ${exe}\n${out}${err}")
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${exe} failed (exit ${rc})")
  endif()
  foreach(key final_estimate_m declared_model_m true_m)
    string(REGEX MATCH "${key} (-?)([0-9]+)\\.([0-9][0-9][0-9][0-9][0-9][0-9])" m "${out}")
    if(NOT m)
      message(FATAL_ERROR "${exe}: no '${key}' line with 6 decimals")
    endif()
    set(um "${CMAKE_MATCH_2}${CMAKE_MATCH_3}")
    string(REGEX REPLACE "^0+([0-9])" "\\1" um "${um}")
    if(CMAKE_MATCH_1 STREQUAL "-")
      math(EXPR um "0 - ${um}")
    endif()
    set(${prefix}_${key} ${um} PARENT_SCOPE)
  endforeach()
endfunction()

function(absdiff a b out)
  math(EXPR d "${a} - ${b}")
  if(d LESS 0)
    math(EXPR d "0 - ${d}")
  endif()
  set(${out} ${d} PARENT_SCOPE)
endfunction()

run_one(${RUN_F32} f32)
run_one(${RUN_F64} f64)
absdiff(${f32_final_estimate_m} ${f64_final_estimate_m} d)
absdiff(${f32_declared_model_m} ${f32_true_m} e32)
absdiff(${f64_declared_model_m} ${f64_true_m} e64)
message("float vs double final blended position: ${d} um (tolerance ${TOL_UM} um); "
        "declared model's error vs truth: float ${e32} um, double ${e64} um")
if(NOT f32_true_m EQUAL f64_true_m)
  message(FATAL_ERROR "the two runs did not simulate the same journey")
endif()
if(e32 GREATER SANE_UM OR e64 GREATER SANE_UM)
  message(FATAL_ERROR "a declared model's estimate is more than ${SANE_UM} um from the truth")
endif()
if(d GREATER TOL_UM)
  message(FATAL_ERROR "float and double builds differ by ${d} um > ${TOL_UM} um")
endif()
