/* The quasi-definite KKT system: pattern, AMD ordering, maps, values, solves.
 *
 *   K = [ P + d I   A'     G'           ]
 *       [ A        -d I    0            ]
 *       [ G         0     -(W'W) - d I  ]
 *
 * An SOC of dimension q > soc_dense_max is not given a dense q x q block. With
 * W'W = eta^2 (2 wbar wbar' - J) = eta^2 (I + u u' - v v'), u = sqrt(2) wbar, v = sqrt(2) e0,
 * the block is expanded with two extra rows (v-row with pivot -1, u-row with pivot +1):
 *
 *   [ -eta^2 I - d I   eta v   eta u ]     whose Schur complement onto the cone rows is
 *   [  eta v'          -1      0     ]     -eta^2 (I + u u' - v v') - d I = -(W'W) - d I.
 *   [  eta u'           0     +1     ]
 *
 * The pattern and every map from data to KKT slot are built once (tscvx_kkt_build); each
 * IPM iteration only writes the cone-block values and refactors numerically.
 */
#include <math.h>

#include "amd.h"
#include "ldl.h"
#include "socp_internal.h"


/* ---- SuiteSparse LDL backend ------------------------------------------------------------- */

static long ldl_backend_symbolic(tscvx_kkt *k, tscvx_int *tmp) {
    tscvx_int *Lp = tmp, *Parent = Lp + k->dim + 1, *Lnz = Parent + k->dim, *Flag = Lnz + k->dim;
    ldl_symbolic(k->dim, k->Kp, k->Ki, Lp, Parent, Lnz, Flag, NULL, NULL);
    return (long)Lp[k->dim];
}

static int ldl_backend_alloc(tscvx_kkt *k, tscvx_arena *a) {
    const size_t dim = (size_t)k->dim;
    TSCVX_CLAIM(a, k->Lp, dim + 1, tscvx_int);
    TSCVX_CLAIM(a, k->Parent, dim, tscvx_int);
    TSCVX_CLAIM(a, k->Lnz, dim, tscvx_int);
    TSCVX_CLAIM(a, k->Flag, dim, tscvx_int);
    TSCVX_CLAIM(a, k->Li, (size_t)k->lnz + 1, tscvx_int);
    TSCVX_CLAIM(a, k->Lx, (size_t)k->lnz + 1, tscvx_float);
    TSCVX_CLAIM(a, k->D, dim, tscvx_float);
    TSCVX_CLAIM(a, k->Y, dim, tscvx_float);
    k->res = k->Y; /* the factor's work vector is free during solves */
    if (a->base == NULL || a->overflow) return 0;
    ldl_symbolic(k->dim, k->Kp, k->Ki, k->Lp, k->Parent, k->Lnz, k->Flag, NULL, NULL);
    return k->Lp[k->dim] == k->lnz ? 0 : -1;
}

static int ldl_backend_numeric(tscvx_kkt *k) {
    if (ldl_numeric(k->dim, k->Kp, k->Ki, k->Kx, k->Lp, k->Parent, k->Lnz, k->Li, k->Lx, k->D,
                    k->Y, k->Pattern, k->Flag, NULL, NULL) != k->dim)
        return -1;
    /* inertia check: the regularized system has exactly (n + nexp) positive pivots */
    tscvx_int npos = 0;
    for (tscvx_int i = 0; i < k->dim; i++) {
        if (!isfinite(k->D[i])) return -1;
        npos += k->D[i] > 0.0;
    }
    return npos == k->npos ? 0 : -1;
}

static void ldl_backend_solve(tscvx_kkt *k, tscvx_float *x) {
    ldl_lsolve(k->dim, x, k->Lp, k->Li, k->Lx);
    ldl_dsolve(k->dim, x, k->D);
    ldl_ltsolve(k->dim, x, k->Lp, k->Li, k->Lx);
}

const tscvx_backend tscvx_backend_ldl = {"suitesparse-ldl", ldl_backend_symbolic,
                                         ldl_backend_alloc, ldl_backend_numeric,
                                         ldl_backend_solve};

/* ---- pattern ----------------------------------------------------------------------------- */

static int is_expanded(tscvx_int q, tscvx_int dense_max) { return q > dense_max; }

/* Enumerate the upper-triangle entries (row <= col, original order) of the KKT pattern in
 * the fixed order that the maps use: P (+ missing x diagonals), A, y diagonals, G, cones. */
