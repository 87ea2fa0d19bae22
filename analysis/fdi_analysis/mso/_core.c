/*
 * fdi_analysis.mso._core -- native MSO / MTES search (CPython extension, plain C API, C11).
 *
 * Equation sets are bitsets of NW 64-bit words; the engine in _core_impl.h is instantiated for each width of
 * a ladder (1, 2, 3, 4, 5, 6, 8, 12, 16, 24, 32, 64, 128, 256 words) and a model runs on the narrowest one
 * that holds its equations (a 41-equation model on one word, 282 equations on five). The ladder ends at
 * 16384 equations, where the int16 indices end; memory, not a constant, limits the search before that.
 * Python sees equation sets as non-negative ints (bit e = equation e) and opaque capsules for the model,
 * the aggregator and the iterators.
 *
 * Functions (all internal; the typed API is fdi_analysis.mso):
 *   model_new(ne, nv, rows, eqfault)        rows[e] = unknown indices of equation e, eqfault[e] = fault mask
 *   model_dense(ne, nv, nf, inc, fmat)      the same from dense 0/1 byte matrices (ne x nv, ne x nf)
 *   mplus(model, S) -> int                  overdetermined part S+ of equation set S
 *   split(model, S, R) -> (phi, [(S', R')]) children of search node (S, R)
 *   agg_new(model) / agg_run(model, agg, S, R, check_signals) -> interrupted / agg_result(agg)
 *   iter_new(model, S, R, mode, emit_all) / iter_next(it, limit) -> [int]
 * Memory: an iterator holds (redundancy + 2) frames of O(ne) bitsets; the aggregator a histogram and one
 * hash entry per distinct fault signature. Nothing grows with the number of MSO sets.
 */
#define PY_SSIZE_T_CLEAN
#include <Python.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

typedef uint64_t w64;
#define NWMAX 256          /* widest instance: 16384 equations */
#define MAX_INDEX 32000    /* equations and unknowns are int16 indices */
#define CAT_(a, b) a##_##b
#define CAT(a, b) CAT_(a, b)

