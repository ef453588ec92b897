/* SCvx (paper Algorithm 1) and its T-SCvx hooks (Algorithm 2): a transcription of
 * guidance/scvx.py on top of the SOCP runtime. Workspace set-up (one arena), the solve loop,
 * the exact penalty J on the FULL constraint set, the trust-region rules, the convergence
 * test and the tight-constraint labelling of guidance/constraints.py. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "pdg_internal.h"
#include "tscvx_fnv1a.h"

/* ---- message tables ---------------------------------------------------------------------- */

static const char *const setup_messages[PDG_SETUP_NSTATUS] = {
    "ok",
    "a required pointer is NULL",
    "N outside [3, 400]",
    "a setting is NaN or out of range",
    "scratch too small: retry with the returned size",
    "arena smaller than pdg_workspace_size()",
    "the SOCP runtime refused the subproblem",
    "workspace not set up, or its arena overwritten or damaged (a set-up checksum mismatch): "
    "set it up again (pdg_setup)",
    "index out of range",
    "a vehicle parameter is NaN or out of range (pdg_check_vehicle names it)",
};

static const char *const status_messages[PDG_NSTATUS] = {
    "converged",
    "virtual control could not be driven to zero: no feasible landing found",
    "iteration limit reached with zero virtual control",
    "a convex subproblem could not be solved, or a workspace was damaged during the call",
    "invalid input: nothing was solved",
};

static const char *const status_names[PDG_NSTATUS] = {
    "solved", "infeasible", "max_iterations", "solver_error", "invalid_input",
};

/* guidance/scvx.py POLISH_MEANINGS */
static const char *const polish_messages[PDG_POLISH_NSTATUS] = {
    "not run (off, prox_u = 0, or the solve did not converge)",
    "the answer is the polished iterate",
    "not run: the IPM iteration budget was spent",
    "its conic solve or the model evaluation failed; the converged iterate kept",
    "it left virtual control, no smaller defects or a path constraint unmet; the converged "
    "iterate kept",
};

/* Python names of the SOCP statuses (guidance/conic.py Status). */
static const char *socp_status_name(int s)
{
    switch (s) {
    case TSCVX_SOLVED: return "solved";
    case TSCVX_SOLVED_INACCURATE: return "solved_inaccurate";
    case TSCVX_PRIMAL_INFEASIBLE: return "primal_infeasible";
    case TSCVX_DUAL_INFEASIBLE: return "dual_infeasible";
    case TSCVX_MAX_ITER: return "max_iterations";
    case TSCVX_INVALID_INPUT: return "invalid_input";
    default: return "numerical_error";
    }
}

const char *pdg_setup_status_message(pdg_setup_status s)
{
    return (unsigned)s < PDG_SETUP_NSTATUS ? setup_messages[s] : "unknown status";
}
const char *pdg_polish_message(pdg_polish_status s)
{
    return (unsigned)s < PDG_POLISH_NSTATUS ? polish_messages[s] : "unknown status";
}
const char *pdg_status_message(pdg_status s)
{
    return (unsigned)s < PDG_NSTATUS ? status_messages[s] : "unknown status";
}
const char *pdg_status_name(pdg_status s)
{
    return (unsigned)s < PDG_NSTATUS ? status_names[s] : "unknown";
}

/* ---- arena ------------------------------------------------------------------------------- */

#define ALIGN 16u

typedef struct {
    unsigned char *base; /* NULL: count only */
    size_t cap, top, high;
    int overflow;
} arena;

static void *take(arena *a, size_t count, size_t size)
{
    size_t start = (a->top + (ALIGN - 1)) & ~(size_t)(ALIGN - 1);
    size_t bytes;
    if (size != 0 && count > (SIZE_MAX / 4) / size) {
        a->overflow = 1;
        return NULL;
    }
    bytes = count * size;
    a->top = start + bytes;
    if (a->top > a->high) {
        a->high = a->top;
    }
    if (!a->base || a->top > a->cap) {
        a->overflow = 1;
        return NULL;
    }
    return a->base + start;
}

static int bad_setting(char *msg, const char *text)
{
    if (msg) {
        snprintf(msg, PDG_MESSAGE_LEN, "settings.%s", text);
    }
    return PDG_SETUP_BAD_SETTINGS;
}

/* The ranges of SCvxSettings.__post_init__ (guidance/params.py); the integer bounds bound the
 * solve's loops and the log. */
/* The settings' checks in three groups, each 1 with the refusal in `text` (the one field at
 * fault and its value, in the order of params.py), 0 when they pass. */
#define SETTING_TEXT (PDG_MESSAGE_LEN - 16)

/* Every real finite (in the order of SCvxSettings' fields, as params.py checks them: with two
 * non-finite both name the first), every integer within its range. */
static int numbers_fault(const pdg_settings *s, char *text)
{
    const struct {
        const char *name;
        double v;
    } d[] = {{"lam", s->lam},         {"rho0", s->rho0},           {"rho1", s->rho1},
             {"rho2", s->rho2},       {"alpha", s->alpha},         {"beta", s->beta},
             {"eta_init", s->eta_init}, {"eta_lb", s->eta_lb},     {"eta_ub", s->eta_ub},
             {"step_tol", s->step_tol}, {"cost_tol", s->cost_tol}, {"vc_tol", s->vc_tol},
             {"defect_tol", s->defect_tol},
             {"tight_tol", s->tight_tol}, {"prox_u", s->prox_u},     {"socp_tol", s->socp_tol}};
    const struct {
        const char *name;
        int v, lo, hi;
    } n[] = {{"iter_max", s->iter_max, 1, 100},
             {"max_subproblems", s->max_subproblems, 1, 500},
             {"rk4_substeps", s->rk4_substeps, 1, PDG_MAX_SUBSTEPS},
             {"socp_max_iter", s->socp_max_iter, 1, 500},
             {"socp_max_iter_total", s->socp_max_iter_total, 1, PDG_MAX_ITER_TOTAL},
             {"socp_warm_start", s->socp_warm_start, 0, 1},
             {"tau_r_update", s->tau_r_update, 0, 1},
             {"polish", s->polish, 0, 1}};
    size_t i;
    for (i = 0; i < sizeof d / sizeof d[0]; ++i) {
        if (!isfinite(d[i].v)) {
            snprintf(text, SETTING_TEXT, "%s: must be finite, got %g", d[i].name, d[i].v);
            return 1;
        }
    }
    for (i = 0; i < sizeof n / sizeof n[0]; ++i) {
        if (n[i].v < n[i].lo || n[i].v > n[i].hi) {
            snprintf(text, SETTING_TEXT, "%s: must lie within %d..%d, got %d", n[i].name,
                     n[i].lo, n[i].hi, n[i].v);
            return 1;
        }
    }
    return 0;
}

/* The trust region's radii (eta_lb <= eta_init <= eta_ub), the penalty weight and the ratio
 * thresholds of Algorithm 1 (0 <= rho0 <= rho1 <= rho2). */
static int trust_region_fault(const pdg_settings *s, char *text)
{
    if (!(s->eta_lb > 0)) {
        snprintf(text, SETTING_TEXT, "eta_lb: must be > 0, got %g", s->eta_lb);
        return 1;
    }
    if (!(s->eta_ub >= s->eta_lb)) {
        snprintf(text, SETTING_TEXT, "eta_ub: must be >= eta_lb = %g, got %g", s->eta_lb,
                 s->eta_ub);
        return 1;
    }
    if (!(s->eta_lb <= s->eta_init && s->eta_init <= s->eta_ub)) {
        snprintf(text, SETTING_TEXT,
                 "eta_init: must lie within [eta_lb, eta_ub] = [%g, %g], got %.17g", s->eta_lb,
                 s->eta_ub, s->eta_init);
        return 1;
    }
    if (!(s->lam > 0 && s->lam <= PDG_LAM_MAX)) {
        snprintf(text, SETTING_TEXT, "lam: must lie within (0, %g], got %g", PDG_LAM_MAX,
                 s->lam);
        return 1;
    }
    if (!(s->rho0 >= 0)) { /* rho0 < 0 accepts steps that raise the penalty J */
        snprintf(text, SETTING_TEXT,
                 "rho0: must be >= 0 (a step that raises the penalty is refused), got %g",
                 s->rho0);
        return 1;
    }
    if (!(s->rho0 <= s->rho1)) {
        snprintf(text, SETTING_TEXT, "rho1: must satisfy rho0 <= rho1 (rho0 = %g), got %g",
                 s->rho0, s->rho1);
        return 1;
    }
    if (!(s->rho1 <= s->rho2)) {
        snprintf(text, SETTING_TEXT, "rho2: must satisfy rho1 <= rho2 (rho1 = %g), got %g",
                 s->rho1, s->rho2);
        return 1;
    }
    return 0;
}

/* The trust-region factors (alpha >= PDG_ALPHA_MIN, beta >= 1), the tolerances and the
 * proximal weight (within [0, PDG_PROX_U_MAX]). */
static int tolerance_fault(const pdg_settings *s, char *text)
{
    const struct {
        const char *name;
        double v;
    } nonneg[] = {{"step_tol", s->step_tol},     {"cost_tol", s->cost_tol},
                  {"vc_tol", s->vc_tol},         {"defect_tol", s->defect_tol},
                  {"tight_tol", s->tight_tol}};
    size_t i;
    if (!(s->alpha >= PDG_ALPHA_MIN)) {
        snprintf(text, SETTING_TEXT,
                 "alpha: must be >= %g (the trust region's shrink factor: a rejected step is "
                 "retried at eta / alpha), got %g",
                 PDG_ALPHA_MIN, s->alpha);
        return 1;
    }
    if (!(s->beta >= 1.0)) {
        snprintf(text, SETTING_TEXT,
                 "beta: must be >= 1 (the trust region's growth factor), got %g", s->beta);
        return 1;
    }
    for (i = 0; i < sizeof nonneg / sizeof nonneg[0]; ++i) {
        if (!(nonneg[i].v >= 0)) {
            snprintf(text, SETTING_TEXT, "%s: must be >= 0, got %g", nonneg[i].name,
                     nonneg[i].v);
            return 1;
        }
    }
    if (!(s->prox_u >= 0 && s->prox_u <= PDG_PROX_U_MAX)) {
        snprintf(text, SETTING_TEXT,
                 "prox_u: must lie within [0, %g] (a larger weight stops SCvx short of the "
                 "optimum), got %g",
                 PDG_PROX_U_MAX, s->prox_u);
        return 1;
    }
    if (!(s->socp_tol > 0 && s->socp_tol < 1)) {
        snprintf(text, SETTING_TEXT, "socp_tol: must lie within (0, 1), got %g", s->socp_tol);
        return 1;
    }
    return 0;
}

static pdg_setup_status check_settings(const pdg_settings *s, char *msg)
{
    char text[SETTING_TEXT];
    if (msg) {
        msg[0] = '\0'; /* "" for settings it accepts (tscvx_check_settings alike) */
    }
    if (numbers_fault(s, text) || trust_region_fault(s, text) || tolerance_fault(s, text)) {
        return bad_setting(msg, text);
    }
    return PDG_SETUP_OK;
}

pdg_setup_status pdg_check_settings(const pdg_settings *settings, char *message)
{
    if (!settings) {
        if (message) {
            snprintf(message, PDG_MESSAGE_LEN, "settings is NULL");
        }
        return PDG_SETUP_NULL_ARGUMENT;
    }
    return check_settings(settings, message);
}

