/*
 * test_guidance.c -- C tests of the guidance layer (run under valgrind by `make ctest-gnc`).
 *
 * Lifecycle and arena sizing, input checking (every bad scenario gets PDG_INVALID_INPUT and a
 * message naming the field, never a crash), settings and arena errors, a full solve of the
 * default scenario (solved; its boundary conditions, path constraints and final mass, the
 * propellant its thrust burns, checked from the scenario; log and masks readable), masks that
 * keep everything reproduce the full solve, a mask that drops constraints is guarded by the
 * full-constraint check, and the log/mask getters refuse bad indices.
 * Cross-checks against the Python reference are in tests/test_cguidance.py.
 */
#define _POSIX_C_SOURCE 200809L /* sigaction, mprotect, sysconf: test_upset_in_conic_solve */
#include <math.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <unistd.h>

#include "gnc_test.h"
#include "pdg_internal.h" /* the workspace's set-up constants (layout checksum) */
#include "socp_internal.h" /* the SOCP workspace inside it (its set-up checksum) */
#include "tscvx_guidance.h"

static pdg_workspace *make_ws(int N, int roll_free, const pdg_settings *st, void **arena,
                              size_t *bytes)
{
    size_t need = 0;
    pdg_workspace *ws = NULL;
    int tries;
    const pdg_setup_status s = arena_size(N, roll_free, st, &need, &tries);
    CHECK(s == PDG_SETUP_OK);
    CHECK(tries <= 3);
    if (s != PDG_SETUP_OK) {
        return NULL;
    }
    *arena = malloc(need);
    *bytes = need;
    /* one byte short must be refused cleanly */
    CHECK(pdg_setup(&ws, *arena, need - 64, vehicle(N, roll_free), st) == PDG_SETUP_ARENA_TOO_SMALL);
    CHECK(ws == NULL);
    CHECK(pdg_setup(&ws, *arena, need, vehicle(N, roll_free), st) == PDG_SETUP_OK);
    CHECK(ws != NULL);
    size_t high_water = 0;
    CHECK(pdg_arena_high_water(ws, &high_water) == PDG_SETUP_OK);
    CHECK(high_water <= need && high_water > need / 2);
    return ws;
}

static void expect_invalid(pdg_workspace *ws, const pdg_scenario *s, const char *field)
{
    pdg_result r;
    char quoted[64];
    r.x = x;
    r.u = u;
    CHECK(pdg_solve(ws, s, NULL, &r) == PDG_INVALID_INPUT);
    CHECK(r.status == PDG_INVALID_INPUT);
    snprintf(quoted, sizeof quoted, "'%s'", field);
    if (!strstr(r.message, quoted)) {
        fprintf(stderr, "expected field %s in message: %s\n", field, r.message);
        failures++;
    }
}

static void test_bad_input(pdg_workspace *ws)
{
    pdg_scenario s;
    pdg_result r;
#define BAD(stmt, field)            \
    do {                            \
        pdg_default_scenario(&s);   \
        stmt;                       \
        expect_invalid(ws, &s, field); \
    } while (0)
    BAD(s.r0[1] = NAN, "r0");
    BAD(s.v0[2] = INFINITY, "v0");
    BAD(s.m0 = NAN, "m0");
    BAD(s.params.T_max = -INFINITY, "T_max");
    BAD(s.m0 = 1e300, "m0");                          /* beyond PDG_MAGNITUDE_MAX */
    BAD(s.v0[0] = -1.0001 * PDG_MAGNITUDE_MAX, "v0");
    BAD(s.params.aero_coeff = 2.0 * PDG_MAGNITUDE_MAX, "aero_coeff");
    BAD(s.q0[0] = 0.9, "q0");                         /* not a unit quaternion */
    BAD(s.m0 = 2.0, "m0");                            /* m0 <= m_dry */
    BAD(s.r0[0] = 0.5, "r0");                         /* below the glideslope cone */
    BAD((s.q0[0] = cos(0.8), s.q0[2] = sin(0.8), s.params.tilt_max_deg = 60.0), "q0");
    BAD(s.w0[1] = 3.0, "w0");                         /* beyond omega_max */
    BAD(s.w0[0] = 0.1, "w0");                         /* roll rate: no roll torque */
    BAD(s.params.T_min = 6.0, "T_min");
    BAD(s.params.gimbal_max_deg = 95.0, "gimbal_max_deg");
    BAD(s.params.glideslope_deg = 90.0, "glideslope_deg");
    BAD(s.params.g_I[1] = 0.1, "g_I");
    BAD(s.params.J_B[2] = 0.0, "J_B");
    BAD(s.params.J_B[1] = 0.1 * PDG_INERTIA_MIN, "J_B");   /* below the floors the solve */
    BAD(s.params.omega_max_deg = 1e-5, "omega_max_deg");  /* divides by */
    BAD(s.params.N = 2, "N");
    BAD(s.params.N = 40, "N");                        /* workspace is for N = 50 */
    BAD(s.params.final_roll_free = 0, "final_roll_free"); /* workspace is roll-free */
    /* the workspace's A_k pattern is r_cp_B = 0's, which this vehicle's dynamics leave */
    BAD(s.params.r_cp_B[2] = 0.01, "r_cp_B");
    BAD(s.params.q_f[0] = 2.0, "q_f");
    /* NULL pointers */
    pdg_default_scenario(&s);
    r.x = x;
    r.u = u;
    CHECK(pdg_solve(ws, NULL, NULL, &r) == PDG_INVALID_INPUT);
    CHECK(pdg_solve(NULL, &s, NULL, &r) == PDG_INVALID_INPUT);
    CHECK(pdg_solve(ws, &s, NULL, NULL) == PDG_INVALID_INPUT);
    r.x = NULL;
    CHECK(pdg_solve(ws, &s, NULL, &r) == PDG_INVALID_INPUT);
    {   /* a non-finite guess */
        pdg_options o;
        static double gx[50 * PDG_NSTATE], gu[50 * PDG_NCTRL];
        memset(&o, 0, sizeof o);
        gx[5] = NAN;
        o.guess_x = gx;
        o.guess_u = gu;
        o.guess_t_f = 5.0;
        r.x = x;
        CHECK(pdg_solve(ws, &s, &o, &r) == PDG_INVALID_INPUT);
        o.guess_x = NULL;
        CHECK(pdg_solve(ws, &s, &o, &r) == PDG_INVALID_INPUT);
    }
    CHECK(pdg_validate_scenario(&s, r.message) == 0);
    s.m0 = -1.0; /* a pdg_status, not a bare 1 (PDG_INFEASIBLE's value) */
    CHECK(pdg_validate_scenario(&s, r.message) == PDG_INVALID_INPUT);
    CHECK(strstr(r.message, "m0") != NULL);
    CHECK(pdg_validate_scenario(&s, NULL) == PDG_INVALID_INPUT);
    s.m0 = 3.0;
#undef BAD
}

