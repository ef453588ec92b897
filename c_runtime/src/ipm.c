/* Primal-dual interior-point method on the homogeneous self-dual embedding.
 *
 * Embedding (ECOS, extended with the quadratic objective as in Clarabel, Goulart & Chen 2024):
 *   rx = P x + A'y + G'z + c tau = 0          s in K, z in K, tau >= 0, kappa >= 0
 *   ry = A x - b tau = 0
 *   rz = G x + s - h tau = 0
 *   rtau = kappa + c'x + b'y + h'z + x'Px/tau = 0
 * tau > 0, kappa = 0 at a solution (x/tau, ...); tau = 0, kappa > 0 gives an infeasibility
 * certificate. Each iteration: Nesterov-Todd scaling, one factorization of
 *   K = [P A' G'; A 0 0; G 0 -W'W],
 * the constant solve K (x1, y1, z1) = (-c, b, h), and two Newton solves (Mehrotra
 * predictor-corrector) of
 *   K (x2, y2, z2) = (-dx, -dy, -dz + W (lambda \ ds)),
 *   dtau from the tau row, (dx, dy, dz) = (x2, y2, z2) + dtau (x1, y1, z1),
 *   ds = -W (lambda \ ds + W dz),  dkappa = -(dk + kappa dtau)/tau,
 * with the affine targets (d = r, ds = lambda o lambda, dk = tau kappa) and the combined ones
 * (d = (1-sigma) r, ds = lambda o lambda + (W^{-1} ds_a) o (W dz_a) - sigma mu e,
 *  dk = tau kappa + dtau_a dkappa_a - sigma mu), sigma = (1 - alpha_a)^3.
 */
#include <float.h>
#include <math.h>

#include "socp_internal.h"


/* ---- small dense/sparse kernels ---------------------------------------------------------- */

/* |u ./ s|_inf (undo a diagonal scaling) */
static tscvx_float vnorm_inf_div(const tscvx_float *u, const tscvx_float *s, tscvx_int n) {
    tscvx_float r = 0.0;
    for (tscvx_int i = 0; i < n; i++) {
        const tscvx_float v = fabs(u[i] / s[i]);
        r = v > r ? v : r;
    }
    return r;
}

static void vcopy(tscvx_float *dst, const tscvx_float *src, tscvx_int n) {
    for (tscvx_int i = 0; i < n; i++) dst[i] = src[i];
}

/* Both products of M in one pass over its entries: yt += M' u  and  y += M x. */
void tscvx_spmv_both(const tscvx_csc *M, const tscvx_float *u, tscvx_float *yt,
                     const tscvx_float *x, tscvx_float *y) {
    for (tscvx_int j = 0; j < M->ncol; j++) {
        const tscvx_float xj = x[j];
        tscvx_float acc = 0.0;
        for (tscvx_int k = M->p[j]; k < M->p[j + 1]; k++) {
            const tscvx_int i = M->i[k];
            const tscvx_float v = M->x[k];
            acc += v * u[i];
            y[i] += v * xj;
        }
        yt[j] += acc;
    }
}

/* yt += M' u */
static void spmv_t(const tscvx_csc *M, const tscvx_float *u, tscvx_float *yt) {
    for (tscvx_int j = 0; j < M->ncol; j++) {
        tscvx_float acc = 0.0;
        for (tscvx_int k = M->p[j]; k < M->p[j + 1]; k++) acc += M->x[k] * u[M->i[k]];
        yt[j] += acc;
    }
}

/* y += M x */
static void spmv_n(const tscvx_csc *M, const tscvx_float *x, tscvx_float *y) {
    for (tscvx_int j = 0; j < M->ncol; j++)
        for (tscvx_int k = M->p[j]; k < M->p[j + 1]; k++) y[M->i[k]] += M->x[k] * x[j];
}

/* y = P x, P symmetric given by its upper triangle */
void tscvx_spmv_sym(const tscvx_csc *P, const tscvx_float *x, tscvx_float *y) {
    for (tscvx_int j = 0; j < P->ncol; j++) y[j] = 0.0;
    for (tscvx_int j = 0; j < P->ncol; j++)
        for (tscvx_int k = P->p[j]; k < P->p[j + 1]; k++) {
            const tscvx_int i = P->i[k];
            y[i] += P->x[k] * x[j];
            if (i != j) y[j] += P->x[k] * x[i];
        }
}

/* ---- residuals and convergence measures -------------------------------------------------- */

typedef struct {
    tscvx_float pcost, dcost, gap_abs, gap_rel, pres, dres, mu;
} measures;

/* rx, ry, rz, rtau of the embedding at the current iterate; Px = P x. */
static void residuals(tscvx_workspace *ws) {
    const tscvx_int n = ws->n, p = ws->p, m = ws->m;
    const tscvx_float tau = ws->tau;
    tscvx_spmv_sym(&ws->P, ws->x, ws->Px);
    for (tscvx_int j = 0; j < n; j++) ws->rx[j] = ws->Px[j] + ws->c[j] * tau;
    for (tscvx_int i = 0; i < p; i++) ws->ry[i] = -ws->b[i] * tau;
    for (tscvx_int i = 0; i < m; i++) ws->rz[i] = ws->s[i] - ws->h[i] * tau;
    tscvx_spmv_both(&ws->A, ws->y, ws->rx, ws->x, ws->ry); /* rx += A'y, ry += A x */
    tscvx_spmv_both(&ws->G, ws->z, ws->rx, ws->x, ws->rz); /* rx += G'z, rz += G x */
    const tscvx_float xPx = tscvx_dot(ws->x, ws->Px, n);
    ws->rtau = ws->kappa + tscvx_dot(ws->c, ws->x, n) + tscvx_dot(ws->b, ws->y, p) +
               tscvx_dot(ws->h, ws->z, m) + xPx / tau;
}

