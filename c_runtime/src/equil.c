/* Ruiz equilibration (Ruiz 2001; as in OSQP/Clarabel) of
 *   M = [P A' G'; A 0 0; G 0 0]  ->  S M S,  S = diag(D, EA, EG),
 * by repeated division of each row/column by the square root of its infinity norm, followed
 * by a cost scaling cs (Clarabel's rule): Ps = cs D P D, cs = 1/max(mean |P col|, |D c|_inf).
 * EG is made constant on each SOC so that the scaling maps the cone onto itself.
 * Works in place: on entry P, A, G, c, b, h hold the caller's numbers. Computed at setup and
 * again on every data update (tscvx_update_equilibrate): O(ruiz_iters nnz); a landing
 * subproblem is balanced in two or three passes, about 0.5 % of its solve (`make budget`'s
 * T-SCvx call, 25 Nov: 20.8 M of 4,301 M instructions).
 */
#include <math.h>

#include "socp_internal.h"

static tscvx_float clamp_norm(tscvx_float v) {
    if (!(v > 1e-4)) return v > 0.0 ? 1e-4 : 1.0; /* empty rows/columns stay unscaled */
    return v > 1e4 ? 1e4 : v;
}

/* One traversal of M: each entry is multiplied by rs[row] cs[col] (unless rs is NULL), then
 * folded into the infinity norms of its column (cn) and row (rn; P passes rn = cn, its
 * symmetric part). Ruiz pass t's scaling and pass t + 1's norms share it. */
static void scale_and_norms(tscvx_csc *M, const tscvx_float *rs, const tscvx_float *cs,
                            tscvx_float *cn, tscvx_float *rn) {
    for (tscvx_int j = 0; j < M->ncol; j++) {
        tscvx_float cj = 0.0;
        for (tscvx_int k = M->p[j]; k < M->p[j + 1]; k++) {
            const tscvx_int i = M->i[k];
            if (rs) M->x[k] *= rs[i] * cs[j];
            const tscvx_float v = fabs(M->x[k]);
            cj = tscvx_max(cj, v);
            rn[i] = tscvx_max(rn[i], v);
        }
        cn[j] = tscvx_max(cn[j], cj);
    }
}

/* The last pass: scaling only. */
static void scale_only(tscvx_csc *M, const tscvx_float *rs, const tscvx_float *cs) {
    for (tscvx_int j = 0; j < M->ncol; j++)
        for (tscvx_int k = M->p[j]; k < M->p[j + 1]; k++) M->x[k] *= rs[M->i[k]] * cs[j];
}

/* Norms -> factors 1/sqrt(norm) in place; returns max(worst, largest |1 - norm|) over the
 * nonempty rows/columns. An empty one stays unscaled and cannot be balanced: counting it
 * would run every pass (T-SCvx's masked-out cones are empty rows). */
static tscvx_float norms_to_factors(tscvx_float *v, tscvx_int len, tscvx_float worst) {
    for (tscvx_int i = 0; i < len; i++) {
        if (v[i] > 0.0) worst = tscvx_max(worst, fabs(1.0 - v[i]));
        v[i] = 1.0 / sqrt(clamp_norm(v[i]));
    }
    return worst;
}

static void zero(tscvx_float *v, tscvx_int len) {
    for (tscvx_int i = 0; i < len; i++) v[i] = 0.0;
}

/* One Ruiz pass's column and A/G row vectors: norms, then factors. */
typedef struct {
    tscvx_float *col, *rowA, *rowG;
} ruiz_vectors;

/* nrm := the column and A/G row norms of the numbers, after scaling them by f's factors
 * when f is not NULL. */
static void pass(tscvx_workspace *ws, const ruiz_vectors *f, const ruiz_vectors *nrm) {
    zero(nrm->col, ws->n), zero(nrm->rowA, ws->p), zero(nrm->rowG, ws->m);
    scale_and_norms(&ws->P, f ? f->col : NULL, f ? f->col : NULL, nrm->col, nrm->col);
    scale_and_norms(&ws->A, f ? f->rowA : NULL, f ? f->col : NULL, nrm->col, nrm->rowA);
    scale_and_norms(&ws->G, f ? f->rowG : NULL, f ? f->col : NULL, nrm->col, nrm->rowG);
    for (tscvx_int k = 0; k < ws->K.nsoc; k++) { /* one scale per SOC maps it onto itself */
        const tscvx_int o = ws->K.off[k], q = ws->K.q[k];
        tscvx_float mx = 0.0;
        for (tscvx_int i = 0; i < q; i++) mx = tscvx_max(mx, nrm->rowG[o + i]);
        for (tscvx_int i = 0; i < q; i++) nrm->rowG[o + i] = mx;
    }
}

