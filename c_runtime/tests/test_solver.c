/* End-to-end solves with known answers, infeasibility, bad input, data updates, log. */
#define _POSIX_C_SOURCE 200809L /* sigaction, mprotect, sysconf: test_upset_during_solve */
                                /* and test_upset_during_update */
#include <signal.h>
#include <string.h>
#include <sys/mman.h>
#include <unistd.h>

#include "ctest_util.h"
#include "socp_internal.h"
#include "tscvx_socp.h"

static unsigned char arena[1 << 16], arena2[1 << 16];

static tscvx_solve_status solve(const tscvx_data *d, tscvx_float *x, tscvx_info *info) {
    tscvx_settings st;
    tscvx_default_settings(&st);
    tscvx_workspace *ws = NULL;
    size_t nscratch = 0, narena = 0;
    CHECK(tscvx_scratch_size(d, &st, &nscratch) == TSCVX_SETUP_OK, "scratch size");
    CHECK(nscratch <= sizeof arena, "scratch %zu", nscratch);
    CHECK(tscvx_workspace_size(d, &st, arena, sizeof arena, &narena) == TSCVX_SETUP_OK, "size");
    CHECK(tscvx_setup(&ws, arena, narena, d, &st) == TSCVX_SETUP_OK, "setup");
    if (ws == NULL) return TSCVX_INVALID_INPUT;
    const tscvx_solve_status s = tscvx_solve(ws);
    tscvx_get_info(ws, info);
    CHECK(info->arena_high_water <= narena, "high water %zu > %zu", info->arena_high_water, narena);
    if (x) tscvx_get_solution(ws, x, NULL, NULL, NULL);
    return s;
}

/* min -x1 - x2 s.t. |(x1, x2)| <= 1 (one second-order cone of 3 rows): x = (1, 1)/sqrt(2).
 * The arrays live in *p, which must outlive the data. */
typedef struct {
    tscvx_int Gp[3], Gi[2], q[1];
    tscvx_float Gx[2], h[3], c[2];
} small_soc;

static tscvx_data small_soc_data(small_soc *p) {
    const small_soc v = {{0, 1, 2}, {1, 2}, {3}, {-1, -1}, {1, 0, 0}, {-1, -1}};
    *p = v;
    const tscvx_data d = {2,    0,    3,     NULL,  NULL,  NULL, p->c, NULL, NULL,
                          NULL, NULL, p->Gp, p->Gi, p->Gx, p->h, 0,    1,    p->q};
    return d;
}

static void test_soc(void) {
    small_soc p;
    const tscvx_data d = small_soc_data(&p);
    tscvx_float x[2];
    tscvx_info info;
    CHECK(solve(&d, x, &info) == TSCVX_SOLVED, "soc status");
    CHECK(fabs(x[0] - sqrt(0.5)) < 1e-7 && fabs(x[1] - sqrt(0.5)) < 1e-7, "soc x %g %g", x[0], x[1]);
    CHECK(fabs(info.pcost + sqrt(2.0)) < 1e-7, "soc obj %g", info.pcost);
}

/* min 1/2 (x1^2 + x2^2) - x1 s.t. x1 + x2 = 0, x2 >= -10 */
static void test_qp(void) {
    tscvx_int Pp[] = {0, 1, 2}, Pi[] = {0, 1}, Ap[] = {0, 1, 2}, Ai[] = {0, 0};
    tscvx_int Gp[] = {0, 0, 1}, Gi[] = {0};
    tscvx_float Px[] = {1, 1}, c[] = {-1, 0}, Ax[] = {1, 1}, b[] = {0}, Gx[] = {-1}, h[] = {10};
    tscvx_float x[2];
    tscvx_data d = {2, 1, 1, Pp, Pi, Px, c, Ap, Ai, Ax, b, Gp, Gi, Gx, h, 1, 0, NULL};
    tscvx_info info;
    CHECK(solve(&d, x, &info) == TSCVX_SOLVED, "qp status");
    CHECK(fabs(x[0] - 0.5) < 1e-7 && fabs(x[1] + 0.5) < 1e-7, "qp x %g %g", x[0], x[1]);
    CHECK(fabs(info.pcost + 0.25) < 1e-8, "qp obj %g", info.pcost);
}

/* x >= 1 and x <= 0: primal infeasible; min -x s.t. x >= 0: dual infeasible */
static void test_infeasible(void) {
    tscvx_int Gp[] = {0, 2}, Gi[] = {0, 1};
    tscvx_float Gx[] = {-1, 1}, h[] = {-1, 0}, c[] = {1};
    tscvx_data d = {1, 0, 2, NULL, NULL, NULL, c, NULL, NULL, NULL, NULL, Gp, Gi, Gx, h, 2, 0, NULL};
    tscvx_info info;
    tscvx_float x[1] = {0.0};
    CHECK(solve(&d, x, &info) == TSCVX_PRIMAL_INFEASIBLE, "primal infeasible");
    CHECK(isnan(x[0]), "x of a primal certificate is NaN (no solution)");
    tscvx_int Gp2[] = {0, 1}, Gi2[] = {0};
    tscvx_float Gx2[] = {-1}, h2[] = {0}, c2[] = {-1};
    tscvx_data d2 = {1, 0, 1, NULL, NULL, NULL, c2, NULL, NULL, NULL, NULL, Gp2, Gi2, Gx2, h2,
                     1, 0, NULL};
    CHECK(solve(&d2, x, &info) == TSCVX_DUAL_INFEASIBLE, "dual infeasible");
    CHECK(fabs(c2[0] * x[0] + 1.0) < 1e-12, "the dual certificate normalized: c'x = -1");
}

/* Found by make fuzz (c_runtime/fuzz/corpus/socp/certificate_overflow): A x = b with four rows
 * of which three are empty and b = DBL_MIN (2.2e-308) in each, infeasible (0 = DBL_MIN), had
 * its primal certificate normalized to b'y = -1 by dividing by a b'y of the order of 1e-308:
 * y came out as +-inf, and b'y as NaN, under a PRIMAL_INFEASIBLE status (the problem set up
 * with b = (-1.5625, DBL_MIN, DBL_MIN, DBL_MIN), then updated and warm-started; tolerances
 * DBL_MIN). A
 * certificate that cannot be normalized to finite numbers is not one: whatever the status,
 * every number returned is finite, and a certificate is normalized. */
static void check_certificate_finite(tscvx_workspace *ws, const tscvx_float *b, const char *when) {
    const tscvx_solve_status s = tscvx_solve(ws);
    tscvx_float x[1], y[4];
    if (tscvx_get_solution(ws, x, y, NULL, NULL) != TSCVX_SETUP_OK) return;
    if (s == TSCVX_DUAL_INFEASIBLE) return;
    double by = 0.0;
    for (int i = 0; i < 4; i++) {
        CHECK(isfinite(y[i]), "certificate_finite, %s (status %d): y[%d] = %g", when, (int)s, i,
              y[i]);
        by += b[i] * y[i];
    }
    if (s == TSCVX_PRIMAL_INFEASIBLE)
        CHECK(fabs(by + 1.0) < 1e-6, "certificate_finite, %s: b'y = %g", when, by);
}

static void test_certificate_finite(void) {
    const tscvx_float tiny = 2.2250738585072014e-308;
    tscvx_int Ap[] = {0, 1}, Ai[] = {2};
    tscvx_float Ax[] = {tiny}, b[] = {-1.5625, tiny, tiny, tiny}, c[] = {tiny};
    tscvx_float b2[] = {tiny, tiny, tiny, tiny}, c2[] = {2.5};
    const tscvx_data d = {1, 4, 0, NULL, NULL, NULL, c, Ap, Ai, Ax, b, NULL, NULL, NULL, NULL,
                          0, 0, NULL};
    tscvx_settings st;
    tscvx_default_settings(&st);
    st.kkt_backend = TSCVX_KKT_STATIC;
    st.max_iter = 165;
    st.tol_feas = st.tol_gap_abs = st.tol_gap_rel = tiny;
    tscvx_workspace *ws = NULL;
    size_t narena = 0;
    CHECK(tscvx_workspace_size(&d, &st, arena, sizeof arena, &narena) == TSCVX_SETUP_OK &&
              tscvx_setup(&ws, arena, narena, &d, &st) == TSCVX_SETUP_OK,
          "certificate_finite: setup");
    if (ws == NULL) return;
    check_certificate_finite(ws, b, "first data");
    CHECK(tscvx_update_data(ws, NULL, c2, NULL, b2, NULL, NULL) == TSCVX_SETUP_OK,
          "certificate_finite: update");
    check_certificate_finite(ws, b2, "updated");
    /* the fuzz input's sequence: the update, then a warm start, then the solve */
    CHECK(tscvx_update_data(ws, NULL, c2, NULL, b2, NULL, NULL) == TSCVX_SETUP_OK,
          "certificate_finite: update");
    const tscvx_float wx[] = {tiny}, wy[] = {tiny, -3.625, -4, -4};
    CHECK(tscvx_warm_start(ws, wx, wy, NULL, NULL) == TSCVX_SETUP_OK,
          "certificate_finite: warm start");
    check_certificate_finite(ws, b2, "updated, warm-started");
}

/* Found by make fuzz (c_runtime/fuzz/corpus/socp/certificate_cancellation): min 1/2 P x^2 - 4x
 * with P = 1.5e135, -3.9375 x = -4, and G x + s = h = -4 in R_+ x Q^3 with G's only entry in
 * the cone's first row: the orthant row (0 + s = -4) makes it infeasible; (y, z) = (0, (1/4,
 * 0, 0, 0)) is a certificate. The test of a primal certificate took A'y + G'z as
 * rx - Px - c tau, a difference of numbers of the order of P x (1e135 in scaled units) that
 * keeps nothing of it: a (y, z) with A'y + G'z = 0.1 (z = (5e-43, 0.104, 0.073, 0.073)) was
 * returned as the certificate. The certificate returned must meet its equations, here from
 * the caller's numbers: |A'y + G'z| small against |A, G| |y, z|, b'y + h'z = -1, z in K. Set
 * up with other numbers and updated, as the fuzz input did, and set up directly. */
static void check_primal_certificate(tscvx_workspace *ws, const tscvx_float *Ax, const tscvx_float *Gx,
                                     const tscvx_float *b, const tscvx_float *h, const char *when) {
    const tscvx_solve_status s = tscvx_solve(ws);
    if (s != TSCVX_PRIMAL_INFEASIBLE) return; /* only a claimed certificate is checked */
    tscvx_float y[1], z[4];
    CHECK(tscvx_get_solution(ws, NULL, y, z, NULL) == TSCVX_SETUP_OK, "%s: solution", when);
    const double aty = Ax[0] * y[0] + Gx[0] * z[1];
    const double size = fmax(fabs(Ax[0] * y[0]), fabs(Gx[0] * z[1]));
    const double obj = b[0] * y[0] + h[0] * (z[0] + z[1] + z[2] + z[3]);
    CHECK(fabs(aty) <= 1e-6 * fmax(size, 1.0), "certificate_cancellation, %s: A'y + G'z = %g "
          "(z = %g %g %g %g)", when, aty, z[0], z[1], z[2], z[3]);
    CHECK(fabs(obj + 1.0) < 1e-6, "certificate_cancellation, %s: b'y + h'z = %g", when, obj);
    CHECK(z[0] >= 0.0 && z[1] >= hypot(z[2], z[3]) * (1.0 - 1e-12),
          "certificate_cancellation, %s: z outside the cones", when);
}

static void test_certificate_cancellation(void) {
    tscvx_int Pp[] = {0, 1}, Pi[] = {0}, Ap[] = {0, 1}, Ai[] = {0}, Gp[] = {0, 1}, Gi[] = {1};
    tscvx_int q[] = {3};
    tscvx_float Px[] = {3.0625}, Ax[] = {6.5185151242703548e+91}, Gx[] = {0.5}, c[] = {0.0625};
    tscvx_float b[] = {1}, h[] = {-4, -4, -4, -4};
    tscvx_float Px2[] = {1.5445322891281643e+135}, Ax2[] = {-3.9375}, Gx2[] = {1}, c2[] = {-4};
    tscvx_float b2[] = {-4};
    const tscvx_data d = {1, 1, 4, Pp, Pi, Px, c, Ap, Ai, Ax, b, Gp, Gi, Gx, h, 1, 1, q};
    const tscvx_data d2 = {1, 1, 4, Pp, Pi, Px2, c2, Ap, Ai, Ax2, b2, Gp, Gi, Gx2, h, 1, 1, q};
    const tscvx_data *start[] = {&d, &d2};
    for (int k = 0; k < 2; k++) {
        tscvx_settings st;
        tscvx_default_settings(&st);
        st.max_iter = 30;
        tscvx_workspace *ws = NULL;
        size_t narena = 0;
        CHECK(tscvx_workspace_size(start[k], &st, arena, sizeof arena, &narena) == TSCVX_SETUP_OK &&
                  tscvx_setup(&ws, arena, narena, start[k], &st) == TSCVX_SETUP_OK,
              "certificate_cancellation: setup");
        if (ws == NULL) continue;
        if (k == 0) {
            check_primal_certificate(ws, Ax, Gx, b, h, "first numbers");
            CHECK(tscvx_update_data(ws, Px2, c2, Ax2, b2, Gx2, h) == TSCVX_SETUP_OK,
                  "certificate_cancellation: update");
        }
        check_primal_certificate(ws, Ax2, Gx2, b2, h, k == 0 ? "updated" : "set up directly");
    }
}

/* Scaling the objective (c) or the right-hand sides (b, h) of a feasible, bounded problem by
 * 1e8 or 1e10 leaves it feasible and bounded, with the same x (c scaled) or x scaled likewise
 * (b, h scaled): no certificate may be claimed. Both problems are random_feasible(142) and
 * (450) of tests/socp_problems.py (a strictly feasible primal and dual by construction), in
 * the C form; with the certificate tests unscaled by the data, the first was certified dual
 * infeasible at c x 1e8 and the second primal infeasible at b, h x 1e10. */
typedef struct {
    tscvx_int n, p, m, l, nsoc;
    tscvx_int q[1], Ap[5], Ai[4], Gp[5], Gi[11];
    tscvx_float Ax[4], b[2], Gx[11], h[9], c[4];
} scaled_case;