static void test_settings_and_sizes(void)
{
    pdg_settings st;
    size_t need = 0;
    pdg_workspace *ws = NULL;
    char buf[64];
    pdg_default_settings(&st);
    CHECK(st.lam == 500.0 && st.iter_max == 20 && st.eta_init == 2.0 && st.rho1 == 0.1);
    CHECK(pdg_workspace_size(vehicle(2, 1), &st, NULL, 0, &need) == PDG_SETUP_BAD_SIZE);
    CHECK(pdg_workspace_size(vehicle(401, 1), &st, NULL, 0, &need) == PDG_SETUP_BAD_SIZE);
    CHECK(pdg_workspace_size(vehicle(50, 1), NULL, NULL, 0, &need) == PDG_SETUP_NULL_ARGUMENT);
    st.lam = NAN;
    CHECK(pdg_workspace_size(vehicle(50, 1), &st, NULL, 0, &need) == PDG_SETUP_BAD_SETTINGS);
    pdg_default_settings(&st);
    st.iter_max = 0;
    CHECK(pdg_workspace_size(vehicle(50, 1), &st, NULL, 0, &need) == PDG_SETUP_BAD_SETTINGS);
    pdg_default_settings(&st);
    st.lam = 2.0 * PDG_LAM_MAX; /* SCvxSettings: lam within (0, LAM_MAX] */
    CHECK(pdg_workspace_size(vehicle(50, 1), &st, NULL, 0, &need) == PDG_SETUP_BAD_SETTINGS);
    st.lam = PDG_LAM_MAX;
    CHECK(pdg_check_settings(&st, NULL) == PDG_SETUP_OK);
    pdg_default_settings(&st);
    st.rho0 = -0.1; /* accepts steps that raise the penalty */
    CHECK(pdg_workspace_size(vehicle(50, 1), &st, NULL, 0, &need) == PDG_SETUP_BAD_SETTINGS);
    pdg_default_settings(&st);
    CHECK(st.tau_r_update == 1); /* Algorithm 2's radius rule unless asked otherwise */
    st.tau_r_update = 2;
    CHECK(pdg_workspace_size(vehicle(50, 1), &st, NULL, 0, &need) == PDG_SETUP_BAD_SETTINGS);
    pdg_default_settings(&st);
    CHECK(st.polish == 0); /* guidance/params.py SCvxSettings.polish */
    st.polish = -1;
    CHECK(pdg_workspace_size(vehicle(50, 1), &st, NULL, 0, &need) == PDG_SETUP_BAD_SETTINGS);
    pdg_default_settings(&st);
    CHECK(st.prox_u == 2e-2); /* guidance/params.py SCvxSettings.prox_u */
    st.prox_u = -1e-3;
    CHECK(pdg_workspace_size(vehicle(50, 1), &st, NULL, 0, &need) == PDG_SETUP_BAD_SETTINGS);
    st.prox_u = NAN;
    CHECK(pdg_workspace_size(vehicle(50, 1), &st, NULL, 0, &need) == PDG_SETUP_BAD_SETTINGS);
    st.prox_u = 0.0; /* the paper's linear objective: valid */
    CHECK(pdg_workspace_size(vehicle(50, 1), &st, NULL, 0, &need) == PDG_SETUP_SCRATCH_TOO_SMALL);
    pdg_default_settings(&st);
    st.eta_init = 20.0; /* outside [eta_lb, eta_ub] = [0.001, 10] (SCvxSettings checks the same) */
    CHECK(pdg_workspace_size(vehicle(50, 1), &st, NULL, 0, &need) == PDG_SETUP_BAD_SETTINGS);
    st.eta_init = 5e-4;
    CHECK(pdg_workspace_size(vehicle(50, 1), &st, NULL, 0, &need) == PDG_SETUP_BAD_SETTINGS);
    pdg_default_settings(&st);
    CHECK(pdg_workspace_size(vehicle(50, 1), &st, NULL, 0, &need) == PDG_SETUP_SCRATCH_TOO_SMALL);
    CHECK(need > 0);
    CHECK(pdg_setup(&ws, buf, sizeof buf, vehicle(50, 1), &st) == PDG_SETUP_ARENA_TOO_SMALL);
    CHECK(pdg_setup(NULL, buf, sizeof buf, vehicle(50, 1), &st) == PDG_SETUP_NULL_ARGUMENT);
    CHECK(pdg_setup(&ws, buf, sizeof buf, NULL, &st) == PDG_SETUP_NULL_ARGUMENT);
    ws = (pdg_workspace *)buf; /* a refused set-up leaves *ws NULL, a NULL arena too */
    CHECK(pdg_setup(&ws, NULL, sizeof buf, vehicle(50, 1), &st) == PDG_SETUP_NULL_ARGUMENT);
    CHECK(ws == NULL);
    CHECK(pdg_workspace_size(NULL, &st, NULL, 0, &need) == PDG_SETUP_NULL_ARGUMENT);
    CHECK(strcmp(pdg_status_name(PDG_INFEASIBLE), "infeasible") == 0);
    CHECK(strcmp(pdg_status_name((pdg_status)99), "unknown") == 0);
    CHECK(strlen(pdg_setup_status_message(PDG_SETUP_ARENA_TOO_SMALL)) > 0);
    {   /* every solve status has its message; one out of range is named as such */
        int k;
        for (k = 0; k < PDG_NSTATUS; ++k) {
            CHECK(strlen(pdg_status_message((pdg_status)k)) > 8);
        }
        CHECK(strcmp(pdg_status_message(PDG_NSTATUS), "unknown status") == 0);
        CHECK(strcmp(pdg_status_message((pdg_status)-1), "unknown status") == 0);
        CHECK(strcmp(pdg_setup_status_message(PDG_SETUP_NSTATUS), "unknown status") == 0);
        for (k = 0; k < PDG_POLISH_NSTATUS; ++k) {
            CHECK(strlen(pdg_polish_message((pdg_polish_status)k)) > 8);
        }
        CHECK(strcmp(pdg_polish_message(PDG_POLISH_NSTATUS), "unknown status") == 0);
    }
    {   /* the check names the setting, its range and the value */
        char msg[PDG_MESSAGE_LEN];
        pdg_default_settings(&st);
        CHECK(pdg_check_settings(&st, msg) == PDG_SETUP_OK);
        CHECK(pdg_check_settings(NULL, msg) == PDG_SETUP_NULL_ARGUMENT);
        st.socp_max_iter = 501;
        CHECK(pdg_check_settings(&st, msg) == PDG_SETUP_BAD_SETTINGS);
        CHECK(strcmp(msg, "settings.socp_max_iter: must lie within 1..500, got 501") == 0);
        pdg_default_settings(&st);
        st.socp_max_iter_total = 0;
        CHECK(pdg_check_settings(&st, msg) == PDG_SETUP_BAD_SETTINGS);
        CHECK(strcmp(msg, "settings.socp_max_iter_total: must lie within 1..500000, got 0") == 0);
        pdg_default_settings(&st);
        st.defect_tol = INFINITY;
        CHECK(pdg_check_settings(&st, msg) == PDG_SETUP_BAD_SETTINGS);
        CHECK(strstr(msg, "settings.defect_tol: must be finite") == msg);
        CHECK(pdg_check_settings(&st, NULL) == PDG_SETUP_BAD_SETTINGS);
        /* alpha >= PDG_ALPHA_MIN: at 1 a rejected step was retried at the same radius until
         * max_subproblems was spent; beta >= 1 (guidance/params.py ALPHA_MIN) */
        pdg_default_settings(&st);
        st.alpha = 1.0;
        CHECK(pdg_check_settings(&st, msg) == PDG_SETUP_BAD_SETTINGS);
        CHECK(strstr(msg, "settings.alpha: must be >= 1.1") == msg);
        st.alpha = PDG_ALPHA_MIN; /* the boundary is valid, and beta = 1 (no growth) */
        st.beta = 1.0;
        CHECK(pdg_check_settings(&st, msg) == PDG_SETUP_OK);
        st.beta = 0.999;
        CHECK(pdg_check_settings(&st, msg) == PDG_SETUP_BAD_SETTINGS);
        CHECK(strstr(msg, "settings.beta: must be >= 1") == msg);
        /* prox_u within [0, PDG_PROX_U_MAX]: a larger weight stops SCvx short of the optimum */
        pdg_default_settings(&st);
        st.prox_u = PDG_PROX_U_MAX;
        CHECK(pdg_check_settings(&st, msg) == PDG_SETUP_OK);
        st.prox_u = 0.05;
        CHECK(pdg_check_settings(&st, msg) == PDG_SETUP_BAD_SETTINGS);
        CHECK(strstr(msg, "settings.prox_u: must lie within [0, 0.03]") == msg);
    }
    {   /* a vehicle the scenario rules refuse is refused at set-up, by name (a NaN r_cp_B set
         * up a workspace that then refused every scenario as "r_cp_B not zero") */
        char msg[PDG_MESSAGE_LEN];
        pdg_params p;
        pdg_default_settings(&st);
        pdg_default_params(&p);
        CHECK(pdg_check_vehicle(&p, msg) == PDG_SETUP_OK);
        CHECK(pdg_check_vehicle(NULL, msg) == PDG_SETUP_NULL_ARGUMENT);
        p.r_cp_B[0] = NAN;
        CHECK(pdg_check_vehicle(&p, msg) == PDG_SETUP_BAD_VEHICLE);
        CHECK(strcmp(msg, "scenario field 'r_cp_B': must be finite") == 0);
        CHECK(pdg_workspace_size(&p, &st, NULL, 0, &need) == PDG_SETUP_BAD_VEHICLE);
        CHECK(pdg_setup(&ws, buf, sizeof buf, &p, &st) == PDG_SETUP_BAD_VEHICLE && ws == NULL);
        /* a final velocity that reaches the landing point (the cone's apex) from outside the
         * glideslope cone: rising out of the ground, or sliding in along it */
        pdg_default_params(&p);
        p.v_f[0] = 0.1;
        CHECK(pdg_check_vehicle(&p, msg) == PDG_SETUP_BAD_VEHICLE);
        CHECK(strstr(msg, "scenario field 'v_f': v_f = (0.1, 0, 0) reaches r_f") == msg);
        p.v_f[0] = 0.0;
        p.v_f[1] = 0.3;
        CHECK(pdg_check_vehicle(&p, msg) == PDG_SETUP_BAD_VEHICLE);
        p.glideslope_deg = 0.0; /* no cone: the surface only */
        CHECK(pdg_check_vehicle(&p, msg) == PDG_SETUP_OK);
        p.v_f[1] = 0.0; /* at rest at touchdown */
        p.glideslope_deg = 20.0;
        CHECK(pdg_check_vehicle(&p, msg) == PDG_SETUP_OK);
        pdg_default_params(&p);
        p.m_dry = -3.0;
        CHECK(pdg_check_vehicle(&p, msg) == PDG_SETUP_BAD_VEHICLE && strstr(msg, "'m_dry'"));
        pdg_default_params(&p);
        p.final_roll_free = 5;
        CHECK(pdg_check_vehicle(&p, NULL) == PDG_SETUP_BAD_VEHICLE);
        pdg_default_params(&p);
        p.g_I[0] = INFINITY;
        CHECK(pdg_workspace_size(&p, &st, NULL, 0, &need) == PDG_SETUP_BAD_VEHICLE);
        CHECK(strlen(pdg_setup_status_message(PDG_SETUP_BAD_VEHICLE)) > 0);
    }
}

/* A workspace whose arena was overwritten (reused for something else) is refused, not
 * trusted; a trust radius that is not positive is refused by the assembly hook. */
static void test_stale_workspace(pdg_workspace *ws, void *arena, size_t bytes)
{
    pdg_scenario s;
    pdg_result r;
    pdg_log_row row;
    char msg[PDG_MESSAGE_LEN];
    double tf = 0.0;
    pdg_default_scenario(&s);
    CHECK(pdg_debug_guess(ws, &s, x, u, &tf, NULL) == 0);
    CHECK(pdg_debug_assemble(ws, &s, x, u, tf, -5.0, NULL, NULL, NULL, NULL, NULL, NULL, NULL,
                             NULL, NULL, NULL) == PDG_INVALID_INPUT);
    CHECK(pdg_debug_assemble(ws, &s, x, u, 0.0, 0.5, NULL, NULL, NULL, NULL, NULL, NULL, NULL,
                             NULL, NULL, NULL) == PDG_INVALID_INPUT);
    CHECK(pdg_debug_assemble(ws, &s, x, u, NAN, 0.5, NULL, NULL, NULL, NULL, NULL, NULL, NULL,
                             NULL, NULL, NULL) == PDG_INVALID_INPUT);
    x[20] = NAN;
    CHECK(pdg_debug_assemble(ws, &s, x, u, tf, 0.5, NULL, NULL, NULL, NULL, NULL, NULL, NULL,
                             NULL, NULL, NULL) == PDG_INVALID_INPUT);
    x[20] = 0.0;
    CHECK(pdg_debug_guess(ws, &s, x, u, &tf, NULL) == 0);
    CHECK(pdg_debug_assemble(ws, &s, x, u, tf, 0.5, NULL, NULL, NULL, NULL, NULL, NULL, NULL,
                             NULL, NULL, NULL) == 0);
    x[6 * PDG_NSTATE + 13] = 0.0; /* m = 0 at a node: the model fails, and says so */
    CHECK(pdg_debug_assemble(ws, &s, x, u, tf, 0.5, NULL, NULL, NULL, NULL, NULL, NULL, NULL,
                             NULL, NULL, msg) == PDG_SOLVER_ERROR &&
          strcmp(msg, "model evaluation failed at the iterate") == 0);
    CHECK(pdg_debug_assemble(ws, &s, x, u, 0.0, 0.5, NULL, NULL, NULL, NULL, NULL, NULL, NULL,
                             NULL, NULL, msg) == PDG_INVALID_INPUT && strstr(msg, "t_f = 0"));
    CHECK(pdg_debug_guess(ws, &s, x, u, &tf, msg) == 0 && msg[0] == '\0');
    /* a bit flipped in a set-up constant (a loop bound, a setting): refused until restored */
    {
        const int n = ws->n, max_sub = ws->st.max_subproblems;
        r.x = x;
        r.u = u;
        ws->n ^= 1 << 20;
        CHECK(pdg_solve(ws, &s, NULL, &r) == PDG_INVALID_INPUT);
        CHECK(strstr(r.message, "workspace not set up") != NULL);
        CHECK(pdg_get_log(ws, 0, &row) == PDG_SETUP_NOT_READY);
        ws->n = n;
        ws->st.max_subproblems ^= 1 << 12;
        CHECK(pdg_solve(ws, &s, NULL, &r) == PDG_INVALID_INPUT);
        ws->st.max_subproblems = max_sub;
        /* the map of the subproblem's entries into A and G: a flip that would send a write
         * out of the arrays (refused by the checksum; assemble's own range check, behind it,
         * refuses the entry if the flip comes during a call) */
        ws->dest[5] ^= 1 << 20;
        CHECK(pdg_solve(ws, &s, NULL, &r) == PDG_INVALID_INPUT);
        CHECK(strstr(r.message, "workspace not set up") != NULL);
        ws->dest[5] ^= 1 << 20;
        CHECK(pdg_solve(ws, &s, NULL, &r) == PDG_SOLVED);
    }
    memset(arena, 0x5A, bytes);
    r.x = x;
    r.u = u;
    CHECK(pdg_solve(ws, &s, NULL, &r) == PDG_INVALID_INPUT);
    CHECK(pdg_get_log(ws, 0, &row) == PDG_SETUP_NOT_READY);
    int rows = -7;
    size_t high_water = 7;
    CHECK(pdg_log_length(ws, &rows) == PDG_SETUP_NOT_READY && rows == -7);
    CHECK(pdg_arena_high_water(ws, &high_water) == PDG_SETUP_NOT_READY && high_water == 7);
    CHECK(pdg_log_length(NULL, &rows) == PDG_SETUP_NULL_ARGUMENT);
    CHECK(pdg_log_length(ws, NULL) == PDG_SETUP_NULL_ARGUMENT);
    CHECK(pdg_arena_high_water(NULL, &high_water) == PDG_SETUP_NULL_ARGUMENT);
    CHECK(pdg_arena_high_water(ws, NULL) == PDG_SETUP_NULL_ARGUMENT);
    int n = -1;
    CHECK(pdg_problem_size(ws, &n, NULL, NULL, NULL, NULL) == PDG_SETUP_NOT_READY && n == -1);
    CHECK(pdg_default_scenario(NULL) == PDG_SETUP_NULL_ARGUMENT);
    CHECK(pdg_default_settings(NULL) == PDG_SETUP_NULL_ARGUMENT);
    CHECK(pdg_theta_of(&s, NULL) == PDG_SETUP_NULL_ARGUMENT);
}