static void socp_settings(const pdg_settings *st, tscvx_settings *ts)
{
    tscvx_default_settings(ts);
    ts->max_iter = st->socp_max_iter;
    ts->tol_gap_abs = st->socp_tol;
    ts->tol_gap_rel = st->socp_tol;
    ts->tol_feas = st->socp_tol;
}

static void socp_data(const pdg_workspace *ws, tscvx_data *d)
{
    memset(d, 0, sizeof *d);
    d->n = ws->n;
    d->p = ws->p;
    d->m = ws->m;
    if (ws->st.prox_u > 0.0) {
        d->Pp = ws->Pp;
        d->Pi = ws->Pi;
        d->Px = ws->Px;
    }
    d->c = ws->c;
    d->Ap = ws->Ap;
    d->Ai = ws->Ai;
    d->Ax = ws->Ax;
    d->b = ws->b;
    d->Gp = ws->Gp;
    d->Gi = ws->Gi;
    d->Gx = ws->Gx;
    d->h = ws->h;
    d->l = ws->l;
    d->nsoc = ws->nsoc;
    d->q = ws->q;
}

/* P = prox_u I on the thrust columns u_hat (upper-triangular CSC: the diagonal). */
static void prox_pattern(pdg_workspace *ws)
{
    const int iu = ws->lay.iu, isig = ws->lay.isig;
    int j, e = 0;
    for (j = 0; j < ws->n; ++j) {
        ws->Pp[j] = e;
        if (j >= iu && j < isig) {
            ws->Pi[e] = j;
            ws->Px[e] = ws->st.prox_u;
            ++e;
        }
    }
    ws->Pp[ws->n] = e;
}

/* Sorts the rows within each of the n columns of a CSC pattern (insertion sort; the columns
 * are short), the entry map en alongside. Returns 0, or -1 on a row given twice in a column. */
static int sort_columns(const int *Pp, int *Pi, int *en, int n)
{
    int j, a, b;
    for (j = 0; j < n; ++j) {
        for (a = Pp[j] + 1; a < Pp[j + 1]; ++a) {
            const int r = Pi[a], t = en[a];
            for (b = a - 1; b >= Pp[j] && Pi[b] > r; --b) {
                Pi[b + 1] = Pi[b];
                en[b + 1] = en[b];
            }
            Pi[b + 1] = r;
            en[b + 1] = t;
        }
        for (a = Pp[j] + 1; a < Pp[j + 1]; ++a) {
            if (Pi[a] == Pi[a - 1]) {
                return -1;
            }
        }
    }
    return 0;
}

/* Builds the CSC patterns of A and G from the emitted (row, col) list and the map from
 * emission order to value slots. Returns 0, or -1 on a duplicate entry. */
static int build_csc(pdg_workspace *ws, const int *row, const int *col, int *ent)
{
    const int n = ws->n, p = ws->p;
    int e, j, k;
    for (j = 0; j <= n; ++j) {
        ws->Ap[j] = 0;
        ws->Gp[j] = 0;
    }
    for (e = 0; e < ws->nnz; ++e) {
        if (row[e] < p) {
            ws->Ap[col[e] + 1]++;
        } else {
            ws->Gp[col[e] + 1]++;
        }
    }
    for (j = 0; j < n; ++j) {
        ws->Ap[j + 1] += ws->Ap[j];
        ws->Gp[j + 1] += ws->Gp[j];
    }
    /* place: a stable counting sort by column; ent[slot] = entry, Ap/Gp shifted by one */
    for (e = 0; e < ws->nnz; ++e) {
        if (row[e] < p) {
            const int s = ws->Ap[col[e]]++;
            ws->Ai[s] = row[e];
            ent[s] = e;
        } else {
            const int s = ws->Gp[col[e]]++;
            ws->Gi[s] = row[e] - p;
            ent[ws->nnz_A + s] = e;
        }
    }
    for (j = n; j > 0; --j) {
        ws->Ap[j] = ws->Ap[j - 1];
        ws->Gp[j] = ws->Gp[j - 1];
    }
    ws->Ap[0] = ws->Gp[0] = 0;
    if (sort_columns(ws->Ap, ws->Ai, ent, n) ||
        sort_columns(ws->Gp, ws->Gi, ent + ws->nnz_A, n)) {
        return -1;
    }
    for (k = 0; k < ws->nnz_A + ws->nnz_G; ++k) {
        ws->dest[ent[k]] = k;
    }
    return 0;
}

enum { BUILD_SIZE, BUILD_SETUP };

/* Member by member, so that the padding of the copy keeps the zeros it was cleared to (the
 * caller's padding is indeterminate, and the layout checksum reads the copy's bytes). A
 * field added to pdg_settings must be added here (test_guidance compares the copy with the
 * caller's settings byte for byte). */
static void copy_settings(pdg_settings *d, const pdg_settings *s)
{
    d->lam = s->lam;
    d->rho0 = s->rho0;
    d->rho1 = s->rho1;
    d->rho2 = s->rho2;
    d->alpha = s->alpha;
    d->beta = s->beta;
    d->eta_init = s->eta_init;
    d->eta_lb = s->eta_lb;
    d->eta_ub = s->eta_ub;
    d->iter_max = s->iter_max;
    d->max_subproblems = s->max_subproblems;
    d->step_tol = s->step_tol;
    d->cost_tol = s->cost_tol;
    d->vc_tol = s->vc_tol;
    d->defect_tol = s->defect_tol;
    d->rk4_substeps = s->rk4_substeps;
    d->tight_tol = s->tight_tol;
    d->socp_tol = s->socp_tol;
    d->socp_max_iter = s->socp_max_iter;
    d->socp_max_iter_total = s->socp_max_iter_total;
    d->socp_warm_start = s->socp_warm_start;
    d->tau_r_update = s->tau_r_update;
    d->prox_u = s->prox_u;
    d->polish = s->polish;
}

/* Sizes of the subproblem for the vehicle's N, terminal condition and A_k pattern (no memory
 * needed). */
static void problem_dims(pdg_workspace *w, const pdg_params *vehicle, const pdg_settings *st)
{
    const int N = vehicle->N;
    double pvec[PDG_NP];
    pdg_emitter em;
    memset(w, 0, sizeof *w);
    w->N = N;
    w->roll_free = vehicle->final_roll_free ? 1 : 0;
    pdg_param_vector(vehicle, pvec);
    w->phi_a = pdg_phi_a_pattern(pvec, &w->phi_a_nnz);
    copy_settings(&w->st, st);
    pdg_layout_init(&w->lay, N);
    w->n = w->lay.n;
    w->p = pdg_rows_eq(N, w->roll_free);
    pdg_cone_dims(N, &w->l, &w->nsoc, NULL);
    w->m = w->l + 18 * N + 12 * (N - 1) + 12 * N; /* path cones, nu pairs, trust pairs */
    em.mode = 0;
    em.cnt = 0;
    em.p = w->p;
    em.phi_a = w->phi_a;
    pdg_emit(&em, &w->lay, w->roll_free, NULL);
    w->nnz = em.cnt;
    w->nnz_A = (N - 1) * (NX * (1 + 2 * NU + 2) + w->phi_a_nnz) + NX + 9 + (w->roll_free ? 2 : 4);
    w->nnz_G = w->nnz - w->nnz_A;
    w->g_mass = w->l - 2 * N; /* rows of G: mass block, then T_min, then the cones */
    w->g_tmin = w->l - N;
    w->g_soc = w->l;
}

/* Claims every persistent array of the workspace from the arena (NULLs when it is short). */
static void claim_arrays(pdg_workspace *t, arena *a)
{
    const size_t N = (size_t)t->N, nI = N - 1, n = (size_t)t->n;
    t->Ap = (int *)take(a, n + 1, sizeof(int));
    t->Ai = (int *)take(a, (size_t)t->nnz_A, sizeof(int));
    t->Gp = (int *)take(a, n + 1, sizeof(int));
    t->Gi = (int *)take(a, (size_t)t->nnz_G, sizeof(int));
    t->q = (int *)take(a, (size_t)t->nsoc, sizeof(int));
    t->dest = (int *)take(a, (size_t)t->nnz, sizeof(int));
    t->Ax = (double *)take(a, (size_t)t->nnz_A, sizeof(double));
    t->Gx = (double *)take(a, (size_t)t->nnz_G, sizeof(double));
    t->b = (double *)take(a, (size_t)t->p, sizeof(double));
    t->h = (double *)take(a, (size_t)t->m, sizeof(double));
    t->c = (double *)take(a, n, sizeof(double));
    if (t->st.prox_u > 0.0) { /* P = w I on the thrust columns, fixed */
        t->Pp = (int *)take(a, n + 1, sizeof(int));
        t->Pi = (int *)take(a, N * NU, sizeof(int));
        t->Px = (double *)take(a, N * NU, sizeof(double));
    }
    t->z = (double *)take(a, n, sizeof(double));
    t->znew = (double *)take(a, n, sizeof(double));
    t->zdual = (double *)take(a, (size_t)t->m, sizeof(double));
    t->ydual = (double *)take(a, (size_t)t->p, sizeof(double));
    t->slack = (double *)take(a, (size_t)t->m, sizeof(double));
    t->disc = (double *)take(a, nI * N_DISC, sizeof(double));
    t->disc_new = (double *)take(a, nI * N_DISC, sizeof(double));
    t->aug = (double *)take(a, PDG_NAUG, sizeof(double));
    t->augw = (double *)take(a, PDG_NAUG, sizeof(double));
    t->x = (double *)take(a, N * NX, sizeof(double));
    t->u = (double *)take(a, N * NU, sizeof(double));
    t->xn = (double *)take(a, N * NX, sizeof(double));
    t->un = (double *)take(a, N * NU, sizeof(double));
    t->hval = (double *)take(a, N * NC, sizeof(double));
    t->gwork = (double *)take(a, N * PDG_GUESS_WORK_PER_NODE, sizeof(double));
    t->nn_out = (double *)take(a, N * (NX + NU) + 1, sizeof(double));
    t->nn_logits = (double *)take(a, N * NC, sizeof(double));
    t->mask = (unsigned char *)take(a, N * NC, 1);
    t->prev_mask = (unsigned char *)take(a, N * NC, 1);
    t->pred = (unsigned char *)take(a, N * NC, 1);
    t->forced = (unsigned char *)take(a, N * NC, 1);
    t->tight = (unsigned char *)take(a, N * NC, 1);
    t->keep = (unsigned char *)take(a, N * NC, 1);
    t->log = (pdg_log_row *)take(a, (size_t)t->st.max_subproblems, sizeof(pdg_log_row));
    t->masks_out = (unsigned char *)take(a, (size_t)t->st.iter_max * N * NC, 1);
}

/* The status of too little memory: the arena's at set-up, the scratch's in the size query */
static pdg_setup_status short_memory(int mode)
{
    return mode == BUILD_SETUP ? PDG_SETUP_ARENA_TOO_SMALL : PDG_SETUP_SCRATCH_TOO_SMALL;
}

/* Step 2 of build: the subproblem's sparsity pattern, fixed from here on (row, col, ent:
 * nnz temporaries each), and finite placeholder numbers; every solve writes the real ones. */
