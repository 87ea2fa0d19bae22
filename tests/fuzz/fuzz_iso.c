/*
 * fuzz_iso.c - libFuzzer harness of the table check and the isolation logic (fdi_table_check, fdi_iso_run).
 *
 * From the input: a random table (1..32 faults, 1..32 tests, random fault masks; signatures and classes
 * derived as the exporter must; reaction sizes on the signature pairs, some 0 = weak, or the classic 1s; a
 * margin >= 1), which must pass fdi_table_check(); a corrupted copy (one field changed),
 * which fdi_table_check() may accept only if it is still consistent; then random alarm / evaluable masks
 * (valid and invalid) through fdi_iso_run() in both modes. Invariants checked after every call:
 *  - invalid masks (alarm outside evaluable, bits beyond n_tests) give FDI_BAD_ARG;
 *  - no candidate outside the table's faults; nothing alarms -> no candidate, not detected, not isolated;
 *  - each candidate explains every alarm (alarm within its signature) and, with exoneration, no quiet
 *    evaluable test clears it by the reaction-size rule of fdi_iso.h (recomputed here in double); every
 *    fault meeting those conditions is a candidate (complete);
 *  - exoneration candidates are a subset of the no-exoneration candidates;
 *  - class_mask == the union of the candidates' classes, n_classes = number of distinct signatures among them,
 *    isolated <=> one class;
 *  - the fault whose signature (restricted to the evaluable tests) is exactly the alarm pattern is always a
 *    candidate (a single fault is never missed);
 *  - an ideal response of fault j at any size m (alarm = the evaluable tests with 0 < s(j,i) <= m, the other
 *    evaluable tests quiet) never exonerates j.
 */
#include <math.h>
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
    float size[FDI_TABLE_MAX_FAULTS * FDI_TABLE_MAX_TESTS];
} table_buf_t;

static const float size_choice[8] = {0.0f, 0.01f, 0.1f, 1.0f, 2.0f, 5.0f, 10.0f, 100.0f};
static const float margin_choice[4] = {1.0f, 1.5f, 2.0f, 4.0f};

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

static const char *const signal_names[1] = {"s"};

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
    b->t.n_signals = 1U;
    b->t.signal_names = signal_names;
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
        b->tests[i].gen = NULL; /* the isolation needs no generator */
        b->tests[i].fault_mask = m;
        b->tests[i].input_mask = 0U;
        b->tests[i].gate = 5.0f;
        b->tests[i].variance = 1.0f;
        b->tests[i].response_steps = 1U;
        b->tests[i].interpretation = "fuzz";
    }
    for (j = 0U; j < nf; ++j)
    {
        b->names[j] = "f";
    }
    derive(b);
    {
        const uint8_t how = fz_u8(in);
        const bool classic = (how & 1U) == 0U;
        b->t.exoneration_margin = classic ? 1.0f : margin_choice[(how >> 1) % 4U];
        b->t.sensitivity_margin = 1.0f;
        for (j = 0U; j < nf; ++j)
        {
            for (i = 0U; i < nt; ++i)
            {
                const bool on = ((b->sig[j] >> i) & 1U) != 0U;
                b->size[(j * nt) + i] = !on ? 0.0f : (classic ? 1.0f : size_choice[fz_u8(in) % 8U]);
            }
        }
    }
    b->t.fault_names = b->names;
    b->t.tests = b->tests;
    b->t.fault_signature = b->sig;
    b->t.iso_class = b->cls;
    b->t.test_size = b->size;
}