/* Residuals and objectives of (x, y, z, s)/tau in the ORIGINAL units (undo Ruiz and cs). */
static measures measure(tscvx_workspace *ws) {
    const tscvx_int n = ws->n, p = ws->p, m = ws->m;
    const tscvx_float tau = ws->tau, cs = ws->cs;
    measures r;
    const tscvx_float xPx = tscvx_dot(ws->x, ws->Px, n) / (tau * tau);
    r.pcost = (0.5 * xPx + tscvx_dot(ws->c, ws->x, n) / tau) / cs;
    r.dcost = (-0.5 * xPx - (tscvx_dot(ws->b, ws->y, p) + tscvx_dot(ws->h, ws->z, m)) / tau) / cs;
    r.gap_abs = fabs(r.pcost - r.dcost);
    r.gap_rel = r.gap_abs / fmax(1.0, fmin(fabs(r.pcost), fabs(r.dcost)));
    const tscvx_float pa = vnorm_inf_div(ws->ry, ws->EA, p) / tau / (1.0 + ws->norm_b);
    const tscvx_float pg = vnorm_inf_div(ws->rz, ws->EG, m) / tau / (1.0 + ws->norm_h);
    r.pres = fmax(pa, pg);
    r.dres = vnorm_inf_div(ws->rx, ws->D, n) / cs / tau / (1.0 + ws->norm_c);
    r.mu = (tscvx_dot(ws->s, ws->z, m) + tau * ws->kappa) / (ws->K.degree + 1);
    return r;
}

/* The primal residual at the rounding of its own terms. pres is normalized by the data,
 * 1 + |b| or 1 + |h|; a residual is the sum of its row's terms (A x - b tau, G x + s - h tau),
 * whose rounding is some ulps of the sum of their magnitudes. Where the answer is large
 * against b (one h entry of 1e14 with the constraint active: x near 1e13, equality rows with
 * b of 1), that rounding alone is 1e-3 of 1 + |b|: no iterate could meet tol_feas, and such
 * problems, solved by Clarabel (whose residuals are relative to |x| too), ended
 * NUMERICAL_ERROR, or SOLVED_INACCURATE from h of 1e10 on. A residual within ROUNDING_ULPS
 * ulps of its row's terms is zero as far as double precision can tell (x solves a problem
 * whose A, b, G, h differ from the caller's by that many ulps): it counts as met. The ratio
 * is the same in the scaled arrays (a diagonal scaling), up to rounding. Worst ratio over
 * the rows, NaN if any is; uses wp and wm. */
#define ROUNDING_ULPS 16.0
static tscvx_float ratio_to_terms(tscvx_float r, tscvx_float terms) {
    return terms > 0.0 ? fabs(r) / (terms * DBL_EPSILON) : (r == 0.0 ? 0.0 : HUGE_VAL);
}

static tscvx_float primal_rounding(tscvx_workspace *ws) {
    const tscvx_int n = ws->n, p = ws->p, m = ws->m;
    tscvx_float *ta = ws->wp, *tg = ws->wm, worst = 0.0;
    for (tscvx_int i = 0; i < p; i++) ta[i] = fabs(ws->b[i] * ws->tau);
    for (tscvx_int i = 0; i < m; i++) tg[i] = fabs(ws->s[i]) + fabs(ws->h[i] * ws->tau);
    for (tscvx_int j = 0; j < n; j++) {
        const tscvx_float xj = fabs(ws->x[j]);
        for (tscvx_int k = ws->A.p[j]; k < ws->A.p[j + 1]; k++)
            ta[ws->A.i[k]] += fabs(ws->A.x[k]) * xj;
        for (tscvx_int k = ws->G.p[j]; k < ws->G.p[j + 1]; k++)
            tg[ws->G.i[k]] += fabs(ws->G.x[k]) * xj;
    }
    for (tscvx_int i = 0; i < p + m; i++) {
        const tscvx_float v = i < p ? ratio_to_terms(ws->ry[i], ta[i])
                                    : ratio_to_terms(ws->rz[i - p], tg[i - p]);
        if (!(v <= worst)) worst = v; /* NaN stays NaN */
    }
    return worst;
}

/* pres, dres and the gap within the tolerances (pres: or at rounding, primal_rounding,
 * evaluated only when the rest is met) */
static int converged(tscvx_workspace *ws, const measures *r, int reduced) {
    const tscvx_settings *st = &ws->st;
    const tscvx_float feas = reduced ? st->tol_feas_inacc : st->tol_feas;
    const tscvx_float ga = reduced ? st->tol_gap_abs_inacc : st->tol_gap_abs;
    const tscvx_float gr = reduced ? st->tol_gap_rel_inacc : st->tol_gap_rel;
    if (!(r->dres <= feas && (r->gap_abs <= ga || r->gap_rel <= gr))) return 0;
    return r->pres <= feas || primal_rounding(ws) <= ROUNDING_ULPS;
}

/* A certificate is judged against the data it is made of. Normalized to a unit objective
 * (c'x = -1, say), a direction's residual |Ax| is small whenever c is large against A, whether
 * or not the direction lies in the recession cone: with costs of 1e8 (a penalty weight), or
 * constraint rows of 1e-10, directions whose residual was as large as themselves passed, on
 * feasible, bounded problems. So the residual relative to the constraint data, |Ax| / |A, G|,
 * is held against the descent relative to the objective's data, -c'x / |c| (for the primal
 * certificate, -(b'y + h'z) / |b, h|): the plain test times this factor. It never loosens the
 * plain test; a problem whose objective is no larger than its constraints sees no change. */