/* ---- independent checks of a returned landing ---------------------------------------------
 * From the scenario and DESIGN.md's model alone, not from earlier runs of this code. */

static double norm3(const double *a) { return sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]); }

/* Boundary rows are equalities of every subproblem (pdg_subproblem.c emit_boundary): the IPM
 * meets them to socp_tol (1 + |b|) in the scaled variable (x - cx) / Sx, |b| a few units in
 * this scaling; 1e-8 scaled, times Sx back in physical units. */
#define BC_TOL_SCALED 1e-8

/* Simpson panels per interval for the propellant integral (its error, burn_rk4_bound with
 * PANELS steps, is (PANELS / rk4_substeps)^4 = 1e6 times below the library's RK4's) */
#define PANELS 64

/* Propellant burnt over one interval of length dt: integral of alpha |u(t)| + beta (DESIGN.md
 * dm/dt = -alpha |T_B| - beta, guidance/model.py dynamics_expr), u(t) the first-order hold
 * from uk to uk1, by composite Simpson on 2 PANELS + 1 points. */
static double burnt(const pdg_params *p, const double *uk, const double *uk1, double dt)
{
    double sum = 0.0, ui[3];
    int j, i;
    for (j = 0; j <= 2 * PANELS; ++j) {
        const double s = (double)j / (2 * PANELS);
        const double w = j == 0 || j == 2 * PANELS ? 1.0 : (j % 2 ? 4.0 : 2.0);
        for (i = 0; i < 3; ++i) {
            ui[i] = (1.0 - s) * uk[i] + s * uk1[i];
        }
        sum += w * norm3(ui);
    }
    return dt * (p->alpha_mdot * sum / (6.0 * PANELS) + p->beta_mdot);
}

/* Bound on the error of the library's propagation of the mass over one interval: m does not
 * enter its own rate, so RK4 is Simpson's rule, error steps H^5 / 2880 max|g''''| with
 * H = dt / steps, steps >= rk4_substeps. Along the hold u = u_k + b t, |u| = sqrt(c^2 + y^2)
 * with y linear in t at rate |b| and c = |u_k x b| / |b| the line's distance from 0, so
 * |g''''| = alpha |b|^4 3 c^2 |4 y^2 - c^2| / |u|^7 <= 12 alpha |b|^4 c^2 / |u|^5; |u| >= u1,
 * linear along the hold, >= the smaller u1 at the ends (> 0 in the gimbal cone). */
static double burn_rk4_bound(const pdg_params *p, const double *uk, const double *uk1,
                             double dt, int steps)
{
    const double d[3] = {uk1[0] - uk[0], uk1[1] - uk[1], uk1[2] - uk[2]};
    const double cr[3] = {uk[1] * d[2] - uk[2] * d[1], uk[2] * d[0] - uk[0] * d[2],
                          uk[0] * d[1] - uk[1] * d[0]}; /* u_k x d = |d| c */
    const double umin = uk[0] < uk1[0] ? uk[0] : uk1[0];
    const double du = norm3(d), cd = norm3(cr), st4 = (double)steps * steps * steps * steps;
    return p->alpha_mdot * dt * du * du * cd * cd / (240.0 * st4 * pow(umin, 5.0));
}

/* The landing (xs, us, t_f) against scenario s: the initial state and the final conditions
 * at nodes 0 and N-1, every path constraint at every node within defect_tol (what
 * PDG_SOLVED promises), and the mass bookkeeping: each interval's drop m_k - m_k+1 equals
 * the propellant burnt under the first-order hold within `dtol` (the largest defect the
 * solve claims) plus the two quadratures' error bounds, and so m(N-1) = m0 - the whole burn
 * within their sum. */
static void check_landing(const pdg_scenario *s, const pdg_settings *st, const double *xs,
                          const double *us, double t_f, double dtol)
{
    const pdg_params *p = &s->params;
    const int N = p->N;
    const double *xl = xs + (size_t)PDG_NSTATE * (N - 1);
    const double deg = 3.14159265358979323846 / 180.0;
    const double Sr = fmax(1.0, norm3(s->r0)), Sv = fmax(1.0, norm3(s->v0));
    const double Sw = p->omega_max_deg * deg, Sm = s->m0 - p->m_dry;
    const double dt = t_f / (N - 1), tol = st->defect_tol;
    const double tg = tan(p->glideslope_deg * deg), cg = cos(p->gimbal_max_deg * deg);
    const double qmax = sqrt((1.0 - cos(p->tilt_max_deg * deg)) / 2.0);
    const double dot = s->q0[0] * p->q_f[0] + s->q0[1] * p->q_f[1] + s->q0[2] * p->q_f[2] +
                       s->q0[3] * p->q_f[3];
    const double sgn = dot >= 0.0 ? 1.0 : -1.0; /* q and -q: one attitude (q_f in q0's half) */
    double m = s->m0, total_tol = 0.0, worst = 0.0, worst_bc = 0.0;
    int k, i, bad = 0;
    CHECK(t_f > 0.0 && isfinite(t_f));
    /* node 0: the scenario's initial state; node N-1: r_f, v_f, omega_f and q2 = q3 = 0
     * (roll free) or q = q_f; each error in the subproblem's scaled units */
    for (i = 0; i < 3; ++i) {
        worst_bc = fmax(worst_bc, fabs(xs[i] - s->r0[i]) / Sr);
        worst_bc = fmax(worst_bc, fabs(xs[3 + i] - s->v0[i]) / Sv);
        worst_bc = fmax(worst_bc, fabs(xs[10 + i] - s->w0[i]) / Sw);
        worst_bc = fmax(worst_bc, fabs(xl[i] - p->r_f[i]) / Sr);
        worst_bc = fmax(worst_bc, fabs(xl[3 + i] - p->v_f[i]) / Sv);
        worst_bc = fmax(worst_bc, fabs(xl[10 + i] - p->omega_f[i]) / Sw);
    }
    for (i = 0; i < 4; ++i) {
        worst_bc = fmax(worst_bc, fabs(xs[6 + i] - s->q0[i]));
        if (i >= 2 || !p->final_roll_free) {
            worst_bc = fmax(worst_bc, fabs(xl[6 + i] - sgn * p->q_f[i]));
        }
    }
    worst_bc = fmax(worst_bc, fabs(xs[13] - s->m0) / Sm);
    CHECK(worst_bc <= BC_TOL_SCALED);
    /* path constraints at every node, in their own units (README "Conventions") */
    for (k = 0; k < N; ++k) {
        const double *xk = xs + (size_t)PDG_NSTATE * k, *uk = us + (size_t)PDG_NCTRL * k;
        const double T = norm3(uk);
        bad += xk[13] < p->m_dry - tol;
        bad += tg * sqrt(xk[1] * xk[1] + xk[2] * xk[2]) - xk[0] > tol;
        bad += sqrt(xk[8] * xk[8] + xk[9] * xk[9]) - qmax > tol;
        bad += norm3(xk + 10) - Sw > tol;
        bad += T - p->T_max > tol || p->T_min - T > tol;
        bad += cg * T - uk[0] > tol;
    }
    CHECK(bad == 0);
    /* mass bookkeeping, interval by interval, then over the whole landing */
    bad = 0;
    for (k = 0; k < N - 1; ++k) {
        const double *uk = us + (size_t)PDG_NCTRL * k;
        const double burn = burnt(p, uk, uk + PDG_NCTRL, dt);
        const double bound = dtol + burn_rk4_bound(p, uk, uk + PDG_NCTRL, dt, st->rk4_substeps) +
                             burn_rk4_bound(p, uk, uk + PDG_NCTRL, dt, PANELS);
        const double misfit = fabs(xs[(size_t)PDG_NSTATE * (k + 1) + 13] -
                                   (xs[(size_t)PDG_NSTATE * k + 13] - burn));
        bad += !(misfit <= bound);
        worst = misfit > worst ? misfit : worst;
        m -= burn;
        total_tol += bound;
    }
    CHECK(bad == 0);
    CHECK(fabs(xl[13] - m) <= total_tol);
    printf("  landing: boundary error %.1e (scaled), m_f %.9f = m0 - burn %.9f %+.1e (allowed "
           "%.1e), worst interval %.1e\n", worst_bc, xl[13], m, xl[13] - m, total_tol, worst);
}

/* Mask callback that fails with an error code at its second call (iteration 2). */
static int fail_second(void *ctx, int k, unsigned char *mask, int n)
{
    (void)ctx;
    (void)mask;
    (void)n;
    return k >= 2 ? -1 : 0;
}

