/*
 * pdg_budget_driver.c -- one complete guidance call, for the RAD750 budget (guidance/budget.py).
 *
 *   pdg_budget_driver [--repeat R] [--nodes N] [--landing THETA]
 *                     [--tscvx SOLUTION.tnn [--masks CONSTRAINT.tnn]]
 *
 * Sets up the workspace for the default scenario (on N nodes with --nodes: the same landing on
 * another grid; with --landing another landing of the default vehicle, THETA its 16 numbers
 * comma-separated in the order of guidance/sampling.py's theta: r0 (3), v0 (3), q0 (4),
 * w0 (3), m0, glideslope_deg, tilt_max_deg), outside the measured call, then calls
 * pdg_solve once (R times for wall-clock timing); with --tscvx the measured call is the
 * complete on-board T-SCvx call pdg_solve_tscvx (solution-network inference, projection, SCvx
 * from the reduced radius, and with --masks a constraint-network inference per subproblem
 * iteration), the networks set up in their own arenas before it. Instructions are counted by
 * running this program under `valgrind --tool=callgrind --toggle-collect=pdg_solve` (or
 * pdg_solve_tscvx). It prints
 * `key value` lines: status, iterations, m_f, a digest of the answer (solution_fnv1a), arena
 * bytes, arena high-water, the stack high-water of pdg_solve (measured by painting the stack
 * below the caller's frame with a pattern and finding the deepest overwritten byte), heap
 * allocations made inside pdg_solve (malloc interposition), the wall time per call and, for
 * T-SCvx, the weight bytes (blobs read in place) and network arena bytes. A bad argument (an
 * unknown option, a number that is not one or out of its range, a landing the library's
 * pdg_validate_scenario refuses) gets the reason and the usage on stderr and exit 1, before
 * any call; a call made exits 0 when solved, 3 otherwise.
 */
#define _GNU_SOURCE
#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "tscvx_guidance.h"
#include "tscvx_nn.h"

#include "host_io.h"
#include "measure.h"

static pdg_tscvx_options tscvx_opt;
static pdg_tscvx_report tscvx_rep;
static int use_tscvx = 0;

static __attribute__((noinline)) pdg_status measured_call(pdg_workspace *ws,
                                                          const pdg_scenario *scn,
                                                          pdg_result *res)
{
    return use_tscvx ? pdg_solve_tscvx(ws, scn, &tscvx_opt, res, &tscvx_rep)
                     : pdg_solve(ws, scn, NULL, res);
}

/* FNV-1a of the answer, x (N x 14) then u (N x 3), each double's bits least significant byte
 * first: the same digest for the same numbers whatever the host's byte order (`make
 * check-ppc` compares the PowerPC build's landing with the x86 build's by it). */
static uint64_t solution_digest(const pdg_result *res, int N)
{
    const double *v[2] = {res->x, res->u};
    const size_t n[2] = {(size_t)N * PDG_NSTATE, (size_t)N * PDG_NCTRL};
    uint64_t h = 0xCBF29CE484222325ull, bits;
    size_t i;
    int a, k;
    for (a = 0; a < 2; ++a) {
        for (i = 0; i < n[a]; ++i) {
            memcpy(&bits, &v[a][i], sizeof bits);
            for (k = 0; k < 8; ++k) {
                h = (h ^ ((bits >> (8 * k)) & 0xFFu)) * 0x100000001B3ull;
            }
        }
    }
    return h;
}

/* The call's answer as `key value` lines (guidance/budget.py reads them). */
static void print_result(pdg_status status, const pdg_result *res, int N)
{
    printf("status %s\n", pdg_status_name(status));
    if (status != PDG_SOLVED) {
        printf("message %s\n", res->message);
    }
    printf("iterations %d\n", res->iterations);
    printf("subproblems %d\n", res->subproblems_solved);
    printf("socp_iterations %d\n", res->socp_iterations);
    printf("m_f %.12f\n", res->x[PDG_NSTATE * (N - 1) + 13]);
    printf("solution_fnv1a %016llx\n", (unsigned long long)solution_digest(res, N));
}

/* The two networks of a T-SCvx call: the files, their blobs and arenas (index 0: solution,
 * 1: constraint; none for SCvx). */
typedef struct {
    const char *path[2];
    unsigned char *blob[2];
    void *arena[2];
    size_t blob_len[2], bytes[2];
    tscvx_nn *net[2];
} networks;

#define N_THETA 16 /* guidance/sampling.py's theta */

static const char usage[] =
    "usage: pdg_budget_driver [--repeat R] [--nodes N] [--landing THETA]\n"
    "                         [--tscvx SOLUTION.tnn [--masks CONSTRAINT.tnn]]\n"
    "  R in [1, 1000]; N in [%d, %d]; THETA: 16 comma-separated numbers,\n"
    "  r0 (3), v0 (3), q0 (4), w0 (3), m0, glideslope_deg, tilt_max_deg\n";

