/* KKT methods against a dense reference (Gaussian elimination with partial pivoting on the
 * unregularized KKT matrix): the sparse method (static-pattern and SuiteSparse LDL backends,
 * dense SOC blocks and the sparse diagonal + rank-2 expansion) and the banded method, on small
 * random problems and on a stage-structured one with a bordered global variable; the static
 * backend against SuiteSparse LDL bit for bit. */
#include <string.h>

#include "ctest_util.h"
#include "socp_internal.h"

#define N 7
#define P_ 2
#define L 2
#define NSOC 2
#define M 9 /* L + 3 + 4 */
#define DMAX 480 /* largest dense reference */

static const tscvx_int q[NSOC] = {3, 4};

/* dense column-major helpers */
static void csc_to_dense(const tscvx_csc *A, double *D, int ld, int r0, int c0, int sym) {
    for (int j = 0; j < A->ncol; j++)
        for (int k = A->p[j]; k < A->p[j + 1]; k++) {
            const double v = A->x[k];
            D[(c0 + j) * ld + r0 + A->i[k]] += v;
            if (sym && A->i[k] != j) D[(r0 + A->i[k]) * ld + c0 + j] += v;
        }
}

static int dense_solve(double *Kd, double *x, int n) { /* partial pivoting, in place */
    for (int c = 0; c < n; c++) {
        int piv = c;
        for (int r = c + 1; r < n; r++)
            if (fabs(Kd[c * n + r]) > fabs(Kd[c * n + piv])) piv = r;
        if (Kd[c * n + piv] == 0.0) return -1;
        for (int j = 0; j < n; j++) {
            double t = Kd[j * n + c];
            Kd[j * n + c] = Kd[j * n + piv];
            Kd[j * n + piv] = t;
        }
        double t = x[c];
        x[c] = x[piv], x[piv] = t;
        for (int r = c + 1; r < n; r++) {
            const double f = Kd[c * n + r] / Kd[c * n + c];
            for (int j = c; j < n; j++) Kd[j * n + r] -= f * Kd[j * n + c];
            x[r] -= f * x[c];
        }
    }
    for (int c = n - 1; c >= 0; c--) {
        for (int j = c + 1; j < n; j++) x[c] -= Kd[j * n + c] * x[j];
        x[c] /= Kd[c * n + c];
    }
    return 0;
}

static void random_csc(int nrow, int ncol, double density, int upper, tscvx_int *Mp, tscvx_int *Mi,
                       tscvx_float *Mx) {
    int nz = 0;
    for (int j = 0; j < ncol; j++) {
        Mp[j] = nz;
        for (int i = 0; i < nrow; i++) {
            if (upper && i > j) break;
            if (ct_rand() < density || (upper && i == j) || (!upper && i == j % nrow)) {
                Mi[nz] = i;
                Mx[nz++] = upper && i == j ? 2.0 + ct_rand() : ct_randn();
            }
        }
    }
    Mp[ncol] = nz;
}

/* Factor ws with its method at the current NT scaling (delta 1e-9) and solve a random
 * right-hand side with refinement; compare with the dense unregularized solution. */
static double dense_error(tscvx_workspace *ws, double delta, int refine, double *scale_out);

static void check_against_dense(tscvx_workspace *ws, int backend, int dense_max, int with_P) {
    double scale;
    const double err = dense_error(ws, 1e-9, 5, &scale);
    CHECK(err < 1e-8 * scale, "%s (backend %d, dense_max %d, P %d): |x - x_ref| = %g (scale %g)",
          ws->method->name, backend, dense_max, with_P, err, scale);
}

/* The unregularized KKT matrix [P A' G'; A 0 0; G 0 -W'W] of the workspace, dense (dim x dim,
 * dim = n + p + m); -1 (a failed check) when dim exceeds DMAX. */
