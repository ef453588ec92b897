/* Banded KKT method: the Newton systems of stage-structured problems by three exact, small
 * dense reductions (cone rows, variable groups, equality rows); the math is in
 * socp_internal.h.
 *
 * Setup (tscvx_banded_analyse) finds the variable groups, the border, a reverse Cuthill-McKee
 * order of the equality rows and the profile of Y. Each IPM iteration (banded_factor):
 *   L_g' = R_g from Givens rotations of the rows of sqrt(d) I, P_gg's factor and
 *          W_c^-1 G_c over the group's cones: H_g = R_g'R_g without forming H_g (forming it
 *          would square the conditioning of W^-1 G, which passes 1e8 near a solution)
 *   C_g' = (L_g^-1 A_g')'
 *   Y    = d I + sum_g C_g' C_g  = L_Y L_Y'   (profile Cholesky)
 *   S    = H_B + A_B' Y^-1 A_B   (border, dense Cholesky)
 * Each solve (base_solve) runs them backwards, the cone rows NT-scaled as in CVXOPT's
 * condensed solver; iterative refinement on the unregularized system follows (as in the sparse
 * method).
 */
#include <limits.h>
#include <math.h>

#include "socp_internal.h"

/* ---- small dense kernels ----------------------------------------------------------------- */

/* Numerically zero pivots. A pivot d <= DYN_EPS a_jj has lost all but the last few digits of
 * its diagonal entry to cancellation: the column is numerically dependent on the earlier ones
 * (H_g or Y of an infeasible problem's diverging scaling; a singular P_gg). Dynamic
 * regularization, as QDLDL and Clarabel do, replaces it by DYN_DELTA a_jj and leaves the
 * difference to the refinement; the semidefinite factor of P_gg drops the column instead
 * (P_gg = F'F exactly, F with a zero row). A non-finite pivot is a failure.
 * Only an indefinite P_gg leaves a dropped column away from zero: a semidefinite one has
 * |S_ij| <= sqrt(S_ii S_jj), at most sqrt(DYN_EPS) |P|_max below a dropped pivot
 * S_jj <= DYN_EPS a_jj (entries allowed SEMIDEF_TOL |P|_max), and the pivot itself only
 * rounding below zero (allowed SEMIDEF_PIVOT_TOL |P|_max: the sparse method's check, which
 * factors P + 1e-9 |P|_max I, draws the same line). */
#define DYN_EPS 1e-13
#define DYN_DELTA 1e-7
#define SEMIDEF_TOL 1e-5
#define SEMIDEF_PIVOT_TOL 1e-9
enum { PIVOT_OK, PIVOT_DROP, PIVOT_FAIL };

static int fix_pivot(tscvx_float *d, tscvx_float ajj, int semidefinite) {
    if (!isfinite(*d)) return PIVOT_FAIL;
    if (*d > DYN_EPS * fabs(ajj)) return PIVOT_OK;
    if (semidefinite) return PIVOT_DROP;
    *d = DYN_DELTA * fabs(ajj);
    return PIVOT_OK;
}

/* Entry (i, j), i >= j, of the Schur complement left after the first j columns of L:
 * M_ij - sum_{k<j} L_ik L_jk */
static inline tscvx_float schur_entry(const tscvx_float *M, tscvx_int s, tscvx_int i,
                                      tscvx_int j) {
    tscvx_float v = M[j * s + i];
    for (tscvx_int k = 0; k < j; k++) v -= M[k * s + i] * M[k * s + j];
    return v;
}

/* Cholesky L L' of the s x s column-major matrix whose lower part is in M (in place; entry
 * (i, k) at M[k s + i]); zero pivots as fix_pivot. `semidefinite`: a positive semidefinite
 * matrix of largest |entry| `scale` (P_gg), its zero pivots dropped. Returns -1 on a
 * non-finite pivot, or a dropped column that shows the semidefinite matrix indefinite. */
static int chol(tscvx_float *M, tscvx_int s, int semidefinite, tscvx_float scale) {
    for (tscvx_int j = 0; j < s; j++) {
        const tscvx_float ajj = M[j * s + j];
        tscvx_float d = schur_entry(M, s, j, j);
        const int fix = fix_pivot(&d, ajj, semidefinite);
        if (fix == PIVOT_FAIL) return -1;
        if (fix == PIVOT_DROP) { /* checked only here: the normal path costs nothing more */
            if (d < -SEMIDEF_PIVOT_TOL * scale) return -1;
            for (tscvx_int i = j + 1; i < s; i++)
                if (fabs(schur_entry(M, s, i, j)) > SEMIDEF_TOL * scale) return -1;
            for (tscvx_int i = j; i < s; i++) M[j * s + i] = 0.0;
            continue;
        }
        d = sqrt(d);
        M[j * s + j] = d;
        for (tscvx_int i = j + 1; i < s; i++) M[j * s + i] = schur_entry(M, s, i, j) / d;
    }
    return 0;
}

/* x := L^-1 x */
static void chol_lsolve(const tscvx_float *L, tscvx_int s, tscvx_float *x) {
    for (tscvx_int i = 0; i < s; i++) {
        tscvx_float v = x[i];
        for (tscvx_int k = 0; k < i; k++) v -= L[k * s + i] * x[k];
        x[i] = v / L[i * s + i];
    }
}

/* x := L'^-1 x (column i of L is contiguous: L(k, i) = L[i s + k]) */
static void chol_ltsolve(const tscvx_float *L, tscvx_int s, tscvx_float *x) {
    for (tscvx_int i = s - 1; i >= 0; i--) {
        const tscvx_float *Li = L + (size_t)i * s;
        const tscvx_float v = x[i] - tscvx_dot(Li + i + 1, x + i + 1, s - i - 1);
        x[i] = v / Li[i];
    }
}

/* ---- profile (envelope) Cholesky of Y ---------------------------------------------------- */

/* u'v with two partial sums (the profile's rows are 10-30 long: half the dependency chain) */
static inline tscvx_float dot2(const tscvx_float *restrict u, const tscvx_float *restrict v,
                               tscvx_int n) {
    tscvx_float d0 = 0.0, d1 = 0.0;
    tscvx_int i = 0;
    for (; i + 4 <= n; i += 4) {
        d0 += u[i] * v[i] + u[i + 2] * v[i + 2];
        d1 += u[i + 1] * v[i + 1] + u[i + 3] * v[i + 3];
    }
    for (; i < n; i++) d0 += u[i] * v[i];
    return d0 + d1;
}

/* Row i of the profile holds columns yfirst[i] .. i; row(i)[j] is entry (i, j). */
static tscvx_float *prow(const tscvx_banded *bd, tscvx_int i) {
    return bd->Y + bd->yp[i] - bd->yfirst[i];
}

/* (u'w, v'w): two rows against one, the loads of w shared */
static inline void dot_pair(const tscvx_float *restrict u, const tscvx_float *restrict v,
                            const tscvx_float *restrict w, tscvx_int n, tscvx_float *uw,
                            tscvx_float *vw) {
    tscvx_float a0 = 0.0, a1 = 0.0, b0 = 0.0, b1 = 0.0;
    tscvx_int k = 0;
    for (; k + 2 <= n; k += 2) {
        const tscvx_float w0 = w[k], w1 = w[k + 1];
        a0 += u[k] * w0, b0 += v[k] * w0;
        a1 += u[k + 1] * w1, b1 += v[k + 1] * w1;
    }
    if (k < n) a0 += u[k] * w[k], b0 += v[k] * w[k];
    *uw = a0 + a1, *vw = b0 + b1;
}

/* The pivot of row i (entries yfirst[i] .. i-1 done): L_ii and 1 / L_ii. */
static int profile_pivot(tscvx_banded *bd, tscvx_int i) {
    tscvx_float *Li = prow(bd, i);
    const tscvx_int fi = bd->yfirst[i];
    tscvx_float d = Li[i] - dot2(Li + fi, Li + fi, i - fi);
    if (fix_pivot(&d, Li[i], 0) != PIVOT_OK) return -1;
    Li[i] = sqrt(d);
    bd->Ydinv[i] = 1.0 / Li[i];
    return 0;
}

/* Y = L L' in place, row by row (each entry one dot product of two contiguous row pieces);
 * two rows at a time where they start in the same column (the rows of one stage), sharing the
 * loads of the earlier row they are both reduced with. Zero pivots regularized (fix_pivot). */