static tscvx_float certificate_factor(const tscvx_workspace *ws, tscvx_float objective_norm) {
    const tscvx_float constraints = fmax(ws->norm_A, ws->norm_G);
    return objective_norm > constraints ? constraints / objective_norm : 1.0;
}

/* The certificate tscvx_unscale_solution would return is finite: its normalization (b'y + h'z
 * = -1, or c'x = -1) divides by the certificate's objective, which for data near the bottom
 * of the double range (b = DBL_MIN: make fuzz) can be so small that the normalized numbers
 * overflow. Such a direction is no certificate the caller can use: the solve goes on (and
 * ends as the iterations decide). The same products as tscvx_unscale_solution. */
static int certificate_finite(const tscvx_workspace *ws, int primal) {
    if (primal) {
        const tscvx_float pd =
            -1.0 / (tscvx_dot(ws->b, ws->y, ws->p) + tscvx_dot(ws->h, ws->z, ws->m));
        if (!isfinite(pd)) return 0;
        for (tscvx_int i = 0; i < ws->p; i++)
            if (!isfinite(ws->EA[i] * ws->y[i] * pd)) return 0;
        for (tscvx_int i = 0; i < ws->m; i++)
            if (!isfinite(ws->EG[i] * ws->z[i] * pd)) return 0;
        return 1;
    }
    const tscvx_float px = -ws->cs / tscvx_dot(ws->c, ws->x, ws->n);
    if (!isfinite(px)) return 0;
    for (tscvx_int j = 0; j < ws->n; j++)
        if (!isfinite(ws->D[j] * ws->x[j] * px)) return 0;
    for (tscvx_int i = 0; i < ws->m; i++)
        if (!isfinite(ws->s[i] / ws->EG[i] * px)) return 0;
    return 1;
}

/* Primal infeasibility: |A'y + G'z| <= tol (-(b'y + h'z)) f, f = certificate_factor, original
 * units, kappa > tau; and the normalized certificate finite. */
static int primal_infeasible(tscvx_workspace *ws) {
    const tscvx_int n = ws->n;
    const tscvx_float rho = -(tscvx_dot(ws->b, ws->y, ws->p) + tscvx_dot(ws->h, ws->z, ws->m)) / ws->cs;
    if (!(rho > 0.0) || !(ws->kappa > ws->tau)) return 0;
    /* A'y + G'z (scaled), from the data: as rx - Px - c tau it kept nothing of itself where
     * Px or c tau dominate (P = 1e135: make fuzz, test_certificate_cancellation) */
    tscvx_float *aty = ws->wn;
    for (tscvx_int j = 0; j < n; j++) aty[j] = 0.0;
    spmv_t(&ws->A, ws->y, aty);
    spmv_t(&ws->G, ws->z, aty);
    const tscvx_float f = certificate_factor(ws, fmax(ws->norm_b, ws->norm_h));
    return vnorm_inf_div(aty, ws->D, n) / ws->cs <= ws->st.tol_infeas * rho * f &&
           certificate_finite(ws, 1);
}

/* Dual infeasibility: |Ax|, |Gx + s| <= tol (-c'x) f (f = certificate_factor) and
 * |Px| <= max(that, tol |P| |x|) (x in the null space of a P perturbed by tol |P|), original
 * units, kappa > tau; and the normalized certificate finite. */
static int dual_infeasible(tscvx_workspace *ws) {
    const tscvx_int n = ws->n, p = ws->p, m = ws->m;
    const tscvx_float rho = -tscvx_dot(ws->c, ws->x, n) / ws->cs;
    if (!(rho > 0.0) || !(ws->kappa > ws->tau)) return 0;
    const tscvx_float tol = ws->st.tol_infeas * rho * certificate_factor(ws, ws->norm_c);
    tscvx_float r = 0.0, xnorm = 0.0;
    /* Ax and Gx + s (scaled) from the data: as ry + b tau and rz + h tau they kept nothing of
     * themselves where b tau or h tau dominate (make fuzz: A x = DBL_MIN x beside b = 2.5) */
    tscvx_float *ax = ws->wp, *gxs = ws->wm;
    for (tscvx_int i = 0; i < p; i++) ax[i] = 0.0;
    for (tscvx_int i = 0; i < m; i++) gxs[i] = ws->s[i];
    spmv_n(&ws->A, ws->x, ax);
    spmv_n(&ws->G, ws->x, gxs);
    for (tscvx_int i = 0; i < p; i++) r = tscvx_max(r, fabs(ax[i] / ws->EA[i]));
    for (tscvx_int i = 0; i < m; i++) r = tscvx_max(r, fabs(gxs[i] / ws->EG[i]));
    for (tscvx_int j = 0; j < n; j++) xnorm = tscvx_max(xnorm, fabs(ws->D[j] * ws->x[j]));
    const tscvx_float px = vnorm_inf_div(ws->Px, ws->D, n) / ws->cs;
    return r <= tol && px <= fmax(tol, ws->st.tol_infeas * ws->norm_P * xnorm) &&
           certificate_finite(ws, 0);
}

/* ---- output ------------------------------------------------------------------------------ */

/* (x, y, z, s) in original units: x = D x/tau, y = EA y/(cs tau), z = EG z/(cs tau),
 * s = s/(EG tau). Certificates are normalized instead: b'y + h'z = -1 (primal infeasible,
 * x and s NaN) or c'x = -1 (dual infeasible, y and z NaN). Any output may be NULL. */
