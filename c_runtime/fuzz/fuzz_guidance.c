/*
 * fuzz_guidance.c -- fuzz harness of the guidance API (tscvx_guidance.h): a small landing
 * (N = 3 to 8 nodes, a few SCvx iterations, short IPM limits: each run is quick) whose
 * settings, vehicle, scenario, guess and masks the input mutates from the defaults.
 *
 * Input: N and the settings' limits, then mutations "field, how, value" of the settings, of
 * the vehicle given to pdg_setup and of the scenario given to pdg_solve (a value from
 * fz_double: NaN, inf, huge, tiny, signs; or the field scaled, negated, nudged), then
 * optionally a guess (the built-in one of the default landing with mutated entries, or
 * NaN / inf / negative t_f) and a mask table. Oracle:
 *   - no crash, no sanitizer report; every status documented, with a non-empty message
 *     (pdg_status_message, and result.message when the solve did not succeed);
 *   - a refused vehicle or settings are refused alike by pdg_check_vehicle /
 *     pdg_check_settings and pdg_workspace_size;
 *   - pdg_arena_high_water <= the arena asked;
 *   - when pdg_solve says SOLVED: t_f finite and positive, every x and u finite, the
 *     initial state the scenario's, the final r, v, omega and quaternion (its roll-free part
 *     or all of it) the targets, and every path constraint (m >= m_dry, glideslope, tilt,
 *     angular rate, T_max, gimbal, T_min) met at every node, recomputed here from
 *     DESIGN.md's formulas, within 10 x defect_tol (plus a relative 1e-6 for the boundary
 *     conditions, which the subproblem meets to the conic solver's tolerance).
 */
#include "fuzz.h"

#include "tscvx_guidance.h"

#define NMAX 8
#define DEG (3.14159265358979323846 / 180.0)

static void *xmalloc(size_t n)
{
    void *v = malloc(n ? n : 1);
    if (!v) {
        abort();
    }
    return v;
}

/* The doubles of a pdg_params, by index. */
static double *param_field(pdg_params *p, unsigned k)
{
    double *const f[] = {&p->g_I[0], &p->g_I[1], &p->g_I[2], &p->J_B[0], &p->J_B[1], &p->J_B[2],
                         &p->r_T_B[0], &p->r_T_B[1], &p->r_T_B[2], &p->r_cp_B[0], &p->r_cp_B[1],
                         &p->r_cp_B[2], &p->alpha_mdot, &p->beta_mdot, &p->aero_coeff,
                         &p->m_dry, &p->T_min, &p->T_max, &p->gimbal_max_deg, &p->tilt_max_deg,
                         &p->glideslope_deg, &p->omega_max_deg, &p->r_f[0], &p->r_f[1],
                         &p->r_f[2], &p->v_f[0], &p->v_f[1], &p->v_f[2], &p->q_f[0], &p->q_f[1],
                         &p->q_f[2], &p->q_f[3], &p->omega_f[0], &p->omega_f[1], &p->omega_f[2]};
    return f[k % (sizeof f / sizeof f[0])];
}

static double *scenario_field(pdg_scenario *s, unsigned k)
{
    double *const f[] = {&s->r0[0], &s->r0[1], &s->r0[2], &s->v0[0], &s->v0[1], &s->v0[2],
                         &s->q0[0], &s->q0[1], &s->q0[2], &s->q0[3], &s->w0[0], &s->w0[1],
                         &s->w0[2], &s->m0};
    if (k % 2u) {
        return param_field(&s->params, k / 2u);
    }
    return f[(k / 2u) % (sizeof f / sizeof f[0])];
}

static double *settings_field(pdg_settings *st, unsigned k)
{
    double *const f[] = {&st->lam, &st->rho0, &st->rho1, &st->rho2, &st->alpha, &st->beta,
                         &st->eta_init, &st->eta_lb, &st->eta_ub, &st->step_tol,
                         &st->cost_tol, &st->vc_tol, &st->defect_tol, &st->tight_tol,
                         &st->socp_tol, &st->prox_u};
    return f[k % (sizeof f / sizeof f[0])];
}