static int profile_chol(tscvx_banded *bd, tscvx_int p) {
    const tscvx_float *dinv = bd->Ydinv;
    for (tscvx_int i = 0; i < p;) {
        tscvx_float *Li = prow(bd, i);
        const tscvx_int fi = bd->yfirst[i];
        const int pair = i + 1 < p && bd->yfirst[i + 1] == fi;
        tscvx_float *Lk = pair ? prow(bd, i + 1) : NULL;
        for (tscvx_int j = fi; j < i; j++) {
            const tscvx_float *Lj = prow(bd, j);
            const tscvx_int f = fi > bd->yfirst[j] ? fi : bd->yfirst[j];
            if (pair) {
                tscvx_float a, b;
                dot_pair(Li + f, Lk + f, Lj + f, j - f, &a, &b);
                Li[j] = (Li[j] - a) * dinv[j];
                Lk[j] = (Lk[j] - b) * dinv[j];
            } else {
                Li[j] = (Li[j] - dot2(Li + f, Lj + f, j - f)) * dinv[j];
            }
        }
        if (profile_pivot(bd, i) != 0) return -1;
        if (pair) { /* row i+1: column i, then its pivot */
            Lk[i] = (Lk[i] - dot2(Lk + fi, Li + fi, i - fi)) * dinv[i];
            if (profile_pivot(bd, i + 1) != 0) return -1;
        }
        i += pair ? 2 : 1;
    }
    return 0;
}

/* x := Y^-1 x = L'^-1 L^-1 x */
static void profile_solve(const tscvx_banded *bd, tscvx_int p, tscvx_float *x) {
    const tscvx_float *dinv = bd->Ydinv;
    for (tscvx_int i = 0; i < p; i++) {
        const tscvx_float *Li = prow(bd, i);
        const tscvx_int f = bd->yfirst[i];
        x[i] = (x[i] - dot2(Li + f, x + f, i - f)) * dinv[i];
    }
    /* L' x = y by columns of L' (rows of L), two rows at a time where they start together */
    for (tscvx_int i = p - 1; i >= 0;) {
        const tscvx_float *restrict Li = prow(bd, i);
        const tscvx_int f = bd->yfirst[i];
        tscvx_float *restrict xk = x;
        const tscvx_float xi = x[i] * dinv[i];
        x[i] = xi;
        if (i > 0 && bd->yfirst[i - 1] == f) {
            const tscvx_float *restrict Lh = prow(bd, i - 1);
            x[i - 1] -= Li[i - 1] * xi;
            const tscvx_float xh = x[i - 1] * dinv[i - 1];
            x[i - 1] = xh;
            for (tscvx_int k = f; k < i - 1; k++) xk[k] -= Li[k] * xi + Lh[k] * xh;
            i -= 2;
        } else {
            for (tscvx_int k = f; k < i; k++) xk[k] -= Li[k] * xi;
            i -= 1;
        }
    }
}

/* ---- the groups' small dense kernels ------------------------------------------------------
 * Each takes the group size s; the callers dispatch s = 1..4 (nearly every group of an
 * optimal-control problem) to calls with a constant s, whose inner loops (SMALL_LOOP) GCC
 * unrolls completely: the same operations in the same order, without the loop control.
 * KERNEL_INLINE makes sure a kernel is inlined where its size is a constant. */
#if defined(__GNUC__) && !defined(__clang__)
#define SMALL_LOOP _Pragma("GCC unroll 4")
#define KERNEL_INLINE __attribute__((always_inline))
#else
#define SMALL_LOOP
#define KERNEL_INLINE
#endif

/* A kernel called with s = 1..4 as a constant (call(S) expands the call). */
#define DISPATCH_S(s, call) \
    switch (s) {            \
    case 1: call(1); break; \
    case 2: call(2); break; \
    case 3: call(3); break; \
    case 4: call(4); break; \
    default: call(s);       \
    }

/* The same with the group size s and its equality part se both constants for the landing's
 * groups: se = s (states, thrust), and s = se + 1 (a virtual control and its epigraph
 * variable, which has no equality entries). */
#define DISPATCH_S_SE(s, se, call)   \
    switch ((s) * 8 + (se)) {        \
    case 1 * 8 + 1: call(1, 1); break; \
    case 2 * 8 + 2: call(2, 2); break; \
    case 3 * 8 + 3: call(3, 3); break; \
    case 4 * 8 + 4: call(4, 4); break; \
    case 2 * 8 + 1: call(2, 1); break; \
    case 3 * 8 + 2: call(3, 2); break; \
    case 4 * 8 + 3: call(4, 3); break; \
    default: call(s, se);            \
    }

/* C_g' (R x s, row-major) := (L^-1 C_g')': forward substitution on all R columns of C_g at
 * once, by columns of L (leading dimension ld; dinv: 1 / diagonal) */
static inline void group_ct(const tscvx_float *restrict L, tscvx_int ld,
                            const tscvx_float *restrict dinv, tscvx_int s,
                            tscvx_float *restrict CT, tscvx_int R) {
    for (tscvx_int a = 0; a < s; a++) {
        for (tscvx_int b = 0; b < a; b++) {
            const tscvx_float lab = L[b * ld + a];
            for (tscvx_int u = 0; u < R; u++) CT[u * s + a] -= lab * CT[u * s + b];
        }
        for (tscvx_int u = 0; u < R; u++) CT[u * s + a] *= dinv[a];
    }
}

/* Y[rows, rows] += C_g' C_g (lower part: rows ascending); two entries of a row per pass,
 * each summed in the same order as alone */
static inline void group_gram(const tscvx_banded *bd, const tscvx_int *restrict rows,
                              const tscvx_float *restrict CT, tscvx_int R, tscvx_int s) {
    for (tscvx_int u = 0; u < R; u++) {
        tscvx_float *restrict Yu = prow(bd, rows[u]);
        const tscvx_float *restrict cu = CT + (size_t)u * s;
        tscvx_int v = 0;
        for (; v + 1 <= u; v += 2) {
            const tscvx_float *restrict cv = CT + (size_t)v * s, *restrict cw = cv + s;
            tscvx_float acc = cu[0] * cv[0], acw = cu[0] * cw[0];
            SMALL_LOOP
            for (tscvx_int a = 1; a < s; a++) acc += cu[a] * cv[a], acw += cu[a] * cw[a];
            Yu[rows[v]] += acc;
            Yu[rows[v + 1]] += acw;
        }
        if (v == u) {
            const tscvx_float *restrict cv = CT + (size_t)v * s;
            tscvx_float acc = cu[0] * cv[0];
            SMALL_LOOP
            for (tscvx_int a = 1; a < s; a++) acc += cu[a] * cv[a];
            Yu[rows[v]] += acc;
        }
    }
}

/* w := L_g^-1 w (s); yb[rows] -= C_g' w over the last se variables (C_g's others are 0) */
static inline void group_forward(const tscvx_float *restrict L,
                                 const tscvx_float *restrict dinv, tscvx_int s, tscvx_int se,
                                 tscvx_float *restrict w, const tscvx_int *restrict rows,
                                 const tscvx_float *restrict CT, tscvx_int R,
                                 tscvx_float *restrict yb) {
    SMALL_LOOP
    for (tscvx_int i = 0; i < s; i++) {
        tscvx_float v = w[i];
        SMALL_LOOP
        for (tscvx_int k = 0; k < i; k++) v -= L[k * s + i] * w[k];
        w[i] = v * dinv[i];
    }
    const tscvx_float *we = w + (s - se);
    for (tscvx_int u = 0; u < R; u++) {
        const tscvx_float *cu = CT + (size_t)u * se;
        tscvx_float acc = cu[0] * we[0];
        SMALL_LOOP
        for (tscvx_int a = 1; a < se; a++) acc += cu[a] * we[a];
        yb[rows[u]] -= acc;
    }
}

/* w := L_g'^-1 (w - C_g dy[rows]) (C_g over the last se variables) */
static inline void group_backward(const tscvx_float *restrict L,
                                  const tscvx_float *restrict dinv, tscvx_int s, tscvx_int se,
                                  tscvx_float *restrict w, const tscvx_int *restrict rows,
                                  const tscvx_float *restrict CT, tscvx_int R,
                                  const tscvx_float *restrict dy) {
    tscvx_float *we = w + (s - se);
    for (tscvx_int u = 0; u < R; u++) {
        const tscvx_float yu = dy[rows[u]];
        const tscvx_float *cu = CT + (size_t)u * se;
        SMALL_LOOP
        for (tscvx_int a = 0; a < se; a++) we[a] -= cu[a] * yu;
    }
    SMALL_LOOP
    for (tscvx_int i = s - 1; i >= 0; i--) {
        tscvx_float v = w[i];
        SMALL_LOOP
        for (tscvx_int k = i + 1; k < s; k++) v -= L[i * s + k] * w[k];
        w[i] = v * dinv[i];
    }
}