/* for (each set bit i of bitset a with nw words) body;  `break` is not allowed inside. */
#define BS_FOREACH(a, nw, i)                                                                   \
    for (int i##_k = 0; i##_k < (nw); i##_k++)                                                 \
        for (w64 i##_x = (a).w[i##_k]; i##_x; i##_x &= i##_x - 1)                              \
            for (int i = i##_k * 64 + __builtin_ctzll(i##_x), i##_once = 1; i##_once; i##_once = 0)

/* Result of adding equations to the set T every MSO set of a subtree must hold (see _core_impl.h). */
enum { T_MATCHABLE = 0, T_IS_MSO = 1, T_DEAD = 2 };

struct engine;

typedef struct {
    int ne, nv, nw;
    int phimax;       /* structural redundancy of the whole model: no search node has more */
    int *row_off;     /* ne + 1 */
    int16_t *row_var; /* row_off[ne] */
    w64 *col;         /* nv * nw: equations holding each unknown */
    w64 *eqfault;     /* ne: fault mask (<= 64 faults) */
    const struct engine *eng;
} model_t;

/* ---- aggregation without storing MSO sets --------------------------------------------------------- */
typedef struct {
    w64 key;
    uint64_t count;
    int32_t size;
    int32_t used;
} sigent_t;

typedef struct {
    int ne, nw;
    uint64_t count;
    uint64_t *hist; /* ne + 1, by number of equations */
    sigent_t *tab;
    w64 *best;      /* cap * nw: the smallest MSO set of each entry */
    size_t cap, n;
    int shift;
} agg_t;

static void agg_free(agg_t *a) {
    if (a) {
        free(a->hist);
        free(a->tab);
        free(a->best);
        free(a);
    }
}

static agg_t *agg_create(int ne, int nw) {
    agg_t *a = (agg_t *)calloc(1, sizeof(agg_t));
    if (!a) return NULL;
    a->ne = ne;
    a->nw = nw;
    a->cap = 1024;
    a->shift = 64 - 10;
    a->hist = (uint64_t *)calloc((size_t)ne + 1, sizeof(uint64_t));
    a->tab = (sigent_t *)calloc(a->cap, sizeof(sigent_t));
    a->best = (w64 *)calloc(a->cap * (size_t)nw, sizeof(w64));
    if (!a->hist || !a->tab || !a->best) {
        agg_free(a);
        return NULL;
    }
    return a;
}

static inline size_t agg_slot(const agg_t *a, w64 key) {
    return (size_t)((key * 0x9E3779B97F4A7C15ull) >> a->shift);
}

/* a lexicographically before b (as sorted equation index lists of equal length) */
static inline int lex_less(const w64 *a, const w64 *b, int nw) {
    for (int k = 0; k < nw; k++) {
        w64 d = a[k] ^ b[k];
        if (d) return (a[k] & (d & (~d + 1))) != 0;
    }
    return 0;
}

static int agg_grow(agg_t *a) {
    const size_t oldcap = a->cap, nw = (size_t)a->nw;
    sigent_t *old = a->tab;
    w64 *oldbest = a->best;
    sigent_t *t = (sigent_t *)calloc(oldcap * 2, sizeof(sigent_t));
    w64 *b = (w64 *)calloc(oldcap * 2 * nw, sizeof(w64));
    if (!t || !b) {
        free(t);
        free(b);
        return -1;
    }
    a->tab = t;
    a->best = b;
    a->cap = oldcap * 2;
    a->shift -= 1;
    for (size_t i = 0; i < oldcap; i++) {
        if (old[i].used) {
            size_t j = agg_slot(a, old[i].key);
            while (t[j].used) j = (j + 1) & (a->cap - 1);
            t[j] = old[i];
            memcpy(b + j * nw, oldbest + i * nw, nw * sizeof(w64));
        }
    }
    free(old);
    free(oldbest);
    return 0;
}

static sigent_t *agg_find(agg_t *a, w64 key) {
    size_t j = agg_slot(a, key);
    while (a->tab[j].used && a->tab[j].key != key) j = (j + 1) & (a->cap - 1);
    if (!a->tab[j].used) {
        if (2 * (a->n + 1) > a->cap) {
            if (agg_grow(a) != 0) return NULL;
            return agg_find(a, key);
        }
        a->tab[j].used = 1;
        a->tab[j].key = key;
        a->tab[j].size = INT32_MAX;
        a->n++;
    }
    return &a->tab[j];
}

static int agg_oom = 0; /* set if the hash table could not grow (reported by agg_run) */

static inline void agg_add(agg_t *a, const w64 *S, int nw, int size, w64 sig) {
    a->count++;
    a->hist[size]++;
    sigent_t *e = agg_find(a, sig);
    if (!e) {
        agg_oom = 1;
        return;
    }
    e->count++;
    w64 *best = a->best + (size_t)(e - a->tab) * (size_t)nw;
    if (size < e->size || (size == e->size && lex_less(S, best, nw))) {
        e->size = size;
        for (int k = 0; k < nw; k++) best[k] = S[k];
    }
}

/* ---- engine instances ------------------------------------------------------------------------------- */
/* Width-independent entry points of one instance (the search itself is in _core_impl.h). */
typedef struct engine {
    int nw;
    void *(*alloc)(const model_t *m, int nframes);
    void (*release)(void *it);
    int (*start)(void *it, const w64 *s, const w64 *r, int mode, int emit_all);
    int (*run)(void *it, agg_t *agg, w64 *buf, w64 *sigbuf, size_t *n, size_t limit, int check, int *interrupted);
    int (*error)(void *it);
    int (*split)(void *it, const w64 *s, const w64 *r, w64 *out, int *nout);
    int (*mplus)(const model_t *m, const w64 *s, w64 *out);
} engine_t;

/* the ladder of widths; a model uses the first that holds its equations */
#define NW 1
#include "_core_impl.h"
#undef NW
#define NW 2
#include "_core_impl.h"
#undef NW
#define NW 3
#include "_core_impl.h"
#undef NW
#define NW 4
#include "_core_impl.h"
#undef NW
#define NW 5
#include "_core_impl.h"
#undef NW
#define NW 6
#include "_core_impl.h"
#undef NW
#define NW 8
#include "_core_impl.h"
#undef NW
#define NW 12
#include "_core_impl.h"
#undef NW
#define NW 16
#include "_core_impl.h"
#undef NW
#define NW 24
#include "_core_impl.h"
#undef NW
#define NW 32
#include "_core_impl.h"
#undef NW
#define NW 64
#include "_core_impl.h"
#undef NW
#define NW 128
#include "_core_impl.h"
#undef NW
#define NW 256
#include "_core_impl.h"
#undef NW

static const engine_t *const ENGINES[] = {&engine_1,  &engine_2,  &engine_3,  &engine_4,  &engine_5,
                                          &engine_6,  &engine_8,  &engine_12, &engine_16, &engine_24,
                                          &engine_32, &engine_64, &engine_128, &engine_256};

static const engine_t *engine_for(int ne) {
    const int need = (ne + 63) / 64;
    for (size_t i = 0; i < sizeof ENGINES / sizeof ENGINES[0]; i++)
        if (ENGINES[i]->nw >= need) return ENGINES[i];
    return NULL;
}

/* ---- Python glue ------------------------------------------------------------------------------------ */
static void model_free(model_t *m) {
    if (m) {
        free(m->row_off);
        free(m->row_var);
        free(m->col);
        free(m->eqfault);
        free(m);
    }
}

static void model_capsule_destructor(PyObject *cap) {
    model_free((model_t *)PyCapsule_GetPointer(cap, "fdi_mso.model"));
}

/* Kuhn augmenting path from equation e (recursion depth <= number of equations). */
static int kuhn(const model_t *m, int e, int *varmatch, int *vis, int stamp) {
    for (int k = m->row_off[e]; k < m->row_off[e + 1]; k++) {
        const int x = m->row_var[k];
        if (vis[x] == stamp) continue;
        vis[x] = stamp;
        if (varmatch[x] < 0 || kuhn(m, varmatch[x], varmatch, vis, stamp)) {
            varmatch[x] = e;
            return 1;
        }
    }
    return 0;
}

/* Allocation and the derived fields once rows are known: column bitsets, engine, redundancy bound. */
static model_t *model_alloc(int ne, int nv, size_t nnz) {
    model_t *m = (model_t *)calloc(1, sizeof(model_t));
    if (!m) return NULL;
    m->ne = ne;
    m->nv = nv;
    m->eng = engine_for(ne);
    m->nw = m->eng->nw;
    m->row_off = (int *)calloc((size_t)ne + 1, sizeof(int));
    m->col = (w64 *)calloc((size_t)(nv > 0 ? nv : 1) * (size_t)m->nw, sizeof(w64));
    m->eqfault = (w64 *)calloc((size_t)ne, sizeof(w64));
    m->row_var = (int16_t *)calloc(nnz + 1, sizeof(int16_t));
    if (!m->row_off || !m->col || !m->eqfault || !m->row_var) {
        model_free(m);
        return NULL;
    }
    return m;
}

static int model_finish(model_t *m) {
    int *buf = (int *)malloc((size_t)(2 * m->nv + 1) * sizeof(int));
    if (!buf) return -1;
    int *varmatch = buf, *vis = buf + m->nv;
    for (int x = 0; x < m->nv; x++) varmatch[x] = vis[x] = -1;
    int matched = 0;
    for (int e = 0; e < m->ne; e++) {
        matched += kuhn(m, e, varmatch, vis, e);
        for (int k = m->row_off[e]; k < m->row_off[e + 1]; k++)
            m->col[(size_t)m->row_var[k] * (size_t)m->nw + (size_t)(e >> 6)] |= (w64)1 << (e & 63);
    }
    m->phimax = m->ne - matched;
    free(buf);
    return 0;
}

static int check_sizes(int ne, int nv, int nf) {
    if (ne < 1 || ne > MAX_INDEX || nv < 0 || nv > MAX_INDEX || nf < 0 || nf > 64) {
        PyErr_Format(PyExc_ValueError, "need 1 <= equations <= %d, unknowns <= %d, faults <= 64 (got %d, %d, %d)",
                     MAX_INDEX, MAX_INDEX, ne, nv, nf);
        return -1;
    }
    if (!engine_for(ne)) {
        PyErr_Format(PyExc_ValueError, "%d equations: the widest compiled bitset holds %d", ne, 64 * NWMAX);
        return -1;
    }
    return 0;
}

static int py_to_words(PyObject *o, w64 *out, int nw) {
    if (!PyLong_Check(o)) {
        PyErr_SetString(PyExc_TypeError, "equation set must be an int bitset");
        return -1;
    }
    PyObject *zero = PyLong_FromLong(0);
    if (!zero) return -1;
    int neg = PyObject_RichCompareBool(o, zero, Py_LT);
    Py_DECREF(zero);
    if (neg != 0) {
        if (neg > 0) PyErr_SetString(PyExc_ValueError, "equation set must be non-negative");
        return -1;
    }
    Py_INCREF(o);
    PyObject *v = o;
    PyObject *sh = PyLong_FromLong(64);
    if (!sh) {
        Py_DECREF(v);
        return -1;
    }
    for (int k = 0; k < nw; k++) {
        out[k] = (w64)PyLong_AsUnsignedLongLongMask(v);
        PyObject *nv = PyNumber_Rshift(v, sh);
        Py_DECREF(v);
        v = nv;
        if (!v) {
            Py_DECREF(sh);
            return -1;
        }
    }
    Py_DECREF(sh);
    int nonzero = PyObject_IsTrue(v);
    Py_DECREF(v);
    if (nonzero) {
        PyErr_SetString(PyExc_OverflowError, "equation set has bits beyond the model's equations");
        return -1;
    }
    return 0;
}

static PyObject *words_to_py(const w64 *w, int nw) {
    unsigned char bytes[NWMAX * 8];
    for (int k = 0; k < nw; k++)
        for (int b = 0; b < 8; b++) bytes[k * 8 + b] = (unsigned char)(w[k] >> (8 * b));
    return _PyLong_FromByteArray(bytes, (size_t)nw * 8, 1, 0);
}

static model_t *get_model(PyObject *cap) { return (model_t *)PyCapsule_GetPointer(cap, "fdi_mso.model"); }

static PyObject *model_capsule(model_t *m) {
    if (model_finish(m) != 0) {
        model_free(m);
        return PyErr_NoMemory();
    }
    PyObject *cap = PyCapsule_New(m, "fdi_mso.model", model_capsule_destructor);
    if (!cap) model_free(m);
    return cap;
}

static PyObject *py_model_new(PyObject *self, PyObject *args) {
    (void)self;
    int ne, nv;
    PyObject *rows, *faults;
    if (!PyArg_ParseTuple(args, "iiOO", &ne, &nv, &rows, &faults)) return NULL;
    if (check_sizes(ne, nv, 0) != 0) return NULL;
    if (!PyList_Check(rows) || PyList_GET_SIZE(rows) != ne || !PyList_Check(faults) || PyList_GET_SIZE(faults) != ne) {
        PyErr_SetString(PyExc_ValueError, "rows and eqfault must be lists with one entry per equation");
        return NULL;
    }
    size_t total = 0;
    for (int e = 0; e < ne; e++) {
        PyObject *r = PyList_GET_ITEM(rows, e);
        if (!PyList_Check(r)) {
            PyErr_SetString(PyExc_TypeError, "each row must be a list of unknown indices");
            return NULL;
        }
        total += (size_t)PyList_GET_SIZE(r);
    }
    model_t *m = model_alloc(ne, nv, total);
    if (!m) return PyErr_NoMemory();
    int pos = 0;
    for (int e = 0; e < ne; e++) {
        PyObject *r = PyList_GET_ITEM(rows, e);
        m->row_off[e] = pos;
        for (Py_ssize_t k = 0; k < PyList_GET_SIZE(r); k++) {
            long x = PyLong_AsLong(PyList_GET_ITEM(r, k));
            if (x < 0 || x >= nv) {
                model_free(m);
                if (!PyErr_Occurred()) PyErr_SetString(PyExc_ValueError, "unknown index out of range");
                return NULL;
            }
            m->row_var[pos++] = (int16_t)x;
        }
        m->eqfault[e] = (w64)PyLong_AsUnsignedLongLongMask(PyList_GET_ITEM(faults, e));
        if (PyErr_Occurred()) {
            model_free(m);
            return NULL;
        }
    }
    m->row_off[ne] = pos;
    return model_capsule(m);
}

/* model_dense(ne, nv, nf, inc, fmat): inc = ne*nv bytes (row-major, nonzero = incidence), fmat = ne*nf bytes.
 * The same model as model_new without building Python lists (the lists cost more than small searches). */
static PyObject *py_model_dense(PyObject *self, PyObject *args) {
    (void)self;
    int ne, nv, nf;
    Py_buffer inc, fm;
    if (!PyArg_ParseTuple(args, "iiiy*y*", &ne, &nv, &nf, &inc, &fm)) return NULL;
    PyObject *cap = NULL;
    model_t *m = NULL;
    if (check_sizes(ne, nv, nf) != 0) goto done;
    if (inc.len != (Py_ssize_t)ne * nv || fm.len != (Py_ssize_t)ne * nf) {
        PyErr_SetString(PyExc_ValueError, "inc must have ne*nv bytes and fmat ne*nf bytes");
        goto done;
    }
    const unsigned char *ip = (const unsigned char *)inc.buf;
    const unsigned char *fp = (const unsigned char *)fm.buf;
    size_t total = 0;
    for (Py_ssize_t k = 0; k < inc.len; k++) total += ip[k] != 0;
    m = model_alloc(ne, nv, total);
    if (!m) {
        PyErr_NoMemory();
        goto done;
    }
    int pos = 0;
    for (int e = 0; e < ne; e++) {
        m->row_off[e] = pos;
        for (int x = 0; x < nv; x++)
            if (ip[(size_t)e * (size_t)nv + (size_t)x]) m->row_var[pos++] = (int16_t)x;
        w64 f = 0;
        for (int j = 0; j < nf; j++)
            if (fp[(size_t)e * (size_t)nf + (size_t)j]) f |= (w64)1 << j;
        m->eqfault[e] = f;
    }
    m->row_off[ne] = pos;
    cap = model_capsule(m);
done:
    PyBuffer_Release(&inc);
    PyBuffer_Release(&fm);
    return cap;
}

static PyObject *py_mplus(PyObject *self, PyObject *args) {
    (void)self;
    PyObject *mc, *so;
    if (!PyArg_ParseTuple(args, "OO", &mc, &so)) return NULL;
    model_t *m = get_model(mc);
    if (!m) return NULL;
    w64 s[NWMAX], r[NWMAX];
    if (py_to_words(so, s, m->nw) != 0) return NULL;
    if (m->eng->mplus(m, s, r) != 0) return PyErr_NoMemory();
    return words_to_py(r, m->nw);
}

/* ---- iterator capsule (also used internally by split and agg_run) ---------------------------------- */
typedef struct {
    const engine_t *eng;
    void *it;
    PyObject *model; /* strong reference */
} iterbox_t;

static void *iter_alloc_any(const model_t *m) { return m->eng->alloc(m, m->phimax + 2); }

static void iterbox_destructor(PyObject *cap) {
    iterbox_t *b = (iterbox_t *)PyCapsule_GetPointer(cap, "fdi_mso.iter");
    if (b) {
        b->eng->release(b->it);
        Py_XDECREF(b->model);
        free(b);
    }
}

static PyObject *py_iter_new(PyObject *self, PyObject *args) {
    (void)self;
    PyObject *mc, *so, *ro;
    int mode = 0, emit_all = 0;
    if (!PyArg_ParseTuple(args, "OOO|ii", &mc, &so, &ro, &mode, &emit_all)) return NULL;
    model_t *m = get_model(mc);
    if (!m) return NULL;
    if (mode != 0 && mode != 1) {
        PyErr_SetString(PyExc_ValueError, "mode must be 0 (MSO) or 1 (MTES)");
        return NULL;
    }
    w64 s[NWMAX], r[NWMAX];
    if (py_to_words(so, s, m->nw) != 0 || py_to_words(ro, r, m->nw) != 0) return NULL;
    iterbox_t *b = (iterbox_t *)calloc(1, sizeof(iterbox_t));
    if (!b) return PyErr_NoMemory();
    b->eng = m->eng;
    b->it = iter_alloc_any(m);
    if (!b->it) {
        free(b);
        return PyErr_NoMemory();
    }
    int phi = m->eng->start(b->it, s, r, mode, emit_all);
    if (phi < 0) {
        b->eng->release(b->it);
        free(b);
        PyErr_SetString(PyExc_ValueError, "start set is not a proper structurally overdetermined (PSO) set");
        return NULL;
    }
    Py_INCREF(mc);
    b->model = mc;
    PyObject *cap = PyCapsule_New(b, "fdi_mso.iter", iterbox_destructor);
    if (!cap) {
        Py_DECREF(mc);
        b->eng->release(b->it);
        free(b);
    }
    return cap;
}

static PyObject *py_iter_next(PyObject *self, PyObject *args) {
    (void)self;
    PyObject *ic;
    Py_ssize_t limit;
    int with_faults = 0;
    if (!PyArg_ParseTuple(args, "On|i", &ic, &limit, &with_faults)) return NULL;
    iterbox_t *b = (iterbox_t *)PyCapsule_GetPointer(ic, "fdi_mso.iter");
    if (!b) return NULL;
    if (limit < 1) limit = 1;
    const model_t *m = get_model(b->model);
    if (!m) return NULL;
    /* slack: one node can emit up to ne results at once */
    size_t cap = (size_t)limit + (size_t)m->ne + 1;
    const int nw = b->eng->nw;
    w64 *buf = (w64 *)malloc(cap * ((size_t)nw + 1) * sizeof(w64));
    if (!buf) return PyErr_NoMemory();
    w64 *sigbuf = with_faults ? buf + cap * (size_t)nw : NULL;
    size_t n = 0;
    int interrupted = 0;
    int rc = b->eng->run(b->it, NULL, buf, sigbuf, &n, (size_t)limit, 0, &interrupted);
    if (rc < 0 && b->eng->error(b->it)) {
        free(buf);
        PyErr_Format(PyExc_RuntimeError, "MSO engine internal error %d", b->eng->error(b->it));
        return NULL;
    }
    PyObject *out = PyList_New((Py_ssize_t)n);
    if (!out) {
        free(buf);
        return NULL;
    }
    for (size_t i = 0; i < n; i++) {
        PyObject *v = words_to_py(buf + i * (size_t)nw, nw);
        if (v && sigbuf) {
            PyObject *f = PyLong_FromUnsignedLongLong(sigbuf[i]);
            PyObject *t = f ? PyTuple_Pack(2, v, f) : NULL;
            Py_XDECREF(f);
            Py_DECREF(v);
            v = t;
        }
        if (!v) {
            free(buf);
            Py_DECREF(out);
            return NULL;
        }
        PyList_SET_ITEM(out, (Py_ssize_t)i, v);
    }
    free(buf);
    return out;
}

static PyObject *py_split(PyObject *self, PyObject *args) {
    (void)self;
    PyObject *mc, *so, *ro;
    if (!PyArg_ParseTuple(args, "OOO", &mc, &so, &ro)) return NULL;
    model_t *m = get_model(mc);
    if (!m) return NULL;
    w64 s[NWMAX], r[NWMAX];
    if (py_to_words(so, s, m->nw) != 0 || py_to_words(ro, r, m->nw) != 0) return NULL;
    void *it = iter_alloc_any(m);
    w64 *out = (w64 *)calloc((size_t)m->ne * 2 * (size_t)m->nw, sizeof(w64));
    if (!it || !out) {
        free(out);
        if (it) m->eng->release(it);
        return PyErr_NoMemory();
    }
    int nout = 0, phi;
    phi = m->eng->split(it, s, r, out, &nout);
    m->eng->release(it);
    if (phi < 0) {
        free(out);
        PyErr_SetString(PyExc_ValueError, "node set is not a proper structurally overdetermined (PSO) set");
        return NULL;
    }
    PyObject *lst = PyList_New(nout);
    for (int i = 0; lst && i < nout; i++) {
        PyObject *a = words_to_py(out + (size_t)i * 2 * (size_t)m->nw, m->nw);
        PyObject *c = words_to_py(out + (size_t)i * 2 * (size_t)m->nw + m->nw, m->nw);
        PyObject *t = (a && c) ? PyTuple_Pack(2, a, c) : NULL;
        Py_XDECREF(a);
        Py_XDECREF(c);
        if (!t) {
            Py_CLEAR(lst);
            break;
        }
        PyList_SET_ITEM(lst, i, t);
    }
    free(out);
    if (!lst) return NULL;
    return Py_BuildValue("(iN)", phi, lst);
}

/* ---- aggregator -------------------------------------------------------------------------------------- */
static void agg_capsule_destructor(PyObject *cap) { agg_free((agg_t *)PyCapsule_GetPointer(cap, "fdi_mso.agg")); }

static PyObject *py_agg_new(PyObject *self, PyObject *args) {
    (void)self;
    PyObject *mc;
    if (!PyArg_ParseTuple(args, "O", &mc)) return NULL;
    model_t *m = get_model(mc);
    if (!m) return NULL;
    agg_t *a = agg_create(m->ne, m->nw);
    if (!a) return PyErr_NoMemory();
    PyObject *cap = PyCapsule_New(a, "fdi_mso.agg", agg_capsule_destructor);
    if (!cap) agg_free(a);
    return cap;
}

static PyObject *py_agg_run(PyObject *self, PyObject *args) {
    (void)self;
    PyObject *mc, *ac, *so, *ro;
    int check = 0, mode = 0;
    if (!PyArg_ParseTuple(args, "OOOO|ii", &mc, &ac, &so, &ro, &check, &mode)) return NULL;
    model_t *m = get_model(mc);
    agg_t *a = (agg_t *)PyCapsule_GetPointer(ac, "fdi_mso.agg");
    if (!m || !a) return NULL;
    if (a->ne != m->ne) {
        PyErr_SetString(PyExc_ValueError, "aggregator belongs to another model");
        return NULL;
    }
    w64 s[NWMAX], r[NWMAX];
    if (py_to_words(so, s, m->nw) != 0 || py_to_words(ro, r, m->nw) != 0) return NULL;
    void *it = iter_alloc_any(m);
    if (!it) return PyErr_NoMemory();
    if (m->eng->start(it, s, r, mode, 0) < 0) {
        m->eng->release(it);
        PyErr_SetString(PyExc_ValueError, "node set is not a proper structurally overdetermined (PSO) set");
        return NULL;
    }
    size_t n = 0;
    int interrupted = 0;
    agg_oom = 0;
    int rc = m->eng->run(it, a, NULL, NULL, &n, 0, check, &interrupted);
    int err = m->eng->error(it);
    m->eng->release(it);
    if (interrupted) {
        PyErr_Clear(); /* KeyboardInterrupt raised by the handler: reported as a partial result */
        Py_RETURN_TRUE;
    }
    if (agg_oom) return PyErr_NoMemory();
    if (rc < 0 || err) {
        PyErr_Format(PyExc_RuntimeError, "MSO engine internal error %d", err);
        return NULL;
    }
    Py_RETURN_FALSE;
}

static PyObject *py_agg_result(PyObject *self, PyObject *args) {
    (void)self;
    PyObject *ac;
    if (!PyArg_ParseTuple(args, "O", &ac)) return NULL;
    agg_t *a = (agg_t *)PyCapsule_GetPointer(ac, "fdi_mso.agg");
    if (!a) return NULL;
    PyObject *hist = PyList_New(a->ne + 1);
    PyObject *sigs = PyList_New((Py_ssize_t)a->n);
    if (!hist || !sigs) {
        Py_XDECREF(hist);
        Py_XDECREF(sigs);
        return NULL;
    }
    for (int i = 0; i <= a->ne; i++) PyList_SET_ITEM(hist, i, PyLong_FromUnsignedLongLong(a->hist[i]));
    Py_ssize_t j = 0;
    for (size_t i = 0; i < a->cap; i++) {
        const sigent_t *e = &a->tab[i];
        if (!e->used) continue;
        PyObject *t = Py_BuildValue("(KKiN)", (unsigned long long)e->key, (unsigned long long)e->count, (int)e->size,
                                    words_to_py(a->best + i * (size_t)a->nw, a->nw));
        if (!t) {
            Py_DECREF(hist);
            Py_DECREF(sigs);
            return NULL;
        }
        PyList_SET_ITEM(sigs, j++, t);
    }
    return Py_BuildValue("(KNN)", (unsigned long long)a->count, hist, sigs);
}

static PyMethodDef methods[] = {
    {"model_new", py_model_new, METH_VARARGS, "model_new(ne, nv, rows, eqfault) -> model"},
    {"model_dense", py_model_dense, METH_VARARGS, "model_dense(ne, nv, nf, inc_bytes, fault_bytes) -> model"},
    {"mplus", py_mplus, METH_VARARGS, "mplus(model, S) -> overdetermined part of S"},
    {"split", py_split, METH_VARARGS, "split(model, S, R) -> (phi, [(S', R'), ...])"},
    {"iter_new", py_iter_new, METH_VARARGS, "iter_new(model, S, R, mode=0, emit_all=0) -> iterator"},
    {"iter_next", py_iter_next, METH_VARARGS, "iter_next(it, limit, with_faults=0) -> list of equation sets or (set, faults) (empty: done)"},
    {"agg_new", py_agg_new, METH_VARARGS, "agg_new(model) -> aggregator"},
    {"agg_run", py_agg_run, METH_VARARGS, "agg_run(model, agg, S, R, check_signals=0, mode=0) -> interrupted"},
    {"agg_result", py_agg_result, METH_VARARGS, "agg_result(agg) -> (count, hist, [(faults, count, size, best)])"},
    {NULL, NULL, 0, NULL},
};

static struct PyModuleDef moddef = {PyModuleDef_HEAD_INIT, "_core", "Native MSO/MTES search engine.", -1, methods,
                                    NULL, NULL, NULL, NULL};

PyMODINIT_FUNC PyInit__core(void) { return PyModule_Create(&moddef); }