static int dense_kkt(tscvx_workspace *ws, double *Kd) {
    const int n = ws->n, p = ws->p, m = ws->m, dim = n + p + m;
    static tscvx_float e[DMAX], t1[DMAX], t2[DMAX];
    if (dim > DMAX) {
        CHECK(0, "reference too small for dim %d", dim);
        return -1;
    }
    memset(Kd, 0, sizeof(double) * dim * dim);
    csc_to_dense(&ws->P, Kd, dim, 0, 0, 1);
    csc_to_dense(&ws->A, Kd, dim, n, 0, 0);
    csc_to_dense(&ws->G, Kd, dim, n + p, 0, 0);
    for (int j = 0; j < n; j++)
        for (int i = n; i < dim; i++) Kd[i * dim + j] = Kd[j * dim + i];
    for (int j = 0; j < m; j++) { /* -W'W column j */
        for (int i = 0; i < m; i++) e[i] = i == j;
        tscvx_nt_apply(&ws->K, &ws->W, 0, e, t1);
        tscvx_nt_apply(&ws->K, &ws->W, 0, t1, t2);
        for (int i = 0; i < m; i++) Kd[(n + p + j) * dim + n + p + i] = -t2[i];
    }
    return 0;
}

/* |x - x_ref|_inf of the method's solve (static regularization delta, `refine` refinement
 * steps) against the dense solution of the UNREGULARIZED system; the scale max(1, |x_ref|). */
static double dense_error(tscvx_workspace *ws, double delta, int refine, double *scale_out) {
    const int n = ws->n, p = ws->p, m = ws->m, dim = n + p + m;
    static double Kd[DMAX * DMAX];
    static double rhs[DMAX], ref[DMAX], sol[DMAX];
    *scale_out = 1.0;
    ws->delta = delta;
    CHECK(ws->method->load(ws) == 0, "load (%s)", ws->method->name);
    CHECK(ws->method->factor(ws) == 0, "factorization (%s, n %d, delta %g)", ws->method->name, n,
          delta);
    if (dense_kkt(ws, Kd) != 0) return INFINITY;
    static tscvx_float t1[DMAX];
    for (int i = 0; i < dim; i++) rhs[i] = ref[i] = ct_randn();
    CHECK(dense_solve(Kd, ref, dim) == 0, "dense solve");
    CHECK(ws->method->solve(ws, rhs, rhs + n, rhs + n + p, sol, sol + n, sol + n + p, t1,
                            refine) >= 0,
          "kkt solve");
    double err = 0.0, scale = 1.0;
    for (int i = 0; i < dim; i++) err = fmax(err, fabs(sol[i] - ref[i]));
    for (int i = 0; i < dim; i++) scale = fmax(scale, fabs(ref[i]));
    *scale_out = scale;
    return err;
}

static tscvx_workspace *last_ws; /* the workspace of the last run() */

static void run(int dense_max, int with_P, int backend) {
    tscvx_int Pp[N + 1], Pi[N * N], Ap[N + 1], Ai[N * P_], Gp[N + 1], Gi[N * M];
    tscvx_float Px[N * N], Ax[N * P_], Gx[N * M], c[N], b[P_], h[M];
    random_csc(N, N, 0.3, 1, Pp, Pi, Px);
    for (int j = 0; j < N; j++) /* diagonally dominant: P positive definite (a convex QP) */
        for (int k = Pp[j]; k < Pp[j + 1] - 1; k++) {
            Px[Pp[Pi[k] + 1] - 1] += fabs(Px[k]);
            Px[Pp[j + 1] - 1] += fabs(Px[k]);
        }
    random_csc(P_, N, 0.4, 0, Ap, Ai, Ax);
    random_csc(M, N, 0.4, 0, Gp, Gi, Gx);
    for (int i = 0; i < N; i++) c[i] = ct_randn();
    for (int i = 0; i < P_; i++) b[i] = ct_randn();
    for (int i = 0; i < M; i++) h[i] = ct_randn();
    tscvx_data d = {N, P_, M, with_P ? Pp : NULL, Pi, Px, c, Ap, Ai, Ax, b,
                    Gp, Gi, Gx, h, L, NSOC, q};
    tscvx_settings st;
    tscvx_default_settings(&st);
    st.soc_dense_max = dense_max;
    st.kkt_backend = backend;
    static unsigned char arena[1 << 20];
    tscvx_workspace *ws = NULL;
    CHECK(tscvx_setup(&ws, arena, sizeof arena, &d, &st) == TSCVX_SETUP_OK, "setup");
    if (!ws) return;
    CHECK(ws->method->id == (backend == TSCVX_KKT_BANDED ? TSCVX_KKT_BANDED : TSCVX_KKT_STATIC),
          "method %s for backend %d", ws->method->name, backend);
    if (backend != TSCVX_KKT_BANDED)
        CHECK(ws->kkt.nexp == (dense_max < 3 ? 2 : (dense_max < 4 ? 1 : 0)), "expansions %d",
              (int)ws->kkt.nexp);

    /* random NT scaling point */
    tscvx_float s[M], z[M], lam[M];
    for (int i = 0; i < M; i++) s[i] = ct_randn(), z[i] = ct_randn();
    for (int i = 0; i < L; i++) s[i] = 0.1 + ct_rand(), z[i] = 0.1 + ct_rand();
    s[L] = 3.0, z[L] = 2.5, s[L + 3] = 4.0, z[L + 3] = 3.0;
    CHECK(tscvx_nt_scaling(&ws->K, s, z, &ws->W, lam) == 0, "scaling");
    check_against_dense(ws, backend, dense_max, with_P);
    last_ws = ws;
}