/* Mask callback: keep everything except every constraint c = 1 (glideslope). */
static int drop_glideslope(void *ctx, int k, unsigned char *mask, int n)
{
    int i;
    (void)k;
    ++*(int *)ctx;
    for (i = 0; i < n; ++i) {
        mask[i] = (unsigned char)(i % PDG_NCON != 1);
    }
    return 1;
}

/* Mask callback calling back into the workspace whose solve calls it: another solve and a
 * debug guess, each refused (they would overwrite the running solve's buffers); then the
 * full problem. ctx: the workspace, its refusals counted in `reentry_refused`. */
static int reentry_refused;
static double inner_x[PDG_NSTATE * 50], inner_u[PDG_NCTRL * 50];
static int call_back_in(void *ctx, int k, unsigned char *mask, int n)
{
    pdg_workspace *ws = (pdg_workspace *)ctx;
    pdg_scenario s;
    pdg_result r;
    double t_f;
    (void)k, (void)mask, (void)n;
    pdg_default_scenario(&s);
    r.x = inner_x;
    r.u = inner_u;
    if (pdg_solve(ws, &s, NULL, &r) == PDG_INVALID_INPUT && strstr(r.message, "busy")) {
        ++reentry_refused;
    }
    if (pdg_debug_guess(ws, &s, inner_x, inner_u, &t_f, NULL) == PDG_INVALID_INPUT) {
        ++reentry_refused;
    }
    return 0;
}

/* Mask callback standing for an upset during a solve: at iteration 2 it flips a high bit of
 * an entry of the map of the subproblem's entries into A and G (ctx: the workspace). */
static int upset_map(void *ctx, int k, unsigned char *mask, int n)
{
    pdg_workspace *ws = (pdg_workspace *)ctx;
    (void)mask, (void)n;
    if (k == 2) {
        ws->dest[5] ^= 1 << 20;
    }
    return 0;
}

/* Mask callback standing for an upset inside the SOCP workspace during a solve: at
 * iteration 2 it flips a high bit of an entry of its equality pattern (ctx: the workspace;
 * the bit flipped back by the test). */
static tscvx_int *socp_upset_at;

static int upset_socp(void *ctx, int k, unsigned char *mask, int n)
{
    pdg_workspace *ws = (pdg_workspace *)ctx;
    (void)mask, (void)n;
    if (k == 2) {
        socp_upset_at = &ws->socp->A.i[7];
        *socp_upset_at ^= 1 << 20;
    }
    return 0;
}

/* A bit of *at flipped after the last subproblem's solve (subproblems: the call's count
 * without the upset): the call says the workspace was damaged during it, with `text` in its
 * message, instead of "solved"; the next call is refused by the start checks (next_status);
 * with the bit back, the same landing to the last bit (m_f). */
static void upset_after_last_solve(pdg_workspace *ws, const pdg_scenario *s, int *at,
                                   int subproblems, const char *text, pdg_status next_status,
                                   double m_f)
{
    pdg_options o;
    pdg_result r;
    pdg_status got;
    memset(&o, 0, sizeof o);
    o.clock_s = upset_clock;
    r.x = x;
    r.u = u;
    x[0] = -7.0;
    clock_reads = 0;
    clock_upset_read = 2 * subproblems;
    clock_upset_at = at;
    got = pdg_solve(ws, s, &o, &r);
    clock_upset_at = NULL;
    CHECK(clock_reads == 2 * subproblems); /* the flip came after the last conic solve */
    CHECK(got == PDG_SOLVER_ERROR && r.status == PDG_SOLVER_ERROR);
    CHECK(isnan(r.t_f) && x[0] == -7.0); /* no trajectory through damaged set-up data */
    CHECK(strstr(r.message, text) != NULL);
    printf("upset after the last subproblem's solve: %s (%s)\n", pdg_status_name(got),
           r.message);
    CHECK(pdg_solve(ws, s, NULL, &r) == next_status);
    *at ^= 1 << 20;
    CHECK(pdg_solve(ws, s, NULL, &r) == PDG_SOLVED);
    CHECK(x[PDG_NSTATE * 49 + 13] == m_f);
}

static void test_solve(pdg_workspace *ws, int with_masks)
{
    pdg_scenario s;
    pdg_settings st;
    pdg_result r;
    pdg_log_row row;
    unsigned char m[PDG_NCON * 50];
    double mf;
    int fewest;
    pdg_default_scenario(&s);
    pdg_default_settings(&st); /* the workspace's (main sets it up with these) */
    r.x = x;
    r.u = u;
    CHECK(pdg_solve(ws, &s, NULL, &r) == PDG_SOLVED);
    mf = x[PDG_NSTATE * 49 + 13];
    printf("default: %s, %d iterations, %d subproblems, m_f = %.9f, defect %.1e, viol %.1e\n",
           pdg_status_name(r.status), r.iterations, r.subproblems_solved, mf, r.max_defect,
           r.max_violation);
    /* the landing meets the scenario, and its final mass is what its thrust burns; that it
     * is the fuel-optimal one is the Python reference's check against Clarabel, live
     * (tests/test_cguidance.py), not repeated here */
    check_landing(&s, &st, x, u, r.t_f, st.defect_tol);
    CHECK(r.iterations >= 9 && r.iterations <= 15);
    CHECK(r.max_defect <= 1e-5 && r.max_violation <= 1e-5);
    CHECK(r.polish == PDG_POLISH_OFF && r.polish_iterations == 0); /* off by default */
    CHECK(r.defect_before_polish == r.max_defect && r.m_f_before_polish == mf);
    CHECK(log_rows(ws) == r.subproblems_solved);
    CHECK(logged_iterations(ws, &fewest) == r.socp_iterations && fewest > 0);
    CHECK(pdg_get_log(ws, log_rows(ws), &row) == PDG_SETUP_BAD_INDEX);
    CHECK(pdg_get_log(ws, -1, &row) == PDG_SETUP_BAD_INDEX);
    CHECK(pdg_get_mask(ws, r.iterations - 1, m) == PDG_SETUP_OK);
    CHECK(pdg_get_mask(ws, r.iterations, m) == PDG_SETUP_BAD_INDEX);
    {   /* the record's counters (written by every solve, outside the checksum) damaged: reads
         * stay within the capacities set-up fixed (they used to read past the 60-row log) */
        const int n_log = ws->n_log, n_masks = ws->n_masks_out;
        ws->n_log = 600;
        ws->n_masks_out = 600;
        CHECK(log_rows(ws) == ws->st.max_subproblems);
        CHECK(pdg_get_log(ws, ws->st.max_subproblems, &row) == PDG_SETUP_BAD_INDEX);
        CHECK(pdg_get_log(ws, 599, &row) == PDG_SETUP_BAD_INDEX);
        CHECK(pdg_get_mask(ws, ws->st.iter_max, m) == PDG_SETUP_BAD_INDEX);
        ws->n_log = -5;
        CHECK(log_rows(ws) == 0);
        ws->n_log = n_log, ws->n_masks_out = n_masks;
    }
    {   /* a solve called from inside its own mask callback is refused, and the outer solve
         * ends as a plain one (it used to run the inner solve over the outer's buffers) */
        pdg_options o;
        memset(&o, 0, sizeof o);
        o.mask_fn = call_back_in;
        o.mask_ctx = ws;
        reentry_refused = 0;
        CHECK(pdg_solve(ws, &s, &o, &r) == PDG_SOLVED);
        CHECK(reentry_refused == 2 * r.subproblems_solved);
        CHECK(fabs(x[PDG_NSTATE * 49 + 13] - mf) < 1e-3);
        /* both a table and a callback: refused (the callback was ignored) */
        o.masks = m;
        o.n_masks = 1;
        CHECK(pdg_solve(ws, &s, &o, &r) == PDG_INVALID_INPUT);
        CHECK(strstr(r.message, "not both") != NULL);
        CHECK(pdg_solve(ws, &s, NULL, &r) == PDG_SOLVED); /* not left busy */
        /* the map upset within the solve: its next subproblem refused (never written outside
         * A and G, which valgrind and ASan check here), the solve ends with the reason */
        memset(&o, 0, sizeof o);
        o.mask_fn = upset_map;
        o.mask_ctx = ws;
        x[0] = -7.0;
        CHECK(pdg_solve(ws, &s, &o, &r) == PDG_SOLVER_ERROR); /* the call ran: no answer */
        CHECK(isnan(r.t_f) && x[0] == -7.0);
        CHECK(strstr(r.message, "iteration 2: the workspace was damaged") != NULL);
        printf("map upset at iteration 2: %d subproblems solved\n", r.subproblems_solved);
        CHECK(pdg_solve(ws, &s, NULL, &r) == PDG_INVALID_INPUT); /* and then by the checksum */
        ws->dest[5] ^= 1 << 20;
        CHECK(pdg_solve(ws, &s, NULL, &r) == PDG_SOLVED);
        /* the SOCP workspace's equality pattern upset within the solve: the next subproblem's
         * data update and solve refuse it by its checksum (nothing followed: valgrind and
         * ASan), the solve ends with the SOCP runtime's reason, and so does the next one
         * until the bit is back */
        o.mask_fn = upset_socp;
        socp_upset_at = NULL;
        CHECK(pdg_solve(ws, &s, &o, &r) == PDG_SOLVER_ERROR);
        CHECK(strstr(r.message, "iteration 2: conic solver returned invalid_input: workspace "
                                "damaged") != NULL);
        printf("SOCP upset at iteration 2: %s\n", r.message);
        CHECK(pdg_solve(ws, &s, NULL, &r) == PDG_SOLVER_ERROR);
        CHECK(strstr(r.message, "iteration 1: conic solver returned invalid_input: workspace "
                                "damaged") != NULL);
        CHECK(socp_upset_at != NULL);
        if (socp_upset_at) {
            *socp_upset_at ^= 1 << 20;
        }
        CHECK(pdg_solve(ws, &s, NULL, &r) == PDG_SOLVED);
        CHECK(x[PDG_NSTATE * 49 + 13] == mf); /* the same landing, to the last bit */
        /* upsets after the last subproblem's solve, when the checks of the subproblems are
         * behind: the solve's end check says so (before it, the solve returned "solved"). The
         * clock alone changes nothing: the same subproblems, reads and landing */
        memset(&o, 0, sizeof o);
        o.clock_s = upset_clock;
        clock_reads = clock_upset_read = 0;
        CHECK(pdg_solve(ws, &s, &o, &r) == PDG_SOLVED);
        CHECK(clock_reads == 2 * r.subproblems_solved && x[PDG_NSTATE * 49 + 13] == mf);
        upset_after_last_solve(ws, &s, &ws->dest[5], r.subproblems_solved,
                               "workspace damaged during the call (the end check: set-up "
                               "checksum mismatch in the guidance workspace's",
                               PDG_INVALID_INPUT, mf);
        upset_after_last_solve(ws, &s, &ws->socp->A.i[7], r.subproblems_solved,
                               "workspace damaged during the call (the end check, SOCP "
                               "workspace: workspace damaged: set-up checksum mismatch in its "
                               "index arrays",
                               PDG_SOLVER_ERROR, mf);
    }
    /* boundary conditions hold exactly enough */
    CHECK(fabs(x[0] - 4.0) < 1e-7 && fabs(x[PDG_NSTATE * 49 + 3] + 0.1) < 1e-7);
    if (!with_masks) {
        return;
    }
    {   /* a mask table that keeps everything: T-SCvx's tau_r trust-region rule (tau_r = 0:
         * no shrink below rho1, full growth), so a slightly different path to a landing */
        static unsigned char all[PDG_NCON * 50];
        pdg_options o;
        memset(&o, 0, sizeof o);
        memset(all, 1, sizeof all);
        o.masks = all;
        o.n_masks = 1;
        CHECK(pdg_solve(ws, &s, &o, &r) == PDG_SOLVED);
        printf("all-ones mask: m_f = %.9f (full %.9f)\n", x[PDG_NSTATE * 49 + 13], mf);
        CHECK(fabs(x[PDG_NSTATE * 49 + 13] - mf) < 1e-3);
        CHECK(r.max_violation <= 1e-5);
    }
    {   /* dropping the glideslope: the answer must still meet the full constraint set */
        pdg_options o;
        int calls = 0;
        memset(&o, 0, sizeof o);
        o.mask_fn = drop_glideslope;
        o.mask_ctx = &calls;
        pdg_solve(ws, &s, &o, &r);
        printf("glideslope masked out: %s, m_f = %.9f, viol %.1e, %d mask calls\n",
               pdg_status_name(r.status), x[PDG_NSTATE * 49 + 13], r.max_violation, calls);
        CHECK(calls == r.subproblems_solved);
        if (r.status == PDG_SOLVED) {
            CHECK(r.max_violation <= 1e-5);
        }
    }
    {   /* a callback answering an error code: refused, not taken as a mask (the buffer holds
         * whatever it held), the solve stopped there, the record that of its subproblems */
        pdg_options o;
        memset(&o, 0, sizeof o);
        o.mask_fn = fail_second;
        CHECK(pdg_solve(ws, &s, &o, &r) == PDG_INVALID_INPUT);
        CHECK(strstr(r.message, "masks: the mask callback answered -1 for iteration 2") != NULL);
        CHECK(r.iterations == 1 && log_rows(ws) == r.subproblems_solved);
    }
}