static void check_scaled(const scaled_case *k, const char *name) {
    tscvx_float c[4], b[2], h[9], x1[4], x[4];
    tscvx_info info;
    tscvx_data d = {k->n, k->p, k->m, NULL, NULL, NULL, c,     k->Ap,   k->Ai,
                    k->Ax, b,    k->Gp, k->Gi, k->Gx, h,    k->l, k->nsoc, k->q};
    const double scales[] = {1e8, 1e10};
    memcpy(c, k->c, sizeof c), memcpy(b, k->b, sizeof b), memcpy(h, k->h, sizeof h);
    CHECK(solve(&d, x1, &info) == TSCVX_SOLVED, "%s: unscaled status %d", name, (int)info.status);
    for (int t = 0; t < 4; t++) {
        const double sigma = scales[t % 2], xs = t < 2 ? 1.0 : sigma;
        for (int j = 0; j < k->n; j++) c[j] = (t < 2 ? sigma : 1.0) * k->c[j];
        for (int i = 0; i < k->p; i++) b[i] = xs * k->b[i];
        for (int i = 0; i < k->m; i++) h[i] = xs * k->h[i];
        const tscvx_solve_status st = solve(&d, x, &info);
        CHECK(st == TSCVX_SOLVED, "%s, %s x %g: status %d (%s)", name, t < 2 ? "c" : "b, h",
              sigma, (int)st, tscvx_solve_status_message(st));
        double err = 0.0, ref = 1.0;
        for (int j = 0; j < k->n; j++) err = fmax(err, fabs(x[j] - xs * x1[j])), ref = fmax(ref, fabs(xs * x1[j]));
        CHECK(st != TSCVX_SOLVED || err <= 1e-6 * ref, "%s, scale %g: x off by %g", name, sigma, err / ref);
    }
}

static void test_no_false_certificate_when_scaled(void) {
    static const scaled_case cone_only = {
        3, 0, 9, 3, 1, {6}, {0, 0, 0, 0}, {0}, {0, 5, 7, 11},
        {0, 1, 5, 6, 8, 0, 1, 0, 1, 2, 7}, {0},  {0},
        {0.4951618319949431, 0.46478873676452725, 0.9537126427457258, 1.2264244461902316,
         0.4018092464445234, 1.5953175346398967, 1.0, -1.4571115550435068,
         -0.45821642402202123, 1.0, 0.15629217154375186},
        {-1.988827577731574, -0.03912014821583365, 2.2018905107219675, 3.6622952898653427,
         -0.7864615164354726, -0.9298534856220507, 3.603289636772952, 0.4129822493991595,
         0.8599864149149063},
        {-2.621278455742447, -3.531719440525511, 1.1485190439085087}};
    static const scaled_case with_equalities = {
        4, 2, 9, 5, 1, {4}, {0, 1, 2, 4, 4}, {0, 1, 0, 1}, {0, 3, 4, 8, 11},
        {0, 3, 6, 1, 0, 3, 4, 6, 1, 2, 4},
        {1.0, 1.0, 0.4396555843900086, 1.0099104023039271},
        {0.08202922453355416, 1.4470663646722621},
        {-0.1345429617997881, 1.3368020199455426, -0.5942822162789441, 0.2591329870878727, 1.0,
         0.8688277815327541, 0.42245486355636785, 1.9912420081704167, 1.0,
         0.14911858985757978, 0.11859072351359756},
        {1.3623672043180712, -0.1312474072295628, 0.42928977660983525, 0.4078144182795981,
         2.0723706208280186, 2.5386402456492365, 2.602352594790859, 0.2543154262231661,
         0.4535170169701874},
        {-3.6566623345038276, -0.16553482317817678, -1.4933010887367797, -1.2776060978401982}};
    check_scaled(&cone_only, "cones only");
    check_scaled(&with_equalities, "with equalities");
}

static tscvx_setup_status try_setup(const tscvx_data *d) {
    tscvx_settings st;
    tscvx_default_settings(&st);
    tscvx_workspace *ws = NULL;
    return tscvx_setup(&ws, arena, sizeof arena, d, &st);
}

static void test_bad_input(void) {
    tscvx_int Pp[] = {0, 1, 2}, Pi[] = {0, 1}, Gp[] = {0, 1, 2}, Gi[] = {1, 2}, q[] = {3};
    tscvx_float Px[] = {1, 1}, Gx[] = {-1, -1}, h[] = {1, 0, 0}, c[] = {-1, -1};
    tscvx_data ok = {2, 0, 3, Pp, Pi, Px, c, NULL, NULL, NULL, NULL, Gp, Gi, Gx, h, 0, 1, q};
    CHECK(try_setup(&ok) == TSCVX_SETUP_OK, "valid data refused");
    { /* a refused set-up leaves *ws NULL, a NULL arena too (it left *ws untouched) */
        tscvx_settings st;
        tscvx_default_settings(&st);
        tscvx_workspace *ws = (tscvx_workspace *)(void *)arena;
        CHECK(tscvx_setup(&ws, NULL, sizeof arena, &ok, &st) == TSCVX_SETUP_NULL_ARGUMENT &&
                  ws == NULL, "NULL arena: *ws %p", (void *)ws);
    }
    char msg[TSCVX_MESSAGE_LEN];
    CHECK(tscvx_check_data(&ok, msg) == TSCVX_SETUP_OK && msg[0] == '\0', "check_data(ok)");
    tscvx_data d = ok;
    tscvx_float cnan[] = {NAN, 1};
    d.c = cnan;
    CHECK(try_setup(&d) == TSCVX_SETUP_NONFINITE_DATA, "NaN accepted");
    /* tscvx_check_data: the status of setup, and the array and entry at fault */
#define NAMES(data, status, text)                                                        \
    CHECK(tscvx_check_data(&(data), msg) == (status) && strstr(msg, (text)) != NULL,       \
          "check_data: '%s', expected '%s'", msg, (text))
    NAMES(d, TSCVX_SETUP_NONFINITE_DATA, "c[0] = nan");
    d = ok;
    tscvx_float hinf[] = {INFINITY, 0, 0};
    d.h = hinf;
    CHECK(try_setup(&d) == TSCVX_SETUP_NONFINITE_DATA, "inf accepted");
    d = ok;
    tscvx_int qbig[] = {4};
    d.q = qbig;
    CHECK(try_setup(&d) == TSCVX_SETUP_BAD_CONES, "cone larger than the rows accepted");
    NAMES(d, TSCVX_SETUP_BAD_CONES, "the cones up to q[0] need 4 rows, G has m = 3");
    d = ok;
    tscvx_int Pp2[] = {0, 2, 2}, Pi2[] = {0, 1};
    d.Pp = Pp2, d.Pi = Pi2;
    CHECK(try_setup(&d) == TSCVX_SETUP_P_NOT_UPPER, "lower-triangular P accepted");
    NAMES(d, TSCVX_SETUP_P_NOT_UPPER, "P: entry (1, 0) below the diagonal");
    d = ok;
    tscvx_int Gi3[] = {5, 2};
    d.Gi = Gi3;
    CHECK(try_setup(&d) == TSCVX_SETUP_BAD_SPARSITY, "row index out of range accepted");
    NAMES(d, TSCVX_SETUP_BAD_SPARSITY, "G: row index 5 in column 0 is outside 0..2");
    d = ok;
    d.m = 4;
    CHECK(try_setup(&d) == TSCVX_SETUP_BAD_CONES, "dimension mismatch accepted");
    d = ok;
    d.n = 0;
    CHECK(try_setup(&d) == TSCVX_SETUP_BAD_DIMENSIONS, "n = 0 accepted");
    d = ok;
    d.c = NULL;
    CHECK(try_setup(&d) == TSCVX_SETUP_NULL_ARGUMENT, "NULL c accepted");
    CHECK(try_setup(NULL) == TSCVX_SETUP_NULL_ARGUMENT, "NULL data accepted");
    tscvx_settings st;
    tscvx_default_settings(&st);
    st.step_fraction = 1.5;
    tscvx_workspace *ws = NULL;
    CHECK(tscvx_setup(&ws, arena, sizeof arena, &ok, &st) == TSCVX_SETUP_BAD_SETTINGS,
          "bad settings accepted");
    /* the documented bounds: max_iter <= 500, step_fraction < 1 */
    tscvx_default_settings(&st);
    st.max_iter = 500;
    CHECK(tscvx_setup(&ws, arena, sizeof arena, &ok, &st) == TSCVX_SETUP_OK, "max_iter 500");
    st.max_iter = 501;
    CHECK(tscvx_setup(&ws, arena, sizeof arena, &ok, &st) == TSCVX_SETUP_BAD_SETTINGS,
          "max_iter 501 accepted");
    tscvx_default_settings(&st);
    st.step_fraction = 1.0;
    CHECK(tscvx_setup(&ws, arena, sizeof arena, &ok, &st) == TSCVX_SETUP_BAD_SETTINGS,
          "step_fraction 1 accepted");
    /* a row index repeated in a column of G */
    d = ok;
    tscvx_int Gp4[] = {0, 2, 3}, Gi4[] = {1, 1, 2};
    tscvx_float Gx4[] = {-1, -1, -1};
    d.Gp = Gp4, d.Gi = Gi4, d.Gx = Gx4;
    CHECK(try_setup(&d) == TSCVX_SETUP_BAD_SPARSITY, "duplicate row index accepted");
    NAMES(d, TSCVX_SETUP_BAD_SPARSITY, "G: row indices of column 0 not strictly increasing");
    /* p = 0 with A's pointers given, not monotone, and no row indices: refused, not read */
    d = ok;
    tscvx_int Ap5[] = {0, 1, 0};
    d.Ap = Ap5, d.Ai = NULL;
    CHECK(try_setup(&d) == TSCVX_SETUP_BAD_SPARSITY, "non-monotone pointers accepted");
    tscvx_int Ap6[] = {0, 1, 1};
    d.Ap = Ap6;
    CHECK(try_setup(&d) == TSCVX_SETUP_BAD_SPARSITY, "entries in a matrix of no rows accepted");
    d = ok;
    d.Gi = NULL;
    CHECK(try_setup(&d) == TSCVX_SETUP_NULL_ARGUMENT, "NULL row indices accepted");
    NAMES(d, TSCVX_SETUP_NULL_ARGUMENT, "Gp, Gi, Gx or h is NULL with m = 3");
    CHECK(tscvx_check_data(NULL, msg) == TSCVX_SETUP_NULL_ARGUMENT, "check_data(NULL)");
    d = ok;
    d.q = NULL; /* a NULL pointer, as the others (it was BAD_CONES) */
    NAMES(d, TSCVX_SETUP_NULL_ARGUMENT, "nsoc = 1, q NULL");
#undef NAMES
    tscvx_default_settings(&st);
    CHECK(tscvx_setup(&ws, arena, 64, &ok, &st) == TSCVX_SETUP_ARENA_TOO_SMALL, "tiny arena");
    CHECK(tscvx_solve(NULL) == TSCVX_INVALID_INPUT, "solve(NULL)");
    for (int s = 0; s <= TSCVX_SETUP_NSTATUS; s++)
        CHECK(tscvx_setup_status_message((tscvx_setup_status)s) != NULL, "message");
    for (int s = 0; s <= TSCVX_NSTATUS; s++)
        CHECK(tscvx_solve_status_message((tscvx_solve_status)s) != NULL, "message");
}

/* update: same sparsity, new numbers; NaN update invalidates until a valid one; a solve after
 * an update takes the same steps as one after a fresh setup with those numbers (the
 * equilibration is redone, the kept numbers recovered from their scaled copies, to rounding),
 * and after updates that resend every part gives the same bits */
static void test_update(void) {
    small_soc p;
    const tscvx_data d = small_soc_data(&p);
    tscvx_float x[2];
    tscvx_settings st;
    tscvx_default_settings(&st);
    tscvx_workspace *ws = NULL;
    tscvx_iter_log row;
    CHECK(tscvx_setup(&ws, arena, sizeof arena, &d, &st) == TSCVX_SETUP_OK, "setup");
    CHECK(tscvx_get_iter_log(ws, 0, &row) == TSCVX_SETUP_NO_SOLUTION, "log before a solve");
    CHECK(tscvx_get_solution(ws, x, NULL, NULL, NULL) == TSCVX_SETUP_NO_SOLUTION,
          "solution before a solve");
    tscvx_info info, fresh_info;
    tscvx_get_info(ws, &info);
    CHECK(info.status == TSCVX_UNSOLVED && info.iterations == 0 && isnan(info.pcost) &&
              isnan(info.mu), "info after setup: %d iterations, pcost %g", (int)info.iterations,
          info.pcost);
    CHECK(tscvx_solve(ws) == TSCVX_SOLVED, "first solve");
    CHECK(tscvx_get_iter_log(ws, 0, &row) == TSCVX_SETUP_OK, "log after a solve");
    tscvx_float h2[] = {2, 0, 0}, bad[] = {NAN, 0, 0};
    CHECK(tscvx_update_data(ws, NULL, NULL, NULL, NULL, NULL, bad) == TSCVX_SETUP_NONFINITE_DATA,
          "NaN update accepted");
    /* review of 27 Nov: info kept the last solve's figures beside the new status */
    tscvx_get_info(ws, &info);
    CHECK(info.status == TSCVX_INVALID_INPUT && info.iterations == 0 &&
              info.factorizations == 0 && isnan(info.pcost) && isnan(info.pres),
          "info after a refused update: %d iterations, pcost %g", (int)info.iterations,
          info.pcost);
    CHECK(tscvx_get_iter_log(ws, 0, &row) == TSCVX_SETUP_NOT_READY, "log after a bad update");
    CHECK(tscvx_solve(ws) == TSCVX_INVALID_INPUT, "solve after bad update");
    CHECK(tscvx_update_data(ws, NULL, NULL, NULL, NULL, NULL, h2) == TSCVX_SETUP_OK, "update");
    CHECK(tscvx_get_iter_log(ws, 0, &row) == TSCVX_SETUP_NO_SOLUTION, "log after an update");
    tscvx_get_info(ws, &info);
    CHECK(info.status == TSCVX_UNSOLVED && info.iterations == 0 && isnan(info.gap_abs) &&
              isnan(info.dres), "info after an update: %d iterations, gap %g",
          (int)info.iterations, info.gap_abs);
    CHECK(tscvx_solve(ws) == TSCVX_SOLVED, "second solve");
    tscvx_get_solution(ws, x, NULL, NULL, NULL);
    CHECK(fabs(x[0] - sqrt(2.0)) < 1e-7, "updated x %g", x[0]);
    tscvx_get_info(ws, &info);
    tscvx_float Gx2[] = {-3, -0.5}; /* |(3 x1, x2 / 2)| <= 2: another equilibration */
    CHECK(tscvx_update_data(ws, NULL, NULL, NULL, NULL, Gx2, NULL) == TSCVX_SETUP_OK, "G update");
    CHECK(tscvx_solve(ws) == TSCVX_SOLVED, "third solve");
    tscvx_get_solution(ws, x, NULL, NULL, NULL);
    tscvx_get_info(ws, &info);
    tscvx_data d2 = d;
    d2.h = h2;
    d2.Gx = Gx2;
    tscvx_workspace *fresh = NULL;
    tscvx_float xf[2];
    CHECK(tscvx_setup(&fresh, arena2, sizeof arena2, &d2, &st) == TSCVX_SETUP_OK, "fresh setup");
    CHECK(tscvx_solve(fresh) == TSCVX_SOLVED, "fresh solve");
    tscvx_get_solution(fresh, xf, NULL, NULL, NULL);
    tscvx_get_info(fresh, &fresh_info);
    CHECK(info.iterations == fresh_info.iterations, "update %d vs fresh %d iterations",
          (int)info.iterations, (int)fresh_info.iterations);
    CHECK(fabs(x[0] - xf[0]) < 1e-12 && fabs(x[1] - xf[1]) < 1e-12, "update vs fresh x %.3g %.3g",
          x[0] - xf[0], x[1] - xf[1]);
    CHECK(tscvx_get_iter_log(ws, info.iterations, &row) == TSCVX_SETUP_OK, "log row");
    CHECK(row.iter == info.iterations && fabs(row.pcost - info.pcost) < 1e-12, "log content");
    CHECK(tscvx_get_iter_log(ws, info.iterations + 1, &row) == TSCVX_SETUP_BAD_INDEX, "log range");
    /* 100 updates that resend every part (h alternating), ending on d2's numbers: the solve
     * equals the fresh one bit for bit (what the guidance loop relies on) */
    tscvx_float h3[] = {0.3, 0, 0};
    for (int k = 0; k < 100; k++)
        CHECK(tscvx_update_data(ws, NULL, d.c, NULL, NULL, Gx2, k % 2 ? h2 : h3) ==
                  TSCVX_SETUP_OK, "full update %d", k);
    CHECK(tscvx_solve(ws) == TSCVX_SOLVED, "solve after 100 full updates");
    tscvx_get_solution(ws, x, NULL, NULL, NULL);
    CHECK(x[0] == xf[0] && x[1] == xf[1], "full updates vs fresh x %.3g %.3g", x[0] - xf[0],
          x[1] - xf[1]);
}