static tscvx_int enumerate(const tscvx_workspace *ws, tscvx_int *Ti, tscvx_int *Tj) {
    const tscvx_int n = ws->n, p = ws->p, m = ws->m;
    const tscvx_int dmax = ws->st.soc_dense_max;
    tscvx_int t = 0;
    for (tscvx_int j = 0; j < n; j++) {
        int has_diag = 0;
        for (tscvx_int k = ws->P.p[j]; k < ws->P.p[j + 1]; k++) {
            Ti[t] = ws->P.i[k], Tj[t++] = j;
            has_diag |= ws->P.i[k] == j;
        }
        if (!has_diag) Ti[t] = j, Tj[t++] = j;
    }
    for (tscvx_int j = 0; j < n; j++)
        for (tscvx_int k = ws->A.p[j]; k < ws->A.p[j + 1]; k++) Ti[t] = j, Tj[t++] = n + ws->A.i[k];
    for (tscvx_int i = 0; i < p; i++) Ti[t] = n + i, Tj[t++] = n + i;
    for (tscvx_int j = 0; j < n; j++)
        for (tscvx_int k = ws->G.p[j]; k < ws->G.p[j + 1]; k++)
            Ti[t] = j, Tj[t++] = n + p + ws->G.i[k];
    const tscvx_int z0 = n + p;
    for (tscvx_int i = 0; i < ws->K.l; i++) Ti[t] = z0 + i, Tj[t++] = z0 + i;
    tscvx_int extra = n + p + m;
    for (tscvx_int k = 0; k < ws->K.nsoc; k++) {
        const tscvx_int o = z0 + ws->K.off[k], q = ws->K.q[k];
        if (!is_expanded(q, dmax)) {
            for (tscvx_int b = 0; b < q; b++)
                for (tscvx_int a = 0; a <= b; a++) Ti[t] = o + a, Tj[t++] = o + b;
        } else {
            for (tscvx_int a = 0; a < q; a++) Ti[t] = o + a, Tj[t++] = o + a;
            Ti[t] = o, Tj[t++] = extra;         /* v column: eta sqrt2 at the cone head */
            Ti[t] = extra, Tj[t++] = extra;     /* v pivot -1 */
            for (tscvx_int a = 0; a < q; a++) Ti[t] = o + a, Tj[t++] = extra + 1;
            Ti[t] = extra + 1, Tj[t++] = extra + 1; /* u pivot +1 */
            extra += 2;
        }
    }
    return t;
}

/* Bytes of temporary memory tscvx_kkt_build needs (AMD and triplets). */
size_t tscvx_kkt_temp_ints(tscvx_int dim, tscvx_int nnz) {
    const size_t nz2 = 2 * (size_t)nnz;
    const size_t iwlen = nz2 + nz2 / 5 + 2 * (size_t)dim;
    return 3 * (size_t)nnz + 9 * (size_t)dim + iwlen;
}

/* Build the permuted pattern, the maps and the symbolic factorization. `tmp` holds
 * tscvx_kkt_temp_ints() ints. Returns nnz(L), or -1 on failure. */
/* AMD's ordering of the KKT pattern (nnz entries (Ti, Tj), upper triangle) into kk->pinv,
 * with each pivot's block in kk->rowblk; w: AMD's work arrays (10 dim + iwlen). 0, or -1
 * when AMD's permutation is not one. */