/* ---- analysis ---------------------------------------------------------------------------- */

/* union-find with path halving; the root of a set is its smallest member */
static tscvx_int uf_root(tscvx_int *parent, tscvx_int i, tscvx_int n) {
    for (tscvx_int steps = 0; parent[i] != i && steps < n; steps++) {
        parent[i] = parent[parent[i]];
        i = parent[i];
    }
    return i;
}

static void uf_union(tscvx_int *parent, tscvx_int i, tscvx_int j, tscvx_int n) {
    const tscvx_int a = uf_root(parent, i, n), b = uf_root(parent, j, n);
    if (a < b) parent[b] = a;
    if (b < a) parent[a] = b;
}

/* The row graph of Y: rows r and c are adjacent when a non-border group couples both. */
typedef struct {
    const tscvx_banded *bd;
    const tscvx_int *rgp, *rgg; /* row -> its non-border groups */
} row_graph;

/* Breadth-first search from `root` over rows not yet ordered (its component); `seen` marks
 * visits with `stamp`. Fills queue[0 .. count); returns the depth, *last = the start of the
 * deepest level in the queue. */
static tscvx_int bfs(const row_graph *G, tscvx_int root, tscvx_int stamp, tscvx_int *seen,
                     tscvx_int *queue, tscvx_int *count, tscvx_int *last) {
    const tscvx_banded *bd = G->bd;
    tscvx_int head = 0, tail = 0, depth = 0, level_end = 1;
    queue[tail++] = root;
    seen[root] = stamp;
    *last = 0;
    while (head < tail) { /* each row enters once */
        if (head == level_end) depth++, *last = head, level_end = tail;
        const tscvx_int r = queue[head++];
        for (tscvx_int t = G->rgp[r]; t < G->rgp[r + 1]; t++) {
            const tscvx_int g = G->rgg[t];
            for (tscvx_int u = bd->rp[g]; u < bd->rp[g + 1]; u++) {
                const tscvx_int c = bd->rrow[u];
                if (seen[c] != stamp) seen[c] = stamp, queue[tail++] = c;
            }
        }
    }
    *count = tail;
    return depth;
}

/* Reverse Cuthill-McKee order of the rows (perm, iperm), each component from a
 * pseudo-peripheral row (George and Liu). deg: row degrees; temporaries seen, queue, order. */
static void rcm(const row_graph *G, tscvx_int p, const tscvx_int *deg, tscvx_int *seen,
                tscvx_int *queue, tscvx_int *order, tscvx_int *perm, tscvx_int *iperm) {
    tscvx_int stamp = 0, nord = 0;
    for (tscvx_int i = 0; i < p; i++) seen[i] = -1, iperm[i] = -1; /* iperm: -1 = unplaced */
    for (tscvx_int comp = 0; comp < p && nord < p; comp++) {
        tscvx_int root = -1;
        for (tscvx_int i = 0; i < p; i++)
            if (iperm[i] < 0 && (root < 0 || deg[i] < deg[root])) root = i;
        /* pseudo-peripheral: move to a least-degree row of the deepest level while the depth
         * grows (a handful of searches) */
        tscvx_int count, last, depth = bfs(G, root, stamp++, seen, queue, &count, &last);
        for (int tries = 0; tries < 8; tries++) {
            tscvx_int best = queue[last];
            for (tscvx_int u = last + 1; u < count; u++)
                if (deg[queue[u]] < deg[best]) best = queue[u];
            tscvx_int c2, l2;
            const tscvx_int d2 = bfs(G, best, stamp++, seen, queue, &c2, &l2);
            if (d2 <= depth) break;
            root = best, depth = d2;
        }
        /* Cuthill-McKee: breadth first, the new neighbours of each row by increasing degree */
        const tscvx_int start = nord;
        order[nord++] = root;
        iperm[root] = 0;
        for (tscvx_int head = start; head < nord; head++) {
            const tscvx_int r = order[head], first_new = nord;
            for (tscvx_int t = G->rgp[r]; t < G->rgp[r + 1]; t++) {
                const tscvx_int g = G->rgg[t];
                for (tscvx_int u = G->bd->rp[g]; u < G->bd->rp[g + 1]; u++) {
                    const tscvx_int c = G->bd->rrow[u];
                    if (iperm[c] < 0) iperm[c] = 0, order[nord++] = c;
                }
            }
            for (tscvx_int u = first_new + 1; u < nord; u++) { /* insertion sort by degree */
                const tscvx_int c = order[u];
                tscvx_int v = u;
                for (; v > first_new && deg[order[v - 1]] > deg[c]; v--) order[v] = order[v - 1];
                order[v] = c;
            }
        }
    }
    for (tscvx_int k = 0; k < p; k++) perm[k] = order[p - 1 - k];
    for (tscvx_int k = 0; k < p; k++) iperm[perm[k]] = k;
}

/* Sort v[0 .. len) ascending (the short row lists of one group). */
static void sort_ints(tscvx_int *v, tscvx_int len) {
    for (tscvx_int u = 1; u < len; u++) {
        const tscvx_int c = v[u];
        tscvx_int w = u;
        for (; w > 0 && v[w - 1] > c; w--) v[w] = v[w - 1];
        v[w] = c;
    }
}

/* Rows coupled to more than this many equality rows make a group a border group. */
static tscvx_int border_rows(tscvx_int p) { return p / 8 > 32 ? p / 8 : 32; }

/* Temporaries of the analysis (released after it). */
typedef struct {
    tscvx_int *parent, *gid; /* n: union-find forest, group of each variable */
    tscvx_int *Grc;          /* nnz(G): column of each entry of G by rows */
    tscvx_int *rgp, *rgg;    /* p+1, nnz(A): the non-border groups of each equality row */
    tscvx_int *deg, *seen, *queue, *order; /* p: row degrees, marks, RCM work */
} analysis_tmp;

/* First and one-past-last row of cone c (orthant rows first, then the SOCs). */
static void cone_rows(const tscvx_cones *K, tscvx_int c, tscvx_int *r0, tscvx_int *r1) {
    *r0 = c < K->l ? c : K->off[c - K->l];
    *r1 = c < K->l ? c + 1 : *r0 + K->q[c - K->l];
}

/* 1. G by rows: row i's entries Gr_k[Grp[i] .. Grp[i+1]), columns ascending (in Grc). */
static void rows_of_G(tscvx_workspace *ws, analysis_tmp *t) {
    tscvx_banded *bd = &ws->bd;
    const tscvx_int m = ws->m;
    tscvx_int *Grp = bd->Grp;
    for (tscvx_int i = 0; i <= m; i++) Grp[i] = 0;
    for (tscvx_int k = 0; k < ws->G.nnz; k++) Grp[ws->G.i[k] + 1]++;
    for (tscvx_int i = 0; i < m; i++) Grp[i + 1] += Grp[i];
    for (tscvx_int j = 0; j < ws->n; j++)
        for (tscvx_int k = ws->G.p[j]; k < ws->G.p[j + 1]; k++) {
            const tscvx_int e = Grp[ws->G.i[k]]++;
            bd->Gr_k[e] = k, t->Grc[e] = j;
        }
    for (tscvx_int i = m; i > 0; i--) Grp[i] = Grp[i - 1];
    Grp[0] = 0;
}

/* 2. The variable groups: connected components of "shares a cone or a P entry", each in group
 * order (variables without equality entries first: their rows of C_g = L_g^-1 A_g' are zero),
 * the cones of each group and its P flag. Returns 0, or -1 without the structure: a group
 * larger than TSCVX_BANDED_GROUP_MAX, or a variable in no cone and not on P's diagonal
 * (H_g would be only the regularization). */
