/* T-SCvx on board (paper Algorithm 2): the solution network's warm start, projected onto the
 * boundary conditions and the convex path constraints, SCvx from the reduced trust radius and,
 * optionally, the constraint network's tight masks at every iteration. The Python counterpart
 * is guidance/tscvx.py solve_tscvx (and guidance/cli.py run_solve for --method tscvx): the
 * same theta, the same projection (guidance/guess.py project_guess = pdg_project_guess), the
 * same radius and the same mask rule (probability >= the network's threshold). */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "pdg_internal.h"
#include "tscvx_nn.h"

#define THETA PDG_THETA_LEN

pdg_setup_status pdg_theta_of(const pdg_scenario *s, double *theta)
{
    if (!s || !theta) {
        return PDG_SETUP_NULL_ARGUMENT;
    }
    pdg_initial_state(s, theta); /* theta starts with x0 (guidance.sampling.theta_of) */
    theta[14] = s->params.glideslope_deg;
    theta[15] = s->params.tilt_max_deg;
    return PDG_SETUP_OK;
}

/* The problem parameters a network is trained for: every parameter that is not a network
 * input (theta has the glideslope and tilt limits), in pdg_params' order, vectors by
 * component, booleans and N as numbers. guidance/nn/infer.py TRAINED_PARAMS writes them into
 * the blob in the same order (tests/test_cnn.py changes each one in turn). */
static const struct {
    const char *name;
    int len;
} TRAINED[] = {{"g_I", 3},        {"J_B", 3},        {"r_T_B", 3},          {"r_cp_B", 3},
               {"alpha_mdot", 1}, {"beta_mdot", 1},  {"aero_coeff", 1},     {"m_dry", 1},
               {"T_min", 1},      {"T_max", 1},      {"gimbal_max_deg", 1}, {"omega_max_deg", 1},
               {"r_f", 3},        {"v_f", 3},        {"q_f", 4},            {"omega_f", 3},
               {"final_roll_free", 1}, {"N", 1}};
#define N_TRAINED 35

static void trained_vector(const pdg_params *p, double *v)
{
    int i = 0, j;
    for (j = 0; j < 3; ++j) v[i++] = p->g_I[j];
    for (j = 0; j < 3; ++j) v[i++] = p->J_B[j];
    for (j = 0; j < 3; ++j) v[i++] = p->r_T_B[j];
    for (j = 0; j < 3; ++j) v[i++] = p->r_cp_B[j];
    v[i++] = p->alpha_mdot;
    v[i++] = p->beta_mdot;
    v[i++] = p->aero_coeff;
    v[i++] = p->m_dry;
    v[i++] = p->T_min;
    v[i++] = p->T_max;
    v[i++] = p->gimbal_max_deg;
    v[i++] = p->omega_max_deg;
    for (j = 0; j < 3; ++j) v[i++] = p->r_f[j];
    for (j = 0; j < 3; ++j) v[i++] = p->v_f[j];
    for (j = 0; j < 4; ++j) v[i++] = p->q_f[j];
    for (j = 0; j < 3; ++j) v[i++] = p->omega_f[j];
    v[i++] = p->final_roll_free ? 1.0 : 0.0;
    v[i] = (double)p->N;
}

/* Refuses a network the scenario's parameters do not match (relative 1e-12, as the ONNX
 * check of guidance/nn/infer.py); 0 = they match. */
static int check_trained_for(const tscvx_nn_info *info, const char *name, const pdg_params *p,
                             char *msg)
{
    double v[N_TRAINED];
    int i, k = 0, t = 0;
    if (info->n_params != N_TRAINED || !info->params) {
        snprintf(msg, PDG_MESSAGE_LEN,
                 "nets: the %s network records %d trained-for problem parameters, this library "
                 "compares %d (a blob of another exporter: convert its ONNX file again)",
                 name, info->n_params, N_TRAINED);
        return 1;
    }
    trained_vector(p, v);
    for (i = 0; i < N_TRAINED; ++i, ++k) {
        if (k == TRAINED[t].len) { /* next parameter */
            ++t;
            k = 0;
        }
        if (!(fabs(info->params[i] - v[i]) <= 1e-12 * fabs(v[i]))) {
            char field[32];
            if (TRAINED[t].len > 1) {
                snprintf(field, sizeof field, "%s[%d]", TRAINED[t].name, k);
            } else {
                snprintf(field, sizeof field, "%s", TRAINED[t].name);
            }
            snprintf(msg, PDG_MESSAGE_LEN,
                     "nets: the %s network was trained for other problem parameters: %s "
                     "(network %.17g, scenario %.17g)",
                     name, field, info->params[i], v[i]);
            return 1;
        }
    }
    return 0;
}

