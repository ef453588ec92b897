/*
 * pdg_example.c -- the flight guidance library used from plain C, without Python.
 *
 *   pdg_example                                   SCvx (pdg_solve), then a re-plan in flight
 *                                                 from a third of the way (pdg_plan_remainder)
 *   pdg_example SOLUTION.tnn [CONSTRAINT.tnn]      T-SCvx on board (pdg_solve_tscvx): the
 *                                                 solution network's warm start, and with the
 *                                                 second file the constraint network's masks
 *
 * Solves the default landing scenario of DESIGN.md and prints the iteration log, the
 * summary and the trajectory (one line per node), following the lifecycle at the top of
 * tscvx_guidance.h. The weight files are build/models/{solution,constraint}.tnn (`make lib`). Links only the static libraries and their Debian dependencies:
 *
 *   cc -std=c99 -Ic_runtime/include pdg_example.c build/libtscvx_gnc.a build/libtscvx.a \
 *      -lamd -lldl -lsuitesparseconfig -lm
 *
 * Exit status: 0 solved (the re-plan too), 3 not solved (the status line says why), 2 input refused by the
 * library or a usage error (nothing solved: the message on stderr, no log or trajectory; a
 * usage error prints nothing else, a refused network follows the networks' size lines), 1
 * set-up failure (a file that cannot be read included).
 *
 * All memory comes from arenas obtained once before the solve (malloc here stands for the
 * flight computer's statically reserved SRAM blocks: the guidance arena, one per network, and
 * the weight blobs read in place); the library never allocates.
 */
#define _POSIX_C_SOURCE 199309L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "host_io.h"
#include "tscvx_guidance.h"
#include "tscvx_nn.h"

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* The memory this program claims before the solve: the guidance arena, and per network its
 * weight blob (read in place) and its arena. */
typedef struct {
    void *arena;
    size_t bytes;
    unsigned char *blobs[2];
    size_t blob_len[2];
    void *net_arenas[2];
    size_t net_bytes[2];
    tscvx_nn *nets[2]; /* solution, constraint */
} memory;

static void release(memory *m)
{
    int i;
    free(m->arena);
    for (i = 0; i < 2; ++i) {
        free(m->net_arenas[i]);
        free(m->blobs[i]);
    }
}

/* Lifecycle steps 2 and 3: size the arena (the scratch may be reused as the arena; at most
 * two retries), then set up in it. 0 = ok, else a message on stderr. */
static int set_up(const pdg_scenario *scn, const pdg_settings *st, memory *m,
                  pdg_workspace **ws)
{
    pdg_setup_status s = PDG_SETUP_SCRATCH_TOO_SMALL;
    void *scratch = NULL;
    size_t need = 0;
    int tries;
    for (tries = 0; tries < 4 && s == PDG_SETUP_SCRATCH_TOO_SMALL; ++tries) {
        free(scratch);
        scratch = need ? malloc(need) : NULL;
        if (need && !scratch) {
            fprintf(stderr, "out of memory\n");
            return 1;
        }
        s = pdg_workspace_size(&scn->params, st, scratch, need, &need);
    }
    free(scratch);
    if (s != PDG_SETUP_OK) {
        fprintf(stderr, "pdg_workspace_size: %s\n", pdg_setup_status_message(s));
        return 1;
    }
    m->arena = malloc(need);
    m->bytes = need;
    if (!m->arena) {
        fprintf(stderr, "out of memory\n");
        return 1;
    }
    s = pdg_setup(ws, m->arena, need, &scn->params, st);
    if (s != PDG_SETUP_OK) {
        fprintf(stderr, "pdg_setup: %s\n", pdg_setup_status_message(s));
        return 1;
    }
    return 0;
}