/* Settings changed between solves: the iteration limit and tolerances take effect on the next
 * solve; what set-up fixed (the KKT method, Ruiz passes, the dense SOC size, a limit beyond
 * the log set-up sized) and a setting out of range are refused, the settings in force kept. */
static void test_update_settings(void) {
    small_soc p;
    const tscvx_data d = small_soc_data(&p);
    tscvx_float x[2];
    tscvx_settings st, st2;
    tscvx_default_settings(&st);
    st.max_iter = 50;
    tscvx_workspace *ws = NULL;
    tscvx_info info;
    CHECK(tscvx_setup(&ws, arena2, sizeof arena2, &d, &st) == TSCVX_SETUP_OK, "setup");
    CHECK(tscvx_solve(ws) == TSCVX_SOLVED, "solve");
    tscvx_get_info(ws, &info);
    const tscvx_int iters = info.iterations;
    CHECK(iters > 2, "iterations %d", (int)iters);
    st2 = st;
    st2.max_iter = 2;
    CHECK(tscvx_update_settings(ws, &st2) == TSCVX_SETUP_OK, "a lower iteration limit");
    CHECK(tscvx_solve(ws) == TSCVX_MAX_ITER, "stops at the new limit");
    tscvx_get_info(ws, &info);
    CHECK(info.iterations == 2, "iterations %d", (int)info.iterations);
    for (int which = 0; which < 5; which++) {
        tscvx_settings bad = st2;
        if (which == 0) bad.max_iter = st.max_iter + 1; /* beyond the log set-up sized */
        if (which == 1) bad.kkt_backend = TSCVX_KKT_LDL;
        if (which == 2) bad.ruiz_iters = st.ruiz_iters + 1;
        if (which == 3) bad.soc_dense_max = st.soc_dense_max + 1;
        if (which == 4) bad.tol_feas = NAN;
        CHECK(tscvx_update_settings(ws, &bad) == TSCVX_SETUP_BAD_SETTINGS, "refused %d", which);
    }
    CHECK(tscvx_solve(ws) == TSCVX_MAX_ITER, "the settings in force kept");
    CHECK(tscvx_update_settings(ws, &st) == TSCVX_SETUP_OK, "back to set-up's settings");
    CHECK(tscvx_solve(ws) == TSCVX_SOLVED, "solved again");
    tscvx_get_info(ws, &info);
    CHECK(info.iterations == iters, "same iterations %d %d", (int)info.iterations, (int)iters);
    tscvx_get_solution(ws, x, NULL, NULL, NULL);
    CHECK(fabs(x[0] - sqrt(0.5)) < 1e-6 && fabs(x[1] - sqrt(0.5)) < 1e-6, "x = (1, 1)/sqrt 2");
    CHECK(tscvx_update_settings(ws, NULL) == TSCVX_SETUP_NULL_ARGUMENT, "NULL settings");
}

/* Fuzzing (27 Nov): tol_infeas = 10 was accepted, and the first iterate of a strictly convex
 * problem bounded by its cones passed as a certificate: DUAL_INFEASIBLE after 1 iteration on
 * every KKT method. A certificate residual as large as its objective certifies nothing:
 * tol_infeas lies in (0, 1), at setup and in tscvx_update_settings. */
static void test_tol_infeas_range(void) {
    /* the fuzzer's case, rounded: min 0.51 x s.t. -5 <= x <= 5, three more orthant rows and a
     * 2-row cone: bounded, solved at x = -5 */
    tscvx_int Gp[] = {0, 4}, Gi[] = {0, 1, 3, 4}, q[] = {2};
    tscvx_float c[] = {0.51}, Gx[] = {1, -1, 0.52, -0.0076};
    tscvx_float h[] = {5, 5, 0.12, 1.64, 0.61, 1.65, -0.77};
    const tscvx_data d = {1, 0, 7, NULL, NULL, NULL, c, NULL, NULL, NULL, NULL, Gp, Gi, Gx, h, 5, 1,
                          q};
    const tscvx_float bad[] = {10.0, 1.0, 1e200};
    tscvx_settings st;
    tscvx_workspace *ws = NULL;
    for (int k = 0; k < 3; k++) {
        tscvx_default_settings(&st);
        st.tol_infeas = bad[k];
        const tscvx_setup_status r = tscvx_setup(&ws, arena2, sizeof arena2, &d, &st);
        CHECK(r == TSCVX_SETUP_BAD_SETTINGS, "tol_infeas = %g: setup %d, then %s", bad[k],
              (int)r, r == TSCVX_SETUP_OK ? tscvx_solve_status_message(tscvx_solve(ws)) : "-");
    }
    tscvx_default_settings(&st);
    st.tol_infeas = 0.5;
    CHECK(tscvx_setup(&ws, arena2, sizeof arena2, &d, &st) == TSCVX_SETUP_OK, "tol_infeas 0.5");
    CHECK(tscvx_solve(ws) == TSCVX_SOLVED, "solved with tol_infeas 0.5");
    st.tol_infeas = 10.0;
    CHECK(tscvx_update_settings(ws, &st) == TSCVX_SETUP_BAD_SETTINGS, "update to tol_infeas 10");
    CHECK(tscvx_solve(ws) == TSCVX_SOLVED, "still solved: the settings in force kept");
}

/* The gap and feasibility tolerances lie in (0, 1) as tol_infeas does (a gap or a residual as
 * large as its data accepts anything: with tol_gap_* = 1 the runtime stopped min -x1 - x2 over
 * x >= 0, x1 + x2 <= 10, |x| <= 8 at its first iterate, -7.3 against -10, as SOLVED);
 * tscvx_check_settings names the setting, its range and its value. */
static void test_tolerance_ranges(void) {
    const char *names[] = {"tol_gap_abs", "tol_gap_rel", "tol_feas"};
    const tscvx_float bad[] = {1.0, 10.0, 1e200, 0.0, NAN};
    char msg[TSCVX_MESSAGE_LEN], want[TSCVX_MESSAGE_LEN];
    tscvx_settings st;
    for (int f = 0; f < 3; f++) {
        for (int k = 0; k < 5; k++) {
            tscvx_default_settings(&st);
            tscvx_float *v = f == 0 ? &st.tol_gap_abs : f == 1 ? &st.tol_gap_rel : &st.tol_feas;
            *v = bad[k];
            snprintf(want, sizeof want, "%s must ", names[f]);
            CHECK(tscvx_check_settings(&st, msg) == TSCVX_SETUP_BAD_SETTINGS &&
                      strncmp(msg, want, strlen(want)) == 0,
                  "%s = %g: '%s'", names[f], (double)bad[k], msg);
        }
        tscvx_default_settings(&st);
        *(f == 0 ? &st.tol_gap_abs : f == 1 ? &st.tol_gap_rel : &st.tol_feas) = 0.5;
        CHECK(tscvx_check_settings(&st, msg) == TSCVX_SETUP_OK && msg[0] == '\0',
              "%s = 0.5 refused: '%s'", names[f], msg);
    }
    tscvx_default_settings(&st);
    st.tol_gap_rel = 1.0;
    CHECK(tscvx_check_settings(&st, msg) == TSCVX_SETUP_BAD_SETTINGS &&
              strcmp(msg, "tol_gap_rel must lie within (0, 1), got 1") == 0,
          "message '%s'", msg);
    /* the reduced bars only label a best iterate: any positive value */
    tscvx_default_settings(&st);
    st.tol_gap_abs_inacc = st.tol_gap_rel_inacc = st.tol_feas_inacc = 1e3;
    CHECK(tscvx_check_settings(&st, msg) == TSCVX_SETUP_OK, "reduced bars 1e3: '%s'", msg);
    st.tol_feas_inacc = -1.0;
    CHECK(tscvx_check_settings(&st, msg) == TSCVX_SETUP_BAD_SETTINGS &&
              strstr(msg, "tol_feas_inacc") == msg,
          "tol_feas_inacc -1: '%s'", msg);
    CHECK(tscvx_check_settings(NULL, msg) == TSCVX_SETUP_NULL_ARGUMENT, "NULL settings");
}

/* Every call on a stale workspace (arena overwritten after setup, or cleaned up) is refused
 * before any of its pointers is followed; so is one whose KKT method pointer is not ours. */
static void test_stale_workspace(void) {
    small_soc p;
    const tscvx_data d = small_soc_data(&p);
    tscvx_float x[2];
    tscvx_settings st;
    tscvx_default_settings(&st);
    tscvx_workspace *ws = NULL;
    tscvx_info info;
    tscvx_iter_log row;
    CHECK(tscvx_setup(&ws, arena2, sizeof arena2, &d, &st) == TSCVX_SETUP_OK, "setup");
    CHECK(tscvx_solve(ws) == TSCVX_SOLVED, "solve");
    memset(arena2, 0x5A, sizeof arena2);
    CHECK(tscvx_solve(ws) == TSCVX_INVALID_INPUT, "solve on an overwritten arena");
    CHECK(tscvx_update_data(ws, NULL, p.c, NULL, NULL, NULL, NULL) == TSCVX_SETUP_NOT_READY,
          "update on an overwritten arena");
    CHECK(tscvx_update_settings(ws, &st) == TSCVX_SETUP_NOT_READY, "settings, overwritten");
    CHECK(tscvx_get_solution(ws, x, NULL, NULL, NULL) == TSCVX_SETUP_NOT_READY, "solution");
    CHECK(tscvx_get_info(ws, &info) == TSCVX_SETUP_NOT_READY, "info, overwritten");
    CHECK(tscvx_get_iter_log(ws, 0, &row) == TSCVX_SETUP_NOT_READY, "log, overwritten");
    CHECK(tscvx_cleanup(ws) == TSCVX_SETUP_NOT_READY, "cleanup, overwritten");
    CHECK(tscvx_cleanup(NULL) == TSCVX_SETUP_NULL_ARGUMENT, "cleanup(NULL)");

    CHECK(tscvx_setup(&ws, arena2, sizeof arena2, &d, &st) == TSCVX_SETUP_OK, "setup again");
    CHECK(tscvx_cleanup(ws) == TSCVX_SETUP_OK, "cleanup");
    CHECK(tscvx_solve(ws) == TSCVX_INVALID_INPUT, "solve after cleanup");
    CHECK(tscvx_get_info(ws, &info) == TSCVX_SETUP_NOT_READY, "info after cleanup");

    /* the magic intact, the method pointer not: refused, not called */
    CHECK(tscvx_setup(&ws, arena2, sizeof arena2, &d, &st) == TSCVX_SETUP_OK, "third setup");
    const tscvx_kkt_method *method = ws->method;
    ws->method = (const tscvx_kkt_method *)(void *)arena;
    CHECK(tscvx_solve(ws) == TSCVX_INVALID_INPUT, "solve with a foreign method pointer");
    ws->method = method;
    CHECK(tscvx_solve(ws) == TSCVX_SOLVED, "solve with the method restored");
}

/* P must be positive semidefinite. Setup and updates refuse a negative diagonal entry or a
 * negative 2 x 2 principal minor (the fuzzing case: min -x^2/2 + x/2 on [-1, 2] came back
 * solved at its maximum x = 0.5); rank-one blocks in rounded numbers and zero rows pass. */
