# Cross toolchain: bare metal (no OS), Arm Cortex-M7 with the single-precision FPU (FPv5-SP-D16),
# Debian's gcc-arm-none-eabi 12 with the picolibc C library and libstdc++ built for it
# (packages gcc-arm-none-eabi, picolibc-arm-none-eabi, libstdc++-arm-none-eabi-picolibc).
#
# This file describes the CPU and the C/C++ runtime only. Memory map, start-up and the program
# that runs the images (QEMU's mps2-an500) belong to a board: platform/boards/<board>/.
#
# Facts found by trying (docs/integration.md, "Bare metal"):
# - --specs=picolibcpp.specs selects picolibc's headers and libraries for the multilib of the
#   -mcpu/-mfpu/-mfloat-abi flags (thumb/v7e-m+fp/hard); it must be on compile and link lines.
# - float is hardware; double is software (__aeabi_d* helpers): the core must not use it.
set(CMAKE_SYSTEM_NAME Generic)
set(CMAKE_SYSTEM_PROCESSOR arm)

set(CMAKE_C_COMPILER arm-none-eabi-gcc)
set(CMAKE_CXX_COMPILER arm-none-eabi-g++)
# No OS to run a test program on: the compiler checks build a static library.
set(CMAKE_TRY_COMPILE_TARGET_TYPE STATIC_LIBRARY)

set(CCMAP_CPU_FLAGS "-mcpu=cortex-m7 -mfpu=fpv5-sp-d16 -mfloat-abi=hard -mthumb")
set(CMAKE_C_FLAGS_INIT "${CCMAP_CPU_FLAGS} --specs=picolibc.specs")
set(CMAKE_CXX_FLAGS_INIT "${CCMAP_CPU_FLAGS} --specs=picolibcpp.specs")
set(CMAKE_EXE_LINKER_FLAGS_INIT "${CCMAP_CPU_FLAGS}")

set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)
