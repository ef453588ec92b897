/*
 * test_tscvx.c -- the on-board T-SCvx call (pdg_solve_tscvx) under valgrind:
 *
 *   test_tscvx [SOLUTION.tnn CONSTRAINT.tnn]      (default: the two files of build/models)
 *
 * every input refused with a clear message (NULLs, networks of the wrong kind, networks for
 * another N, bad scenario, bad eta_init) before any inference; theta in the dataset's order;
 * the projected warm start meets the boundary conditions; T-SCvx with and without masks
 * solves the default landing from the reduced radius; without networks it is pdg_solve.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gnc_test.h"
#include "host_io.h"
#include "pdg_internal.h"       /* the guidance workspace's map (an upset's site) */
#include "../../nn/nn_internal.h" /* a network's fields (an upset's site) */
#include "tscvx_guidance.h"
#include "tscvx_nn.h"

/* A workspace for N nodes with Table 1's settings, but the trust radius bounded below by
 * eta_lb (0: Table 1's) */
static pdg_workspace *make_ws(int N, double eta_lb, void **arena)
{
    pdg_settings st;
    pdg_workspace *ws = NULL;
    size_t need = 0;
    int tries;
    pdg_default_settings(&st);
    if (eta_lb > 0.0) st.eta_lb = eta_lb;
    if (arena_size(N, 1, &st, &need, &tries) != PDG_SETUP_OK || !(*arena = malloc(need))) {
        return NULL;
    }
    return pdg_setup(&ws, *arena, need, vehicle(N, 1), &st) == PDG_SETUP_OK ? ws : NULL;
}

static void expect_refused(pdg_workspace *ws, const pdg_scenario *s, tscvx_nn *sol,
                           tscvx_nn *con, const char *text)
{
    pdg_tscvx_options o = {0};
    pdg_tscvx_report rep;
    pdg_result r;
    r.x = x;
    r.u = u;
    o.solution = sol;
    o.constraint = con;
    CHECK(pdg_solve_tscvx(ws, s, &o, &r, &rep) == PDG_INVALID_INPUT);
    CHECK(r.status == PDG_INVALID_INPUT && r.subproblems_solved == 0);
    if (!strstr(r.message, text)) {
        fprintf(stderr, "message '%s' lacks '%s'\n", r.message, text);
        failures++;
    }
}

/* Mask callback asking for a T-SCvx guess on the workspace whose solve calls it: refused as
 * busy (it would overwrite the running solve's buffers); then the full problem. */
typedef struct {
    pdg_workspace *ws;
    const pdg_scenario *s;
    tscvx_nn *sol;
    int refused;
} guess_inside_ctx;

static int guess_inside(void *ctx, int k, unsigned char *mask, int n)
{
    static double gx2[PDG_N_MAX * PDG_NSTATE], gu2[PDG_N_MAX * PDG_NCTRL];
    guess_inside_ctx *g = (guess_inside_ctx *)ctx;
    char m[PDG_MESSAGE_LEN];
    double tf2;
    (void)k, (void)mask, (void)n;
    if (pdg_tscvx_guess(g->ws, g->s, g->sol, gx2, gu2, &tf2, m) == PDG_INVALID_INPUT &&
        strstr(m, "busy") != NULL) {
        ++g->refused;
    }
    return 0;
}

/* One buffer for both (a caller sharing its memory): a network's arena, as given to
 * tscvx_nn_init, spans the guidance workspace set up in its unused tail. What the network
 * would write there (the logits, the warm start) would land in its arena: the call is refused
 * before anything runs, naming the network and the overlap, with PDG_INVALID_INPUT for either
 * network. (The constraint network's used to fall back to the full problem at every k,
 * counted as mask failures only; then it stopped at the first subproblem, returning the
 * unsolved guess; the solution network's ended PDG_SOLVER_ERROR.) */
