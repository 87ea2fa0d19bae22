/*
 * test_fdi_frame.c - the finiteness mask of a signal frame (fw/include/fdi_frame.h): every signal finite (the fast
 * path), NaN, +Inf and -Inf at each position of the mask (the per-signal path), non-finite values outside the mask
 * (not reported, also beyond its highest bit), the extreme finite values, -0, the full 32-bit mask, NULL, and the
 * low masks.
 */
#include <float.h>
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include "fdi_frame.h"

static void fill(fdi_frame_t *f, float v)
{
    uint32_t i;
    for (i = 0U; i < FDI_FRAME_MAX_SIGNALS; ++i)
    {
        f->value[i] = v;
    }
}

static void test_all_finite(void **state)
{
    fdi_frame_t f;
    (void)state;
    fill(&f, 1.5f);
    f.value[0] = FLT_MAX;
    f.value[1] = -FLT_MAX;
    f.value[2] = -0.0f;
    f.value[3] = FLT_MIN * 0.5f; /* subnormal */
    assert_int_equal(fdi_frame_finite_mask(&f, 0xFFFFFFFFU), 0xFFFFFFFFU);
    assert_int_equal(fdi_frame_finite_mask(&f, 0x00050003U), 0x00050003U);
    assert_int_equal(fdi_frame_finite_mask(&f, 0U), 0U);
    assert_int_equal(fdi_frame_finite_mask(NULL, 0xFFU), 0U);
}

static void test_not_finite(void **state)
{
    const float bad[3] = {NAN, INFINITY, -INFINITY};
    fdi_frame_t f;
    uint32_t i;
    uint32_t k;
    (void)state;
    for (k = 0U; k < 3U; ++k)
    {
        for (i = 0U; i < FDI_FRAME_MAX_SIGNALS; ++i)
        {
            const uint32_t bit = (uint32_t)1U << i;
            fill(&f, -2.0f);
            f.value[i] = bad[k];
            assert_int_equal(fdi_frame_finite_mask(&f, 0xFFFFFFFFU), ~bit);
            assert_int_equal(fdi_frame_finite_mask(&f, bit | 1U), (i == 0U) ? 0U : 1U);
            assert_int_equal(fdi_frame_finite_mask(&f, ~bit), ~bit); /* outside the mask: not reported */
            if (i > 0U)
            {
                assert_int_equal(fdi_frame_finite_mask(&f, bit - 1U), bit - 1U); /* beyond the highest bit */
            }
        }
    }
    fill(&f, NAN);
    f.value[5] = 3.0f;
    assert_int_equal(fdi_frame_finite_mask(&f, 0xFFFFFFFFU), 0x20U);
}

static void test_low_mask(void **state)
{
    (void)state;
    assert_int_equal(fdi_frame_low_mask(0U), 0U);
    assert_int_equal(fdi_frame_low_mask(5U), 0x1FU);
    assert_int_equal(fdi_frame_low_mask(32U), 0xFFFFFFFFU);
    assert_int_equal(fdi_frame_low_mask(40U), 0xFFFFFFFFU);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_all_finite),
        cmocka_unit_test(test_not_finite),
        cmocka_unit_test(test_low_mask),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
