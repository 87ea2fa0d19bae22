/*
 * MSO / MTES search engine, instantiated once per bitset width (NW 64-bit words per equation set).
 * _core.c includes this file once per width of its ladder (NW = 1, 2, 3, 4, 5, 6, 8, 12, 16, ...); a model
 * runs on the narrowest instance that holds its equations, so small models keep one-word bitsets.
 *
 * Algorithm (Krysander, Aslund, Nyberg 2008, with lumping and no repeated removals):
 *   node = (S, R): S a proper structurally overdetermined (PSO) equation set with redundancy phi = |S| - |X(S)|,
 *   R the equations the subtree may still remove. phi == 1: S is an MSO set. Otherwise S is lumped into its
 *   equivalence classes [e] = S \ (S \ {e})+; every class E inside R gives one child (S \ E, R_E) where
 *   R_E is the union of the allowed classes after E. Every MSO set is reached exactly once.
 *
 * Classes without recomputing a DM decomposition per equation: keep a matching of S that covers all of
 * X(S) (phi equations stay free). Let G be the digraph u -> w when w holds the variable matched to u.
 * Two equations e, e' can be free together in some complete matching iff there are two vertex-disjoint
 * G-paths from {e, e'} to the free equations (alternating paths). So e ~ e' iff one equation v lies on every
 * path from e and from e' to the free set, i.e. iff e and e' have the same top dominator in G towards the
 * free set. The dominator sets are a bitset data-flow fixpoint:
 *     Dom(f) = {f} for free f,   Dom(u) = {u} U  AND_{u -> w} Dom(w),
 * reached by one pass in breadth-first order from the free equations (inside the search that finds them)
 * and a worklist of the equations that read a successor before it was computed or whose successor's set
 * shrank since (about 1.8 re-evaluations per equation on the full vertical-dynamics model; its count took
 * 15% less time than with repeated full passes; a Cooper-Harvey-Kennedy immediate-dominator iteration and
 * reverse-postorder or breadth-first worklist orders were all slower there).
 * A class is {u : c in Dom(u)} for a root c with Dom(c) = {c}. The child matching is the parent matching
 * minus the class (all class variables except possibly the root's disappear with it) and, when the root is
 * matched, one augmenting path from the root to a free equation (it exists and avoids the class).
 * Cost per node: O(edges * NW) words, no allocation; children of redundancy-2 nodes are MSO sets and are
 * reported without being visited.
 *
 * Dead subtrees (MSO mode). The subtree of node (S, R) holds exactly the MSO sets M of S with S \ M inside R,
 * so every one of them holds T = S \ R, and also every class of S that is not inside R (S \ M is a union
 * of classes of S). A proper subset of an MSO set is matchable (structural redundancy 0), so the subtree is
 * empty unless T is matchable or T itself is an MSO set (then it is the subtree's only result). Along the
 * children of a node T only grows (child i keeps the allowed classes before i), so each frame keeps a
 * maximum matching of T and extends it by one augmenting path per added equation (Kuhn); the first
 * class that makes T unmatchable ends the frame. Without this test the search visits subtrees that
 * cannot hold an MSO set, and their share grows with the model: 97% of the nodes on a 150-equation
 * structure of redundancy 10 (140 nodes per MSO set), against 1-3 nodes per MSO set on small models.
 */

#define F_(name) CAT(name, NW)
#define BS F_(bs)

typedef struct {
    w64 w[NW];
} BS;