static void test_psd_check(void) {
    tscvx_int Pp[] = {0, 1}, Pi[] = {0}, Gp[] = {0, 2}, Gi[] = {0, 1};
    tscvx_float Px[] = {-1}, c[] = {0.5}, Gx[] = {1, -1}, h[] = {2, 1};
    tscvx_data d = {1, 0, 2, Pp, Pi, Px, c, NULL, NULL, NULL, NULL, Gp, Gi, Gx, h, 2, 0, NULL};
    CHECK(try_setup(&d) == TSCVX_SETUP_P_NOT_PSD, "P = [-1] accepted");
    /* -1 <= x_i <= 1; P = [P11 P12; P12 P22] */
    tscvx_int Pp2[] = {0, 1, 3}, Pi2[] = {0, 0, 1}, Gp2[] = {0, 2, 4}, Gi2[] = {0, 1, 2, 3};
    tscvx_float Gx2[] = {1, -1, 1, -1}, h2[] = {1, 1, 1, 1}, c2[] = {1, -1};
    tscvx_data d2 = {2, 0, 4, Pp2, Pi2, NULL, c2, NULL, NULL, NULL, NULL, Gp2, Gi2, Gx2, h2,
                     4, 0, NULL};
    static const tscvx_float bad[][3] = {{1, 2, 1}, {1, 1 + 1e-9, 1}, {0, 1e-6, 1}, {1, 0, -1}};
    static const tscvx_float good[][3] = {{1, -1, 1},        {0.01, 0.03, 0.09}, {0, 0, 1},
                                          {0, 1e-13, 1},     {2, 0, 0},          {0, 0, 0},
                                          {1e-3, 0.1, 10.0}, {3, 0.5, 1}};
    for (size_t k = 0; k < sizeof bad / sizeof bad[0]; k++) {
        d2.Px = bad[k];
        CHECK(try_setup(&d2) == TSCVX_SETUP_P_NOT_PSD, "bad P %zu accepted", k);
    }
    for (size_t k = 0; k < sizeof good / sizeof good[0]; k++) {
        d2.Px = good[k];
        CHECK(try_setup(&d2) == TSCVX_SETUP_OK, "good P %zu refused", k);
    }
    /* a negative diagonal entry is refused however small: in diag(1, -1e-12) it lies within
     * the factorization's tolerance (1e-9 of the largest entry), so only the entry check sees
     * it; at setup and in an update */
    tscvx_int Pp3[] = {0, 1, 2}, Pi3[] = {0, 1};
    const tscvx_float Px3[] = {1, -1e-12}, Px3_good[] = {1, 0};
    tscvx_data d3 = d2;
    d3.Pp = Pp3, d3.Pi = Pi3, d3.Px = Px3;
    CHECK(try_setup(&d3) == TSCVX_SETUP_P_NOT_PSD, "P = diag(1, -1e-12) accepted");
    {
        tscvx_settings st3;
        tscvx_workspace *ws3 = NULL;
        tscvx_default_settings(&st3);
        d3.Px = Px3_good;
        CHECK(tscvx_setup(&ws3, arena, sizeof arena, &d3, &st3) == TSCVX_SETUP_OK, "diag setup");
        CHECK(ws3 && tscvx_update_data(ws3, Px3, NULL, NULL, NULL, NULL, NULL) ==
                         TSCVX_SETUP_P_NOT_PSD,
              "update to P = diag(1, -1e-12) accepted");
    }
    /* updates: a bad P makes the workspace not ready until a good one */
    tscvx_settings st;
    tscvx_default_settings(&st);
    tscvx_workspace *ws = NULL;
    d2.Px = good[0];
    CHECK(tscvx_setup(&ws, arena, sizeof arena, &d2, &st) == TSCVX_SETUP_OK, "setup");
    CHECK(tscvx_update_data(ws, bad[0], NULL, NULL, NULL, NULL, NULL) == TSCVX_SETUP_P_NOT_PSD,
          "indefinite P update accepted");
    CHECK(tscvx_solve(ws) == TSCVX_INVALID_INPUT, "solve after an indefinite P update");
    CHECK(tscvx_update_data(ws, good[7], NULL, NULL, NULL, NULL, NULL) == TSCVX_SETUP_OK,
          "good P update");
    CHECK(tscvx_solve(ws) == TSCVX_SOLVED, "solve after a good P update");
}

/* min 1/2 x'Px + c'x over the box |x_i| <= 1 (G = [I; -I]), set up in arena2 under the
 * given KKT method: the problem of the indefinite-P test below. */
static tscvx_setup_status setup_box(tscvx_workspace **ws, tscvx_int *Pp, tscvx_int *Pi,
                                    const tscvx_float *Px, tscvx_int kkt_backend) {
    static tscvx_int Gp[] = {0, 2, 4, 6}, Gi[] = {0, 3, 1, 4, 2, 5};
    static tscvx_float c[] = {1, -1, 1}, Gx[] = {1, -1, 1, -1, 1, -1};
    static tscvx_float h[] = {1, 1, 1, 1, 1, 1};
    tscvx_data d = {3, 0, 6, Pp, Pi, Px, c, NULL, NULL, NULL, NULL, Gp, Gi, Gx, h, 6, 0, NULL};
    tscvx_settings st;
    tscvx_default_settings(&st);
    st.kkt_backend = kkt_backend;
    *ws = NULL;
    return tscvx_setup(ws, arena2, sizeof arena2, &d, &st);
}

/* Indefinite P whose 2 x 2 minors all pass the cheap check are refused at setup and in
 * updates by a factorization of P, under every KKT method (the sparse method's IPM pivots mix
 * P with the constraint terms and would not show it):
 *   tridiagonal [1 1 0; 1 1 1; 0 1 1] (eigenvalue 1 - sqrt 2),
 *   full [1 .9 -.9; .9 1 .9; -.9 .9 1] (determinant -2.888, minors 0.19; the banded factor
 *   meets its negative pivot last).
 *   barely indefinite [1 1 0; 1 2-3e-6 1; 0 1 1] (eigenvalue -1e-6, below the 1e-9 |P|
 *   every method allows for rounding; the banded factor meets it as a negative pivot it
 *   would drop as zero).
 * Semidefinite P of the same patterns pass and solve: [1 1 0; 1 2 1; 0 1 1] (eigenvalues 0,
 * 1, 3) and v v' in rounded numbers, v = (1, 1/3, -0.7). */
static void test_indefinite_p_every_method(void) {
    tscvx_int tri_p[] = {0, 1, 3, 5}, tri_i[] = {0, 0, 1, 1, 2};
    tscvx_int full_p[] = {0, 1, 3, 6}, full_i[] = {0, 0, 1, 0, 1, 2};
    const tscvx_float tri_bad[] = {1, 1, 1, 1, 1}, tri_good[] = {1, 1, 2, 1, 1};
    const tscvx_float tri_barely[] = {1, 1, 2 - 3e-6, 1, 1};
    const tscvx_float full_bad[] = {1, 0.9, 1, -0.9, 0.9, 1};
    const tscvx_float v[] = {1.0, 1.0 / 3.0, -0.7};
    const tscvx_float full_good[] = {v[0] * v[0], v[0] * v[1], v[1] * v[1],
                                     v[0] * v[2], v[1] * v[2], v[2] * v[2]};
    const tscvx_int methods[] = {TSCVX_KKT_STATIC, TSCVX_KKT_LDL, TSCVX_KKT_BANDED};
    for (size_t k = 0; k < sizeof methods / sizeof methods[0]; k++) {
        const tscvx_int mth = methods[k];
        tscvx_workspace *ws;
        CHECK(setup_box(&ws, tri_p, tri_i, tri_bad, mth) == TSCVX_SETUP_P_NOT_PSD,
              "method %d: tridiagonal indefinite P accepted", (int)mth);
        CHECK(setup_box(&ws, full_p, full_i, full_bad, mth) == TSCVX_SETUP_P_NOT_PSD,
              "method %d: full indefinite P accepted", (int)mth);
        CHECK(setup_box(&ws, tri_p, tri_i, tri_barely, mth) == TSCVX_SETUP_P_NOT_PSD,
              "method %d: barely indefinite P accepted", (int)mth);
        CHECK(setup_box(&ws, tri_p, tri_i, tri_good, mth) == TSCVX_SETUP_OK && ws &&
                  tscvx_solve(ws) == TSCVX_SOLVED,
              "method %d: singular semidefinite P refused or unsolved", (int)mth);
        CHECK(setup_box(&ws, full_p, full_i, full_good, mth) == TSCVX_SETUP_OK && ws &&
                  tscvx_solve(ws) == TSCVX_SOLVED,
              "method %d: rank-one P refused or unsolved", (int)mth);
        if (ws == NULL) continue;
        CHECK(tscvx_update_data(ws, full_bad, NULL, NULL, NULL, NULL, NULL) ==
                  TSCVX_SETUP_P_NOT_PSD, "method %d: indefinite P update accepted", (int)mth);
        CHECK(tscvx_solve(ws) == TSCVX_INVALID_INPUT, "method %d: solve after it", (int)mth);
        /* the refused P is stored (the factorization test needs it there): an update without
         * P keeps it refused, not solved as if it were valid */
        const tscvx_float c2[] = {1, -1, 0.5};
        CHECK(tscvx_update_data(ws, NULL, c2, NULL, NULL, NULL, NULL) == TSCVX_SETUP_P_NOT_PSD,
              "method %d: an update without P accepted the refused P", (int)mth);
        CHECK(tscvx_solve(ws) == TSCVX_INVALID_INPUT, "method %d: solve on the refused P",
              (int)mth);
        CHECK(tscvx_update_data(ws, full_good, NULL, NULL, NULL, NULL, NULL) == TSCVX_SETUP_OK &&
                  tscvx_solve(ws) == TSCVX_SOLVED,
              "method %d: good P update", (int)mth);
    }
}

/* A positive definite but ill-conditioned P is accepted and solved by every method: the
 * semidefinite factor of P drops only numerically zero pivots (DYN_EPS = 1e-13 of their
 * diagonal entry, banded.c), and the sparse check factors P + 1e-9 |P|_max I.
 *   P = [1 1 0; 1 1+1e-8 5e-5; 0 5e-5 1]: Cholesky pivots 1, 1e-8, 0.75 (all > 0; the
 *   middle one is 1e-8 of its diagonal entry and has an entry 5e-5 below it, which a
 *   dropped pivot may not have). */
static void test_ill_conditioned_p_every_method(void) {
    tscvx_int tri_p[] = {0, 1, 3, 5}, tri_i[] = {0, 0, 1, 1, 2};
    const tscvx_float tri_pd[] = {1, 1, 1 + 1e-8, 5e-5, 1};
    const tscvx_int methods[] = {TSCVX_KKT_STATIC, TSCVX_KKT_LDL, TSCVX_KKT_BANDED};
    for (size_t k = 0; k < sizeof methods / sizeof methods[0]; k++) {
        tscvx_workspace *ws;
        const tscvx_setup_status st = setup_box(&ws, tri_p, tri_i, tri_pd, methods[k]);
        CHECK(st == TSCVX_SETUP_OK && ws && tscvx_solve(ws) == TSCVX_SOLVED,
              "method %d: positive definite P (pivot 1e-8) refused (%d) or unsolved",
              (int)methods[k], (int)st);
    }
}

/* ---- Ruiz equilibration and cost scaling against a dense reference ---------------------
 * The rule (equil.c, tscvx_info.ruiz_passes): each pass divides every row and column of
 * M = [P A' G'; A 0 0; G 0 0] by the square root of its infinity norm (clamped to
 * [1e-4, 1e4]; an empty one stays), one norm per SOC (the largest of its rows); it stops
 * before a pass once every nonempty row/column has norm 1 +- 1e-3, or after ruiz_iters
 * passes. Then the cost scaling cs = 1 / max(mean_j |Ps col j|_inf, |D c|_inf) (clamped). */
#define EQ_N 6
#define EQ_P 2
#define EQ_L 3
#define EQ_M 10 /* EQ_L + 3 + 4 */

typedef struct {
    double P[EQ_N][EQ_N], A[EQ_P][EQ_N], G[EQ_M][EQ_N], c[EQ_N], b[EQ_P], h[EQ_M];
} eq_dense;

static double eq_clamp(double v) {
    if (!(v > 1e-4)) return v > 0.0 ? 1e-4 : 1.0;
    return v > 1e4 ? 1e4 : v;
}

/* The reference: D, EA, EG, cs and the number of passes. */
static int eq_reference(const eq_dense *e, const tscvx_int *q, int nsoc, int iters, double *D,
                        double *EA, double *EG, double *cs) {
    int passes = 0;
    for (int j = 0; j < EQ_N; j++) D[j] = 1.0;
    for (int i = 0; i < EQ_P; i++) EA[i] = 1.0;
    for (int i = 0; i < EQ_M; i++) EG[i] = 1.0;
    for (int it = 0; it < iters; it++) {
        double cn[EQ_N] = {0}, an[EQ_P] = {0}, gn[EQ_M] = {0}, worst = 0.0;
        for (int j = 0; j < EQ_N; j++) {
            for (int i = 0; i < EQ_N; i++) cn[j] = fmax(cn[j], fabs(D[i] * e->P[i][j] * D[j]));
            for (int i = 0; i < EQ_P; i++) {
                const double v = fabs(EA[i] * e->A[i][j] * D[j]);
                cn[j] = fmax(cn[j], v), an[i] = fmax(an[i], v);
            }
            for (int i = 0; i < EQ_M; i++) {
                const double v = fabs(EG[i] * e->G[i][j] * D[j]);
                cn[j] = fmax(cn[j], v), gn[i] = fmax(gn[i], v);
            }
        }
        for (int k = 0, o = EQ_L; k < nsoc; o += q[k++]) {
            double mx = 0.0;
            for (int r = 0; r < q[k]; r++) mx = fmax(mx, gn[o + r]);
            for (int r = 0; r < q[k]; r++) gn[o + r] = mx;
        }
        for (int j = 0; j < EQ_N; j++) worst = cn[j] > 0.0 ? fmax(worst, fabs(1.0 - cn[j])) : worst;
        for (int i = 0; i < EQ_P; i++) worst = an[i] > 0.0 ? fmax(worst, fabs(1.0 - an[i])) : worst;
        for (int i = 0; i < EQ_M; i++) worst = gn[i] > 0.0 ? fmax(worst, fabs(1.0 - gn[i])) : worst;
        if (worst < 1e-3) break;
        for (int j = 0; j < EQ_N; j++) D[j] /= sqrt(eq_clamp(cn[j]));
        for (int i = 0; i < EQ_P; i++) EA[i] /= sqrt(eq_clamp(an[i]));
        for (int i = 0; i < EQ_M; i++) EG[i] /= sqrt(eq_clamp(gn[i]));
        passes = it + 1;
    }
    double pmean = 0.0, cmax = 0.0;
    for (int j = 0; j < EQ_N; j++) {
        double pc = 0.0;
        for (int i = 0; i < EQ_N; i++) pc = fmax(pc, fabs(D[i] * e->P[i][j] * D[j]));
        pmean += pc / EQ_N;
        cmax = fmax(cmax, fabs(D[j] * e->c[j]));
    }
    const double scale = fmax(pmean, cmax);
    *cs = scale > 0.0 ? 1.0 / fmin(fmax(scale, 1e-4), 1e4) : 1.0;
    return passes;
}

/* a random number of either sign, magnitude spread over 2 `decades` */
static double eq_wide(double decades) {
    const double scale = pow(10.0, decades * ct_randn());
    return scale * ct_randn();
}

static double rel_err(double a, double b) { return fabs(a - b) / fmax(fabs(b), 1e-300); }

