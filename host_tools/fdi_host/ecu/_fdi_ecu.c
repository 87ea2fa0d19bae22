/*
 * _fdi_ecu.c - glue of the shared library fdi_host.ecu._fdi_ecu: the fw/ diagnoser and ECU core (compiled into the
 * same .so by setup.py) plus a few helpers that let host_tools/fdi_host/ecu_lib.py use them through ctypes
 * without mirroring structs that may change (tables) and check the layout of those it mirrors (sizes).
 * The Python module itself is empty; it exists so that setuptools builds and installs the library.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>

#include <stddef.h>
#include <string.h>

#include "fdi_ecu.h"
#include "fdi_kin_table.h"
#include "fdi_romo_table.h"

/* sizeof of the structs ecu_lib.py handles: 0 fdi_ecu_t, 1 config, 2 counters, 3 result, 4 tx; else 0. */
size_t fdi_py_sizeof(int what)
{
    size_t n = 0U;
    switch (what)
    {
    case 0: n = sizeof(fdi_ecu_t); break;
    case 1: n = sizeof(fdi_ecu_config_t); break;
    case 2: n = sizeof(fdi_ecu_counters_t); break;
    case 3: n = sizeof(fdi_ecu_result_t); break;
    case 4: n = sizeof(fdi_ecu_tx_t); break;
    case 5: n = offsetof(fdi_ecu_result_t, diag); break;
    case 6: n = offsetof(fdi_diag_result_t, iso); break;
    case 7: n = FDI_DIAG_MAX_TESTS; break;
    default: break;
    }
    return n;
}

/* The built-in tables by name ("kin", "romo"); NULL for others. */
const fdi_table_t *fdi_py_table(const char *name)
{
    const fdi_table_t *t = NULL;
    if (name != NULL)
    {
        if (strcmp(name, "kin") == 0)
        {
            t = &fdi_kin_table;
        }
        else if (strcmp(name, "romo") == 0)
        {
            t = &fdi_romo_table;
        }
    }
    return t;
}

/* Integers of a table: 0 n_faults, 1 n_tests, 2 mso_id of test i, 3 kind of test i, 4 fault_mask of test i,
   5 input_mask of test i, 6 iso_class of fault i, 7 fault_signature of fault i,
   8 design dt in microseconds; -1 on bad arguments. */
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
        case 0: v = nf; break;
        case 1: v = nt; break;
        case 2: v = test_ok ? (long long)t->tests[i].mso_id : -1; break;
        case 3: v = test_ok ? (long long)t->tests[i].kind : -1; break;
        case 4: v = test_ok ? (long long)t->tests[i].fault_mask : -1; break;
        case 5: v = test_ok ? (long long)t->tests[i].input_mask : -1; break;
        case 6: v = fault_ok ? (long long)t->iso_class[i] : -1; break;
        case 7: v = fault_ok ? (long long)t->fault_signature[i] : -1; break;
        case 8: v = (long long)(t->design.dt * 1.0e6f + 0.5f); break;
        default: break;
        }
    }
    return v;
}

/* Strings of a table: 0 fault name i, 1 interpretation of test i; NULL on bad arguments. */
const char *fdi_py_table_str(const fdi_table_t *t, int what, int i)
{
    const char *s = NULL;
    if ((t != NULL) && (i >= 0))
    {
        if ((what == 0) && (i < (int)t->n_faults))
        {
            s = t->fault_names[i];
        }
        else if ((what == 1) && (i < (int)t->n_tests))
        {
            s = t->tests[i].interpretation;
        }
    }
    return s;
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

static struct PyModuleDef fdi_ecu_module = {PyModuleDef_HEAD_INIT, "_fdi_ecu",
                                            "fw/ diagnoser and ECU core; use fdi_host.ecu.bindings", -1, NULL,
                                            NULL, NULL, NULL, NULL};

PyMODINIT_FUNC PyInit__fdi_ecu(void)
{
    return PyModule_Create(&fdi_ecu_module);
}
