/* Defaults (paper Table 1, guidance/params.py) and scenario validation (the rules, order and
 * field names of guidance/scenario.py). */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "pdg_internal.h"

#define DEG (3.14159265358979323846 / 180.0)
#define UNIT_QUATERNION_TOL 1e-6

pdg_setup_status pdg_default_params(pdg_params *p)
{
    const double I_sp = 30.0, P_amb = 0.1, A_noz = 0.5, rho_SA_CA = 0.2;
    if (!p) {
        return PDG_SETUP_NULL_ARGUMENT;
    }
    memset(p, 0, sizeof *p);
    p->g_I[0] = -1.0;
    p->J_B[0] = 0.001;
    p->J_B[1] = 0.01;
    p->J_B[2] = 0.01;
    p->r_T_B[0] = -0.01;
    p->alpha_mdot = 1.0 / I_sp;
    p->beta_mdot = P_amb * A_noz / I_sp;
    p->aero_coeff = 0.5 * rho_SA_CA;
    p->m_dry = 2.0;
    p->T_min = 0.3;
    p->T_max = 5.0;
    p->gimbal_max_deg = 20.0;
    p->tilt_max_deg = 90.0;
    p->glideslope_deg = 20.0;
    p->omega_max_deg = 90.0;
    p->v_f[0] = -0.1;
    p->q_f[0] = 1.0;
    p->final_roll_free = 1;
    p->N = 50;
    return PDG_SETUP_OK;
}

pdg_setup_status pdg_default_scenario(pdg_scenario *s)
{
    if (!s) {
        return PDG_SETUP_NULL_ARGUMENT;
    }
    memset(s, 0, sizeof *s);
    s->r0[0] = 4.0;
    s->r0[1] = 4.0;
    s->v0[1] = -1.0;
    s->v0[2] = -2.0;
    s->q0[0] = 1.0;
    s->m0 = 3.0;
    return pdg_default_params(&s->params);
}

pdg_setup_status pdg_default_settings(pdg_settings *st)
{
    if (!st) {
        return PDG_SETUP_NULL_ARGUMENT;
    }
    st->lam = 500.0;
    st->rho0 = 0.0;
    st->rho1 = 0.1;
    st->rho2 = 0.7;
    st->alpha = 2.0;
    st->beta = 2.0;
    st->eta_init = 2.0;
    st->eta_lb = 0.001;
    st->eta_ub = 10.0;
    st->iter_max = 20;
    st->max_subproblems = 60;
    st->step_tol = 5e-3;
    st->cost_tol = 1e-5;
    st->vc_tol = 1e-6;
    st->defect_tol = 1e-5;
    st->rk4_substeps = 2;
    st->tight_tol = 1e-6;
    st->socp_tol = 1e-9;
    st->socp_max_iter = 200;
    st->socp_max_iter_total = 24000;
    st->socp_warm_start = 1;
    st->tau_r_update = 1;
    st->prox_u = 2e-2;
    st->polish = 0;
    return PDG_SETUP_OK;
}

/* ---- derived quantities (guidance/params.py properties) ---------------------------------- */

double pdg_tan_glideslope(const pdg_params *p) { return tan(p->glideslope_deg * DEG); }
double pdg_cos_gimbal(const pdg_params *p) { return cos(p->gimbal_max_deg * DEG); }
double pdg_omega_max(const pdg_params *p) { return p->omega_max_deg * DEG; }
double pdg_tilt_q_max(const pdg_params *p)
{
    return sqrt((1.0 - cos(p->tilt_max_deg * DEG)) / 2.0);
}

/* ---- portable arithmetic ----------------------------------------------------------------- */

/* sqrt(big^2 + small^2) for big >= small >= 0 in range, corrected to the correctly rounded
 * value in nearly all cases: the rounding error of the first sqrt, computed without FMA from
 * the exact-enough residuals, taken off (C. F. Borges, "An improved algorithm for hypot(a,b)",
 * ACM TOMS 47(1), 2021, the corrected algorithm). */
static double hypot_corrected(double big, double small)
{
    const double h = sqrt(big * big + small * small);
    double p, q;
    if (h <= 2.0 * small) {
        const double e = h - small;
        p = big * (2.0 * e - big);
        q = (e - 2.0 * (big - small)) * e;
    } else {
        const double e = h - big;
        p = 2.0 * e * (big - 2.0 * small);
        q = (4.0 * e - small) * small + e * e;
    }
    return h - (p + q) / (2.0 * h);
}