/* The workspace's scalings and scaled data against the reference for the numbers in e. */
static void eq_compare(const char *what, tscvx_workspace *ws, const eq_dense *e,
                       const tscvx_int *q, int nsoc, int iters) {
    double D[EQ_N], EA[EQ_P], EG[EQ_M], cs, err = 0.0;
    const int passes = eq_reference(e, q, nsoc, iters, D, EA, EG, &cs);
    tscvx_info info;
    tscvx_get_info(ws, &info);
    CHECK(info.ruiz_passes == passes, "%s (ruiz_iters %d): %d passes, the rule takes %d", what,
          iters, (int)info.ruiz_passes, passes);
    for (int j = 0; j < EQ_N; j++) err = fmax(err, rel_err(ws->D[j], D[j]));
    for (int i = 0; i < EQ_P; i++) err = fmax(err, rel_err(ws->EA[i], EA[i]));
    for (int i = 0; i < EQ_M; i++) err = fmax(err, rel_err(ws->EG[i], EG[i]));
    CHECK(err < 1e-12, "%s (ruiz_iters %d): scalings off by %g", what, iters, err);
    CHECK(rel_err(ws->cs, cs) < 1e-12, "%s (ruiz_iters %d): cost scale %g, expected %g", what,
          iters, ws->cs, cs);
    /* the scaled data: Ps = cs D P D, As = EA A D, Gs = EG G D, cs D c, EA b, EG h */
    err = 0.0;
    for (int j = 0; j < EQ_N; j++) {
        for (int k = ws->P.p[j]; k < ws->P.p[j + 1]; k++) {
            const int i = ws->P.i[k];
            err = fmax(err, rel_err(ws->P.x[k], cs * D[i] * e->P[i][j] * D[j]));
        }
        for (int k = ws->A.p[j]; k < ws->A.p[j + 1]; k++) {
            const int i = ws->A.i[k];
            err = fmax(err, rel_err(ws->A.x[k], EA[i] * e->A[i][j] * D[j]));
        }
        for (int k = ws->G.p[j]; k < ws->G.p[j + 1]; k++) {
            const int i = ws->G.i[k];
            err = fmax(err, rel_err(ws->G.x[k], EG[i] * e->G[i][j] * D[j]));
        }
        err = fmax(err, rel_err(ws->c[j], cs * D[j] * e->c[j]));
    }
    for (int i = 0; i < EQ_P; i++) err = fmax(err, rel_err(ws->b[i], EA[i] * e->b[i]));
    for (int i = 0; i < EQ_M; i++) err = fmax(err, rel_err(ws->h[i], EG[i] * e->h[i]));
    CHECK(err < 1e-12, "%s (ruiz_iters %d): scaled data off by %g", what, iters, err);
}

/* dense -> CSC (upper triangle only when `upper`) */
static int eq_csc(int nrow, const double *Md, int upper, tscvx_int *Mp, tscvx_int *Mi,
                  tscvx_float *Mx) {
    int nz = 0;
    for (int j = 0; j < EQ_N; j++) {
        Mp[j] = nz;
        for (int i = 0; i < (upper ? j + 1 : nrow); i++)
            if (Md[i * EQ_N + j] != 0.0) Mi[nz] = i, Mx[nz++] = Md[i * EQ_N + j];
    }
    Mp[EQ_N] = nz;
    return nz;
}

static void test_equilibration_reference(void) {
    static const tscvx_int q[2] = {3, 4};
    static unsigned char ar[1 << 17];
    for (int trial = 0; trial < 6; trial++) {
        eq_dense e;
        memset(&e, 0, sizeof e);
        /* entries spread over six decades: Ruiz has work to do */
        for (int j = 0; j < EQ_N; j++) {
            const double pj = pow(10.0, 3.0 * ct_randn());
            e.P[j][j] = pj * (1.0 + ct_rand());
            if (j % 2 == 1 && trial % 2 == 0) { /* 2 x 2 blocks of correlation 0.9: P > 0,
                                                 * and an entry off the diagonal can be the
                                                 * largest of its column in either triangle */
                const double sign = ct_rand() < 0.5 ? -1.0 : 1.0;
                const double v = 0.9 * sign * sqrt(e.P[j - 1][j - 1] * e.P[j][j]);
                e.P[j - 1][j] = e.P[j][j - 1] = v;
            }
            /* trials 0 and 2: a small cost, so that the cost scale is P's mean column norm */
            e.c[j] = pow(10.0, trial % 2 == 0 ? -4.0 : 2.0 * ct_randn()) * ct_randn();
            for (int i = 0; i < EQ_P; i++)
                if (ct_rand() < 0.5 || i == j % EQ_P) e.A[i][j] = eq_wide(3.0);
            for (int i = 0; i < EQ_M; i++)
                if (ct_rand() < 0.4 || i == j % EQ_M) e.G[i][j] = eq_wide(3.0);
        }
        for (int i = 0; i < EQ_P; i++) e.b[i] = ct_randn();
        for (int i = 0; i < EQ_M; i++) e.h[i] = 1.0 + ct_rand();
        double Pu[EQ_N * EQ_N], Ad[EQ_P * EQ_N], Gd[EQ_M * EQ_N];
        for (int i = 0; i < EQ_N; i++)
            for (int j = 0; j < EQ_N; j++) Pu[i * EQ_N + j] = e.P[i][j];
        for (int i = 0; i < EQ_P; i++)
            for (int j = 0; j < EQ_N; j++) Ad[i * EQ_N + j] = e.A[i][j];
        for (int i = 0; i < EQ_M; i++)
            for (int j = 0; j < EQ_N; j++) Gd[i * EQ_N + j] = e.G[i][j];
        tscvx_int Pp[EQ_N + 1], Pi[EQ_N * EQ_N], Ap[EQ_N + 1], Ai[EQ_P * EQ_N];
        tscvx_int Gp[EQ_N + 1], Gi[EQ_M * EQ_N];
        tscvx_float Px[EQ_N * EQ_N], Ax[EQ_P * EQ_N], Gx[EQ_M * EQ_N];
        eq_csc(EQ_N, Pu, 1, Pp, Pi, Px);
        eq_csc(EQ_P, Ad, 0, Ap, Ai, Ax);
        eq_csc(EQ_M, Gd, 0, Gp, Gi, Gx);
        tscvx_data d = {EQ_N, EQ_P, EQ_M, Pp, Pi, Px, e.c, Ap, Ai, Ax, e.b,
                        Gp, Gi, Gx, e.h, EQ_L, 2, q};
        static const int iters[4] = {1, 2, 3, 15};
        for (int t = 0; t < 4; t++) {
            tscvx_settings st;
            tscvx_default_settings(&st);
            st.ruiz_iters = iters[t];
            tscvx_workspace *ws = NULL;
            CHECK(tscvx_setup(&ws, ar, sizeof ar, &d, &st) == TSCVX_SETUP_OK, "eq setup");
            if (!ws) continue;
            eq_compare("setup", ws, &e, q, 2, iters[t]);
            /* an update of some parts: the kept ones are the caller's numbers again */
            tscvx_float c2[EQ_N], h2[EQ_M];
            for (int j = 0; j < EQ_N; j++) c2[j] = e.c[j] = eq_wide(2.0);
            CHECK(tscvx_update_data(ws, NULL, c2, NULL, NULL, NULL, NULL) == TSCVX_SETUP_OK,
                  "c update");
            eq_compare("after a c update", ws, &e, q, 2, iters[t]);
            for (int i = 0; i < EQ_M; i++) h2[i] = e.h[i] = 1.0 + 3.0 * ct_rand();
            CHECK(tscvx_update_data(ws, NULL, NULL, NULL, NULL, NULL, h2) == TSCVX_SETUP_OK,
                  "h update");
            eq_compare("after an h update", ws, &e, q, 2, iters[t]);
            tscvx_float Px2[EQ_N * EQ_N];
            for (int k = 0; k < Pp[EQ_N]; k++) Px2[k] = Px[k];
            for (int j = 0; j < EQ_N; j++) { /* G and P: new numbers, b and h kept */
                for (int k = Pp[j]; k < Pp[j + 1]; k++)
                    if (Pi[k] == j) Px2[k] *= 4.0, e.P[j][j] *= 4.0;
            }
            tscvx_float Gx2[EQ_M * EQ_N];
            for (int j = 0; j < EQ_N; j++)
                for (int k = Gp[j]; k < Gp[j + 1]; k++) {
                    Gx2[k] = Gx[k] * 0.25;
                    e.G[Gi[k]][j] = Gx2[k];
                }
            CHECK(tscvx_update_data(ws, Px2, NULL, NULL, NULL, Gx2, NULL) == TSCVX_SETUP_OK,
                  "P, G update");
            eq_compare("after a P and G update", ws, &e, q, 2, iters[t]);
            /* the next setup: P and G as before (c and h, which d points to, as updated) */
            for (int j = 0; j < EQ_N; j++) {
                for (int k = Pp[j]; k < Pp[j + 1]; k++)
                    if (Pi[k] == j) e.P[j][j] /= 4.0;
                for (int k = Gp[j]; k < Gp[j + 1]; k++) e.G[Gi[k]][j] = Gx[k];
            }
        }
    }
}

/* tscvx_warm_start: the next solve (only) starts from the given point, centred into the
 * cones, and reaches the same answer; bad points are refused or fall back to the cold start. */
static void test_warm_start(void) {
    small_soc p;
    const tscvx_data d = small_soc_data(&p);
    tscvx_settings st;
    tscvx_default_settings(&st);
    tscvx_workspace *ws = NULL;
    tscvx_info info;
    tscvx_float x[2], z[3], s[3], y[1] = {0.0}, h2[] = {1.5, 0, 0};
    CHECK(tscvx_setup(&ws, arena, sizeof arena, &d, &st) == TSCVX_SETUP_OK, "setup");
    CHECK(tscvx_solve(ws) == TSCVX_SOLVED, "cold solve");
    tscvx_get_info(ws, &info);
    CHECK(info.warm_started == 0, "a solve without a warm point started warm");
    tscvx_get_solution(ws, x, NULL, z, s);
    /* another radius, warm from the first answer: the answer of the new data */
    CHECK(tscvx_warm_start(ws, x, y, z, s) == TSCVX_SETUP_OK, "warm start refused");
    CHECK(tscvx_update_data(ws, NULL, NULL, NULL, NULL, NULL, h2) == TSCVX_SETUP_OK, "update");
    CHECK(tscvx_solve(ws) == TSCVX_SOLVED, "warm solve");
    tscvx_get_info(ws, &info);
    CHECK(info.warm_started == 1, "the warm point was not used");
    tscvx_float xw[2];
    tscvx_get_solution(ws, xw, NULL, NULL, NULL);
    CHECK(fabs(xw[0] - 1.5 * sqrt(0.5)) < 1e-7 && fabs(xw[1] - 1.5 * sqrt(0.5)) < 1e-7,
          "warm x %g %g", xw[0], xw[1]);
    CHECK(fabs(info.pcost + 1.5 * sqrt(2.0)) < 1e-7, "warm obj %g", info.pcost);
    /* the point served one solve */
    CHECK(tscvx_solve(ws) == TSCVX_SOLVED, "solve after the warm one");
    tscvx_get_info(ws, &info);
    CHECK(info.warm_started == 0, "the warm point served a second solve");
    /* refused: NULL (but for a part of length 0: y here), non-finite (which also drops a
     * point given before) */
    CHECK(tscvx_warm_start(ws, x, y, z, s) == TSCVX_SETUP_OK, "warm start refused");
    CHECK(tscvx_warm_start(ws, x, y, NULL, s) == TSCVX_SETUP_NULL_ARGUMENT, "NULL z accepted");
    CHECK(tscvx_solve(ws) == TSCVX_SOLVED, "solve after a NULL point");
    tscvx_get_info(ws, &info);
    CHECK(info.warm_started == 0, "a point survived a refused call");
    CHECK(tscvx_warm_start(ws, NULL, y, z, s) == TSCVX_SETUP_NULL_ARGUMENT, "NULL x accepted");
    CHECK(tscvx_warm_start(NULL, x, y, z, s) == TSCVX_SETUP_NULL_ARGUMENT, "NULL ws accepted");
    CHECK(tscvx_warm_start(ws, x, y, z, s) == TSCVX_SETUP_OK, "warm start refused");
    tscvx_float znan[3] = {z[0], NAN, z[2]};
    CHECK(tscvx_warm_start(ws, x, y, znan, s) == TSCVX_SETUP_NONFINITE_DATA, "NaN z accepted");
    CHECK(tscvx_solve(ws) == TSCVX_SOLVED, "solve after a refused point");
    tscvx_get_info(ws, &info);
    CHECK(info.warm_started == 0, "a refused point was used");
    /* s outside its cone (|s_1| > s_0 by far), and so is the data's slack h - G x at x: the
     * centred point is outside too, the solve starts cold and still solves */
    tscvx_float sout[3] = {-10.0, 50.0, 0.0}, xfar[2] = {10.0, 10.0}, xnear[2] = {0.1, 0.2};
    CHECK(tscvx_warm_start(ws, xfar, y, z, sout) == TSCVX_SETUP_OK, "finite point refused");
    CHECK(tscvx_solve(ws) == TSCVX_SOLVED, "solve from a point outside the cone");
    tscvx_get_info(ws, &info);
    CHECK(info.warm_started == 0, "a point outside the cone was used");
    tscvx_get_solution(ws, xw, NULL, NULL, NULL);
    CHECK(fabs(xw[0] - 1.5 * sqrt(0.5)) < 1e-7, "x after the cold fallback %g", xw[0]);
    /* the same s, but the data's slack at x strictly inside the cone: it replaces s */
    CHECK(tscvx_warm_start(ws, xnear, y, z, sout) == TSCVX_SETUP_OK, "finite point refused");
    CHECK(tscvx_solve(ws) == TSCVX_SOLVED, "solve with the data's slack");
    tscvx_get_info(ws, &info);
    CHECK(info.warm_started == 1, "the data's slack did not replace s");
    CHECK(fabs(info.pcost + 1.5 * sqrt(2.0)) < 1e-7, "obj from the data's slack %.12g",
          info.pcost);

    /* infeasibility is still detected from a warm start (x >= 1 and x <= 0) */
    tscvx_int Gp[] = {0, 2}, Gi[] = {0, 1};
    tscvx_float Gx[] = {-1, 1}, h[] = {-1, 0}, c[] = {1};
    tscvx_data di = {1, 0, 2, NULL, NULL, NULL, c, NULL, NULL, NULL, NULL, Gp, Gi, Gx, h, 2, 0,
                     NULL};
    tscvx_workspace *wi = NULL;
    tscvx_float xi[1] = {0.5}, zi[2] = {1.0, 1.0}, si[2] = {0.5, 0.5};
    CHECK(tscvx_setup(&wi, arena2, sizeof arena2, &di, &st) == TSCVX_SETUP_OK, "setup");
    /* no equalities: y may be NULL */
    CHECK(tscvx_warm_start(wi, xi, NULL, zi, si) == TSCVX_SETUP_OK, "warm");
    CHECK(tscvx_solve(wi) == TSCVX_PRIMAL_INFEASIBLE, "infeasible from a warm start");
    tscvx_get_info(wi, &info);
    CHECK(info.warm_started == 1, "the warm point was not used");
}

/* Corrupted structure never crashes: random mutations of the index arrays (row indices,
 * interior column pointers), the cone dimensions and the orthant size of a small problem with
 * P, A, an orthant and two SOCs. Every array and the arena are malloc'ed at their exact sizes,
 * so that valgrind flags any read or write outside them. Each mutant is refused with a status
 * or, if still valid, solved to one of the solve statuses, with every KKT method. (The
 * lengths the caller promises, n + 1 pointers and nnz = Gp[n] entries, are the caller's
 * contract: a C API cannot check them, so the last pointer and n are not mutated.) */
#define FUZZ_N 6
#define FUZZ_P 2
#define FUZZ_M 9 /* l = 3, q = {3, 3} */
#define FUZZ_TRIALS 3000