static void shared_buffer_refused(const pdg_scenario *s, const unsigned char *blob, size_t len,
                                  int constraint)
{
    pdg_tscvx_options o = {0};
    pdg_tscvx_report rep;
    pdg_result r;
    pdg_settings st;
    pdg_workspace *ws = NULL;
    tscvx_nn *net = NULL;
    size_t net_need = 0, gnc_need = 0, offset;
    int tries;
    unsigned char *shared;
    pdg_default_settings(&st);
    CHECK(tscvx_nn_arena_size(blob, len, 0u, &net_need) == TSCVX_NN_OK);
    CHECK(arena_size(s->params.N, 1, &st, &gnc_need, &tries) == PDG_SETUP_OK);
    offset = (net_need + 63u) / 64u * 64u;
    shared = malloc(offset + gnc_need);
    CHECK(shared != NULL);
    if (!shared) return;
    CHECK(tscvx_nn_init(&net, shared, offset + gnc_need, blob, len, 0u) == TSCVX_NN_OK);
    CHECK(pdg_setup(&ws, shared + offset, gnc_need, vehicle(s->params.N, 1), &st) ==
          PDG_SETUP_OK);
    r.x = x;
    r.u = u;
    x[0] = -7.0;
    if (constraint) {
        o.constraint = net;
    } else {
        o.solution = net;
    }
    CHECK(pdg_solve_tscvx(ws, s, &o, &r, &rep) == PDG_INVALID_INPUT);
    CHECK(r.subproblems_solved == 0 && rep.mask_failures == 0 && isnan(r.t_f) && x[0] == -7.0);
    if (!strstr(r.message, constraint ? "nets: the constraint network: overlapping buffers"
                                      : "nets: the solution network: overlapping buffers")) {
        fprintf(stderr, "message '%s' does not name the overlap\n", r.message);
        failures++;
    }
    free(shared);
}

/* T-SCvx with both networks, a bit of *at flipped after the last subproblem's solve (when
 * no network runs any more): the call's end check says so (`text` in the message) instead of
 * "solved" (which it returned before the end check); with the bit back, the same landing. */
static void upset_after_last_solve(pdg_workspace *ws, const pdg_scenario *s, tscvx_nn *sol,
                                   tscvx_nn *con, int *at, const char *text)
{
    pdg_tscvx_options o = {0};
    pdg_result r;
    pdg_status got;
    double m_f;
    int subproblems;
    const int N = s->params.N;
    o.solution = sol;
    o.constraint = con;
    o.clock_s = upset_clock;
    r.x = x;
    r.u = u;
    clock_reads = clock_upset_read = 0;
    CHECK(pdg_solve_tscvx(ws, s, &o, &r, NULL) == PDG_SOLVED);
    subproblems = r.subproblems_solved;
    m_f = x[PDG_NSTATE * (N - 1) + 13];
    CHECK(clock_reads == 2 * subproblems);
    clock_reads = 0;
    clock_upset_read = 2 * subproblems;
    clock_upset_at = at;
    got = pdg_solve_tscvx(ws, s, &o, &r, NULL);
    clock_upset_at = NULL;
    CHECK(clock_reads == 2 * subproblems);
    CHECK(got == PDG_SOLVER_ERROR && r.status == PDG_SOLVER_ERROR);
    if (!strstr(r.message, text)) {
        fprintf(stderr, "upset after the last solve: %s, message '%s' lacks '%s'\n",
                pdg_status_name(got), r.message, text);
        failures++;
    }
    printf("T-SCvx, upset after the last subproblem's solve: %s (%s)\n", pdg_status_name(got),
           r.message);
    *at ^= 1 << 20;
    CHECK(pdg_solve_tscvx(ws, s, &o, &r, NULL) == PDG_SOLVED);
    CHECK(x[PDG_NSTATE * (N - 1) + 13] == m_f);
}

/* A copy of the network file `blob` (len bytes, little-endian doubles after the header) with
 * its CRC-32 recomputed, built into a net in *arena (copy and arena malloc'd, the caller frees
 * them): outputs = 0, every weight (the values before the probes: normalization, encoder,
 * layers, decoder) set to a; outputs = 1, the output means set to a and the output stds to b.
 * A file the loader accepts as it would the exporter's (every number finite and within the
 * float32 range, the scales positive, the trained-for parameters kept). */