static pdg_setup_status fix_pattern(pdg_workspace *ws, int *row, int *col, int *ent)
{
    pdg_emitter em;
    int e, i, l, nsoc, n_eq = 0;
    pdg_cone_dims(ws->N, &l, &nsoc, ws->q);
    em.mode = 1;
    em.cnt = 0;
    em.p = ws->p;
    em.phi_a = ws->phi_a;
    em.row = row;
    em.col = col;
    pdg_emit(&em, &ws->lay, ws->roll_free, NULL);
    for (e = 0; e < ws->nnz; ++e) {
        n_eq += row[e] < ws->p;
    }
    if (em.cnt != ws->nnz || n_eq != ws->nnz_A || build_csc(ws, row, col, ent) != 0) {
        return PDG_SETUP_SOCP_ERROR; /* an inconsistent pattern is a bug: report, never crash */
    }
    if (ws->st.prox_u > 0.0) {
        prox_pattern(ws);
    }
    for (i = 0; i < ws->nnz_A; ++i) {
        ws->Ax[i] = 1.0;
    }
    for (i = 0; i < ws->nnz_G; ++i) {
        ws->Gx[i] = -1.0;
    }
    for (i = 0; i < ws->p; ++i) {
        ws->b[i] = 0.0;
    }
    for (i = 0; i < ws->m; ++i) {
        ws->h[i] = 1.0;
    }
    for (i = 0; i < ws->n; ++i) {
        ws->c[i] = 1.0;
    }
    return PDG_SETUP_OK;
}

/* Step 3 of build: the SOCP workspace, its symbolic analysis in the rest of the arena, then
 * (BUILD_SETUP) its set-up there. The subproblem has stage structure by construction (every
 * variable under the trust region or a penalty cone, the dynamics coupling neighbouring
 * nodes): the banded KKT method first, whose analysis needs far less scratch than the sparse
 * method's AMD; the sparse method only should the runtime refuse it. *need as build's. */
static pdg_setup_status socp_workspace(pdg_workspace *ws, const arena *a,
                                       const pdg_settings *st, int mode, size_t skip,
                                       size_t *need)
{
    const size_t socp_at = (a->top + (ALIGN - 1)) & ~(size_t)(ALIGN - 1);
    size_t nscr = 0, nsocp = 0, total, hw;
    tscvx_settings ts;
    tscvx_data d;
    tscvx_info info;
    int i;
    socp_settings(st, &ts);
    socp_data(ws, &d);
    for (i = 0; i < 2; ++i) {
        tscvx_setup_status sz;
        ts.kkt_backend = i == 0 ? TSCVX_KKT_BANDED : TSCVX_KKT_STATIC;
        if (tscvx_scratch_size(&d, &ts, &nscr) != TSCVX_SETUP_OK) {
            return PDG_SETUP_SOCP_ERROR;
        }
        if (socp_at + nscr > a->cap) {
            *need = (socp_at + nscr > a->high ? socp_at + nscr : a->high) + ALIGN;
            return short_memory(mode);
        }
        sz = tscvx_workspace_size(&d, &ts, a->base + socp_at, a->cap - socp_at, &nsocp);
        if (sz == TSCVX_SETUP_OK) {
            break;
        }
        if (sz != TSCVX_SETUP_NOT_BANDED || i == 1) {
            return PDG_SETUP_SOCP_ERROR;
        }
    }
    total = socp_at + (nsocp > nscr ? nsocp : nscr);
    *need = (total > a->high ? total : a->high) + ALIGN;
    if (mode == BUILD_SIZE) {
        return PDG_SETUP_OK;
    }
    if (socp_at + nsocp > a->cap) {
        return PDG_SETUP_ARENA_TOO_SMALL;
    }
    if (tscvx_setup(&ws->socp, a->base + socp_at, a->cap - socp_at, &d, &ts) !=
        TSCVX_SETUP_OK) {
        return PDG_SETUP_SOCP_ERROR;
    }
    if (tscvx_get_info(ws->socp, &info) != TSCVX_SETUP_OK) {
        return PDG_SETUP_SOCP_ERROR;
    }
    hw = socp_at + (info.arena_high_water > nscr ? info.arena_high_water : nscr);
    ws->arena_high = skip + (hw > a->high ? hw : a->high);
    return PDG_SETUP_OK;
}

/* The set-up arguments a size query checks too: N, the settings and the vehicle. */
static pdg_setup_status check_inputs(const pdg_params *vehicle, const pdg_settings *st)
{
    if (vehicle->N < PDG_N_MIN || vehicle->N > PDG_N_MAX) {
        return PDG_SETUP_BAD_SIZE;
    }
    if (pdg_check_settings(st, NULL) != PDG_SETUP_OK) {
        return PDG_SETUP_BAD_SETTINGS;
    }
    if (pdg_check_vehicle(vehicle, NULL) != PDG_SETUP_OK) {
        return PDG_SETUP_BAD_VEHICLE;
    }
    return PDG_SETUP_OK;
}

/* An empty arena over mem (NULL: counting only), its start aligned; returns the bytes skipped
 * (the +ALIGN of every size covers them). */
static size_t arena_init(arena *a, void *mem, size_t bytes)
{
    const size_t skip = mem ? (ALIGN - ((uintptr_t)mem % ALIGN)) % ALIGN : 0;
    a->base = mem && bytes > skip ? (unsigned char *)mem + skip : NULL;
    a->cap = mem && bytes > skip ? bytes - skip : 0;
    a->top = a->high = 0;
    a->overflow = 0;
    return skip;
}

/* The one set-up path. BUILD_SIZE stops after the SOCP's analysis and returns the arena size
 * in *need; BUILD_SETUP builds the workspace. When the memory is short, *need is a size that
 * gets further (the exact one once the pattern fits). */
static pdg_setup_status build(void *mem, size_t bytes, const pdg_params *vehicle,
                              const pdg_settings *st, int mode, pdg_workspace **out,
                              size_t *need)
{
    arena a;
    pdg_workspace dims, *ws;
    pdg_setup_status status;
    size_t mark, skip;
    int *row, *col, *ent;

    if (!vehicle || !st || !need) {
        return PDG_SETUP_NULL_ARGUMENT;
    }
    *need = 0;
    status = check_inputs(vehicle, st);
    if (status != PDG_SETUP_OK) {
        return status;
    }
    skip = arena_init(&a, mem, bytes);

    /* 1. the workspace, its arrays and the temporaries of the pattern build */
    problem_dims(&dims, vehicle, st);
    ws = (pdg_workspace *)take(&a, 1, sizeof(pdg_workspace));
    if (ws) {
        memcpy(ws, &dims, sizeof *ws); /* the padding too (zeros): the checksum reads it */
    } else {
        ws = &dims; /* count only */
    }
    claim_arrays(ws, &a);
    mark = a.top;
    row = (int *)take(&a, (size_t)ws->nnz, sizeof(int));
    col = (int *)take(&a, (size_t)ws->nnz, sizeof(int));
    ent = (int *)take(&a, (size_t)ws->nnz, sizeof(int));
    if (a.overflow) {
        *need = a.high + ALIGN;
        return short_memory(mode);
    }
    /* 2. the sparsity pattern, then 3. the SOCP workspace in the memory left */
    status = fix_pattern(ws, row, col, ent);
    if (status != PDG_SETUP_OK) {
        return status;
    }
    a.top = mark; /* temporaries released */
    status = socp_workspace(ws, &a, st, mode, skip, need);
    if (status != PDG_SETUP_OK || mode == BUILD_SIZE) {
        return status;
    }
    ws->arena_bytes = bytes;
    ws->busy = 0;
    ws->running = NULL;
    ws->socp_cap = st->socp_max_iter;
    ws->socp_polish = 0;
    ws->layout_sum = pdg_layout_sum(ws);
    ws->map_sum = pdg_map_sum(ws);
    ws->magic = PDG_WS_MAGIC;
    *out = ws;
    return PDG_SETUP_OK;
}

/* The fields pdg_setup fixes and no call changes: from N to the SOCP workspace pointer
 * (sizes, settings, layout, the pattern and data pointers), the buffer pointers from z to
 * log but the two discretization buffers (swapped on acceptance, as a pair: checked for
 * being the pair), the masks pointer and the arena size (about 1 KB); pdg_map_sum covers
 * the map of the subproblem's entries into A and G (dest), whose every entry is written on
 * every iteration (4 nnz bytes, 62 KB at N = 50). The map's pointer and length are among
 * the fields: the map is summed only once they match (pdg_ws_ready), so a flip in them is
 * refused, never followed (it used to send the sum itself out of bounds: 28 Nov).
 * Word-wise (tscvx_wordsum): any single bit flip is found for certain, as by the bytewise
 * FNV-1a before, in about an eighth of the instructions (make budget, 28 Nov: the default
 * landing's SCvx call 0.56 M fewer host instructions, T-SCvx's 0.93 M). */
uint64_t pdg_layout_sum(const pdg_workspace *ws)
{
    const char *base = (const char *)ws;
    const uintptr_t a = (uintptr_t)ws->disc, b = (uintptr_t)ws->disc_new;
    const uintptr_t pair[2] = {a < b ? a : b, a < b ? b : a};
    uint64_t h = TSCVX_FNV1A_START;
    h = tscvx_wordsum(h, base + offsetof(pdg_workspace, N),
                      offsetof(pdg_workspace, scn) - offsetof(pdg_workspace, N));
    h = tscvx_wordsum(h, base + offsetof(pdg_workspace, z),
                      offsetof(pdg_workspace, disc) - offsetof(pdg_workspace, z));
    h = tscvx_wordsum(h, pair, sizeof pair);
    h = tscvx_wordsum(h, base + offsetof(pdg_workspace, aug),
                      offsetof(pdg_workspace, n_log) - offsetof(pdg_workspace, aug));
    h = tscvx_wordsum(h, &ws->masks_out, sizeof ws->masks_out);
    return tscvx_wordsum(h, &ws->arena_bytes, sizeof ws->arena_bytes);
}

uint64_t pdg_map_sum(const pdg_workspace *ws)
{
    return tscvx_wordsum(TSCVX_FNV1A_START, ws->dest, sizeof(int) * (size_t)ws->nnz);
}

int pdg_ws_ready(const pdg_workspace *ws)
{
    return ws && ws->magic == PDG_WS_MAGIC && ws->layout_sum == pdg_layout_sum(ws) &&
           ws->map_sum == pdg_map_sum(ws);
}

int pdg_ws_idle(const pdg_workspace *ws) { return pdg_ws_ready(ws) && !ws->busy; }

pdg_setup_status pdg_workspace_size(const pdg_params *vehicle, const pdg_settings *settings,
                                    void *scratch, size_t scratch_bytes, size_t *bytes)
{
    return build(scratch, scratch_bytes, vehicle, settings, BUILD_SIZE, NULL, bytes);
}

pdg_setup_status pdg_setup(pdg_workspace **ws, void *arena_mem, size_t arena_bytes,
                           const pdg_params *vehicle, const pdg_settings *settings)
{
    size_t need = 0;
    if (!ws) {
        return PDG_SETUP_NULL_ARGUMENT;
    }
    *ws = NULL; /* whatever is refused below: no workspace */
    if (!arena_mem) {
        return PDG_SETUP_NULL_ARGUMENT;
    }
    return build(arena_mem, arena_bytes, vehicle, settings, BUILD_SETUP, ws, &need);
}

/* ---- pieces of the iteration ------------------------------------------------------------- */

static void to_physical(const pdg_workspace *ws, const double *z, double *x, double *u,
                        double *t_f)
{
    const pdg_layout *L = &ws->lay;
    int k, i;
    for (k = 0; k < ws->N; ++k) {
        for (i = 0; i < NX; ++i) {
            x[NX * k + i] = z[L->ix + NX * k + i] * ws->sc.Sx[i] + ws->sc.cx[i];
        }
        for (i = 0; i < NU; ++i) {
            u[NU * k + i] = z[L->iu + NU * k + i] * ws->sc.Su;
        }
    }
    *t_f = z[L->isig] * ws->sc.Ss;
}

