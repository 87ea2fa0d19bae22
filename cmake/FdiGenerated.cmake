# How the generated generator sources (fw/vehicles/*/generated/*_generators.c) are compiled.
#
# FDI_GENERATED_FOR_SIZE (ON by default): in Release and RelWithDebInfo builds they get -Os, whatever the build type
# says for the rest. They are long straight-line float code (residuals, observers, sensitivities) that -O3 only
# makes longer: on the Cortex-M4F the ROMO generators built with -Os execute fewer instructions per diagnosis step
# than at -O3 and take less flash (`scripts/bench_fw.sh` prints both builds). Values are unchanged: the library is
# built as ISO C99 (-ffp-contract=off), so no optimisation level fuses or reorders float operations. Debug and
# MinSizeRel builds keep their own level; OFF leaves every source at the build type's.
option(FDI_GENERATED_FOR_SIZE "Compile the generated generators with -Os in Release/RelWithDebInfo builds" ON)

function(fdi_generated_sources)
  if(FDI_GENERATED_FOR_SIZE AND CMAKE_C_COMPILER_ID MATCHES "GNU|Clang")
    set_source_files_properties(${ARGN} PROPERTIES COMPILE_OPTIONS "$<$<CONFIG:Release,RelWithDebInfo>:-Os>")
  endif()
endfunction()
