# Cross toolchain: Debian's g++-aarch64-linux-gnu, ARMv8-A (Snapdragon 820 / Kryo class).
#
# Facts found by trying (see docs/integration.md):
# - Debian's cross gcc is built with --with-sysroot=/, so CMAKE_SYSROOT must NOT be set;
#   the target's libraries are found through CMAKE_FIND_ROOT_PATH instead.
# - qemu-aarch64 needs -L to find the target's dynamic loader and libc.
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)

set(CMAKE_C_COMPILER aarch64-linux-gnu-gcc)
set(CMAKE_CXX_COMPILER aarch64-linux-gnu-g++)

set(CMAKE_FIND_ROOT_PATH /usr/aarch64-linux-gnu)
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)

# Kryo has no -mcpu entry in gcc 12; it is an A57-class out-of-order core with NEON.
set(CMAKE_C_FLAGS_INIT "-march=armv8-a -mtune=cortex-a57")
set(CMAKE_CXX_FLAGS_INIT "-march=armv8-a -mtune=cortex-a57")

# Every add_test(NAME .. COMMAND exe) runs under QEMU user mode.
set(CMAKE_CROSSCOMPILING_EMULATOR "qemu-aarch64;-L;/usr/aarch64-linux-gnu")