static void to_scaled(const pdg_workspace *ws, const double *x, const double *u, double t_f,
                      double *z)
{
    const pdg_layout *L = &ws->lay;
    int k, i;
    for (i = 0; i < L->n; ++i) {
        z[i] = 0.0;
    }
    for (k = 0; k < ws->N; ++k) {
        for (i = 0; i < NX; ++i) {
            z[L->ix + NX * k + i] = (x[NX * k + i] - ws->sc.cx[i]) / ws->sc.Sx[i];
        }
        for (i = 0; i < NU; ++i) {
            z[L->iu + NU * k + i] = u[NU * k + i] / ws->sc.Su;
        }
    }
    z[L->isig] = t_f / ws->sc.Ss;
}

/* FOH discretization of all intervals about (x, u, t_f) into disc ((N-1) x N_DISC). */
static int discretize(pdg_workspace *ws, const double *x, const double *u, double t_f,
                      double *disc)
{
    const int N = ws->N;
    const double dtau = 1.0 / (N - 1);
    const int steps = pdg_rk4_steps(ws->st.rk4_substeps, N);
    int k, i, j;
    for (k = 0; k < N - 1; ++k) {
        double *D = disc + (size_t)k * N_DISC;
        const double *aug = ws->aug;
        if (pdg_foh_interval(x + NX * k, u + NU * k, u + NU * (k + 1), t_f, dtau, ws->pvec,
                             steps, ws->aug, D + D_Z, ws->augw) != 0) {
            return -1;
        }
        for (i = 0; i < NX; ++i) {
            D[D_XN + i] = aug[PDG_AUG_X + i];
            D[D_S + i] = aug[PDG_AUG_S + i];
            for (j = 0; j < NX; ++j) {
                D[D_A + NX * i + j] = aug[PDG_AUG_A + NX * j + i];
            }
            for (j = 0; j < NU; ++j) {
                D[D_BM + NU * i + j] = aug[PDG_AUG_BM + NX * j + i];
                D[D_BP + NU * i + j] = aug[PDG_AUG_BP + NX * j + i];
            }
        }
    }
    return 0;
}

/* h (N x 7) in each constraint's own units (guidance/constraints.py). */
static void path_values(const pdg_workspace *ws, const double *x, const double *u, double *h)
{
    const pdg_params *p = &ws->scn.params;
    const double tg = pdg_tan_glideslope(p), qm = pdg_tilt_q_max(p), wm = pdg_omega_max(p);
    const double cg = pdg_cos_gimbal(p);
    int k;
    for (k = 0; k < ws->N; ++k) {
        const double *xk = x + NX * k, *uk = u + NU * k;
        const double T = sqrt(uk[0] * uk[0] + uk[1] * uk[1] + uk[2] * uk[2]);
        double *hk = h + NC * k;
        hk[0] = p->m_dry - xk[IM];
        hk[1] = tg * sqrt(xk[1] * xk[1] + xk[2] * xk[2]) - xk[0];
        hk[2] = sqrt(xk[8] * xk[8] + xk[9] * xk[9]) - qm;
        hk[3] = sqrt(xk[10] * xk[10] + xk[11] * xk[11] + xk[12] * xk[12]) - wm;
        hk[4] = T - p->T_max;
        hk[5] = cg * T - uk[0];
        hk[6] = p->T_min - T;
    }
}

/* J on the full constraint set; the largest defect and path-constraint value. */
static double penalty(pdg_workspace *ws, const double *x, const double *u, const double *disc,
                      double *h, double *defect, double *viol)
{
    const double *Sx = ws->sc.Sx;
    double blocks = 0.0, vsum = 0.0, dmax = 0.0, hmax = -INFINITY;
    int k, i;
    for (k = 0; k < ws->N - 1; ++k) {
        double d[NX];
        for (i = 0; i < NX; ++i) {
            const double di = x[NX * (k + 1) + i] - disc[(size_t)k * N_DISC + D_XN + i];
            dmax = fabs(di) > dmax ? fabs(di) : dmax;
            d[i] = di / Sx[i];
        }
        for (i = 0; i < N_TR_SCALAR; ++i) {
            blocks += fabs(d[pdg_tr_scalar_states[i]]);
        }
        for (i = 0; i < N_TR_PAIRS; ++i) {
            blocks += pdg_hypot(d[pdg_tr_pairs[i][0]], d[pdg_tr_pairs[i][1]]);
        }
    }
    path_values(ws, x, u, h);
    for (k = 0; k < ws->N * NC; ++k) {
        vsum += (h[k] > 0.0 ? h[k] : 0.0) / ws->scales[k % NC];
        hmax = h[k] > hmax ? h[k] : hmax;
    }
    *defect = dmax;
    *viol = hmax;
    return -(x[NX * (ws->N - 1) + IM] - ws->sc.cx[IM]) / Sx[IM] + ws->st.lam * (blocks + vsum);
}

/* Tight labels (7N): slack <= tol max(1, scale) or multiplier >= TIGHT_DUAL_TOL. */
static int label_tight(pdg_workspace *ws, const double *h, const unsigned char *keep,
                       unsigned char *tight)
{
    static const int soc_off[6] = {0, 0, 3, 6, 10, 14};
    int k, c, count = 0;
    for (k = 0; k < ws->N; ++k) {
        for (c = 0; c < NC; ++c) {
            const double scale = ws->scales[c] > 1.0 ? ws->scales[c] : 1.0;
            double dual = 0.0;
            int t;
            if (!keep || keep[NC * k + c]) {
                if (c == 0) {
                    dual = ws->zdual[ws->g_mass + k];
                } else if (c == 6) {
                    dual = ws->zdual[ws->g_tmin + k];
                } else {
                    dual = ws->zdual[ws->g_soc + 18 * k + soc_off[c]];
                }
            }
            t = (-h[NC * k + c] <= ws->st.tight_tol * scale) || dual >= TIGHT_DUAL_TOL;
            tight[NC * k + c] = (unsigned char)t;
            count += t;
        }
    }
    return count;
}

/* retry_radius: a radius more than RETRY_MARGIN above the rejected step counts as holding it
 * and is skipped (one within the margin is solved: the safe side); at most RETRY_SKIP_MAX are
 * skipped (a bound for alpha near 1) */
#define RETRY_MARGIN 1.001
#define RETRY_SKIP_MAX 64
/* The IPM of a retry starts from the rejected answer with its trajectory part pulled back
 * towards the reference, to RETRY_START of the new radius, where the retry's answer lies
 * (guidance/scvx.py RETRY_START) */
#define RETRY_START 0.99

/* z_new's trajectory part := z + f (z_new - z); the rest of the answer stays */
static void pull_back(pdg_workspace *ws, double f)
{
    int i;
    for (i = 0; i < ws->lay.n_traj; ++i) {
        ws->znew[i] = ws->z[i] + f * (ws->znew[i] - ws->z[i]);
    }
}

/* |z_new - z| in the trust region's norm: the largest |difference| of a scalar component
 * (states, thrust, sigma) and 2-norm of a rotation pair of states (guidance/subproblem.py). */
static double trust_norm_step(const pdg_workspace *ws)
{
    const pdg_layout *L = &ws->lay;
    double r = 0.0;
    int k, i;
    for (i = L->iu; i < L->n_traj; ++i) { /* thrust and sigma */
        const double d = fabs(ws->znew[i] - ws->z[i]);
        r = d > r ? d : r;
    }
    for (k = 0; k < ws->N; ++k) {
        const double *zn = ws->znew + L->ix + NX * k, *zr = ws->z + L->ix + NX * k;
        for (i = 0; i < N_TR_SCALAR; ++i) {
            const double d = fabs(zn[pdg_tr_scalar_states[i]] - zr[pdg_tr_scalar_states[i]]);
            r = d > r ? d : r;
        }
        for (i = 0; i < N_TR_PAIRS; ++i) {
            const int a = pdg_tr_pairs[i][0], b = pdg_tr_pairs[i][1];
            const double d = pdg_hypot(zn[a] - zr[a], zn[b] - zr[b]);
            r = d > r ? d : r;
        }
    }
    return r;
}

/* The radius after a rejection. The retry has the same reference and data, only a smaller
 * radius: every radius eta / alpha^j that still holds the rejected step (tr_step, with a
 * margin for the solver's tolerance) gives the same step back and is rejected again, so
 * those solves are skipped. Eq. (15)'s radius sequence is unchanged. */
static double retry_radius(const pdg_settings *st, double eta, double tr_step)
{
    int j;
    eta = eta / st->alpha;
    for (j = 0; j < RETRY_SKIP_MAX && eta > st->eta_lb && eta > RETRY_MARGIN * tr_step; ++j) {
        eta = eta / st->alpha;
    }
    return eta > st->eta_lb ? eta : st->eta_lb;
}

/* The radius after a guard rejection of a step rho rejected too (judge; guidance/scvx.py
 * _guard_radius) */
static double guard_radius(const pdg_settings *st, double eta)
{
    eta = eta / st->alpha;
    return eta > st->eta_lb ? eta : st->eta_lb;
}

static double trust_update(const pdg_settings *st, double eta, double rho, int accepted,
                           double tr_step, int use_tau, double tau_r)
{
    const double shrink = use_tau ? pow(st->alpha, tau_r) : st->alpha;
    const double grow = use_tau ? pow(st->beta, 1.0 - tau_r) : st->beta;
    if (!accepted) {
        eta = retry_radius(st, eta, tr_step); /* a rejection always contracts */
    } else if (rho < st->rho1) {
        eta = eta / shrink;
    } else if (rho >= st->rho2) {
        eta = eta * grow;
    }
    eta = eta > st->eta_lb ? eta : st->eta_lb;
    return eta < st->eta_ub ? eta : st->eta_ub;
}

/* assemble() found an entry of the map dest outside A and G (an upset during the call) */
#define ASSEMBLE_MAP_DAMAGED (-2)
/* solve_subproblem's answer for it: no SOCP status */
#define SST_MAP_DAMAGED (-1000)
/* solve_subproblem's answer when the clock callback set the workspace up again or wrote over
 * it (callback_kept): no SOCP status, nothing read or written after */
#define SST_LOST (-1001)

/* Assembles the subproblem about the scaled iterate z and hands its numbers to the SOCP;
 * polish: the polish's objective (no fuel term, P = PDG_POLISH_WEIGHT I; needs prox_u > 0).
 * Returns 0, -1 if the SOCP refused the numbers, or ASSEMBLE_MAP_DAMAGED. */
static int assemble(pdg_workspace *ws, const double *z, const double *disc,
                    const unsigned char *keep, double eta, int polish)
{
    pdg_emitter em;
    pdg_values v;
    int e;
    em.mode = 2;
    em.cnt = 0;
    em.p = ws->p;
    em.phi_a = ws->phi_a;
    em.dest = ws->dest;
    em.Ax = ws->Ax;
    em.Gx = ws->Gx;
    em.nnz_A = ws->nnz_A;
    em.nnz = ws->nnz_A + ws->nnz_G;
    em.bad_slot = 0;
    v.scn = &ws->scn;
    v.sc = &ws->sc;
    v.disc = disc;
    v.zref = z;
    v.keep = keep;
    v.eta = eta;
    v.lam = ws->st.lam;
    v.prox_u = polish ? PDG_POLISH_WEIGHT : ws->st.prox_u;
    v.fuel = polish ? 0.0 : 1.0;
    if (ws->st.prox_u > 0.0) {
        for (e = 0; e < ws->N * NU; ++e) {
            ws->Px[e] = v.prox_u;
        }
    }
    v.b = ws->b;
    v.h = ws->h;
    v.c = ws->c;
    pdg_emit(&em, &ws->lay, ws->roll_free, &v);
    if (em.bad_slot) {
        return ASSEMBLE_MAP_DAMAGED;
    }
    /* every part, the constant P included: a part left out would come back from its scaled
     * copy with a rounding error, and the solve would depend on the solves before it */
    return tscvx_update_data(ws->socp, ws->Px, ws->c, ws->Ax, ws->b, ws->Gx, ws->h) ==
                   TSCVX_SETUP_OK
               ? 0
               : -1;
}