/* One mutation of *v: how = 0 a value from the input, 1 scaled, 2 negated, 3 nudged. */
static void mutate(fz_reader *r, double *v)
{
    const unsigned how = fz_u8(r) % 4u;
    if (how == 0) {
        *v = fz_double(r);
    } else if (how == 1) {
        *v *= fz_double(r);
    } else if (how == 2) {
        *v = -*v;
    } else {
        *v += ((double)fz_u8(r) - 128.0) / 256.0;
    }
}

static void check_status(pdg_status s, const char *message, const char *where)
{
    const char *m;
    if ((unsigned)s >= (unsigned)PDG_NSTATUS) {
        FZ_FAIL("%s: undocumented status %d", where, (int)s);
    }
    m = pdg_status_message(s);
    if (!m || !m[0] || !pdg_status_name(s) || !pdg_status_name(s)[0]) {
        FZ_FAIL("%s: status %d without a message", where, (int)s);
    }
    if (s != PDG_SOLVED && (!message[0] || !memchr(message, 0, PDG_MESSAGE_LEN))) {
        FZ_FAIL("%s: status %s with an empty result message", where, pdg_status_name(s));
    }
}

/* |a - b| within 1e-6 relative plus tol */
static void near(double a, double b, double tol, const char *what, int i)
{
    if (!(fabs(a - b) <= tol + 1e-6 * fmax(1.0, fabs(b)))) {
        FZ_FAIL("SOLVED with %s[%d] = %.17g, the scenario says %.17g", what, i, a, b);
    }
}

static void check_solved(const pdg_scenario *sc, const pdg_settings *st, int N, const double *x,
                         const double *u, const pdg_result *res)
{
    const pdg_params *p = &sc->params;
    const double *xf = x + 14 * (N - 1), tol = 10.0 * st->defect_tol;
    const double tg = tan(p->glideslope_deg * DEG), qmax = sqrt((1.0 - cos(p->tilt_max_deg * DEG)) / 2.0);
    const double wmax = p->omega_max_deg * DEG, cg = cos(p->gimbal_max_deg * DEG);
    int k, i;
    if (!(isfinite(res->t_f) && res->t_f > 0.0)) {
        FZ_FAIL("SOLVED with t_f = %g", res->t_f);
    }
    for (i = 0; i < 14 * N; ++i) {
        if (!isfinite(x[i])) {
            FZ_FAIL("SOLVED with x[%d] = %g", i, x[i]);
        }
    }
    for (i = 0; i < 3 * N; ++i) {
        if (!isfinite(u[i])) {
            FZ_FAIL("SOLVED with u[%d] = %g", i, u[i]);
        }
    }
    /* x = (r, v, q scalar first, omega, m) */
    for (i = 0; i < 3; ++i) {
        near(x[i], sc->r0[i], tol, "r(0)", i);
        near(x[3 + i], sc->v0[i], tol, "v(0)", i);
        near(x[10 + i], sc->w0[i], tol, "omega(0)", i);
        near(xf[i], p->r_f[i], tol, "r(t_f)", i);
        near(xf[3 + i], p->v_f[i], tol, "v(t_f)", i);
        near(xf[10 + i], p->omega_f[i], tol, "omega(t_f)", i);
    }
    for (i = 0; i < 4; ++i) {
        near(x[6 + i], sc->q0[i], tol, "q(0)", i);
        if (!p->final_roll_free) {
            near(xf[6 + i], p->q_f[i], tol, "q(t_f)", i);
        }
    }
    if (p->final_roll_free) {
        near(xf[8], 0.0, tol, "q(t_f)", 2);
        near(xf[9], 0.0, tol, "q(t_f)", 3);
    }
    near(x[13], sc->m0, tol, "m(0)", 0);
    for (k = 0; k < N; ++k) {
        const double *xk = x + 14 * k, *uk = u + 3 * k;
        const double T = sqrt(uk[0] * uk[0] + uk[1] * uk[1] + uk[2] * uk[2]);
        const double h[7] = {
            p->m_dry - xk[13],
            tg * sqrt(xk[1] * xk[1] + xk[2] * xk[2]) - xk[0],
            sqrt(xk[8] * xk[8] + xk[9] * xk[9]) - qmax,
            sqrt(xk[10] * xk[10] + xk[11] * xk[11] + xk[12] * xk[12]) - wmax,
            T - p->T_max,
            cg * T - uk[0],
            p->T_min - T,
        };
        for (i = 0; i < 7; ++i) {
            if (!(h[i] <= tol)) {
                FZ_FAIL("SOLVED with path constraint %d at node %d = %g > %g (max_violation "
                        "%g)", i, k, h[i], tol, res->max_violation);
            }
        }
    }
}

