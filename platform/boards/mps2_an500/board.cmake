# Board layer: QEMU's mps2-an500 (Cortex-M7). Included by the top-level CMakeLists.txt when the
# toolchain is bare metal (CMAKE_SYSTEM_NAME Generic, toolchains/arm-none-eabi-cortex-m7.cmake).
#
#   ccmap_board                          start-up, board services (board.h) and the three
#                                        ccmap_bm_* hooks of platform/baremetal (OBJECT library:
#                                        the vector table is always linked)
#   ccmap_board_image(<target> [RAM_SIZE <bytes>] [STACK_SIZE <bytes>])
#                                        makes <target> a bootable image (<target>.elf + .map)
#   ccmap_board_add_test(<name> <target> [ARGS <words...>])
#                                        a ctest test running the image under qemu-system-arm;
#                                        ARGS reach the image as its arguments (-append)
#   CCMAP_BOARD_LINK_OPTIONS             the image link options (for scripts that link by hand)
#   CCMAP_BOARD_EMULATOR                 the emulator command line, up to -kernel
set(_ccmap_board_dir ${CMAKE_CURRENT_LIST_DIR})

add_library(ccmap_board OBJECT ${_ccmap_board_dir}/startup.cpp ${_ccmap_board_dir}/hooks.cpp)
target_include_directories(ccmap_board PUBLIC ${_ccmap_board_dir})
target_link_libraries(ccmap_board PRIVATE ccmap_core_flags)

set(CCMAP_BOARD_LINKER_SCRIPT ${_ccmap_board_dir}/mps2_an500.ld)
# -nostartfiles: this start-up replaces picolibc's crt0. No --oslib: the board does its own
# semihosting, and a stray stdio or exit() call is then a link error, not a silent dependency.
set(CCMAP_BOARD_LINK_OPTIONS -nostartfiles "-T${CCMAP_BOARD_LINKER_SCRIPT}" -Wl,--gc-sections
    -Wl,--print-memory-usage)

find_program(CCMAP_QEMU_SYSTEM_ARM qemu-system-arm)
if(NOT CCMAP_QEMU_SYSTEM_ARM)
  message(FATAL_ERROR "qemu-system-arm not found (the bare-metal tests run under it): "
                      "apt-get install qemu-system-arm, or ./tools/install-deps")
endif()
# -icount shift=0: one guest instruction = 1 ns of virtual time, so timer reads count
# instructions and every run is identical (board.h). The semihosting console on a stdio
# chardev: QEMU 7.2 writes it to stderr otherwise.
set(CCMAP_BOARD_EMULATOR ${CCMAP_QEMU_SYSTEM_ARM} -M mps2-an500 -cpu cortex-m7 -nographic -monitor none
    -serial none -chardev stdio,id=semihost -semihosting-config enable=on,target=native,chardev=semihost
    -icount shift=0 -kernel)

function(ccmap_board_image target)
  cmake_parse_arguments(ARG "" "RAM_SIZE;STACK_SIZE" "" ${ARGN})
  target_link_libraries(${target} PRIVATE ccmap_board)
  target_link_options(${target} PRIVATE ${CCMAP_BOARD_LINK_OPTIONS} "-Wl,-Map=$<TARGET_FILE:${target}>.map")
  if(ARG_RAM_SIZE)
    target_link_options(${target} PRIVATE "-Wl,--defsym=__ccmap_ram_size=${ARG_RAM_SIZE}")
  endif()
  if(ARG_STACK_SIZE)
    target_link_options(${target} PRIVATE "-Wl,--defsym=__ccmap_stack_size=${ARG_STACK_SIZE}")
  endif()
  set_target_properties(${target} PROPERTIES SUFFIX .elf LINK_DEPENDS ${CCMAP_BOARD_LINKER_SCRIPT})
endfunction()

function(ccmap_board_add_test name target)
  cmake_parse_arguments(ARG "" "" "ARGS" ${ARGN})
  set(_append)
  if(ARG_ARGS)
    string(JOIN " " _words ${ARG_ARGS})
    set(_append -append "${_words}")
  endif()
  add_test(NAME ${name} COMMAND ${CCMAP_BOARD_EMULATOR} $<TARGET_FILE:${target}> ${_append})
endfunction()