static int find_groups(tscvx_workspace *ws, analysis_tmp *t) {
    tscvx_banded *bd = &ws->bd;
    const tscvx_cones *K = &ws->K;
    const tscvx_int n = ws->n, ncone = K->l + K->nsoc;
    tscvx_int *parent = t->parent, *gid = t->gid;
    for (tscvx_int j = 0; j < n; j++) {
        int covered = ws->G.p[j + 1] > ws->G.p[j];
        for (tscvx_int k = ws->P.p[j]; k < ws->P.p[j + 1]; k++) covered |= ws->P.i[k] == j;
        if (!covered) return -1;
        parent[j] = j;
    }
    for (tscvx_int c = 0; c < ncone; c++) {
        tscvx_int r0, r1;
        cone_rows(K, c, &r0, &r1);
        for (tscvx_int e = bd->Grp[r0]; e < bd->Grp[r1]; e++)
            uf_union(parent, t->Grc[bd->Grp[r0]], t->Grc[e], n);
    }
    for (tscvx_int j = 0; j < n; j++)
        for (tscvx_int k = ws->P.p[j]; k < ws->P.p[j + 1]; k++) uf_union(parent, ws->P.i[k], j, n);
    tscvx_int ng = 0;
    for (tscvx_int j = 0; j < n; j++) { /* roots are the smallest members: numbered in order */
        const tscvx_int r = uf_root(parent, j, n);
        gid[j] = r == j ? ng++ : gid[r];
    }
    bd->ngroup = ng;
    for (tscvx_int g = 0; g <= ng; g++) bd->gp[g] = 0;
    for (tscvx_int j = 0; j < n; j++) bd->gp[gid[j] + 1]++;
    for (tscvx_int g = 0; g < ng; g++) {
        if (bd->gp[g + 1] > TSCVX_BANDED_GROUP_MAX) return -1;
        bd->gp[g + 1] += bd->gp[g];
    }
    for (tscvx_int g = 0; g < ng; g++) parent[g] = bd->gp[g], bd->ga0[g] = 0; /* fill pointers */
    for (int with_A = 0; with_A < 2; with_A++)
        for (tscvx_int j = 0; j < n; j++) {
            if ((ws->A.p[j + 1] > ws->A.p[j]) != with_A) continue;
            const tscvx_int e = parent[gid[j]]++;
            bd->gvar[e] = j, bd->loc[j] = e - bd->gp[gid[j]];
            bd->ga0[gid[j]] += !with_A;
        }
    for (tscvx_int e = 0; e < ws->G.nnz; e++) bd->Gr_loc[e] = bd->loc[t->Grc[e]];
    for (tscvx_int g = 0; g <= ng; g++) bd->gcp[g] = 0;
    for (tscvx_int c = 0; c < ncone; c++) bd->gcone[c] = -1; /* all set: the checksum reads it */
    for (tscvx_int c = 0; c < ncone; c++) {
        tscvx_int r0, r1;
        cone_rows(K, c, &r0, &r1);
        bd->cgroup[c] = bd->Grp[r1] > bd->Grp[r0] ? gid[t->Grc[bd->Grp[r0]]] : -1;
        if (bd->cgroup[c] >= 0) bd->gcp[bd->cgroup[c] + 1]++;
    }
    for (tscvx_int g = 0; g < ng; g++) bd->gcp[g + 1] += bd->gcp[g];
    for (tscvx_int g = 0; g < ng; g++) parent[g] = bd->gcp[g];
    for (tscvx_int c = 0; c < ncone; c++)
        if (bd->cgroup[c] >= 0) bd->gcone[parent[bd->cgroup[c]]++] = c;
    for (tscvx_int g = 0; g < ng; g++) bd->hasP[g] = 0;
    for (tscvx_int j = 0; j < n; j++) bd->hasP[gid[j]] |= ws->P.p[j + 1] > ws->P.p[j];
    return 0;
}

/* 3. The equality rows of each group (rrow, original rows for now), the border, and the
 * groups of each row (rgp, rgg). Returns -1 without the structure: more than
 * TSCVX_BANDED_BORDER_MAX border variables, or a row of border variables only (Y singular). */
static int group_rows(tscvx_workspace *ws, analysis_tmp *t) {
    tscvx_banded *bd = &ws->bd;
    const tscvx_int p = ws->p, ng = bd->ngroup;
    tscvx_int *mark = t->seen, *rgp = t->rgp;
    for (tscvx_int i = 0; i < p; i++) mark[i] = -1;
    for (tscvx_int k = 0; k < ws->A.nnz; k++) bd->rrow[k] = -1; /* all set: the checksum reads it */
    bd->nb = 0;
    bd->rp[0] = 0;
    for (tscvx_int g = 0; g < ng; g++) {
        const tscvx_int start = bd->rp[g];
        tscvx_int cnt = 0;
        for (tscvx_int v = bd->gp[g]; v < bd->gp[g + 1]; v++) {
            const tscvx_int j = bd->gvar[v];
            for (tscvx_int k = ws->A.p[j]; k < ws->A.p[j + 1]; k++)
                if (mark[ws->A.i[k]] != g) mark[ws->A.i[k]] = g, bd->rrow[start + cnt++] = ws->A.i[k];
        }
        bd->border[g] = cnt > border_rows(p);
        if (bd->border[g]) {
            for (tscvx_int v = bd->gp[g]; v < bd->gp[g + 1]; v++) {
                if (bd->nb >= TSCVX_BANDED_BORDER_MAX) return -1;
                bd->bgroup[bd->nb] = g;
                bd->bvar[bd->nb++] = bd->gvar[v];
            }
            cnt = 0;
        }
        bd->rp[g + 1] = start + cnt;
    }
    for (tscvx_int i = 0; i <= p; i++) rgp[i] = 0;
    for (tscvx_int u = 0; u < bd->rp[ng]; u++) rgp[bd->rrow[u] + 1]++;
    for (tscvx_int i = 0; i < p; i++) {
        if (rgp[i + 1] == 0) return -1;
        rgp[i + 1] += rgp[i];
    }
    for (tscvx_int i = 0; i < p; i++) t->deg[i] = rgp[i]; /* fill pointers */
    for (tscvx_int g = 0; g < ng; g++)
        for (tscvx_int u = bd->rp[g]; u < bd->rp[g + 1]; u++) t->rgg[t->deg[bd->rrow[u]]++] = g;
    return 0;
}

/* 4. Row degrees, the reverse Cuthill-McKee order of the rows and the profile of Y. Returns -1
 * when the profile is too wide (more than TSCVX_BANDED_ENV_AVG entries per row on average,
 * for more than 2 TSCVX_BANDED_ENV_AVG rows: a small Y is always accepted). */
static int order_rows(tscvx_workspace *ws, analysis_tmp *t) {
    tscvx_banded *bd = &ws->bd;
    const tscvx_int p = ws->p;
    const row_graph RG = {bd, t->rgp, t->rgg};
    for (tscvx_int i = 0; i < p; i++) t->seen[i] = -1;
    for (tscvx_int r = 0; r < p; r++) {
        tscvx_int d = 0;
        for (tscvx_int e = t->rgp[r]; e < t->rgp[r + 1]; e++)
            for (tscvx_int u = bd->rp[t->rgg[e]]; u < bd->rp[t->rgg[e] + 1]; u++)
                if (t->seen[bd->rrow[u]] != r) t->seen[bd->rrow[u]] = r, d++;
        t->deg[r] = d;
    }
    rcm(&RG, p, t->deg, t->seen, t->queue, t->order, bd->perm, bd->iperm);
    bd->yp[0] = 0;
    for (tscvx_int b = 0; b < p; b++) {
        const tscvx_int r = bd->perm[b];
        tscvx_int f = b;
        for (tscvx_int e = t->rgp[r]; e < t->rgp[r + 1]; e++)
            for (tscvx_int u = bd->rp[t->rgg[e]]; u < bd->rp[t->rgg[e] + 1]; u++) {
                const tscvx_int c = bd->iperm[bd->rrow[u]];
                f = c < f ? c : f;
            }
        bd->yfirst[b] = f;
        bd->yp[b + 1] = bd->yp[b] + (b - f + 1);
        if (bd->yp[b + 1] > INT_MAX / 4) return -1;
    }
    bd->nY = (size_t)bd->yp[p];
    return bd->nY > (size_t)TSCVX_BANDED_ENV_AVG * p && p > 2 * TSCVX_BANDED_ENV_AVG ? -1 : 0;
}

/* 5. The group row lists in band positions, ascending, and each A entry's place in its
 * group's list (posA; -1 in border groups). */
static void place_rows(tscvx_workspace *ws, analysis_tmp *t) {
    tscvx_banded *bd = &ws->bd;
    for (tscvx_int g = 0; g < bd->ngroup; g++) {
        tscvx_int *R = bd->rrow + bd->rp[g];
        const tscvx_int len_g = bd->rp[g + 1] - bd->rp[g];
        for (tscvx_int u = 0; u < len_g; u++) R[u] = bd->iperm[R[u]];
        sort_ints(R, len_g);
        for (tscvx_int u = 0; u < len_g; u++) t->seen[R[u]] = u;
        for (tscvx_int v = bd->gp[g]; v < bd->gp[g + 1]; v++) {
            const tscvx_int j = bd->gvar[v];
            for (tscvx_int k = ws->A.p[j]; k < ws->A.p[j + 1]; k++)
                bd->posA[k] = bd->border[g] ? -1 : t->seen[bd->iperm[ws->A.i[k]]];
        }
    }
}