/* pdg_workspace_size with the retries the header describes; the arena size in *need. */
static pdg_setup_status size_arena(const pdg_params *veh, const pdg_settings *st, size_t *need)
{
    void *scratch = NULL;
    pdg_setup_status s = PDG_SETUP_SCRATCH_TOO_SMALL;
    int tries;
    *need = 0;
    for (tries = 0; tries < 3 && s == PDG_SETUP_SCRATCH_TOO_SMALL; ++tries) {
        free(scratch);
        scratch = *need ? xmalloc(*need) : NULL;
        s = pdg_workspace_size(veh, st, scratch, *need, need);
    }
    free(scratch);
    if (s == PDG_SETUP_SCRATCH_TOO_SMALL) {
        FZ_FAIL("pdg_workspace_size still asks for more scratch after two retries");
    }
    return s;
}

typedef struct {
    int N;
    pdg_settings st;
    pdg_params veh;
    pdg_scenario sc;
    unsigned flags;
} landing;

static void read_landing(fz_reader *r, landing *L)
{
    unsigned k, nmut;
    L->N = 3 + (int)(fz_u8(r) % (NMAX - 2));
    pdg_default_settings(&L->st);
    pdg_default_scenario(&L->sc);
    L->sc.params.N = L->N;
    L->st.iter_max = 1 + (int)(fz_u8(r) % 16u);
    L->st.max_subproblems = 1 + (int)(fz_u8(r) % 24u);
    L->st.socp_max_iter = 1 + (int)(fz_u8(r) % 60u);
    L->st.socp_max_iter_total = 1 + (int)(fz_u16(r) % 1500u);
    L->flags = fz_u8(r);
    if (L->flags & 1u) {
        L->st.socp_warm_start = 0;
    }
    if (L->flags & 2u) {
        L->st.polish = 1;
    }
    if (L->flags & 4u) {
        L->st.rk4_substeps = (int)fz_u8(r) - 1;
    }
    if (L->flags & 8u) {
        L->sc.params.final_roll_free = (int)(int8_t)fz_u8(r) % 3;
    }
    nmut = fz_u8(r) % 4u; /* settings */
    for (k = 0; k < nmut; ++k) {
        mutate(r, settings_field(&L->st, fz_u8(r)));
    }
    nmut = fz_u8(r) % 8u; /* scenario (its params too) */
    for (k = 0; k < nmut; ++k) {
        mutate(r, scenario_field(&L->sc, fz_u8(r)));
    }
    L->veh = L->sc.params; /* the vehicle set up: the scenario's, or mutated apart */
    nmut = fz_u8(r) % 3u;
    for (k = 0; k < nmut; ++k) {
        mutate(r, param_field(&L->veh, fz_u8(r)));
    }
    if (L->flags & 16u) {
        L->veh.N = (int)(int8_t)fz_u8(r);
    }
}