/* The driver's command line: what parse_args fills. */
typedef struct {
    int repeat, nodes; /* nodes 0: the scenario's own N */
    int has_landing;
    double theta[N_THETA];
} options;

/* A whole-string integer in [lo, hi]: 0, or 1 for anything else (no sign games, no
 * trailing characters, no overflow). */
static int parse_int(const char *s, long lo, long hi, int *out)
{
    char *end;
    long v;
    errno = 0;
    v = strtol(s, &end, 10);
    if (end == s || *end != '\0' || errno != 0 || v < lo || v > hi) {
        return 1;
    }
    *out = (int)v;
    return 0;
}

/* Exactly N_THETA finite numbers separated by single commas (strtod each; no blank, which
 * strtod would skip, nothing between a number and its comma, no empty field, no overflow or
 * underflow): 0, or 1. */
static int parse_theta(const char *s, double theta[N_THETA])
{
    int k;
    for (k = 0; k < N_THETA; ++k) {
        char *end;
        if (isspace((unsigned char)*s)) {
            return 1;
        }
        errno = 0;
        theta[k] = strtod(s, &end);
        if (end == s || errno != 0 || !isfinite(theta[k])) {
            return 1;
        }
        if (k < N_THETA - 1 ? *end != ',' : *end != '\0') {
            return 1;
        }
        s = end + 1;
    }
    return 0;
}

/* --repeat R, --nodes N, --landing THETA, --tscvx FILE, --masks FILE; 0, or 1 (with the
 * reason on stderr) for an unknown option or one without its value, a number that is not
 * one or out of its range, or --masks without --tscvx. */
static int parse_args(int argc, char **argv, options *o, networks *nn)
{
    int i;
    for (i = 1; i < argc; i += 2) {
        const char *v;
        if (i + 1 >= argc) {
            fprintf(stderr, "%s: needs a value\n", argv[i]);
            return 1;
        }
        v = argv[i + 1];
        if (strcmp(argv[i], "--repeat") == 0) {
            if (parse_int(v, 1, 1000, &o->repeat)) {
                fprintf(stderr, "--repeat %s: R must be an integer in [1, 1000]\n", v);
                return 1;
            }
        } else if (strcmp(argv[i], "--nodes") == 0) {
            if (parse_int(v, PDG_N_MIN, PDG_N_MAX, &o->nodes)) {
                fprintf(stderr, "--nodes %s: N must be an integer in [%d, %d]\n", v, PDG_N_MIN,
                        PDG_N_MAX);
                return 1;
            }
        } else if (strcmp(argv[i], "--landing") == 0) {
            if (parse_theta(v, o->theta)) {
                fprintf(stderr, "--landing %s: THETA must be %d finite numbers, "
                                "comma-separated\n", v, N_THETA);
                return 1;
            }
            o->has_landing = 1;
        } else if (strcmp(argv[i], "--tscvx") == 0) {
            nn->path[0] = v;
        } else if (strcmp(argv[i], "--masks") == 0) {
            nn->path[1] = v;
        } else {
            fprintf(stderr, "%s: unknown option\n", argv[i]);
            return 1;
        }
    }
    if (nn->path[1] && !nn->path[0]) {
        fprintf(stderr, "--masks needs --tscvx\n");
        return 1;
    }
    return 0;
}

/* The default scenario, turned into the landing of theta (the default vehicle otherwise, as
 * guidance/sampling.py's scenario_of) and on N nodes when asked; 0, or 1 with the reason on
 * stderr when the library refuses the landing. */
static int scenario_from(const options *o, pdg_scenario *scn)
{
    char message[PDG_MESSAGE_LEN];
    int k;
    pdg_default_scenario(scn);
    if (o->nodes) {
        scn->params.N = o->nodes;
    }
    if (!o->has_landing) {
        return 0;
    }
    for (k = 0; k < 3; ++k) {
        scn->r0[k] = o->theta[k];
        scn->v0[k] = o->theta[3 + k];
        scn->w0[k] = o->theta[10 + k];
    }
    for (k = 0; k < 4; ++k) {
        scn->q0[k] = o->theta[6 + k];
    }
    scn->m0 = o->theta[13];
    scn->params.glideslope_deg = o->theta[14];
    scn->params.tilt_max_deg = o->theta[15];
    if (pdg_validate_scenario(scn, message) != 0) {
        fprintf(stderr, "--landing: %s\n", message);
        return 1;
    }
    return 0;
}

/* The default scenario's workspace in a zeroed malloc'ed arena (*need bytes), sized by the
 * library's retry protocol; NULL (with the reason on stderr) when that fails. */
