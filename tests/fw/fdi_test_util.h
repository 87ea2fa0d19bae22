/*
 * fdi_test_util.h - shared helpers of the fw unit tests (vehicle-independent): tolerance checks that print
 * the numbers and a deterministic Gaussian noise source. The ROMO reference vehicle: fdi_test_vehicle.h.
 */
#ifndef FDI_TEST_UTIL_H
#define FDI_TEST_UTIL_H

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>


#define TEST_PI 3.14159265358979323846

/* Fail (through cmocka's assert_true) unless |actual - expected| <= tol; print all three on failure. */
#define assert_near(actual, expected, tol)                                                                        \
    do                                                                                                            \
    {                                                                                                             \
        const double a_ = (double)(actual);                                                                       \
        const double e_ = (double)(expected);                                                                     \
        const double t_ = (double)(tol);                                                                          \
        if (!(fabs(a_ - e_) <= t_))                                                                               \
        {                                                                                                         \
            print_error("%s = %.9g, expected %.9g +- %.3g (%s:%d)\n", #actual, a_, e_, t_, __FILE__, __LINE__); \
        }                                                                                                         \
        assert_true(fabs(a_ - e_) <= t_);                                                                         \
    } while (0)

/* Deterministic standard normal numbers (xorshift64* + Box-Muller). */
typedef struct
{
    uint64_t s;
} test_rng_t;

static inline double test_uniform(test_rng_t *r)
{
    r->s ^= r->s >> 12;
    r->s ^= r->s << 25;
    r->s ^= r->s >> 27;
    return ((double)((r->s * 2685821657736338717ULL) >> 11) + 0.5) / 9007199254740992.0;
}

static inline double test_normal(test_rng_t *r)
{
    const double u1 = test_uniform(r);
    const double u2 = test_uniform(r);
    return sqrt(-2.0 * log(u1)) * cos(2.0 * TEST_PI * u2);
}

#endif /* FDI_TEST_UTIL_H */