/* hypot(a, b) from IEEE operations only (+ - * / sqrt, each correctly rounded): the same bits
 * on every host. libm's hypot is not: Debian's 32-bit PowerPC glibc has its own, whose last
 * bit differs from x86-64 glibc's for 6 % of random arguments and for about a third of the
 * default landing's calls, so the trust-region steps and the penalty, and with them the
 * landing (one more IPM iteration, m_f 4e-12 apart), differed between the ground and the
 * RAD750's kind of CPU. These are the bits of x86-64 glibc 2.36's hypot (20 million arguments
 * compared), with the same scaling by powers of two near overflow and underflow. */
double pdg_hypot(double a, double b)
{
    double big, small;
    if (isinf(a) || isinf(b)) {
        return INFINITY;
    }
    if (isnan(a) || isnan(b)) {
        return a + b;
    }
    a = fabs(a);
    b = fabs(b);
    big = a < b ? b : a;
    small = a < b ? a : b;
    if (big > 0x1p511) {
        if (small <= big * 0x1p-54) {
            return big + small;
        }
        return hypot_corrected(big * 0x1p-600, small * 0x1p-600) * 0x1p600;
    }
    if (small < 0x1p-511) {
        if (big >= small * 0x1p54) {
            return big + small;
        }
        return hypot_corrected(big * 0x1p600, small * 0x1p600) * 0x1p-600;
    }
    if (small <= big * 0x1p-54) {
        return big + small;
    }
    return hypot_corrected(big, small);
}

/* The parameter vector of the generated model (guidance/model.py param_vector). */
void pdg_param_vector(const pdg_params *p, double *pv)
{
    int i;
    pv[0] = p->g_I[0];
    for (i = 0; i < 3; ++i) {
        pv[1 + i] = p->J_B[i];
        pv[4 + i] = p->r_T_B[i];
        pv[7 + i] = p->r_cp_B[i];
    }
    pv[10] = p->alpha_mdot;
    pv[11] = p->beta_mdot;
    pv[12] = p->aero_coeff;
}

void pdg_initial_state(const pdg_scenario *s, double *x0)
{
    int i;
    for (i = 0; i < 3; ++i) {
        x0[i] = s->r0[i];
        x0[3 + i] = s->v0[i];
        x0[10 + i] = s->w0[i];
    }
    for (i = 0; i < 4; ++i) {
        x0[6 + i] = s->q0[i];
    }
    x0[13] = s->m0;
}

/* q_f in q0's hemisphere: q and -q are the same attitude, and from q0 . q_f < 0 the pinned
 * q(t_f) = q_f as written would ask for 360 degrees more of turn (Scenario.x_final_target). */
void pdg_x_final_target(const pdg_scenario *s, double *xf)
{
    const pdg_params *p = &s->params;
    const double dot = s->q0[0] * p->q_f[0] + s->q0[1] * p->q_f[1] + s->q0[2] * p->q_f[2] +
                       s->q0[3] * p->q_f[3];
    const double sign = dot >= 0.0 ? 1.0 : -1.0;
    int i;
    for (i = 0; i < NX; ++i) {
        xf[i] = 0.0;
    }
    for (i = 0; i < 3; ++i) {
        xf[i] = p->r_f[i];
        xf[3 + i] = p->v_f[i];
        xf[10 + i] = p->omega_f[i];
    }
    for (i = 0; i < 4; ++i) {
        xf[6 + i] = sign * p->q_f[i];
    }
}

/* C_B<-I(q), homogeneous form (guidance/model.py _dcm_entries). */
void pdg_dcm_bi(const double *q, double C[3][3])
{
    const double q0 = q[0], q1 = q[1], q2 = q[2], q3 = q[3];
    const double s0 = q0 * q0, s1 = q1 * q1, s2 = q2 * q2, s3 = q3 * q3;
    C[0][0] = s0 + s1 - s2 - s3;
    C[0][1] = 2 * (q1 * q2 + q0 * q3);
    C[0][2] = 2 * (q1 * q3 - q0 * q2);
    C[1][0] = 2 * (q1 * q2 - q0 * q3);
    C[1][1] = s0 - s1 + s2 - s3;
    C[1][2] = 2 * (q2 * q3 + q0 * q1);
    C[2][0] = 2 * (q1 * q3 + q0 * q2);
    C[2][1] = 2 * (q2 * q3 - q0 * q1);
    C[2][2] = s0 - s1 - s2 + s3;
}

