/* fdi_iso.c - signature matching, the reaction-size rule of exoneration (see fdi_iso.h). */
#include "fdi_iso.h"

#include <stddef.h>

/* Faults of test i's generator with an on-line sensitivity (left to the diagnoser's rule). */
static uint32_t iso_sens_mask(const fdi_table_t *table, uint32_t i)
{
    const fdi_gen_desc_t *g = table->tests[i].gen;
    return (g != NULL) ? g->sens_mask : 0U;
}

/*
 * Whether a quiet test clears fault j by the reaction sizes: the alarms imply, were the fault j, a size of at
 * least implied = max over alarmed tests of their reaction size (any alarmed test that never reacts to j
 * within its limits implies a size beyond every stated one); a quiet test with reaction size s > 0 and
 * margin * s <= implied would have reacted. Quiet tests that give j's sensitivity on line are skipped.
 */
static bool iso_exonerated(const fdi_table_t *table, uint32_t j, uint32_t alarm_mask, uint32_t quiet)
{
    const uint32_t nt = (uint32_t)table->n_tests;
    const uint32_t fbit = (uint32_t)1U << j;
    const float *row = &table->test_size[(size_t)j * (size_t)nt];
    float least = 0.0f; /* the smallest reaction size of a quiet test that may clear j (0: none) */
    bool cleared = false;
    uint32_t left = quiet; /* the tests of a mask still to look at: each loop stops after its last one */
    uint32_t i;
    for (i = 0U; (left != 0U) && (i < nt); ++i)
    {
        const uint32_t bit = (uint32_t)1U << i;
        if (((left & bit) != 0U) && (row[i] > 0.0f) && ((least <= 0.0f) || (row[i] < least)) &&
            ((iso_sens_mask(table, i) & fbit) == 0U))
        {
            least = row[i];
        }
        left &= ~bit;
    }
    if (least > 0.0f) /* else no quiet test can clear j: the alarms need not be looked at */
    {
        const float need = table->exoneration_margin * least; /* the quiet test that reacts at the smallest size */
        float implied = 0.0f;
        bool beyond = false;
        left = alarm_mask;
        for (i = 0U; (left != 0U) && (i < nt) && !beyond; ++i)
        {
            const uint32_t bit = (uint32_t)1U << i;
            if ((left & bit) != 0U)
            {
                left &= ~bit;
                if (row[i] <= 0.0f)
                {
                    beyond = true;
                }
                else if (row[i] > implied)
                {
                    implied = row[i];
                }
                else
                {
                    /* a smaller size implies less */
                }
            }
        }
        cleared = beyond || (need <= implied);
    }
    return cleared;
}

static bool iso_table_usable(const fdi_table_t *table)
{
    return (table != NULL) && (table->fault_signature != NULL) && (table->iso_class != NULL) &&
           (table->test_size != NULL) && (table->tests != NULL) && (table->n_faults <= FDI_TABLE_MAX_FAULTS) &&
           (table->n_tests <= FDI_TABLE_MAX_TESTS);
}

uint32_t fdi_iso_size_cleared(const fdi_table_t *table, uint32_t alarm_mask, uint32_t quiet)
{
    uint32_t cleared = 0U;
    if (iso_table_usable(table) && (alarm_mask != 0U) && ((alarm_mask & quiet) == 0U) &&
        (((alarm_mask | quiet) & ~fdi_frame_low_mask(table->n_tests)) == 0U))
    {
        uint32_t j;
        for (j = 0U; j < (uint32_t)table->n_faults; ++j)
        {
            const uint32_t sig = table->fault_signature[j];
            if (((alarm_mask & ~sig) == 0U) && iso_exonerated(table, j, alarm_mask, quiet & sig))
            {
                cleared |= ((uint32_t)1U << j);
            }
        }
    }
    return cleared;
}

fdi_status_t fdi_iso_match(const fdi_table_t *table, uint32_t alarm_mask, uint32_t cleared, fdi_iso_result_t *out)
{
    fdi_status_t st = FDI_OK;
    if (!iso_table_usable(table) || (out == NULL))
    {
        st = FDI_BAD_ARG;
    }
    else if (((alarm_mask & ~fdi_frame_low_mask(table->n_tests)) != 0U) ||
             ((cleared & ~fdi_frame_low_mask(table->n_faults)) != 0U))
    {
        st = FDI_BAD_ARG;
    }
    else
    {
        uint32_t cand = 0U;
        uint32_t classes = 0U;
        uint32_t left;
        uint8_t n_classes = 0U;
        uint32_t j;
        if (alarm_mask != 0U)
        {
            for (j = 0U; j < (uint32_t)table->n_faults; ++j)
            {
                if ((alarm_mask & ~table->fault_signature[j]) == 0U)
                {
                    cand |= ((uint32_t)1U << j);
                }
            }
            cand &= ~cleared;
        }
        /* Count the classes: take the lowest remaining candidate, remove its whole class. */
        left = cand;
        for (j = 0U; (j < (uint32_t)table->n_faults) && (left != 0U); ++j)
        {
            if ((left & ((uint32_t)1U << j)) != 0U)
            {
                classes |= table->iso_class[j];
                left &= ~table->iso_class[j];
                ++n_classes;
            }
        }
        out->candidates = cand;
        out->class_mask = classes;
        out->n_classes = n_classes;
        out->detected = (alarm_mask != 0U);
        out->isolated = (n_classes == 1U);
    }
    return st;
}

fdi_status_t fdi_iso_run(const fdi_table_t *table, uint32_t alarm_mask, uint32_t evaluable_mask,
                         fdi_iso_mode_t mode, fdi_iso_result_t *out)
{
    fdi_status_t st = FDI_OK;
    if (!iso_table_usable(table) || (out == NULL))
    {
        st = FDI_BAD_ARG;
    }
    else if (((alarm_mask & ~evaluable_mask) != 0U) || ((evaluable_mask & ~fdi_frame_low_mask(table->n_tests)) != 0U) ||
             ((mode != FDI_ISO_NO_EXONERATION) && (mode != FDI_ISO_EXONERATION)))
    {
        st = FDI_BAD_ARG;
    }
    else
    {
        const uint32_t quiet = (mode == FDI_ISO_EXONERATION) ? (evaluable_mask & ~alarm_mask) : 0U;
        st = fdi_iso_match(table, alarm_mask, fdi_iso_size_cleared(table, alarm_mask, quiet), out);
    }
    return st;
}