static void *dup_exact(const void *src, size_t bytes) {
    void *d = malloc(bytes);
    CHECK(d != NULL, "malloc");
    if (d) memcpy(d, src, bytes);
    return d;
}

static tscvx_int fuzz_value(tscvx_int old, tscvx_int range) {
    const tscvx_int pick[] = {-1, 0, 1, range - 1, range, range + 1, old - 1, old + 1,
                              1 << 30, -(1 << 30)};
    return pick[(int)(ct_rand() * (sizeof pick / sizeof pick[0]))];
}

static void test_fuzz_structure(void) {
    /* columns: x0..x5; A rows {0, 1}; G: orthant rows 0..2, SOC rows 3..5 and 6..8 */
    const tscvx_int Pp0[FUZZ_N + 1] = {0, 1, 2, 3, 4, 5, 6}, Pi0[6] = {0, 1, 2, 3, 4, 5};
    const tscvx_int Ap0[FUZZ_N + 1] = {0, 1, 2, 3, 4, 4, 4}, Ai0[4] = {0, 0, 1, 1};
    const tscvx_int Gp0[FUZZ_N + 1] = {0, 2, 4, 6, 7, 8, 9};
    const tscvx_int Gi0[9] = {0, 4, 1, 5, 2, 7, 3, 6, 8}, q0[2] = {3, 3};
    const tscvx_float Px[6] = {1, 1, 1, 1, 1, 1}, c[FUZZ_N] = {-1, 1, -1, 1, 0, 0};
    const tscvx_float Ax[4] = {1, 1, 1, -1}, b[FUZZ_P] = {1, 0};
    const tscvx_float Gx[9] = {-1, -1, -1, -1, -1, -1, -1, -1, -1};
    const tscvx_float h[FUZZ_M] = {1, 1, 1, 2, 0, 0, 2, 0, 0};
    const int backends[] = {TSCVX_KKT_AUTO, TSCVX_KKT_STATIC, TSCVX_KKT_LDL};
    int solved = 0, refused = 0;
    for (int trial = 0; trial < FUZZ_TRIALS; trial++) {
        tscvx_int *Pp = dup_exact(Pp0, sizeof Pp0), *Pi = dup_exact(Pi0, sizeof Pi0);
        tscvx_int *Ap = dup_exact(Ap0, sizeof Ap0), *Ai = dup_exact(Ai0, sizeof Ai0);
        tscvx_int *Gp = dup_exact(Gp0, sizeof Gp0), *Gi = dup_exact(Gi0, sizeof Gi0);
        tscvx_int *q = dup_exact(q0, sizeof q0);
        tscvx_float *vPx = dup_exact(Px, sizeof Px), *vc = dup_exact(c, sizeof c);
        tscvx_float *vAx = dup_exact(Ax, sizeof Ax), *vb = dup_exact(b, sizeof b);
        tscvx_float *vGx = dup_exact(Gx, sizeof Gx), *vh = dup_exact(h, sizeof h);
        tscvx_data d = {FUZZ_N, FUZZ_P, FUZZ_M, Pp, Pi, vPx, vc, Ap, Ai, vAx, vb,
                        Gp, Gi, vGx, vh, 3, 2, q};
        const int mutations = 1 + (int)(ct_rand() * 3);
        for (int k = 0; k < mutations; k++) {
            const int j = (int)(ct_rand() * FUZZ_N); /* a column or an entry */
            switch ((int)(ct_rand() * 8)) {
            case 0: Pi[j] = fuzz_value(Pi[j], FUZZ_N); break;
            case 1: Ai[j % 4] = fuzz_value(Ai[j % 4], FUZZ_P); break;
            case 2: Gi[j] = fuzz_value(Gi[j], FUZZ_M); break;
            case 3: Pp[j] = fuzz_value(Pp[j], 6); break; /* pointers 0..n-1 */
            case 4: Ap[j] = fuzz_value(Ap[j], 4); break;
            case 5: Gp[j] = fuzz_value(Gp[j], 9); break;
            case 6: q[j % 2] = fuzz_value(q[j % 2], FUZZ_M); break;
            default: d.l = fuzz_value(d.l, FUZZ_M); break;
            }
        }
        tscvx_settings st;
        tscvx_default_settings(&st);
        st.kkt_backend = backends[trial % 3];
        st.max_iter = 30;
        size_t nscratch = 0, narena = 0;
        char msg[TSCVX_MESSAGE_LEN];
        const tscvx_setup_status checked = tscvx_check_data(&d, msg);
        tscvx_setup_status r = tscvx_scratch_size(&d, &st, &nscratch);
        CHECK((checked == TSCVX_SETUP_OK) == (r == TSCVX_SETUP_OK), "trial %d: check_data %d, "
              "scratch_size %d", trial, (int)checked, (int)r);
        void *scratch = r == TSCVX_SETUP_OK ? malloc(nscratch) : NULL;
        if (scratch) r = tscvx_workspace_size(&d, &st, scratch, nscratch, &narena);
        free(scratch);
        void *mem = r == TSCVX_SETUP_OK ? malloc(narena) : NULL;
        tscvx_workspace *ws = NULL;
        if (mem) r = tscvx_setup(&ws, mem, narena, &d, &st);
        if (mem && r == TSCVX_SETUP_OK) {
            const tscvx_solve_status s = tscvx_solve(ws);
            CHECK(s >= TSCVX_SOLVED && s < TSCVX_NSTATUS, "trial %d: solve status %d", trial,
                  (int)s);
            solved++;
        } else {
            CHECK(r > TSCVX_SETUP_OK && r < TSCVX_SETUP_NSTATUS, "trial %d: status %d", trial,
                  (int)r);
            refused++;
        }
        free(mem);
        free(Pp), free(Pi), free(Ap), free(Ai), free(Gp), free(Gi), free(q);
        free(vPx), free(vc), free(vAx), free(vb), free(vGx), free(vh);
    }
    CHECK(solved > 0 && refused > FUZZ_TRIALS / 2, "solved %d, refused %d", solved, refused);
    printf("fuzzed structure: %d mutants refused, %d still valid and solved\n", refused, solved);
}


/* ---- single-event upsets in the workspace: the set-up checksum ---------------------------
 * A stage problem (T stages of x_k in R^2, u_k in R: x_{k+1} = A x_k + B u_k, x_0 given;
 * x_k <= 5, |x_k| <= 10, |u_k| <= 2; cost sum 0.1 |x_k|^2 + u_k^2 + c'z) that every KKT method
 * takes: the banded one finds the stages (groups {x_k}, {u_k}), the sparse ones expand its
 * Q3 cones with soc_dense_max = 2. */
#define UP_T 12
#define UP_N (3 * UP_T)
#define UP_P (2 * UP_T)
#define UP_M (2 * UP_T + 5 * UP_T) /* orthant 2T, then per stage Q3 (10, x_k) and Q2 (2, u_k) */
#define UP_GUARD 4096

typedef struct {
    tscvx_int Pp[UP_N + 1], Pi[UP_N], Ap[UP_N + 1], Ai[4 * UP_N], Gp[UP_N + 1], Gi[2 * UP_N];
    tscvx_int q[2 * UP_T];
    tscvx_float Px[UP_N], c[UP_N], Ax[4 * UP_N], b[UP_P], Gx[2 * UP_N], h[UP_M];
} stage_problem;

static tscvx_data stage_data(stage_problem *sp) {
    const tscvx_float Ad[2][2] = {{1.0, 0.1}, {0.0, 1.0}}, Bd[2] = {0.005, 0.1};
    const int l = 2 * UP_T;
    int na = 0, ng = 0;
    for (int k = 0; k < UP_T; k++)
        for (int v = 0; v < 3; v++) { /* column 3k + v: x_k0, x_k1, u_k */
            const int j = 3 * k + v;
            sp->Pp[j] = j, sp->Pi[j] = j, sp->Px[j] = v < 2 ? 0.1 : 1.0;
            sp->c[j] = 0.05 * ct_randn();
            sp->Ap[j] = na; /* rows: x_0 = x0 (0, 1), then 2 + 2k + i: x_{k+1} - A x_k - B u_k */
            if (k == 0 && v < 2) sp->Ai[na] = v, sp->Ax[na++] = 1.0;
            if (k > 0 && v < 2) sp->Ai[na] = 2 * k + v, sp->Ax[na++] = 1.0;
            for (int i = 0; k + 1 < UP_T && i < 2; i++) {
                const tscvx_float a = v < 2 ? -Ad[i][v] : -Bd[i];
                if (a != 0.0) sp->Ai[na] = 2 + 2 * k + i, sp->Ax[na++] = a;
            }
            sp->Gp[j] = ng; /* rows: orthant 2k + v (x only), Q3 at l + 5k (head 10), Q2 at l + 5k + 3 */
            if (v < 2) sp->Gi[ng] = 2 * k + v, sp->Gx[ng++] = 1.0;
            sp->Gi[ng] = v < 2 ? l + 5 * k + 1 + v : l + 5 * k + 4, sp->Gx[ng++] = -1.0;
        }
    sp->Pp[UP_N] = UP_N, sp->Ap[UP_N] = na, sp->Gp[UP_N] = ng;
    sp->b[0] = 1.0, sp->b[1] = 0.5;
    for (int i = 2; i < UP_P; i++) sp->b[i] = 0.0;
    for (int i = 0; i < l; i++) sp->h[i] = 5.0;
    for (int k = 0; k < UP_T; k++) {
        const int o = l + 5 * k;
        sp->h[o] = 10.0, sp->h[o + 1] = sp->h[o + 2] = 0.0, sp->h[o + 3] = 2.0, sp->h[o + 4] = 0.0;
        sp->q[2 * k] = 3, sp->q[2 * k + 1] = 2;
    }
    const tscvx_data d = {UP_N, UP_P, UP_M, sp->Pp, sp->Pi, sp->Px, sp->c, sp->Ap, sp->Ai,
                          sp->Ax, sp->b, sp->Gp, sp->Gi, sp->Gx, sp->h, l, 2 * UP_T, sp->q};
    return d;
}

/* One bit of the workspace to flip: an int, a byte or a pointer; head: in the struct (every
 * call but cleanup refuses it), else in an index array (update and solve refuse it). */
typedef struct {
    const char *name;
    void *at;
    int kind; /* 0: tscvx_int, 1: signed char, 2: pointer, 3: tscvx_int's lowest bit */
    int head;
} upset_site;

static void flip(const upset_site *u) {
    if (u->kind == 0 || u->kind == 3) {
        tscvx_int v;
        memcpy(&v, u->at, sizeof v);
        v ^= u->kind == 0 ? 1 << 20 : 1; /* an index a million entries away, or the next */
        memcpy(u->at, &v, sizeof v);
    } else if (u->kind == 1) {
        *(signed char *)u->at ^= 0x40;
    } else {
        uintptr_t v;
        memcpy(&v, u->at, sizeof v);
        v ^= (uintptr_t)1 << 24; /* 16 MiB away */
        memcpy(u->at, &v, sizeof v);
    }
}

#define SITE(name, lvalue, kind, head) {name, (void *)(uintptr_t)&(lvalue), kind, head}

static unsigned char up_buf[UP_GUARD + (1 << 18) + UP_GUARD], up_copy[1 << 18];

/* Each site flipped in turn between solves: every call that would follow it refuses the
 * workspace (solve: INVALID_INPUT; the others: NOT_READY), tscvx_check_workspace says it is
 * damaged, and the refused calls write nothing (the arena compared byte for byte, the guard
 * bytes around it intact: valgrind and ASan watch the rest). Flipped back, the workspace
 * solves to the same bits. The sites: pattern indices and pointers, cone sizes and offsets,
 * the permutation, the KKT maps, L's pattern, the banded groups, row lists, band order and
 * profile; in the struct: sizes, counts, settings and pointers. */