static inline BS F_(bs_load)(const w64 *p) {
    BS r;
    for (int k = 0; k < NW; k++) r.w[k] = p[k];
    return r;
}
static inline void F_(bs_store)(w64 *p, BS a) {
    for (int k = 0; k < NW; k++) p[k] = a.w[k];
}
static inline BS F_(bs_zero)(void) {
    BS r;
    for (int k = 0; k < NW; k++) r.w[k] = 0;
    return r;
}
static inline BS F_(bs_and)(BS a, BS b) {
    for (int k = 0; k < NW; k++) a.w[k] &= b.w[k];
    return a;
}
static inline BS F_(bs_or)(BS a, BS b) {
    for (int k = 0; k < NW; k++) a.w[k] |= b.w[k];
    return a;
}
static inline BS F_(bs_andnot)(BS a, BS b) {
    for (int k = 0; k < NW; k++) a.w[k] &= ~b.w[k];
    return a;
}
static inline int F_(bs_empty)(BS a) {
    w64 x = 0;
    for (int k = 0; k < NW; k++) x |= a.w[k];
    return x == 0;
}
static inline int F_(bs_equal)(BS a, BS b) {
    w64 x = 0;
    for (int k = 0; k < NW; k++) x |= a.w[k] ^ b.w[k];
    return x == 0;
}
static inline int F_(bs_subset)(BS a, BS b) {
    w64 x = 0;
    for (int k = 0; k < NW; k++) x |= a.w[k] & ~b.w[k];
    return x == 0;
}
static inline int F_(bs_count)(BS a) {
    int n = 0;
    for (int k = 0; k < NW; k++) n += __builtin_popcountll(a.w[k]);
    return n;
}
static inline int F_(bs_has)(BS a, int i) { return (int)((a.w[i >> 6] >> (i & 63)) & 1u); }
static inline void F_(bs_set)(BS *a, int i) { a->w[i >> 6] |= (w64)1 << (i & 63); }
static inline void F_(bs_clr)(BS *a, int i) { a->w[i >> 6] &= ~((w64)1 << (i & 63)); }
static inline int F_(bs_first)(BS a) {
    for (int k = 0; k < NW; k++)
        if (a.w[k]) return k * 64 + __builtin_ctzll(a.w[k]);
    return -1;
}
static inline BS F_(bs_single)(int i) {
    BS r = F_(bs_zero)();
    F_(bs_set)(&r, i);
    return r;
}
/* The column (equation set) of variable x. */
static inline BS F_(col)(const model_t *m, int x) { return F_(bs_load)(m->col + (size_t)x * NW); }

static inline w64 F_(faults_of)(const model_t *m, BS s) {
    w64 f = 0;
    BS_FOREACH(s, NW, e) { f |= m->eqfault[e]; }
    return f;
}

/* ---- search frames --------------------------------------------------------------------------------- */
typedef struct {
    BS S, F;       /* equations, free equations of the matching */
    BS allowed;    /* union of the allowed classes (also those cut by the count pruning) */
    BS T;          /* MSO mode, phi >= 3: equations every MSO set of the remaining children holds */
    int phi;       /* redundancy = |F| */
    int ncls;      /* allowed classes */
    int next;      /* next class to expand */
    int nfaultcls; /* classes holding a faulty equation (MTES) */
    int tdead;     /* T is no longer matchable: the remaining children hold no MSO set */
    int16_t *eqvar; /* ne: variable matched to equation or -1 */
    int16_t *vareq; /* nv: equation matched to variable or -1 */
    int16_t *teq;   /* ne: variable matched to equation in the matching of T, or -1 */
    int16_t *tvar;  /* nv: equation matched to variable in the matching of T, or -1 */
    BS *cls;        /* ne: allowed classes */
    BS *rsuf;       /* ne: union of the allowed classes after i */
    w64 *csig;      /* ne: faults of S \ cls[i] (redundancy-2 nodes) */
    int16_t *croot; /* ne: root equation of class i */
} F_(frame);

typedef struct {
    const model_t *m;
    int mode;     /* 0 MSO, 1 MTES (only faulty classes removable; stop at one faulty class) */
    int emit_all; /* MTES mode: report every visited node (all TES), not only the minimal ones */
    int depth;    /* top frame, -1 when finished */
    int nframes;
    int error;
    F_(frame) *fr;
    BS *dom;         /* ne scratch */
    BS *allcls;      /* ne scratch */
    w64 *allf;       /* ne scratch */
    w64 *pre;        /* ne + 1 scratch */
    int16_t *queue;  /* ne scratch */
    int16_t *parent; /* ne scratch */
    int16_t *cidx;   /* ne scratch: class index of a root equation */
    int16_t *match_vis; /* ne scratch */
    int16_t *tq;        /* ne scratch: augmenting path search in T */
    int16_t *tpred;     /* ne scratch */
    BS faulty;
    BS pending;      /* a root that is itself a result (phi == 1 or MTES) */
    int has_pending;
    void *mem;
} F_(iter);

