/*
 * fuzz_iso.c - libFuzzer harness of the table check and the isolation logic (fdi_table_check, fdi_iso_run).
 *
 * From the input: a random table (1..32 faults, 1..32 tests, random fault masks; signatures and classes
 * derived as the exporter must), which must pass fdi_table_check(); a corrupted copy (one field changed),
 * which fdi_table_check() may accept only if it is still consistent; then random alarm / evaluable masks
 * (valid and invalid) through fdi_iso_run() in both modes. Invariants checked after every call:
 *  - invalid masks (alarm outside evaluable, bits beyond n_tests) give FDI_BAD_ARG;
 *  - no candidate outside the table's faults; nothing alarms -> no candidate, not detected, not isolated;
 *  - each candidate explains every alarm (alarm within its signature) and, with exoneration, no quiet
 *    evaluable test sees it; every fault meeting those conditions is a candidate (complete);
 *  - exoneration candidates are a subset of the no-exoneration candidates;
 *  - class_mask == candidates (whole classes), n_classes = number of distinct signatures among them,
 *    isolated <=> one class;
 *  - the fault whose signature (restricted to the evaluable tests) is exactly the alarm pattern is always a
 *    candidate (a single fault is never missed).
 */
#include <stdbool.h>

#include "fdi_iso.h"
#include "fdi_table.h"
#include "fuzz_input.h"

static uint32_t low_bits(uint32_t n)
{
    return (n >= 32U) ? 0xFFFFFFFFU : (((uint32_t)1U << n) - 1U);
}

typedef struct
{
    fdi_table_t t;
    fdi_test_desc_t tests[FDI_TABLE_MAX_TESTS];
    uint32_t sig[FDI_TABLE_MAX_FAULTS];
    uint32_t cls[FDI_TABLE_MAX_FAULTS];
    const char *names[FDI_TABLE_MAX_FAULTS];
} table_buf_t;

static void derive(table_buf_t *b)
{
    uint32_t j;
    uint32_t g;
    uint32_t i;
    for (j = 0U; j < b->t.n_faults; ++j)
    {
        b->sig[j] = 0U;
        for (i = 0U; i < b->t.n_tests; ++i)
        {
            if ((b->tests[i].fault_mask >> j) & 1U)
            {
                b->sig[j] |= (uint32_t)1U << i;
            }
        }
    }
    for (j = 0U; j < b->t.n_faults; ++j)
    {
        b->cls[j] = 0U;
        for (g = 0U; g < b->t.n_faults; ++g)
        {
            if (b->sig[g] == b->sig[j])
            {
                b->cls[j] |= (uint32_t)1U << g;
            }
        }
    }
}

static void build(table_buf_t *b, fuzz_in_t *in)
{
    uint32_t i;
    uint32_t j;
    const uint8_t nf = (uint8_t)(1U + (fz_u8(in) % 32U));
    const uint8_t nt = (uint8_t)(1U + (fz_u8(in) % 32U));
    memset(b, 0, sizeof *b);
    b->t.format_version = FDI_TABLE_FORMAT_VERSION;
    b->t.design.dt = 0.01f;
    b->t.design.cutoff_hz = 1.0f;
    b->t.design.zeta = 0.7071f;
    b->t.design.obs_gain = 2.0f;
    b->t.n_faults = nf;
    b->t.n_tests = nt;
    for (i = 0U; i < nt; ++i)
    {
        uint32_t m = fz_u32(in) & low_bits(nf);
        if (m == 0U)
        {
            m = (uint32_t)1U << (i % nf);
        }
        b->tests[i].mso_id = (uint16_t)(i + 1U);
        b->tests[i].kind = FDI_GEN_NONE;
        b->tests[i].fault_mask = m;
        b->tests[i].input_mask = 0U;
        b->tests[i].gate = 5.0f;
        b->tests[i].variance = 1.0f;
        b->tests[i].interpretation = "fuzz";
    }
    for (j = 0U; j < nf; ++j)
    {
        b->names[j] = "f";
    }
    derive(b);
    b->t.fault_names = b->names;
    b->t.tests = b->tests;
    b->t.fault_signature = b->sig;
    b->t.iso_class = b->cls;
}