/* The default landing at N = 12 on a workspace whose call budget is 80 IPM iterations (30 a
 * subproblem): it ends PDG_MAX_ITERATIONS. NULL (the arena freed) if set-up failed. */
static pdg_workspace *budget_ws(pdg_settings *st, pdg_scenario *s, void **arena, size_t *bytes)
{
    pdg_workspace *ws;
    pdg_default_settings(st);
    st->socp_max_iter_total = 80;
    st->socp_max_iter = 30;
    pdg_default_scenario(s);
    s->params.N = 12;
    ws = make_ws(12, 1, st, arena, bytes);
    if (!ws) {
        free(*arena);
    }
    return ws;
}

/* The call's IPM iteration budget (socp_max_iter_total): the call ends at it with
 * PDG_MAX_ITERATIONS and the last accepted iterate, having spent no more than it; the next
 * call on the workspace has the whole budget again (the runtime's limit, lowered where the
 * budget bound, is set back). */
static void test_iteration_budget(void)
{
    static double x1[PDG_NSTATE * 12], u1[PDG_NCTRL * 12];
    pdg_settings st;
    pdg_scenario s;
    pdg_result r;
    void *arena = NULL;
    size_t bytes = 0;
    pdg_workspace *ws;
    int first_total;
    ws = budget_ws(&st, &s, &arena, &bytes);
    if (!ws) {
        return;
    }
    r.x = x1;
    r.u = u1;
    CHECK(pdg_solve(ws, &s, NULL, &r) == PDG_MAX_ITERATIONS);
    printf("budget 80: %d IPM iterations, %d subproblems, %d iterations (%s)\n",
           r.socp_iterations, r.subproblems_solved, r.iterations, r.message);
    CHECK(strstr(r.message, "IPM iteration budget spent (") == r.message);
    CHECK(r.socp_iterations <= 80 && r.socp_iterations >= 60 && r.iterations >= 1);
    CHECK(logged_iterations(ws, NULL) == r.socp_iterations);
    CHECK(r.t_f > 0.0 && fabs(x1[0] - 4.0) < 1e-7); /* an iterate, not the caller's arrays */
    first_total = r.socp_iterations;
    memcpy(x, x1, sizeof x1);
    CHECK(pdg_solve(ws, &s, NULL, &r) == PDG_MAX_ITERATIONS);
    CHECK(r.socp_iterations == first_total && memcmp(x, x1, sizeof x1) == 0);
    free(arena);
}

/* What a mask callback of test_callbacks does into its own solve, from iteration `at` on. */
typedef struct {
    pdg_workspace *ws;
    const pdg_scenario *s;
    pdg_result *running; /* the result the solve was given */
    void *arena;
    size_t bytes;
    const pdg_settings *st;
    int mode; /* 0: pdg_solve with the running result; 1: pdg_setup over the arena */
    int at, refused;
} misuse_ctx;

static int misuse(void *ctx, int k, unsigned char *mask, int n)
{
    misuse_ctx *c = (misuse_ctx *)ctx;
    pdg_workspace *again = NULL;
    (void)mask, (void)n;
    if (k < c->at) {
        return 0;
    }
    if (c->mode == 0) {
        c->refused += pdg_solve(c->ws, c->s, NULL, c->running) == PDG_INVALID_INPUT;
    } else if (k == c->at) {
        CHECK(pdg_setup(&again, c->arena, c->bytes, &c->s->params, c->st) == PDG_SETUP_OK);
        CHECK(again == c->ws);
    }
    return 0;
}

/* Clock standing for an integrator's misuse: at read clock_misuse_read it sets the
 * workspace of clock_misuse up again over its arena (reads counted in clock_reads). */
static misuse_ctx *clock_misuse;
static int clock_misuse_read;

static double misuse_clock(void)
{
    pdg_workspace *again = NULL;
    if (++clock_reads == clock_misuse_read) {
        CHECK(pdg_setup(&again, clock_misuse->arena, clock_misuse->bytes,
                        &clock_misuse->s->params, clock_misuse->st) == PDG_SETUP_OK);
        CHECK(again == clock_misuse->ws);
    }
    return 0.0;
}

/* Review of 27 Nov (an integrator's misuse of the callbacks and the result), on N = 12:
 * - a solve called from its own mask callback with the running solve's result is refused and
 *   leaves that result as it is: it used to zero its IPM iteration count, which is the
 *   call's budget, so a call bounded at 80 IPM iterations ran 120 and more;
 * - a mask callback's error answer returns no trajectory (t_f NaN, x untouched): it used to
 *   return the last iterate, the unsolved guess at iteration 1, under PDG_INVALID_INPUT;
 * - pdg_setup from a mask callback over the running workspace's arena stops the solve with
 *   that reason (it used to run on, ending "conic solver returned invalid_input" with t_f 0);
 *   so does pdg_setup from the clock, before a subproblem's conic solve or after it (it used
 *   to run on over the new set-up: 28 Nov);
 * - a solve refused for a NULL result leaves no record of the solve before it (it used to
 *   leave its log and masks), and pdg_problem_size takes a NULL workspace as the getters. */
static void test_callbacks(void)
{
    static double x1[PDG_NSTATE * 12], u1[PDG_NCTRL * 12];
    pdg_settings st;
    pdg_scenario s;
    pdg_result r;
    pdg_options o;
    misuse_ctx c;
    void *arena = NULL;
    size_t bytes = 0;
    pdg_workspace *ws;
    int i, rows = -1, sum = 0, n = -1;
    ws = budget_ws(&st, &s, &arena, &bytes);
    if (!ws) {
        return;
    }
    memset(&o, 0, sizeof o);
    memset(&c, 0, sizeof c);
    c.ws = ws, c.s = &s, c.running = &r, c.arena = arena, c.bytes = bytes, c.st = &st;
    c.at = 1;
    o.mask_fn = misuse;
    o.mask_ctx = &c;
    r.x = x1;
    r.u = u1;
    CHECK(pdg_solve(ws, &s, &o, &r) == PDG_MAX_ITERATIONS);
    sum = logged_iterations(ws, NULL);
    printf("callback re-entering with the running result: %d refused, %d IPM iterations "
           "(budget 80), logged %d\n", c.refused, r.socp_iterations, sum);
    CHECK(c.refused == r.subproblems_solved && c.refused > 0);
    CHECK(sum == r.socp_iterations && sum <= 80);
    CHECK(strstr(r.message, "IPM iteration budget spent (") == r.message);

    for (i = 0; i < PDG_NSTATE * 12; ++i) {
        x1[i] = -7.0;
    }
    o.mask_fn = fail_second;
    CHECK(pdg_solve(ws, &s, &o, &r) == PDG_INVALID_INPUT);
    CHECK(isnan(r.t_f) && x1[0] == -7.0 && x1[PDG_NSTATE * 12 - 1] == -7.0);
    CHECK(r.subproblems_solved >= 1 && log_rows(ws) == r.subproblems_solved);

    c.mode = 1;
    c.at = 2;
    o.mask_fn = misuse;
    CHECK(pdg_solve(ws, &s, &o, &r) == PDG_INVALID_INPUT);
    printf("pdg_setup from the mask callback: %s\n", r.message);
    CHECK(strstr(r.message, "set the workspace up again or wrote over its arena") != NULL);
    CHECK(isnan(r.t_f) && x1[0] == -7.0);
    CHECK(pdg_solve(ws, &s, NULL, &r) == PDG_MAX_ITERATIONS); /* set up, and idle */

    /* reads 3 and 4: around the second subproblem's conic solve */
    memset(&o, 0, sizeof o);
    o.clock_s = misuse_clock;
    clock_misuse = &c;
    for (clock_misuse_read = 3; clock_misuse_read <= 4; ++clock_misuse_read) {
        for (i = 0; i < PDG_NSTATE * 12; ++i) {
            x1[i] = -7.0;
        }
        clock_reads = 0;
        CHECK(pdg_solve(ws, &s, &o, &r) == PDG_INVALID_INPUT);
        printf("pdg_setup from the clock (read %d): %s\n", clock_misuse_read, r.message);
        CHECK(clock_reads == clock_misuse_read); /* nothing ran after it */
        CHECK(strstr(r.message, "the clock callback of iteration ") == r.message &&
              strstr(r.message, "set the workspace up again or wrote over its arena") != NULL);
        CHECK(isnan(r.t_f) && x1[0] == -7.0 && r.subproblems_solved == 0);
        CHECK(pdg_solve(ws, &s, NULL, &r) == PDG_MAX_ITERATIONS); /* set up, and idle */
    }

    CHECK(pdg_log_length(ws, &rows) == PDG_SETUP_OK && rows > 0);
    CHECK(pdg_solve(ws, &s, NULL, NULL) == PDG_INVALID_INPUT);
    CHECK(pdg_log_length(ws, &rows) == PDG_SETUP_OK && rows == 0);
    CHECK(pdg_problem_size(NULL, &n, NULL, NULL, NULL, NULL) == PDG_SETUP_NULL_ARGUMENT &&
          n == -1);
    free(arena);
}

