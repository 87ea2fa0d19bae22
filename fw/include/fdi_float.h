/*
 * fdi_float.h - IEEE-754 single precision helpers that do not depend on the C library.
 *
 * fdi_float_is_finite(x) is true iff -FLT_MAX <= x <= FLT_MAX: both ordered comparisons are false for NaN
 * and one of them for +-Inf. It uses no library call and never promotes to double (some newlib versions
 * implement isfinite() through a double, which trips -Wdouble-promotion), and no type punning (MISRA
 * 21.15). It relies on IEEE semantics: do not build the library with -ffast-math / -ffinite-math-only.
 * Cost: two float compares. Memory: none.
 */
#ifndef FDI_FLOAT_H
#define FDI_FLOAT_H

#include <float.h>
#include <stdbool.h>

static inline bool fdi_float_is_finite(float x)
{
    return (x >= -FLT_MAX) && (x <= FLT_MAX);
}

#endif /* FDI_FLOAT_H */