static void F_(iter_free)(F_(iter) *it) {
    if (it) {
        free(it->mem);
        free(it);
    }
}

static F_(iter) *F_(iter_alloc)(const model_t *m, int nframes) {
    const size_t ne = (size_t)m->ne, nv = (size_t)m->nv;
    F_(iter) *it = (F_(iter) *)calloc(1, sizeof(F_(iter)));
    if (!it) return NULL;
    /* one block: BS arrays first (alignment), then w64, then int16 */
    size_t nbs = ne * 2 + (size_t)nframes * ne * 2;
    size_t nw64 = ne + (ne + 1) + (size_t)nframes * ne;
    size_t ni16 = ne * 6 + nv + (size_t)nframes * (ne * 3 + nv * 2);
    size_t bytes = nbs * sizeof(BS) + nw64 * sizeof(w64) + ni16 * sizeof(int16_t) + (size_t)nframes * sizeof(F_(frame)) + 64;
    char *p = (char *)calloc(1, bytes);
    if (!p) {
        free(it);
        return NULL;
    }
    it->mem = p;
    it->m = m;
    it->nframes = nframes;
    it->fr = (F_(frame) *)p;
    p += (size_t)nframes * sizeof(F_(frame));
    p += (8 - ((uintptr_t)p & 7)) & 7;
    BS *b = (BS *)p;
    it->dom = b; b += ne;
    it->allcls = b; b += ne;
    for (int d = 0; d < nframes; d++) {
        it->fr[d].cls = b; b += ne;
        it->fr[d].rsuf = b; b += ne;
    }
    w64 *q = (w64 *)b;
    it->allf = q; q += ne;
    it->pre = q; q += ne + 1;
    for (int d = 0; d < nframes; d++) {
        it->fr[d].csig = q; q += ne;
    }
    int16_t *s = (int16_t *)q;
    it->queue = s; s += ne;
    it->parent = s; s += ne;
    it->cidx = s; s += ne;
    it->match_vis = s; s += ne;
    it->tq = s; s += ne;
    it->tpred = s; s += ne;
    s += nv; /* spare */
    for (int d = 0; d < nframes; d++) {
        it->fr[d].eqvar = s; s += ne;
        it->fr[d].croot = s; s += ne;
        it->fr[d].teq = s; s += ne;
        it->fr[d].vareq = s; s += nv;
        it->fr[d].tvar = s; s += nv;
    }
    it->faulty = F_(bs_zero)();
    for (int e = 0; e < m->ne; e++)
        if (m->eqfault[e]) F_(bs_set)(&it->faulty, e);
    it->depth = -1;
    return it;
}

/* Kuhn augmenting path from variable x inside S (recursion depth <= number of variables). */
static int F_(augment)(const model_t *m, BS S, int x, int16_t *eqvar, int16_t *vareq, int16_t *vis, int stamp) {
    BS c = F_(bs_and)(F_(col)(m, x), S);
    BS_FOREACH(c, NW, e) {
        if (vis[e] != stamp) {
            vis[e] = (int16_t)stamp;
            if (eqvar[e] < 0 || F_(augment)(m, S, eqvar[e], eqvar, vareq, vis, stamp)) {
                eqvar[e] = (int16_t)x;
                vareq[x] = (int16_t)e;
                return 1;
            }
        }
    }
    return 0;
}

