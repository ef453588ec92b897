/*
 * gnc_test.h -- what the C guidance tests share: the CHECK counter, trajectory buffers and
 * the arena sizing loop (scratch for pdg_workspace_size grows until it suffices).
 */
#ifndef TSCVX_GNC_TEST_H
#define TSCVX_GNC_TEST_H

#include <limits.h>
#include <stdio.h>
#include <stdlib.h>

#include "tscvx_guidance.h"

static int failures = 0;
#define CHECK(cond)                                                                  \
    do {                                                                             \
        if (!(cond)) {                                                               \
            fprintf(stderr, "%s:%d: CHECK failed: %s\n", __FILE__, __LINE__, #cond); \
            failures++;                                                              \
        }                                                                            \
    } while (0)

/* main's exit status: 1 after any failed CHECK (counted on stderr), 0 with `name`'s all-clear */
static inline int gnc_report(const char *name)
{
    if (failures) {
        fprintf(stderr, "%s: %d check(s) failed\n", name, failures);
        return 1;
    }
    printf("%s: all checks passed\n", name);
    return 0;
}

static double x[PDG_N_MAX * PDG_NSTATE], u[PDG_N_MAX * PDG_NCTRL];

/* The default vehicle with N nodes and the terminal condition roll_free (one static copy:
 * use it in the call it is made for) */
static inline const pdg_params *vehicle(int N, int roll_free)
{
    static pdg_params p;
    pdg_default_params(&p);
    p.N = N;
    p.final_roll_free = roll_free;
    return &p;
}

/* Clock standing for an upset after the last subproblem's solve: a solve reads the clock
 * before and after each subproblem's conic solve (reads 2i - 1 and 2i of subproblem i), so at
 * read clock_upset_read = 2 x the subproblems it flips a high bit of *clock_upset_at, after
 * the SOCP runtime's own end check, and the call goes on (the candidate's evaluation, the
 * acceptance and convergence tests, the answer). 0: counts the reads only. */
static int clock_reads, clock_upset_read;
static int *clock_upset_at;

static inline double upset_clock(void)
{
    if (++clock_reads == clock_upset_read && clock_upset_at) {
        *clock_upset_at ^= 1 << 20;
    }
    return 0.0;
}

/* The last solve's log rows (-1 when the library refuses to say). */
static inline int log_rows(const pdg_workspace *ws)
{
    int rows = -1;
    return pdg_log_length(ws, &rows) == PDG_SETUP_OK ? rows : -1;
}

/* The IPM iterations of the last solve's log rows, summed, each row read (CHECKed); *fewest,
 * unless NULL, the fewest of a row (INT_MAX without rows). */
static inline int logged_iterations(const pdg_workspace *ws, int *fewest)
{
    pdg_log_row row;
    int i, sum = 0, least = INT_MAX;
    for (i = 0; i < log_rows(ws); ++i) {
        CHECK(pdg_get_log(ws, i, &row) == PDG_SETUP_OK);
        sum += row.solver_iterations;
        least = row.solver_iterations < least ? row.solver_iterations : least;
    }
    if (fewest) {
        *fewest = least;
    }
    return sum;
}

/* Arena bytes for (N, roll_free, settings) in *need; *tries counts the sizing calls. */
static inline pdg_setup_status arena_size(int N, int roll_free, const pdg_settings *st,
                                          size_t *need, int *tries)
{
    void *scratch = NULL;
    pdg_setup_status s = PDG_SETUP_SCRATCH_TOO_SMALL;
    *need = 0;
    for (*tries = 0; *tries < 4 && s == PDG_SETUP_SCRATCH_TOO_SMALL; ++*tries) {
        free(scratch);
        scratch = *need ? malloc(*need) : NULL;
        s = pdg_workspace_size(vehicle(N, roll_free), st, scratch, *need, need);
    }
    free(scratch);
    return s;
}

#endif
