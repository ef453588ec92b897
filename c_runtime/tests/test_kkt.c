/* KKT system: pattern + maps + factor (supernodal and SuiteSparse LDL backends) and refined
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

int main(void) {
    for (int rep = 0; rep < 20; rep++) /* both KKT backends */
        for (int backend = TSCVX_KKT_SUPERNODAL; backend <= TSCVX_KKT_LDL; backend++) {
            run(16, rep % 2, backend);
            run(3, rep % 2, backend);
            run(1, rep % 2, backend);
        }
    return ct_report("test_kkt");
}