static int order_by_amd(tscvx_workspace *ws, const tscvx_int *Ti, const tscvx_int *Tj,
                     tscvx_int *w) {
    tscvx_kkt *kk = &ws->kkt;
    const tscvx_int dim = kk->dim, nnz = kk->nnz;
    tscvx_int *Pe = w, *Len = Pe + dim, *Nv = Len + dim, *Next = Nv + dim;
    tscvx_int *Last = Next + dim, *Head = Last + dim, *Elen = Head + dim, *Deg = Elen + dim;
    tscvx_int *Wk = Deg + dim, *Iw = Wk + dim;
    const size_t nz2 = 2 * (size_t)nnz;
    const tscvx_int iwlen = (tscvx_int)(nz2 + nz2 / 5 + 2 * (size_t)dim);

    /* the symmetric pattern without diagonal (amd_2 wants both triangles) */
    for (tscvx_int i = 0; i < dim; i++) Len[i] = 0;
    for (tscvx_int t = 0; t < nnz; t++)
        if (Ti[t] != Tj[t]) Len[Ti[t]]++, Len[Tj[t]]++;
    tscvx_int pfree = 0;
    for (tscvx_int i = 0; i < dim; i++) Pe[i] = pfree, pfree += Len[i], Nv[i] = 0;
    for (tscvx_int t = 0; t < nnz; t++)
        if (Ti[t] != Tj[t]) Iw[Pe[Ti[t]] + Nv[Ti[t]]++] = Tj[t], Iw[Pe[Tj[t]] + Nv[Tj[t]]++] = Ti[t];
    double control[AMD_CONTROL], info[AMD_INFO];
    amd_defaults(control);
    amd_2(dim, Pe, Iw, Len, iwlen, pfree, Nv, Next, Last, Head, Elen, Deg, Wk, control, info);
    for (tscvx_int k = 0; k < dim; k++) kk->pinv[k] = -1;
    for (tscvx_int k = 0; k < dim; k++) { /* Last[k] = original row of pivot k */
        const tscvx_int i = Last[k];
        if (i < 0 || i >= dim || kk->pinv[i] != -1) return -1;
        kk->pinv[i] = k;
        kk->rowblk[k] = (signed char)(i < ws->n ? KKT_ROW_X
                                      : i < ws->n + ws->p ? KKT_ROW_Y
                                      : i < ws->n + ws->p + ws->m ? KKT_ROW_Z : KKT_ROW_EXP);
    }
    return 0;
}

/* The permuted upper triangle (Kp, Ki): entry t, (i, j), goes to column max(pinv i, pinv j),
 * at slot[t]; next: dim temporaries. */
static void permuted_pattern(tscvx_kkt *kk, const tscvx_int *Ti, const tscvx_int *Tj,
                             tscvx_int *slot, tscvx_int *next) {
    const tscvx_int dim = kk->dim, nnz = kk->nnz;
    for (tscvx_int k = 0; k <= dim; k++) kk->Kp[k] = 0;
    for (tscvx_int t = 0; t < nnz; t++) {
        const tscvx_int a = kk->pinv[Ti[t]], b = kk->pinv[Tj[t]];
        kk->Kp[(a > b ? a : b) + 1]++;
    }
    for (tscvx_int k = 0; k < dim; k++) kk->Kp[k + 1] += kk->Kp[k];
    for (tscvx_int k = 0; k < dim; k++) next[k] = kk->Kp[k];
    for (tscvx_int t = 0; t < nnz; t++) {
        const tscvx_int a = kk->pinv[Ti[t]], b = kk->pinv[Tj[t]];
        const tscvx_int col = a > b ? a : b;
        slot[t] = next[col]++;
        kk->Ki[slot[t]] = a < b ? a : b;
    }
}

/* The slots to the maps from the problem's data into K, in the order of enumerate(). */
static void distribute_slots(tscvx_workspace *ws, const tscvx_int *slot) {
    tscvx_kkt *kk = &ws->kkt;
    tscvx_int t = 0;
    for (tscvx_int j = 0; j < ws->n; j++) {
        int has_diag = 0;
        for (tscvx_int k = ws->P.p[j]; k < ws->P.p[j + 1]; k++) {
            kk->mapP[k] = slot[t++];
            if (ws->P.i[k] == j) has_diag = 1, kk->mapDiag[j] = kk->mapP[k];
        }
        if (!has_diag) kk->mapDiag[j] = slot[t++];
    }
    for (tscvx_int k = 0; k < ws->A.nnz; k++) kk->mapA[k] = slot[t++];
    for (tscvx_int i = 0; i < ws->p; i++) kk->mapDiag[ws->n + i] = slot[t++];
    for (tscvx_int k = 0; k < ws->G.nnz; k++) kk->mapG[k] = slot[t++];
    for (tscvx_int k = 0; k < kk->ncone; k++) kk->mapCone[k] = slot[t++];
}