/* Maximum matching of S; returns the overdetermined part S+ and fills the matching arrays. */
static BS F_(mplus_match)(const model_t *m, BS S, int16_t *eqvar, int16_t *vareq, int16_t *queue, int16_t *vis) {
    for (int e = 0; e < m->ne; e++) {
        eqvar[e] = -1;
        vis[e] = -1;
    }
    for (int x = 0; x < m->nv; x++) vareq[x] = -1;
    /* variables of S; the search from variable x marks visited equations with stamp x (no reset) */
    BS_FOREACH(S, NW, e0) {
        for (int k = m->row_off[e0]; k < m->row_off[e0 + 1]; k++) {
            int x = m->row_var[k];
            if (vareq[x] == -1) {
                vareq[x] = -2; /* mark as attempted */
                if (!F_(augment)(m, S, x, eqvar, vareq, vis, x)) vareq[x] = -3; /* unmatched variable */
            }
        }
    }
    for (int x = 0; x < m->nv; x++)
        if (vareq[x] < -1) vareq[x] = -1;
    /* S+ = equations reachable from free equations by alternating paths */
    BS reach = F_(bs_zero)();
    int n = 0;
    BS_FOREACH(S, NW, e1) {
        if (eqvar[e1] < 0) {
            F_(bs_set)(&reach, e1);
            queue[n++] = (int16_t)e1;
        }
    }
    for (int h = 0; h < n; h++) {
        int w = queue[h];
        for (int k = m->row_off[w]; k < m->row_off[w + 1]; k++) {
            int u = vareq[m->row_var[k]];
            if (u >= 0 && !F_(bs_has)(reach, u)) {
                F_(bs_set)(&reach, u);
                queue[n++] = (int16_t)u;
            }
        }
    }
    return reach;
}

/* The successors of equation u in G inside S (u -> w when w holds the variable matched to u), and the meet
 * {u} U AND Dom(w) over the successors in `succ` (S, the top of the lattice, when there is none). Forced inline:
 * left to gcc -O3, the quasi-static count took 2 % longer on one core than with the lines written out. */
static inline __attribute__((always_inline)) BS F_(succ_of)(const model_t *m, const F_(frame) *fr, BS S, int u) {
    BS succ = F_(bs_and)(F_(col)(m, fr->eqvar[u]), S);
    F_(bs_clr)(&succ, u);
    return succ;
}
static inline __attribute__((always_inline)) BS F_(meet)(const BS *dom, BS S, BS succ, int u) {
    BS d = S;
    BS_FOREACH(succ, NW, x) { d = F_(bs_and)(d, dom[x]); }
    F_(bs_set)(&d, u);
    return d;
}