static void put_le64(unsigned char *p, double v)
{
    uint64_t bits;
    int i;
    memcpy(&bits, &v, sizeof bits);
    for (i = 0; i < 8; ++i) p[i] = (unsigned char)(bits >> (8 * i));
}

static tscvx_nn *edited_net(const unsigned char *blob, size_t len, int outputs, double a,
                            double b, unsigned char **copy, void **arena)
{
    tscvx_nn *net = NULL;
    size_t bytes = 0, first, count, k;
    uint32_t crc;
    int i;
    *copy = malloc(len);
    *arena = NULL;
    if (!*copy) return NULL;
    memcpy(*copy, blob, len);
    /* the layout from the blob as given (a net built for this only) */
    if (tscvx_nn_arena_size(blob, len, 0u, &bytes) != TSCVX_NN_OK || !(*arena = malloc(bytes)) ||
        tscvx_nn_init(&net, *arena, bytes, blob, len, 0u) != TSCVX_NN_OK) {
        return NULL;
    }
    /* in_mean, in_scale (d_in each), out_mean, out_std (d_out each) lead the values */
    first = outputs ? 2u * (size_t)net->d_in : 0u;
    count = outputs ? (size_t)net->d_out : (size_t)(net->probe_in - net->in_mean);
    for (k = 0; k < count; ++k) {
        put_le64(*copy + TSCVX_NN_HEADER_BYTES + 8u * (first + k), a);
        if (outputs) put_le64(*copy + TSCVX_NN_HEADER_BYTES + 8u * (first + count + k), b);
    }
    crc = nn_crc32(*copy, NN_CRC_OFFSET, 0u);
    crc = nn_crc32(*copy + TSCVX_NN_HEADER_BYTES, len - TSCVX_NN_HEADER_BYTES, crc);
    for (i = 0; i < 4; ++i) (*copy)[NN_CRC_OFFSET + (unsigned)i] = (unsigned char)(crc >> (8 * i));
    net = NULL;
    if (tscvx_nn_init(&net, *arena, bytes, *copy, len, 0u) != TSCVX_NN_OK) {
        char why[TSCVX_NN_MESSAGE_LEN] = "";
        tscvx_nn_check_blob(*copy, len, why);
        fprintf(stderr, "edited network refused: %s\n", why);
        return NULL;
    }
    return net;
}

/* The mask-failure fallback of pdg_solve_tscvx (pdg_tscvx_report.mask_failures: "mask
 * inferences refused by the network (non-finite output): those subproblems were the full
 * one"), exercised by no other test. The loader refuses NaN, infinite and beyond-float32
 * values, not large ones: a constraint network whose every weight is 3e38 (within the float32
 * range) is accepted, and its products compound past the double range before a LayerNorm
 * can rescale them (the standardized input is already 9e76), so every inference is NaN. Whether a network overflows depends on its input;
 * a bound on the weights that excluded it would refuse networks that never do. Each
 * subproblem then falls back to the full one: no mask predicted, a failure per subproblem,
 * and the landing the same to the bit as with a network whose every logit is 50 (out_mean 50,
 * out_std 1e-300: every constraint kept, a full mask at every k). */