static void test_upsets(int backend, tscvx_int dense_max) {
    static stage_problem sp;
    const tscvx_data d = stage_data(&sp);
    tscvx_settings st;
    memset(&st, 0, sizeof st); /* its padding too: setup copies it into the arena compared */
    tscvx_default_settings(&st);
    st.kkt_backend = backend;
    st.soc_dense_max = dense_max;
    unsigned char *arena3 = up_buf + UP_GUARD;
    size_t narena = 0;
    memset(up_buf, 0xA5, sizeof up_buf);
    CHECK(tscvx_workspace_size(&d, &st, arena3, sizeof up_copy, &narena) == TSCVX_SETUP_OK &&
              narena <= sizeof up_copy, "stage problem: size %zu", narena);
    memset(up_buf, 0xA5, sizeof up_buf);
    tscvx_workspace *ws = NULL;
    CHECK(tscvx_setup(&ws, arena3, narena, &d, &st) == TSCVX_SETUP_OK, "stage setup");
    if (ws == NULL) return;
    const tscvx_int expect = backend == TSCVX_KKT_AUTO ? TSCVX_KKT_BANDED : backend;
    tscvx_info info;
    tscvx_get_info(ws, &info);
    CHECK(info.kkt_backend == expect, "method %d, not %d", (int)info.kkt_backend, (int)expect);
    CHECK(tscvx_solve(ws) == TSCVX_SOLVED, "stage problem unsolved (method %d)", (int)expect);
    tscvx_float x0[UP_N], x1[UP_N], y[UP_P], z[UP_M], s[UP_M];
    CHECK(tscvx_get_solution(ws, x0, y, z, s) == TSCVX_SETUP_OK, "solution");
    tscvx_kkt *k = &ws->kkt;
    tscvx_banded *bd = &ws->bd;
    upset_site sites[64];
    int ns = 0;
    const upset_site common[] = {
        SITE("P.i[3]", ws->P.i[3], 0, 0),      SITE("A.p[4]", ws->A.p[4], 0, 0),
        SITE("A.i[6]", ws->A.i[6], 0, 0),      SITE("G.p[5]", ws->G.p[5], 0, 0),
        SITE("G.i[7]", ws->G.i[7], 0, 0),      SITE("K.q[1]", ws->K.q[1], 0, 0),
        SITE("K.off[2]", ws->K.off[2], 0, 0),  SITE("n", ws->n, 0, 1),
        SITE("m", ws->m, 0, 1),                SITE("K.nsoc", ws->K.nsoc, 0, 1),
        SITE("K.l", ws->K.l, 0, 1),            SITE("G.nnz", ws->G.nnz, 0, 1),
        SITE("log_cap", ws->log_cap, 0, 1),    SITE("st.max_iter", ws->st.max_iter, 0, 1),
        SITE("pointer G.i", ws->G.i, 2, 1),    SITE("pointer x", ws->x, 2, 1),
        SITE("pointer log", ws->log, 2, 1),    SITE("kkt.nexp", k->nexp, 0, 1)};
    for (size_t t = 0; t < sizeof common / sizeof common[0]; t++) sites[ns++] = common[t];
    if (expect == TSCVX_KKT_BANDED) {
        const upset_site banded[] = {
            SITE("bd.gp[2]", bd->gp[2], 0, 0),         SITE("bd.gvar[5]", bd->gvar[5], 0, 0),
            SITE("bd.loc[4]", bd->loc[4], 0, 0),       SITE("bd.hp[3]", bd->hp[3], 0, 0),
            SITE("bd.mapP[2]", bd->mapP[2], 0, 0),     SITE("bd.gcp[1]", bd->gcp[1], 0, 0),
            SITE("bd.gcone[3]", bd->gcone[3], 0, 0),   SITE("bd.Grp[4]", bd->Grp[4], 0, 0),
            SITE("bd.Gr_k[5]", bd->Gr_k[5], 0, 0),     SITE("bd.Gr_loc[2]", bd->Gr_loc[2], 0, 0),
            SITE("bd.cgroup[6]", bd->cgroup[6], 0, 0), SITE("bd.rp[2]", bd->rp[2], 0, 0),
            SITE("bd.rrow[3]", bd->rrow[3], 0, 0),     SITE("bd.posA[4]", bd->posA[4], 0, 0),
            SITE("bd.cp[2]", bd->cp[2], 0, 0),         SITE("bd.perm[5]", bd->perm[5], 0, 0),
            SITE("bd.iperm[6]", bd->iperm[6], 0, 0),   SITE("bd.yfirst[7]", bd->yfirst[7], 0, 0),
            SITE("bd.yp[8]", bd->yp[8], 0, 0),         SITE("bd.bp[2]", bd->bp[2], 0, 0),
            SITE("bd.ga0[1]", bd->ga0[1], 0, 0),       SITE("bd.border[1]", bd->border[1], 1, 0),
            SITE("bd.hasP[2]", bd->hasP[2], 1, 0),     SITE("bd.ngroup", bd->ngroup, 0, 1),
            SITE("bd.nb", bd->nb, 0, 1),               SITE("pointer bd.yp", bd->yp, 2, 1),
            SITE("pointer bd.Y", bd->Y, 2, 1)};
        for (size_t t = 0; t < sizeof banded / sizeof banded[0]; t++) sites[ns++] = banded[t];
    } else {
        const upset_site sparse[] = {
            SITE("kkt.Kp[5]", k->Kp[5], 0, 0),           SITE("kkt.Ki[7]", k->Ki[7], 0, 0),
            SITE("kkt.rowblk[2]", k->rowblk[2], 1, 0),   SITE("kkt.pinv[3]", k->pinv[3], 0, 0),
            SITE("kkt.mapP[1]", k->mapP[1], 0, 0),       SITE("kkt.mapA[2]", k->mapA[2], 0, 0),
            SITE("kkt.mapG[3]", k->mapG[3], 0, 0),       SITE("kkt.mapDiag[4]", k->mapDiag[4], 0, 0),
            SITE("kkt.mapCone[5]", k->mapCone[5], 0, 0), SITE("kkt.expanded[1]", k->expanded[1], 0, 0),
            SITE("kkt.Lp[6]", k->Lp[6], 0, 0),           SITE("kkt.dim", k->dim, 0, 1),
            SITE("kkt.lnz", k->lnz, 0, 1),               SITE("pointer kkt.Kx", k->Kx, 2, 1)};
        for (size_t t = 0; t < sizeof sparse / sizeof sparse[0]; t++) sites[ns++] = sparse[t];
        if (k->backend == &tscvx_backend_static) {
            sites[ns++] = (upset_site)SITE("kkt.Li[9]", k->Li[9], 0, 0);
            sites[ns++] = (upset_site)SITE("kkt.Rp[4]", k->Rp[4], 0, 0);
            sites[ns++] = (upset_site)SITE("kkt.Rj[8]", k->Rj[8], 0, 0);
        } else {
            sites[ns++] = (upset_site)SITE("kkt.Parent[3]", k->Parent[3], 0, 0);
        }
    }
    char msg[TSCVX_MESSAGE_LEN];
    int refused = 0;
    for (int t = 0; t < ns; t++) {
        const upset_site *u = &sites[t];
        flip(u);
        memcpy(up_copy, arena3, narena);
        tscvx_iter_log row;
        const int solve_refused = tscvx_solve(ws) == TSCVX_INVALID_INPUT;
        const int update_refused =
            tscvx_update_data(ws, NULL, sp.c, NULL, NULL, NULL, NULL) == TSCVX_SETUP_NOT_READY;
        CHECK(solve_refused && update_refused, "method %d, %s flipped: solve %s, update %s",
              (int)expect, u->name, solve_refused ? "refused" : "ran",
              update_refused ? "refused" : "ran");
        CHECK(tscvx_check_workspace(ws, msg) == TSCVX_SETUP_NOT_READY &&
                  strstr(msg, "workspace damaged") != NULL,
              "method %d, %s flipped: check says \"%s\"", (int)expect, u->name, msg);
        if (u->head) { /* every call reads the struct: all refuse */
            CHECK(tscvx_warm_start(ws, x0, y, z, s) == TSCVX_SETUP_NOT_READY &&
                      tscvx_get_solution(ws, x1, NULL, NULL, NULL) == TSCVX_SETUP_NOT_READY &&
                      tscvx_get_info(ws, &info) == TSCVX_SETUP_NOT_READY &&
                      tscvx_get_iter_log(ws, 1, &row) == TSCVX_SETUP_NOT_READY &&
                      tscvx_update_settings(ws, &st) == TSCVX_SETUP_NOT_READY,
                  "method %d, %s flipped: a call taking the struct was not refused",
                  (int)expect, u->name);
        }
        CHECK(memcmp(up_copy, arena3, narena) == 0, "method %d, %s flipped: a refused call "
              "wrote into the workspace", (int)expect, u->name);
        flip(u);
        refused += solve_refused;
    }
    for (size_t i = 0; i < UP_GUARD; i++)
        CHECK(up_buf[i] == 0xA5 && arena3[sizeof up_copy + i] == 0xA5, "guard byte %zu", i);
    /* restored: intact, and the same answer to the last bit */
    CHECK(tscvx_check_workspace(ws, msg) == TSCVX_SETUP_OK && msg[0] == '\0', "restored: %s",
          msg);
    CHECK(tscvx_solve(ws) == TSCVX_SOLVED && tscvx_get_solution(ws, x1, NULL, NULL, NULL) ==
              TSCVX_SETUP_OK && memcmp(x0, x1, sizeof x0) == 0,
          "method %d: not the same answer after the upsets", (int)expect);
    /* numbers are not covered: an iterate, rewritten at every solve, flipped between solves
     * changes nothing; the checks stay quiet */
    ws->x[3] = -ws->x[3];
    CHECK(tscvx_check_workspace(ws, msg) == TSCVX_SETUP_OK, "iterate flipped: %s", msg);
    CHECK(tscvx_solve(ws) == TSCVX_SOLVED && tscvx_get_solution(ws, x1, NULL, NULL, NULL) ==
              TSCVX_SETUP_OK && memcmp(x0, x1, sizeof x0) == 0, "iterate flipped: answer");
    /* settings changed through tscvx_update_settings are sealed again, not taken for damage */
    st.max_iter = 40, st.tol_feas = 1e-7;
    CHECK(tscvx_update_settings(ws, &st) == TSCVX_SETUP_OK && tscvx_solve(ws) == TSCVX_SOLVED,
          "method %d: solve after new settings", (int)expect);
    /* a damaged workspace can still be ended (cleanup follows no pointer) */
    ws->n ^= 1 << 20;
    CHECK(tscvx_cleanup(ws) == TSCVX_SETUP_OK, "cleanup of a damaged workspace");
    CHECK(tscvx_check_workspace(ws, msg) == TSCVX_SETUP_NOT_READY && strstr(msg, "mark"),
          "after cleanup: %s", msg);
    printf("method %d: %d bit flips in the workspace, each refused before it was followed\n",
           (int)expect, refused);
}

/* ---- an upset during a solve: tscvx_solve's end check ------------------------------------
 * The library has no hook inside a solve, and none is added for the test: the moment of the
 * upset is the solve's own write of its last log row. A first solve gives that row (its
 * iteration count; the solve is deterministic from the cold start), the workspace is set up
 * again with the arena shifted so that the row begins a page, and the page is made
 * read-only: the solve's write of the row traps into a handler that flips a high bit of
 * set-up data the solve follows (an index of A's pattern: the body; the log's length: the
 * head), lets the page be written and returns, and the write completes. The solve has converged at that row:
 * without the end check it reports SOLVED with the answer (as it did before the check); with
 * it, TSCVX_INVALID_INPUT, no answer from tscvx_get_solution, and tscvx_check_workspace says
 * the workspace was damaged during a solve. Nothing follows the flipped index after the trap,
 * so valgrind and ASan stay quiet either way. Flipped back, the workspace solves to the same
 * bits as before. */
static unsigned char *trap_page;
static size_t trap_len;
static const upset_site *trap_site;
static volatile sig_atomic_t trap_hits;

static void on_trap(int sig, siginfo_t *si, void *uc) {
    (void)uc;
    const unsigned char *at = (const unsigned char *)si->si_addr;
    if (trap_page == NULL || at < trap_page || at >= trap_page + trap_len) {
        signal(sig, SIG_DFL); /* not ours: the fault happens again, unhandled */
        return;
    }
    flip(trap_site);
    mprotect(trap_page, trap_len, PROT_READ | PROT_WRITE);
    trap_page = NULL;
    trap_hits++;
}

/* Arms the trap: `site` is flipped at the first write into [at, at + len), made read-only
 * here; the previous SIGSEGV action is kept in `old` for trap_disarm. */
static void trap_arm(const upset_site *site, unsigned char *at, size_t len, struct sigaction *old) {
    struct sigaction on;
    memset(&on, 0, sizeof on);
    on.sa_sigaction = on_trap;
    on.sa_flags = SA_SIGINFO;
    sigemptyset(&on.sa_mask);
    trap_site = site;
    trap_hits = 0;
    trap_len = len;
    trap_page = at;
    CHECK(sigaction(SIGSEGV, &on, old) == 0, "sigaction");
    CHECK(mprotect(at, len, PROT_READ) == 0, "mprotect");
}

/* The page writable again (whether or not the trap fired) and the old SIGSEGV action back. */
static void trap_disarm(unsigned char *at, size_t len, const struct sigaction *old) {
    mprotect(at, len, PROT_READ | PROT_WRITE);
    trap_page = NULL;
    sigaction(SIGSEGV, old, NULL);
}

static unsigned char dur_buf[(1 << 18) + 2 * 65536];

/* The page size the upset tests trap on (0 when the system's is not one they can use), the
 * start of dur_buf's first whole page, and an upset test's settings. */
static size_t upset_page(void) {
    const long page = sysconf(_SC_PAGESIZE);
    CHECK(page > 0 && page <= 65536, "page size %ld", page);
    return page > 0 && page <= 65536 ? (size_t)page : 0;
}

static unsigned char *upset_base(size_t page) {
    return dur_buf + (page - (uintptr_t)dur_buf % page) % page;
}

static tscvx_settings upset_settings(int backend, tscvx_int dense_max) {
    tscvx_settings st;
    tscvx_default_settings(&st);
    st.kkt_backend = backend;
    st.soc_dense_max = dense_max;
    return st;
}

static void test_upset_during_solve(int backend, tscvx_int dense_max) {
    static stage_problem sp;
    const tscvx_data d = stage_data(&sp);
    const size_t page = upset_page();
    if (page == 0) return;
    tscvx_settings st = upset_settings(backend, dense_max);
    st.max_iter = 500; /* a log long enough that the page from the last row holds log rows only */
    unsigned char *base = upset_base(page);
    size_t narena = 0;
    CHECK(tscvx_workspace_size(&d, &st, base, 1 << 18, &narena) == TSCVX_SETUP_OK &&
              narena + (size_t)page <= (1 << 18) + 65536, "size %zu", narena);
    tscvx_workspace *ws = NULL;
    CHECK(tscvx_setup(&ws, base, narena, &d, &st) == TSCVX_SETUP_OK, "setup");
    if (ws == NULL) return;
    tscvx_info info;
    tscvx_float x0[UP_N], x1[UP_N];
    CHECK(tscvx_solve(ws) == TSCVX_SOLVED && tscvx_get_info(ws, &info) == TSCVX_SETUP_OK &&
              tscvx_get_solution(ws, x0, NULL, NULL, NULL) == TSCVX_SETUP_OK, "first solve");
    const tscvx_int last = info.iterations, method = info.kkt_backend;
    CHECK((size_t)(ws->log_cap - last) * sizeof(tscvx_iter_log) >= (size_t)page,
          "log too short for the page: %d rows from row %d", (int)ws->log_cap, (int)last);
    /* the same problem again, the arena shifted so that the last row begins a page */
    const size_t shift = ((size_t)page - (uintptr_t)&ws->log[last] % (size_t)page) % (size_t)page;
    CHECK(tscvx_setup(&ws, base + shift, narena, &d, &st) == TSCVX_SETUP_OK, "setup shifted");
    if (ws == NULL) return;
    CHECK((uintptr_t)&ws->log[last] % (size_t)page == 0, "row %d not at a page", (int)last);
    /* what the solve no longer follows after that row (n is: the best iterate is saved) */
    const upset_site sites[] = {SITE("A.i[6]", ws->A.i[6], 0, 0),
                                SITE("log_cap", ws->log_cap, 0, 1)};
    struct sigaction old;
    char msg[TSCVX_MESSAGE_LEN];
    int said = 0;
    for (size_t t = 0; t < sizeof sites / sizeof sites[0]; t++) {
        const upset_site *u = &sites[t];
        trap_arm(u, (unsigned char *)&ws->log[last], (size_t)page, &old);
        const tscvx_solve_status got = tscvx_solve(ws);
        trap_disarm((unsigned char *)&ws->log[last], (size_t)page, &old);
        CHECK(trap_hits == 1, "method %d, %s: the upset did not come during the solve (%d)",
              (int)method, u->name, (int)trap_hits);
        said += trap_hits == 1 && got == TSCVX_INVALID_INPUT;
        CHECK(got == TSCVX_INVALID_INPUT, "method %d, %s flipped during the solve (at its last "
              "iteration, %d): it returned \"%s\", not invalid input", (int)method, u->name,
              (int)last, tscvx_solve_status_message(got));
        CHECK(tscvx_check_workspace(ws, msg) == TSCVX_SETUP_NOT_READY &&
                  strstr(msg, "workspace damaged during a solve: set-up checksum mismatch in "
                              "its ") != NULL &&
                  strstr(msg, u->head ? "sizes, settings or pointers" : "index arrays") != NULL,
              "method %d, %s flipped during the solve: check says \"%s\"", (int)method,
              u->name, msg);
        if (!u->head) { /* the struct intact: its info read, the iterate withheld */
            CHECK(tscvx_get_info(ws, &info) == TSCVX_SETUP_OK &&
                      info.status == TSCVX_INVALID_INPUT,
                  "method %d, %s: info.status %d", (int)method, u->name, (int)info.status);
            CHECK(tscvx_get_solution(ws, x1, NULL, NULL, NULL) == TSCVX_SETUP_NO_SOLUTION,
                  "method %d, %s: the iterate of a damaged solve was returned", (int)method,
                  u->name);
        }
        CHECK(tscvx_solve(ws) == TSCVX_INVALID_INPUT, "method %d, %s: the next solve ran",
              (int)method, u->name);
        flip(u);
        CHECK(tscvx_check_workspace(ws, msg) == TSCVX_SETUP_OK && msg[0] == '\0',
              "restored: %s", msg);
        CHECK(tscvx_solve(ws) == TSCVX_SOLVED &&
                  tscvx_get_solution(ws, x1, NULL, NULL, NULL) == TSCVX_SETUP_OK &&
                  memcmp(x0, x1, sizeof x0) == 0,
              "method %d, %s: not the same answer once restored", (int)method, u->name);
    }
    printf("method %d: %d of %d upsets during the solve (at its last iteration, %d) said by "
           "that solve\n", (int)method, said, (int)(sizeof sites / sizeof sites[0]), (int)last);
}