static void solve(fz_reader *r, pdg_workspace *ws, const landing *L, size_t narena)
{
    const int N = L->N;
    double *x = (double *)xmalloc(sizeof(double) * 14 * N);
    double *u = (double *)xmalloc(sizeof(double) * 3 * N);
    double *gx = NULL, *gu = NULL;
    unsigned char *masks = NULL;
    pdg_options opt;
    pdg_result res;
    pdg_status s;
    size_t hw = 0;
    const unsigned g = fz_u8(r);
    memset(&opt, 0, sizeof opt);
    memset(&res, 0, sizeof res);
    res.x = x, res.u = u;
    if (g & 1u) { /* a guess: the built-in one, mutated */
        unsigned k, nmut = fz_u8(r) % 4u;
        gx = (double *)xmalloc(sizeof(double) * 14 * N);
        gu = (double *)xmalloc(sizeof(double) * 3 * N);
        opt.guess_t_f = 1.0;
        if (pdg_debug_guess(ws, &L->sc, gx, gu, &opt.guess_t_f, NULL) != 0) {
            for (k = 0; k < 14u * (unsigned)N; ++k) {
                gx[k] = 0.5;
            }
            for (k = 0; k < 3u * (unsigned)N; ++k) {
                gu[k] = 1.0;
            }
        }
        for (k = 0; k < nmut; ++k) {
            const unsigned at = fz_u8(r) % (17u * (unsigned)N + 1u);
            mutate(r, at < 14u * (unsigned)N ? &gx[at]
                      : at < 17u * (unsigned)N ? &gu[at - 14u * (unsigned)N] : &opt.guess_t_f);
        }
        opt.guess_x = gx;
        opt.guess_u = g & 2u ? NULL : gu; /* one of x, u alone: refused */
    }
    if (g & 4u) { /* a mask table */
        const int rows = 1 + (int)(fz_u8(r) % 3u);
        int k;
        masks = (unsigned char *)xmalloc((size_t)rows * 7u * (size_t)N);
        for (k = 0; k < rows * 7 * N; ++k) {
            masks[k] = (unsigned char)(fz_u8(r) & 1u ? 0u : 1u);
        }
        opt.masks = masks;
        opt.n_masks = g & 8u ? rows : -rows;
    }
    s = pdg_solve(ws, &L->sc, g & 0xFu ? &opt : NULL, &res);
#ifdef FUZZ_TRACE
    fprintf(stderr, "N %d: %s: %s\n", N, pdg_status_name(s), res.message);
#endif
    check_status(s, res.message, "pdg_solve");
    if (s == PDG_SOLVED) {
        check_solved(&L->sc, &L->st, N, x, u, &res);
    }
    if (pdg_arena_high_water(ws, &hw) != PDG_SETUP_OK || hw > narena) {
        FZ_FAIL("arena high water %zu beyond the %zu bytes asked", hw, narena);
    }
    free(x), free(u), free(gx), free(gu), free(masks);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fz_reader r = {data, size, 0};
    landing L;
    char msg[PDG_MESSAGE_LEN];
    pdg_setup_status s_set, s_veh, s;
    size_t narena = 0;
    void *arena;
    pdg_workspace *ws = NULL;

    read_landing(&r, &L);
    s_set = pdg_check_settings(&L.st, msg);
    if (s_set != PDG_SETUP_OK && (s_set != PDG_SETUP_BAD_SETTINGS || !msg[0])) {
        FZ_FAIL("pdg_check_settings: status %d, message '%s'", (int)s_set, msg);
    }
    s_veh = pdg_check_vehicle(&L.veh, msg);
    if (s_veh != PDG_SETUP_OK && (s_veh != PDG_SETUP_BAD_VEHICLE || !msg[0])) {
        FZ_FAIL("pdg_check_vehicle: status %d, message '%s'", (int)s_veh, msg);
    }
    s = size_arena(&L.veh, &L.st, &narena);
    if ((unsigned)s >= (unsigned)PDG_SETUP_NSTATUS || !pdg_setup_status_message(s)[0]) {
        FZ_FAIL("pdg_workspace_size: undocumented status %d", (int)s);
    }
    if (s != PDG_SETUP_OK) {
        if (s_set == PDG_SETUP_OK && s_veh == PDG_SETUP_OK && s != PDG_SETUP_BAD_SIZE) {
            FZ_FAIL("pdg_workspace_size refused (%d) what the checks accept", (int)s);
        }
        return 0;
    }
    if (s_set != PDG_SETUP_OK || s_veh != PDG_SETUP_OK) {
        FZ_FAIL("pdg_workspace_size accepted settings %d / vehicle %d refused", (int)s_set,
                (int)s_veh);
    }
    arena = xmalloc(narena);
    s = pdg_setup(&ws, arena, narena, &L.veh, &L.st);
    if (s != PDG_SETUP_OK) {
        FZ_FAIL("pdg_setup refused (%d) what pdg_workspace_size sized", (int)s);
    }
    solve(&r, ws, &L, narena);
    if (r.at < r.n) { /* a second solve on the same workspace */
        solve(&r, ws, &L, narena);
    }
    free(arena);
    return 0;
}
