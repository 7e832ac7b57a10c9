# Strict warnings as errors for everything the project compiles.
add_library(hstpf_warnings INTERFACE)
target_compile_options(hstpf_warnings INTERFACE
  -Wall -Wextra -Werror -pedantic -Wshadow -Wstrict-prototypes
  -Wmissing-prototypes -Wcast-qual -Wpointer-arith -Wwrite-strings
  -Wundef -Wformat=2 -Wvla)
# The library is held to more: no implicit conversions, no silent float->double.
add_library(hstpf_strict INTERFACE)
target_link_libraries(hstpf_strict INTERFACE hstpf_warnings)
target_compile_options(hstpf_strict INTERFACE -Wconversion -Wsign-conversion -Wdouble-promotion -Wcast-align)

# The compiler gates (cmake/gates.sh) build the same sources as C11 too:
# -DHSTPF_C_STANDARD=11 (the project is C99; this file is included after
# the top level sets it).
set(HSTPF_C_STANDARD "" CACHE STRING "C standard to build with instead of 99 (gates: 11)")
if(HSTPF_C_STANDARD)
  set(CMAKE_C_STANDARD ${HSTPF_C_STANDARD})
endif()
