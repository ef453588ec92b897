/* Ruiz equilibration (Ruiz 2001; as in OSQP/Clarabel) of
 *   M = [P A' G'; A 0 0; G 0 0]  ->  S M S,  S = diag(D, EA, EG),
 * by repeated division of each row/column by the square root of its infinity norm, followed
 * by a cost scaling cs (Clarabel's rule): Ps = cs D P D, cs = 1/max(mean |P col|, |D c|_inf).
 * EG is made constant on each SOC so that the scaling maps the cone onto itself.
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
        tscvx_float worst = 0.0;
        for (tscvx_int j = 0; j < n; j++) {
            worst = fmax(worst, fabs(1.0 - cn[j]));
            cn[j] = 1.0 / sqrt(clamp_norm(cn[j]));
        }
        for (tscvx_int i = 0; i < p; i++) {
            worst = fmax(worst, fabs(1.0 - rnA[i]));
            rnA[i] = 1.0 / sqrt(clamp_norm(rnA[i]));
        }
        for (tscvx_int i = 0; i < m; i++) {
            worst = fmax(worst, fabs(1.0 - rnG[i]));
            rnG[i] = 1.0 / sqrt(clamp_norm(rnG[i]));
        }
        if (worst < 1e-3) break; /* already balanced */
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
