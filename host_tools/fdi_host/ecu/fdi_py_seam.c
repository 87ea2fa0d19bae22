/*
 * fdi_py_seam.c - the host side of a vehicle plugin: the questions the ctypes bindings
 * (host_tools/fdi_host/ecu/bindings.py) ask a plugin's generic fw/ diagnoser and ECU core without mirroring the
 * structs that may change (tables, buses), and the sizes of those they mirror, which they check. Compiled into every
 * vehicle plugin (fdi_py_plugin.h: a shared library of the core, this file, the vehicle's generated diagnosis and
 * its plugin glue), by setup.py for the shipped vehicles and by the vehicle's generated CMake file for the others.
 * No Python header: the plugin is loaded with ctypes.
 */
#include <stddef.h>
#include <string.h>

#include "fdi_diag.h"
#include "fdi_ecu.h"
#include "fdi_py_plugin.h"
#include "fdi_py_seam.h"

/* sizeof / offsetof / capacities the bindings check (fdi_py_sizeof_t, fdi_py_seam.h); 0 for an unknown one. */
size_t fdi_py_sizeof(int what)
{
    size_t n = 0U;
    switch (what)
    {
    case FDI_PY_SIZEOF_ECU: n = sizeof(fdi_ecu_t); break;
    case FDI_PY_SIZEOF_ECU_CONFIG: n = sizeof(fdi_ecu_config_t); break;
    case FDI_PY_SIZEOF_ECU_COUNTERS: n = sizeof(fdi_ecu_counters_t); break;
    case FDI_PY_SIZEOF_ECU_RESULT: n = sizeof(fdi_ecu_result_t); break;
    case FDI_PY_SIZEOF_ECU_TX: n = sizeof(fdi_ecu_tx_t); break;
    case FDI_PY_SIZEOF_ECU_RESULT_DIAG: n = offsetof(fdi_ecu_result_t, diag); break;
    case FDI_PY_SIZEOF_DIAG_RESULT_ISO: n = offsetof(fdi_diag_result_t, iso); break;
    case FDI_PY_SIZEOF_MAX_TESTS: n = FDI_DIAG_MAX_TESTS; break;
    case FDI_PY_SIZEOF_DIAG: n = sizeof(fdi_diag_t); break;
    case FDI_PY_SIZEOF_MAX_MSGS: n = FDI_ECU_MAX_MSGS; break;
    case FDI_PY_SIZEOF_MAX_SENS: n = FDI_DIAG_MAX_SENS; break;
    case FDI_PY_SIZEOF_DIAG_RESULT_SENS_OFFSET: n = offsetof(fdi_diag_result_t, sens_offset); break;
    case FDI_PY_SIZEOF_DIAG_RESULT: n = sizeof(fdi_diag_result_t); break;
    case FDI_PY_SIZEOF_DIAG_CONFIG: n = sizeof(fdi_diag_config_t); break;
    case FDI_PY_SIZEOF_GEN_N_PARAMS: n = FDI_GEN_N_PARAMS; break;
    case FDI_PY_SIZEOF_FRAME_MAX_SIGNALS: n = FDI_FRAME_MAX_SIGNALS; break;
    case FDI_PY_SIZEOF_ECU_HISTORY: n = FDI_ECU_HISTORY; break;
    case FDI_PY_SIZEOF_DIAG_EVIDENCE: n = sizeof(fdi_diag_evidence_t); break;
    case FDI_PY_SIZEOF_TABLE_MAX_FAULTS: n = FDI_TABLE_MAX_FAULTS; break;
    case FDI_PY_SIZEOF_EST_MAX_PARAMS: n = FDI_EST_MAX_PARAMS; break;
    default: break;
    }
    return n;
}

/* fdi_diag_init for the bindings: it is an inline function of fdi_diag.h (the caller's layout signature), so no
   symbol of the library. */
int fdi_py_diag_init(fdi_diag_t *d, const fdi_diag_config_t *cfg)
{
    return (int)fdi_diag_init(d, cfg);
}

/* The exoneration's evidence of an ECU's diagnoser after its last step (fdi_diag_explain). */
int fdi_py_ecu_explain(const fdi_ecu_t *ecu, fdi_diag_evidence_t *out)
{
    return (int)((ecu != NULL) ? fdi_diag_explain(&ecu->diag, out) : FDI_BAD_ARG);
}