long tscvx_kkt_build(tscvx_workspace *ws, tscvx_int *tmp) {
    tscvx_kkt *kk = &ws->kkt;
    const tscvx_int nnz = kk->nnz;
    tscvx_int *Ti = tmp, *Tj = Ti + nnz, *slot = Tj + nnz, *work = slot + nnz;

    if (enumerate(ws, Ti, Tj) != nnz) return -1;
    if (order_by_amd(ws, Ti, Tj, work) != 0) return -1;
    permuted_pattern(kk, Ti, Tj, slot, work);
    distribute_slots(ws, slot);
    for (tscvx_int k = 0, e = 0; k < ws->K.nsoc; k++)
        kk->expanded[k] = is_expanded(ws->K.q[k], ws->st.soc_dense_max) ? e++ : -1;
    kk->npos = ws->n + kk->nexp;
    return kk->backend->symbolic(kk, tmp); /* all of tmp is free again */
}

/* ---- values ------------------------------------------------------------------------------ */

void tscvx_kkt_data_values(tscvx_workspace *ws, tscvx_float delta) {
    tscvx_kkt *kk = &ws->kkt;
    const tscvx_int n = ws->n, p = ws->p;
    /* the data part: P + d I, A, -d I, G; the cone block is written per factorization */
    for (tscvx_int k = 0; k < ws->P.nnz; k++) kk->Kx[kk->mapP[k]] = 0.0;
    for (tscvx_int j = 0; j < n; j++) kk->Kx[kk->mapDiag[j]] = 0.0;
    for (tscvx_int k = 0; k < ws->P.nnz; k++) kk->Kx[kk->mapP[k]] += ws->P.x[k];
    for (tscvx_int j = 0; j < n; j++) kk->Kx[kk->mapDiag[j]] += delta;
    for (tscvx_int i = 0; i < p; i++) kk->Kx[kk->mapDiag[n + i]] = -delta;
    for (tscvx_int k = 0; k < ws->A.nnz; k++) kk->Kx[kk->mapA[k]] = ws->A.x[k];
    for (tscvx_int k = 0; k < ws->G.nnz; k++) kk->Kx[kk->mapG[k]] = ws->G.x[k];
    kk->delta = delta; /* removed again by iterative refinement (reg_of) */
    /* |entry|_max of the data part, for the refinement's rounding floor */
    tscvx_float kmax = delta;
    for (tscvx_int j = 0; j < n; j++) kmax = tscvx_max(kmax, fabs(kk->Kx[kk->mapDiag[j]]));
    for (tscvx_int k = 0; k < ws->P.nnz; k++) kmax = tscvx_max(kmax, fabs(kk->Kx[kk->mapP[k]]));
    kmax = tscvx_max_abs(ws->G.x, ws->G.nnz, tscvx_max_abs(ws->A.x, ws->A.nnz, kmax));
    kk->kmax_data = kmax;
}

void tscvx_kkt_cone_values(tscvx_kkt *kk, const tscvx_cones *K, const tscvx_nt *W,
                           tscvx_float delta) {
    const tscvx_int *map = kk->mapCone;
    tscvx_float *Kx = kk->Kx;
    tscvx_int t = 0;
    tscvx_float cmax = 0.0; /* largest |W'W| + d: a diagonal entry of each cone block */
    for (tscvx_int i = 0; i < K->l; i++) {
        const tscvx_float v = W->w[i] * W->w[i] + delta;
        Kx[map[t++]] = -v;
        cmax = v > cmax ? v : cmax;
    }
    for (tscvx_int k = 0; k < K->nsoc; k++) {
        const tscvx_int q = K->q[k];
        const tscvx_float *w = W->w + K->off[k];
        const tscvx_float eta = W->eta[k], eta2 = eta * eta;
        /* largest |entry|: dense block eta^2 (2 wbar0^2 - 1) + d, its head (|wbar1|^2 =
         * wbar0^2 - 1); expansion max(eta^2 + d, sqrt2 eta wbar0) (wbar0 >= 1) */
        const tscvx_float big = kk->expanded[k] < 0 ? eta2 * (2.0 * w[0] * w[0] - 1.0) + delta
                                                    : fmax(eta2 + delta, sqrt(2.0) * eta * w[0]);
        cmax = big > cmax ? big : cmax;
        if (kk->expanded[k] < 0) {
            /* -(W'W) = -eta^2 (2 wbar wbar' - J) */
            for (tscvx_int b = 0; b < q; b++)
                for (tscvx_int a = 0; a <= b; a++) {
                    const tscvx_float J = a != b ? 0.0 : (a == 0 ? 1.0 : -1.0);
                    Kx[map[t++]] = -eta2 * (2.0 * w[a] * w[b] - J) - (a == b ? delta : 0.0);
                }
        } else {
            const tscvx_float r2eta = sqrt(2.0) * eta;
            for (tscvx_int a = 0; a < q; a++) Kx[map[t++]] = -eta2 - delta;
            Kx[map[t++]] = r2eta;
            Kx[map[t++]] = -1.0;
            for (tscvx_int a = 0; a < q; a++) Kx[map[t++]] = r2eta * w[a];
            Kx[map[t++]] = 1.0;
        }
    }
    kk->kmax = fmax(kk->kmax_data, cmax);
    if (kk->nexp > 0) kk->kmax = fmax(kk->kmax, 1.0); /* the expansion pivots -1, +1 */
}

