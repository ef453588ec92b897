/* Cone operations: Jordan product/division, NT scaling, step to the boundary, shift, the
 * interior test of the warm start. */
#include "ctest_util.h"
#include "socp_internal.h"

#define L 3
#define NSOC 4 /* sizes 3 and 4 take the runtime's unrolled kernels, 1 and 6 the general ones */
static const tscvx_int q[NSOC] = {1, 3, 4, 6};
static const tscvx_int off[NSOC] = {3, 4, 7, 11};
#define M 17

static tscvx_cones cones(void) {
    tscvx_cones K = {L, NSOC, q, off, M, L + NSOC};
    return K;
}

/* random point in int K with eigenvalues in [lo, lo + 2] */
static void interior(const tscvx_cones *K, tscvx_float *u, double lo) {
    for (int i = 0; i < K->l; i++) u[i] = lo + 2.0 * ct_rand();
    for (int k = 0; k < K->nsoc; k++) {
        double nrm = 0.0;
        for (int j = 1; j < K->q[k]; j++) {
            u[K->off[k] + j] = ct_randn();
            nrm += u[K->off[k] + j] * u[K->off[k] + j];
        }
        u[K->off[k]] = sqrt(nrm) + lo + 2.0 * ct_rand();
    }
}

static double maxdiff(const tscvx_float *a, const tscvx_float *b, int n) {
    double d = 0.0;
    for (int i = 0; i < n; i++) d = fmax(d, fabs(a[i] - b[i]));
    return d;
}

static int in_cone(const tscvx_cones *K, const tscvx_float *u, double tol) {
    for (int i = 0; i < K->l; i++)
        if (u[i] < -tol) return 0;
    for (int k = 0; k < K->nsoc; k++) {
        double nrm = 0.0;
        for (int j = 1; j < K->q[k]; j++) nrm += u[K->off[k] + j] * u[K->off[k] + j];
        if (u[K->off[k]] < sqrt(nrm) - tol) return 0;
    }
    return 1;
}

static void test_product_division(void) {
    tscvx_cones K = cones();
    tscvx_float u[M], v[M], w[M], back[M];
    for (int trial = 0; trial < 100; trial++) {
        interior(&K, u, 0.01);
        for (int i = 0; i < M; i++) v[i] = ct_randn();
        tscvx_cone_div(&K, u, v, w);
        tscvx_cone_prod(&K, u, w, back);
        CHECK(maxdiff(back, v, M) < 1e-9, "u o (u \\ v) != v: %g", maxdiff(back, v, M));
    }
    /* identity e: e o v = v */
    tscvx_float e[M] = {0};
    tscvx_cone_add_identity(&K, e, 1.0);
    for (int i = 0; i < M; i++) v[i] = ct_randn();
    tscvx_cone_prod(&K, e, v, w);
    CHECK(maxdiff(w, v, M) < 1e-15, "e o v != v");
}