/* Equivalence classes of the PSO node fr; keeps the classes inside R (and, MTES, holding a fault). */
static void F_(classes)(F_(iter) *it, F_(frame) *fr, BS R) {
    const model_t *m = it->m;
    const BS S = fr->S, F = fr->F;
    BS *dom = it->dom;
    int16_t *queue = it->queue;
    BS vis = F;
    int n = 0;
    BS_FOREACH(F, NW, f) {
        queue[n++] = (int16_t)f;
        dom[f] = F_(bs_single)(f);
    }
    /* Breadth-first from the free equations along u -> w reversed; each equation's set is computed when it
     * leaves the queue, from the successors already computed (those earlier in the queue; one not yet
     * computed stands for S, the top of the lattice); then a worklist: an equation is recomputed when it
     * read a successor before that was computed, or when the set of one of its successors shrank since. */
    BS done = F, stale = F_(bs_zero)();
    for (int h = 0; h < n; h++) {
        const int w = queue[h];
        if (h >= fr->phi) {
            const BS succ = F_(succ_of)(m, fr, S, w);
            dom[w] = F_(meet)(dom, S, F_(bs_and)(succ, done), w);
            if (!F_(bs_subset)(succ, done)) F_(bs_set)(&stale, w);
            F_(bs_set)(&done, w);
        }
        for (int k = m->row_off[w]; k < m->row_off[w + 1]; k++) {
            int u = fr->vareq[m->row_var[k]];
            if (u >= 0 && !F_(bs_has)(vis, u)) {
                F_(bs_set)(&vis, u);
                queue[n++] = (int16_t)u;
            }
        }
    }
    while (!F_(bs_empty)(stale)) {
        const int u = F_(bs_first)(stale);
        F_(bs_clr)(&stale, u);
        const BS d = F_(meet)(dom, S, F_(succ_of)(m, fr, S, u), u);
        if (F_(bs_equal)(d, dom[u])) continue;
        dom[u] = d;
        for (int k = m->row_off[u]; k < m->row_off[u + 1]; k++) { /* equations that read u */
            const int v = fr->vareq[m->row_var[k]];
            if (v >= 0 && v != u) F_(bs_set)(&stale, v);
        }
    }
    /* roots and classes */
    BS roots = F_(bs_zero)();
    int nc = 0;
    for (int h = 0; h < n; h++) {
        int u = queue[h];
        if (F_(bs_count)(dom[u]) == 1) {
            F_(bs_set)(&roots, u);
            it->cidx[u] = (int16_t)nc;
            it->allcls[nc] = F_(bs_zero)();
            it->allf[nc] = 0;
            nc++;
        }
    }
    for (int h = 0; h < n; h++) {
        int u = queue[h];
        int c = F_(bs_first)(F_(bs_and)(dom[u], roots));
        int j = it->cidx[c];
        F_(bs_set)(&it->allcls[j], u);
        it->allf[j] |= m->eqfault[u];
    }
    if (n != F_(bs_count)(S)) it->error = 1; /* not PSO: cannot happen for nodes built here */
    /* allowed classes, in root order of discovery */
    int na = 0, nfc = 0;
    for (int j = 0; j < nc; j++) {
        const BS c = it->allcls[j];
        const int isfaulty = it->allf[j] != 0 || !F_(bs_empty)(F_(bs_and)(c, it->faulty));
        nfc += isfaulty;
        if (it->mode == 0 && !F_(bs_subset)(c, R)) continue;
        /* MTES: only faulty classes are removed; R holds the faulty equations still removable */
        if (it->mode == 1 && (!isfaulty || !F_(bs_subset)(F_(bs_and)(c, it->faulty), R))) continue;
        fr->cls[na] = c;
        fr->croot[na] = (int16_t)F_(bs_first)(F_(bs_and)(c, roots));
        it->cidx[na] = (int16_t)j; /* reuse: allowed -> class index (roots no longer needed) */
        na++;
    }
    fr->ncls = na;
    fr->nfaultcls = nfc;
    fr->next = 0;
    BS acc = F_(bs_zero)();
    for (int i = na - 1; i >= 0; i--) {
        fr->rsuf[i] = acc;
        acc = F_(bs_or)(acc, fr->cls[i]);
    }
    fr->allowed = acc;
    /* MSO mode pruning (exact): below a node of redundancy phi an MSO set needs phi - 1 more removals, each
     * a union of allowed classes of this node lying inside R. Child i only keeps the classes after i, so it
     * can reach an MSO set only if at least phi - 2 allowed classes follow it. */
    if (it->mode == 0 && fr->phi > 2) fr->ncls = na - (fr->phi - 2) > 0 ? na - (fr->phi - 2) : 0;
    if (it->mode == 0 && fr->phi == 2) {
        w64 *pre = it->pre;
        pre[0] = 0;
        for (int j = 0; j < nc; j++) pre[j + 1] = pre[j] | it->allf[j];
        w64 suf = 0;
        int i = na - 1;
        for (int j = nc - 1; j >= 0; j--) {
            if (i >= 0 && it->cidx[i] == j) {
                fr->csig[i] = pre[j] | suf;
                i--;
            }
            suf |= it->allf[j];
        }
    }
}

/* One augmenting path for equation e in the matching of T (breadth first, inside T's matched equations). */
static int F_(taugment)(F_(iter) *it, F_(frame) *fr, int e) {
    const model_t *m = it->m;
    int16_t *q = it->tq, *pred = it->tpred;
    BS vis = F_(bs_single)(e);
    int n = 0;
    q[n++] = (int16_t)e;
    for (int h = 0; h < n; h++) {
        const int u = q[h];
        for (int k = m->row_off[u]; k < m->row_off[u + 1]; k++) {
            const int x = m->row_var[k];
            const int w = fr->tvar[x];
            if (w < 0) { /* free variable: flip the path u, pred[u], ..., e */
                int cur = u, xn = x;
                for (;;) {
                    const int old = fr->teq[cur];
                    fr->teq[cur] = (int16_t)xn;
                    fr->tvar[xn] = (int16_t)cur;
                    if (cur == e) return 1;
                    xn = old;
                    cur = pred[cur];
                }
            }
            if (!F_(bs_has)(vis, w)) {
                F_(bs_set)(&vis, w);
                pred[w] = (int16_t)u;
                q[n++] = (int16_t)w;
            }
        }
    }
    return 0;
}

/* Adds `add` to T and extends T's maximum matching: T_MATCHABLE while every equation of T is matched,
 * T_IS_MSO when exactly one is not and T is its own overdetermined part, T_DEAD otherwise. */