/* Consistency of a table fdi_table_check() accepted, recomputed here independently. */
static bool consistent(const table_buf_t *b)
{
    table_buf_t c = *b;
    uint32_t j;
    uint32_t i;
    bool ok = (b->t.n_faults >= 1U) && (b->t.n_faults <= 32U) && (b->t.n_tests >= 1U) && (b->t.n_tests <= 32U);
    for (i = 0U; ok && (i < b->t.n_tests); ++i)
    {
        ok = (b->tests[i].fault_mask != 0U) && ((b->tests[i].fault_mask & ~low_bits(b->t.n_faults)) == 0U) &&
             (b->tests[i].gate > 0.0f) && (b->tests[i].variance > 0.0f);
    }
    if (ok)
    {
        derive(&c);
        for (j = 0U; ok && (j < b->t.n_faults); ++j)
        {
            ok = (c.sig[j] == b->sig[j]) && (c.cls[j] == b->cls[j]);
        }
    }
    return ok;
}

static void corrupt(table_buf_t *b, fuzz_in_t *in)
{
    const uint8_t what = fz_u8(in) % 8U;
    const uint32_t v = fz_u32(in);
    const uint32_t i = (uint32_t)fz_u8(in) % b->t.n_tests;
    const uint32_t j = (uint32_t)fz_u8(in) % b->t.n_faults;
    switch (what)
    {
    case 0U: b->t.n_faults = (uint8_t)v; break;
    case 1U: b->t.n_tests = (uint8_t)v; break;
    case 2U: b->tests[i].fault_mask = v; break;
    case 3U: b->sig[j] = v; break;
    case 4U: b->cls[j] = v; break;
    case 5U: memcpy(&b->tests[i].gate, &v, sizeof v); break;
    case 6U: b->tests[i].kind = (fdi_gen_kind_t)(v % 16U); break;
    default: b->tests[i].input_mask = v; break;
    }
}