/* Every single bit flip in what the set-up checksum covers (pdg_layout_sum and pdg_map_sum,
 * word-wise since 28 Nov: a change within one 8-byte word is found for certain, as a change
 * within one byte was by the bytewise FNV-1a) makes the workspace not set up; flipped back,
 * it is again. On N = 12: the struct's covered fields, and the first and last 16 entries of
 * the map dest. A flip in the map's pointer or length is refused without being followed (the
 * sum used to read the map by them: out of bounds, under ASan and valgrind). */
static int flips_refused(pdg_workspace *ws, unsigned char *at, size_t bytes)
{
    size_t i;
    int b, refused = 0;
    for (i = 0; i < bytes; ++i) {
        for (b = 0; b < 8; ++b) {
            at[i] ^= (unsigned char)(1u << b);
            refused += !pdg_ws_ready(ws);
            at[i] ^= (unsigned char)(1u << b);
        }
    }
    return refused;
}

static void test_every_bit_flip_refused(void)
{
    pdg_settings st;
    pdg_scenario s;
    void *arena = NULL;
    size_t bytes = 0, total = 0;
    unsigned char *w;
    pdg_workspace *ws = budget_ws(&st, &s, &arena, &bytes);
    int refused = 0;
    if (!ws) {
        return;
    }
    w = (unsigned char *)ws;
    {
        const struct {
            size_t from, to;
        } span[] = {{offsetof(pdg_workspace, N), offsetof(pdg_workspace, scn)},
                    {offsetof(pdg_workspace, z), offsetof(pdg_workspace, disc)},
                    {offsetof(pdg_workspace, aug), offsetof(pdg_workspace, n_log)},
                    {offsetof(pdg_workspace, masks_out),
                     offsetof(pdg_workspace, masks_out) + sizeof(unsigned char *)},
                    {offsetof(pdg_workspace, arena_bytes),
                     offsetof(pdg_workspace, arena_bytes) + sizeof(size_t)}};
        size_t i;
        for (i = 0; i < sizeof span / sizeof span[0]; ++i) {
            refused += flips_refused(ws, w + span[i].from, span[i].to - span[i].from);
            total += 8 * (span[i].to - span[i].from);
        }
    }
    refused += flips_refused(ws, (unsigned char *)ws->dest, 16 * sizeof(int));
    refused += flips_refused(ws, (unsigned char *)(ws->dest + ws->nnz - 16), 16 * sizeof(int));
    total += 2 * 8 * 16 * sizeof(int);
    printf("set-up checksum: %d of %zu single bit flips refused\n", refused, total);
    CHECK((size_t)refused == total);
    CHECK(pdg_ws_ready(ws));
    free(arena);
}

/* ---- an upset inside a subproblem's conic solve ---------------------------------------------
 * The SOCP runtime's end check (tscvx_solve) finds a bit flipped during the solve; the
 * iterations the solve ran count in the call's record and budget all the same (28 Nov: its
 * log row said 0). The library has no hook inside a solve, and none is added for the test:
 * as in test_solver.c's test_upset_during_solve, the moment is the solve's own write of a
 * row of its iteration log. The workspace is set up with the row (iteration 1) at a page
 * boundary; the clock read just before the second subproblem's conic solve makes the page
 * read-only; the solve's write of the row traps into a handler that flips the lowest bit of
 * a row index of A's pattern (within range: the solve follows it without leaving its arrays,
 * for valgrind and ASan), lets the page be written and returns, and the solve goes on. */
static unsigned char *trap_page;
static size_t trap_len;
static tscvx_int *trap_at;
static volatile sig_atomic_t trap_hits;
static int trap_read; /* the clock read that arms the trap */

static void on_trap(int sig, siginfo_t *si, void *uc)
{
    const unsigned char *at = (const unsigned char *)si->si_addr;
    (void)uc;
    if (!trap_page || at < trap_page || at >= trap_page + trap_len) {
        signal(sig, SIG_DFL); /* not ours: the fault happens again, unhandled */
        return;
    }
    *trap_at ^= 1;
    mprotect(trap_page, trap_len, PROT_READ | PROT_WRITE);
    trap_page = NULL;
    trap_hits++;
}

static double trapping_clock(void)
{
    if (++clock_reads == trap_read && trap_page) {
        CHECK(mprotect(trap_page, trap_len, PROT_READ) == 0);
    }
    return 0.0;
}

static void test_upset_in_conic_solve(void)
{
    static double x1[PDG_NSTATE * 12], u1[PDG_NCTRL * 12];
    const long page = sysconf(_SC_PAGESIZE);
    pdg_settings st;
    pdg_scenario s;
    pdg_result r;
    pdg_options o;
    pdg_log_row row;
    tscvx_info info;
    struct sigaction on, old;
    unsigned char *buf, *base;
    size_t need = 0, shift;
    pdg_workspace *ws = NULL;
    int tries, i, k = -1;
    CHECK(page > 0 && page <= 65536);
    pdg_default_settings(&st);
    pdg_default_scenario(&s);
    s.params.N = 12;
    CHECK(arena_size(12, 1, &st, &need, &tries) == PDG_SETUP_OK);
    buf = (unsigned char *)malloc(need + 2 * (size_t)page);
    if (!buf || page <= 0 || page > 65536) {
        free(buf);
        return;
    }
    base = buf + ((size_t)page - (uintptr_t)buf % (size_t)page) % (size_t)page;
    CHECK(pdg_setup(&ws, base, need, &s.params, &st) == PDG_SETUP_OK);
    if (!ws) {
        free(buf);
        return;
    }
    /* the log rows are 16-aligned, as the arena's claims: a shift by a multiple of 16 moves
     * the layout as a whole */
    shift = ((size_t)page - (uintptr_t)&ws->socp->log[1] % (size_t)page) % (size_t)page;
    CHECK(shift % 16 == 0);
    CHECK(pdg_setup(&ws, base + shift, need, &s.params, &st) == PDG_SETUP_OK);
    if (!ws) {
        free(buf);
        return;
    }
    CHECK((uintptr_t)&ws->socp->log[1] % (size_t)page == 0);
    CHECK((size_t)(ws->socp->log_cap - 1) * sizeof(tscvx_iter_log) >= (size_t)page);
    for (i = 0; i < ws->socp->A.nnz && k < 0; ++i) { /* an even row index below the last */
        k = ws->socp->A.i[i] % 2 == 0 && ws->socp->A.i[i] + 1 < ws->socp->p ? i : -1;
    }
    CHECK(k >= 0);
    trap_at = &ws->socp->A.i[k >= 0 ? k : 0];
    memset(&on, 0, sizeof on);
    on.sa_sigaction = on_trap;
    on.sa_flags = SA_SIGINFO;
    sigemptyset(&on.sa_mask);
    memset(&o, 0, sizeof o);
    o.clock_s = trapping_clock;
    r.x = x1;
    r.u = u1;
    clock_reads = 0;
    trap_read = 3; /* before the second subproblem's conic solve */
    trap_hits = 0;
    trap_len = (size_t)page;
    trap_page = (unsigned char *)&ws->socp->log[1];
    CHECK(sigaction(SIGSEGV, &on, &old) == 0);
    CHECK(pdg_solve(ws, &s, &o, &r) == PDG_SOLVER_ERROR);
    mprotect((unsigned char *)&ws->socp->log[1], (size_t)page, PROT_READ | PROT_WRITE);
    trap_page = NULL;
    sigaction(SIGSEGV, &old, NULL);
    printf("upset in the second subproblem's conic solve: %s\n", r.message);
    CHECK(trap_hits == 1 && clock_reads == 4);
    CHECK(strstr(r.message, "conic solver returned invalid_input: workspace damaged during a "
                            "solve") != NULL);
    /* the solve's own count, from the SOCP runtime (its struct intact), in the row */
    CHECK(tscvx_get_info(ws->socp, &info) == TSCVX_SETUP_OK && info.iterations >= 1);
    CHECK(log_rows(ws) == 2 && pdg_get_log(ws, 1, &row) == PDG_SETUP_OK);
    CHECK(row.solver_iterations == info.iterations + info.restart_iterations);
    CHECK(logged_iterations(ws, NULL) == r.socp_iterations);
    printf("  its log row: %d IPM iterations (the runtime ran %d); the call %d\n",
           row.solver_iterations, (int)info.iterations, r.socp_iterations);
    *trap_at ^= 1;
    CHECK(pdg_solve(ws, &s, NULL, &r) == PDG_SOLVED);
    free(buf);
}

/* The polish (pdg_settings.polish): the default landing's defects removed, the final mass
 * moved by what they had bought, its IPM iterations counted in the call's; with the budget
 * spent at convergence it is not run, and with prox_u = 0 it is off. */
/* pdg_solve of s started from the guess (gx, gu, t_f), the answer into x, u */
static pdg_status solve_from_guess(pdg_workspace *ws, const pdg_scenario *s, const double *gx,
                                   const double *gu, double t_f, pdg_result *r)
{
    pdg_options o;
    memset(&o, 0, sizeof o);
    o.guess_x = gx;
    o.guess_u = gu;
    o.guess_t_f = t_f;
    r->x = x;
    r->u = u;
    return pdg_solve(ws, s, &o, r);
}

/* Re-planning from the polished plan (x, u, t_f of the last solve): lambda times any step's
 * second-order defects outweighs its gain, so every step is rejected down to eta_lb, where
 * the plan, meeting every tolerance, is returned solved (it used to end
 * PDG_MAX_ITERATIONS). */
