/* KKT system: pattern + maps + factor (static-pattern and SuiteSparse LDL backends) and refined
 * solve against a dense reference (Gaussian elimination with partial pivoting on the
 * unregularized KKT matrix), for dense SOC blocks and for the sparse (diagonal + rank-2)
 * expansion. */
#include <string.h>

#include "ctest_util.h"
#include "socp_internal.h"

#define N 7
#define P_ 2
#define L 2
#define NSOC 2
#define M 9 /* L + 3 + 4 */
#define DIM (N + P_ + M)

static const tscvx_int q[NSOC] = {3, 4};

/* dense column-major helpers */
static void csc_to_dense(const tscvx_csc *A, double *D, int ld, int r0, int c0, int sym) {
    for (int j = 0; j < A->ncol; j++)
        for (int k = A->p[j]; k < A->p[j + 1]; k++) {
            const double v = A->xmap ? CSC_VAL(A, k) : A->x[k];
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

static void run(int dense_max, int with_P, int backend) {
    tscvx_int Pp[N + 1], Pi[N * N], Ap[N + 1], Ai[N * P_], Gp[N + 1], Gi[N * M];
    tscvx_float Px[N * N], Ax[N * P_], Gx[N * M], c[N], b[P_], h[M];
    random_csc(N, N, 0.3, 1, Pp, Pi, Px);
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
    CHECK(ws->kkt.nexp == (dense_max < 3 ? 2 : (dense_max < 4 ? 1 : 0)), "expansions %d",
          (int)ws->kkt.nexp);

    /* random NT scaling point */
    tscvx_float s[M], z[M], lam[M];
    for (int i = 0; i < M; i++) s[i] = ct_randn(), z[i] = ct_randn();
    for (int i = 0; i < L; i++) s[i] = 0.1 + ct_rand(), z[i] = 0.1 + ct_rand();
    s[L] = 3.0, z[L] = 2.5, s[L + 3] = 4.0, z[L + 3] = 3.0;
    CHECK(tscvx_nt_scaling(&ws->K, s, z, &ws->W, lam) == 0, "scaling");
    const double delta = 1e-9;
    tscvx_kkt_data_values(ws, delta);
    tscvx_kkt_cone_values(&ws->kkt, &ws->K, &ws->W, delta);
    CHECK(ws->kkt.backend->numeric(&ws->kkt) == 0, "factorization");

    /* dense reference (unregularized) */
    static double Kd[DIM * DIM];
    memset(Kd, 0, sizeof Kd);
    csc_to_dense(&ws->P, Kd, DIM, 0, 0, 1);
    csc_to_dense(&ws->A, Kd, DIM, N, 0, 0);
    csc_to_dense(&ws->G, Kd, DIM, N + P_, 0, 0);
    for (int j = 0; j < N; j++)
        for (int i = N; i < DIM; i++) Kd[i * DIM + j] = Kd[j * DIM + i];
    for (int j = 0; j < M; j++) { /* -W'W column j */
        tscvx_float e[M] = {0}, t1[M], t2[M];
        e[j] = 1.0;
        tscvx_nt_apply(&ws->K, &ws->W, 0, e, t1);
        tscvx_nt_apply(&ws->K, &ws->W, 0, t1, t2);
        for (int i = 0; i < M; i++) Kd[(N + P_ + j) * DIM + N + P_ + i] = -t2[i];
    }
    double rhs[DIM], ref[DIM];
    for (int i = 0; i < DIM; i++) rhs[i] = ref[i] = ct_randn();
    CHECK(dense_solve(Kd, ref, DIM) == 0, "dense solve");
    tscvx_float dx[N], dy[P_], dz[M];
    CHECK(tscvx_kkt_solve(&ws->kkt, N, P_, M, rhs, rhs + N, rhs + N + P_, dx, dy, dz, 5) >= 0,
          "kkt solve");
    double err = 0.0, scale = 1.0;
    for (int i = 0; i < N; i++) err = fmax(err, fabs(dx[i] - ref[i]));
    for (int i = 0; i < P_; i++) err = fmax(err, fabs(dy[i] - ref[N + i]));
    for (int i = 0; i < M; i++) err = fmax(err, fabs(dz[i] - ref[N + P_ + i]));
    for (int i = 0; i < DIM; i++) scale = fmax(scale, fabs(ref[i]));
    CHECK(err < 1e-8 * scale, "backend %d dense_max %d P %d: |x - x_ref| = %g (scale %g)",
          backend, dense_max, with_P, err, scale);
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
    tscvx_arena a = {arena, bytes, 0, 0, 0};
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

int main(void) {
    for (int rep = 0; rep < 20; rep++) /* both KKT backends */
        for (int backend = TSCVX_KKT_LDL; backend <= TSCVX_KKT_STATIC; backend++) {
            run(16, rep % 2, backend);
            run(3, rep % 2, backend);
            run(1, rep % 2, backend);
        }
    for (int rep = 0; rep < 200; rep++) /* dims 1..60, sparse to dense */
        run_static_vs_ldl(1 + rep % QD_MAX, rep < 100 ? 0.08 : 0.3);
    return ct_report("test_kkt");
}
