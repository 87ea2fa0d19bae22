# The warning set every C target of the project is built with (host and cross): the library, the tests
# and the benchmarks. -std=c99 comes from C_STANDARD 99 + C_EXTENSIONS OFF on each target.
# -Werror only with FDI_WERROR (on by default when the project is top level, off as a subproject).
set(FDI_WARNING_FLAGS
    -Wall -Wextra -Wpedantic -Wconversion -Wsign-conversion -Wdouble-promotion -Wshadow -Wcast-qual
    -Wstrict-prototypes -Wfloat-equal)
if(FDI_WERROR)
  list(APPEND FDI_WARNING_FLAGS -Werror)
endif()

# -fno-math-errno: the library never reads errno, so sqrtf() and friends need not set it. Without it GCC follows every
# inlined square root (vsqrt.f32 on the Cortex-M4F, sqrtss on x86-64) with a compare and a branch to the library
# call that sets errno for a negative argument, and may not merge two calls of a math function with the same
# argument (tanhf(x) * tanhf(x) of the generated sensitivities: two calls). Values are unchanged (IEEE results,
# NaN for a negative square root either way); unlike -ffast-math / -ffinite-math-only it keeps NaN and Inf
# semantics, so the finiteness checks of fdi_float.h still work (fdi_float.h).
set(FDI_MATH_FLAGS $<$<C_COMPILER_ID:GNU,Clang,AppleClang>:-fno-math-errno>)

function(fdi_target_defaults target)
  set_target_properties(${target} PROPERTIES C_STANDARD 99 C_STANDARD_REQUIRED ON C_EXTENSIONS OFF)
  target_compile_options(${target} PRIVATE ${FDI_WARNING_FLAGS} ${FDI_MATH_FLAGS})
endfunction()