/* A large static regularization (1e-4): the refinement, which measures the residual of the
 * UNREGULARIZED system, still recovers its solution (a wrong sign on the z rows' removed
 * regularization would leave an error ~ delta |dz|); each refinement step counts (0 steps
 * leave the O(delta) error, 1 step reduces it; each solve has a new random right-hand side). */
static void run_refinement(int dense_max, int backend) {
    run(dense_max, 1, backend);
    tscvx_workspace *ws = last_ws;
    if (!ws) return;
    double scale, e[3];
    const int steps[3] = {0, 1, 20};
    for (int k = 0; k < 3; k++) e[k] = dense_error(ws, 1e-4, steps[k], &scale) / scale;
    CHECK(e[2] <= 1e-10, "backend %d: refined error %g with delta 1e-4", backend, e[2]);
    /* the sparse method regularizes by delta (error ~1e-4 here); the banded one less */
    CHECK(e[0] > (backend == TSCVX_KKT_BANDED ? 1e-9 : 1e-6),
          "backend %d: unrefined error %g: no regularization seen?", backend, e[0]);
    CHECK(e[1] < 0.1 * e[0], "backend %d: one refinement step %g vs none %g", backend, e[1], e[0]);
}

/* The refinement's stopping rule (socp_internal.h): a step is taken only while the residual
 * of the UNREGULARIZED system is above REFINE_TOL (1 + |rhs|) and above the rounding floor,
 * and after the first only while the last step at least halved it; it stops otherwise. With
 * a static regularization comparable to the matrix's entries or larger (delta = 1 and 1e4;
 * the banded method regularizes by 1e-4 delta), refinement gains slowly or stalls, and must
 * stop at the first step that gains less than 2x instead of spending its 20 steps. The
 * residuals r_k after k steps are measured here on the dense matrix (the solve with
 * `refine` = k takes the first k steps of the solve with more). */
static void run_refinement_stops(int dense_max, int backend) {
    run(dense_max, 1, backend);
    tscvx_workspace *ws = last_ws;
    if (!ws) return;
    const int n = ws->n, p = ws->p, m = ws->m, dim = n + p + m;
    static double Kd[DMAX * DMAX], rhs[DMAX], sol[DMAX], r[21];
    static tscvx_float t1[DMAX];
    for (int pass = 0; pass < 2; pass++) {
        ws->delta = pass == 0 ? 1.0 : 1e4;
        CHECK(ws->method->load(ws) == 0 && ws->method->factor(ws) == 0, "factor (%s)",
              ws->method->name);
        if (dense_kkt(ws, Kd) != 0) return;
        double bnorm = 0.0;
        for (int i = 0; i < dim; i++) rhs[i] = ct_randn(), bnorm = fmax(bnorm, fabs(rhs[i]));
        const int steps = ws->method->solve(ws, rhs, rhs + n, rhs + n + p, sol, sol + n,
                                            sol + n + p, t1, 20);
        CHECK(steps >= 0, "%s: refinement failed", ws->method->name);
        for (int k = 0; k <= steps; k++) {
            CHECK(ws->method->solve(ws, rhs, rhs + n, rhs + n + p, sol, sol + n, sol + n + p, t1,
                                    k) == k,
                  "%s: refine %d", ws->method->name, k);
            r[k] = 0.0;
            for (int i = 0; i < dim; i++) {
                double v = rhs[i];
                for (int j = 0; j < dim; j++) v -= Kd[j * dim + i] * sol[j];
                r[k] = fmax(r[k], fabs(v));
            }
            if (k < steps) /* a step was taken from here: not yet accurate */
                CHECK(r[k] > 0.5 * TSCVX_REFINE_TOL * (1.0 + bnorm),
                      "%s: step %d taken at residual %g", ws->method->name, k + 1, r[k]);
            if (k >= 1 && k < steps) /* ... and the last one gained at least 2x */
                CHECK(r[k] <= 0.5 * r[k - 1] * 1.01, "%s, delta %g: step %d taken after %g -> %g",
                      ws->method->name, ws->delta, k + 1, r[k - 1], r[k]);
        }
        /* stopped before its 20 steps for a reason: accurate, or the last step gained less
         * than 2x (the rounding floor, 1e-15 |K| |x|, is far below these residuals) */
        if (steps >= 1 && steps < 20)
            CHECK(r[steps] <= 2.0 * TSCVX_REFINE_TOL * (1.0 + bnorm) ||
                      r[steps] > 0.5 * r[steps - 1] * 0.99,
                  "%s, delta %g: stopped after %d steps at %g (before %g)", ws->method->name,
                  ws->delta, steps, r[steps], r[steps - 1]);
    }
}