/* 6. Offsets and sizes of the value arrays (H and PF blocks, C_g', the SOC blocks W^-1 G_k)
 * and the slots of P's entries. Returns -1 if a size overflows the index type. */
static int size_values(tscvx_workspace *ws, const analysis_tmp *t) {
    tscvx_banded *bd = &ws->bd;
    const tscvx_int ng = bd->ngroup, l = ws->K.l;
    bd->hp[0] = bd->cp[0] = bd->bp[0] = 0;
    for (tscvx_int g = 0; g < ng; g++) {
        const tscvx_int s = bd->gp[g + 1] - bd->gp[g];
        bd->hp[g + 1] = bd->hp[g] + s * s;
        bd->cp[g + 1] = bd->cp[g] + (s - bd->ga0[g]) * (bd->rp[g + 1] - bd->rp[g]);
    }
    for (tscvx_int k = 0; k < ws->K.nsoc; k++) {
        const tscvx_int g = bd->cgroup[l + k];
        const tscvx_int s = g < 0 ? 0 : bd->gp[g + 1] - bd->gp[g];
        if (bd->bp[k] > INT_MAX / 4 - s * ws->K.q[k]) return -1;
        bd->bp[k + 1] = bd->bp[k] + s * ws->K.q[k];
    }
    for (tscvx_int j = 0; j < ws->n; j++)
        for (tscvx_int k = ws->P.p[j]; k < ws->P.p[j + 1]; k++) {
            const tscvx_int i = ws->P.i[k], g = t->gid[j], s = bd->gp[g + 1] - bd->gp[g];
            const tscvx_int lo = bd->loc[i] < bd->loc[j] ? bd->loc[i] : bd->loc[j];
            const tscvx_int hi = bd->loc[i] < bd->loc[j] ? bd->loc[j] : bd->loc[i];
            bd->mapP[k] = bd->hp[g] + lo * s + hi;
        }
    bd->nH = (size_t)bd->hp[ng], bd->nCT = (size_t)bd->cp[ng];
    return 0;
}

/* The arrays whose sizes the problem's dimensions fix, kept for the workspace's life. */
static void claim_persistent(tscvx_workspace *ws, tscvx_arena *a) {
    tscvx_banded *bd = &ws->bd;
    const tscvx_int n = ws->n, p = ws->p, m = ws->m, l = ws->K.l, nsoc = ws->K.nsoc;
    const tscvx_int nnzA = ws->A.nnz, nnzG = ws->G.nnz, nnzP = ws->P.nnz;
    TSCVX_CLAIM(a, bd->gp, n + 1, tscvx_int);
    TSCVX_CLAIM(a, bd->gvar, n, tscvx_int);
    TSCVX_CLAIM(a, bd->loc, n, tscvx_int);
    TSCVX_CLAIM(a, bd->border, n, signed char);
    TSCVX_CLAIM(a, bd->hp, n + 1, tscvx_int);
    TSCVX_CLAIM(a, bd->mapP, nnzP, tscvx_int);
    TSCVX_CLAIM(a, bd->Grp, m + 1, tscvx_int);
    TSCVX_CLAIM(a, bd->Gr_k, nnzG, tscvx_int);
    TSCVX_CLAIM(a, bd->Gr_loc, nnzG, tscvx_int);
    TSCVX_CLAIM(a, bd->cgroup, l + nsoc, tscvx_int);
    TSCVX_CLAIM(a, bd->gcp, n + 1, tscvx_int);
    TSCVX_CLAIM(a, bd->gcone, l + nsoc, tscvx_int);
    TSCVX_CLAIM(a, bd->hasP, n, signed char);
    TSCVX_CLAIM(a, bd->ga0, n, tscvx_int);
    TSCVX_CLAIM(a, bd->bp, nsoc + 1, tscvx_int);
    TSCVX_CLAIM(a, bd->rp, n + 1, tscvx_int);
    TSCVX_CLAIM(a, bd->rrow, nnzA, tscvx_int);
    TSCVX_CLAIM(a, bd->posA, nnzA, tscvx_int);
    TSCVX_CLAIM(a, bd->cp, n + 1, tscvx_int);
    TSCVX_CLAIM(a, bd->perm, p, tscvx_int);
    TSCVX_CLAIM(a, bd->iperm, p, tscvx_int);
    TSCVX_CLAIM(a, bd->yfirst, p, tscvx_int);
    TSCVX_CLAIM(a, bd->yp, p + 1, tscvx_int);
    TSCVX_CLAIM(a, bd->Ydinv, p, tscvx_float);
    TSCVX_CLAIM(a, bd->Hdinv, n, tscvx_float);
    tscvx_float **vec[] = {&bd->xg, &bd->res_x, &bd->ex, &bd->yb, &bd->res_y, &bd->ey,
                           &bd->t, &bd->res_z, &bd->ez, &bd->ewz};
    const tscvx_int len[] = {n, n, n, p, p, p, m, m, m, m};
    for (size_t i = 0; i < sizeof len / sizeof len[0]; i++) {
        TSCVX_CLAIM(a, *vec[i], len[i], tscvx_float);
    }
}

/* The analysis's temporaries (released once it is done). */
static void claim_temporaries(const tscvx_workspace *ws, tscvx_arena *a, analysis_tmp *t) {
    const tscvx_int n = ws->n, p = ws->p, nnzA = ws->A.nnz, nnzG = ws->G.nnz;
    TSCVX_CLAIM(a, t->parent, n, tscvx_int);
    TSCVX_CLAIM(a, t->gid, n, tscvx_int);
    TSCVX_CLAIM(a, t->Grc, nnzG, tscvx_int);
    TSCVX_CLAIM(a, t->rgp, p + 1, tscvx_int);
    TSCVX_CLAIM(a, t->rgg, nnzA, tscvx_int);
    TSCVX_CLAIM(a, t->deg, p, tscvx_int);
    TSCVX_CLAIM(a, t->seen, p, tscvx_int);
    TSCVX_CLAIM(a, t->queue, p, tscvx_int);
    TSCVX_CLAIM(a, t->order, p, tscvx_int);
}

/* The numeric arrays, of the sizes the analysis found (size_values). */
static void claim_values(tscvx_workspace *ws, tscvx_arena *a) {
    tscvx_banded *bd = &ws->bd;
    TSCVX_CLAIM(a, bd->H, bd->nH, tscvx_float);
    TSCVX_CLAIM(a, bd->PF, ws->P.nnz > 0 ? bd->nH : 0, tscvx_float);
    TSCVX_CLAIM(a, bd->CT, bd->nCT, tscvx_float);
    TSCVX_CLAIM(a, bd->Y, bd->nY, tscvx_float);
    TSCVX_CLAIM(a, bd->V, (size_t)ws->p * bd->nb, tscvx_float);
    TSCVX_CLAIM(a, bd->B, bd->bp[ws->K.nsoc], tscvx_float);
}

int tscvx_banded_analyse(tscvx_workspace *ws, tscvx_arena *a) {
    const size_t entry = a->top;
    claim_persistent(ws, a);
    const size_t mark = a->top;
    analysis_tmp t;
    claim_temporaries(ws, a, &t);
    if (a->base == NULL) { /* counting: the value arrays are sized by the analysis itself */
        a->top = mark;
        return 1;
    }
    if (a->overflow) return -1;
    rows_of_G(ws, &t);
    if (find_groups(ws, &t) != 0 || group_rows(ws, &t) != 0 || order_rows(ws, &t) != 0) {
        a->top = entry; /* no banded structure: nothing kept */
        return 0;
    }
    place_rows(ws, &t);
    if (size_values(ws, &t) != 0) {
        a->top = entry;
        return 0;
    }
    a->top = mark; /* temporaries released; the value arrays */
    claim_values(ws, a);
    return 1;
}

/* ---- numeric factorization --------------------------------------------------------------- */

/* R := the triangular factor of [R; b] (R upper s x s, row-major, positive diagonal; b a
 * dense row, clobbered): one Givens rotation per entry of b. */
static inline KERNEL_INLINE void givens_absorb(tscvx_float *R, tscvx_int s, tscvx_float *b) {
    for (tscvx_int k = 0; k < s; k++) {
        if (b[k] == 0.0) continue;
        tscvx_float *Rk = R + (size_t)k * s;
        const tscvx_float r = sqrt(Rk[k] * Rk[k] + b[k] * b[k]);
        const tscvx_float c = Rk[k] / r, sn = b[k] / r;
        Rk[k] = r;
        SMALL_LOOP
        for (tscvx_int i = k + 1; i < s; i++) {
            const tscvx_float t = Rk[i];
            Rk[i] = c * t + sn * b[i];
            b[i] = c * b[i] - sn * t;
        }
    }
}