void tscvx_unscale_solution(const tscvx_workspace *ws, tscvx_float *x, tscvx_float *y,
                            tscvx_float *z, tscvx_float *s) {
    const tscvx_int n = ws->n, p = ws->p, m = ws->m;
    tscvx_float px = 1.0 / ws->tau, pd = 1.0 / (ws->tau * ws->cs);
    if (ws->info.status == TSCVX_PRIMAL_INFEASIBLE) {
        px = NAN;
        pd = -1.0 / (tscvx_dot(ws->b, ws->y, p) + tscvx_dot(ws->h, ws->z, m));
    } else if (ws->info.status == TSCVX_DUAL_INFEASIBLE) {
        px = -ws->cs / tscvx_dot(ws->c, ws->x, n);
        pd = NAN;
    }
    for (tscvx_int j = 0; x && j < n; j++) x[j] = ws->D[j] * ws->x[j] * px;
    for (tscvx_int i = 0; y && i < p; i++) y[i] = ws->EA[i] * ws->y[i] * pd;
    for (tscvx_int i = 0; z && i < m; i++) z[i] = ws->EG[i] * ws->z[i] * pd;
    for (tscvx_int i = 0; s && i < m; i++) s[i] = ws->s[i] / ws->EG[i] * px;
}

/* The best iterate: the smallest worst ratio to the tolerances,
 *   max(max(pres, dres) / tol_feas, min(gap_abs / tol_gap_abs, gap_abs / (g tol_gap_rel))),
 * with both candidates' gaps made relative to one yardstick g = max(1, min(|pcost|, |dcost|))
 * of the CURRENT iterate (the latest estimate of the objective's size), not each to its own.
 * Each to its own (until 28 Nov) rewarded iterates whose costs were far off: an early
 * iterate's costs in the hundreds made its relative gap about 1, which beat a later one whose
 * residuals, gap and objective were 10 to 100 times closer to the answer but whose costs
 * (near the optimum's) were smaller. Stopped at max_iter 4, subproblem 7 of the default
 * landing returned iterate 2, 118 times as far from Clarabel's answer as iterate 4
 * (tests/test_socp_bindings.py, test_iteration_limit_*). Near an answer the two yardsticks
 * agree, and the rule still keeps the best of the last iterates when rounding makes them
 * worse (tolerances below what the arithmetic reaches). */
static tscvx_float merit(const tscvx_workspace *ws, tscvx_float feas, tscvx_float gap_abs,
                         tscvx_float g) {
    const tscvx_settings *st = &ws->st;
    return fmax(feas / st->tol_feas, fmin(gap_abs / st->tol_gap_abs, gap_abs / g / st->tol_gap_rel));
}

/* Saves the current iterate as the best one if it is (or none is saved yet). */
static void update_best(tscvx_workspace *ws, const measures *r, tscvx_int k) {
    const tscvx_float feas = fmax(r->pres, r->dres);
    const tscvx_float g = fmax(1.0, fmin(fabs(r->pcost), fabs(r->dcost)));
    if (ws->best_iter >= 0 && !(merit(ws, feas, r->gap_abs, g) < merit(ws, ws->bfeas, ws->bgap, g)))
        return;
    vcopy(ws->bx, ws->x, ws->n);
    vcopy(ws->by, ws->y, ws->p);
    vcopy(ws->bz, ws->z, ws->m);
    vcopy(ws->bs, ws->s, ws->m);
    ws->btau = ws->tau, ws->bkappa = ws->kappa, ws->best_iter = k;
    ws->bfeas = feas, ws->bgap = r->gap_abs;
}

static void restore_best(tscvx_workspace *ws) {
    vcopy(ws->x, ws->bx, ws->n);
    vcopy(ws->y, ws->by, ws->p);
    vcopy(ws->z, ws->bz, ws->m);
    vcopy(ws->s, ws->bs, ws->m);
    ws->tau = ws->btau, ws->kappa = ws->bkappa;
}

/* ---- factorization and Newton directions ------------------------------------------------- */

/* Factor with the current NT scaling; on a bad pivot raise the regularization (bounded). */
static int factor(tscvx_workspace *ws) {
    for (int attempt = 0; attempt < 4; attempt++) {
        ws->info.factorizations++;
        if (ws->method->factor(ws) == 0) return 0;
        ws->delta *= 100.0;
        if (ws->method->load(ws) != 0) return -1;
    }
    return -1;
}

/* The constant system K (x1, y1, z1) = (-c, b, h) and the tau-row coefficient
 *   den = -kappa/tau + xi'x1 + b'y1 + h'z1 - xhat'P xhat,  xi = c + 2 P xhat, xhat = x/tau.
 * (The equivalent -(kappa/tau + |x1 - xhat|_P^2 + |W z1|^2) is exact only for exact solves;
 * the direct form shares its rounding errors with the numerator, which cancel in dtau.)
 * Refined only where it weighs: it enters each direction as dtau (x1, y1, z1), small while
 * tau converges (near a solution the primal-row error that matters is caught on the whole
 * direction, in direction()), dominant once tau collapses towards a certificate (kappa > tau).
 * The sparse SOC expansion's solves always need it, as in the predictor. Saves 6 % of a
 * guidance call; the cost, where within its tolerances the IPM stops depends more on
 * rounding, is measured in docs/socp-runtime.md. */
static int constant_solve(tscvx_workspace *ws) {
    const tscvx_int n = ws->n, m = ws->m;
    const tscvx_float tau = ws->tau;
    for (tscvx_int j = 0; j < n; j++) ws->wn[j] = -ws->c[j];
    const tscvx_int refine = ws->kkt.nexp > 0 || ws->kappa > tau ? ws->refine_now : 0;
    if (ws->method->solve(ws, ws->wn, ws->b, ws->h, ws->x1, ws->y1, ws->z1, ws->wz1, refine) < 0)
        return -1;
    tscvx_float den = -ws->kappa / tau + tscvx_dot(ws->b, ws->y1, ws->p) + tscvx_dot(ws->h, ws->z1, m);
    for (tscvx_int j = 0; j < n; j++)
        den += (ws->c[j] + 2.0 * ws->Px[j] / tau) * ws->x1[j] - ws->x[j] * ws->Px[j] / (tau * tau);
    ws->tau_den = den;
    return isfinite(den) && den != 0.0 ? 0 : -1;
}

