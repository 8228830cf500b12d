# Compile flags shared by every ccmap target.

# Same rounding on host and aarch64: no FMA contraction, no fast-math.
add_compile_options(-ffp-contract=off -fno-fast-math)
# Bare metal: math functions set no errno, so sqrtf is the one VSQRT.F32 instruction (the same
# correctly rounded result) without a NaN test and a libm call. It must follow -fno-fast-math,
# which turns -fmath-errno back on.
if(CCMAP_BAREMETAL)
  add_compile_options(-fno-math-errno)
endif()

if(CCMAP_SANITIZE)
  add_compile_options(-fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer)
  add_link_options(-fsanitize=address,undefined)
endif()

# Statement and branch coverage of the core (gcc --coverage, read by tools/coverage with gcovr):
# every translation unit is instrumented, since most of the core is templates compiled in the
# tests' own files. The host-coverage preset turns it on, without the sanitizers (together they
# made the tests five times slower; docs/integration.md section 11).
if(CCMAP_COVERAGE)
  if(NOT CMAKE_CXX_COMPILER_ID STREQUAL "GNU")
    message(FATAL_ERROR "CCMAP_COVERAGE needs gcc (gcov data for gcovr), not ${CMAKE_CXX_COMPILER_ID}")
  endif()
  add_compile_options(--coverage)
  add_link_options(--coverage)
endif()

# libFuzzer build (clang): everything instrumented for coverage; the fuzz targets link -fsanitize=fuzzer.
if(CCMAP_BUILD_FUZZ)
  add_compile_options(-fsanitize=fuzzer-no-link,address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer)
  add_link_options(-fsanitize=address,undefined)
endif()

# The flight core: warning wall that fails the build, no exceptions, no RTTI.
add_library(ccmap_core_flags INTERFACE)
target_compile_options(ccmap_core_flags INTERFACE
  -Wall -Wextra -Wpedantic -Wconversion -Wsign-conversion -Wdouble-promotion -Wshadow
  -Wold-style-cast -Wfloat-equal -Wcast-align -Wnull-dereference -Werror
  $<$<COMPILE_LANGUAGE:CXX>:-fno-exceptions -fno-rtti>)
# Per-function stack frame sizes and call graphs (.su, .ci next to each object) for tools/stack-usage.
if(CCMAP_STACK_USAGE)
  target_compile_options(ccmap_core_flags INTERFACE -fstack-usage -fcallgraph-info=su)
endif()

# Tests and host tools: a lighter wall (they compute references in double on purpose).
add_library(ccmap_host_flags INTERFACE)
target_compile_options(ccmap_host_flags INTERFACE -Wall -Wextra -Wshadow -Werror)
target_link_libraries(ccmap_host_flags INTERFACE ccmap_eigen)  # tests and host tools may use Eigen