static void overflowing_constraint_net(pdg_workspace *ws, const pdg_scenario *s, tscvx_nn *sol,
                                       const unsigned char *blob, size_t len)
{
    static double x_keep[PDG_N_MAX * PDG_NSTATE], u_keep[PDG_N_MAX * PDG_NCTRL];
    unsigned char *copy[2] = {NULL, NULL};
    void *arena[2] = {NULL, NULL};
    tscvx_nn *huge = edited_net(blob, len, 0, 3e38, 0.0, &copy[0], &arena[0]);
    tscvx_nn *keep = edited_net(blob, len, 1, 50.0, 1e-300, &copy[1], &arena[1]);
    pdg_tscvx_options o = {0};
    pdg_tscvx_report rep, rep_keep;
    pdg_result r, r_keep;
    double out[PDG_N_MAX * PDG_NCON];
    double theta[PDG_THETA_LEN + 1];
    int N = s->params.N, i;
    CHECK(huge != NULL && keep != NULL);
    if (!huge || !keep) goto done;
    pdg_theta_of(s, theta);
    theta[PDG_THETA_LEN] = 1.0;
    CHECK(tscvx_nn_run(huge, theta, PDG_THETA_LEN + 1, out, PDG_NCON * N) ==
          TSCVX_NN_NUMERICAL_ERROR);
    o.solution = sol;
    o.constraint = keep;
    r_keep.x = x_keep;
    r_keep.u = u_keep;
    CHECK(pdg_solve_tscvx(ws, s, &o, &r_keep, &rep_keep) == PDG_SOLVED);
    CHECK(rep_keep.masks_predicted == r_keep.subproblems_solved && rep_keep.mask_failures == 0);
    o.constraint = huge;
    r.x = x;
    r.u = u;
    CHECK(pdg_solve_tscvx(ws, s, &o, &r, &rep) == PDG_SOLVED);
    CHECK(rep.masks_predicted == 0 && rep.mask_failures == r.subproblems_solved &&
          rep.mask_failures > 0);
    CHECK(rep.warm_started && rep.eta_init == PDG_TSCVX_ETA_INIT);
    CHECK(r.iterations == r_keep.iterations && r.subproblems_solved == r_keep.subproblems_solved);
    CHECK(r.t_f == r_keep.t_f && r.max_violation <= 1e-6 && r.max_defect <= 1e-3);
    for (i = 0; i < N * PDG_NSTATE; ++i) CHECK(x[i] == x_keep[i]);
    for (i = 0; i < N * PDG_NCTRL; ++i) CHECK(u[i] == u_keep[i]);
    printf("T-SCvx, constraint network overflowing: %d mask failures, %d subproblems, m_f %.6f "
           "(as with full masks)\n",
           rep.mask_failures, r.subproblems_solved, x[PDG_NSTATE * (N - 1) + 13]);
done:
    for (i = 0; i < 2; ++i) {
        free(arena[i]);
        free(copy[i]);
    }
}