/* Refuses a network that is not of `kind`, does not fit N or was trained for other problem
 * parameters than the scenario's; 0 = fits. */
static int check_net(tscvx_nn *net, int kind, const pdg_params *p, char *msg)
{
    const int N = p->N;
    const char *name = kind == TSCVX_NN_KIND_SOLUTION ? "solution" : "constraint";
    const int d_in = kind == TSCVX_NN_KIND_SOLUTION ? THETA : THETA + 1;
    const long d_out = kind == TSCVX_NN_KIND_SOLUTION ? (long)N * (NX + NU) + 1 : (long)N * NC;
    tscvx_nn_info info;
    const tscvx_nn_status st = tscvx_nn_get_info(net, &info);
    if (st != TSCVX_NN_OK) {
        snprintf(msg, PDG_MESSAGE_LEN, "nets: the %s network: %s", name,
                 tscvx_nn_status_message(st));
        return 1;
    }
    if (info.kind != kind) {
        snprintf(msg, PDG_MESSAGE_LEN, "nets: the %s network given is a %s network", name,
                 info.kind == TSCVX_NN_KIND_SOLUTION     ? "solution"
                 : info.kind == TSCVX_NN_KIND_CONSTRAINT ? "constraint"
                                                         : "unknown");
        return 1;
    }
    if (info.d_in != d_in) {
        snprintf(msg, PDG_MESSAGE_LEN,
                 "nets: the %s network takes %d inputs, the guidance call gives %d (%s)", name,
                 info.d_in, d_in, d_in == THETA ? "theta" : "theta and the iteration k");
        return 1;
    }
    if (info.N != N || (long)info.d_out != d_out) {
        snprintf(msg, PDG_MESSAGE_LEN,
                 "nets: the %s network was trained for N = %d (%d outputs), the workspace "
                 "has N = %d (%ld outputs)",
                 name, info.N, info.d_out, N, d_out);
        return 1;
    }
    return check_trained_for(&info, name, p, msg);
}

/* Solution network -> ws->nn_out (x, u, t_f, contiguous) -> projection in place. */
static int predict_guess(pdg_workspace *ws, const pdg_scenario *s, tscvx_nn *net,
                         const double *theta, char *msg)
{
    const int N = ws->N, n_out = N * (NX + NU) + 1;
    double *x = ws->nn_out, *u = ws->nn_out + (size_t)N * NX, *t_f = ws->nn_out + n_out - 1;
    const tscvx_nn_status st = tscvx_nn_run(net, theta, THETA, ws->nn_out, n_out);
    if (st != TSCVX_NN_OK) {
        snprintf(msg, PDG_MESSAGE_LEN, "solution network: %s", tscvx_nn_status_message(st));
        return 1;
    }
    pdg_project_guess(s, x, u, t_f);
    return 0;
}

int pdg_tscvx_guess(pdg_workspace *ws, const pdg_scenario *s, tscvx_nn *solution, double *x,
                    double *u, double *t_f, char *message)
{
    char local[PDG_MESSAGE_LEN];
    char *msg = message ? message : local;
    double theta[THETA];
    msg[0] = '\0';
    if (!PDG_WS_READY(ws) || !s || !solution || !x || !u || !t_f) {
        snprintf(msg, PDG_MESSAGE_LEN, "a required pointer is NULL or the workspace not set up");
        return PDG_INVALID_INPUT;
    }
    if (!pdg_ws_idle(ws)) {
        snprintf(msg, PDG_MESSAGE_LEN, PDG_BUSY_MESSAGE);
        return PDG_INVALID_INPUT;
    }
    if (pdg_check_workspace_scenario(ws, s, msg) ||
        check_net(solution, TSCVX_NN_KIND_SOLUTION, &s->params, msg)) {
        return PDG_INVALID_INPUT;
    }
    pdg_theta_of(s, theta);
    if (predict_guess(ws, s, solution, theta, msg)) {
        return PDG_SOLVER_ERROR;
    }
    memcpy(x, ws->nn_out, sizeof(double) * (size_t)ws->N * NX);
    memcpy(u, ws->nn_out + (size_t)ws->N * NX, sizeof(double) * (size_t)ws->N * NU);
    *t_f = ws->nn_out[ws->N * (NX + NU)];
    return 0;
}