/* ---- the static-pattern backend alone, on random quasi-definite matrices ---------------- */

#define QD_MAX 60

/* Random quasi-definite K = [H B'; B -C] (H, C diagonally dominant, positive diagonals),
 * symmetrically permuted at random; upper triangle CSC into kk (dim, nnz, Kp, Ki, Kx) and the
 * dense matrix into Kd. Returns the number of positive pivots the LDL' must have. */
static tscvx_int random_qd(tscvx_kkt *kk, int dim, double density, double *Kd) {
    int npos = 1 + (int)(ct_rand() * (dim - 1)), perm[QD_MAX];
    for (int i = 0; i < dim; i++) perm[i] = i;
    for (int i = dim - 1; i > 0; i--) { /* Fisher-Yates */
        const int j = (int)(ct_rand() * (i + 1)), t = perm[i];
        perm[i] = perm[j], perm[j] = t;
    }
    memset(Kd, 0, sizeof(double) * dim * dim);
    for (int j = 0; j < dim; j++)
        for (int i = 0; i < j; i++)
            if (ct_rand() < density) {
                const double v = ct_randn();
                Kd[perm[j] * dim + perm[i]] = Kd[perm[i] * dim + perm[j]] = v;
            }
    for (int i = 0; i < dim; i++) { /* dominant diagonal: + on the first npos, - after */
        double s = 1.0 + ct_rand();
        for (int j = 0; j < dim; j++) s += fabs(Kd[perm[j] * dim + perm[i]]);
        Kd[perm[i] * dim + perm[i]] = i < npos ? s : -s;
    }
    tscvx_int nz = 0;
    for (int j = 0; j < dim; j++) {
        kk->Kp[j] = nz;
        for (int i = 0; i <= j; i++)
            if (Kd[j * dim + i] != 0.0 || i == j) kk->Ki[nz] = i, kk->Kx[nz++] = Kd[j * dim + i];
    }
    kk->Kp[dim] = nz;
    kk->dim = dim, kk->nnz = nz;
    return npos;
}

/* Symbolic + alloc + numeric of backend b on kk (memory from `arena`); 0 or -1. */
static int factor_with(tscvx_kkt *kk, const tscvx_backend *b, unsigned char *arena,
                       size_t bytes, tscvx_int *tmp, tscvx_float *sol) {
    kk->backend = b;
    const long lnz = b->symbolic(kk, tmp);
    if (lnz < 0) return -1;
    kk->lnz = (tscvx_int)lnz;
    tscvx_arena a = {arena, bytes, 0, 0, 0, 0};
    if (b->alloc(kk, &a) != 0 || a.overflow) return -1;
    kk->sol = sol, kk->Pattern = (tscvx_int *)sol;
    return b->numeric(kk);
}