static void prepare_scenario(pdg_workspace *ws, const pdg_scenario *s, double t_f_guess)
{
    const pdg_params *p = &s->params;
    ws->scn = *s;
    pdg_param_vector(p, ws->pvec);
    pdg_scaling_init(&ws->sc, s, t_f_guess);
    ws->scales[0] = ws->sc.Sx[IM];
    ws->scales[1] = ws->sc.Sx[0];
    ws->scales[2] = 1.0;
    ws->scales[3] = pdg_omega_max(p);
    ws->scales[4] = ws->scales[5] = ws->scales[6] = ws->sc.Su;
}

int pdg_check_workspace_scenario(const pdg_workspace *ws, const pdg_scenario *s, char *msg)
{
    if (pdg_check_scenario(s, msg)) {
        return 1;
    }
    if (s->params.N != ws->N) {
        snprintf(msg, PDG_MESSAGE_LEN,
                 "scenario field 'N': the workspace was set up for N = %d, got %d", ws->N,
                 s->params.N);
        return 1;
    }
    if ((s->params.final_roll_free ? 1 : 0) != ws->roll_free) {
        snprintf(msg, PDG_MESSAGE_LEN,
                 "scenario field 'final_roll_free': the workspace was set up for %s",
                 ws->roll_free ? "true" : "false");
        return 1;
    }
    {
        double pvec[PDG_NP];
        pdg_param_vector(&s->params, pvec);
        if (pdg_phi_a_pattern(pvec, NULL) != ws->phi_a) {
            snprintf(msg, PDG_MESSAGE_LEN,
                     "scenario field 'r_cp_B': the workspace was set up for a vehicle with r_cp_B "
                     "%s zero (another structure of the dynamics' Jacobian)",
                     s->params.r_cp_B[0] == 0.0 && s->params.r_cp_B[1] == 0.0 &&
                             s->params.r_cp_B[2] == 0.0
                         ? "not"
                         : "all");
            return 1;
        }
    }
    return 0;
}

static const char *const state_names[NX] = {"r1", "r2", "r3", "v1", "v2", "v3", "q0",
                                            "q1", "q2", "q3", "w1", "w2", "w3", "m"};

/* Why the iteration limit was hit (guidance/scvx.py _diagnose, not_converged_reason,
 * infeasible_reason and stalled_reason: the same words). Whatever the numbers, the text fits
 * msg: the longest, built by tests/test_scvx_termination.py from the widest value of each
 * field (eta_lb and vc_tol at a three-digit exponent, vc and the defect negative at one, k =
 * iter_max's bound 100, interval PDG_N_MAX - 2), is 246 characters of PDG_MESSAGE_LEN - 1 =
 * 255. */
static pdg_status diagnose(pdg_workspace *ws, double vc, double defect, double viol,
                           int iterations, int stalled, char *msg)
{
    const pdg_settings *st = &ws->st;
    double best = -1.0;
    int k, i, bk = 0, bi = 0, len = 0, written;
    if (stalled) { /* the same prefix on both verdicts, as guidance/scvx.py */
        len = snprintf(msg, PDG_MESSAGE_LEN, "step rejected at the smallest trust radius %g; ",
                       st->eta_lb);
        if (len < 0 || len >= PDG_MESSAGE_LEN) {
            len = 0;
        }
    }
    if (vc <= st->vc_tol) {
        snprintf(msg + len, (size_t)(PDG_MESSAGE_LEN - len),
                 "not converged after %d iterations; virtual control is zero (the "
                 "linearized dynamics are met), largest nonlinear defect %.2e, largest "
                 "path-constraint value %.2e",
                 iterations, defect, viol);
        return PDG_MAX_ITERATIONS;
    }
    for (k = 0; k < ws->N - 1; ++k) { /* disc holds the current iterate's discretization */
        for (i = 0; i < NX; ++i) {
            const double r =
                fabs((ws->x[NX * (k + 1) + i] - ws->disc[(size_t)k * N_DISC + D_XN + i]) /
                     ws->sc.Sx[i]);
            if (r > best) {
                best = r;
                bk = k;
                bi = i;
            }
        }
    }
    written = snprintf(msg + len, (size_t)(PDG_MESSAGE_LEN - len),
                       "virtual control %.3g > %g after %d iterations; largest defect %.3g at "
                       "interval %d, state %s",
                       vc, st->vc_tol, iterations, defect, bk, state_names[bi]);
    len = written > 0 ? len + written : PDG_MESSAGE_LEN;
    if (len < PDG_MESSAGE_LEN &&
        ws->x[NX * (ws->N - 1) + IM] <= ws->scn.params.m_dry + 1e-6 * ws->sc.Sx[IM]) {
        snprintf(msg + len, (size_t)(PDG_MESSAGE_LEN - len),
                 "; mass at the floor: not enough fuel, or no landing within the constraints");
    }
    return PDG_INFEASIBLE;
}

/* After every return from a callback (mask_fn, clock_s): 1 when the running solve still
 * holds the workspace, 0 when the callback set it up again (pdg_setup over its arena) or
 * wrote over it: no mark, or no longer busy. Two loads and two compares; the checksum is the
 * end check's and the next call's. After 0, the solve writes nothing more into the arena (it
 * is no longer this solve's) and stops (callback_lost). */
static int callback_kept(const pdg_workspace *ws)
{
    return ws->magic == PDG_WS_MAGIC && ws->busy;
}

/* The reason of a solve stopped by callback_kept: `which` callback, at iteration k. */
static void callback_lost(char *msg, const char *which, int k)
{
    snprintf(msg, PDG_MESSAGE_LEN,
             "%s of iteration %d set the workspace up again or wrote over its arena: the "
             "solve stops, its record lost (set the workspace up again)",
             which, k);
}

/* 1: ws->mask holds iteration k's mask; 0: the full problem; -1: the callback answered
 * neither (its answer in *answer), which stops the solve; -2: the callback set the workspace
 * up again or wrote over it (callback_kept), which stops it too. */
static int mask_for(pdg_workspace *ws, const pdg_options *o, int k, int *answer)
{
    const int n = NC * ws->N;
    int i;
    if (o->masks) {
        const int r = (k < o->n_masks ? k : o->n_masks) - 1;
        for (i = 0; i < n; ++i) {
            ws->mask[i] = o->masks[(size_t)r * n + i] ? 1 : 0;
        }
        return 1;
    }
    if (o->mask_fn) {
        *answer = o->mask_fn(o->mask_ctx, k, ws->mask, n);
        if (!callback_kept(ws)) {
            return -2;
        }
        if (*answer != 0 && *answer != 1) {
            return -1; /* an error code, not a mask: whatever the buffer holds is not used */
        }
        if (!*answer) {
            return 0;
        }
        for (i = 0; i < n; ++i) {
            ws->mask[i] = ws->mask[i] ? 1 : 0;
        }
        return 1;
    }
    return 0;
}

/* ---- Algorithm 1 / 2 --------------------------------------------------------------------- */

/* The candidate z_new of one subproblem, evaluated on the FULL constraint set. */
typedef struct {
    double t_f;       /* physical t_f of z_new */
    double J;         /* penalty J(z_new) */
    double defect;    /* largest nonlinear defect (physical units) */
    double viol;      /* largest path-constraint value */
    double L;         /* predicted cost: the subproblem objective */
    double vc;        /* virtual control + buffers, max(sum, 0) */
    double step;      /* |z_new - z|_inf over the trajectory variables */
    double tr_step;   /* |z_new - z| in the trust region's norm (retry_radius) */
    int n_tight;
} candidate;

/* Checks the call and the scenario, takes the guess, sets the scaling and evaluates J at the
 * guess. Returns PDG_SOLVED to go on, otherwise the status to return. */
static pdg_status start(pdg_workspace *ws, const pdg_scenario *scn, const pdg_options *opt,
                        pdg_result *res, double *J, double *defect, double *viol)
{
    const int N = ws->N;
    double t_f;
    if (!res->x || !res->u) {
        snprintf(res->message, PDG_MESSAGE_LEN, "result arrays x and u must be given");
        return PDG_INVALID_INPUT;
    }
    if (pdg_check_workspace_scenario(ws, scn, res->message)) {
        return PDG_INVALID_INPUT;
    }
    if (opt->masks && opt->n_masks < 1) {
        snprintf(res->message, PDG_MESSAGE_LEN, "masks: n_masks must be at least 1");
        return PDG_INVALID_INPUT;
    }
    if (opt->masks && opt->mask_fn) { /* one would be ignored without a word */
        snprintf(res->message, PDG_MESSAGE_LEN, "masks: give a table or a callback, not both");
        return PDG_INVALID_INPUT;
    }
    if ((opt->guess_x != NULL) != (opt->guess_u != NULL)) {
        snprintf(res->message, PDG_MESSAGE_LEN, "guess: give x, u and t_f together");
        return PDG_INVALID_INPUT;
    }
    if (opt->guess_x) { /* used as given, as the reference's solve(guess=...) does */
        if (!pdg_all_finite(opt->guess_x, (size_t)N * NX) ||
            !pdg_all_finite(opt->guess_u, (size_t)N * NU) || !isfinite(opt->guess_t_f) ||
            !(opt->guess_t_f > 0.0)) {
            snprintf(res->message, PDG_MESSAGE_LEN,
                     "guess: x, u and t_f must be finite and t_f positive");
            return PDG_INVALID_INPUT;
        }
        memcpy(ws->x, opt->guess_x, sizeof(double) * (size_t)N * NX);
        memcpy(ws->u, opt->guess_u, sizeof(double) * (size_t)N * NU);
        t_f = opt->guess_t_f;
    } else {
        pdg_initial_guess(scn, ws->x, ws->u, &t_f, ws->gwork);
    }
    prepare_scenario(ws, scn, t_f);
    to_scaled(ws, ws->x, ws->u, t_f, ws->z);
    to_physical(ws, ws->z, ws->x, ws->u, &t_f);
    memset(ws->forced, 0, (size_t)N * NC);
    if (discretize(ws, ws->x, ws->u, t_f, ws->disc) != 0) {
        snprintf(res->message, PDG_MESSAGE_LEN, "model evaluation failed at the initial guess");
        return PDG_SOLVER_ERROR;
    }
    *J = penalty(ws, ws->x, ws->u, ws->disc, ws->hval, defect, viol);
    return PDG_SOLVED;
}

/* Discretizes about z_new and evaluates it: J, defects, predicted cost L, virtual control,
 * step and tight labels (paper Eq. (12), (13)). Returns 0, or -1 if the model fails. */
