# The warning set every C target of the project is built with (host and cross): the library, the tests
# and the benchmarks. -std=c99 comes from C_STANDARD 99 + C_EXTENSIONS OFF on each target.
set(FDI_WARNING_FLAGS
    -Wall -Wextra -Wpedantic -Wconversion -Wsign-conversion -Wdouble-promotion -Wshadow -Wcast-qual
    -Wstrict-prototypes -Wfloat-equal -Werror)

function(fdi_target_defaults target)
  set_target_properties(${target} PROPERTIES C_STANDARD 99 C_STANDARD_REQUIRED ON C_EXTENSIONS OFF)
  target_compile_options(${target} PRIVATE ${FDI_WARNING_FLAGS})
endfunction()