void tscvx_equilibrate(tscvx_workspace *ws) {
    const tscvx_int n = ws->n, p = ws->p, m = ws->m;
    tscvx_csc *P = &ws->P;
    /* work (the iterates' vectors are free between solves): norms of one pass beside the
     * factors of the one before */
    ruiz_vectors u = {ws->wn, ws->ry, ws->wm}, v = {ws->rx, ws->wp, ws->wm2};
    ruiz_vectors *f = &u, *nrm = &v;
    tscvx_float *cn = ws->wn;
    for (tscvx_int j = 0; j < n; j++) ws->D[j] = 1.0;
    for (tscvx_int i = 0; i < p; i++) ws->EA[i] = 1.0;
    for (tscvx_int i = 0; i < m; i++) ws->EG[i] = 1.0;

    if (ws->st.ruiz_iters > 0) pass(ws, NULL, f); /* the norms of the caller's numbers */
    ws->info.ruiz_passes = 0;
    for (tscvx_int it = 0; it < ws->st.ruiz_iters; it++) {
        /* f: the norms of the current numbers, turned into this pass's factors */
        tscvx_float worst = norms_to_factors(f->col, n, 0.0);
        worst = norms_to_factors(f->rowA, p, worst);
        worst = norms_to_factors(f->rowG, m, worst);
        if (worst < 1e-3) break; /* already balanced */
        if (it + 1 < ws->st.ruiz_iters) {
            pass(ws, f, nrm); /* scale, and the next pass's norms */
        } else {
            scale_only(P, f->col, f->col), scale_only(&ws->A, f->rowA, f->col);
            scale_only(&ws->G, f->rowG, f->col);
        }
        for (tscvx_int j = 0; j < n; j++) ws->D[j] *= f->col[j];
        for (tscvx_int i = 0; i < p; i++) ws->EA[i] *= f->rowA[i];
        for (tscvx_int i = 0; i < m; i++) ws->EG[i] *= f->rowG[i];
        ws->info.ruiz_passes = it + 1;
        ruiz_vectors *t = f;
        f = nrm, nrm = t;
    }

    /* cost scaling */
    tscvx_float cmax = 0.0, pmean = 0.0;
    for (tscvx_int j = 0; j < n; j++) {
        ws->c[j] *= ws->D[j];
        cmax = tscvx_max(cmax, fabs(ws->c[j]));
        cn[j] = 0.0;
    }
    for (tscvx_int j = 0; j < n; j++)
        for (tscvx_int k = P->p[j]; k < P->p[j + 1]; k++) {
            cn[j] = tscvx_max(cn[j], fabs(P->x[k]));
            cn[P->i[k]] = tscvx_max(cn[P->i[k]], fabs(P->x[k]));
        }
    for (tscvx_int j = 0; j < n; j++) pmean += cn[j] / n;
    const tscvx_float scale = fmax(pmean, cmax);
    ws->cs = scale > 0.0 ? 1.0 / fmin(fmax(scale, 1e-4), 1e4) : 1.0;
    for (tscvx_int k = 0; k < P->nnz; k++) P->x[k] *= ws->cs;
    for (tscvx_int j = 0; j < n; j++) ws->c[j] *= ws->cs;
    for (tscvx_int i = 0; i < p; i++) ws->b[i] *= ws->EA[i];
    for (tscvx_int i = 0; i < m; i++) ws->h[i] *= ws->EG[i];
}

/* New numbers (NULL = unchanged), equilibrated afresh: the kept arrays are brought back to
 * the caller's units with the current scaling, the new ones copied, and the whole problem
 * equilibrated again. A scaling computed for other numbers would make the conditioning, and
 * so the stopping point on a flat optimal face, depend on the history of updates. */
void tscvx_update_equilibrate(tscvx_workspace *ws, const tscvx_float *Px, const tscvx_float *c,
                              const tscvx_float *Ax, const tscvx_float *b,
                              const tscvx_float *Gx, const tscvx_float *h) {
    const tscvx_float *D = ws->D;
    for (tscvx_int j = 0; j < ws->n; j++) {
        for (tscvx_int k = ws->P.p[j]; k < ws->P.p[j + 1]; k++)
            ws->P.x[k] = Px ? Px[k] : ws->P.x[k] / (ws->cs * D[ws->P.i[k]] * D[j]);
        for (tscvx_int k = ws->A.p[j]; k < ws->A.p[j + 1]; k++)
            ws->A.x[k] = Ax ? Ax[k] : ws->A.x[k] / (ws->EA[ws->A.i[k]] * D[j]);
        for (tscvx_int k = ws->G.p[j]; k < ws->G.p[j + 1]; k++)
            ws->G.x[k] = Gx ? Gx[k] : ws->G.x[k] / (ws->EG[ws->G.i[k]] * D[j]);
        ws->c[j] = c ? c[j] : ws->c[j] / (ws->cs * D[j]);
    }
    for (tscvx_int i = 0; i < ws->p; i++) ws->b[i] = b ? b[i] : ws->b[i] / ws->EA[i];
    for (tscvx_int i = 0; i < ws->m; i++) ws->h[i] = h ? h[i] : ws->h[i] / ws->EG[i];
    tscvx_equilibrate(ws);
}