/* ---- solve with iterative refinement ----------------------------------------------------- */

/* res = rhs - (K - reg) x for the stored upper triangle (permuted coordinates), the right-hand
 * side gathered from its three parts (src, len; zero on the expansion rows); returns |res|_inf
 * and writes |x|_inf. */
static tscvx_float kkt_residual(const tscvx_kkt *kk, const tscvx_float *x,
                                const tscvx_float *const src[3], const tscvx_int len[3],
                                tscvx_float *res, tscvx_float *xnorm) {
    const tscvx_float d = kk->delta;
    const tscvx_float unreg[4] = {-d, d, d, 0.0}; /* -(regularization), by KKT_ROW_* */
    const tscvx_int *Kp = kk->Kp, *Ki = kk->Ki;
    const tscvx_float *Kx = kk->Kx;
    const signed char *rowblk = kk->rowblk;
    for (tscvx_int i = 0; i < kk->dim; i++) res[i] = unreg[rowblk[i]] * x[i];
    tscvx_float xn = 0.0;
    for (tscvx_int j = 0; j < kk->dim; j++) {
        const tscvx_float xj = x[j];
        tscvx_float acc = 0.0;
        for (tscvx_int k = Kp[j]; k < Kp[j + 1]; k++) {
            const tscvx_int i = Ki[k];
            const tscvx_float v = Kx[k];
            if (i == j) {
                acc += v * xj;
            } else {
                res[i] += v * xj;
                acc += v * x[i];
            }
        }
        res[j] += acc;
        xn = fabs(xj) > xn ? fabs(xj) : xn;
    }
    *xnorm = xn;
    tscvx_float rn = 0.0;
    const tscvx_int *pv = kk->pinv;
    for (int part = 0; part < 3; part++) {
        const tscvx_float *r = src[part];
        for (tscvx_int i = 0; i < len[part]; i++) {
            const tscvx_int t = pv[i];
            res[t] = r[i] - res[t];
            rn = fabs(res[t]) > rn ? fabs(res[t]) : rn;
        }
        pv += len[part];
    }
    for (tscvx_int i = len[0] + len[1] + len[2]; i < kk->dim; i++) {
        const tscvx_int t = kk->pinv[i];
        res[t] = -res[t];
        rn = fabs(res[t]) > rn ? fabs(res[t]) : rn;
    }
    return rn;
}

int tscvx_kkt_solve(tscvx_kkt *kk, tscvx_int n, tscvx_int p, tscvx_int m,
                    const tscvx_float *rx, const tscvx_float *ry, const tscvx_float *rz,
                    tscvx_float *dx, tscvx_float *dy, tscvx_float *dz, tscvx_int refine_iters) {
    const tscvx_int *pinv = kk->pinv;
    tscvx_float *sol = kk->sol, *res = kk->res;
    tscvx_float bnorm = 0.0;
    const tscvx_float *const src[3] = {rx, ry, rz}; /* read again by the refinement (the
                                                        outputs are written at the end) */
    const tscvx_int len[3] = {n, p, m};
    const tscvx_int *pv = pinv;
    for (int part = 0; part < 3; part++) { /* permute into sol */
        const tscvx_float *r = src[part];
        for (tscvx_int i = 0; i < len[part]; i++) {
            const tscvx_float v = r[i];
            sol[pv[i]] = v;
            bnorm = fabs(v) > bnorm ? fabs(v) : bnorm;
        }
        pv += len[part];
    }
    for (tscvx_int i = n + p + m; i < kk->dim; i++) sol[pinv[i]] = 0.0;
    kk->backend->solve(kk, sol);
    int steps = 0;
    tscvx_float last = INFINITY;
    for (tscvx_int it = 0; it < refine_iters; it++) {
        tscvx_float xnorm;
        const tscvx_float rnorm = kkt_residual(kk, sol, src, len, res, &xnorm);
        if (!isfinite(rnorm)) return -1;
        /* stop when accurate, or when refinement no longer pays */
        if (rnorm <= TSCVX_REFINE_TOL * (1.0 + bnorm) ||
            rnorm <= TSCVX_REFINE_FLOOR * kk->kmax * xnorm || rnorm > TSCVX_REFINE_RATIO * last)
            break;
        last = rnorm;
        kk->backend->solve(kk, res);
        for (tscvx_int i = 0; i < kk->dim; i++) sol[i] += res[i];
        steps++;
    }
    for (tscvx_int i = 0; i < n; i++) dx[i] = sol[pinv[i]];
    for (tscvx_int i = 0; i < p; i++) dy[i] = sol[pinv[n + i]];
    for (tscvx_int i = 0; i < m; i++) dz[i] = sol[pinv[n + p + i]];
    return steps;
}