/* Consistency of a table fdi_table_check() accepted, recomputed here independently. */
static bool consistent(const table_buf_t *b)
{
    table_buf_t c = *b;
    uint32_t j;
    uint32_t i;
    bool ok = (b->t.n_faults >= 1U) && (b->t.n_faults <= 32U) && (b->t.n_tests >= 1U) && (b->t.n_tests <= 32U) &&
              (b->t.n_signals >= 1U) && (b->t.n_signals <= 32U) && (b->t.signal_names != NULL);
    for (i = 0U; ok && (i < b->t.n_tests); ++i)
    {
        ok = (b->tests[i].fault_mask != 0U) && ((b->tests[i].fault_mask & ~low_bits(b->t.n_faults)) == 0U) &&
             ((b->tests[i].input_mask & ~low_bits(b->t.n_signals)) == 0U) &&
             (b->tests[i].gate > 0.0f) && (b->tests[i].variance > 0.0f) && (b->tests[i].response_steps >= 1U);
    }
    if (ok)
    {
        derive(&c);
        for (j = 0U; ok && (j < b->t.n_faults); ++j)
        {
            ok = (c.sig[j] == b->sig[j]) && (c.cls[j] == b->cls[j]);
            for (i = 0U; ok && (i < b->t.n_tests); ++i)
            {
                const float sz = b->size[(j * b->t.n_tests) + i];
                ok = (sz >= 0.0f) && isfinite(sz) && ((sz <= 0.0f) || (((b->sig[j] >> i) & 1U) != 0U));
            }
        }
        ok = ok && (b->t.exoneration_margin >= 1.0f) && isfinite(b->t.exoneration_margin);
    }
    return ok;
}

static void corrupt(table_buf_t *b, fuzz_in_t *in)
{
    const uint8_t what = fz_u8(in) % 10U;
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
    case 6U: b->tests[i].input_mask = v; break; /* signals beyond the frame's */
    case 8U: memcpy(&b->size[(j * b->t.n_tests) + i], &v, sizeof v); break;
    case 9U: memcpy(&b->t.exoneration_margin, &v, sizeof v); break;
    default: b->tests[i].input_mask = v; break;
    }
}

/* The reaction-size rule of fdi_iso.h, in double. */
static bool cleared(const fdi_table_t *t, uint32_t j, uint32_t alarm, uint32_t quiet)
{
    const uint32_t nt = t->n_tests;
    double implied = 0.0;
    bool beyond = false;
    bool out = false;
    uint32_t i;
    for (i = 0U; i < nt; ++i)
    {
        const double sz = (double)t->test_size[(j * nt) + i];
        if ((alarm >> i) & 1U)
        {
            beyond = beyond || (sz <= 0.0);
            implied = (sz > implied) ? sz : implied;
        }
    }
    for (i = 0U; i < nt; ++i)
    {
        const double sz = (double)t->test_size[(j * nt) + i];
        if (((quiet >> i) & 1U) && (sz > 0.0) && (beyond || ((double)t->exoneration_margin * sz <= implied)))
        {
            out = true;
        }
    }
    return out;
}

/* Ideal response of fault j at size m on the evaluable tests: j stays a candidate. */
static void check_ideal(const fdi_table_t *t, uint32_t j, float m, uint32_t eval)
{
    uint32_t alarm = 0U;
    uint32_t i;
    fdi_iso_result_t r;
    for (i = 0U; i < t->n_tests; ++i)
    {
        const float sz = t->test_size[(j * t->n_tests) + i];
        alarm |= ((sz > 0.0f) && (sz <= m) && ((eval >> i) & 1U)) ? ((uint32_t)1U << i) : 0U;
    }
    if (alarm != 0U)
    {
        FUZZ_CHECK(fdi_iso_run(t, alarm, eval, FDI_ISO_EXONERATION, &r) == FDI_OK, "ideal response status");
        FUZZ_CHECK(((r.candidates >> j) & 1U) != 0U, "fault %u exonerated by its own ideal response at %g", j,
                   (double)m);
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
        const bool exonerated = cleared(t, j, alarm, (eval & ~alarm) & s);
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
            uint32_t classes = 0U;
            for (j = 0U; j < t->n_faults; ++j)
            {
                classes |= ((r[m]->candidates >> j) & 1U) ? t->iso_class[j] : 0U;
            }
            FUZZ_CHECK(r[m]->class_mask == classes, "class mask %08x != classes of candidates %08x", r[m]->class_mask,
                       classes);
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
    bad.t.test_size = bad.size;
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
        if ((sel & 0x30U) == 0x10U)
        {
            check_ideal(&b.t, (uint32_t)fz_u8(&in) % b.t.n_faults, size_choice[fz_u8(&in) % 8U] * 1.5f,
                        eval & low_bits(b.t.n_tests));
        }
    }
    return 0;
}
