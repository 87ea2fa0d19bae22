/*
 * fuzz_input.h - reading typed values from a libFuzzer input (a byte cursor that yields zeros when the
 * input runs out), and an abort-with-message check for harness invariants. Shared by the fuzz harnesses.
 */
#ifndef FUZZ_INPUT_H
#define FUZZ_INPUT_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct
{
    const uint8_t *p;
    size_t n;
} fuzz_in_t;

static inline uint8_t fz_u8(fuzz_in_t *in)
{
    uint8_t v = 0U;
    if (in->n > 0U)
    {
        v = in->p[0];
        in->p++;
        in->n--;
    }
    return v;
}

static inline uint32_t fz_u32(fuzz_in_t *in)
{
    uint32_t v = 0U;
    int i;
    for (i = 0; i < 4; ++i)
    {
        v |= (uint32_t)fz_u8(in) << (8 * i);
    }
    return v;
}

static inline float fz_f32(fuzz_in_t *in) /* any bit pattern: NaN, Inf, denormals, extremes */
{
    const uint32_t u = fz_u32(in);
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}

#define FUZZ_CHECK(cond, ...)                                                                                     \
    do                                                                                                            \
    {                                                                                                             \
        if (!(cond))                                                                                              \
        {                                                                                                         \
            fprintf(stderr, "invariant violated (%s:%d): %s: ", __FILE__, __LINE__, #cond);                       \
            fprintf(stderr, __VA_ARGS__);                                                                         \
            fprintf(stderr, "\n");                                                                                \
            abort();                                                                                              \
        }                                                                                                         \
    } while (0)

#endif /* FUZZ_INPUT_H */