static int F_(tgrow)(F_(iter) *it, F_(frame) *fr, BS add) {
    const model_t *m = it->m;
    int failed = -1, nfailed = 0;
    fr->T = F_(bs_or)(fr->T, add);
    BS_FOREACH(add, NW, e) {
        if (nfailed < 2 && !F_(taugment)(it, fr, e)) {
            failed = e;
            nfailed++;
        }
    }
    if (nfailed == 0) return T_MATCHABLE;
    if (nfailed > 1) return T_DEAD;
    /* redundancy 1: an MSO set iff every equation of T is reached from the free one by alternating paths */
    int16_t *q = it->tq;
    BS reach = F_(bs_single)(failed);
    int n = 0;
    q[n++] = (int16_t)failed;
    for (int h = 0; h < n; h++) {
        const int w = q[h];
        for (int k = m->row_off[w]; k < m->row_off[w + 1]; k++) {
            const int u = fr->tvar[m->row_var[k]];
            if (u >= 0 && !F_(bs_has)(reach, u)) {
                F_(bs_set)(&reach, u);
                q[n++] = (int16_t)u;
            }
        }
    }
    return F_(bs_equal)(reach, fr->T) ? T_IS_MSO : T_DEAD;
}

/* Child i of frame p into frame c: S \ cls[i] with the matching repaired (and, MSO mode with redundancy
 * >= 2 left, the matching of T copied). Returns 0 on success. */
static int F_(make_child)(F_(iter) *it, const F_(frame) *p, int i, F_(frame) *c) {
    const model_t *m = it->m;
    const BS E = p->cls[i];
    const int r = p->croot[i];
    c->S = F_(bs_andnot)(p->S, E);
    c->phi = p->phi - 1;
    c->tdead = 0;
    memcpy(c->eqvar, p->eqvar, (size_t)m->ne * sizeof(int16_t));
    memcpy(c->vareq, p->vareq, (size_t)m->nv * sizeof(int16_t));
    if (it->mode == 0 && c->phi >= 3) {
        c->T = p->T;
        memcpy(c->teq, p->teq, (size_t)m->ne * sizeof(int16_t));
        memcpy(c->tvar, p->tvar, (size_t)m->nv * sizeof(int16_t));
    }
    BS_FOREACH(E, NW, u) {
        if (u != r && c->eqvar[u] >= 0) {
            c->vareq[c->eqvar[u]] = -1;
            c->eqvar[u] = -1;
        }
    }
    if (F_(bs_has)(p->F, r)) {
        c->F = p->F;
        F_(bs_clr)(&c->F, r);
        return 0;
    }
    /* augmenting path r -> ... -> free equation inside c->S */
    int16_t *queue = it->queue, *parent = it->parent;
    BS vis = F_(bs_single)(r);
    int n = 0, found = -1;
    queue[n++] = (int16_t)r;
    for (int h = 0; h < n && found < 0; h++) {
        int u = queue[h];
        BS cand = F_(bs_andnot)(F_(bs_and)(F_(col)(m, c->eqvar[u]), c->S), vis);
        BS_FOREACH(cand, NW, w) {
            if (found < 0) {
                parent[w] = (int16_t)u;
                F_(bs_set)(&vis, w);
                if (F_(bs_has)(p->F, w))
                    found = w;
                else
                    queue[n++] = (int16_t)w;
            }
        }
    }
    if (found < 0) {
        it->error = 2;
        return -1;
    }
    int w = found;
    while (w != r) {
        int u = parent[w];
        int x = c->eqvar[u];
        c->vareq[x] = (int16_t)w;
        c->eqvar[w] = (int16_t)x;
        w = u;
    }
    c->eqvar[r] = -1;
    c->F = p->F;
    F_(bs_clr)(&c->F, found);
    return 0;
}