static int evaluate(pdg_workspace *ws, const unsigned char *keep, candidate *cd)
{
    const pdg_layout *L = &ws->lay;
    double sum = 0.0;
    int i;
    to_physical(ws, ws->znew, ws->xn, ws->un, &cd->t_f);
    if (discretize(ws, ws->xn, ws->un, cd->t_f, ws->disc_new) != 0) {
        return -1;
    }
    cd->J = penalty(ws, ws->xn, ws->un, ws->disc_new, ws->hval, &cd->defect, &cd->viol);
    for (i = L->ivc; i < L->n; ++i) {
        sum += ws->znew[i];
    }
    cd->L = -ws->znew[L->ix + NX * (ws->N - 1) + IM] + ws->st.lam * sum;
    cd->vc = sum > 0.0 ? sum : 0.0;
    cd->step = 0.0;
    for (i = 0; i < L->n_traj; ++i) {
        const double d = fabs(ws->znew[i] - ws->z[i]);
        cd->step = d > cd->step ? d : cd->step;
    }
    cd->tr_step = trust_norm_step(ws);
    cd->n_tight = label_tight(ws, ws->hval, keep, ws->tight);
    return 0;
}

/* The candidate becomes the iterate (its discretization is kept for the next subproblem). */
static void take_candidate(pdg_workspace *ws)
{
    double *swap = ws->disc;
    memcpy(ws->z, ws->znew, sizeof(double) * (size_t)ws->lay.n);
    memcpy(ws->x, ws->xn, sizeof(double) * (size_t)ws->N * NX);
    memcpy(ws->u, ws->un, sizeof(double) * (size_t)ws->N * NU);
    ws->disc = ws->disc_new;
    ws->disc_new = swap;
}

/* ... as succession k, its tight labels recorded */
static void accept(pdg_workspace *ws, int k)
{
    const size_t n_mask = (size_t)NC * ws->N;
    memcpy(ws->masks_out + (size_t)k * n_mask, ws->tight, n_mask);
    take_candidate(ws);
}

/* Puts back (forces) every constraint the subproblem dropped that the candidate violates;
 * returns the number put back. T_min is always kept (its buffer is penalized instead). */
static int put_back_dropped(pdg_workspace *ws)
{
    int i, dropped = 0;
    for (i = 0; i < NC * ws->N; ++i) {
        if (ws->hval[i] > ws->st.defect_tol && !ws->keep[i]) {
            ws->forced[i] = 1;
            dropped++;
        }
    }
    return dropped;
}

/* tau_r of Algorithm 2 (step 4): the fraction of bits in which the predicted masks of
 * successions k+1 (pred) and k (prev_mask, kept from the last accepted step) differ. */
static double changed_fraction(const pdg_workspace *ws)
{
    int i, changed = 0;
    for (i = 0; i < NC * ws->N; ++i) {
        changed += ws->prev_mask[i] != ws->pred[i];
    }
    return (double)changed / (NC * ws->N);
}

static void failed_row(pdg_log_row *r, double J)
{
    r->J = J;
    r->dJ = r->dL = r->rho = r->vc_norm1 = NAN;
    r->n_tight = 0;
    r->accepted = 0;
}

/* What Algorithm 1 carries from one subproblem to the next. */
typedef struct {
    int k;             /* successions (accepted steps); a rejection retries the same k */
    double eta;        /* trust radius of the next subproblem */
    double J;          /* penalty J at the iterate z */
    double defect;     /* its largest nonlinear defect */
    double viol;       /* its largest path-constraint value */
    double vc;         /* virtual control + buffers of the last candidate */
    int have_masks;    /* T-SCvx: the caller gives masks */
    int prev_has_mask; /* the last accepted subproblem was masked (tau_r compares with it) */
    int have_solution; /* a subproblem solution to warm-start the next IPM from */
    int stalled;       /* rejected at the smallest radius: the same subproblem forever */
    int spent;         /* the IPM iteration budget (socp_max_iter_total) is spent */
    int polishing;     /* the next subproblem is the polish (pdg_settings.polish) */
    int lost;          /* a callback set the workspace up again or wrote over it */
    int damaged;       /* what set-up fixed changed during the call: no answer */
} scvx_state;

/* Step 1 (T-SCvx): the caller's mask for iteration k + 1 plus what the full-constraint guard
 * put back, into ws->keep (T_min always kept). Returns 1 with a mask, 0 for the full
 * problem, -1 (message written) when the callback answered neither. */
static int iteration_mask(pdg_workspace *ws, const pdg_options *opt, const scvx_state *s,
                          double *tau_r, char *msg)
{
    int answer = 0, i;
    const int has_mask = s->have_masks ? mask_for(ws, opt, s->k + 1, &answer) : 0;
    if (has_mask == -2) {
        callback_lost(msg, "masks: the mask callback", s->k + 1);
        return -2;
    }
    if (has_mask < 0) {
        snprintf(msg, PDG_MESSAGE_LEN,
                 "masks: the mask callback answered %d for iteration %d (1: it wrote a "
                 "mask, 0: the full problem); the solve stops at its last accepted step",
                 answer, s->k + 1);
        return -1;
    }
    if (has_mask) {
        memcpy(ws->pred, ws->mask, (size_t)NC * ws->N);
        if (s->prev_has_mask) {
            *tau_r = changed_fraction(ws);
        }
        for (i = 0; i < NC * ws->N; ++i) {
            ws->mask[i] |= ws->forced[i];
            ws->keep[i] = (i % NC == 6) ? 1 : ws->mask[i]; /* T_min always kept */
        }
    }
    return has_mask;
}

/* The IPM iteration limit of the next subproblem under the call's budget (guidance/scvx.py
 * iteration_cap): what is left of socp_max_iter_total, half of it when warm-started (the
 * runtime runs a failed warm start again cold, with the same limit), socp_max_iter at most.
 * *warm is cleared when a single iteration is left. 0: the budget is spent. */
static int iteration_cap(const pdg_settings *st, int used, int *warm)
{
    const int left = st->socp_max_iter_total - used;
    int cap;
    if (left <= 0) {
        return 0;
    }
    *warm = *warm && left >= 2;
    cap = *warm ? left / 2 : left;
    return cap < st->socp_max_iter ? cap : st->socp_max_iter;
}

/* The SOCP runtime's iteration limit set to cap, its tolerances to the polish's or the
 * settings' (the other settings as at set-up). */
static int set_socp_limits(pdg_workspace *ws, int cap, int polish)
{
    tscvx_settings ts;
    tscvx_info info;
    if (cap == ws->socp_cap && polish == ws->socp_polish) {
        return 0;
    }
    socp_settings(&ws->st, &ts);
    if (tscvx_get_info(ws->socp, &info) != TSCVX_SETUP_OK) {
        return -1;
    }
    ts.kkt_backend = info.kkt_backend; /* the method set-up chose (structural) */
    ts.max_iter = cap;
    if (polish) {
        ts.tol_gap_abs = ts.tol_gap_rel = ts.tol_feas = ws->st.socp_tol * PDG_POLISH_TOL_FACTOR;
    }
    if (tscvx_update_settings(ws->socp, &ts) != TSCVX_SETUP_OK) {
        return -1;
    }
    ws->socp_cap = cap;
    ws->socp_polish = polish;
    return 0;
}

/* The clock's reading (0 without options.clock_s); *kept cleared when the callback set the
 * workspace up again or wrote over it (callback_kept). */
static double read_clock(const pdg_workspace *ws, const pdg_options *opt, int *kept)
{
    double t;
    if (!opt->clock_s) {
        return 0.0;
    }
    t = opt->clock_s();
    *kept = *kept && callback_kept(ws);
    return t;
}

/* Step 2: the convex subproblem about z with radius eta, solved by the SOCP runtime into
 * ws->znew and its duals, in at most cap IPM iterations (iteration_cap). Starts the log row
 * (the time is the conic solve's alone, as in the Python reference's log). Returns the SOCP
 * status (TSCVX_INVALID_INPUT if assembly failed, SST_MAP_DAMAGED if the map was, SST_LOST
 * with s->lost set if the clock callback took the workspace). */
static int solve_subproblem(pdg_workspace *ws, const pdg_options *opt,
                            const unsigned char *keep, scvx_state *s, pdg_log_row *r,
                            pdg_result *res)
{
    tscvx_info info;
    double t_solve = 0.0;
    int sst = TSCVX_INVALID_INPUT;
    /* from the last subproblem's solution, accepted or not: the subproblems of a solve
     * differ by one linearization or one radius (tscvx_warm_start) */
    int warm = s->have_solution && ws->st.socp_warm_start;
    const int cap = iteration_cap(&ws->st, res->socp_iterations, &warm);
    int assembled = -1, kept = 1;
    if (set_socp_limits(ws, cap, s->polishing) == 0 &&
        (assembled = assemble(ws, ws->z, ws->disc, keep, s->eta, s->polishing)) == 0) {
        const double t0 = read_clock(ws, opt, &kept);
        if (kept) {
            if (warm) { /* a start the runtime refuses leaves its cold start: nothing lost */
                (void)tscvx_warm_start(ws->socp, ws->znew, ws->ydual, ws->zdual, ws->slack);
            }
            sst = (int)tscvx_solve(ws->socp);
            t_solve = read_clock(ws, opt, &kept) - t0;
        }
        if (!kept) {
            s->lost = 1;
            return SST_LOST;
        }
    }
    if (tscvx_get_info(ws->socp, &info) != TSCVX_SETUP_OK) { /* the SOCP workspace damaged */
        memset(&info, 0, sizeof info);
        sst = TSCVX_INVALID_INPUT;
    }
    memset(r, 0, sizeof *r);
    r->subproblem_time_s = t_solve;
    r->k = s->k + 1;
    r->eta = s->eta;
    r->solver_status = sst;
    /* The IPM iterations the solve ran, whatever its outcome: assemble's data update zeroed
     * the count, so a solve refused at its start counts none, and one whose end check found
     * the SOCP workspace damaged (TSCVX_INVALID_INPUT, its head intact) counts those it ran.
     * A warm start that failed and was run again cold counts both runs. */
    r->solver_iterations = assembled == 0 ? info.iterations + info.restart_iterations : 0;
    res->socp_iterations += r->solver_iterations;
    if ((sst == TSCVX_SOLVED || sst == TSCVX_SOLVED_INACCURATE) &&
        tscvx_get_solution(ws->socp, ws->znew, ws->ydual, ws->zdual, ws->slack) !=
            TSCVX_SETUP_OK) {
        sst = TSCVX_INVALID_INPUT; /* no answer to read: as a failed solve */
    }
    if (sst == TSCVX_SOLVED || sst == TSCVX_SOLVED_INACCURATE) {
        s->have_solution = 1;
    }
    return assembled == ASSEMBLE_MAP_DAMAGED ? SST_MAP_DAMAGED : sst;
}

/* Step 4: rho = actual / predicted change, acceptance and the next radius, Eq. (15), into the
 * log row; the full-constraint guard of T-SCvx may overrule. Returns the next radius. */
static double judge(pdg_workspace *ws, const scvx_state *s, const candidate *cd, int has_mask,
                    double tau_r, pdg_log_row *r)
{
    const pdg_settings *st = &ws->st;
    const double dJ = s->J - cd->J, dL = s->J - cd->L;
    const double rho = dL != 0.0 ? dJ / dL : (double)NAN;
    /* dL <= 0 only when the subproblem gives the reference back (to the solver's tolerance);
     * Algorithm 1 stops there (dJ = 0), here the step is accepted with rho = 1 and the
     * convergence test decides (as the Python reference) */
    int accepted = dJ == 0.0 || dL <= 0.0 || rho >= st->rho0;
    double eta_new = trust_update(st, s->eta, dL > 0 ? rho : 1.0, accepted, cd->tr_step,
                                  s->have_masks && st->tau_r_update, tau_r);
    /* Full-constraint guard: a candidate that violates a constraint the mask dropped is
     * rejected and the constraint put back for the rest of the solve; the retry starts from
     * the same reference (which meets every convex constraint, so the subproblem stays
     * feasible). A step rho accepted is retried at the same radius (the mask failed, not the
     * linearization); one rho rejected too at the radius contracted by alpha, as step 5 of
     * Algorithm 2 rejects it: at the same radius the retry was mostly rejected again
     * (guidance/scvx.py _judge). retry_radius's skipping does not apply: the retry has
     * another constraint. */
    const int restored = has_mask ? put_back_dropped(ws) : 0;
    if (restored > 0) {
        eta_new = accepted ? s->eta : guard_radius(st, s->eta);
        accepted = 0;
    }
    r->J = cd->J;
    r->dJ = dJ;
    r->dL = dL;
    r->rho = rho;
    r->vc_norm1 = cd->vc;
    r->n_tight = cd->n_tight;
    r->accepted = accepted;
    r->restored = restored;
    return eta_new;
}