/* The mask callback of pdg_solve: constraint network at (theta, k). A rejected step retries
 * the same k, whose logits are kept (the network is deterministic: no second inference). */
typedef struct {
    tscvx_nn *net;
    double input[THETA + 1];
    double *logits; /* 7N, in the guidance arena */
    int last_k;     /* k of the logits (0: none) */
    int predicted, failures;
} mask_ctx;

/* A failed inference falls back to the full subproblem (always safe). Overlapping buffers,
 * a configuration error that would recur at every k, are refused before the call starts. */
static int mask_failed(mask_ctx *c)
{
    c->failures++;
    return 0;
}

static int network_mask(void *ctx, int k, unsigned char *mask, int n)
{
    mask_ctx *c = (mask_ctx *)ctx;
    tscvx_nn_status st;
    if (k != c->last_k) {
        c->input[THETA] = (double)k;
        c->last_k = 0;
        st = tscvx_nn_run(c->net, c->input, THETA + 1, c->logits, n);
        if (st != TSCVX_NN_OK) {
            return mask_failed(c);
        }
        c->last_k = k;
    }
    st = tscvx_nn_tight_mask(c->net, c->logits, n, mask);
    if (st != TSCVX_NN_OK) {
        return mask_failed(c);
    }
    c->predicted++;
    return 1;
}

/* The buffers a network reads and writes in the call (input: theta [+ k] at `input`; the
 * outputs in the guidance arena) apart from its arena and blob: a network arena that holds
 * the guidance workspace is a configuration error, refused before anything runs. */
static int buffers_refused(const pdg_workspace *ws, tscvx_nn *net, int kind,
                           const double *input, char *msg)
{
    const size_t n7 = (size_t)NC * (size_t)ws->N;
    tscvx_nn_status st;
    if (kind == TSCVX_NN_KIND_SOLUTION) {
        st = tscvx_nn_check_buffers(net, input, sizeof(double) * THETA, ws->nn_out,
                                    sizeof(double) * ((size_t)ws->N * (NX + NU) + 1));
    } else {
        st = tscvx_nn_check_buffers(net, input, sizeof(double) * (THETA + 1), ws->nn_logits,
                                    sizeof(double) * n7);
        if (st == TSCVX_NN_OK) {
            st = tscvx_nn_check_buffers(net, ws->nn_logits, sizeof(double) * n7, ws->mask, n7);
        }
    }
    if (st == TSCVX_NN_OK) {
        return 0;
    }
    snprintf(msg, PDG_MESSAGE_LEN,
             "nets: the %s network: %s (its arena as given to tscvx_nn_init must not hold the "
             "guidance workspace)",
             kind == TSCVX_NN_KIND_SOLUTION ? "solution" : "constraint",
             tscvx_nn_status_message(st));
    return 1;
}

/* Every input of pdg_solve_tscvx, checked before any inference; the warm start's radius into
 * *warm_eta. 0, or -1 with the message in res. `input`: the call's network input buffer. */