static void test_nt_scaling(void) {
    tscvx_cones K = cones();
    tscvx_float s[M], z[M], w[M], eta[NSOC], lam[M], t1[M], t2[M];
    tscvx_nt W = {w, eta};
    for (int trial = 0; trial < 200; trial++) {
        interior(&K, s, trial % 2 ? 1e-6 : 0.5);
        interior(&K, z, trial % 3 ? 0.5 : 1e-6);
        CHECK(tscvx_nt_scaling(&K, s, z, &W, lam) == 0, "scaling failed");
        tscvx_nt_apply(&K, &W, 0, z, t1); /* lambda = W z */
        tscvx_nt_apply(&K, &W, 1, s, t2); /* lambda = W^{-1} s */
        double scale = 1.0 + fabs(lam[0]);
        for (int i = 0; i < M; i++) scale = fmax(scale, fabs(lam[i]));
        CHECK(maxdiff(t1, lam, M) < 1e-8 * scale, "W z != lambda: %g", maxdiff(t1, lam, M));
        CHECK(maxdiff(t2, lam, M) < 1e-8 * scale, "W^-1 s != lambda: %g", maxdiff(t2, lam, M));
        CHECK(in_cone(&K, lam, 0.0), "lambda not in K");
        /* W W^{-1} v = v */
        for (int i = 0; i < M; i++) t1[i] = ct_randn();
        tscvx_nt_apply(&K, &W, 1, t1, t2);
        tscvx_nt_apply(&K, &W, 0, t2, s);
        CHECK(maxdiff(s, t1, M) < 1e-9, "W W^-1 != I: %g", maxdiff(s, t1, M));
        /* the fused passes give exactly the two-pass results */
        tscvx_float t3[M], t4[M], t5[M];
        tscvx_nt_apply(&K, &W, 0, t1, t2);
        tscvx_nt_apply(&K, &W, 0, t2, t3);
        tscvx_nt_apply2(&K, &W, t1, t4, t5);
        CHECK(maxdiff(t3, t5, M) == 0.0, "nt_apply2 != W W v: %g", maxdiff(t3, t5, M));
        tscvx_cone_div(&K, lam, t1, t2);
        tscvx_nt_apply(&K, &W, 0, t2, t3);
        tscvx_nt_div_apply(&K, &W, lam, t1, t4, t5);
        CHECK(maxdiff(t3, t5, M) == 0.0, "nt_div_apply != W (lam \\ v): %g", maxdiff(t3, t5, M));
        /* det wbar = 1 on each SOC */
        for (int k = 0; k < NSOC; k++) {
            double nrm = 0.0;
            for (int j = 1; j < q[k]; j++) nrm += w[off[k] + j] * w[off[k] + j];
            CHECK(fabs(w[off[k]] * w[off[k]] - nrm - 1.0) < 1e-9, "det wbar != 1");
        }
    }
    /* a point outside the cone is refused */
    interior(&K, s, 0.5);
    interior(&K, z, 0.5);
    s[off[2]] = -1.0;
    CHECK(tscvx_nt_scaling(&K, s, z, &W, lam) != 0, "exterior s accepted");
}

static void test_max_step(void) {
    tscvx_cones K = cones();
    tscvx_float u[M], du[M], t[M];
    int limited = 0;
    for (int trial = 0; trial < 500; trial++) {
        interior(&K, u, 0.01);
        for (int i = 0; i < M; i++) du[i] = 3.0 * ct_randn();
        const double a = tscvx_cone_max_step(&K, u, du, 1e3);
        CHECK(a > 0.0 && a <= 1e3, "step out of range: %g", a);
        for (int i = 0; i < M; i++) t[i] = u[i] + 0.999 * a * du[i];
        CHECK(in_cone(&K, t, 1e-12), "0.999 alpha leaves the cone");
        if (a < 1e3) {
            limited++;
            for (int i = 0; i < M; i++) t[i] = u[i] + 1.001 * a * du[i];
            CHECK(!in_cone(&K, t, 0.0), "1.001 alpha still inside (alpha %g)", a);
        }
    }
    CHECK(limited > 100, "too few limited steps: %d", limited);
    /* direction inside the cone: unlimited */
    interior(&K, u, 0.5);
    interior(&K, du, 0.5);
    CHECK(tscvx_cone_max_step(&K, u, du, 7.0) == 7.0, "direction in K limited");
}

static void test_shift(void) {
    tscvx_cones K = cones();
    tscvx_float u[M];
    for (int trial = 0; trial < 100; trial++) {
        for (int i = 0; i < M; i++) u[i] = 2.0 * ct_randn();
        const double t = tscvx_cone_shift_needed(&K, u);
        tscvx_cone_add_identity(&K, u, t + 1e-9);
        CHECK(in_cone(&K, u, 0.0), "shifted point not in K");
        tscvx_cone_add_identity(&K, u, -2e-6);
        CHECK(!in_cone(&K, u, 0.0), "shift not minimal");
    }
}