/* An SOC's rows in a group's factor: B = W^-1 G_c (q x s dense, column by column) kept for
 * the solves, its rows absorbed into R (q a constant where it is one, as s) */
static inline KERNEL_INLINE void soc_absorb(const tscvx_banded *bd, const tscvx_float *Gx,
                                            const tscvx_int *Grp, const tscvx_float *wb,
                                            tscvx_float eta, const tscvx_int q,
                                            const tscvx_int s, tscvx_float *B, tscvx_float *R,
                                            tscvx_float *b) {
    for (tscvx_int e = 0; e < q * s; e++) B[e] = 0.0;
    for (tscvx_int r = 0; r < q; r++)
        for (tscvx_int e = Grp[r]; e < Grp[r + 1]; e++) B[r * s + bd->Gr_loc[e]] = Gx[bd->Gr_k[e]];
    /* W^-1 v = (1/eta) (wb0 v0 - wb1'v1, v1 + (-v0 + wb1'v1/(1 + wb0)) wb1) (cones.c) */
    for (tscvx_int col = 0; col < s; col++) {
        tscvx_float w1v1 = 0.0;
        for (tscvx_int r = 1; r < q; r++) w1v1 += wb[r] * B[r * s + col];
        const tscvx_float v0 = B[col];
        const tscvx_float coef = -v0 + w1v1 / (1.0 + wb[0]);
        for (tscvx_int r = 1; r < q; r++) B[r * s + col] = (B[r * s + col] + coef * wb[r]) / eta;
        B[col] = (wb[0] * v0 - w1v1) / eta;
    }
    for (tscvx_int r = 0; r < q; r++) { /* absorbing clobbers its row: a copy */
        for (tscvx_int i = 0; i < s; i++) b[i] = B[r * s + i];
        givens_absorb(R, s, b);
    }
}

/* The factor of H_g = P_gg + d I + sum over the group's cones of (W_c^-1 G_c)'(W_c^-1 G_c),
 * H_g = R_g'R_g, by absorbing the rows of sqrt(d) I, of P_gg's factor and of every W_c^-1 G_c
 * into R_g (Givens): an orthogonal factorization of the stacked rows, so the conditioning of
 * W^-1 G is not squared as forming H_g would. R_g (row-major upper) is L_g' and is stored as
 * L_g (column-major lower): the same array. Returns the largest |entry| of W over the
 * group's cones (refinement floor). */
static inline KERNEL_INLINE tscvx_float factor_group_s(tscvx_workspace *ws, tscvx_int g,
                                                     tscvx_float d, const tscvx_int s) {
    tscvx_banded *bd = &ws->bd;
    const tscvx_cones *K = &ws->K;
    const tscvx_float *Gx = ws->G.x;
    tscvx_float *R = bd->H + bd->hp[g], b[TSCVX_BANDED_GROUP_MAX], wmax = 0.0;
    for (tscvx_int t = 0; t < s * s; t++) R[t] = 0.0;
    for (tscvx_int k = 0; k < s; k++) R[k * s + k] = sqrt(d);
    if (bd->hasP[g])
        for (tscvx_int k = 0; k < s; k++) { /* row k of F = L_P' */
            for (tscvx_int i = 0; i < s; i++) b[i] = i < k ? 0.0 : bd->PF[bd->hp[g] + k * s + i];
            givens_absorb(R, s, b);
        }
    for (tscvx_int t = bd->gcp[g]; t < bd->gcp[g + 1]; t++) {
        const tscvx_int c = bd->gcone[t];
        if (c < K->l) { /* orthant row: G_c / w_c */
            const tscvx_float w = ws->W.w[c];
            wmax = w > wmax ? w : wmax;
            for (tscvx_int i = 0; i < s; i++) b[i] = 0.0;
            for (tscvx_int e = bd->Grp[c]; e < bd->Grp[c + 1]; e++) b[bd->Gr_loc[e]] = Gx[bd->Gr_k[e]] / w;
            givens_absorb(R, s, b);
            continue;
        }
        /* SOC: B = W^-1 G_c (q x s dense, column by column), its rows absorbed */
        const tscvx_int k = c - K->l, o = K->off[k], q = K->q[k];
        const tscvx_float *wb = ws->W.w + o, eta = ws->W.eta[k];
        const tscvx_float big = eta * (wb[0] + sqrt(tscvx_dot(wb + 1, wb + 1, q - 1)));
        wmax = big > wmax ? big : wmax;
        tscvx_float *B = bd->B + bd->bp[k];
        const tscvx_int *Grp = bd->Grp + o;
        if (q == 3)
            soc_absorb(bd, Gx, Grp, wb, eta, 3, s, B, R, b);
        else if (q == 4)
            soc_absorb(bd, Gx, Grp, wb, eta, 4, s, B, R, b);
        else
            soc_absorb(bd, Gx, Grp, wb, eta, q, s, B, R, b);
    }
    return wmax;
}

static tscvx_float factor_group(tscvx_workspace *ws, tscvx_int g, tscvx_float d) {
    const tscvx_int s = ws->bd.gp[g + 1] - ws->bd.gp[g];
    tscvx_float wmax = 0.0;
#define FACTOR(S) wmax = factor_group_s(ws, g, d, S)
    DISPATCH_S(s, FACTOR)
#undef FACTOR
    return wmax;
}

/* An SOC's rows of Gt (q x s row-major B, Gt = W^-1 G on the cone's group): xgg += B' tk */
static inline void soc_scatter(const tscvx_float *restrict B, tscvx_int q, tscvx_int s,
                               const tscvx_float *restrict tk, tscvx_float *restrict xgg) {
    for (tscvx_int r = 0; r < q; r++) {
        SMALL_LOOP
        for (tscvx_int a = 0; a < s; a++) xgg[a] += B[r * s + a] * tk[r];
    }
}

/* out = B xgg - tk */
static inline void soc_gather(const tscvx_float *restrict B, tscvx_int q, tscvx_int s,
                              const tscvx_float *restrict xgg, const tscvx_float *restrict tk,
                              tscvx_float *restrict out) {
    for (tscvx_int r = 0; r < q; r++) out[r] = tscvx_dot(B + (size_t)r * s, xgg, s) - tk[r];
}

/* C_g' = (L_g^-1 A_g')' and Y = d I + sum_g C_g' C_g. Only the last se = s - ga0 variables
 * of a group have equality entries: C_g's rows above them are zero, and the rest is
 * L22^-1 A_g' with L22 the trailing block of L_g. */
static void form_Y(tscvx_workspace *ws, tscvx_float d) {
    tscvx_banded *bd = &ws->bd;
    for (size_t t = 0; t < bd->nY; t++) bd->Y[t] = 0.0;
    for (tscvx_int i = 0; i < ws->p; i++) prow(bd, i)[i] = d;
    for (size_t t = 0; t < bd->nCT; t++) bd->CT[t] = 0.0;
    for (tscvx_int g = 0; g < bd->ngroup; g++) {
        const tscvx_int s = bd->gp[g + 1] - bd->gp[g], a0 = bd->ga0[g], se = s - a0;
        const tscvx_int R = bd->rp[g + 1] - bd->rp[g];
        if (bd->border[g] || se == 0 || R == 0) continue;
        const tscvx_float *L22 = bd->H + bd->hp[g] + a0 * s + a0;
        const tscvx_float *dinv = bd->Hdinv + bd->gp[g] + a0;
        const tscvx_int *rows = bd->rrow + bd->rp[g];
        tscvx_float *CT = bd->CT + bd->cp[g];
        for (tscvx_int v = a0; v < s; v++) {
            const tscvx_int j = bd->gvar[bd->gp[g] + v];
            for (tscvx_int k = ws->A.p[j]; k < ws->A.p[j + 1]; k++)
                CT[bd->posA[k] * se + v - a0] = ws->A.x[k];
        }
#define FORM(S)                          \
    group_ct(L22, s, dinv, S, CT, R);    \
    group_gram(bd, rows, CT, R, S)
        DISPATCH_S(se, FORM)
#undef FORM
    }
}