/* ---- validation -------------------------------------------------------------------------- */

static int fail(char *msg, const char *field, const char *text)
{
    if (msg) {
        snprintf(msg, PDG_MESSAGE_LEN, "scenario field '%s': %s", field, text);
    }
    return 1;
}

int pdg_all_finite(const double *v, size_t n)
{
    size_t i;
    for (i = 0; i < n; ++i) {
        if (!isfinite(v[i])) {
            return 0;
        }
    }
    return 1;
}

static double norm(const double *v, int n)
{
    double s = 0.0;
    int i;
    for (i = 0; i < n; ++i) {
        s += v[i] * v[i];
    }
    return sqrt(s);
}

static double largest_magnitude(const double *v, int n)
{
    double largest = 0.0;
    int i;
    for (i = 0; i < n; ++i) {
        largest = fabs(v[i]) > largest ? fabs(v[i]) : largest;
    }
    return largest;
}

/* Every real number finite (the JSON parser's check in Python), then within
 * PDG_MAGNITUDE_MAX, field by field in the order of guidance/scenario.py's dataclasses. */
static int check_numbers(const pdg_scenario *s, char *msg)
{
    char text[200];
    const pdg_params *p = &s->params;
    struct {
        const char *name;
        const double *v;
        int n;
    } f[] = {
        {"r0", s->r0, 3}, {"v0", s->v0, 3}, {"q0", s->q0, 4}, {"w0", s->w0, 3},
        {"m0", &s->m0, 1}, {"g_I", p->g_I, 3}, {"J_B", p->J_B, 3}, {"r_T_B", p->r_T_B, 3},
        {"r_cp_B", p->r_cp_B, 3}, {"alpha_mdot", &p->alpha_mdot, 1},
        {"beta_mdot", &p->beta_mdot, 1}, {"aero_coeff", &p->aero_coeff, 1},
        {"m_dry", &p->m_dry, 1}, {"T_min", &p->T_min, 1}, {"T_max", &p->T_max, 1},
        {"gimbal_max_deg", &p->gimbal_max_deg, 1}, {"tilt_max_deg", &p->tilt_max_deg, 1},
        {"glideslope_deg", &p->glideslope_deg, 1}, {"omega_max_deg", &p->omega_max_deg, 1},
        {"r_f", p->r_f, 3}, {"v_f", p->v_f, 3}, {"q_f", p->q_f, 4}, {"omega_f", p->omega_f, 3},
    };
    size_t i;
    for (i = 0; i < sizeof f / sizeof f[0]; ++i) {
        if (!pdg_all_finite(f[i].v, (size_t)f[i].n)) {
            return fail(msg, f[i].name, "must be finite");
        }
    }
    for (i = 0; i < sizeof f / sizeof f[0]; ++i) {
        const double largest = largest_magnitude(f[i].v, f[i].n);
        if (largest > PDG_MAGNITUDE_MAX) {
            snprintf(text, sizeof text,
                     "magnitude %g is beyond the library's envelope (|value| <= %g in "
                     "nondimensional units)", largest, PDG_MAGNITUDE_MAX);
            return fail(msg, f[i].name, text);
        }
    }
    return 0;
}

static double tilt_deg(double tilt_q)
{
    double c = 1.0 - 2.0 * tilt_q * tilt_q; /* cos(tilt) for |(q2, q3)| = tilt_q */
    c = c < -1.0 ? -1.0 : (c > 1.0 ? 1.0 : c);
    return acos(c) / DEG;
}

/* Whether the vehicle reaches r_f (in the glideslope cone, |(r2, r3)| = horizontal) with
 * velocity v_f only from outside the cone: r_f on its boundary (to 1e-12) and the cone's
 * g(r) = sin(gs) |(r2, r3)| - cos(gs) r1 growing backwards along -v_f, so the path constraint
 * is broken between the last nodes (guidance/scenario.py _arrives_from_outside_the_cone: the
 * same computation in the same order). */