static void test_replan_from_polished(double t_f)
{
    static double plan_x[50 * PDG_NSTATE], plan_u[50 * PDG_NCTRL];
    pdg_settings st;
    pdg_scenario s;
    pdg_result r;
    pdg_log_row row;
    void *arena = NULL;
    size_t bytes = 0;
    pdg_workspace *ws;
    int i;
    memcpy(plan_x, x, sizeof plan_x);
    memcpy(plan_u, u, sizeof plan_u);
    pdg_default_settings(&st);
    ws = make_ws(50, 1, &st, &arena, &bytes);
    if (!ws) {
        return;
    }
    pdg_default_scenario(&s);
    CHECK(solve_from_guess(ws, &s, plan_x, plan_u, t_f, &r) == PDG_SOLVED);
    printf("re-planned from the polished plan: %d subproblems, %s\n", r.subproblems_solved,
           r.message);
    CHECK(strncmp(r.message, "converged; the step at the smallest trust radius", 48) == 0);
    CHECK(r.iterations == 0 && log_rows(ws) == r.subproblems_solved);
    for (i = 0; i < log_rows(ws); ++i) {
        CHECK(pdg_get_log(ws, i, &row) == PDG_SETUP_OK && !row.accepted);
    }
    CHECK(row.eta == st.eta_lb);
    CHECK(memcmp(x, plan_x, sizeof plan_x) == 0 && memcmp(u, plan_u, sizeof plan_u) == 0);
    CHECK(r.t_f == t_f);
    free(arena);
}

static void test_polish(void)
{
    pdg_settings st;
    pdg_scenario s;
    pdg_result r;
    void *arena = NULL;
    size_t bytes = 0;
    pdg_workspace *ws;
    int i, plain_total;
    double plain_mf;
    pdg_default_settings(&st);
    st.polish = 1;
    ws = make_ws(50, 1, &st, &arena, &bytes);
    if (!ws) {
        return;
    }
    pdg_default_scenario(&s);
    r.x = x;
    r.u = u;
    CHECK(pdg_solve(ws, &s, NULL, &r) == PDG_SOLVED);
    printf("polished: largest defect %.1e -> %.1e, m_f %.9f -> %.9f, %d IPM iterations\n",
           r.defect_before_polish, r.max_defect, r.m_f_before_polish,
           x[PDG_NSTATE * 49 + 13], r.polish_iterations);
    CHECK(r.polish == PDG_POLISH_KEPT && r.polish_iterations > 0);
    CHECK(r.max_defect <= 1e-8 && r.max_violation <= 1e-8);
    CHECK(r.defect_before_polish > 1e3 * r.max_defect && r.defect_before_polish <= 1e-5);
    /* the polished landing meets the scenario and burns what its mass says, to its own
     * defects (<= 1e-8, above) and the RK4 error; the final mass the defects had bought is
     * given back: 7.1e-5 (docs/scvx.md), the band of tests/test_polish.py */
    check_landing(&s, &st, x, u, r.t_f, 1e-8);
    CHECK(r.m_f_before_polish - x[PDG_NSTATE * 49 + 13] > 1e-5);
    CHECK(r.m_f_before_polish - x[PDG_NSTATE * 49 + 13] < 1e-3);
    CHECK(logged_iterations(ws, NULL) + r.polish_iterations == r.socp_iterations);
    free(arena);
    test_replan_from_polished(r.t_f);
    /* the budget spent to the last iteration at convergence: no polish. Cold IPM starts, so
     * that each subproblem may use all that is left and a budget of the call's iterations
     * changes none of them (warm-started ones get half of it) */
    st.socp_warm_start = 0;
    for (i = 0; i < 3; ++i) { /* unlimited, the call's total, one more */
        st.socp_max_iter_total = i == 0 ? 24000 : plain_total + (i - 1);
        ws = make_ws(50, 1, &st, &arena, &bytes);
        if (ws) {
            CHECK(pdg_solve(ws, &s, NULL, &r) == PDG_SOLVED);
            if (i == 0) {
                CHECK(r.polish == PDG_POLISH_KEPT);
                plain_total = r.socp_iterations - r.polish_iterations;
                plain_mf = r.m_f_before_polish;
            } else { /* 0 or 1 iteration left: not run, or stopped at its first */
                CHECK(r.polish == PDG_POLISH_NO_BUDGET && r.polish_iterations == i - 1);
                CHECK(r.socp_iterations == st.socp_max_iter_total);
                CHECK(x[PDG_NSTATE * 49 + 13] == plain_mf);
                CHECK(r.max_defect == r.defect_before_polish);
            }
        }
        free(arena);
    }
    st.socp_warm_start = 1;
    /* the paper's linear objective has no P to carry the polish's */
    st.socp_max_iter_total = 24000;
    st.prox_u = 0.0;
    ws = make_ws(50, 1, &st, &arena, &bytes);
    if (ws) {
        pdg_solve(ws, &s, NULL, &r);
        CHECK(r.polish == PDG_POLISH_OFF && r.polish_iterations == 0);
    }
    free(arena);
}

/* In-flight re-planning: the default landing's plan from node 15 on, with the plan's state
 * there as the new start (its roll rate zero: the vehicle makes no roll torque), re-plans in
 * fewer subproblems than the plan took; bad input is refused with a message. */
static void test_plan_remainder(pdg_workspace *ws)
{
    static double plan_x[50 * PDG_NSTATE], plan_u[50 * PDG_NCTRL];
    static double gx[50 * PDG_NSTATE], gu[50 * PDG_NCTRL];
    const double *x15 = plan_x + 15 * PDG_NSTATE;
    pdg_scenario s, here;
    pdg_result r;
    char msg[PDG_MESSAGE_LEN];
    double t_f, t1, gt_f;
    int plan_subproblems;
    pdg_default_scenario(&s);
    r.x = plan_x;
    r.u = plan_u;
    CHECK(pdg_solve(ws, &s, NULL, &r) == PDG_SOLVED);
    t_f = r.t_f;
    t1 = t_f * 15.0 / 49.0;
    plan_subproblems = r.subproblems_solved;
    CHECK(pdg_scenario_at_state(&s, x15, &here, msg) == 0);
    CHECK(pdg_plan_remainder(&here, plan_x, plan_u, t_f, t1, gx, gu, &gt_f, msg) == 0);
    CHECK(gt_f == t_f - t1 && gx[0] == here.r0[0] && gx[13] == here.m0);
    CHECK(solve_from_guess(ws, &here, gx, gu, gt_f, &r) == PDG_SOLVED);
    printf("re-planned from t = %.3f: %d subproblems (the plan %d), m_f %.6f (the plan %.6f)\n",
           t1, r.subproblems_solved, plan_subproblems, x[49 * PDG_NSTATE + 13],
           plan_x[49 * PDG_NSTATE + 13]);
    CHECK(r.subproblems_solved < plan_subproblems);
    CHECK(fabs(x[49 * PDG_NSTATE + 13] - plan_x[49 * PDG_NSTATE + 13]) < 1e-3);
    /* refusals */
    CHECK(pdg_plan_remainder(NULL, plan_x, plan_u, t_f, t1, gx, gu, &gt_f, msg) ==
          PDG_INVALID_INPUT);
    CHECK(strstr(msg, "NULL") != NULL);
    CHECK(pdg_plan_remainder(&here, plan_x, plan_u, t_f, t_f, gx, gu, &gt_f, msg) ==
          PDG_INVALID_INPUT);
    CHECK(strstr(msg, "is not within the plan's") != NULL);
    CHECK(pdg_plan_remainder(&here, plan_x, plan_u, t_f, NAN, gx, gu, &gt_f, NULL) ==
          PDG_INVALID_INPUT);
    CHECK(pdg_plan_remainder(&here, plan_x, plan_u, t_f, -1.0, gx, gu, &gt_f, msg) ==
          PDG_INVALID_INPUT);
    plan_u[7] = INFINITY;
    CHECK(pdg_plan_remainder(&here, plan_x, plan_u, t_f, t1, gx, gu, &gt_f, msg) ==
          PDG_INVALID_INPUT);
    CHECK(strstr(msg, "must be finite") != NULL);
    plan_u[7] = 2.0 * PDG_PLAN_VALUE_MAX;
    CHECK(pdg_plan_remainder(&here, plan_x, plan_u, t_f, t1, gx, gu, &gt_f, msg) ==
          PDG_INVALID_INPUT);
    CHECK(strstr(msg, "values beyond") != NULL);
    plan_u[7] = 0.0;
    CHECK(pdg_plan_remainder(&here, plan_x, plan_u, 2.0 * PDG_PLAN_T_F_MAX, t1, gx, gu, &gt_f,
                             msg) == PDG_INVALID_INPUT);
    CHECK(strstr(msg, "t_f = 20000 is outside") != NULL);
    here.q0[0] *= 2.0;
    CHECK(pdg_plan_remainder(&here, plan_x, plan_u, t_f, t1, gx, gu, &gt_f, msg) ==
          PDG_INVALID_INPUT);
    CHECK(strstr(msg, "q0") != NULL);
}

/* pdg_scenario_at_state: a measured state becomes the landing from it (q renormalized, a
 * roll rate within PDG_ROLL_NOISE zeroed, the vehicle and targets kept); everything else is
 * refused with the field in the message. */
static void test_scenario_at_state(void)
{
    pdg_scenario base, out;
    double x[PDG_NSTATE] = {1.0, 2.0, 0.5, -0.1, -0.2, -1.0, 2.0, 0.0, 0.2, 0.0,
                            0.5e-9, 0.01, -0.02, 2.7};
    char msg[PDG_MESSAGE_LEN];
    const double nq = sqrt(4.0 + 0.04);
    int i;
    pdg_default_scenario(&base);
    base.params.T_max = 4.5; /* a vehicle field the result must keep */
    CHECK(pdg_scenario_at_state(&base, x, &out, msg) == 0);
    for (i = 0; i < 3; ++i) {
        CHECK(out.r0[i] == x[i] && out.v0[i] == x[3 + i]);
    }
    CHECK(fabs(out.q0[0] - 2.0 / nq) < 1e-15 && fabs(out.q0[2] - 0.2 / nq) < 1e-15);
    CHECK(out.q0[1] == 0.0 && out.q0[3] == 0.0);
    CHECK(out.w0[0] == 0.0 && out.w0[1] == 0.01 && out.w0[2] == -0.02 && out.m0 == 2.7);
    CHECK(memcmp(&out.params, &base.params, sizeof base.params) == 0);
    CHECK(pdg_scenario_at_state(NULL, x, &out, msg) == PDG_INVALID_INPUT);
    CHECK(strstr(msg, "NULL") != NULL);
    CHECK(pdg_scenario_at_state(&base, x, NULL, NULL) == PDG_INVALID_INPUT);
    x[10] = 2.0 * PDG_ROLL_NOISE;
    CHECK(pdg_scenario_at_state(&base, x, &out, msg) == PDG_INVALID_INPUT);
    CHECK(strstr(msg, "'w0'") != NULL && strstr(msg, "roll rate") != NULL);
    x[10] = 0.0;
    x[4] = NAN;
    CHECK(pdg_scenario_at_state(&base, x, &out, msg) == PDG_INVALID_INPUT);
    CHECK(strstr(msg, "NaN") != NULL);
    x[4] = -0.2;
    x[6] = x[8] = 0.0;
    CHECK(pdg_scenario_at_state(&base, x, &out, msg) == PDG_INVALID_INPUT);
    CHECK(strstr(msg, "'q0'") != NULL);
    x[6] = 1.0;
    x[13] = 1.5; /* below the dry mass */
    CHECK(pdg_scenario_at_state(&base, x, &out, msg) == PDG_INVALID_INPUT);
    CHECK(strstr(msg, "'m0'") != NULL);
}