/* (dx, dy, dz, wdz) := the solve for (x2, y2, z2) plus dtau (x1, y1, z1) with dtau from the
 * tau row, dtau (-kappa/tau + xi'x1 + b'y1 + h'z1 - x'Px/tau^2) = num0 - xi'x2 - b'y2 - h'z2,
 * xi = c + 2 P x/tau. Returns dtau. */
static tscvx_float add_tau_part(tscvx_workspace *ws, tscvx_float num0, tscvx_float *dx,
                                tscvx_float *dy, tscvx_float *dz, tscvx_float *wdz) {
    const tscvx_int n = ws->n, p = ws->p, m = ws->m;
    tscvx_float num = num0;
    for (tscvx_int j = 0; j < n; j++) num -= (ws->c[j] + 2.0 * ws->Px[j] / ws->tau) * dx[j];
    num -= tscvx_dot(ws->b, dy, p) + tscvx_dot(ws->h, dz, m);
    const tscvx_float dtau = num / ws->tau_den;
    for (tscvx_int j = 0; j < n; j++) dx[j] += dtau * ws->x1[j];
    for (tscvx_int i = 0; i < p; i++) dy[i] += dtau * ws->y1[i];
    for (tscvx_int i = 0; i < m; i++) dz[i] += dtau * ws->z1[i], wdz[i] += dtau * ws->wz1[i];
    return dtau;
}

/* Error of the direction in the primal row, e = G dx + ds - h dtau + lin rz, into ws->e;
 * returns max |e_i / EG_i| (original units). */
static tscvx_float primal_row_error(tscvx_workspace *ws, tscvx_float lin) {
    const tscvx_int n = ws->n, m = ws->m;
    tscvx_float *e = ws->e, emax = 0.0;
    for (tscvx_int i = 0; i < m; i++) e[i] = ws->ds[i] - ws->h[i] * ws->dtau + lin * ws->rz[i];
    for (tscvx_int j = 0; j < n; j++) {
        const tscvx_float dxj = ws->dx[j];
        for (tscvx_int k = ws->G.p[j]; k < ws->G.p[j + 1]; k++) e[ws->G.i[k]] += ws->G.x[k] * dxj;
    }
    for (tscvx_int i = 0; i < m; i++) emax = tscvx_max(emax, fabs(e[i] / ws->EG[i]));
    return emax;
}

/* Newton direction for linear targets lin*(rx, ry, rz, rtau), complementarity target dsv
 * (m; may be wm2, it is consumed first) and dk, with up to `refine` refinement steps.
 * Result in dx, dy, dz, ds, dtau, dkappa (and wdz = W dz). */
static int direction(tscvx_workspace *ws, tscvx_float lin, const tscvx_float *dsv,
                     tscvx_float dk, tscvx_int refine) {
    const tscvx_int n = ws->n, p = ws->p, m = ws->m;
    tscvx_float *wlds = ws->ds; /* W (lambda \ ds), until ds is written at the end */
    tscvx_nt_div_apply(&ws->K, &ws->W, ws->lambda, dsv, ws->wm2, wlds);
    for (tscvx_int j = 0; j < n; j++) ws->wn[j] = -lin * ws->rx[j];
    for (tscvx_int i = 0; i < p; i++) ws->wp[i] = -lin * ws->ry[i];
    for (tscvx_int i = 0; i < m; i++) ws->wm[i] = -lin * ws->rz[i] + wlds[i];
    if (ws->method->solve(ws, ws->wn, ws->wp, ws->wm, ws->dx, ws->dy, ws->dz, ws->wdz, refine) < 0)
        return -1;
    ws->dtau = add_tau_part(ws, -lin * ws->rtau + dk / ws->tau, ws->dx, ws->dy, ws->dz, ws->wdz);
    /* ds = -W (lambda \ ds) - W (W dz), with W dz from the KKT solve (one application of W) */
    tscvx_nt_apply(&ws->K, &ws->W, 0, ws->wdz, ws->wm2);
    for (tscvx_int i = 0; i < m; i++) ws->ds[i] = -wlds[i] - ws->wm2[i]; /* in place */
    /* Refinement of the direction. Near the end the NT scaling of an SOC gets so
     * ill-conditioned that W (W dz) no longer matches the W'W the KKT solve used, and the
     * primal row G dx + ds - h dtau = -lin rz picks up the difference (the orthant rows are
     * exact). Where that error would show in the primal residual, one more solve with the
     * same factor removes it, the complementarity row staying exact: K (cx, cy, cz) =
     * (0, 0, -e), ctau from the tau row, cs = -W (W cz), ckappa = -kappa ctau / tau. */
    const tscvx_float tol = 0.1 * ws->st.tol_feas * (1.0 + ws->norm_h) * ws->tau;
    if (refine > 0 && primal_row_error(ws, lin) > tol) {
        for (tscvx_int j = 0; j < n; j++) ws->wn[j] = 0.0;
        for (tscvx_int i = 0; i < p; i++) ws->wp[i] = 0.0;
        for (tscvx_int i = 0; i < m; i++) ws->wm[i] = -ws->e[i];
        if (ws->method->solve(ws, ws->wn, ws->wp, ws->wm, ws->cx, ws->cy, ws->cz, ws->cwz,
                              refine) < 0)
            return -1;
        const tscvx_float ctau = add_tau_part(ws, 0.0, ws->cx, ws->cy, ws->cz, ws->cwz);
        tscvx_nt_apply(&ws->K, &ws->W, 0, ws->cwz, ws->wm2);
        for (tscvx_int j = 0; j < n; j++) ws->dx[j] += ws->cx[j];
        for (tscvx_int i = 0; i < p; i++) ws->dy[i] += ws->cy[i];
        for (tscvx_int i = 0; i < m; i++) {
            ws->dz[i] += ws->cz[i], ws->wdz[i] += ws->cwz[i];
            ws->ds[i] -= ws->wm2[i];
        }
        ws->dtau += ctau;
    }
    ws->dkappa = -(dk + ws->kappa * ws->dtau) / ws->tau;
    return isfinite(ws->dtau) && isfinite(ws->dkappa) ? 0 : -1;
}

