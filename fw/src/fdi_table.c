/* fdi_table.c - validation of an exported diagnosis table (see fdi_table.h). */
#include "fdi_table.h"

#include <stdbool.h>
#include <stddef.h>

#include "fdi_float.h"
#include "fdi_frame.h"
#include "fdi_gen.h"

static bool table_positive_finite(float x)
{
    return fdi_float_is_finite(x) && (x > 0.0f);
}

static bool header_ok(const fdi_table_t *t)
{
    return (t->format_version == FDI_TABLE_FORMAT_VERSION) && (t->n_signals >= 1U) &&
           (t->n_signals <= FDI_FRAME_MAX_SIGNALS) && (t->signal_names != NULL) && (t->n_faults >= 1U) &&
           (t->n_faults <= FDI_TABLE_MAX_FAULTS) && (t->n_tests >= 1U) && (t->n_tests <= FDI_TABLE_MAX_TESTS) &&
           (t->fault_names != NULL) && (t->tests != NULL) && (t->fault_signature != NULL) &&
           (t->iso_class != NULL) && (t->test_size != NULL) && fdi_float_is_finite(t->exoneration_margin) &&
           (t->exoneration_margin >= 1.0f) && fdi_float_is_finite(t->sensitivity_margin) &&
           (t->sensitivity_margin >= 1.0f) && table_positive_finite(t->design.dt) &&
           table_positive_finite(t->design.cutoff_hz) &&
           table_positive_finite(t->design.zeta) && table_positive_finite(t->design.obs_gain);
}

static bool test_ok(const fdi_test_desc_t *d, uint32_t fault_universe, uint32_t signal_universe)
{
    bool ok = (d->interpretation != NULL) && (d->fault_mask != 0U) && ((d->fault_mask & ~fault_universe) == 0U) &&
              ((d->input_mask & ~signal_universe) == 0U) && table_positive_finite(d->gate) &&
              table_positive_finite(d->variance) && (d->response_steps >= 1U);
    if (ok && (d->gen != NULL))
    {
        const uint32_t need = d->gen->input_mask;
        ok = (fdi_gen_desc_check(d->gen) == FDI_OK) && ((d->input_mask & need) == need) &&
             (((d->gen->sens_mask | d->gen->rate_mask) & ~d->fault_mask) == 0U);
    }
    return ok;
}

static bool names_ok(const char *const *names, uint32_t n)
{
    bool ok = true;
    uint32_t k;
    for (k = 0U; ok && (k < n); ++k)
    {
        ok = names[k] != NULL;
    }
    return ok;
}

/* Signature of fault j rebuilt from the tests' fault masks. */
static uint32_t column(const fdi_table_t *t, uint32_t j)
{
    uint32_t sig = 0U;
    uint32_t i;
    for (i = 0U; i < (uint32_t)t->n_tests; ++i)
    {
        if ((t->tests[i].fault_mask & ((uint32_t)1U << j)) != 0U)
        {
            sig |= ((uint32_t)1U << i);
        }
    }
    return sig;
}

static bool faults_ok(const fdi_table_t *t)
{
    const uint32_t n = (uint32_t)t->n_faults;
    bool ok = true;
    uint32_t j;
    for (j = 0U; ok && (j < n); ++j)
    {
        uint32_t same = 0U;
        uint32_t g;
        ok = (t->fault_names[j] != NULL) && (t->fault_signature[j] == column(t, j));
        for (g = 0U; ok && (g < n); ++g)
        {
            if (t->fault_signature[g] == t->fault_signature[j])
            {
                same |= ((uint32_t)1U << g);
            }
        }
        ok = ok && (t->iso_class[j] == same);
        for (g = 0U; ok && (g < (uint32_t)t->n_tests); ++g)
        {
            const float size = t->test_size[(j * (uint32_t)t->n_tests) + g];
            ok = fdi_float_is_finite(size) && (size >= 0.0f) &&
                 ((size <= 0.0f) || ((t->fault_signature[j] & ((uint32_t)1U << g)) != 0U));
        }
    }
    return ok;
}

