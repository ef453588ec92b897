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

static long ldl_backend_symbolic(tscvx_kkt *k) {
    ldl_symbolic(k->dim, k->Kp, k->Ki, k->Lp, k->Parent, k->Lnz, k->Flag, NULL, NULL);
    return (long)k->Lp[k->dim];
}

static int ldl_backend_numeric(tscvx_kkt *k) {
    tscvx_float kmax = 0.0; /* |K|_max for the refinement's rounding floor */
    for (tscvx_int i = 0; i < k->nnz; i++) {
        const tscvx_float v = fabs(k->Kx[i]);
        kmax = v > kmax ? v : kmax;
    }
    k->kmax = kmax;
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
                                         ldl_backend_numeric, ldl_backend_solve};

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
long tscvx_kkt_build(tscvx_workspace *ws, tscvx_int *tmp) {
    tscvx_kkt *kk = &ws->kkt;
    const tscvx_int dim = kk->dim, nnz = kk->nnz;
    tscvx_int *Ti = tmp, *Tj = Ti + nnz, *slot = Tj + nnz;
    tscvx_int *Pe = slot + nnz, *Len = Pe + dim, *Nv = Len + dim, *Next = Nv + dim;
    tscvx_int *Last = Next + dim, *Head = Last + dim, *Elen = Head + dim, *Deg = Elen + dim;
    tscvx_int *Wk = Deg + dim, *Iw = Wk + dim;
    const size_t nz2 = 2 * (size_t)nnz;
    const tscvx_int iwlen = (tscvx_int)(nz2 + nz2 / 5 + 2 * (size_t)dim);

    if (enumerate(ws, Ti, Tj) != nnz) return -1;

    /* AMD on the symmetric pattern without diagonal (amd_2 wants both triangles) */
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
        kk->regsign[k] = (signed char)(i < ws->n ? 1 : (i < ws->n + ws->p + ws->m ? -1 : 0));
    }

    /* permuted upper triangle: entry (i, j) goes to column max(pinv i, pinv j) */
    for (tscvx_int k = 0; k <= dim; k++) kk->Kp[k] = 0;
    for (tscvx_int t = 0; t < nnz; t++) {
        const tscvx_int a = kk->pinv[Ti[t]], b = kk->pinv[Tj[t]];
        kk->Kp[(a > b ? a : b) + 1]++;
    }
    for (tscvx_int k = 0; k < dim; k++) kk->Kp[k + 1] += kk->Kp[k];
    for (tscvx_int k = 0; k < dim; k++) Len[k] = kk->Kp[k];
    for (tscvx_int t = 0; t < nnz; t++) {
        const tscvx_int a = kk->pinv[Ti[t]], b = kk->pinv[Tj[t]];
        const tscvx_int col = a > b ? a : b;
        slot[t] = Len[col]++;
        kk->Ki[slot[t]] = a < b ? a : b;
    }

    /* distribute the slots to the maps, in the order of enumerate() */
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

    for (tscvx_int k = 0, e = 0; k < ws->K.nsoc; k++)
        kk->expanded[k] = is_expanded(ws->K.q[k], ws->st.soc_dense_max) ? e++ : -1;
    kk->npos = ws->n + kk->nexp;
    return kk->backend->symbolic(kk);
}

/* ---- values ------------------------------------------------------------------------------ */

void tscvx_kkt_data_values(tscvx_workspace *ws, tscvx_float delta) {
    tscvx_kkt *kk = &ws->kkt;
    const tscvx_int n = ws->n, p = ws->p;
    /* A and G live in Kx already (written at setup/update); the cone block is written per
     * factorization. Here: P + d I and -d I. */
    for (tscvx_int k = 0; k < ws->P.nnz; k++) kk->Kx[kk->mapP[k]] = 0.0;
    for (tscvx_int j = 0; j < n; j++) kk->Kx[kk->mapDiag[j]] = 0.0;
    for (tscvx_int k = 0; k < ws->P.nnz; k++) kk->Kx[kk->mapP[k]] += ws->P.x[k];
    for (tscvx_int j = 0; j < n; j++) kk->Kx[kk->mapDiag[j]] += delta;
    for (tscvx_int i = 0; i < p; i++) kk->Kx[kk->mapDiag[n + i]] = -delta;
    kk->delta = delta; /* removed again by iterative refinement (reg_of) */
}