/* Lifecycle step 5: the iteration log of the last solve. */
static void print_log(const pdg_workspace *ws)
{
    int i, rows = 0;
    pdg_log_length(ws, &rows); /* rows stays 0 for a workspace not set up */
    printf("  k        J         dJ         dL        rho    radius   |vc|_1  tight  sub[ms]  "
           "step\n");
    for (i = 0; i < rows; ++i) {
        pdg_log_row r;
        if (pdg_get_log(ws, i, &r) != PDG_SETUP_OK) {
            break;
        }
        printf("%3d %10.5f %10.3e %10.3e %8.3f %9.4f %8.1e %6d %8.1f  %s", r.k, r.J, r.dJ,
               r.dL, r.rho, r.eta, r.vc_norm1, r.n_tight, 1e3 * r.subproblem_time_s,
               r.accepted ? "acc" : "rej");
        if (r.restored) { /* the full-constraint guard's rejection (same radius) */
            printf(", %d put back", r.restored);
        }
        printf("\n");
    }
}

/* The summary of the answer. */
static void print_summary(const pdg_scenario *scn, const pdg_result *res)
{
    const int N = scn->params.N;
    const double m_f = res->x[PDG_NSTATE * (N - 1) + 13];
    printf("status %s (%s)\niterations %d, subproblems %d, t_f %.6f, m_f %.6f, fuel %.6f\n",
           pdg_status_name(res->status), res->message, res->iterations, res->subproblems_solved,
           res->t_f, m_f, scn->m0 - m_f);
    printf("largest defect %.2e, largest path-constraint value %.2e\n", res->max_defect,
           res->max_violation);
    if (res->polish == PDG_POLISH_KEPT) {
        printf("polish: largest defect %.2e before, final mass %+.2e, %d IPM iterations\n",
               res->defect_before_polish, m_f - res->m_f_before_polish, res->polish_iterations);
    } else if (res->polish != PDG_POLISH_OFF) {
        printf("polish: %s\n", pdg_polish_message(res->polish));
    }
}

/* One line per node: t, the state x and the thrust T_B with its norm. */
static void print_trajectory(const pdg_scenario *scn, const pdg_result *res)
{
    const int N = scn->params.N;
    int i, k;
    printf("\n node      t      r1       r2       r3       v1       v2       v3       q0       "
           "q1       q2       q3       w1       w2       w3       m        T1       T2       "
           "T3      |T|\n");
    for (k = 0; k < N; ++k) {
        const double *xk = res->x + PDG_NSTATE * k, *uk = res->u + PDG_NCTRL * k;
        printf("%4d %7.4f", k, res->t_f * k / (N - 1));
        for (i = 0; i < PDG_NSTATE; ++i) {
            printf(" %8.4f", xk[i]);
        }
        printf(" %8.4f %8.4f %8.4f %8.4f\n", uk[0], uk[1], uk[2],
               sqrt(uk[0] * uk[0] + uk[1] * uk[1] + uk[2] * uk[2]));
    }
}

/* In-flight re-planning (pdg_plan_remainder): the landing from the plan's state at node k,
 * standing in for the state navigation measures there (its roll rate zero: the vehicle makes
 * no roll torque), started from the rest of the plan. Returns the solve's status. */
static pdg_status replan(pdg_workspace *ws, const pdg_scenario *scn, const pdg_result *plan,
                         int k)
{
    static double gx[PDG_N_MAX * PDG_NSTATE], gu[PDG_N_MAX * PDG_NCTRL];
    static double x[PDG_N_MAX * PDG_NSTATE], u[PDG_N_MAX * PDG_NCTRL];
    const int N = scn->params.N;
    const double t1 = plan->t_f * k / (N - 1);
    pdg_scenario here;
    pdg_options o = {0};
    pdg_result r;
    pdg_status status;
    double t0;
    if (pdg_scenario_at_state(scn, plan->x + PDG_NSTATE * k, &here, r.message) != 0 ||
        pdg_plan_remainder(&here, plan->x, plan->u, plan->t_f, t1, gx, gu, &o.guess_t_f,
                           r.message) != 0) {
        fprintf(stderr, "re-plan refused: %s\n", r.message);
        return PDG_INVALID_INPUT;
    }
    o.guess_x = gx;
    o.guess_u = gu;
    r.x = x;
    r.u = u;
    t0 = now_s();
    status = pdg_solve(ws, &here, &o, &r);
    printf("re-plan at t = %.4f (node %d) from the rest of the plan: %s (%s), %d subproblems, "
           "%.1f ms, touchdown at %.6f, m_f %.6f\n",
           t1, k, pdg_status_name(status), r.message, r.subproblems_solved,
           1e3 * (now_s() - t0), t1 + r.t_f, x[PDG_NSTATE * (N - 1) + 13]);
    return status;
}