/* Integers of a table (fdi_py_table_int_t, fdi_py_seam.h); -1 on bad arguments. */
long long fdi_py_table_int(const fdi_table_t *t, int what, int i)
{
    long long v = -1;
    if (t != NULL)
    {
        const int nt = (int)t->n_tests;
        const int nf = (int)t->n_faults;
        const int test_ok = (i >= 0) && (i < nt);
        const int fault_ok = (i >= 0) && (i < nf);
        switch (what)
        {
        case FDI_PY_TABLE_INT_N_FAULTS: v = nf; break;
        case FDI_PY_TABLE_INT_N_TESTS: v = nt; break;
        case FDI_PY_TABLE_INT_MSO_ID: v = test_ok ? (long long)t->tests[i].mso_id : -1; break;
        case FDI_PY_TABLE_INT_HAS_GENERATOR: v = test_ok ? (long long)(t->tests[i].gen != NULL) : -1; break;
        case FDI_PY_TABLE_INT_FAULT_MASK: v = test_ok ? (long long)t->tests[i].fault_mask : -1; break;
        case FDI_PY_TABLE_INT_INPUT_MASK: v = test_ok ? (long long)t->tests[i].input_mask : -1; break;
        case FDI_PY_TABLE_INT_ISO_CLASS: v = fault_ok ? (long long)t->iso_class[i] : -1; break;
        case FDI_PY_TABLE_INT_FAULT_SIGNATURE: v = fault_ok ? (long long)t->fault_signature[i] : -1; break;
        case FDI_PY_TABLE_INT_DT_US: v = (long long)(t->design.dt * 1.0e6f + 0.5f); break;
        case FDI_PY_TABLE_INT_N_SIGNALS: v = (long long)t->n_signals; break;
        case FDI_PY_TABLE_INT_SENS_MASK: v = test_ok ? ((t->tests[i].gen != NULL) ? (long long)t->tests[i].gen->sens_mask : 0) : -1; break;
        case FDI_PY_TABLE_INT_N_EST: v = test_ok ? ((t->tests[i].gen != NULL) ? (long long)t->tests[i].gen->n_est : 0) : -1; break;
        default: break;
        }
    }
    return v;
}

/* Reals of a table (fdi_py_table_real_t, fdi_py_seam.h); -1 on bad arguments. */
double fdi_py_table_real(const fdi_table_t *t, int what, int i)
{
    double v = -1.0;
    if (t != NULL)
    {
        const int test_ok = (i >= 0) && (i < (int)t->n_tests);
        switch (what)
        {
        case FDI_PY_TABLE_REAL_SENSITIVITY_MARGIN: v = (double)t->sensitivity_margin; break;
        case FDI_PY_TABLE_REAL_GATE: v = test_ok ? (double)t->tests[i].gate : -1.0; break;
        case FDI_PY_TABLE_REAL_VARIANCE: v = test_ok ? (double)t->tests[i].variance : -1.0; break;
        default: break;
        }
    }
    return v;
}

/* Strings of a table (fdi_py_table_str_t, fdi_py_seam.h); NULL on bad arguments. */
const char *fdi_py_table_str(const fdi_table_t *t, int what, int i)
{
    const char *s = NULL;
    if ((t != NULL) && (i >= 0))
    {
        if ((what == (int)FDI_PY_TABLE_STR_FAULT_NAME) && (i < (int)t->n_faults))
        {
            s = t->fault_names[i];
        }
        else if ((what == (int)FDI_PY_TABLE_STR_INTERPRETATION) && (i < (int)t->n_tests))
        {
            s = t->tests[i].interpretation;
        }
        else if ((what == (int)FDI_PY_TABLE_STR_SIGNAL_NAME) && (i < (int)t->n_signals))
        {
            s = t->signal_names[i];
        }
        else if ((what == (int)FDI_PY_TABLE_STR_GENERATOR_NAME) && (i < (int)t->n_tests))
        {
            s = (t->tests[i].gen != NULL) ? t->tests[i].gen->name : "";
        }
    }
    return s;
}

/* Integers of a bus (fdi_py_bus_int_t, fdi_py_seam.h); -1 on bad arguments. */
long long fdi_py_bus_int(const fdi_ecu_bus_t *b, int what, int i)
{
    long long v = -1;
    if (b != NULL)
    {
        const int ok = (i >= 0) && (i < (int)b->n_msgs);
        switch (what)
        {
        case FDI_PY_BUS_INT_N_MSGS: v = (long long)b->n_msgs; break;
        case FDI_PY_BUS_INT_CAN_ID: v = ok ? (long long)b->msgs[i].can_id : -1; break;
        case FDI_PY_BUS_INT_DIAG_ID: v = (long long)b->diag_id; break;
        case FDI_PY_BUS_INT_CYCLE_MS: v = ok ? (long long)b->msgs[i].cycle_ms : -1; break;
        case FDI_PY_BUS_INT_SIGNALS: v = ok ? (long long)b->msgs[i].signals : -1; break;
        case FDI_PY_BUS_INT_DLC: v = ok ? (long long)b->msgs[i].dlc : -1; break;
        case FDI_PY_BUS_INT_DATA_ID: v = ok ? (long long)b->msgs[i].data_id : -1; break;
        case FDI_PY_BUS_INT_DIAG_DATA_ID: v = (long long)b->diag_data_id; break;
        default: break;
        }
    }
    return v;
}