/* Border: V = Y^-1 A_B, S = H_B + A_B' V (lower part), factored. */
static int form_border(tscvx_workspace *ws) {
    tscvx_banded *bd = &ws->bd;
    const tscvx_int p = ws->p, nb = bd->nb;
    for (tscvx_int b = 0; b < nb; b++) {
        tscvx_float *Vb = bd->V + (size_t)b * p;
        const tscvx_int j = bd->bvar[b];
        for (tscvx_int i = 0; i < p; i++) Vb[i] = 0.0;
        for (tscvx_int k = ws->A.p[j]; k < ws->A.p[j + 1]; k++) Vb[bd->iperm[ws->A.i[k]]] = ws->A.x[k];
        profile_solve(bd, p, Vb);
    }
    for (tscvx_int c = 0; c < nb; c++) {
        const tscvx_int jc = bd->bvar[c], g = bd->bgroup[c];
        const tscvx_int s = bd->gp[g + 1] - bd->gp[g];
        const tscvx_float *R = bd->H + bd->hp[g]; /* H_B = R'R, R row-major upper */
        for (tscvx_int r = c; r < nb; r++) {
            const tscvx_int jr = bd->bvar[r];
            tscvx_float v = 0.0;
            if (bd->bgroup[r] == g) /* same group: loc[jc] <= loc[jr] (listed in group order) */
                for (tscvx_int k = 0; k <= bd->loc[jc]; k++)
                    v += R[k * s + bd->loc[jc]] * R[k * s + bd->loc[jr]];
            for (tscvx_int k = ws->A.p[jr]; k < ws->A.p[jr + 1]; k++)
                v += ws->A.x[k] * bd->V[(size_t)c * p + bd->iperm[ws->A.i[k]]];
            bd->S[c * nb + r] = v;
        }
    }
    return chol(bd->S, nb, 0, 0.0);
}

/* The banded method's static regularization: TSCVX_BANDED_REG_SCALE times the IPM's delta.
 * Its factors need no regularization for stability (Givens rotations, positive pivots), only
 * against exact singularity, and a smaller d leaves less for the refinement to remove. */
static tscvx_float banded_reg(const tscvx_workspace *ws) {
    return TSCVX_BANDED_REG_SCALE * ws->delta;
}

/* The factors of the groups' P blocks (P_gg = L_P L_P'); *pmax = the largest |entry| of P.
 * P is block diagonal over the groups (a P entry joins its variables' groups), so this is
 * also the full semidefiniteness test of P. Returns -1 when a block is found indefinite (or
 * its factor not finite). */
static int factor_p_blocks(tscvx_workspace *ws, tscvx_float *pmax) {
    tscvx_banded *bd = &ws->bd;
    for (tscvx_int g = 0; g < bd->ngroup; g++) {
        if (!bd->hasP[g]) continue;
        const tscvx_int s = bd->gp[g + 1] - bd->gp[g];
        tscvx_float *F = bd->PF + bd->hp[g];
        for (tscvx_int t = 0; t < s * s; t++) F[t] = 0.0;
    }
    *pmax = 0.0;
    for (tscvx_int k = 0; k < ws->P.nnz; k++) {
        bd->PF[bd->mapP[k]] += ws->P.x[k];
        *pmax = tscvx_max(*pmax, fabs(ws->P.x[k]));
    }
    int status = 0;
    for (tscvx_int g = 0; g < bd->ngroup; g++)
        if (bd->hasP[g] && chol(bd->PF + bd->hp[g], bd->gp[g + 1] - bd->gp[g], 1, *pmax) != 0)
            status = -1;
    return status;
}

static int banded_check_p(tscvx_workspace *ws) {
    tscvx_float pmax;
    return factor_p_blocks(ws, &pmax);
}

/* New data: the P-block factors and the largest |entry| of P, A, G. Returns -1 when a P
 * block is found indefinite. */
static int banded_load(tscvx_workspace *ws) {
    tscvx_float pmax;
    const int status = factor_p_blocks(ws, &pmax);
    tscvx_float kmax = fmax(banded_reg(ws), pmax);
    kmax = tscvx_max_abs(ws->G.x, ws->G.nnz, tscvx_max_abs(ws->A.x, ws->A.nnz, kmax));
    ws->bd.kmax_data = kmax;
    return status;
}

static int banded_factor(tscvx_workspace *ws) {
    tscvx_banded *bd = &ws->bd;
    const tscvx_float d = banded_reg(ws);
    bd->kmax = bd->kmax_data;
    for (tscvx_int g = 0; g < bd->ngroup; g++) {
        bd->kmax = fmax(bd->kmax, factor_group(ws, g, d));
        const tscvx_int s = bd->gp[g + 1] - bd->gp[g];
        for (tscvx_int a = 0; a < s; a++) bd->Hdinv[bd->gp[g] + a] = 1.0 / bd->H[bd->hp[g] + a * s + a];
    }
    form_Y(ws, d);
    if (profile_chol(bd, ws->p) != 0) return -1;
    return bd->nb > 0 ? form_border(ws) : 0;
}

/* ---- solves ------------------------------------------------------------------------------ */

/* A group's factor L_g (with 1 / its diagonal) and its coupling C_g to the R equality rows
 * `rows`, stored over the group's last se variables, as the solves read them. */
typedef struct {
    tscvx_int s, se, R;
    const tscvx_float *L, *dinv, *CT;
    const tscvx_int *rows;
} group_blocks;

static inline group_blocks group_blocks_of(const tscvx_banded *bd, tscvx_int g) {
    group_blocks b;
    b.s = bd->gp[g + 1] - bd->gp[g];
    b.se = b.s - bd->ga0[g];
    b.R = bd->rp[g + 1] - bd->rp[g];
    b.L = bd->H + bd->hp[g];
    b.dinv = bd->Hdinv + bd->gp[g];
    b.CT = bd->CT + bd->cp[g];
    b.rows = bd->rrow + bd->rp[g];
    return b;
}

/* Cone rows in: t = W^-1 rz and xg = rx~ = rx + Gt't in group order (Gt = W^-1 G: orthant
 * rows G_i / w_i, SOC blocks kept from the factorization). */
static void cone_rows_in(tscvx_workspace *ws, const tscvx_float *rx, const tscvx_float *rz) {
    tscvx_banded *bd = &ws->bd;
    const tscvx_cones *K = &ws->K;
    const tscvx_float *Gx = ws->G.x, *w = ws->W.w;
    tscvx_float *xg = bd->xg, *t = bd->t;
    tscvx_nt_apply(K, &ws->W, 1, rz, t);
    for (tscvx_int v = 0; v < ws->n; v++) xg[v] = rx[bd->gvar[v]];
    for (tscvx_int i = 0; i < K->l; i++) {
        const tscvx_int g = bd->cgroup[i];
        if (g < 0) continue;
        tscvx_float *xgg = xg + bd->gp[g];
        const tscvx_float ti = t[i] / w[i];
        for (tscvx_int e = bd->Grp[i]; e < bd->Grp[i + 1]; e++) xgg[bd->Gr_loc[e]] += Gx[bd->Gr_k[e]] * ti;
    }
    for (tscvx_int k = 0; k < K->nsoc; k++) {
        const tscvx_int g = bd->cgroup[K->l + k];
        if (g < 0) continue;
        const tscvx_int s = bd->gp[g + 1] - bd->gp[g], q = K->q[k];
        const tscvx_float *B = bd->B + bd->bp[k], *tk = t + K->off[k];
        tscvx_float *xgg = xg + bd->gp[g];
#define SCATTER(S) soc_scatter(B, q, S, tk, xgg)
        DISPATCH_S(s, SCATTER)
#undef SCATTER
    }
}

/* Groups forward: w_g = L_g^-1 rx~_g (in xg); yb = ry~ = ry - sum_g C_g' w_g (band order) */
static void groups_forward(tscvx_workspace *ws, const tscvx_float *ry) {
    tscvx_banded *bd = &ws->bd;
    tscvx_float *yb = bd->yb;
    for (tscvx_int i = 0; i < ws->p; i++) yb[bd->iperm[i]] = ry[i];
    for (tscvx_int g = 0; g < bd->ngroup; g++) {
        if (bd->border[g]) continue;
        const group_blocks b = group_blocks_of(bd, g);
        tscvx_float *wg = bd->xg + bd->gp[g];
#define FORWARD(S, SE) group_forward(b.L, b.dinv, S, SE, wg, b.rows, b.CT, b.R, yb)
        if (b.R > 0) {
            DISPATCH_S_SE(b.s, b.se, FORWARD)
        } else {
            group_forward(b.L, b.dinv, b.s, 0, wg, b.rows, b.CT, 0, yb);
        }
#undef FORWARD
    }
}

/* Equalities and border: -Y dy + A_B dx_B = ry~, H_B dx_B + A_B' dy = rx~_B. Leaves dy in yb
 * (band order) and dx_B in the border variables' places of xg. */