static void check_iso(const fdi_table_t *t, uint32_t alarm, uint32_t eval)
{
    fdi_iso_result_t rx;
    fdi_iso_result_t rn;
    const bool valid = ((alarm & ~eval) == 0U) && ((eval & ~low_bits(t->n_tests)) == 0U);
    const fdi_status_t sx = fdi_iso_run(t, alarm, eval, FDI_ISO_EXONERATION, &rx);
    const fdi_status_t sn = fdi_iso_run(t, alarm, eval, FDI_ISO_NO_EXONERATION, &rn);
    uint32_t j;
    FUZZ_CHECK(sx == (valid ? FDI_OK : FDI_BAD_ARG) && sn == sx, "status %d/%d for alarm %08x eval %08x", (int)sx,
               (int)sn, alarm, eval);
    if (!valid)
    {
        return;
    }
    FUZZ_CHECK((rx.candidates & ~low_bits(t->n_faults)) == 0U, "candidate outside the faults: %08x", rx.candidates);
    FUZZ_CHECK((rn.candidates & ~low_bits(t->n_faults)) == 0U, "candidate outside the faults: %08x", rn.candidates);
    FUZZ_CHECK((rx.candidates & ~rn.candidates) == 0U, "exoneration added a candidate");
    if (alarm == 0U)
    {
        FUZZ_CHECK(rx.candidates == 0U && rn.candidates == 0U && !rx.detected && !rn.detected && !rx.isolated &&
                       !rn.isolated,
                   "something isolated/detected with no alarm");
    }
    for (j = 0U; j < t->n_faults; ++j)
    {
        const uint32_t s = t->fault_signature[j];
        const bool explains = (alarm != 0U) && ((alarm & ~s) == 0U);
        const bool exonerated = ((eval & ~alarm) & s) != 0U;
        FUZZ_CHECK((((rn.candidates >> j) & 1U) != 0U) == explains, "fault %u: no-exoneration candidacy", j);
        FUZZ_CHECK((((rx.candidates >> j) & 1U) != 0U) == (explains && !exonerated), "fault %u: exoneration", j);
        if ((alarm != 0U) && ((s & eval) == alarm))
        {
            FUZZ_CHECK(((rx.candidates >> j) & 1U) != 0U, "fault %u with exactly this pattern missed", j);
        }
    }
    {
        const fdi_iso_result_t *r[2] = {&rx, &rn};
        int m;
        for (m = 0; m < 2; ++m)
        {
            uint32_t seen[FDI_TABLE_MAX_FAULTS];
            uint32_t n_seen = 0U;
            uint32_t k;
            FUZZ_CHECK(r[m]->class_mask == r[m]->candidates, "class mask %08x != candidates %08x", r[m]->class_mask,
                       r[m]->candidates);
            for (j = 0U; j < t->n_faults; ++j)
            {
                if ((r[m]->candidates >> j) & 1U)
                {
                    bool dup = false;
                    for (k = 0U; k < n_seen; ++k)
                    {
                        dup = dup || (seen[k] == t->fault_signature[j]);
                    }
                    if (!dup)
                    {
                        seen[n_seen++] = t->fault_signature[j];
                    }
                }
            }
            FUZZ_CHECK(r[m]->n_classes == n_seen, "n_classes %u, distinct signatures %u", r[m]->n_classes, n_seen);
            FUZZ_CHECK(r[m]->isolated == (n_seen == 1U), "isolated flag");
            FUZZ_CHECK(r[m]->detected == (alarm != 0U), "detected flag");
        }
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fuzz_in_t in = {data, size};
    static table_buf_t b;
    static table_buf_t bad;
    fdi_iso_result_t r;
    int k;
    build(&b, &in);
    FUZZ_CHECK(fdi_table_check(&b.t) == FDI_OK, "a consistent table was rejected");
    FUZZ_CHECK(fdi_iso_run(NULL, 0U, 0U, FDI_ISO_EXONERATION, &r) == FDI_BAD_ARG, "NULL table");
    FUZZ_CHECK(fdi_iso_run(&b.t, 0U, 0U, FDI_ISO_EXONERATION, NULL) == FDI_BAD_ARG, "NULL out");
    FUZZ_CHECK(fdi_iso_run(&b.t, 0U, 0U, (fdi_iso_mode_t)2, &r) == FDI_BAD_ARG, "bad mode");
    bad = b;
    bad.t.tests = bad.tests;
    bad.t.fault_signature = bad.sig;
    bad.t.iso_class = bad.cls;
    bad.t.fault_names = bad.names;
    corrupt(&bad, &in);
    if (fdi_table_check(&bad.t) == FDI_OK)
    {
        FUZZ_CHECK(consistent(&bad), "fdi_table_check accepted an inconsistent table");
        check_iso(&bad.t, 0U, low_bits(bad.t.n_tests));
    }
    for (k = 0; (k < 64) && (in.n > 0U); ++k)
    {
        const uint8_t sel = fz_u8(&in);
        uint32_t eval = fz_u32(&in);
        uint32_t alarm = fz_u32(&in);
        if ((sel & 1U) == 0U) /* mostly valid masks, sometimes raw */
        {
            eval &= low_bits(b.t.n_tests);
            alarm &= eval;
        }
        if ((sel & 6U) == 2U) /* the exact pattern of one fault on the evaluable tests */
        {
            alarm = b.sig[(uint32_t)(sel >> 3) % b.t.n_faults] & eval;
        }
        check_iso(&b.t, alarm, eval);
    }
    return 0;
}