static pdg_workspace *set_up(const pdg_scenario *scn, const pdg_settings *st, void **arena,
                             size_t *need)
{
    pdg_workspace *ws = NULL;
    pdg_setup_status s = PDG_SETUP_SCRATCH_TOO_SMALL;
    int tries;
    *arena = NULL;
    *need = 0;
    for (tries = 0; tries < 4 && s == PDG_SETUP_SCRATCH_TOO_SMALL; ++tries) {
        free(*arena);
        *arena = *need ? malloc(*need) : NULL;
        s = pdg_workspace_size(&scn->params, st, *arena, *need, need);
    }
    free(*arena);
    if (s != PDG_SETUP_OK || !(*arena = malloc(*need))) {
        fprintf(stderr, "sizing failed: %s\n", pdg_setup_status_message(s));
        return NULL;
    }
    memset(*arena, 0, *need);
    s = pdg_setup(&ws, *arena, *need, &scn->params, st);
    if (s != PDG_SETUP_OK) {
        fprintf(stderr, "pdg_setup: %s\n", pdg_setup_status_message(s));
        return NULL;
    }
    return ws;
}

/* The measured call: once with the stack painted and allocations counted, then repeat - 1
 * more times for the fastest wall time. */
static pdg_status measure(pdg_workspace *ws, const pdg_scenario *scn, pdg_result *res,
                          int repeat, double *wall, size_t *stack)
{
    pdg_status status;
    double t0;
    int i;
    paint_stack();
    counting = 1;
    t0 = now_s();
    status = measured_call(ws, scn, res);
    *wall = now_s() - t0;
    counting = 0;
    *stack = painted_depth();
    for (i = 1; i < repeat; ++i) {
        double dt;
        t0 = now_s();
        measured_call(ws, scn, res);
        dt = now_s() - t0; /* read once: the minimum is of measured times */
        *wall = dt < *wall ? dt : *wall;
    }
    return status;
}

static void print_report(pdg_status status, const pdg_result *res, const pdg_scenario *scn,
                         const pdg_workspace *ws, size_t need, size_t stack, double wall,
                         const networks *nn)
{
    printf("mode %s\n", !use_tscvx ? "scvx" : (nn->net[1] ? "tscvx_masks" : "tscvx"));
    printf("nodes %d\n", scn->params.N);
    print_result(status, res, scn->params.N);
    printf("arena_bytes %zu\n", need);
    size_t high_water = 0;
    pdg_arena_high_water(ws, &high_water);
    printf("arena_high_water %zu\n", high_water);
    printf("stack_high_water %zu\n", stack);
    printf("heap_allocations_in_solve %ld\n", n_alloc);
    printf("wall_s_min %.6f\n", wall);
    printf("nn_weights_bytes %zu\n", nn->blob_len[0] + nn->blob_len[1]);
    printf("nn_arena_bytes %zu\n", nn->bytes[0] + nn->bytes[1]);
    /* the caller's answer arrays, x (N x 14) and u (N x 3), as a flight caller sizes them
     * (this driver's are static at PDG_N_MAX) */
    printf("result_bytes %zu\n",
           sizeof(double) * (size_t)scn->params.N * (PDG_NSTATE + PDG_NCTRL));
    if (use_tscvx) {
        printf("masks_predicted %d\n", tscvx_rep.masks_predicted);
        printf("mask_failures %d\n", tscvx_rep.mask_failures);
    }
}

static void release(void *arena, networks *nn)
{
    int i;
    free(arena);
    for (i = 0; i < 2; ++i) {
        free(nn->arena[i]);
        free(nn->blob[i]);
    }
}

int main(int argc, char **argv)
{
    static double x[PDG_N_MAX * PDG_NSTATE], u[PDG_N_MAX * PDG_NCTRL];
    static networks nn; /* zeroed */
    pdg_settings st;
    pdg_scenario scn;
    pdg_result res;
    pdg_workspace *ws;
    void *arena = NULL;
    size_t need = 0, stack = 0;
    options o = {1, 0, 0, {0.0}};
    int i;
    double wall = 0.0;
    pdg_status status;

    pdg_default_settings(&st);
    if (parse_args(argc, argv, &o, &nn) || scenario_from(&o, &scn)) {
        fprintf(stderr, usage, PDG_N_MIN, PDG_N_MAX);
        return 1;
    }
    for (i = 0; i < 2; ++i) {
        if (nn.path[i] && load_net(nn.path[i], &nn.blob[i], &nn.blob_len[i], &nn.arena[i],
                                   &nn.bytes[i], &nn.net[i])) {
            release(NULL, &nn);
            return 1;
        }
    }
    use_tscvx = nn.path[0] != NULL;
    tscvx_opt.solution = nn.net[0];
    tscvx_opt.constraint = nn.net[1];
    ws = set_up(&scn, &st, &arena, &need);
    if (!ws) {
        release(arena, &nn);
        return 1;
    }
    res.x = x;
    res.u = u;
    status = measure(ws, &scn, &res, o.repeat, &wall, &stack);
    print_report(status, &res, &scn, ws, need, stack, wall, &nn);
    release(arena, &nn);
    return status == PDG_SOLVED ? 0 : 3;
}
