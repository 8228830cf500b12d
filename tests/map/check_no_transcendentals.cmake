# cmake -DNM=<nm> -DFILES=<binary;archive;...> -P check_no_transcendentals.cmake
# Fails if any file references a libm transcendental function (their last-bit results differ
# between libm implementations and targets; + - * / sqrt floor fabs are exact or correctly
# rounded everywhere, so they are allowed).
set(_deny "sin|cos|tan|asin|acos|atan|atan2|sinh|cosh|tanh|asinh|acosh|atanh|exp|exp2|exp10|expm1|log|log2|log10|log1p|logb|pow|powi|cbrt|hypot|erf|erfc|lgamma|tgamma|sincos|j0|j1|y0|y1")
set(_bad "")
foreach(_file IN LISTS FILES)
  execute_process(COMMAND ${NM} -u ${_file} OUTPUT_VARIABLE _out RESULT_VARIABLE _rc ERROR_VARIABLE _err)
  if(NOT _rc EQUAL 0)
    message(FATAL_ERROR "${NM} -u ${_file} failed: ${_err}")
  endif()
  string(REPLACE "\n" ";" _lines "${_out}")
  foreach(_line IN LISTS _lines)
    # "                 U sinf@GLIBC_2.2.5" or "U sinf"
    if(_line MATCHES "U[ \t]+(__)?(${_deny})(f|l|f32|f64)?(_finite)?(@.*)?$")
      list(APPEND _bad "${_file}: ${_line}")
    endif()
  endforeach()
endforeach()
if(_bad)
  string(REPLACE ";" "\n  " _msg "${_bad}")
  message(FATAL_ERROR "libm transcendental functions referenced on the update path:\n  ${_msg}")
endif()
list(LENGTH FILES _n)
message(STATUS "no libm transcendental referenced by ${_n} files")