/* ---- an answer does not depend on the workspace's history ---------------------------------
 * One call on a workspace that has been through other calls (another settings' set-up in the
 * same arena, a T-SCvx solve with masks, refused input, a callback stopping a solve, the model
 * failing at a guess and at a subproblem's answer, an upset found and repaired, a debug
 * assembly) gives, to the bit, the answer of the same call on a workspace freshly set up in an arena of
 * other bytes: status, message, every field of the result, x, u, the log and the masks. */
typedef struct {
    pdg_status status;
    pdg_result r;
    double x[12 * PDG_NSTATE], u[12 * PDG_NCTRL];
    int rows;
    pdg_log_row log[60];
    unsigned char masks[20 * PDG_NCON * 12];
} history_answer;

static int stop_at_two(void *ctx, int k, unsigned char *mask, int n)
{
    (void)ctx;
    (void)mask;
    (void)n;
    return k == 2 ? 7 : 0;
}

static void history_call(pdg_workspace *ws, const pdg_scenario *s, const unsigned char *masks,
                         history_answer *a)
{
    pdg_options o;
    int i;
    memset(a, 0, sizeof *a);
    memset(&o, 0, sizeof o);
    o.masks = masks;
    o.n_masks = masks ? 1 : 0;
    a->r.x = a->x;
    a->r.u = a->u;
    a->status = pdg_solve(ws, s, &o, &a->r);
    a->r.x = NULL; /* compared by value below */
    a->r.u = NULL;
    a->rows = log_rows(ws);
    CHECK(a->rows >= 0 && a->rows <= 60 && a->r.iterations <= 20);
    for (i = 0; i < a->rows && i < 60; ++i) {
        CHECK(pdg_get_log(ws, i, &a->log[i]) == PDG_SETUP_OK);
    }
    for (i = 0; i < a->r.iterations && i < 20; ++i) {
        CHECK(pdg_get_mask(ws, i, a->masks + (size_t)i * PDG_NCON * 12) == PDG_SETUP_OK);
    }
}

static void test_answers_independent_of_history(void)
{
    enum { NH = 12 };
    static unsigned char drop[PDG_NCON * NH];
    static history_answer fresh, used;
    pdg_settings st, other;
    pdg_scenario s, b, bad, far;
    pdg_options o;
    pdg_result r;
    pdg_workspace *ws = NULL, *ws_fresh = NULL;
    void *arena = NULL, *arena2 = NULL;
    size_t bytes = 0, need_other = 0;
    int tries, i, round;
    static double gx[NH * PDG_NSTATE], gu[NH * PDG_NCTRL], c[4000], Ax[20000], bb[4000],
        Gx[20000], h[4000];
    double gt_f;
    pdg_default_settings(&st);
    other = st;
    other.polish = 1;
    other.socp_warm_start = 0;
    other.lam = 300.0;
    if (arena_size(NH, 1, &st, &bytes, &tries) != PDG_SETUP_OK ||
        arena_size(NH, 1, &other, &need_other, &tries) != PDG_SETUP_OK) {
        CHECK(0);
        return;
    }
    bytes = need_other > bytes ? need_other : bytes;
    arena = malloc(bytes);
    arena2 = malloc(bytes);
    if (!arena || !arena2) {
        CHECK(0);
        free(arena);
        free(arena2);
        return;
    }
    pdg_default_scenario(&s);
    s.params.N = NH;
    b = s;
    b.r0[1] = 1.0;
    b.r0[2] = 2.5;
    b.v0[1] = 0.5;
    b.params.glideslope_deg = 35.0;
    for (i = 0; i < PDG_NCON * NH; ++i) {
        drop[i] = i % PDG_NCON != 1; /* the glideslope dropped everywhere */
    }
    r.x = x;
    r.u = u;
    memset(arena, 0xA5, bytes);
    /* the history: another settings' workspace in the arena first, then ours over it */
    CHECK(pdg_setup(&ws, arena, bytes, vehicle(NH, 1), &other) == PDG_SETUP_OK);
    CHECK(pdg_solve(ws, &b, NULL, &r) == PDG_SOLVED);
    CHECK(pdg_setup(&ws, arena, bytes, vehicle(NH, 1), &st) == PDG_SETUP_OK);
    memset(&o, 0, sizeof o);
    o.masks = drop;
    o.n_masks = 1;
    CHECK(pdg_solve(ws, &b, &o, &r) != PDG_INVALID_INPUT);
    bad = s;
    bad.m0 = NAN;
    CHECK(pdg_solve(ws, &bad, NULL, &r) == PDG_INVALID_INPUT);
    memset(&o, 0, sizeof o);
    o.mask_fn = stop_at_two;
    CHECK(pdg_solve(ws, &b, &o, &r) == PDG_INVALID_INPUT && log_rows(ws) > 0);
    CHECK(pdg_debug_guess(ws, &b, gx, gu, &gt_f, NULL) == 0);
    gx[6 * PDG_NSTATE + 13] = 0.0; /* m = 0 at a node: the model fails at the guess */
    memset(&o, 0, sizeof o);
    o.guess_x = gx;
    o.guess_u = gu;
    o.guess_t_f = gt_f;
    CHECK(pdg_solve(ws, &b, &o, &r) == PDG_SOLVER_ERROR);
    ws->lay.n ^= 1 << 3; /* an upset, refused, then repaired */
    CHECK(pdg_solve(ws, &s, NULL, &r) == PDG_INVALID_INPUT);
    ws->lay.n ^= 1 << 3;
    CHECK(pdg_debug_guess(ws, &b, gx, gu, &gt_f, NULL) == 0);
    CHECK(pdg_debug_assemble(ws, &b, gx, gu, gt_f, 0.3, c, Ax, bb, Gx, h, NULL, NULL, NULL,
                             NULL, NULL) == 0);
    far = s;
    far.r0[0] = 1e3; /* out of reach: the model fails at the first subproblem's answer */
    CHECK(pdg_solve(ws, &far, NULL, &r) == PDG_SOLVER_ERROR && r.subproblems_solved > 0);
    for (round = 0; round < 2; ++round) { /* plain SCvx, then with a mask table */
        const unsigned char *masks = round ? drop : NULL;
        history_call(ws, &s, masks, &used);
        memset(arena2, 0, bytes); /* the history's arena was 0xA5 bytes */
        CHECK(pdg_setup(&ws_fresh, arena2, bytes, vehicle(NH, 1), &st) == PDG_SETUP_OK);
        history_call(ws_fresh, &s, masks, &fresh);
        CHECK(used.status == PDG_SOLVED && fresh.status == PDG_SOLVED);
        CHECK(strcmp(used.r.message, fresh.r.message) == 0);
        CHECK(memcmp(&used.r.t_f, &fresh.r.t_f, sizeof(double)) == 0);
        CHECK(used.r.iterations == fresh.r.iterations);
        CHECK(used.r.subproblems_solved == fresh.r.subproblems_solved);
        CHECK(used.r.socp_iterations == fresh.r.socp_iterations);
        CHECK(memcmp(&used.r.max_defect, &fresh.r.max_defect, sizeof(double)) == 0);
        CHECK(memcmp(&used.r.max_violation, &fresh.r.max_violation, sizeof(double)) == 0);
        CHECK(used.r.polish == fresh.r.polish);
        CHECK(memcmp(used.x, fresh.x, sizeof used.x) == 0);
        CHECK(memcmp(used.u, fresh.u, sizeof used.u) == 0);
        CHECK(used.rows == fresh.rows);
        CHECK(memcmp(used.log, fresh.log, sizeof used.log) == 0);
        CHECK(memcmp(used.masks, fresh.masks, sizeof used.masks) == 0);
        printf("history vs fresh (%s): %s in %d subproblems, %d IPM iterations\n",
               round ? "masks" : "SCvx", pdg_status_name(used.status), used.r.subproblems_solved,
               used.r.socp_iterations);
    }
    free(arena);
    free(arena2);
}

int main(void)
{
    pdg_settings st;
    void *arena = NULL;
    size_t bytes = 0;
    pdg_workspace *ws;
    const int full = getenv("PDG_TEST_QUICK") == NULL;
    test_settings_and_sizes();
    test_iteration_budget();
    test_callbacks();
    test_upset_in_conic_solve();
    test_every_bit_flip_refused();
    test_polish();
    test_scenario_at_state();
    test_answers_independent_of_history();
    memset(&st, 0, sizeof st); /* padding zero, as the workspace's copy */
    pdg_default_settings(&st);
    ws = make_ws(50, 1, &st, &arena, &bytes);
    if (ws) {
        /* every field copied (copy_settings goes member by member) */
        CHECK(memcmp(&ws->st, &st, sizeof st) == 0);
        test_bad_input(ws);
        test_solve(ws, full);
        test_plan_remainder(ws);
        test_stale_workspace(ws, arena, bytes);
    }
    free(arena);
    {   /* a pinned final attitude and another N set up and run without errors */
        pdg_scenario s;
        pdg_result r;
        pdg_default_scenario(&s);
        s.params.N = 12;
        s.params.final_roll_free = 0;
        st.iter_max = 3;
        ws = make_ws(12, 0, &st, &arena, &bytes);
        r.x = x;
        r.u = u;
        if (ws) {
            const pdg_status status = pdg_solve(ws, &s, NULL, &r);
            const double *qf = x + 11 * PDG_NSTATE + 6;
            double err = 0.0;
            int i;
            CHECK(status == PDG_SOLVED || status == PDG_MAX_ITERATIONS ||
                  status == PDG_INFEASIBLE);
            CHECK(r.iterations <= 3);
            /* q(t_f) = q_f is a hard constraint whatever the status: an equality row of every
             * subproblem (no virtual control on it, pdg_subproblem.c emit_boundary) and set in
             * the guess (pdg_guess.c pin_boundary); the answer is one of those. q is unscaled
             * (Sx = 1), so it holds to the IPM's socp_tol (1 + |b|). q0 . q_f > 0 here. */
            for (i = 0; i < 4; ++i) {
                err = fmax(err, fabs(qf[i] - s.params.q_f[i]));
            }
            CHECK(s.q0[0] * s.params.q_f[0] > 0.0 && err <= BC_TOL_SCALED);
            printf("N = 12 pinned attitude, 3 iterations: %s (%s), |q(t_f) - q_f| %.1e\n",
                   pdg_status_name(status), r.message, err);
        }
        free(arena);
    }
    return gnc_report("test_guidance");
}