/* copy_interior takes a u block exactly where that block alone is strictly inside its cone */
static void test_copy_interior(void) {
    tscvx_cones K = cones();
    tscvx_float u[M], dst[M];
    for (int trial = 0; trial < 100; trial++) {
        for (int i = 0; i < M; i++) u[i] = 2.0 * ct_randn(), dst[i] = 100.0 + i;
        u[0] = 0.0;                                  /* an orthant boundary: not inside */
        u[off[1]] = hypot(u[off[1] + 1], u[off[1] + 2]); /* an SOC boundary */
        tscvx_cone_copy_interior(&K, u, dst);
        for (int i = 0; i < K.l; i++)
            CHECK(dst[i] == (u[i] > 0.0 ? u[i] : 100.0 + i), "orthant row %d", i);
        for (int k = 0; k < K.nsoc; k++) {
            double nrm = 0.0;
            for (int j = 1; j < q[k]; j++) nrm += u[off[k] + j] * u[off[k] + j];
            const int inside = sqrt(nrm) < u[off[k]];
            for (int j = 0; j < q[k]; j++)
                CHECK(dst[off[k] + j] == (inside ? u[off[k] + j] : 100.0 + off[k] + j),
                      "SOC %d entry %d", k, j);
        }
    }
}

/* 10^U(-6, 3): the sizes of an answer's slacks and multipliers */
static double magnitude(void) { return pow(10.0, -6.0 + 9.0 * ct_rand()); }

/* center_pair: complementary s, z (s'z = 0 on each cone, either or both on the boundary, of
 * any size) end strictly inside their cones with each cone's s'z in [mu/4, 5 mu/4] */
static void test_center_pair(void) {
    tscvx_cones K = cones();
    tscvx_float s[M], z[M];
    const double mus[] = {1e-4, 1.0};
    for (int trial = 0; trial < 200; trial++) {
        const double mu = mus[trial % 2];
        for (int i = 0; i < K.l; i++) { /* s = 0, z = 0 or both 0 */
            const int which = (int)(3.0 * ct_rand());
            s[i] = which == 0 ? magnitude() : 0.0;
            z[i] = which == 1 ? magnitude() : 0.0;
        }
        for (int k = 0; k < K.nsoc; k++) { /* s = a (1, u), z = b (1, -u), |u| = 1 */
            const tscvx_int o = off[k];
            double nrm = 0.0;
            for (int j = 1; j < q[k]; j++) s[o + j] = ct_randn(), nrm += s[o + j] * s[o + j];
            const double a = ct_rand() < 0.2 ? 0.0 : magnitude();
            const double b = ct_rand() < 0.2 ? 0.0 : magnitude();
            s[o] = a, z[o] = b;
            if (q[k] == 1 && a > 0.0) z[o] = 0.0; /* Q^1 is a ray: one of them 0 */
            for (int j = 1; j < q[k]; j++) {
                const double uj = s[o + j] / sqrt(nrm);
                s[o + j] = a * uj, z[o + j] = -b * uj;
            }
        }
        tscvx_float s2[M], z2[M];
        for (int i = 0; i < M; i++) s2[i] = s[i], z2[i] = z[i];
        tscvx_cone_center_pair(&K, s2, z2, mu);
        CHECK(tscvx_cone_shift_needed(&K, s2) < 0.0 && tscvx_cone_shift_needed(&K, z2) < 0.0,
              "centred point not strictly inside");
        for (int c = 0; c < K.l + K.nsoc; c++) {
            const tscvx_int o = c < K.l ? c : off[c - K.l], len = c < K.l ? 1 : q[c - K.l];
            double before = 0.0, after = 0.0;
            for (int j = 0; j < len; j++) before += s[o + j] * z[o + j], after += s2[o + j] * z2[o + j];
            const double gain = after - before;
            CHECK(gain >= 0.25 * mu * (1.0 - 1e-9) && gain <= 1.25 * mu * (1.0 + 1e-9),
                  "cone %d: s'z grew by %g for mu %g", c, gain, mu);
        }
    }
}

int main(void) {
    test_product_division();
    test_nt_scaling();
    test_max_step();
    test_shift();
    test_copy_interior();
    test_center_pair();
    return ct_report("test_cones");
}