static void run_static_vs_ldl(int dim, double density) {
    static double Kd[QD_MAX * QD_MAX];
    static tscvx_int Kp[QD_MAX + 1], Ki[QD_MAX * QD_MAX], tmp[5 * QD_MAX + 2];
    static tscvx_float Kx[QD_MAX * QD_MAX], sol_s[QD_MAX], sol_l[QD_MAX];
    static unsigned char mem_s[1 << 16], mem_l[1 << 16];
    tscvx_kkt ks, kl;
    memset(&ks, 0, sizeof ks);
    ks.Kp = Kp, ks.Ki = Ki, ks.Kx = Kx;
    ks.npos = random_qd(&ks, dim, density, Kd);
    kl = ks;
    CHECK(factor_with(&kl, &tscvx_backend_ldl, mem_l, sizeof mem_l, tmp, sol_l) == 0, "ldl");
    CHECK(factor_with(&ks, &tscvx_backend_static, mem_s, sizeof mem_s, tmp, sol_s) == 0,
          "static dim %d", dim);
    CHECK(ks.lnz == kl.lnz, "nnz(L) %d vs %d", (int)ks.lnz, (int)kl.lnz);
    /* the same operations in the same order: bitwise the same factor */
    int same = 1;
    for (int i = 0; i < dim; i++) same &= ks.D[i] == kl.D[i];
    for (int j = 0; j <= dim; j++) same &= ks.Lp[j] == kl.Lp[j];
    for (tscvx_int p = 0; p < ks.lnz; p++) same &= ks.Li[p] == kl.Li[p] && ks.Lx[p] == kl.Lx[p];
    CHECK(same, "static factor differs from SuiteSparse LDL (dim %d)", dim);
    /* solves: bitwise LDL's, and K x = b to rounding against the dense matrix */
    double b[QD_MAX], xs[QD_MAX], xl[QD_MAX];
    for (int i = 0; i < dim; i++) b[i] = xs[i] = xl[i] = ct_randn();
    ks.backend->solve(&ks, xs);
    kl.backend->solve(&kl, xl);
    double rmax = 0.0, kmax = 0.0, xmax = 0.0;
    for (int i = 0; i < dim; i++) {
        double r = b[i];
        for (int j = 0; j < dim; j++) r -= Kd[j * dim + i] * xs[j], kmax = fmax(kmax, fabs(Kd[j * dim + i]));
        rmax = fmax(rmax, fabs(r)), xmax = fmax(xmax, fabs(xs[i]));
        same &= xs[i] == xl[i];
    }
    CHECK(same, "static solve differs from SuiteSparse LDL (dim %d)", dim);
    CHECK(rmax <= 1e-12 * kmax * xmax * dim, "residual %g (|K| %g |x| %g)", rmax, kmax, xmax);
    /* the solves use the work vector: a second factorization must not see that */
    for (int i = 0; i < dim; i++) ks.Y[i] = 1e300, sol_s[i] = 0.0;
    CHECK(ks.backend->numeric(&ks) == 0, "refactor");
    for (int i = 0; i < dim; i++) same &= ks.D[i] == kl.D[i];
    CHECK(same, "refactorization differs (dim %d)", dim);
    /* wrong inertia and a zero pivot are failures */
    ks.npos = kl.npos + 1;
    CHECK(ks.backend->numeric(&ks) == -1, "inertia not checked");
    ks.npos = kl.npos;
    for (tscvx_int t = Kp[0]; t < Kp[1]; t++) Kx[t] = 0.0; /* K(0,0) = 0 */
    CHECK(ks.backend->numeric(&ks) == -1, "zero pivot not caught");
}

/* ---- a stage-structured problem (optimal control) for the banded method ----------------- */

#define T_ 30                    /* stages */
#define SN (5 * T_ + 3)          /* x_k (3), u_k (2) per stage, the global sigma (and g1, g2) */
#define SP (3 * (T_ - 1) + 3)    /* dynamics, then x_0 = x0 (last: the row order is not banded) */
#define SM (3 * T_ + 1 + 3 * T_ + 2) /* x_k <= 10, sigma >= 0.1 | |u_k| <= x_k0 + 5 (| |g2| <= g1 + 2) */
#define SNZ 2048

typedef struct {
    int nz;
    tscvx_int r[SNZ], c[SNZ];
    tscvx_float v[SNZ];
} triplets;

static void put(triplets *t, int r, int c, double v) { t->r[t->nz] = r, t->c[t->nz] = c, t->v[t->nz++] = v; }

