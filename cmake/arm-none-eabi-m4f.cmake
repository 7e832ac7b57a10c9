# CMake toolchain file: ARM Cortex-M4F (single-precision FPU, hard-float ABI),
# bare metal, GNU Arm Embedded toolchain (Debian: gcc-arm-none-eabi,
# binutils-arm-none-eabi, libnewlib-arm-none-eabi).
#
#   cmake -S . -B build-m4f -G Ninja \
#         -DCMAKE_TOOLCHAIN_FILE=cmake/arm-none-eabi-m4f.cmake
#   cmake --build build-m4f        # -> build-m4f/lib/libhstpf.a
#
# Configuring the root project with this file builds the library only
# (HSTPF_BUILD_HOST defaults to OFF when cross-compiling).
#
# Optimisation: Release (the root project's default build type) is -O2;
# MinSizeRel is -Os. Every object gets -ffunction-sections -fdata-sections so
# that a firmware link with -Wl,--gc-sections keeps only what it calls.
# Another toolchain location: -DHSTPF_ARM_PREFIX=/opt/arm/bin/arm-none-eabi-
# Extra compile flags without losing the CPU flags (setting CMAKE_C_FLAGS on
# the command line would replace them): -DHSTPF_M4F_EXTRA_C_FLAGS="-fstack-usage"

set(CMAKE_SYSTEM_NAME Generic)
set(CMAKE_SYSTEM_PROCESSOR arm)

if(NOT HSTPF_ARM_PREFIX)
  set(HSTPF_ARM_PREFIX arm-none-eabi-)
endif()
# Forward the prefix to CMake's try_compile projects.
list(APPEND CMAKE_TRY_COMPILE_PLATFORM_VARIABLES HSTPF_ARM_PREFIX HSTPF_M4F_EXTRA_C_FLAGS)

set(CMAKE_C_COMPILER ${HSTPF_ARM_PREFIX}gcc)
set(CMAKE_ASM_COMPILER ${HSTPF_ARM_PREFIX}gcc)
# CMake derives ar, ranlib, nm, objcopy, objdump from the compiler's prefix;
# size is not among them.
find_program(CMAKE_SIZE NAMES ${HSTPF_ARM_PREFIX}size)

# No OS: compiler checks build a static library instead of linking a program.
set(CMAKE_TRY_COMPILE_TARGET_TYPE STATIC_LIBRARY)

set(HSTPF_M4F_CPU_FLAGS "-mcpu=cortex-m4 -mthumb -mfpu=fpv4-sp-d16 -mfloat-abi=hard")
set(CMAKE_C_FLAGS_INIT "${HSTPF_M4F_CPU_FLAGS} -ffunction-sections -fdata-sections ${HSTPF_M4F_EXTRA_C_FLAGS}")
set(CMAKE_ASM_FLAGS_INIT "${HSTPF_M4F_CPU_FLAGS}")
# Cache entries, not *_INIT: CMake's GNU defaults would append -O3 after them.
set(CMAKE_C_FLAGS_RELEASE "-O2 -DNDEBUG" CACHE STRING "C flags, Release (Cortex-M4F)")
set(CMAKE_C_FLAGS_MINSIZEREL "-Os -DNDEBUG" CACHE STRING "C flags, MinSizeRel (Cortex-M4F)")
set(CMAKE_C_FLAGS_RELWITHDEBINFO "-O2 -g -DNDEBUG" CACHE STRING "C flags, RelWithDebInfo (Cortex-M4F)")
set(CMAKE_C_FLAGS_DEBUG "-Og -g" CACHE STRING "C flags, Debug (Cortex-M4F)")
# Programs (firmware, link tests): newlib-nano, no system calls, unused
# sections dropped. A firmware project adds its own linker script.
set(CMAKE_EXE_LINKER_FLAGS_INIT
    "${HSTPF_M4F_CPU_FLAGS} --specs=nano.specs --specs=nosys.specs -Wl,--gc-sections")

# find_* look in the target's newlib multilib directory (thumb/v7e-m+fp/hard)
# only, never in the host's /usr/lib: find_library(m) then finds the libm.a
# that the compiler driver would pick for -lm. Programs come from the host.
separate_arguments(_hstpf_cpu_list UNIX_COMMAND "${HSTPF_M4F_CPU_FLAGS}")
execute_process(COMMAND ${CMAKE_C_COMPILER} ${_hstpf_cpu_list} -print-file-name=libc.a
                OUTPUT_VARIABLE _hstpf_libc OUTPUT_STRIP_TRAILING_WHITESPACE
                ERROR_QUIET)
if(_hstpf_libc AND IS_ABSOLUTE "${_hstpf_libc}")
  get_filename_component(_hstpf_multilib_dir "${_hstpf_libc}" DIRECTORY)
  get_filename_component(_hstpf_multilib_dir "${_hstpf_multilib_dir}" REALPATH)
  set(CMAKE_FIND_ROOT_PATH "${_hstpf_multilib_dir}")
  list(APPEND CMAKE_LIBRARY_PATH "${_hstpf_multilib_dir}")
endif()
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)