static void equalities(tscvx_workspace *ws) {
    tscvx_banded *bd = &ws->bd;
    const tscvx_int p = ws->p, nb = bd->nb;
    tscvx_float *xg = bd->xg, *yb = bd->yb;
    profile_solve(bd, p, yb); /* yb = Y^-1 ry~ */
    tscvx_float dxb[TSCVX_BANDED_BORDER_MAX];
    for (tscvx_int b = 0; b < nb; b++) {
        const tscvx_int j = bd->bvar[b];
        tscvx_float v = xg[bd->gp[bd->bgroup[b]] + bd->loc[j]];
        for (tscvx_int k = ws->A.p[j]; k < ws->A.p[j + 1]; k++) v += ws->A.x[k] * yb[bd->iperm[ws->A.i[k]]];
        dxb[b] = v;
    }
    chol_lsolve(bd->S, nb, dxb);
    chol_ltsolve(bd->S, nb, dxb);
    for (tscvx_int i = 0; i < p; i++) { /* dy = V dx_B - Y^-1 ry~ */
        tscvx_float v = -yb[i];
        for (tscvx_int b = 0; b < nb; b++) v += bd->V[(size_t)b * p + i] * dxb[b];
        yb[i] = v;
    }
    for (tscvx_int b = 0; b < nb; b++) xg[bd->gp[bd->bgroup[b]] + bd->loc[bd->bvar[b]]] = dxb[b];
}

/* Groups back: dx_g = L_g'^-1 (w_g - C_g dy), in xg (the border groups' values kept) */
static void groups_backward(tscvx_workspace *ws) {
    tscvx_banded *bd = &ws->bd;
    for (tscvx_int g = 0; g < bd->ngroup; g++) {
        if (bd->border[g]) continue;
        const group_blocks b = group_blocks_of(bd, g);
        tscvx_float *wg = bd->xg + bd->gp[g];
#define BACKWARD(S, SE) group_backward(b.L, b.dinv, S, SE, wg, b.rows, b.CT, b.R, bd->yb)
        DISPATCH_S_SE(b.s, b.se, BACKWARD)
#undef BACKWARD
    }
}

/* Cone rows out: wdz = Gt dx - t, dz = W^-1 wdz; dx and dy back in the original order. */
static void cone_rows_out(tscvx_workspace *ws, tscvx_float *dx, tscvx_float *dy,
                          tscvx_float *dz, tscvx_float *wdz) {
    tscvx_banded *bd = &ws->bd;
    const tscvx_cones *K = &ws->K;
    const tscvx_float *Gx = ws->G.x, *w = ws->W.w, *xg = bd->xg, *t = bd->t;
    for (tscvx_int i = 0; i < K->l; i++) {
        const tscvx_int g = bd->cgroup[i];
        tscvx_float v = 0.0;
        if (g >= 0) {
            const tscvx_float *xgg = xg + bd->gp[g];
            for (tscvx_int e = bd->Grp[i]; e < bd->Grp[i + 1]; e++) v += Gx[bd->Gr_k[e]] * xgg[bd->Gr_loc[e]];
        }
        wdz[i] = v / w[i] - t[i];
    }
    for (tscvx_int k = 0; k < K->nsoc; k++) {
        const tscvx_int g = bd->cgroup[K->l + k], o = K->off[k], q = K->q[k];
        if (g < 0) {
            for (tscvx_int r = 0; r < q; r++) wdz[o + r] = -t[o + r];
            continue;
        }
        const tscvx_int s = bd->gp[g + 1] - bd->gp[g];
        const tscvx_float *B = bd->B + bd->bp[k], *xgg = xg + bd->gp[g];
#define GATHER(S) soc_gather(B, q, S, xgg, t + o, wdz + o)
        DISPATCH_S(s, GATHER)
#undef GATHER
    }
    tscvx_nt_apply(K, &ws->W, 1, wdz, dz);
    for (tscvx_int v = 0; v < ws->n; v++) dx[bd->gvar[v]] = xg[v];
    for (tscvx_int i = 0; i < ws->p; i++) dy[i] = bd->yb[bd->iperm[i]];
}

/* One solve of the regularized system (no refinement) into (dx, dy, dz) and wdz = W dz;
 * outputs do not alias inputs. The cone rows NT-scaled (CVXOPT's condensed solver):
 *   t = W^-1 rz,  rx~ = rx + Gt't,  ...,  wdz = Gt dx - t,  dz = W^-1 wdz.
 * The variables are handled in group order (xg) throughout. */
static void base_solve(tscvx_workspace *ws, const tscvx_float *rx, const tscvx_float *ry,
                       const tscvx_float *rz, tscvx_float *dx, tscvx_float *dy,
                       tscvx_float *dz, tscvx_float *wdz) {
    cone_rows_in(ws, rx, rz);
    groups_forward(ws, ry);
    equalities(ws);
    groups_backward(ws);
    cone_rows_out(ws, dx, dy, dz, wdz);
}

/* Residual of the unregularized KKT system, into res_x, res_y, res_z:
 *   (rx - P dx - A'dy - G'dz, ry - A dx, rz - G dx + W wdz); returns its inf-norm. */
static tscvx_float residual(tscvx_workspace *ws, const tscvx_float *rx, const tscvx_float *ry,
                            const tscvx_float *rz, const tscvx_float *dx,
                            const tscvx_float *dy, const tscvx_float *dz,
                            const tscvx_float *wdz) {
    tscvx_banded *bd = &ws->bd;
    const tscvx_int n = ws->n, p = ws->p, m = ws->m;
    tscvx_spmv_sym(&ws->P, dx, bd->res_x);
    for (tscvx_int i = 0; i < p; i++) bd->res_y[i] = 0.0;
    tscvx_nt_apply(&ws->K, &ws->W, 0, wdz, bd->res_z);
    for (tscvx_int i = 0; i < m; i++) bd->res_z[i] = -bd->res_z[i];
    tscvx_spmv_both(&ws->A, dy, bd->res_x, dx, bd->res_y);
    tscvx_spmv_both(&ws->G, dz, bd->res_x, dx, bd->res_z);
    tscvx_float r = 0.0;
    for (tscvx_int j = 0; j < n; j++) bd->res_x[j] = rx[j] - bd->res_x[j];
    for (tscvx_int i = 0; i < p; i++) bd->res_y[i] = ry[i] - bd->res_y[i];
    for (tscvx_int i = 0; i < m; i++) bd->res_z[i] = rz[i] - bd->res_z[i];
    r = tscvx_max_abs(bd->res_x, n, r);
    r = tscvx_max_abs(bd->res_y, p, r);
    return tscvx_max_abs(bd->res_z, m, r);
}

static int banded_solve(tscvx_workspace *ws, const tscvx_float *rx, const tscvx_float *ry,
                        const tscvx_float *rz, tscvx_float *dx, tscvx_float *dy, tscvx_float *dz,
                        tscvx_float *wdz, tscvx_int refine) {
    tscvx_banded *bd = &ws->bd;
    const tscvx_int n = ws->n, p = ws->p, m = ws->m;
    base_solve(ws, rx, ry, rz, dx, dy, dz, wdz);
    if (refine <= 0) return 0;
    const tscvx_float bnorm = tscvx_max_abs(rz, m, tscvx_max_abs(ry, p, tscvx_max_abs(rx, n, 0.0)));
    tscvx_float last = INFINITY;
    int steps = 0;
    for (tscvx_int it = 0; it < refine; it++) {
        const tscvx_float rnorm = residual(ws, rx, ry, rz, dx, dy, dz, wdz);
        if (!isfinite(rnorm)) return -1;
        const tscvx_float xnorm = tscvx_max_abs(wdz, m, tscvx_max_abs(dy, p, tscvx_max_abs(dx, n, 0.0)));
        if (rnorm <= TSCVX_REFINE_TOL * (1.0 + bnorm) ||
            rnorm <= TSCVX_REFINE_FLOOR * bd->kmax * xnorm || rnorm > TSCVX_REFINE_RATIO * last)
            break;
        last = rnorm;
        base_solve(ws, bd->res_x, bd->res_y, bd->res_z, bd->ex, bd->ey, bd->ez, bd->ewz);
        for (tscvx_int j = 0; j < n; j++) dx[j] += bd->ex[j];
        for (tscvx_int i = 0; i < p; i++) dy[i] += bd->ey[i];
        for (tscvx_int i = 0; i < m; i++) dz[i] += bd->ez[i], wdz[i] += bd->ewz[i];
        steps++;
    }
    return steps;
}

const tscvx_kkt_method tscvx_method_banded = {"banded", TSCVX_KKT_BANDED, banded_load,
                                              banded_check_p, banded_factor, banded_solve};