void tscvx_kkt_cone_values(tscvx_kkt *kk, const tscvx_cones *K, const tscvx_nt *W,
                           tscvx_float delta) {
    const tscvx_int *map = kk->mapCone;
    tscvx_float *Kx = kk->Kx;
    tscvx_int t = 0;
    for (tscvx_int i = 0; i < K->l; i++) Kx[map[t++]] = -W->w[i] * W->w[i] - delta;
    for (tscvx_int k = 0; k < K->nsoc; k++) {
        const tscvx_int q = K->q[k];
        const tscvx_float *w = W->w + K->off[k];
        const tscvx_float eta = W->eta[k], eta2 = eta * eta;
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
}

/* ---- solve with iterative refinement ----------------------------------------------------- */

/* Refinement stops at |r| <= REFINE_TOL (1 + |rhs|), at the rounding floor
 * |r| <= REFINE_FLOOR |K| |x| (backward stable: nothing left to gain), or when a step gains
 * less than 2x. */
#define REFINE_TOL 1e-10
#define REFINE_FLOOR 1e-15
#define REFINE_RATIO 0.5

/* y = (K - reg) x for the stored upper triangle (permuted coordinates) */
static void kkt_matvec_unreg(const tscvx_kkt *kk, const tscvx_float *x, tscvx_float *y) {
    for (tscvx_int i = 0; i < kk->dim; i++) y[i] = -kk->regsign[i] * kk->delta * x[i];
    for (tscvx_int j = 0; j < kk->dim; j++) {
        const tscvx_float xj = x[j];
        tscvx_float acc = 0.0;
        for (tscvx_int k = kk->Kp[j]; k < kk->Kp[j + 1]; k++) {
            const tscvx_int i = kk->Ki[k];
            const tscvx_float v = kk->Kx[k];
            if (i == j) {
                acc += v * xj;
            } else {
                y[i] += v * xj;
                acc += v * x[i];
            }
        }
        y[j] += acc;
    }
}

int tscvx_kkt_solve(tscvx_kkt *kk, tscvx_int n, tscvx_int p, tscvx_int m,
                    const tscvx_float *rx, const tscvx_float *ry, const tscvx_float *rz,
                    tscvx_float *dx, tscvx_float *dy, tscvx_float *dz, tscvx_int refine_iters) {
    const tscvx_int *pinv = kk->pinv;
    tscvx_float *rhs = kk->rhs, *sol = kk->sol, *res = kk->res;
    for (tscvx_int i = 0; i < n; i++) rhs[pinv[i]] = rx[i];
    for (tscvx_int i = 0; i < p; i++) rhs[pinv[n + i]] = ry[i];
    for (tscvx_int i = 0; i < m; i++) rhs[pinv[n + p + i]] = rz[i];
    for (tscvx_int i = n + p + m; i < kk->dim; i++) rhs[pinv[i]] = 0.0;
    tscvx_float bnorm = 0.0;
    for (tscvx_int i = 0; i < kk->dim; i++) {
        sol[i] = rhs[i];
        if (fabs(rhs[i]) > bnorm) bnorm = fabs(rhs[i]);
    }
    kk->backend->solve(kk, sol);
    int steps = 0;
    tscvx_float last = INFINITY;
    for (tscvx_int it = 0; it < refine_iters; it++) {
        kkt_matvec_unreg(kk, sol, res);
        tscvx_float rnorm = 0.0;
        for (tscvx_int i = 0; i < kk->dim; i++) {
            res[i] = rhs[i] - res[i];
            if (fabs(res[i]) > rnorm) rnorm = fabs(res[i]);
        }
        if (!isfinite(rnorm)) return -1;
        /* stop when accurate, or when refinement no longer pays */
        tscvx_float xnorm = 0.0;
        for (tscvx_int i = 0; i < kk->dim; i++) xnorm = fabs(sol[i]) > xnorm ? fabs(sol[i]) : xnorm;
        if (rnorm <= REFINE_TOL * (1.0 + bnorm) || rnorm <= REFINE_FLOOR * kk->kmax * xnorm ||
            rnorm > REFINE_RATIO * last)
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