/* ---- an upset during a data update: tscvx_update_data's end check ------------------------
 * As above, without a hook: the moment of the upset is the update's first write into the page
 * of the scaled h (the intake writes every entry of the data's scaled copies), made
 * read-only. The handler flips a bit the rest of the update may follow without leaving its
 * arrays (the lowest bit of an even row index of A's pattern: the body; nothing else than
 * the range it stays in) or does not follow (the log's length: the head). Without the end
 * check the update returns OK and only the next call says the workspace is damaged; with it,
 * TSCVX_SETUP_NOT_READY, tscvx_check_workspace says the damage came during a data update,
 * the solve is refused, and once the bit is back the workspace waits for a valid update,
 * after which it solves to the bits of a fresh setup. */
static void test_upset_during_update(int backend, tscvx_int dense_max) {
    static stage_problem sp;
    const tscvx_data d = stage_data(&sp);
    const size_t page = upset_page();
    if (page == 0) return;
    tscvx_settings st = upset_settings(backend, dense_max);
    unsigned char *base = upset_base(page);
    size_t narena = 0;
    CHECK(tscvx_workspace_size(&d, &st, base, 1 << 18, &narena) == TSCVX_SETUP_OK &&
              narena <= (1 << 18), "size %zu", narena);
    tscvx_workspace *ws = NULL;
    CHECK(tscvx_setup(&ws, base, narena, &d, &st) == TSCVX_SETUP_OK, "setup");
    if (ws == NULL) return;
    tscvx_info info;
    tscvx_float x0[UP_N], x1[UP_N];
    CHECK(tscvx_solve(ws) == TSCVX_SOLVED && tscvx_get_info(ws, &info) == TSCVX_SETUP_OK &&
              tscvx_get_solution(ws, x0, NULL, NULL, NULL) == TSCVX_SETUP_OK, "first solve");
    const tscvx_int method = info.kkt_backend;
    tscvx_int k = 0;
    while (k < ws->A.nnz && !(ws->A.i[k] % 2 == 0 && ws->A.i[k] + 1 < ws->p)) k++;
    CHECK(k < ws->A.nnz, "no even row index in A");
    if (k == ws->A.nnz) return;
    const upset_site sites[] = {SITE("A.i (lowest bit)", ws->A.i[k], 3, 0),
                                SITE("log_cap", ws->log_cap, 0, 1)};
    unsigned char *const h_page =
        (unsigned char *)((uintptr_t)ws->h - (uintptr_t)ws->h % (size_t)page);
    CHECK(h_page >= base, "the page of h begins before the arena");
    struct sigaction old;
    char msg[TSCVX_MESSAGE_LEN];
    int said = 0;
    for (size_t t = 0; t < sizeof sites / sizeof sites[0]; t++) {
        const upset_site *u = &sites[t];
        trap_arm(u, h_page, (size_t)page, &old);
        const tscvx_setup_status got = tscvx_update_data(ws, NULL, sp.c, NULL, NULL, NULL, NULL);
        trap_disarm(h_page, (size_t)page, &old);
        CHECK(trap_hits == 1, "method %d, %s: the upset did not come during the update (%d)",
              (int)method, u->name, (int)trap_hits);
        said += trap_hits == 1 && got == TSCVX_SETUP_NOT_READY;
        CHECK(got == TSCVX_SETUP_NOT_READY, "method %d, %s flipped during a data update: it "
              "returned \"%s\", not not-ready", (int)method, u->name,
              tscvx_setup_status_message(got));
        CHECK(tscvx_check_workspace(ws, msg) == TSCVX_SETUP_NOT_READY &&
                  strstr(msg, "workspace damaged during a data update: set-up checksum "
                              "mismatch in its ") != NULL &&
                  strstr(msg, u->head ? "sizes, settings or pointers" : "index arrays") != NULL,
              "method %d, %s flipped during a data update: check says \"%s\"", (int)method,
              u->name, msg);
        if (!u->head) { /* the struct intact: its info read, no solution of the last data */
            CHECK(tscvx_get_info(ws, &info) == TSCVX_SETUP_OK &&
                      info.status == TSCVX_INVALID_INPUT && info.iterations == 0,
                  "method %d, %s: info.status %d", (int)method, u->name, (int)info.status);
        }
        CHECK(tscvx_solve(ws) == TSCVX_INVALID_INPUT, "method %d, %s: the solve ran",
              (int)method, u->name);
        flip(u);
        /* intact again, but the numbers went through the damage: a valid update first */
        CHECK(tscvx_check_workspace(ws, msg) == TSCVX_SETUP_NOT_READY &&
                  strstr(msg, "waits for a valid update") != NULL,
              "method %d, %s restored: check says \"%s\"", (int)method, u->name, msg);
        CHECK(tscvx_solve(ws) == TSCVX_INVALID_INPUT, "method %d, %s restored: solve ran",
              (int)method, u->name);
        CHECK(tscvx_update_data(ws, sp.Px, sp.c, sp.Ax, sp.b, sp.Gx, sp.h) == TSCVX_SETUP_OK &&
                  tscvx_solve(ws) == TSCVX_SOLVED &&
                  tscvx_get_solution(ws, x1, NULL, NULL, NULL) == TSCVX_SETUP_OK &&
                  memcmp(x0, x1, sizeof x0) == 0,
              "method %d, %s: not a fresh setup's answer once restored and updated",
              (int)method, u->name);
    }
    printf("method %d: %d of %d upsets during a data update said by that update\n",
           (int)method, said, (int)(sizeof sites / sizeof sites[0]));
}

/* Started from its own answer, a problem is solved to the full tolerances. A warm point's mu
 * is about 1e-5; while the refinement waited for mu < 1e-6 of that, the banded method's
 * unrefined directions spoilt the primal residual of this problem (seed 147 of
 * tests/socp_problems.py's random_feasible, with P: 6 variables, 4 orthant rows, SOCs of 6
 * and 5) and the warm solve ended SOLVED_INACCURATE where the cold one solves it. */
static void test_warm_start_from_its_own_answer(void) {
    tscvx_int Gp[] = {0, 7, 11, 15, 20, 25, 33};
    tscvx_int Gi[] = {0, 2, 4, 5, 6, 9, 12, 1, 2, 11, 12, 2, 6, 8, 12, 1, 3,
                      7, 13, 14, 2, 4, 6, 12, 14, 3, 4, 5, 9, 11, 12, 13, 14};
    tscvx_float Gx[] = {0.7562088489832172,   0.1529630385848758,   -0.815439683831503,
                        1.2777426344627014,   -0.7425093270593649,  0.49035666924084315,
                        -1.691326626851531,   1.0,                  2.099280498824504,
                        -1.2306719534521107,  -2.214782510452624,   1.0,
                        1.4174302701114931,   0.36127660219043656,  -0.1946626710339065,
                        -0.5686467517769965,  1.0,                  -1.6175268300266765,
                        2.1200362260636743,   -2.3045075583695107,  -0.9612109054190797,
                        1.0,                  -0.8538040327723482,  0.14827317344177807,
                        -0.4514434897986513,  0.08584314615059828,  0.44034421834047527,
                        2.3091497586533145,   -0.40854606513940567, 0.6673722174520087,
                        -0.21374148147553584, 0.35210635647929983,  1.380349057576127};
    tscvx_float h[] = {0.34682955377075636, 0.6251748308882493,   1.5602028424503636,
                       1.855714438853353,   4.066501442288167,    -1.9983253807390728,
                       0.5603829231535592,  -1.2595910275541373,  0.547213846009136,
                       0.684331095787081,   4.562319744534219,    0.6873366669863596,
                       -0.10549860971352754, 0.337633730988081,   -4.761947087680487};
    tscvx_float c[] = {4.4395998998209665,  -1.3701567299917148, -2.0400814703823693,
                       2.4624399155756174,  -2.625271814717075,  -7.304365170719096};
    tscvx_int Pp[] = {0, 1, 2, 3, 4, 5, 7}, Pi[] = {0, 1, 2, 3, 4, 1, 5}, q[] = {6, 5};
    tscvx_float Px[] = {0.001, 0.012728830009658954, 0.001, 0.001, 0.001, -0.1494690486218058,
                        1.9057932724329227};
    const tscvx_data d = {6, 0, 15, Pp, Pi, Px, c, NULL, NULL, NULL, NULL, Gp, Gi, Gx, h, 4, 2, q};
    tscvx_settings st;
    tscvx_default_settings(&st);
    st.kkt_backend = TSCVX_KKT_BANDED;
    tscvx_workspace *ws = NULL;
    tscvx_info info;
    tscvx_float x[6], z[15], s[15];
    CHECK(tscvx_setup(&ws, arena, sizeof arena, &d, &st) == TSCVX_SETUP_OK, "setup");
    if (ws == NULL) return;
    CHECK(tscvx_solve(ws) == TSCVX_SOLVED, "cold solve");
    tscvx_get_info(ws, &info);
    const tscvx_float cold = info.pcost;
    CHECK(info.kkt_backend == TSCVX_KKT_BANDED, "method %d", (int)info.kkt_backend);
    tscvx_get_solution(ws, x, NULL, z, s);
    CHECK(tscvx_warm_start(ws, x, NULL, z, s) == TSCVX_SETUP_OK, "warm start refused");
    const tscvx_solve_status status = tscvx_solve(ws);
    tscvx_get_info(ws, &info);
    CHECK(status == TSCVX_SOLVED, "warm solve from its own answer: status %d, pres %g, dres %g",
          (int)status, info.pres, info.dres);
    CHECK(info.warm_started == 1 && info.restart_iterations == 0, "not the warm run's answer");
    CHECK(fabs(info.pcost - cold) <= 1e-7 * fabs(cold), "warm obj %.12g, cold %.12g",
          info.pcost, cold);
}

/* A solve that fails before its first iterate (NUMERICAL_ERROR, 0 iterations) computed no
 * cost, gap, residual or mu: the log's row 0 and the info hold NaN for them (as before any
 * solve), not 0 (which read as a zero gap and residuals). The start fails here on overflow:
 * min 1e300 x1 + x2 s.t. 1e300 x1 = 1e300, x >= 0. Under every KKT method. */
static void test_start_failure_logs_nan(void) {
    tscvx_int Ap[] = {0, 1, 1}, Ai[] = {0}, Gp[] = {0, 1, 2}, Gi[] = {0, 1};
    tscvx_float c[] = {1e300, 1}, Ax[] = {1e300}, b[] = {1e300}, Gx[] = {-1, -1}, h[] = {0, 0};
    tscvx_data d = {2, 1, 2, NULL, NULL, NULL, c, Ap, Ai, Ax, b, Gp, Gi, Gx, h, 2, 0, NULL};
    const tscvx_int methods[] = {TSCVX_KKT_AUTO, TSCVX_KKT_STATIC, TSCVX_KKT_LDL};
    for (size_t k = 0; k < sizeof methods / sizeof methods[0]; k++) {
        tscvx_settings st;
        tscvx_default_settings(&st);
        st.kkt_backend = methods[k];
        tscvx_workspace *ws = NULL;
        CHECK(tscvx_setup(&ws, arena2, sizeof arena2, &d, &st) == TSCVX_SETUP_OK && ws,
              "method %d: setup", (int)methods[k]);
        if (ws == NULL) continue;
        tscvx_info info;
        tscvx_iter_log row;
        CHECK(tscvx_solve(ws) == TSCVX_NUMERICAL_ERROR, "method %d: status", (int)methods[k]);
        CHECK(tscvx_get_info(ws, &info) == TSCVX_SETUP_OK && info.iterations == 0 &&
                  isnan(info.pcost) && isnan(info.dcost) && isnan(info.gap_abs) &&
                  isnan(info.gap_rel) && isnan(info.pres) && isnan(info.dres) && isnan(info.mu),
              "method %d: info %d iterations, pcost %g pres %g dres %g", (int)methods[k],
              (int)info.iterations, info.pcost, info.pres, info.dres);
        CHECK(tscvx_get_iter_log(ws, 0, &row) == TSCVX_SETUP_OK && row.iter == 0 &&
                  isnan(row.pcost) && isnan(row.dcost) && isnan(row.gap) && isnan(row.pres) &&
                  isnan(row.dres) && isnan(row.mu) && row.step == 0.0,
              "method %d: log row 0 pcost %g gap %g pres %g dres %g mu %g step %g",
              (int)methods[k], row.pcost, row.gap, row.pres, row.dres, row.mu, row.step);
    }
}

int main(void) {
    test_soc();
    test_qp();
    test_infeasible();
    test_certificate_finite();
    test_certificate_cancellation();
    test_no_false_certificate_when_scaled();
    test_bad_input();
    test_update();
    test_stale_workspace();
    test_update_settings();
    test_tol_infeas_range();
    test_tolerance_ranges();
    test_psd_check();
    test_indefinite_p_every_method();
    test_ill_conditioned_p_every_method();
    test_equilibration_reference();
    test_warm_start();
    test_warm_start_from_its_own_answer();
    test_fuzz_structure();
    test_start_failure_logs_nan();
    test_upsets(TSCVX_KKT_AUTO, 16);
    test_upsets(TSCVX_KKT_STATIC, 16);
    test_upsets(TSCVX_KKT_STATIC, 2);
    test_upsets(TSCVX_KKT_LDL, 2);
    test_upset_during_solve(TSCVX_KKT_AUTO, 16);
    test_upset_during_solve(TSCVX_KKT_STATIC, 2);
    test_upset_during_solve(TSCVX_KKT_LDL, 2);
    test_upset_during_update(TSCVX_KKT_AUTO, 16);
    test_upset_during_update(TSCVX_KKT_STATIC, 2);
    test_upset_during_update(TSCVX_KKT_LDL, 2);
    return ct_report("test_solver");
}