/* The candidate becomes the iterate: succession k + 1. */
static void succeed(pdg_workspace *ws, scvx_state *s, const candidate *cd, int has_mask)
{
    s->prev_has_mask = has_mask;
    if (has_mask) {
        memcpy(ws->prev_mask, ws->pred, (size_t)NC * ws->N);
    }
    accept(ws, s->k);
    ws->n_masks_out = ++s->k;
    s->J = cd->J;
    s->defect = cd->defect;
    s->viol = cd->viol;
}

/* The call's IPM iteration budget is spent: the result is the last accepted iterate. */
static void budget_spent(const pdg_workspace *ws, scvx_state *s, pdg_result *res,
                         pdg_status *status)
{
    *status = PDG_MAX_ITERATIONS;
    s->spent = 1;
    /* fewer used than the budget: the last subproblem ran out of its share (half of what
     * was left when warm-started), and what is left would not solve one */
    snprintf(res->message, PDG_MESSAGE_LEN,
             "IPM iteration budget spent (%d of socp_max_iter_total = %d%s) after %d "
             "iterations; the last accepted iterate has largest nonlinear defect %.2e, largest "
             "path-constraint value %.2e",
             res->socp_iterations, ws->st.socp_max_iter_total,
             res->socp_iterations < ws->st.socp_max_iter_total
                 ? "; the last subproblem stopped at its share"
                 : "",
             s->k, s->defect, s->viol);
}

/* The convergence test: the candidate's step within step_tol, or the change of J it made
 * (dJ, accepted steps only; INFINITY otherwise) within cost_tol (paper Algorithm 1: while
 * dJ > eps_tol); its virtual control within vc_tol; the iterate (the candidate when
 * accepted) within defect_tol. */
static int converged(const pdg_settings *st, const scvx_state *s, const candidate *cd,
                     double dJ)
{
    return (cd->step <= st->step_tol || fabs(dJ) <= st->cost_tol) && s->vc <= st->vc_tol &&
           s->defect <= st->defect_tol && s->viol <= st->defect_tol;
}

/* One subproblem of Algorithm 1 (Algorithm 2 with masks). Returns 1 to go on; 0 to stop,
 * with the status in *status (PDG_MAX_ITERATIONS when stalled, for diagnose). */
static int scvx_iteration(pdg_workspace *ws, const pdg_options *opt, scvx_state *s,
                          pdg_result *res, pdg_status *status)
{
    const pdg_settings *st = &ws->st;
    pdg_log_row *r = &ws->log[ws->n_log++];
    double tau_r = 0.0, eta_new;
    candidate cd;
    int sst;
    if (res->socp_iterations >= st->socp_max_iter_total) {
        ws->n_log--;
        budget_spent(ws, s, res, status);
        return 0;
    }
    const int has_mask = iteration_mask(ws, opt, s, &tau_r, res->message);
    if (has_mask == -2) { /* nothing of the workspace is this solve's any more */
        s->lost = 1;
        *status = PDG_INVALID_INPUT;
        return 0;
    }
    if (has_mask < 0) {
        ws->n_log--;
        *status = PDG_INVALID_INPUT;
        return 0;
    }
    sst = solve_subproblem(ws, opt, has_mask ? ws->keep : NULL, s, r, res);
    if (sst == SST_LOST) { /* as the mask callback's (has_mask == -2) */
        callback_lost(res->message, "the clock callback", s->k + 1);
        *status = PDG_INVALID_INPUT;
        return 0;
    }
    if (sst == SST_MAP_DAMAGED) { /* nothing of this workspace can be trusted any more */
        failed_row(r, s->J);
        s->damaged = 1;
        *status = PDG_SOLVER_ERROR;
        snprintf(res->message, PDG_MESSAGE_LEN,
                 "subproblem at iteration %d: the workspace was damaged during the solve (its "
                 "map of the subproblem into A and G points outside them): set it up again",
                 s->k + 1);
        return 0;
    }
    if (sst == TSCVX_MAX_ITER && ws->socp_cap < st->socp_max_iter) {
        failed_row(r, s->J); /* stopped at its share of the budget */
        budget_spent(ws, s, res, status);
        return 0;
    }
    if (sst != TSCVX_SOLVED && sst != TSCVX_SOLVED_INACCURATE) {
        char why[TSCVX_MESSAGE_LEN];
        failed_row(r, s->J);
        *status = PDG_SOLVER_ERROR;
        if (sst == TSCVX_INVALID_INPUT &&
            tscvx_check_workspace(ws->socp, why) != TSCVX_SETUP_OK) { /* refused: why */
            snprintf(res->message, PDG_MESSAGE_LEN,
                     "subproblem at iteration %d: conic solver returned %s: %s", s->k + 1,
                     socp_status_name(sst), why);
        } else {
            snprintf(res->message, PDG_MESSAGE_LEN,
                     "subproblem at iteration %d: conic solver returned %s", s->k + 1,
                     socp_status_name(sst));
        }
        return 0;
    }
    /* step 3: the candidate on the full nonlinear problem */
    if (evaluate(ws, has_mask ? ws->keep : NULL, &cd) != 0) {
        failed_row(r, s->J);
        *status = PDG_SOLVER_ERROR;
        snprintf(res->message, PDG_MESSAGE_LEN,
                 "iteration %d: model evaluation failed at the subproblem solution", s->k + 1);
        return 0;
    }
    s->vc = cd.vc;
    eta_new = judge(ws, s, &cd, has_mask, tau_r, r);
    if (r->accepted) {
        succeed(ws, s, &cd, has_mask);
    }
    /* step 5: convergence on the FULL constraint set; T-SCvx never returns what it rejects */
    if (r->accepted && converged(st, s, &cd, r->dJ)) {
        *status = PDG_SOLVED;
        /* a step longer than step_tol that changed J by at most cost_tol: a creep along a
         * flat valley of J (guidance/scvx.py CONVERGED_ON_COST) */
        snprintf(res->message, PDG_MESSAGE_LEN, "%s",
                 cd.step <= st->step_tol
                     ? "converged"
                     : "converged; the accepted step changed J by at most cost_tol");
        return 0;
    }
    if (!r->accepted && !r->restored && s->eta <= st->eta_lb) {
        /* same reference, same radius: rejected forever. Beyond the paper: near a plan whose
         * defects are far below defect_tol, lambda times a step's second-order defects
         * outweighs its gain (the Maratos effect); a reference that meets every tolerance is
         * returned, solved (guidance/scvx.py CONVERGED_AT_REFERENCE) */
        if (converged(st, s, &cd, INFINITY)) {
            *status = PDG_SOLVED;
            snprintf(res->message, PDG_MESSAGE_LEN,
                     "converged; the step at the smallest trust radius, within step_tol, was "
                     "rejected: the iterate kept");
        } else {
            s->stalled = 1;
        }
        return 0;
    }
    /* the retry's warm start (a guard rejection at the same radius keeps the answer) */
    if (!r->accepted && eta_new < s->eta && eta_new < cd.tr_step) {
        pull_back(ws, RETRY_START * eta_new / cd.tr_step);
    }
    s->eta = eta_new;
    return 1;
}

/* Beyond the paper (pdg_settings.polish): once converged, one more subproblem about the
 * answer on the full constraint set, without the fuel term and at radius eta_ub, solved to
 * tighter tolerances; its solution replaces the answer when it leaves no virtual control,
 * smaller defects and every path constraint met (guidance/scvx.py SCvxSolver._polish). */
static pdg_polish_status polish(pdg_workspace *ws, const pdg_options *opt, scvx_state *s,
                                pdg_result *res)
{
    const pdg_settings *st = &ws->st;
    pdg_log_row row;
    candidate cd;
    int sst;
    if (!st->polish || !(st->prox_u > 0.0)) {
        return PDG_POLISH_OFF;
    }
    if (res->socp_iterations >= st->socp_max_iter_total) {
        return PDG_POLISH_NO_BUDGET;
    }
    s->polishing = 1;
    s->eta = st->eta_ub;
    sst = solve_subproblem(ws, opt, NULL, s, &row, res);
    s->polishing = 0;
    if (sst == SST_LOST) { /* run_scvx stops the solve */
        return PDG_POLISH_FAILED;
    }
    res->polish_iterations = row.solver_iterations;
    if (sst != TSCVX_SOLVED && sst != TSCVX_SOLVED_INACCURATE) {
        return sst == TSCVX_MAX_ITER && ws->socp_cap < st->socp_max_iter ? PDG_POLISH_NO_BUDGET
                                                                         : PDG_POLISH_FAILED;
    }
    if (evaluate(ws, NULL, &cd) != 0) {
        return PDG_POLISH_FAILED;
    }
    if (cd.vc > st->vc_tol || !(cd.defect < s->defect) || cd.viol > st->defect_tol) {
        return PDG_POLISH_NOT_BETTER;
    }
    take_candidate(ws);
    s->J = cd.J;
    s->defect = cd.defect;
    s->viol = cd.viol;
    return PDG_POLISH_KEPT;
}

pdg_status pdg_solve(pdg_workspace *ws, const pdg_scenario *scenario, const pdg_options *opt,
                     pdg_result *res)
{
    return pdg_solve_from(ws, scenario, opt, res, 0.0); /* the settings' radius */
}

int pdg_result_begin(pdg_workspace *ws, pdg_result *res)
{
    if (!res) {
        if (pdg_ws_idle(ws)) { /* refused like any other call: no stale record left */
            ws->n_log = ws->n_masks_out = 0;
        }
        return -1;
    }
    if (PDG_WS_READY(ws) && ws->busy && res == ws->running) {
        return -1; /* from a callback, with the running solve's own result: left as it is */
    }
    res->status = PDG_INVALID_INPUT;
    res->message[0] = '\0';
    res->iterations = res->subproblems_solved = res->socp_iterations = 0;
    res->t_f = res->max_defect = res->max_violation = NAN;
    res->polish = PDG_POLISH_OFF;
    res->polish_iterations = 0;
    res->defect_before_polish = res->m_f_before_polish = NAN;
    if (!PDG_WS_READY(ws)) {
        snprintf(res->message, PDG_MESSAGE_LEN,
                 "workspace not set up, or its arena overwritten or damaged (a set-up checksum "
                 "mismatch): call pdg_setup");
        return -1;
    }
    if (ws->busy) { /* the running solve's record stays as it is */
        snprintf(res->message, PDG_MESSAGE_LEN, PDG_BUSY_MESSAGE);
        return -1;
    }
    ws->n_log = ws->n_masks_out = 0;
    return 0;
}

int pdg_reports_answer(pdg_status status)
{
    return status == PDG_SOLVED || status == PDG_INFEASIBLE || status == PDG_MAX_ITERATIONS;
}