/* Largest step in (0, amax] keeping s, z, tau, kappa in their cones. */
static tscvx_float max_step(const tscvx_workspace *ws, tscvx_float amax) {
    tscvx_float a = tscvx_cone_max_step(&ws->K, ws->s, ws->ds, amax);
    a = tscvx_cone_max_step(&ws->K, ws->z, ws->dz, a);
    if (ws->dtau < 0.0 && ws->tau < a * -ws->dtau) a = -ws->tau / ws->dtau;
    if (ws->dkappa < 0.0 && ws->kappa < a * -ws->dkappa) a = -ws->kappa / ws->dkappa;
    return a;
}

static void take_step(tscvx_workspace *ws, tscvx_float a) {
    for (tscvx_int j = 0; j < ws->n; j++) ws->x[j] += a * ws->dx[j];
    for (tscvx_int i = 0; i < ws->p; i++) ws->y[i] += a * ws->dy[i];
    for (tscvx_int i = 0; i < ws->m; i++) ws->z[i] += a * ws->dz[i], ws->s[i] += a * ws->ds[i];
    ws->tau += a * ws->dtau;
    ws->kappa += a * ws->dkappa;
}

/* ---- initial point ---------------------------------------------------------------------- */

/* Warm start: the caller's point (x*, y*, s*, z*) in the current scaling (x = x_o / D,
 * y = cs y_o / EA, z = cs z_o / EG, s = EG s_o: tscvx_unscale_solution inverted at tau = 1),
 * tau = 1. On each cone where the current data's slack h - G x* lies strictly inside, s* is
 * that slack (the given s* may be another problem's), so those rows start with no primal
 * residual. Then every cone is moved off the boundary along e until its s'z is about mu_0
 * (tscvx_cone_center_pair), kappa = mu_0, with mu_0 balanced against the point's relative
 * residuals on the new data:
 *   mu_0 = max(WARM_MU_MIN, WARM_MU_PER_RES max(pres, dres)).
 * The homogeneous IPM shrinks residuals and mu together (by 1 - alpha per step): a start
 * whose mu is far below its residuals takes short steps until they catch up, one far above
 * spends iterations on complementarity alone. An answer is complementary (s'z = 0), so the
 * centring moves it only as far as that balance needs. Before this (until 25 Nov) the point
 * was blended with the cold start (Skajaa, Andersen & Ye 2013), which gave each cone the
 * complementarity 0.02 (s_0 + z_0) whatever the residuals: up to 10 on the landing's
 * penalty rows (multipliers near 500). Over the SCvx solves of the landing catalog this
 * start takes 8 % fewer IPM iterations than that blend (docs/socp-runtime.md, "Warm start"). Returns -1
 * when the centred s or z is not strictly inside the cones (the caller's s or z outside). */
#define WARM_MU_MIN 1e-5
#define WARM_MU_PER_RES 0.1
static int warm_initialize(tscvx_workspace *ws) {
    const tscvx_int n = ws->n, p = ws->p, m = ws->m;
    const tscvx_float cs = ws->cs;
    for (tscvx_int j = 0; j < n; j++) ws->x[j] = ws->bx[j] / ws->D[j];
    for (tscvx_int i = 0; i < p; i++) ws->y[i] = cs * ws->by[i] / ws->EA[i];
    for (tscvx_int i = 0; i < m; i++) ws->z[i] = cs * ws->bz[i] / ws->EG[i], ws->s[i] = 0.0;
    ws->tau = 1.0, ws->kappa = 0.0;
    residuals(ws); /* with s = 0: rz = G x* - h, the data's slack negated */
    tscvx_float *slack = ws->wm;
    for (tscvx_int i = 0; i < m; i++) slack[i] = -ws->rz[i], ws->s[i] = ws->EG[i] * ws->bs[i];
    tscvx_cone_copy_interior(&ws->K, slack, ws->s);
    for (tscvx_int i = 0; i < m; i++) ws->rz[i] += ws->s[i];
    const measures r = measure(ws);
    const tscvx_float mu0 = fmax(WARM_MU_MIN, WARM_MU_PER_RES * fmax(r.pres, r.dres));
    if (!isfinite(mu0)) return -1;
    tscvx_cone_center_pair(&ws->K, ws->s, ws->z, mu0);
    if (m > 0 && !(tscvx_cone_shift_needed(&ws->K, ws->s) < 0.0 &&
                   tscvx_cone_shift_needed(&ws->K, ws->z) < 0.0))
        return -1;
    ws->kappa = mu0;
    return 0;
}

/* The warm start if asked for and possible, else the cold start (ECOS): W = I, the two least
 * squares solves below, then s and z shifted into the cones. */