static int arrives_from_outside_the_cone(const pdg_params *p, double horizontal, double gs)
{
    const double sin_gs = sin(gs), cos_gs = cos(gs);
    double away;
    if (sin_gs * horizontal - cos_gs * p->r_f[0] < -1e-12) {
        return 0; /* inside the cone: any final velocity keeps the path near r_f in it */
    }
    if (horizontal > 0.0) { /* d|r_h| along -v_h: -(r_h . v_h) / |r_h| */
        away = -(p->r_f[1] * p->v_f[1] + p->r_f[2] * p->v_f[2]) / horizontal;
    } else { /* at the axis |r_h| grows along any horizontal motion */
        away = norm(p->v_f + 1, 2);
    }
    return sin_gs * away + cos_gs * p->v_f[0] > 1e-12;
}

/* The terminal state must meet the path constraints it is held to at the last node, and be
 * reached from inside the glideslope cone. */
static int check_terminal(const pdg_params *p, char *msg)
{
    char text[200];
    const double gs = p->glideslope_deg * DEG, wn = norm(p->omega_f, 3);
    const double tilt_q = norm(p->q_f + 2, 2), horizontal = norm(p->r_f + 1, 2);
    if (sin(gs) * horizontal > cos(gs) * p->r_f[0] + 1e-12) {
        snprintf(text, sizeof text, "landing point is outside the %g deg glideslope cone",
                 p->glideslope_deg);
        return fail(msg, "r_f", text);
    }
    if (arrives_from_outside_the_cone(p, horizontal, gs)) {
        snprintf(text, sizeof text,
                 "v_f = (%g, %g, %g) reaches r_f, on the %g deg glideslope cone, from outside "
                 "the cone (e1 is up): at r_f = 0, v_f[0] <= -tan(glideslope) |(v_f[1], v_f[2])|",
                 p->v_f[0], p->v_f[1], p->v_f[2], p->glideslope_deg);
        return fail(msg, "v_f", text);
    }
    if (wn > pdg_omega_max(p) + 1e-12) {
        snprintf(text, sizeof text, "|omega_f| = %.3f deg/U_T exceeds omega_max_deg = %g",
                 wn / DEG, p->omega_max_deg);
        return fail(msg, "omega_f", text);
    }
    if (p->final_roll_free && tilt_q > 1e-12) {
        snprintf(text, sizeof text,
                 "a roll-free landing ends upright (q2 = q3 = 0), but q_f is tilted %.3f deg; "
                 "set final_roll_free to false to pin it",
                 tilt_deg(tilt_q));
        return fail(msg, "q_f", text);
    }
    if (!p->final_roll_free && tilt_q > pdg_tilt_q_max(p) + 1e-12) {
        snprintf(text, sizeof text, "pinned final tilt %.3f deg exceeds tilt_max_deg = %g",
                 tilt_deg(tilt_q), p->tilt_max_deg);
        return fail(msg, "q_f", text);
    }
    return 0;
}

/* The vehicle's rates, masses, inertia and thrust limits: positive (beta_mdot non-negative),
 * J_B and omega_max_deg above their floors, T_min below T_max. */
static int check_vehicle_sizes(const pdg_params *p, char *msg)
{
    char text[200];
    struct {
        const char *name;
        double v;
    } pos[] = {{"alpha_mdot", p->alpha_mdot}, {"aero_coeff", p->aero_coeff},
               {"m_dry", p->m_dry},           {"T_min", p->T_min},
               {"T_max", p->T_max},           {"omega_max_deg", p->omega_max_deg}};
    size_t i;
    for (i = 0; i < sizeof pos / sizeof pos[0]; ++i) {
        if (pos[i].v <= 0.0) {
            snprintf(text, sizeof text, "must be positive, got %.17g", pos[i].v);
            return fail(msg, pos[i].name, text);
        }
    }
    if (p->beta_mdot < 0.0) {
        snprintf(text, sizeof text, "must be non-negative, got %.17g", p->beta_mdot);
        return fail(msg, "beta_mdot", text);
    }
    if (p->J_B[0] <= 0.0 || p->J_B[1] <= 0.0 || p->J_B[2] <= 0.0) {
        snprintf(text, sizeof text, "inertia diagonal must be positive, got (%g, %g, %g)",
                 p->J_B[0], p->J_B[1], p->J_B[2]);
        return fail(msg, "J_B", text);
    }
    if (p->J_B[0] < PDG_INERTIA_MIN || p->J_B[1] < PDG_INERTIA_MIN ||
        p->J_B[2] < PDG_INERTIA_MIN) {
        snprintf(text, sizeof text, "inertia diagonal must be at least %g, got (%g, %g, %g)",
                 PDG_INERTIA_MIN, p->J_B[0], p->J_B[1], p->J_B[2]);
        return fail(msg, "J_B", text);
    }
    if (p->omega_max_deg < PDG_OMEGA_MAX_DEG_MIN) {
        snprintf(text, sizeof text, "must be at least %g deg/U_T, got %g",
                 PDG_OMEGA_MAX_DEG_MIN, p->omega_max_deg);
        return fail(msg, "omega_max_deg", text);
    }
    if (p->T_min >= p->T_max) {
        snprintf(text, sizeof text, "T_min = %g must be below T_max = %g", p->T_min, p->T_max);
        return fail(msg, "T_min", text);
    }
    return 0;
}