/* The end check of a solve (pdg_solve, pdg_solve_tscvx): the checksums its start checked,
 * again, the guidance workspace's first (the SOCP workspace's pointer is among what it
 * covers). The SOCP workspace's were checked at the end of each subproblem's solve too
 * (tscvx_solve), but the call goes on after the last one. 0 when intact; 1 with the
 * reason in msg (PDG_MESSAGE_LEN bytes) when a bit flipped during the call. */
static int damaged_during_call(const pdg_workspace *ws, char *msg)
{
    char why[TSCVX_MESSAGE_LEN];
    if (!PDG_WS_READY(ws)) {
        snprintf(msg, PDG_MESSAGE_LEN,
                 "workspace damaged during the call (the end check: set-up checksum mismatch "
                 "in the guidance workspace's sizes, settings, layout or map of the subproblem "
                 "into A and G): no answer; set it up again");
        return 1;
    }
    if (tscvx_check_workspace(ws->socp, why) != TSCVX_SETUP_OK) {
        snprintf(msg, PDG_MESSAGE_LEN,
                 "workspace damaged during the call (the end check, SOCP workspace: %s): no "
                 "answer",
                 why);
        return 1;
    }
    return 0;
}

/* Paper Algorithm 1 (Algorithm 2 when the options carry masks): subproblems until
 * convergence on the full constraint set, a stall, a failure or the settings' limits. */
static pdg_status run_scvx(pdg_workspace *ws, const pdg_scenario *scenario,
                           const pdg_options *opt, pdg_result *res, double eta_init)
{
    pdg_status status;
    scvx_state s = {0, 0.0, NAN, NAN, NAN, INFINITY, 0, 0, 0, 0, 0, 0, 0, 0};
    int it;

    status = start(ws, scenario, opt, res, &s.J, &s.defect, &s.viol);
    if (status != PDG_SOLVED) {
        res->status = status;
        return status;
    }
    status = PDG_MAX_ITERATIONS;
    s.have_masks = opt->masks != NULL || opt->mask_fn != NULL;
    s.eta = eta_init > 0.0 ? eta_init : ws->st.eta_init;
    for (it = 0; it < ws->st.max_subproblems && s.k < ws->st.iter_max; ++it) {
        if (!scvx_iteration(ws, opt, &s, res, &status)) {
            break;
        }
    }
    if (status == PDG_MAX_ITERATIONS && !s.spent) {
        status = diagnose(ws, s.vc, s.defect, s.viol, s.k, s.stalled, res->message);
    }
    if (status == PDG_SOLVED) {
        res->defect_before_polish = s.defect;
        res->m_f_before_polish = ws->x[(size_t)(ws->N - 1) * NX + IM];
        res->polish = polish(ws, opt, &s, res);
        if (s.lost) { /* the polish's clock callback took the workspace */
            callback_lost(res->message, "the clock callback", s.k + 1);
            status = PDG_INVALID_INPUT;
        }
    }
    /* an answer computed through set-up data that changed during the call is not reported
     * (the failures before keep their own reason) */
    if (pdg_reports_answer(status) && damaged_during_call(ws, res->message)) {
        status = PDG_SOLVER_ERROR;
        s.damaged = 1;
    }
    if (status != PDG_INVALID_INPUT && !s.damaged) { /* else no trajectory (t_f NaN) */
        to_physical(ws, ws->z, res->x, res->u, &res->t_f);
    }
    res->status = status;
    res->iterations = s.k;
    res->subproblems_solved = s.lost ? 0 : ws->n_log;
    res->max_defect = s.defect;
    res->max_violation = s.viol;
    return status;
}

pdg_status pdg_solve_from(pdg_workspace *ws, const pdg_scenario *scenario,
                          const pdg_options *opt, pdg_result *res, double eta_init)
{
    static const pdg_options no_options = {NULL, NULL, 0.0, NULL, 0, NULL, NULL, NULL};
    pdg_status status;
    if (pdg_result_begin(ws, res) != 0) {
        return PDG_INVALID_INPUT;
    }
    ws->busy = 1; /* pdg_result_begin and pdg_ws_idle refuse calls from its callbacks */
    ws->running = res;
    status = run_scvx(ws, scenario, opt ? opt : &no_options, res, eta_init);
    if (ws->running == res) { /* not when a callback set it up again (running NULL) */
        ws->busy = 0; /* the struct's own fields, outside the checksum: written if damaged */
        ws->running = NULL;
    }
    return status;
}

/* ---- record of the last solve ------------------------------------------------------------ */

/* The record's counters are written by every solve and not in the checksum: its reads are
 * bounded by the capacities set-up fixed (max_subproblems log rows, iter_max masks) too. */
static int log_rows(const pdg_workspace *ws)
{
    const int n = ws->n_log < ws->st.max_subproblems ? ws->n_log : ws->st.max_subproblems;
    return n > 0 ? n : 0;
}

/* What every read of the record checks first: somewhere to write, and a set-up workspace. */
static pdg_setup_status record_readable(const pdg_workspace *ws, const void *out)
{
    if (!ws || !out) {
        return PDG_SETUP_NULL_ARGUMENT;
    }
    return PDG_WS_READY(ws) ? PDG_SETUP_OK : PDG_SETUP_NOT_READY;
}

pdg_setup_status pdg_log_length(const pdg_workspace *ws, int *rows)
{
    const pdg_setup_status ready = record_readable(ws, rows);
    if (ready != PDG_SETUP_OK) {
        return ready;
    }
    *rows = log_rows(ws);
    return PDG_SETUP_OK;
}

pdg_setup_status pdg_get_log(const pdg_workspace *ws, int i, pdg_log_row *row)
{
    const pdg_setup_status ready = record_readable(ws, row);
    if (ready != PDG_SETUP_OK) {
        return ready;
    }
    if (i < 0 || i >= log_rows(ws)) {
        return PDG_SETUP_BAD_INDEX;
    }
    *row = ws->log[i];
    return PDG_SETUP_OK;
}

pdg_setup_status pdg_get_mask(const pdg_workspace *ws, int k, unsigned char *mask)
{
    const pdg_setup_status ready = record_readable(ws, mask);
    if (ready != PDG_SETUP_OK) {
        return ready;
    }
    if (k < 0 || k >= ws->n_masks_out || k >= ws->st.iter_max) {
        return PDG_SETUP_BAD_INDEX;
    }
    memcpy(mask, ws->masks_out + (size_t)k * NC * ws->N, (size_t)NC * ws->N);
    return PDG_SETUP_OK;
}

pdg_setup_status pdg_arena_high_water(const pdg_workspace *ws, size_t *bytes)
{
    const pdg_setup_status ready = record_readable(ws, bytes);
    if (ready != PDG_SETUP_OK) {
        return ready;
    }
    *bytes = ws->arena_high;
    return PDG_SETUP_OK;
}

pdg_setup_status pdg_problem_size(const pdg_workspace *ws, int *n, int *p, int *m, int *nnz_A,
                                  int *nnz_G)
{
    if (!ws) {
        return PDG_SETUP_NULL_ARGUMENT; /* as the record's getters */
    }
    if (!PDG_WS_READY(ws)) {
        return PDG_SETUP_NOT_READY;
    }
    if (n) *n = ws->n;
    if (p) *p = ws->p;
    if (m) *m = ws->m;
    if (nnz_A) *nnz_A = ws->nnz_A;
    if (nnz_G) *nnz_G = ws->nnz_G;
    return PDG_SETUP_OK;
}

/* ---- test hooks -------------------------------------------------------------------------- */

int pdg_debug_guess(pdg_workspace *ws, const pdg_scenario *s, double *x, double *u, double *t_f,
                    char *message)
{
    char local[PDG_MESSAGE_LEN];
    char *msg = message ? message : local;
    msg[0] = '\0';
    if (!PDG_WS_READY(ws) || !x || !u || !t_f) {
        snprintf(msg, PDG_MESSAGE_LEN, "a required pointer is NULL or the workspace not set up");
        return PDG_INVALID_INPUT;
    }
    if (!pdg_ws_idle(ws)) {
        snprintf(msg, PDG_MESSAGE_LEN, PDG_BUSY_MESSAGE);
        return PDG_INVALID_INPUT;
    }
    if (pdg_check_workspace_scenario(ws, s, msg)) {
        return PDG_INVALID_INPUT;
    }
    pdg_initial_guess(s, x, u, t_f, ws->gwork);
    return 0;
}

int pdg_debug_assemble(pdg_workspace *ws, const pdg_scenario *s, const double *x,
                       const double *u, double t_f, double eta, double *c, double *Ax,
                       double *b, double *Gx, double *h, int *Ap, int *Ai, int *Gp, int *Gi,
                       char *message)
{
    char local[PDG_MESSAGE_LEN];
    char *msg = message ? message : local;
    double tf2;
    int i, assembled;
    msg[0] = '\0';
    if (!PDG_WS_READY(ws) || !x || !u) {
        snprintf(msg, PDG_MESSAGE_LEN, "a required pointer is NULL or the workspace not set up");
        return PDG_INVALID_INPUT;
    }
    if (!pdg_ws_idle(ws)) {
        snprintf(msg, PDG_MESSAGE_LEN, PDG_BUSY_MESSAGE);
        return PDG_INVALID_INPUT;
    }
    if (!(t_f > 0.0 && isfinite(t_f)) || !(eta > 0.0 && isfinite(eta))) {
        snprintf(msg, PDG_MESSAGE_LEN, "t_f = %g and eta = %g: both must be finite and > 0",
                 t_f, eta);
        return PDG_INVALID_INPUT;
    }
    if (pdg_check_workspace_scenario(ws, s, msg)) {
        return PDG_INVALID_INPUT;
    }
    if (!pdg_all_finite(x, (size_t)ws->N * NX) || !pdg_all_finite(u, (size_t)ws->N * NU)) {
        snprintf(msg, PDG_MESSAGE_LEN, "x or u holds a number that is not finite");
        return PDG_INVALID_INPUT;
    }
    prepare_scenario(ws, s, t_f);
    to_scaled(ws, x, u, t_f, ws->z);
    to_physical(ws, ws->z, ws->x, ws->u, &tf2);
    if (discretize(ws, x, u, t_f, ws->disc) != 0) {
        snprintf(msg, PDG_MESSAGE_LEN, "model evaluation failed at the iterate");
        return PDG_SOLVER_ERROR;
    }
    assembled = assemble(ws, ws->z, ws->disc, NULL, eta, 0);
    if (assembled != 0) {
        snprintf(msg, PDG_MESSAGE_LEN, "%s",
                 assembled == ASSEMBLE_MAP_DAMAGED
                     ? "the workspace is damaged (its map of the subproblem into A and G "
                       "points outside them): set it up again"
                     : "the SOCP runtime refused the subproblem's numbers");
        return PDG_SOLVER_ERROR;
    }
    for (i = 0; c && i < ws->n; ++i) c[i] = ws->c[i];
    for (i = 0; Ax && i < ws->nnz_A; ++i) Ax[i] = ws->Ax[i];
    for (i = 0; Gx && i < ws->nnz_G; ++i) Gx[i] = ws->Gx[i];
    for (i = 0; b && i < ws->p; ++i) b[i] = ws->b[i];
    for (i = 0; h && i < ws->m; ++i) h[i] = ws->h[i];
    for (i = 0; Ap && i <= ws->n; ++i) Ap[i] = ws->Ap[i];
    for (i = 0; Gp && i <= ws->n; ++i) Gp[i] = ws->Gp[i];
    for (i = 0; Ai && i < ws->nnz_A; ++i) Ai[i] = ws->Ai[i];
    for (i = 0; Gi && i < ws->nnz_G; ++i) Gi[i] = ws->Gi[i];
    return 0;
}