/* The generated generators of the tests: slots of one set, each slot at most once, the set's bank within the
   vehicle's signals (the descriptors themselves are checked by test_ok). */
static bool set_ok(const fdi_table_t *t, uint32_t signals)
{
    const fdi_gen_set_t *set = NULL;
    uint32_t slots = 0U;
    bool ok = true;
    uint32_t i;
    for (i = 0U; ok && (i < (uint32_t)t->n_tests); ++i)
    {
        const fdi_gen_desc_t *g = t->tests[i].gen;
        if ((g != NULL) && (g->set != NULL))
        {
            const uint32_t bit = (uint32_t)1U << (g->slot & 31U);
            ok = ((set == NULL) || (set == g->set)) && ((slots & bit) == 0U);
            set = g->set;
            slots |= bit;
        }
    }
    if (ok && (set != NULL))
    {
        /* derived signals take free places of the frame and are computed from the vehicle's signals */
        const uint32_t derived = fdi_gen_derived_signals(set);
        uint32_t k;
        ok = (fdi_gen_set_check(set) == FDI_OK) && ((derived & signals) == 0U) &&
             ((fdi_gen_bank_signals(set) & ~(signals | derived)) == 0U);
        for (k = 0U; ok && (k < (uint32_t)set->n_derived); ++k)
        {
            ok = (set->derived[k].sources & ~signals) == 0U;
        }
    }
    return ok;
}

/* The envelope, if any: 1..FDI_TABLE_MAX_ENVELOPE distinct frame signals, finite positive limits, 1..n votes. */
static bool envelope_ok(const fdi_table_envelope_t *e, uint32_t n_signals)
{
    bool ok = true;
    if (e != NULL)
    {
        uint32_t seen = 0U;
        uint32_t k;
        ok = (e->n_signals >= 1U) && (e->n_signals <= FDI_TABLE_MAX_ENVELOPE) && (e->votes >= 1U) &&
             (e->votes <= e->n_signals) && (e->signal != NULL) && (e->limit != NULL);
        for (k = 0U; ok && (k < (uint32_t)e->n_signals); ++k)
        {
            const uint32_t sig = (uint32_t)e->signal[k];
            ok = (sig < n_signals) && ((seen & ((uint32_t)1U << sig)) == 0U) && table_positive_finite(e->limit[k]);
            seen |= (sig < n_signals) ? ((uint32_t)1U << sig) : 0U;
        }
    }
    return ok;
}

fdi_status_t fdi_table_check(const fdi_table_t *table)
{
    fdi_status_t st = FDI_OK;
    if (table == NULL)
    {
        st = FDI_BAD_ARG;
    }
    else if (!header_ok(table))
    {
        st = FDI_BAD_TABLE;
    }
    else
    {
        const uint32_t universe = fdi_frame_low_mask((uint32_t)table->n_faults);
        const uint32_t signals = fdi_frame_low_mask((uint32_t)table->n_signals);
        uint32_t i;
        if (!names_ok(table->signal_names, (uint32_t)table->n_signals))
        {
            st = FDI_BAD_TABLE;
        }
        for (i = 0U; (st == FDI_OK) && (i < (uint32_t)table->n_tests); ++i)
        {
            if (!test_ok(&table->tests[i], universe, signals))
            {
                st = FDI_BAD_TABLE;
            }
        }
        if ((st == FDI_OK) && !set_ok(table, signals))
        {
            st = FDI_BAD_TABLE;
        }
        if ((st == FDI_OK) && !faults_ok(table))
        {
            st = FDI_BAD_TABLE;
        }
        if ((st == FDI_OK) && !envelope_ok(table->envelope, (uint32_t)table->n_signals))
        {
            st = FDI_BAD_TABLE;
        }
    }
    return st;
}
