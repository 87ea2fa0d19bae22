/*
 * fdi_frame.h - the signal frame: one sample of every measured signal of a vehicle, by index.
 *
 * The library knows no signal by name. A vehicle's generated code (fw/vehicles/<vehicle>/generated/
 * fdi_<vehicle>_signals.h, written by `fdi-analyze export-c` from the model file) numbers its measured
 * signals 0..n-1 in the model's order and defines for each the index <VEHICLE>_SIG_<NAME> and the mask
 * <VEHICLE>_SIGM_<NAME> = 1 << index; the table says how many there are (fdi_table_t.n_signals). A validity
 * bitmask with the same bit layout accompanies every frame: bit set = the sample is fresh and plausible (the
 * caller's CAN layer clears it on timeout, checksum or range errors). Generators declare the signals they read
 * as such a mask; the diagnoser reports a test "not evaluable" when any of them is invalid or not finite.
 *
 * fdi_frame_finite_mask() returns the signals of a mask whose value is finite: one multiply and add per signal up
 * to the highest bit of the mask (the sum of value * 0 is finite iff every value is), and one compare pair per
 * such signal only when some value is not finite.
 * Memory: fdi_frame_t is FDI_FRAME_MAX_SIGNALS floats (128 bytes), asserted below.
 */
#ifndef FDI_FRAME_H
#define FDI_FRAME_H

#include <stdint.h>

#include "fdi_static_assert.h"

#define FDI_FRAME_MAX_SIGNALS 32U /* validity and input masks are uint32_t */

typedef struct
{
    float value[FDI_FRAME_MAX_SIGNALS]; /* value[i]: signal i of the vehicle, in its SI unit */
} fdi_frame_t;

/* cppcheck-suppress misra-c2012-2.3 ; compile-time assertion (fw/MISRA_DEVIATIONS.md) */
FDI_STATIC_ASSERT(sizeof(fdi_frame_t) == (FDI_FRAME_MAX_SIGNALS * sizeof(float)), fdi_sa_frame_size);

/* The signals of `mask` whose value in *frame is finite (bit layout as the mask). frame == NULL gives 0. */
uint32_t fdi_frame_finite_mask(const fdi_frame_t *frame, uint32_t mask);

/* Mask of the first n signals (n >= 32: all 32); also of the first n tests or faults of a table. Cannot fail.
   Inline: the isolation calls it on its hot path, where a call into another unit would cost instructions at
   every matching step. */
static inline uint32_t fdi_frame_low_mask(uint32_t n)
{
    return (n >= 32U) ? 0xFFFFFFFFU : (((uint32_t)1U << n) - 1U);
}

#endif /* FDI_FRAME_H */
