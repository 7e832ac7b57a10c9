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
