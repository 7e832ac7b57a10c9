# Compiles the codec for a Cortex-M4F with the project's strict warnings and
# fails if it references the heap or an OS: the codec must run on an MCU.
# cmake -DCC=arm-none-eabi-gcc -DNM=arm-none-eabi-nm -DSRC=<port/codec> -DOUT=<dir> -P cross_check.cmake
file(MAKE_DIRECTORY ${OUT})
set(_objs)
foreach(_s hstpf_e2e.c generated/hstpf_can.c generated/hstpf_frames.c)
  get_filename_component(_n ${_s} NAME_WE)
  execute_process(
    COMMAND ${CC} -std=c99 -mcpu=cortex-m4 -mthumb -mfpu=fpv4-sp-d16 -mfloat-abi=hard -Os
            -Wall -Wextra -Werror -pedantic -Wshadow -Wstrict-prototypes -Wmissing-prototypes
            -Wcast-qual -Wpointer-arith -Wwrite-strings -Wundef -Wformat=2 -Wvla
            -Wconversion -Wsign-conversion -Wdouble-promotion -Wcast-align
            -I${SRC} -I${SRC}/generated -c ${SRC}/${_s} -o ${OUT}/${_n}.o
    RESULT_VARIABLE _rc)
  if(NOT _rc EQUAL 0)
    message(FATAL_ERROR "cross compile of ${_s} failed")
  endif()
  list(APPEND _objs ${OUT}/${_n}.o)
endforeach()
execute_process(COMMAND ${NM} -u ${_objs} OUTPUT_VARIABLE _undef RESULT_VARIABLE _rc)
if(NOT _rc EQUAL 0)
  message(FATAL_ERROR "nm failed")
endif()
foreach(_bad malloc calloc realloc free printf fopen socket)
  if(_undef MATCHES "[ \n]${_bad}\n")
    message(FATAL_ERROR "the codec references ${_bad}")
  endif()
endforeach()
message(STATUS "codec cross-compiled for Cortex-M4F; undefined symbols:\n${_undef}")