static int check_params(const pdg_params *p, char *msg)
{
    char text[200];
    if (check_vehicle_sizes(p, msg)) {
        return 1;
    }
    if (!(p->r_T_B[0] < 0.0)) { /* the gimbal's lever arm; the guess divides by it */
        snprintf(text, sizeof text, "r_T_B[0] = %.17g: the engine sits below the centre of "
                 "mass on the body axis (r_T_B[0] < 0, DESIGN.md: -0.01)", p->r_T_B[0]);
        return fail(msg, "r_T_B", text);
    }
    if (!(0.0 < p->gimbal_max_deg && p->gimbal_max_deg < 90.0)) {
        return fail(msg, "gimbal_max_deg", "must lie in (0, 90) degrees");
    }
    if (!(0.0 < p->tilt_max_deg && p->tilt_max_deg <= 180.0)) {
        return fail(msg, "tilt_max_deg", "must lie in (0, 180] degrees");
    }
    if (!(0.0 <= p->glideslope_deg && p->glideslope_deg < 90.0)) {
        return fail(msg, "glideslope_deg", "must lie in [0, 90) degrees");
    }
    if (fabs(norm(p->q_f, 4) - 1.0) > UNIT_QUATERNION_TOL) {
        return fail(msg, "q_f", "must be a unit quaternion");
    }
    if (p->g_I[0] >= 0.0 || p->g_I[1] != 0.0 || p->g_I[2] != 0.0) {
        return fail(msg, "g_I", "gravity must point along -e1 (e1 is up)");
    }
    if (!(PDG_N_MIN <= p->N && p->N <= PDG_N_MAX)) {
        snprintf(text, sizeof text, "must lie in [3, 400], got %d", p->N);
        return fail(msg, "N", text);
    }
    if (p->r_f[0] < 0.0) {
        return fail(msg, "r_f", "landing point must not be below the surface");
    }
    if (p->final_roll_free != 0 && p->final_roll_free != 1) {
        return fail(msg, "final_roll_free", "expected true or false");
    }
    return check_terminal(p, msg);
}