int main(int argc, char **argv)
{
    const char *paths[2] = {"build/models/solution.tnn", "build/models/constraint.tnn"};
    unsigned char *blob[2] = {NULL, NULL};
    void *net_arena[2] = {NULL, NULL}, *arena = NULL, *arena30 = NULL, *arena_lb = NULL;
    size_t net_bytes[2] = {0, 0};
    size_t len[2] = {0, 0};
    tscvx_nn *nets[2] = {NULL, NULL}, *sol, *con;
    pdg_workspace *ws, *ws30, *ws_lb;
    pdg_scenario s, bad, s30;
    pdg_tscvx_options o = {0};
    pdg_tscvx_report rep;
    pdg_result r, r0;
    double theta[PDG_THETA_LEN], tf, m_scvx;
    static double gx[PDG_N_MAX * PDG_NSTATE], gu[PDG_N_MAX * PDG_NCTRL];
    char msg[PDG_MESSAGE_LEN];
    int i, N, iters_scvx;

    if (argc == 3) {
        paths[0] = argv[1];
        paths[1] = argv[2];
    }
    for (i = 0; i < 2; ++i) {
        if (load_net(paths[i], &blob[i], &len[i], &net_arena[i], &net_bytes[i], &nets[i])) {
            fprintf(stderr, "(make lib builds the network files)\n");
            return 1;
        }
    }
    sol = nets[0];
    con = nets[1];
    pdg_default_scenario(&s);
    N = s.params.N;
    ws = make_ws(N, 0.0, &arena);
    CHECK(sol && con && ws);
    if (!sol || !con || !ws) return 1;

    /* theta: r0, v0, q0, w0, m0, glideslope_deg, tilt_max_deg */
    pdg_theta_of(&s, theta);
    CHECK(theta[0] == s.r0[0] && theta[5] == s.v0[2] && theta[6] == s.q0[0]);
    CHECK(theta[12] == s.w0[2] && theta[13] == s.m0);
    CHECK(theta[14] == s.params.glideslope_deg && theta[15] == s.params.tilt_max_deg);

    /* bad input: nothing solved, a message naming what is wrong */
    o.solution = sol;
    r.x = x;
    r.u = u;
    CHECK(pdg_solve_tscvx(ws, &s, &o, NULL, NULL) == PDG_INVALID_INPUT);
    CHECK(pdg_solve_tscvx(NULL, &s, &o, &r, NULL) == PDG_INVALID_INPUT);
    CHECK(pdg_solve_tscvx(ws, &s, NULL, &r, NULL) == PDG_INVALID_INPUT);
    CHECK(strstr(r.message, "options") != NULL);
    expect_refused(ws, &s, con, NULL, "solution network given is a constraint network");
    expect_refused(ws, &s, sol, sol, "constraint network given is a solution network");
    shared_buffer_refused(&s, blob[0], len[0], 0);
    shared_buffer_refused(&s, blob[1], len[1], 1);
    bad = s;
    bad.m0 = 1.0;
    expect_refused(ws, &bad, sol, con, "scenario field 'm0'");
    bad = s;
    bad.q0[0] = NAN;
    expect_refused(ws, &bad, sol, con, "scenario field 'q0'");
    o.eta_init = -1.0;
    r0.x = x;
    r0.u = u;
    CHECK(pdg_solve(ws, &s, NULL, &r0) == PDG_SOLVED && log_rows(ws) > 0);
    CHECK(pdg_solve_tscvx(ws, &s, &o, &r, NULL) == PDG_INVALID_INPUT);
    CHECK(strstr(r.message, "eta_init") != NULL);
    CHECK(log_rows(ws) == 0); /* a refused call leaves no record of the solve before */
    o.eta_init = 20.0; /* above eta_ub = 10: refused, not replaced by the default */
    CHECK(pdg_solve_tscvx(ws, &s, &o, &r, NULL) == PDG_INVALID_INPUT);
    CHECK(strstr(r.message, "[eta_lb, eta_ub] = [0.001, 10], got 20") != NULL);
    o.eta_init = NAN;
    CHECK(pdg_solve_tscvx(ws, &s, &o, &r, NULL) == PDG_INVALID_INPUT);
    o.eta_init = 0.0;
    /* settings whose eta_lb = 0.1 exclude Table 1's 0.01: refused, not started below eta_lb */
    ws_lb = make_ws(N, 0.1, &arena_lb);
    CHECK(ws_lb != NULL);
    if (ws_lb) {
        expect_refused(ws_lb, &s, sol, NULL, "Table 1's radius is outside the settings' bounds");
    }
    /* networks trained for N = 50 against a workspace for N = 30 */
    s30 = s;
    s30.params.N = 30;
    ws30 = make_ws(30, 0.0, &arena30);
    CHECK(ws30 != NULL);
    if (ws30) {
        expect_refused(ws30, &s30, sol, NULL, "trained for N = 50");
        expect_refused(ws30, &s30, NULL, con, "N = 30");
        CHECK(pdg_tscvx_guess(ws30, &s30, sol, gx, gu, &tf, msg) == PDG_INVALID_INPUT);
        CHECK(strstr(msg, "N = 30") != NULL);
    }

    /* pdg_tscvx_guess refuses a missing output, a network overwritten since its init and a
     * call from inside a running solve on the workspace, each with its message */
    CHECK(pdg_tscvx_guess(ws, &s, sol, NULL, gu, &tf, msg) == PDG_INVALID_INPUT);
    CHECK(strstr(msg, "NULL") != NULL);
    {
        unsigned char *saved = malloc(net_bytes[0]);
        CHECK(saved != NULL);
        if (saved) {
            memcpy(saved, net_arena[0], net_bytes[0]);
            memset(net_arena[0], 0x5A, net_bytes[0]);
            CHECK(pdg_tscvx_guess(ws, &s, sol, gx, gu, &tf, msg) == PDG_INVALID_INPUT);
            CHECK(strstr(msg, "nets: the solution network: ") != NULL);
            memcpy(net_arena[0], saved, net_bytes[0]); /* the same bytes: the same net */
            free(saved);
        }
    }
    {
        guess_inside_ctx g = {NULL, NULL, NULL, 0};
        pdg_options po;
        memset(&po, 0, sizeof po);
        g.ws = ws, g.s = &s, g.sol = sol;
        po.mask_fn = guess_inside;
        po.mask_ctx = &g;
        r0.x = x;
        r0.u = u;
        CHECK(pdg_solve(ws, &s, &po, &r0) == PDG_SOLVED);
        CHECK(g.refused == r0.subproblems_solved && g.refused > 0);
    }

    /* the projected warm start meets the boundary conditions */
    CHECK(pdg_tscvx_guess(ws, &s, sol, gx, gu, &tf, msg) == 0);
    CHECK(tf > 0.0 && fabs(gx[0] - s.r0[0]) < 1e-15 && gx[13] == s.m0);
    for (i = 0; i < 3; ++i) {
        CHECK(gx[PDG_NSTATE * (N - 1) + i] == s.params.r_f[i]);
        CHECK(gx[PDG_NSTATE * (N - 1) + 3 + i] == s.params.v_f[i]);
    }

    /* plain SCvx, then T-SCvx without and with masks */
    r0.x = x;
    r0.u = u;
    CHECK(pdg_solve(ws, &s, NULL, &r0) == PDG_SOLVED);
    m_scvx = x[PDG_NSTATE * (N - 1) + 13];
    iters_scvx = r0.iterations;
    o.solution = NULL;
    o.constraint = NULL;
    CHECK(pdg_solve_tscvx(ws, &s, &o, &r, &rep) == PDG_SOLVED); /* no networks: pdg_solve */
    CHECK(r.iterations == iters_scvx && x[PDG_NSTATE * (N - 1) + 13] == m_scvx);
    CHECK(!rep.warm_started && rep.masks_predicted == 0);
    o.solution = sol;
    CHECK(pdg_solve_tscvx(ws, &s, &o, &r, &rep) == PDG_SOLVED);
    CHECK(rep.warm_started && rep.eta_init == PDG_TSCVX_ETA_INIT && rep.masks_predicted == 0);
    {
        pdg_log_row row;
        CHECK(pdg_get_log(ws, 0, &row) == PDG_SETUP_OK && row.eta == PDG_TSCVX_ETA_INIT);
    }
    o.constraint = con;
    CHECK(pdg_solve_tscvx(ws, &s, &o, &r, &rep) == PDG_SOLVED);
    CHECK(rep.masks_predicted == r.subproblems_solved && rep.mask_failures == 0);
    CHECK(r.max_violation <= 1e-6 && r.max_defect <= 1e-3);
    printf("T-SCvx: %d iterations, %d subproblems, m_f %.6f (SCvx %d iterations, m_f %.6f)\n",
           r.iterations, r.subproblems_solved, x[PDG_NSTATE * (N - 1) + 13], iters_scvx,
           m_scvx);

    overflowing_constraint_net(ws, &s, sol, blob[1], len[1]);

    /* the end check of pdg_solve_tscvx: each network, and the guidance workspace */
    upset_after_last_solve(ws, &s, sol, con, &con->ff,
                           "nets: the constraint network was damaged during the call (the end "
                           "check: ");
    upset_after_last_solve(ws, &s, sol, con, &sol->d_in,
                           "nets: the solution network was damaged during the call (the end "
                           "check: ");
    upset_after_last_solve(ws, &s, sol, con, &ws->dest[3],
                           "workspace damaged during the call (the end check: set-up checksum "
                           "mismatch in the guidance workspace's");

    free(arena);
    free(arena30);
    free(arena_lb);
    for (i = 0; i < 2; ++i) {
        free(net_arena[i]);
        free(blob[i]);
    }
    return gnc_report("test_tscvx");
}
