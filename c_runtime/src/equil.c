/* Ruiz equilibration (Ruiz 2001; as in OSQP/Clarabel) of
 *   M = [P A' G'; A 0 0; G 0 0]  ->  S M S,  S = diag(D, EA, EG),
 * by repeated division of each row/column by the square root of its infinity norm, followed
 * by a cost scaling cs (Clarabel's rule): Ps = cs D P D, cs = 1/max(mean |P col|, |D c|_inf).
 * EG is made constant on each SOC so that the scaling maps the cone onto itself.
 * Every factor is rounded to a power of two: scaling is then exact, so a data update brings
 * the kept arrays back to the caller's numbers bit for bit, and a solve gives the same answer
 * whatever updates came before it (with other factors each update's round trip rounded, and
 * the error built up over an SCvx run's updates).
 * Works in place: on entry P, A, G, c, b, h hold the caller's numbers. Computed at setup and
 * again on every data update (tscvx_update_equilibrate): O(ruiz_iters nnz), about 0.5 % of
 * a landing subproblem's solve.
 */
#include <math.h>

#include "socp_internal.h"

static tscvx_float clamp_norm(tscvx_float v) {
    if (!(v > 1e-4)) return v > 0.0 ? 1e-4 : 1.0; /* empty rows/columns stay unscaled */
    return v > 1e4 ? 1e4 : v;
}

/* The power of two nearest to v > 0 on a log scale. */
static tscvx_float pow2_near(tscvx_float v) {
    int e;
    const tscvx_float f = frexp(v, &e); /* v = f 2^e, 0.5 <= f < 1 */
    return ldexp(1.0, f < 0.70710678118654752440 ? e - 1 : e);
}

/* The Ruiz factor of a row or column of infinity norm v: 1/sqrt(v) to a power of two. */
static tscvx_float ruiz_factor(tscvx_float v) { return pow2_near(1.0 / sqrt(clamp_norm(v))); }

void tscvx_equilibrate(tscvx_workspace *ws) {
    const tscvx_int n = ws->n, p = ws->p, m = ws->m;
    tscvx_csc *P = &ws->P, *A = &ws->A, *G = &ws->G;
    tscvx_float *cn = ws->wn, *rnA = ws->ry, *rnG = ws->wm; /* work: column/row norms */
    for (tscvx_int j = 0; j < n; j++) ws->D[j] = 1.0;
    for (tscvx_int i = 0; i < p; i++) ws->EA[i] = 1.0;
    for (tscvx_int i = 0; i < m; i++) ws->EG[i] = 1.0;

    for (tscvx_int it = 0; it < ws->st.ruiz_iters; it++) {
        for (tscvx_int j = 0; j < n; j++) cn[j] = 0.0;
        for (tscvx_int i = 0; i < p; i++) rnA[i] = 0.0;
        for (tscvx_int i = 0; i < m; i++) rnG[i] = 0.0;
        for (tscvx_int j = 0; j < n; j++) {
            for (tscvx_int k = P->p[j]; k < P->p[j + 1]; k++) {
                const tscvx_float v = fabs(P->x[k]);
                if (v > cn[j]) cn[j] = v;
                if (v > cn[P->i[k]]) cn[P->i[k]] = v; /* symmetric part */
            }
            for (tscvx_int k = A->p[j]; k < A->p[j + 1]; k++) {
                const tscvx_float v = fabs(A->x[k]);
                if (v > cn[j]) cn[j] = v;
                if (v > rnA[A->i[k]]) rnA[A->i[k]] = v;
            }
            for (tscvx_int k = G->p[j]; k < G->p[j + 1]; k++) {
                const tscvx_float v = fabs(G->x[k]);
                if (v > cn[j]) cn[j] = v;
                if (v > rnG[G->i[k]]) rnG[G->i[k]] = v;
            }
        }
        for (tscvx_int k = 0; k < ws->K.nsoc; k++) { /* one scale per SOC */
            const tscvx_int o = ws->K.off[k], q = ws->K.q[k];
            tscvx_float mx = 0.0;
            for (tscvx_int i = 0; i < q; i++) mx = rnG[o + i] > mx ? rnG[o + i] : mx;
            for (tscvx_int i = 0; i < q; i++) rnG[o + i] = mx;
        }
        int changed = 0;
        for (tscvx_int j = 0; j < n; j++) changed |= (cn[j] = ruiz_factor(cn[j])) != 1.0;
        for (tscvx_int i = 0; i < p; i++) changed |= (rnA[i] = ruiz_factor(rnA[i])) != 1.0;
        for (tscvx_int i = 0; i < m; i++) changed |= (rnG[i] = ruiz_factor(rnG[i])) != 1.0;
        if (!changed) break; /* balanced to within the rounding to powers of two */
        for (tscvx_int j = 0; j < n; j++) {
            for (tscvx_int k = P->p[j]; k < P->p[j + 1]; k++) P->x[k] *= cn[P->i[k]] * cn[j];
            for (tscvx_int k = A->p[j]; k < A->p[j + 1]; k++) A->x[k] *= rnA[A->i[k]] * cn[j];
            for (tscvx_int k = G->p[j]; k < G->p[j + 1]; k++) G->x[k] *= rnG[G->i[k]] * cn[j];
            ws->D[j] *= cn[j];
        }
        for (tscvx_int i = 0; i < p; i++) ws->EA[i] *= rnA[i];
        for (tscvx_int i = 0; i < m; i++) ws->EG[i] *= rnG[i];
    }

    /* cost scaling */
    tscvx_float cmax = 0.0, pmean = 0.0;
    for (tscvx_int j = 0; j < n; j++) {
        ws->c[j] *= ws->D[j];
        cmax = fmax(cmax, fabs(ws->c[j]));
        cn[j] = 0.0;
    }
    for (tscvx_int j = 0; j < n; j++)
        for (tscvx_int k = P->p[j]; k < P->p[j + 1]; k++) {
            cn[j] = fmax(cn[j], fabs(P->x[k]));
            cn[P->i[k]] = fmax(cn[P->i[k]], fabs(P->x[k]));
        }
    for (tscvx_int j = 0; j < n; j++) pmean += cn[j] / n;
    const tscvx_float scale = fmax(pmean, cmax);
    ws->cs = scale > 0.0 ? pow2_near(1.0 / fmin(fmax(scale, 1e-4), 1e4)) : 1.0;
    for (tscvx_int k = 0; k < P->nnz; k++) P->x[k] *= ws->cs;
    for (tscvx_int j = 0; j < n; j++) ws->c[j] *= ws->cs;
    for (tscvx_int i = 0; i < p; i++) ws->b[i] *= ws->EA[i];
    for (tscvx_int i = 0; i < m; i++) ws->h[i] *= ws->EG[i];
}

/* New numbers (NULL = unchanged), equilibrated afresh: the kept arrays are brought back to
 * the caller's units with the current scaling (exactly: powers of two), the new ones copied,
 * and the whole problem equilibrated again. A scaling computed for other numbers would make
 * the conditioning, and so the stopping point on a flat optimal face, depend on the history
 * of updates. */
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