int pdg_check_scenario(const pdg_scenario *s, char *msg)
{
    const pdg_params *p;
    char text[200];
    double nq, horizontal, gs, tilt_q, wn;
    if (!s) {
        return fail(msg, "<root>", "no scenario given (NULL)");
    }
    p = &s->params;
    if (check_numbers(s, msg) || check_params(p, msg)) {
        return 1;
    }
    nq = norm(s->q0, 4);
    if (fabs(nq - 1.0) > UNIT_QUATERNION_TOL) {
        snprintf(text, sizeof text, "must be a unit quaternion, |q0| = %.9g", nq);
        return fail(msg, "q0", text);
    }
    if (s->m0 <= p->m_dry) {
        snprintf(text, sizeof text, "m0 = %g must exceed the dry mass m_dry = %g", s->m0,
                 p->m_dry);
        return fail(msg, "m0", text);
    }
    horizontal = norm(s->r0 + 1, 2);
    gs = p->glideslope_deg * DEG;
    if (sin(gs) * horizontal > cos(gs) * s->r0[0] + 1e-12) {
        snprintf(text, sizeof text,
                 "start is below the %g deg glideslope cone (altitude %g, horizontal "
                 "distance %g)",
                 p->glideslope_deg, s->r0[0], horizontal);
        return fail(msg, "r0", text);
    }
    tilt_q = norm(s->q0 + 2, 2);
    if (tilt_q > pdg_tilt_q_max(p) + 1e-12) {
        snprintf(text, sizeof text, "initial tilt %.3f deg exceeds tilt_max_deg = %g",
                 tilt_deg(tilt_q), p->tilt_max_deg);
        return fail(msg, "q0", text);
    }
    wn = norm(s->w0, 3);
    if (wn > pdg_omega_max(p) + 1e-12) {
        snprintf(text, sizeof text, "|w0| = %.3f deg/U_T exceeds omega_max_deg = %g", wn / DEG,
                 p->omega_max_deg);
        return fail(msg, "w0", text);
    }
    /* Roll decoupling: J2 = J3 and no off-axis engine or pressure offset -> omega_1 const. */
    if (p->J_B[1] == p->J_B[2] && p->r_T_B[1] == 0.0 && p->r_T_B[2] == 0.0 &&
        p->r_cp_B[1] == 0.0 && p->r_cp_B[2] == 0.0 && s->w0[0] != p->omega_f[0]) {
        snprintf(text, sizeof text,
                 "the engine cannot make roll torque (J2 = J3, r_T on the body axis), so the "
                 "roll rate is constant: w0[0] = %g cannot reach omega_f[0] = %g",
                 s->w0[0], p->omega_f[0]);
        /* the field the user moved from its default (0): a rolling start or a rolling end */
        return fail(msg, p->omega_f[0] != 0.0 ? "omega_f" : "w0", text);
    }
    return 0;
}

int pdg_validate_scenario(const pdg_scenario *scenario, char *message)
{
    if (message) {
        message[0] = '\0'; /* "" for a scenario it accepts */
    }
    return pdg_check_scenario(scenario, message) != 0 ? PDG_INVALID_INPUT : 0;
}

/* The params' part of pdg_check_scenario: its number checks on a scenario holding the vehicle
 * and the default initial state (which passes them), then the parameters' own rules. */
pdg_setup_status pdg_check_vehicle(const pdg_params *vehicle, char *message)
{
    pdg_scenario s;
    if (message) {
        message[0] = '\0'; /* "" for a vehicle it accepts */
    }
    if (!vehicle) {
        if (message) {
            snprintf(message, PDG_MESSAGE_LEN, "vehicle is NULL");
        }
        return PDG_SETUP_NULL_ARGUMENT;
    }
    pdg_default_scenario(&s);
    s.params = *vehicle;
    if (check_numbers(&s, message) || check_params(vehicle, message)) {
        return PDG_SETUP_BAD_VEHICLE;
    }
    return PDG_SETUP_OK;
}

/* ---- re-planning from a measured state --------------------------------------------------- */

int pdg_scenario_at_state(const pdg_scenario *base, const double *x, pdg_scenario *out,
                          char *message)
{
    char text[160]; /* fail() prefixes it within PDG_MESSAGE_LEN */
    double nq;
    int i;
    if (!base || !x || !out) {
        fail(message, "x", "NULL argument");
        return PDG_INVALID_INPUT;
    }
    if (!pdg_all_finite(x, PDG_NSTATE)) {
        fail(message, "x", "a state value is NaN or infinite");
        return PDG_INVALID_INPUT;
    }
    /* J2 = J3 and r_T on the body axis: the engine makes no roll torque, so a roll rate in
     * flight is the integration's or the estimator's rounding, or a broken disturbance model. */
    if (fabs(x[10]) > PDG_ROLL_NOISE) {
        snprintf(text, sizeof text, "roll rate %.3g rad/U_T in flight: the vehicle cannot make "
                 "one (above PDG_ROLL_NOISE = %g)", x[10], PDG_ROLL_NOISE);
        fail(message, "w0", text);
        return PDG_INVALID_INPUT;
    }
    nq = norm(x + 6, 4);
    if (!(nq > 0.0)) {
        fail(message, "q0", "the state's quaternion is zero");
        return PDG_INVALID_INPUT;
    }
    *out = *base;
    for (i = 0; i < 3; ++i) {
        out->r0[i] = x[i];
        out->v0[i] = x[3 + i];
        out->w0[i] = i == 0 ? 0.0 : x[10 + i];
    }
    for (i = 0; i < 4; ++i) {
        out->q0[i] = x[6 + i] / nq;
    }
    out->m0 = x[13];
    return pdg_validate_scenario(out, message);
}