/* CSC (rows ascending in each column) of triplets without duplicates */
static void to_csc(const triplets *t, int ncol, tscvx_int *Mp, tscvx_int *Mi, tscvx_float *Mx) {
    for (int j = 0; j <= ncol; j++) Mp[j] = 0;
    for (int e = 0; e < t->nz; e++) Mp[t->c[e] + 1]++;
    for (int j = 0; j < ncol; j++) Mp[j + 1] += Mp[j];
    tscvx_int next[SN + 1];
    for (int j = 0; j < ncol; j++) next[j] = Mp[j];
    for (int e = 0; e < t->nz; e++) {
        int k = next[t->c[e]]++;
        for (; k > Mp[t->c[e]] && Mi[k - 1] > t->r[e]; k--) Mi[k] = Mi[k - 1], Mx[k] = Mx[k - 1];
        Mi[k] = t->r[e], Mx[k] = t->v[e];
    }
}

/* Stage problem; free_var leaves one state in no cone (no banded structure); two_more adds two
 * more global variables g1, g2 in every dynamics row, sharing a cone (a border of three: two
 * in one group). */
static void run_stages(int with_P, int backend, int free_var, int two_more) {
    static triplets tA, tG, tP;
    static tscvx_int Ap[SN + 1], Ai[SNZ], Gp[SN + 1], Gi[SNZ], Pp[SN + 1], Pi[SNZ];
    static tscvx_float Ax[SNZ], Gx[SNZ], Px[SNZ], c[SN], b[SP], h[SM];
    static tscvx_int q3[T_ + 1];
    for (int k = 0; k <= T_; k++) q3[k] = k < T_ ? 3 : 2;
    tA.nz = tG.nz = tP.nz = 0;
    const int sig = 5 * T_, n = 5 * T_ + 1 + 2 * two_more;
    for (int k = 0; k + 1 < T_; k++) /* x_{k+1} - A_k x_k - B_k u_k - c_k sigma = 0 */
        for (int i = 0; i < 3; i++) {
            const int row = 3 * k + i;
            put(&tA, row, 5 * (k + 1) + i, 1.0);
            for (int j = 0; j < 3; j++) put(&tA, row, 5 * k + j, -(i == j) - 0.1 * ct_randn());
            for (int j = 0; j < 2; j++) put(&tA, row, 5 * k + 3 + j, ct_randn());
            put(&tA, row, sig, ct_randn());
            if (two_more) put(&tA, row, sig + 1, ct_randn()), put(&tA, row, sig + 2, ct_randn());
            b[row] = 0.1 * ct_randn();
        }
    for (int i = 0; i < 3; i++) put(&tA, SP - 3 + i, i, 1.0), b[SP - 3 + i] = ct_randn();
    int row = 0; /* orthant: x_k,i <= 10 (one left out with free_var), sigma >= 0.1 */
    for (int k = 0; k < T_; k++)
        for (int i = 0; i < 3; i++) {
            if (free_var && k == T_ / 2 && i == 2) continue;
            put(&tG, row, 5 * k + i, 1.0), h[row++] = 10.0;
        }
    put(&tG, row, sig, -1.0), h[row++] = -0.1;
    const tscvx_int l = row;
    for (int k = 0; k < T_; k++) { /* (x_k0 + 5, u_k) in Q3 */
        put(&tG, row, 5 * k, -1.0), h[row++] = 5.0;
        put(&tG, row, 5 * k + 3, -1.0), h[row++] = 0.0;
        put(&tG, row, 5 * k + 4, -1.0), h[row++] = 0.0;
    }
    if (two_more) { /* (g1 + 2, g2) in Q2 */
        put(&tG, row, sig + 1, -1.0), h[row++] = 2.0;
        put(&tG, row, sig + 2, -1.0), h[row++] = 0.0;
    }
    for (int k = 0; k < T_; k++) {
        put(&tP, 5 * k + 3, 5 * k + 3, 2.0);
        put(&tP, 5 * k + 3, 5 * k + 4, 0.5);
        put(&tP, 5 * k + 4, 5 * k + 4, 1.0);
    }
    for (int j = 0; j < n; j++) c[j] = ct_randn();
    to_csc(&tA, n, Ap, Ai, Ax);
    to_csc(&tG, n, Gp, Gi, Gx);
    to_csc(&tP, n, Pp, Pi, Px);
    tscvx_data d = {n, SP, row, with_P ? Pp : NULL, Pi, Px, c, Ap, Ai, Ax, b,
                    Gp, Gi, Gx, h, l, T_ + two_more, q3};
    tscvx_settings st;
    tscvx_default_settings(&st);
    st.kkt_backend = backend;
    static unsigned char arena[1 << 21];
    tscvx_workspace *ws = NULL;
    const tscvx_setup_status status = tscvx_setup(&ws, arena, sizeof arena, &d, &st);
    if (free_var) { /* a variable in no cone: banded refused, AUTO falls back to sparse */
        if (backend == TSCVX_KKT_BANDED)
            CHECK(status == TSCVX_SETUP_NOT_BANDED, "free variable: status %d", (int)status);
        else
            CHECK(status == TSCVX_SETUP_OK && ws->method->id == TSCVX_KKT_STATIC, "auto fallback");
        return;
    }
    CHECK(status == TSCVX_SETUP_OK, "stage setup %d", (int)status);
    if (!ws) return;
    CHECK(ws->method->id == TSCVX_KKT_BANDED, "stage problem not banded (%s)", ws->method->name);
    CHECK(ws->bd.nb == 1 + 2 * two_more && ws->bd.bvar[0] == sig, "border: %d variables",
          (int)ws->bd.nb);
    if (two_more)
        CHECK(ws->bd.bvar[1] == sig + 1 && ws->bd.bvar[2] == sig + 2 &&
                  ws->bd.bgroup[1] == ws->bd.bgroup[2] && ws->bd.bgroup[0] != ws->bd.bgroup[1],
              "border groups");
    CHECK(ws->bd.ngroup == 3 * T_ + 1 + two_more, "groups %d", (int)ws->bd.ngroup);
    /* the profile follows the stages: at most two intervals wide */
    for (int i = 0; i < SP; i++) CHECK(i - ws->bd.yfirst[i] < 9, "row %d profile %d", i, i - (int)ws->bd.yfirst[i]);
    static tscvx_float s[SM], z[SM], lam[SM];
    for (int i = 0; i < l; i++) s[i] = 0.01 + ct_rand(), z[i] = 0.01 + 10.0 * ct_rand();
    for (int k = 0; k < T_; k++) {
        const int o = l + 3 * k;
        s[o + 1] = ct_randn(), s[o + 2] = ct_randn(), z[o + 1] = ct_randn(), z[o + 2] = ct_randn();
        s[o] = hypot(s[o + 1], s[o + 2]) * (1.0 + 0.1 * ct_rand()) + 1e-3;
        z[o] = hypot(z[o + 1], z[o + 2]) * (1.0 + 3.0 * ct_rand()) + 1e-3;
    }
    if (two_more) {
        const int o = l + 3 * T_;
        s[o + 1] = ct_randn(), z[o + 1] = ct_randn();
        s[o] = fabs(s[o + 1]) + 0.5, z[o] = fabs(z[o + 1]) + 0.2;
    }
    CHECK(tscvx_nt_scaling(&ws->K, s, z, &ws->W, lam) == 0, "scaling");
    check_against_dense(ws, backend, 0, with_P);
}

int main(void) {
    for (int rep = 0; rep < 20; rep++) /* every KKT method */
        for (int backend = TSCVX_KKT_LDL; backend <= TSCVX_KKT_BANDED; backend++) {
            run(16, rep % 2, backend);
            run(3, rep % 2, backend);
            run(1, rep % 2, backend);
        }
    for (int rep = 0; rep < 200; rep++) /* dims 1..60, sparse to dense */
        run_static_vs_ldl(1 + rep % QD_MAX, rep < 100 ? 0.08 : 0.3);
    for (int rep = 0; rep < 8; rep++) {
        run_stages(rep % 2, TSCVX_KKT_BANDED, 0, rep >= 4);
        run_stages(rep % 2, TSCVX_KKT_AUTO, 0, rep >= 4);
    }
    run_stages(0, TSCVX_KKT_BANDED, 1, 0);
    run_stages(0, TSCVX_KKT_AUTO, 1, 0);
    for (int backend = TSCVX_KKT_LDL; backend <= TSCVX_KKT_BANDED; backend++) {
        run_refinement(16, backend);
        run_refinement(1, backend);
        run_refinement_stops(16, backend);
        run_refinement_stops(1, backend);
    }
    return ct_report("test_kkt");
}