/* ---- the sparse KKT method --------------------------------------------------------------- */

static int sparse_load(tscvx_workspace *ws) {
    tscvx_kkt_data_values(ws, ws->delta);
    return 0; /* an indefinite P shows, if at all, in the factorization's inertia check */
}

/* Whether P is positive semidefinite to PSD_FACTOR_TOL of its largest entry. The IPM's
 * pivots mix P with the constraint terms (P + G'W^-2 G + ...), so an indefinite P need not
 * show in them; this factors the KKT pattern with A = G = 0 and unit NT scaling,
 *   [P + eps I, 0; 0, -(I + eps I)]   (cone expansions: one +1 and one -1 pivot each),
 * whose inertia check (n + nexp positive pivots) holds iff P + eps I is positive definite
 * (Sylvester's law of inertia). eps = PSD_FACTOR_TOL |P|_max keeps the factor's rounding
 * below its pivots (condition <= 1 / PSD_FACTOR_TOL). Overwrites ws->W and the KKT values:
 * the IPM sets both before it uses them. Returns 0 or -1. */
#define PSD_FACTOR_TOL 1e-9
static int sparse_check_p(tscvx_workspace *ws) {
    const tscvx_float pmax = tscvx_max_abs(ws->P.x, ws->P.nnz, 0.0);
    if (pmax == 0.0) return 0;
    tscvx_kkt *kk = &ws->kkt;
    const tscvx_float eps = PSD_FACTOR_TOL * pmax;
    tscvx_kkt_data_values(ws, eps);
    for (tscvx_int k = 0; k < ws->A.nnz; k++) kk->Kx[kk->mapA[k]] = 0.0;
    for (tscvx_int k = 0; k < ws->G.nnz; k++) kk->Kx[kk->mapG[k]] = 0.0;
    for (tscvx_int i = 0; i < ws->m; i++) ws->W.w[i] = 0.0;
    tscvx_cone_add_identity(&ws->K, ws->W.w, 1.0); /* w = e: W = I */
    for (tscvx_int k = 0; k < ws->K.nsoc; k++) ws->W.eta[k] = 1.0;
    tscvx_kkt_cone_values(kk, &ws->K, &ws->W, eps);
    return kk->backend->numeric(kk);
}

static int sparse_factor(tscvx_workspace *ws) {
    tscvx_kkt_cone_values(&ws->kkt, &ws->K, &ws->W, ws->delta);
    return ws->kkt.backend->numeric(&ws->kkt);
}

static int sparse_solve(tscvx_workspace *ws, const tscvx_float *rx, const tscvx_float *ry,
                        const tscvx_float *rz, tscvx_float *dx, tscvx_float *dy, tscvx_float *dz,
                        tscvx_float *wdz, tscvx_int refine) {
    const int steps = tscvx_kkt_solve(&ws->kkt, ws->n, ws->p, ws->m, rx, ry, rz, dx, dy, dz,
                                      refine);
    tscvx_nt_apply(&ws->K, &ws->W, 0, dz, wdz);
    return steps;
}

const tscvx_kkt_method tscvx_method_sparse = {"sparse-ldl", TSCVX_KKT_STATIC, sparse_load,
                                              sparse_check_p, sparse_factor, sparse_solve};