/* Name of message i of a bus; NULL on bad arguments. */
const char *fdi_py_bus_str(const fdi_ecu_bus_t *b, int i)
{
    return ((b != NULL) && (i >= 0) && (i < (int)b->n_msgs)) ? b->msgs[i].name : NULL;
}

/*
 * Offline replay in one call: for frame k (can_id[k], dlc[k], data[8k..8k+7], t_us[k]) fdi_ecu_rx then
 * fdi_ecu_poll; every diagnosis frame is appended to out_data (8 bytes each) with the index k of the frame after
 * which it was produced in out_index. Returns the number of diagnosis frames (at most max_out), or -1 on a bad
 * argument or a failing call.
 */
long fdi_py_process(fdi_ecu_t *ecu, long n, const uint32_t *can_id, const uint8_t *dlc, const uint8_t *data,
                    const uint32_t *t_us, uint8_t *out_data, long *out_index, long max_out)
{
    long k;
    long n_out = 0;
    if ((ecu == NULL) || (n < 0) || (max_out < 0) || ((n > 0) && ((can_id == NULL) || (dlc == NULL) ||
                                                                   (data == NULL) || (t_us == NULL))) ||
        ((max_out > 0) && ((out_data == NULL) || (out_index == NULL))))
    {
        return -1;
    }
    for (k = 0; k < n; ++k)
    {
        fdi_ecu_tx_t tx;
        const uint8_t len = (dlc[k] <= 8U) ? dlc[k] : (uint8_t)255U;
        if ((fdi_ecu_rx(ecu, can_id[k], len, &data[8 * k], t_us[k]) != FDI_OK) ||
            (fdi_ecu_poll(ecu, t_us[k], &tx) != FDI_OK))
        {
            return -1;
        }
        if ((tx.n_frames == 1U) && (n_out < max_out))
        {
            memcpy(&out_data[8 * n_out], tx.frame[0].data, 8U);
            out_index[n_out] = k;
            ++n_out;
        }
    }
    return n_out;
}

/*
 * The diagnoser alone over n frames (values[n * n_signals], signal k of frame s at s * n_signals + k, validity
 * per frame): after each step its residuals (out_r[s * max_tests + i]) and, when out_sens is not NULL, its
 * sensitivities (out_sens[s * max_sens + j], the result's sens[] as listed by sens_offset). Returns the number of
 * steps run, or -1 on a bad argument or a failing call.
 */
long fdi_py_diag_run(fdi_diag_t *d, long n, int n_signals, const float *values, const uint32_t *validity,
                     float *out_r, float *out_sens)
{
    long s;
    if ((d == NULL) || (n < 0) || (n_signals < 0) || (n_signals > (int)FDI_FRAME_MAX_SIGNALS) ||
        ((n > 0) && ((values == NULL) || (validity == NULL) || (out_r == NULL))))
    {
        return -1;
    }
    for (s = 0; s < n; ++s)
    {
        fdi_frame_t in;
        fdi_diag_result_t res;
        int k;
        unsigned i;
        for (k = 0; k < (int)FDI_FRAME_MAX_SIGNALS; ++k)
        {
            in.value[k] = (k < n_signals) ? values[(s * n_signals) + k] : 0.0f;
        }
        if ((fdi_diag_step(d, &in, validity[s]) != FDI_OK) || (fdi_diag_result(d, &res) != FDI_OK))
        {
            return -1;
        }
        for (i = 0U; i < FDI_DIAG_MAX_TESTS; ++i)
        {
            out_r[(s * (long)FDI_DIAG_MAX_TESTS) + (long)i] = res.residual[i];
        }
        if (out_sens != NULL)
        {
            for (i = 0U; i < (unsigned)res.sens_offset[FDI_DIAG_MAX_TESTS]; ++i)
            {
                out_sens[(s * (long)FDI_DIAG_MAX_SENS) + (long)i] = res.sens[i];
            }
        }
    }
    return n;
}
