# The instruction classes of the QEMU instruction-count plugin (tools/qemu-icount/a64_class.c)
# against binutils' aarch64 disassembler. Included from tests/tools/CMakeLists.txt (host
# builds); skips, saying why, without aarch64-linux-gnu-objdump or the aarch64 libraries.
find_program(CCMAP_AARCH64_OBJDUMP aarch64-linux-gnu-objdump)
set(CCMAP_AARCH64_LIB_DIR /usr/aarch64-linux-gnu/lib CACHE PATH "aarch64 target libraries (Debian cross toolchain)")
if(CCMAP_AARCH64_OBJDUMP)
  set(_ccmap_objdump ${CCMAP_AARCH64_OBJDUMP})
else()
  set(_ccmap_objdump "")
endif()
add_executable(ccmap_test_icount_classify ${CMAKE_CURRENT_LIST_DIR}/icount_classify_test.cpp
               ${PROJECT_SOURCE_DIR}/tools/qemu-icount/a64_class.c)
target_link_libraries(ccmap_test_icount_classify PRIVATE GTest::gtest_main ccmap_host_flags)
target_compile_definitions(ccmap_test_icount_classify PRIVATE
  CCMAP_AARCH64_OBJDUMP="${_ccmap_objdump}" CCMAP_AARCH64_LIB_DIR="${CCMAP_AARCH64_LIB_DIR}")
# One label only: gtest_discover_tests flattens a list-valued LABELS property.
gtest_discover_tests(ccmap_test_icount_classify DISCOVERY_MODE PRE_TEST DISCOVERY_TIMEOUT 60
                     PROPERTIES LABELS "icount" TIMEOUT 300)