/* Start a search at node (S, R). S must be PSO (S == S+); returns phi, or -1 if S is not PSO. */
static int F_(iter_start)(F_(iter) *it, BS S, BS R) {
    const model_t *m = it->m;
    F_(frame) *fr = &it->fr[0];
    BS sp = F_(mplus_match)(m, S, fr->eqvar, fr->vareq, it->queue, it->match_vis);
    it->depth = -1;
    it->has_pending = 0;
    if (F_(bs_empty)(S) || !F_(bs_equal)(sp, S)) return -1;
    fr->S = S;
    fr->F = F_(bs_zero)();
    fr->tdead = 0;
    BS_FOREACH(S, NW, e) {
        if (fr->eqvar[e] < 0) F_(bs_set)(&fr->F, e);
    }
    fr->phi = F_(bs_count)(fr->F);
    if (fr->phi + 1 > it->nframes) {
        it->error = 3;
        return -1;
    }
    if (it->mode == 0) {
        if (fr->phi == 1) {
            it->pending = S;
            it->has_pending = 1;
            return 1;
        }
        F_(classes)(it, fr, R);
        if (fr->phi >= 3) {
            for (int e = 0; e < m->ne; e++) fr->teq[e] = -1;
            for (int x = 0; x < m->nv; x++) fr->tvar[x] = -1;
            fr->T = F_(bs_zero)();
            const int t = F_(tgrow)(it, fr, F_(bs_andnot)(S, fr->allowed));
            if (t == T_IS_MSO) {
                it->pending = fr->T;
                it->has_pending = 1;
            }
            if (t != T_MATCHABLE) return fr->phi;
        }
        it->depth = 0;
    } else {
        F_(classes)(it, fr, R);
        if (fr->nfaultcls == 0) return fr->phi; /* nothing to test */
        if (fr->nfaultcls == 1 || it->emit_all) {
            it->pending = S;
            it->has_pending = 1;
        }
        if (fr->nfaultcls > 1) it->depth = 0;
    }
    return fr->phi;
}

typedef struct {
    agg_t *agg;      /* aggregate here, or */
    w64 *buf;        /* write NW words per result here */
    w64 *sigbuf;     /* and optionally its fault mask here */
    size_t n, cap;   /* results written to buf (cap includes slack for one node) */
    int check_signals;
    int interrupted;
} F_(sink);

static inline void F_(emit)(F_(sink) *sk, BS S, int size, w64 sig) {
    if (sk->agg) {
        agg_add(sk->agg, S.w, NW, size, sig);
    } else {
        for (int k = 0; k < NW; k++) sk->buf[sk->n * NW + (size_t)k] = S.w[k];
        if (sk->sigbuf) sk->sigbuf[sk->n] = sig;
        sk->n++;
    }
}

/* Run until the search is finished (returns 1), `limit` results were written to buf (0), or interrupted (-1). */
static int F_(iter_run)(F_(iter) *it, F_(sink) *sk, size_t limit) {
    const model_t *m = it->m;
    unsigned long work = 0, next_check = 1ul << 14; /* nodes + reported sets since the start */
    if (it->has_pending) {
        it->has_pending = 0;
        F_(emit)(sk, it->pending, F_(bs_count)(it->pending), F_(faults_of)(m, it->pending));
    }
    while (it->depth >= 0) {
        if (!sk->agg && sk->n >= limit) return 0;
        F_(frame) *fr = &it->fr[it->depth];
        work += 1u + (unsigned long)fr->ncls;
        if (sk->check_signals && work >= next_check) {
            next_check = work + (1ul << 14);
            if (PyErr_CheckSignals() != 0) {
                sk->interrupted = 1;
                return -1;
            }
        }
        if (it->mode == 0 && fr->phi == 2) {
            const int sz = F_(bs_count)(fr->S);
            for (int i = fr->next; i < fr->ncls; i++)
                F_(emit)(sk, F_(bs_andnot)(fr->S, fr->cls[i]), sz - F_(bs_count)(fr->cls[i]), fr->csig[i]);
            it->depth--;
            continue;
        }
        if (fr->next >= fr->ncls || fr->tdead) {
            it->depth--;
            continue;
        }
        const int i = fr->next++;
        if (it->mode == 0 && F_(bs_empty)(fr->rsuf[i])) continue; /* child could remove nothing */
        F_(frame) *ch = &it->fr[it->depth + 1];
        if (F_(make_child)(it, fr, i, ch) != 0) return -1;
        if (it->mode == 0 && i + 1 < fr->ncls) {
            /* T of the next child: T of this one plus its class (this child copied T before) */
            const int t = F_(tgrow)(it, fr, fr->cls[i]);
            if (t != T_MATCHABLE) fr->tdead = 1;
            if (t == T_IS_MSO) F_(emit)(sk, fr->T, F_(bs_count)(fr->T), F_(faults_of)(m, fr->T));
        }
        F_(classes)(it, ch, fr->rsuf[i]);
        if (it->error) return -1;
        if (it->mode == 0) {
            if (ch->ncls == 0) continue;
            if (ch->phi >= 3) {
                const int t = F_(tgrow)(it, ch, F_(bs_andnot)(F_(bs_andnot)(ch->S, ch->allowed), ch->T));
                if (t == T_IS_MSO) F_(emit)(sk, ch->T, F_(bs_count)(ch->T), F_(faults_of)(m, ch->T));
                if (t != T_MATCHABLE) continue;
            }
            it->depth++;
        } else {
            if (ch->nfaultcls == 1 || it->emit_all) F_(emit)(sk, ch->S, F_(bs_count)(ch->S), F_(faults_of)(m, ch->S));
            if (ch->nfaultcls > 1) it->depth++;
        }
    }
    return 1;
}