static int initialize(tscvx_workspace *ws, int warm) {
    const tscvx_int n = ws->n, p = ws->p, m = ws->m;
    ws->info.warm_started = warm && warm_initialize(ws) == 0;
    if (ws->info.warm_started) return 0;
    for (tscvx_int i = 0; i < ws->K.l; i++) ws->W.w[i] = 1.0;
    for (tscvx_int k = 0; k < ws->K.nsoc; k++) {
        const tscvx_int o = ws->K.off[k];
        ws->W.eta[k] = 1.0, ws->W.w[o] = 1.0;
        for (tscvx_int j = 1; j < ws->K.q[k]; j++) ws->W.w[o + j] = 0.0;
    }
    if (factor(ws) != 0) return -1;
    /* primal: K (x, y, -s) = (0, b, h): min |Gx - h| s.t. Ax = b, s = h - Gx */
    for (tscvx_int j = 0; j < n; j++) ws->wn[j] = 0.0;
    if (ws->method->solve(ws, ws->wn, ws->b, ws->h, ws->x, ws->y, ws->s, ws->wdz,
                          ws->st.refine_iters) < 0)
        return -1;
    for (tscvx_int i = 0; i < m; i++) ws->s[i] = -ws->s[i];
    /* dual: K (x', y, z) = (-c, 0, 0) */
    for (tscvx_int j = 0; j < n; j++) ws->wn[j] = -ws->c[j];
    for (tscvx_int i = 0; i < p; i++) ws->wp[i] = 0.0;
    for (tscvx_int i = 0; i < m; i++) ws->wm[i] = 0.0;
    if (ws->method->solve(ws, ws->wn, ws->wp, ws->wm, ws->dx, ws->y, ws->z, ws->wdz,
                          ws->st.refine_iters) < 0)
        return -1;
    /* shift into the interior: u += (1 + t) e when the smallest eigenvalue -t > -1 */
    const tscvx_float ts = tscvx_cone_shift_needed(&ws->K, ws->s);
    const tscvx_float tz = tscvx_cone_shift_needed(&ws->K, ws->z);
    if (m > 0 && ts > -1.0) tscvx_cone_add_identity(&ws->K, ws->s, 1.0 + ts);
    if (m > 0 && tz > -1.0) tscvx_cone_add_identity(&ws->K, ws->z, 1.0 + tz);
    ws->tau = 1.0, ws->kappa = 1.0;
    return 0;
}

/* ---- the loop ---------------------------------------------------------------------------- */

/* Iterative refinement of the Newton solves starts once mu < REFINE_MU mu_0. Before that the
 * factor's rounding is far below what the step needs; it grows as W's conditioning does
 * (like 1/mu) and matters in the last iterations only. Over the SCvx solves of the landing
 * catalog (25 Nov), every ratio from 1e-3 (used before) down to 1e-6 took the same
 * subproblems and IPM iterations; 1e-8 took 1 % more iterations (and, from the blended warm
 * start used before, 1e-12 took 10 % more). 1e-6 keeps two decades from that edge.
 * mu_0 is at least REFINE_MU_0_MIN = 1e-4. A cold start has mu_0 >= 1 anyway: it shifts s and
 * z until every cone holds e + (a point of the cone), so s'z >= 1 per cone, and tau kappa = 1.
 * A warm start begins near an answer with mu below 1e-5 (warm_initialize), where the rounding
 * already matters: measured from its own mu_0, refinement started near mu = 1e-11 or later,
 * after the banded method's unrefined directions had spoilt the primal residual (28 of the
 * 134 random problems of seeds 0-299 it takes, warm-started from their own answers, ended
 * SOLVED_INACCURATE where the cold start solves them; docs/socp-runtime.md, "Warm start").
 * Over seeds 0-3999 the floor 1e-4 leaves none such, 1e-5 nine (of seeds 300-1199), 1e-3 and
 * 1 one each; 1e-4 costs 1.1 % of a guidance call, 1 cost 4.4 %. Cold runs are unchanged. */
#define REFINE_MU 1e-6
#define REFINE_MU_0_MIN 1e-4

static void log_row(tscvx_workspace *ws, tscvx_int k, const measures *r, tscvx_float step) {
    if (k >= ws->log_cap) return;
    tscvx_iter_log *row = &ws->log[k];
    row->iter = k, row->pcost = r->pcost, row->dcost = r->dcost, row->gap = r->gap_abs;
    row->pres = r->pres, row->dres = r->dres, row->mu = r->mu, row->step = step;
}

static void finish_info(tscvx_workspace *ws, tscvx_solve_status st, tscvx_int k,
                        const measures *r) {
    ws->info.status = st, ws->info.iterations = k;
    ws->info.pcost = r->pcost, ws->info.dcost = r->dcost, ws->info.gap_abs = r->gap_abs;
    ws->info.gap_rel = r->gap_rel, ws->info.pres = r->pres, ws->info.dres = r->dres;
    ws->info.mu = r->mu;
}

/* After a failure or the iteration limit: the best iterate, if it meets reduced tolerances. */
static tscvx_solve_status fallback(tscvx_workspace *ws, tscvx_solve_status why, measures *r) {
    if (ws->best_iter < 0) return why;
    restore_best(ws);
    residuals(ws);
    *r = measure(ws);
    return converged(ws, r, 1) ? TSCVX_SOLVED_INACCURATE : why;
}

/* Mehrotra predictor: affine direction (ds = lambda o lambda, dk = tau kappa, full residual
 * targets); returns -1 on failure, else writes the centering sigma = (1 - alpha_aff)^3.
 * The affine direction only sets sigma and the second-order term: no refinement (with the
 * sparse SOC expansion, whose solves need it, as many steps as the other solves).
 * The cube is two multiplications, not libm's pow: IEEE 754 fixes their rounding, not pow's,
 * so the iterates are the same bits under any libm (the RAD750's included). */