/* T-SCvx's networks (solution, then constraint), each in its own arena. 0 = ok, else a
 * message on stderr. */
static int load_nets(int count, char **paths, memory *m)
{
    int i;
    for (i = 0; i < count && i < 2; ++i) {
        if (load_net(paths[i], &m->blobs[i], &m->blob_len[i], &m->net_arenas[i],
                     &m->net_bytes[i], &m->nets[i])) {
            return 1;
        }
        printf("network %s: %zu bytes of weights, arena %zu bytes\n", paths[i], m->blob_len[i],
               m->net_bytes[i]);
    }
    return 0;
}

int main(int argc, char **argv)
{
    memory mem = {0};
    pdg_settings st;
    pdg_scenario scn;
    pdg_workspace *ws = NULL;
    pdg_options opt = {0};
    pdg_tscvx_options topt = {0};
    pdg_tscvx_report rep;
    pdg_result res;
    pdg_status status;
    double x[PDG_N_MAX * PDG_NSTATE], u[PDG_N_MAX * PDG_NCTRL], t0;
    const int tscvx = argc > 1;

    if (argc > 3 || (argc > 1 && argv[1][0] == '-') || (argc > 2 && argv[2][0] == '-')) {
        fprintf(stderr, "usage: %s [SOLUTION.tnn [CONSTRAINT.tnn]]\n", argv[0]);
        return 2;
    }
    /* 1. Table 1's settings and the default scenario; 2.-3. the arena */
    pdg_default_settings(&st);
    pdg_default_scenario(&scn);
    if (set_up(&scn, &st, &mem, &ws) != 0) {
        release(&mem);
        return 1;
    }
    /* T-SCvx: the networks */
    if (load_nets(argc - 1, argv + 1, &mem) != 0) {
        release(&mem);
        return 1;
    }
    /* 4. solve */
    res.x = x;
    res.u = u;
    opt.clock_s = now_s;
    topt.solution = mem.nets[0];
    topt.constraint = mem.nets[1];
    topt.clock_s = now_s;
    t0 = now_s();
    status = tscvx ? pdg_solve_tscvx(ws, &scn, &topt, &res, &rep)
                   : pdg_solve(ws, &scn, &opt, &res);
    if (status == PDG_INVALID_INPUT) { /* nothing was solved: no log, no trajectory */
        fprintf(stderr, "refused: %s\n", res.message);
        release(&mem);
        return 2;
    }
    printf("%s time %.1f ms\n", tscvx ? "T-SCvx (networks included)" : "SCvx",
           1e3 * (now_s() - t0));
    if (tscvx) {
        printf("T-SCvx: warm start %s, initial radius %g, %d network masks, %d refused\n",
               rep.warm_started ? "yes" : "no", rep.eta_init, rep.masks_predicted,
               rep.mask_failures);
    }
    /* 5. the record of the solve, and its answer: a NaN t_f means none was returned (x and u
     *    untouched; the header lists when) */
    print_log(ws);
    if (isnan(res.t_f)) {
        printf("status %s (%s): no trajectory returned\n", pdg_status_name(res.status),
               res.message);
        release(&mem);
        return 3;
    }
    print_summary(&scn, &res);
    size_t high_water = 0;
    pdg_arena_high_water(ws, &high_water);
    printf("arena %zu bytes, high-water %zu bytes\n", mem.bytes, high_water);
    print_trajectory(&scn, &res);
    if (!tscvx && status == PDG_SOLVED) { /* the same workspace serves the re-plan */
        printf("\n");
        status = replan(ws, &scn, &res, scn.params.N / 3);
    }
    /* 6. cleanup: the arenas are the caller's */
    release(&mem);
    return status == PDG_SOLVED ? 0 : 3;
}