/* Children of node (S, R) for splitting the search: writes up to ne pairs (child S, child R) of NW words each. */
static int F_(split)(F_(iter) *it, BS S, BS R, w64 *out, int *nout) {
    *nout = 0;
    int phi = F_(iter_start)(it, S, R);
    if (phi < 0) return -1;
    if (phi == 1) return 1;
    F_(frame) *fr = &it->fr[0];
    for (int i = 0; i < fr->ncls; i++) {
        if (fr->phi > 2 && F_(bs_empty)(fr->rsuf[i])) continue;
        BS c = F_(bs_andnot)(fr->S, fr->cls[i]);
        for (int k = 0; k < NW; k++) {
            out[(size_t)(*nout) * 2 * NW + (size_t)k] = c.w[k];
            out[(size_t)(*nout) * 2 * NW + NW + (size_t)k] = fr->rsuf[i].w[k];
        }
        (*nout)++;
    }
    it->depth = -1;
    return phi;
}

static int F_(mplus)(const model_t *m, const w64 *sin, w64 *sout) {
    size_t ne = (size_t)m->ne, nv = (size_t)m->nv;
    int16_t *tmp = (int16_t *)malloc((ne * 3 + nv + 1) * sizeof(int16_t));
    if (!tmp) return -1;
    BS r = F_(mplus_match)(m, F_(bs_load)(sin), tmp, tmp + ne, tmp + ne + nv, tmp + 2 * ne + nv);
    F_(bs_store)(sout, r);
    free(tmp);
    return 0;
}

/* ---- the width-independent entry points (engine_t) ---- */
static void *F_(e_alloc)(const model_t *m, int nframes) { return F_(iter_alloc)(m, nframes); }
static void F_(e_free)(void *it) { F_(iter_free)((F_(iter) *)it); }
static int F_(e_start)(void *p, const w64 *s, const w64 *r, int mode, int emit_all) {
    F_(iter) *it = (F_(iter) *)p;
    it->mode = mode;
    it->emit_all = emit_all;
    return F_(iter_start)(it, F_(bs_load)(s), F_(bs_load)(r));
}
static int F_(e_run)(void *it, agg_t *agg, w64 *buf, w64 *sigbuf, size_t *n, size_t limit, int check, int *interrupted) {
    F_(sink) sk = {agg, buf, sigbuf, 0, 0, check, 0};
    const int rc = F_(iter_run)((F_(iter) *)it, &sk, limit);
    *n = sk.n;
    *interrupted = sk.interrupted;
    return rc;
}
static int F_(e_error)(void *it) { return ((F_(iter) *)it)->error; }
static int F_(e_split)(void *it, const w64 *s, const w64 *r, w64 *out, int *nout) {
    return F_(split)((F_(iter) *)it, F_(bs_load)(s), F_(bs_load)(r), out, nout);
}
static const engine_t F_(engine) = {NW, F_(e_alloc), F_(e_free), F_(e_start), F_(e_run), F_(e_error), F_(e_split), F_(mplus)};

#undef BS
#undef F_