static int predictor(tscvx_workspace *ws, tscvx_float *sigma) {
    tscvx_cone_prod(&ws->K, ws->lambda, ws->lambda, ws->wm2);
    const tscvx_int refine = ws->kkt.nexp > 0 ? ws->refine_now : 0;
    if (direction(ws, 1.0, ws->wm2, ws->tau * ws->kappa, refine) != 0) return -1;
    const tscvx_float one_minus_alpha = 1.0 - max_step(ws, 1.0);
    *sigma = one_minus_alpha * one_minus_alpha * one_minus_alpha;
    return 0;
}

/* Mehrotra corrector: ds = lambda o lambda + (W^{-1} ds_a) o (W dz_a) - sigma mu e,
 * dk = tau kappa + dtau_a dkappa_a - sigma mu, residual targets scaled by (1 - sigma). */
static int corrector(tscvx_workspace *ws, tscvx_float sigma, tscvx_float mu) {
    tscvx_nt_apply(&ws->K, &ws->W, 1, ws->ds, ws->wm);
    tscvx_cone_prod(&ws->K, ws->wm, ws->wdz, ws->ds); /* ds_a is spent: its space is work */
    tscvx_cone_prod(&ws->K, ws->lambda, ws->lambda, ws->wm2);
    for (tscvx_int i = 0; i < ws->m; i++) ws->wm2[i] += ws->ds[i];
    tscvx_cone_add_identity(&ws->K, ws->wm2, -sigma * mu);
    const tscvx_float dk = ws->tau * ws->kappa + ws->dtau * ws->dkappa - sigma * mu;
    return direction(ws, 1.0 - sigma, ws->wm2, dk, ws->refine_now);
}

/* One run of the IPM from the warm start (if asked for and possible) or the cold start. */
static tscvx_solve_status ipm_run(tscvx_workspace *ws, int warm) {
    tscvx_solve_status status = TSCVX_MAX_ITER;
    measures r = {0, 0, 0, 0, 0, 0, 0};
    tscvx_float step = 0.0, mu0 = 1.0, sigma = 0.0;
    tscvx_int k = 0, stalls = 0;
    ws->delta = ws->st.static_reg;
    ws->best_iter = -1;
    ws->info.factorizations = 0;
    ws->refine_now = ws->st.refine_iters;
    ws->info.warm_started = 0;
    if (ws->method->load(ws) != 0 || initialize(ws, warm) != 0) {
        /* no iterate: row 0 of the log and the info hold NaN for the costs, gaps,
         * residuals and mu, never computed (as before a solve; 0 read as a perfect answer) */
        const measures none = {NAN, NAN, NAN, NAN, NAN, NAN, NAN};
        log_row(ws, 0, &none, 0.0);
        finish_info(ws, TSCVX_NUMERICAL_ERROR, 0, &none);
        return TSCVX_NUMERICAL_ERROR;
    }
    for (k = 0; k <= ws->st.max_iter; k++) {
        residuals(ws);
        r = measure(ws);
        log_row(ws, k, &r, step);
        if (!isfinite(r.pcost + r.dcost + r.pres + r.dres)) {
            status = fallback(ws, TSCVX_NUMERICAL_ERROR, &r);
            break;
        }
        update_best(ws, &r, k);
        if (converged(ws, &r, 0)) { status = TSCVX_SOLVED; break; }
        if (primal_infeasible(ws)) { status = TSCVX_PRIMAL_INFEASIBLE; break; }
        if (dual_infeasible(ws)) { status = TSCVX_DUAL_INFEASIBLE; break; }
        if (k == ws->st.max_iter) { status = fallback(ws, TSCVX_MAX_ITER, &r); break; }

        /* inexact Newton: directions need no refinement until mu < REFINE_MU mu_0 */
        if (k == 0) mu0 = fmax(r.mu, REFINE_MU_0_MIN);
        ws->refine_now = r.mu < REFINE_MU * mu0 || ws->kkt.nexp > 0 ? ws->st.refine_iters : 0;
        /* NT scaling, one factorization, constant solve, predictor-corrector */
        if (tscvx_nt_scaling(&ws->K, ws->s, ws->z, &ws->W, ws->lambda) != 0 || factor(ws) != 0 ||
            constant_solve(ws) != 0 || predictor(ws, &sigma) != 0 ||
            corrector(ws, sigma, r.mu) != 0) {
            status = fallback(ws, TSCVX_NUMERICAL_ERROR, &r);
            break;
        }
        /* step: a fraction of the way to the boundary of the cones */
        step = fmin(1.0, ws->st.step_fraction * max_step(ws, 1.0 / ws->st.step_fraction));
        stalls = step < 1e-8 ? stalls + 1 : 0;
        if (stalls >= 3 || !(step > 0.0)) {
            status = fallback(ws, TSCVX_NUMERICAL_ERROR, &r);
            break;
        }
        take_step(ws, step);
    }
    if (k > ws->st.max_iter) k = ws->st.max_iter;
    finish_info(ws, status, k, &r);
    return status;
}

/* A warm-started run that fails (numerical error, iteration limit) is run again from the
 * cold start: a warm start is there to save iterations, not to cost an answer the cold start
 * would give. (Seen on the ill-posed subproblems of a landing with no fuel to spare, where a
 * start from an inaccurate answer ran into a numerical error that the cold start avoids.)
 * info and the log describe the cold run; info.restart_iterations counts the failed one. */
tscvx_solve_status tscvx_ipm(tscvx_workspace *ws) {
    const int warm = ws->warm;
    ws->warm = 0; /* tscvx_warm_start's point serves this solve only */
    ws->info.restart_iterations = 0;
    tscvx_solve_status status = ipm_run(ws, warm);
    if (ws->info.warm_started &&
        (status == TSCVX_NUMERICAL_ERROR || status == TSCVX_MAX_ITER)) {
        const tscvx_int lost = ws->info.iterations;
        status = ipm_run(ws, 0);
        ws->info.restart_iterations = lost;
    }
    return status;
}