static int check_tscvx_call(const pdg_workspace *ws, const pdg_scenario *s,
                            const pdg_tscvx_options *o, const double *input, pdg_result *res,
                            double *warm_eta)
{
    if (!o) {
        snprintf(res->message, PDG_MESSAGE_LEN, "nets: the T-SCvx options must be given");
        return -1;
    }
    if (!res->x || !res->u) {
        snprintf(res->message, PDG_MESSAGE_LEN, "result arrays x and u must be given");
        return -1;
    }
    if (pdg_check_workspace_scenario(ws, s, res->message) ||
        (o->solution && check_net(o->solution, TSCVX_NN_KIND_SOLUTION, &s->params, res->message)) ||
        (o->constraint &&
         check_net(o->constraint, TSCVX_NN_KIND_CONSTRAINT, &s->params, res->message)) ||
        (o->solution &&
         buffers_refused(ws, o->solution, TSCVX_NN_KIND_SOLUTION, input, res->message)) ||
        (o->constraint &&
         buffers_refused(ws, o->constraint, TSCVX_NN_KIND_CONSTRAINT, input, res->message))) {
        return -1;
    }
    /* 0 stands for Table 1's radius, which the settings' bounds must admit when it is used */
    *warm_eta = o->eta_init == 0.0 ? PDG_TSCVX_ETA_INIT : o->eta_init;
    if ((o->eta_init != 0.0 || o->solution) &&
        !(*warm_eta >= ws->st.eta_lb && *warm_eta <= ws->st.eta_ub)) {
        snprintf(res->message, PDG_MESSAGE_LEN,
                 "eta_init: must be 0 (Table 1's %g) or within [eta_lb, eta_ub] = [%g, %g], got "
                 "%.17g%s",
                 PDG_TSCVX_ETA_INIT, ws->st.eta_lb, ws->st.eta_ub, o->eta_init,
                 o->eta_init == 0.0 ? " (Table 1's radius is outside the settings' bounds)" : "");
        return -1;
    }
    return 0;
}

/* The networks' part of the end check (pdg_solve_from checked the workspaces): their
 * checksums, checked by every call taking them (tscvx_nn_get_info at the start, each mask
 * inference), again. 0 when intact; 1 with the reason in msg when one changed during the
 * call. */
static int nets_damaged_during_call(const pdg_tscvx_options *o, char *msg)
{
    const char *const names[2] = {"solution", "constraint"};
    tscvx_nn *const nets[2] = {o->solution, o->constraint};
    tscvx_nn_info info;
    int i;
    for (i = 0; i < 2; ++i) {
        const tscvx_nn_status st = nets[i] ? tscvx_nn_get_info(nets[i], &info) : TSCVX_NN_OK;
        if (st != TSCVX_NN_OK) {
            snprintf(msg, PDG_MESSAGE_LEN,
                     "nets: the %s network was damaged during the call (the end check: %s): "
                     "no answer; initialize it again",
                     names[i], tscvx_nn_status_message(st));
            return 1;
        }
    }
    return 0;
}

/* Paper Algorithm 2 on board: the solution network's warm start (with the reduced radius),
 * the constraint network's mask at every iteration, and the SCvx loop with its
 * full-constraint guard. */
pdg_status pdg_solve_tscvx(pdg_workspace *ws, const pdg_scenario *s,
                           const pdg_tscvx_options *o, pdg_result *res, pdg_tscvx_report *rep)
{
    pdg_options opt;
    mask_ctx mc;
    double eta, warm_eta = 0.0;
    pdg_status status;
    int N;

    if (rep) {
        memset(rep, 0, sizeof *rep);
    }
    if (pdg_result_begin(ws, res) != 0) {
        return PDG_INVALID_INPUT;
    }
    memset(&mc, 0, sizeof mc);
    if (check_tscvx_call(ws, s, o, mc.input, res, &warm_eta) != 0) {
        return PDG_INVALID_INPUT;
    }
    N = ws->N;
    memset(&opt, 0, sizeof opt);
    opt.clock_s = o->clock_s;
    pdg_theta_of(s, mc.input);
    eta = ws->st.eta_init; /* the reduced radius goes with the warm start only */
    if (o->solution) {
        if (predict_guess(ws, s, o->solution, mc.input, res->message)) {
            res->status = PDG_SOLVER_ERROR;
            return PDG_SOLVER_ERROR;
        }
        opt.guess_x = ws->nn_out;
        opt.guess_u = ws->nn_out + (size_t)N * NX;
        opt.guess_t_f = ws->nn_out[N * (NX + NU)];
        eta = warm_eta;
    }
    if (o->constraint) {
        mc.net = o->constraint;
        mc.logits = ws->nn_logits;
        opt.mask_fn = network_mask;
        opt.mask_ctx = &mc;
    }
    status = pdg_solve_from(ws, s, &opt, res, eta);
    if (pdg_reports_answer(status) && nets_damaged_during_call(o, res->message)) {
        status = res->status = PDG_SOLVER_ERROR;
    }
    if (rep) {
        rep->warm_started = o->solution != NULL;
        rep->masks_predicted = mc.predicted;
        rep->mask_failures = mc.failures;
        rep->eta_init = eta;
    }
    return status;
}
