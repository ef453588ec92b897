/*
 * tscvx_socp.h -- flight SOCP interior-point solver (the one public header).
 *
 * Problem form (all matrices in compressed sparse column form, 0-based):
 *
 *     minimize    1/2 x'Px + c'x
 *     subject to  A x = b                    (p equality rows)
 *                 G x + s = h,   s in K      (m cone rows)
 *
 *   x in R^n.  P (n x n) must be positive semidefinite (a convex objective) and is given by its
 *   UPPER triangle only (it may be absent: Pp == NULL). Setup and tscvx_update_data (when
 *   given P) refuse an indefinite P (TSCVX_SETUP_P_NOT_PSD) by a cheap necessary test (every
 *   P_jj >= 0, every P_ij^2 <= P_ii P_jj to 1e-12 relative) and then a factorization of P:
 *   the sparse method factors P + 1e-9 |P|_max I and checks its inertia, the banded method
 *   factors P's diagonal blocks, dropping zero pivots. A negative eigenvalue above about
 *   -1e-9 |P|_max (sparse method) or -1e-5 |P|_max (banded) passes as rounding.
 *   K = R_+^l  x  Q^{q_1} x ... x Q^{q_nsoc}: the first l rows of G are the nonnegative
 *   orthant, the following rows are second-order cones Q^q = {(t, u) in R x R^{q-1}: |u|_2 <= t}
 *   in the order given by q[]; l + sum(q) = m.
 *
 * Algorithm: primal-dual interior-point method on the homogeneous self-dual embedding
 * (quadratic objective as in Clarabel), Nesterov-Todd scaling, Mehrotra predictor-corrector,
 * Ruiz equilibration, static regularization of the quasi-definite KKT system with iterative
 * refinement, best-iterate fallback, primal/dual infeasibility certificates. Two ways to solve
 * the Newton systems (tscvx_settings.kkt_backend):
 *   - banded, for stage-structured problems (optimal control: each cone and P entry couples a
 *     few variables, the equalities couple neighbouring stages): the cone rows and then the
 *     variable groups are eliminated exactly (small dense Cholesky factors), and the remaining
 *     system in the equality multipliers is factored in a reverse Cuthill-McKee order by a
 *     profile Cholesky; variables coupled to very many equalities (a free final time) are
 *     bordered. Chosen by default when setup finds the structure;
 *   - sparse: the whole quasi-definite KKT matrix, ordered by SuiteSparse AMD and factored by
 *     our static-pattern LDL' (SuiteSparse LDL's arithmetic with the symbolic work done once at
 *     setup) or SuiteSparse LDL itself (the reference).
 *
 * Lifecycle (memory is claimed in exactly one place, from ONE caller-provided arena):
 *
 *   1. tscvx_default_settings(&st)                      -- defaults, edit as needed
 *   2. tscvx_scratch_size(&data, &st, &nscratch)         -- validates, then arithmetic
 *      tscvx_workspace_size(&data, &st, scratch, nscratch, &narena)
 *                                                       -- ordering + symbolic analysis in
 *                                                          caller scratch (contents clobbered;
 *                                                          the arena itself may be used)
 *   3. tscvx_setup(&ws, arena, narena, &data, &st)       -- validates the data, builds the KKT
 *                                                          pattern, maps and factor symbolics
 *   4. tscvx_update_data(ws, Px, c, Ax, b, Gx, h)        -- new numbers, same sparsity;
 *                                                          NULL = unchanged; no symbolic work
 *      tscvx_warm_start(ws, x, y, z, s)                  -- optional: where the next solve
 *                                                          starts (e.g. the last answer)
 *   5. tscvx_solve(ws)                                   -- no allocation, bounded loops
 *      tscvx_get_solution / tscvx_get_info / tscvx_get_iter_log
 *   6. tscvx_cleanup(ws)                                 -- ends the workspace (later calls
 *                                                          with it are refused); the caller
 *                                                          owns the arena and may reuse it
 *
 * The workspace is opaque and lives inside the arena. Every call taking it first checks a mark
 * that setup writes last and cleanup clears (and that the KKT method pointer is one of the
 * library's), so a workspace whose arena was reused or overwritten is refused
 * (TSCVX_SETUP_NOT_READY; tscvx_solve: TSCVX_INVALID_INPUT) before any of its pointers is
 * followed, when the reuse reached the mark or (below) what the checksums cover; the numbers
 * (data, iterates, the solution the getters copy) are covered by neither: the arena is the
 * workspace's alone until tscvx_cleanup. Then it checks a checksum of what setup fixed and the call relies on, so that a
 * bit flipped there with the mark intact (a single-event upset) is refused the same way,
 * nothing written, instead of sending a loop out of bounds; tscvx_check_workspace says
 * which check failed. Two 64-bit sums, taken at setup:
 *   - head: the workspace's settings, sizes, counts and every pointer into the arena (a few
 *     hundred bytes; tscvx_update_settings takes it again). Checked by every call but
 *     tscvx_cleanup (which follows no pointer and ends a damaged workspace too);
 *   - body: the index arrays: the patterns of P, A and G, the cone sizes and offsets, and
 *     the chosen KKT method's maps, ordering and symbolic factor (sparse: the permuted KKT
 *     pattern, its inverse permutation and row blocks, the maps of the data and cone block,
 *     L's pattern with the row patterns, or SuiteSparse LDL's elimination tree; banded: the
 *     groups, cones by group, G by rows, the groups' row lists, the band order, Y's profile
 *     and the value blocks' offsets). Checked by tscvx_update_data and tscvx_solve, the
 *     calls that follow them; the other calls index only by the head.
 * tscvx_solve checks the head and body again at its end, whatever the IPM's outcome: a bit
 * flipped in either during the solve (whose iterations may have followed it since) makes it
 * return TSCVX_INVALID_INPUT instead of its outcome, info.status says so, tscvx_get_solution
 * gives no iterate (TSCVX_SETUP_NO_SOLUTION) and tscvx_check_workspace says the workspace was
 * damaged "during a solve". Such a flip is thus reported by the solve it hit, not by the
 * next call; it may still have been followed before the end (the start check keeps a call
 * from following damage that was there when it began, the end check from answering with
 * damage that came during it). tscvx_update_data checks them again at its end in the same
 * way (28 Nov): a flip during the data intake makes it return TSCVX_SETUP_NOT_READY instead
 * of OK, info.status says invalid input, tscvx_check_workspace says the workspace was
 * damaged "during a data update", and, the numbers taken having gone through the damage,
 * the workspace waits for a valid update once the damage is repaired (as after a refused
 * update).
 * A change within any one 8-byte word of either is detected for certain (a word-wise hash,
 * each step a bijection), others with probability 1 - 2^-64. Not covered: the numbers, which
 * every update, solve or iteration writes again (the scaled data, iterates, NT scaling,
 * factors' values, work vectors, results and the log), so a flip there can spoil an answer
 * (the IPM's residual and finiteness checks catch much of it) but not send a loop out of
 * bounds; an upset during the other calls (tscvx_warm_start, tscvx_update_settings, the
 * getters) is seen by the next call that checks, not by the one running; and the caller's
 * arrays. The library never
 * calls malloc, has no recursion and no global mutable state. Every public function returns
 * a status code.
 */
#ifndef TSCVX_SOCP_H
#define TSCVX_SOCP_H

#include <stddef.h>

#include "tscvx_types.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---- status codes ------------------------------------------------------------------------ */

/* Errors of the set-up phase (settings, size queries, setup, data updates, getters). */
typedef enum {
    TSCVX_SETUP_OK = 0,
    TSCVX_SETUP_NULL_ARGUMENT,   /* a required pointer is NULL */
    TSCVX_SETUP_BAD_SETTINGS,    /* a setting is out of its documented range */
    TSCVX_SETUP_BAD_DIMENSIONS,  /* n <= 0, p < 0 or m < 0 */
    TSCVX_SETUP_BAD_CONES,       /* l < 0, nsoc < 0, a cone dimension < 1, or
                                    l + sum(q) != m (the cones cover more or fewer rows
                                    than G has) */
    TSCVX_SETUP_BAD_SPARSITY,    /* CSC pointers/indices invalid, unsorted or duplicated */
    TSCVX_SETUP_P_NOT_UPPER,     /* P has an entry below the diagonal (give the upper part) */
    TSCVX_SETUP_NONFINITE_DATA,  /* NaN or infinity in P, c, A, b, G or h */
    TSCVX_SETUP_SCRATCH_TOO_SMALL, /* scratch smaller than tscvx_scratch_size() */
    TSCVX_SETUP_ARENA_TOO_SMALL, /* arena smaller than tscvx_workspace_size() */
    TSCVX_SETUP_TOO_LARGE,       /* sizes overflow the index type, or the workspace would
                                    pass SIZE_MAX / 2 bytes (2 GiB with a 32-bit size_t) */
    TSCVX_SETUP_NOT_READY,       /* workspace not set up, cleaned up or overwritten,
                                    damaged (set-up checksum mismatch), or invalidated by a
                                    failed update (tscvx_check_workspace says which) */
    TSCVX_SETUP_BAD_INDEX,       /* iteration-log index out of range */
    TSCVX_SETUP_NOT_BANDED,      /* kkt_backend TSCVX_KKT_BANDED, but no banded structure */
    TSCVX_SETUP_P_NOT_PSD,       /* P fails the semidefiniteness check (see the problem form) */
    TSCVX_SETUP_NO_SOLUTION,     /* getters: no solve since setup or the last data update, or
                                    (tscvx_get_solution) the last one ended in NUMERICAL_ERROR
                                    or found the workspace damaged at its end */
    TSCVX_SETUP_NSTATUS
} tscvx_setup_status;

/* Outcome of tscvx_solve. */
typedef enum {
    TSCVX_UNSOLVED = 0,          /* solve not called since setup/update */
    TSCVX_SOLVED,                /* all tolerances met (a primal residual within 16 ulps
                                    of its row's terms counts as met: rounding) */
    TSCVX_SOLVED_INACCURATE,     /* reduced tolerances met (best iterate) */
    TSCVX_PRIMAL_INFEASIBLE,     /* certificate (y, z): A'y + G'z = 0, z in K, b'y + h'z < 0 */
    TSCVX_DUAL_INFEASIBLE,       /* certificate (x, s): Px = 0, Ax = 0, Gx + s = 0, s in K, c'x < 0 */
    TSCVX_MAX_ITER,              /* iteration limit reached */
    TSCVX_NUMERICAL_ERROR,       /* factorization or step failure, no acceptable iterate */
    TSCVX_INVALID_INPUT,         /* workspace not ready (setup or update failed, cleaned up,
                                    overwritten or damaged: tscvx_check_workspace), found at
                                    the start of the solve or, damaged during it, at its end
                                    (then no answer: the iterate is not returned) */
    TSCVX_NSTATUS
} tscvx_solve_status;

const char *tscvx_setup_status_message(tscvx_setup_status status);
const char *tscvx_solve_status_message(tscvx_solve_status status);

/* ---- problem data (read during setup/update only; never modified, never kept) ----------- */

typedef struct {
    tscvx_int n;                 /* number of variables, >= 1 */
    tscvx_int p;                 /* number of equality rows, >= 0 */
    tscvx_int m;                 /* number of cone rows, >= 0 */
    const tscvx_int *Pp;         /* n+1 column pointers of P's upper triangle, or NULL (P = 0) */
    const tscvx_int *Pi;         /* nnz(P) row indices, sorted within a column, row <= col */
    const tscvx_float *Px;       /* nnz(P) values */
    const tscvx_float *c;        /* n linear cost */
    const tscvx_int *Ap;         /* n+1 column pointers of A (p x n); may be NULL when p == 0 */
    const tscvx_int *Ai;         /* nnz(A) row indices, sorted within a column */
    const tscvx_float *Ax;       /* nnz(A) values */
    const tscvx_float *b;        /* p right-hand side */
    const tscvx_int *Gp;         /* n+1 column pointers of G (m x n); may be NULL when m == 0 */
    const tscvx_int *Gi;         /* nnz(G) row indices, sorted within a column */
    const tscvx_float *Gx;       /* nnz(G) values */
    const tscvx_float *h;        /* m right-hand side */
    tscvx_int l;                 /* dimension of the nonnegative orthant (first l rows of G),
                                    >= 0 */
    tscvx_int nsoc;              /* number of second-order cones, >= 0 */
    const tscvx_int *q;          /* nsoc cone dimensions (each >= 1), in row order after l */
} tscvx_data;

/* Why setup (and the size queries) would refuse `data`: the same checks in the same order,
 * the same status, and in `message` (TSCVX_MESSAGE_LEN bytes; may be NULL) the array and the
 * entry at fault, e.g. "G: row index 5 in column 1 is outside 0..2" or "c[3] = nan";
 * TSCVX_SETUP_OK and "" for data they accept. Two checks of setup are not repeated here:
 * the factorization test of P (TSCVX_SETUP_P_NOT_PSD from setup with an OK here means it) and
 * the size of the KKT system, which depends on the settings (soc_dense_max, the method):
 * TSCVX_SETUP_TOO_LARGE. */
#define TSCVX_MESSAGE_LEN 160
tscvx_setup_status tscvx_check_data(const tscvx_data *data, char *message);

/* KKT methods (tscvx_settings.kkt_backend): AUTO = banded when setup finds the structure,
 * else STATIC; LDL and STATIC are the sparse method's two factorizations. */
enum { TSCVX_KKT_AUTO = 0, TSCVX_KKT_LDL = 1, TSCVX_KKT_STATIC = 2, TSCVX_KKT_BANDED = 3 };

/* ---- settings ---------------------------------------------------------------------------- */

typedef struct {
    tscvx_int max_iter;          /* IPM iteration limit, 1..500 (fixes the log size at setup);
                                    per run: a warm-started solve that fails runs again cold,
                                    so one tscvx_solve takes at most 2 max_iter */
    tscvx_float tol_gap_abs;     /* |pcost - dcost| <= tol_gap_abs, or ..., (0, 1) */
    tscvx_float tol_gap_rel;     /* ... <= tol_gap_rel * max(1, min(|pcost|, |dcost|)), (0, 1) */
    tscvx_float tol_feas;        /* |Ax-b|,|Gx+s-h| <= tol_feas (1 + |b,h|); dual same with c,
                                    (0, 1) */
    tscvx_float tol_infeas;      /* certificate residual / certificate objective, (0, 1) */
    tscvx_float tol_gap_abs_inacc; /* reduced tolerances for SOLVED_INACCURATE: gap, > 0 */
    tscvx_float tol_gap_rel_inacc; /* relative gap, > 0 */
    tscvx_float tol_feas_inacc;    /* feasibility, > 0 */
    tscvx_float step_fraction;   /* fraction of the step to the cone boundary, (0, 1) */
    tscvx_float static_reg;      /* static KKT regularization delta (scaled data), (0, 1); the
                                    banded method uses 1e-4 of it (its factors need no
                                    regularization for stability) */
    tscvx_int refine_iters;      /* iterative-refinement steps per KKT solve, 0..20 (used once
                                    mu < 1e-6 mu_0, mu_0 taken as at least 1e-4; always with
                                    expanded SOCs) */
    tscvx_int ruiz_iters;        /* Ruiz equilibration passes at most, 0..50 (setup only) */
    tscvx_int soc_dense_max;     /* SOCs up to this dimension get a dense KKT block; larger
                                    ones the sparse diagonal + rank-2 expansion (setup only),
                                    >= 1 (no upper bound: a dense block too large for the
                                    index type is TSCVX_SETUP_TOO_LARGE) */
    tscvx_int kkt_backend;       /* KKT method (setup only): TSCVX_KKT_AUTO (default: banded
                                    if the problem has the structure, else static),
                                    TSCVX_KKT_BANDED (setup fails with NOT_BANDED without the
                                    structure), TSCVX_KKT_STATIC (sparse LDL' with the row
                                    patterns of L recorded at setup: SuiteSparse LDL's
                                    operations without elimination-tree walks) or
                                    TSCVX_KKT_LDL (SuiteSparse LDL, the reference) */
} tscvx_settings;

/* ---- information after a solve ----------------------------------------------------------- */
/* After setup or a data update (before the next solve): status TSCVX_UNSOLVED
 * (TSCVX_INVALID_INPUT for a refused update), iterations, factorizations, warm_started and
 * restart_iterations 0, the costs, gaps, residuals and mu NaN; the method, sizes, arena and
 * Ruiz fields those of the set-up and current data. */

typedef struct {
    tscvx_solve_status status;
    tscvx_int iterations;        /* IPM iterations taken */
    tscvx_float pcost;           /* primal objective 1/2 x'Px + c'x */
    tscvx_float dcost;           /* dual objective -1/2 x'Px - b'y - h'z */
    tscvx_float gap_abs;         /* |pcost - dcost| */
    tscvx_float gap_rel;         /* gap_abs / max(1, min(|pcost|, |dcost|)) */
    tscvx_float pres;            /* max(|Ax-b|_inf/(1+|b|_inf), |Gx+s-h|_inf/(1+|h|_inf)) */
    tscvx_float dres;            /* |Px + c + A'y + G'z|_inf / (1 + |c|_inf) */
    tscvx_float mu;              /* complementarity (s'z + tau kappa) / (degree + 1) */
    tscvx_int kkt_backend;       /* the method in use: TSCVX_KKT_BANDED, _STATIC or _LDL */
    tscvx_int kkt_dim;           /* dimension of the factored matrix (sparse: the KKT matrix;
                                    banded: Y, one row per equality) */
    tscvx_int kkt_nnz;           /* its stored entries (upper triangle; banded: profile) */
    tscvx_int factor_nnz;        /* entries of its factor (banded: profile + group blocks) */
    tscvx_int factorizations;    /* numeric factorizations in the last solve */
    size_t arena_used;           /* bytes of the arena held by the workspace */
    size_t arena_high_water;     /* most bytes of the arena ever touched (setup scratch incl.) */
    tscvx_int ruiz_passes;       /* Ruiz passes the current data took (stops early once every
                                    nonempty row and column has infinity norm 1 +- 1e-3) */
    tscvx_int warm_started;      /* 1: the last solve started from tscvx_warm_start's point;
                                    0: from the cold start */
    tscvx_int restart_iterations; /* a warm-started run that failed (numerical error,
                                    iteration limit) is run again cold: its IPM iterations
                                    (0: none); iterations and the log are the cold run's */
} tscvx_info;

/* One row of the iteration log. */
typedef struct {
    tscvx_int iter;
    tscvx_float pcost, dcost, gap, pres, dres, mu, step;
} tscvx_iter_log;

typedef struct tscvx_workspace tscvx_workspace; /* opaque, lives in the arena */

/* ---- API --------------------------------------------------------------------------------- */

tscvx_setup_status tscvx_default_settings(tscvx_settings *settings);

/* Why setup, the size queries and tscvx_update_settings would refuse `settings`
 * (TSCVX_SETUP_BAD_SETTINGS, the ranges documented in tscvx_settings): in `message`
 * (TSCVX_MESSAGE_LEN bytes; may be NULL) the first setting out of range, its range and its
 * value, e.g. "tol_gap_abs must lie within (0, 1), got 10"; TSCVX_SETUP_OK and "" for settings
 * they accept. */
tscvx_setup_status tscvx_check_settings(const tscvx_settings *settings, char *message);

/* Bytes of scratch that tscvx_workspace_size needs: the data and settings are validated as
 * by setup (the same statuses), then the size is arithmetic on the dimensions. A size past
 * SIZE_MAX / 2 is never reported: TSCVX_SETUP_TOO_LARGE (here, from tscvx_workspace_size and
 * from tscvx_setup alike). */
tscvx_setup_status tscvx_scratch_size(const tscvx_data *data, const tscvx_settings *settings,
                                      size_t *scratch_bytes);

/* Validates the data, orders and analyses the KKT system in `scratch` and returns the exact
 * arena size that tscvx_setup needs. */
tscvx_setup_status tscvx_workspace_size(const tscvx_data *data, const tscvx_settings *settings,
                                        void *scratch, size_t scratch_bytes,
                                        size_t *arena_bytes);

/* Builds the workspace inside `arena` (16-byte aligned is best; any alignment works). On
 * success *ws points into the arena; on any refusal (a NULL arena included) *ws is NULL
 * (ws itself NULL: TSCVX_SETUP_NULL_ARGUMENT, nothing written). */
tscvx_setup_status tscvx_setup(tscvx_workspace **ws, void *arena, size_t arena_bytes,
                               const tscvx_data *data, const tscvx_settings *settings);

/* New values with the setup sparsity (same nnz arrays); NULL leaves that part unchanged;
 * new P values are checked as at setup (TSCVX_SETUP_P_NOT_PSD).
 * No symbolic work: the problem is equilibrated again with the new numbers (O(nnz) per Ruiz
 * pass) and written into the KKT matrix through the setup maps. Given every part, a solve
 * after any updates gives, bit for bit, what a solve after a fresh setup with those numbers
 * gives. A part left NULL is recovered from its scaled copy to rounding (about an ulp per
 * update), so the solve then depends slightly on the updates before it.
 * Non-finite values or a P that fails its check make the workspace not ready
 * (solve returns TSCVX_INVALID_INPUT) until a valid update. Checks the mark, head and body
 * first (TSCVX_SETUP_NOT_READY, nothing written) and again at its end (TSCVX_SETUP_NOT_READY:
 * damaged during the update; not ready until a valid update; see above). */
tscvx_setup_status tscvx_update_data(tscvx_workspace *ws, const tscvx_float *Px,
                                     const tscvx_float *c, const tscvx_float *Ax,
                                     const tscvx_float *b, const tscvx_float *Gx,
                                     const tscvx_float *h);

/* Tolerances, iteration limit (<= setup's), step fraction, regularization and refinement;
 * ruiz_iters, soc_dense_max and kkt_backend are fixed at setup (changing them:
 * TSCVX_SETUP_BAD_SETTINGS). */
tscvx_setup_status tscvx_update_settings(tscvx_workspace *ws, const tscvx_settings *settings);

/* Warm start: the next tscvx_solve starts from (x, y, z, s) in original units (what
 * tscvx_get_solution returns, e.g. the solution of the previous, similar problem) instead of
 * the cold start. On each cone where the data's own slack h - G x lies strictly inside, that
 * slack replaces s; then each cone of s and z is moved off the boundary along the identity
 * until its s'z is about mu_0, a tenth of the point's relative residuals on the data (at
 * least 1e-5), and tau = 1, kappa = mu_0: a point centred as far as its infeasibility
 * needs. An s or z outside the cones falls back to the cold start. Only the next solve uses
 * the point; data updates before it are fine (it is scaled at the solve). info.warm_started
 * says which start a solve took.
 * x: n, y: p, z: m, s: m, all finite (TSCVX_SETUP_NONFINITE_DATA otherwise); NULL only for a
 * part of length 0 (TSCVX_SETUP_NULL_ARGUMENT otherwise). A refused call leaves no point: the
 * next solve starts cold. */
tscvx_setup_status tscvx_warm_start(tscvx_workspace *ws, const tscvx_float *x,
                                    const tscvx_float *y, const tscvx_float *z,
                                    const tscvx_float *s);

/* Solves from the current data. Checks the mark, head and body first (TSCVX_INVALID_INPUT,
 * nothing written) and the head and body again at its end (TSCVX_INVALID_INPUT, no answer:
 * the workspace was damaged during the solve; see above). */
tscvx_solve_status tscvx_solve(tscvx_workspace *ws);

/* Copies the last solution (original units) into caller arrays; any may be NULL.
 * x: n, y: p, z: m, s: m. For infeasible statuses these hold the certificate, normalized to
 * b'y + h'z = -1 (primal) or c'x = -1 (dual), and the arrays it does not use are NaN (x and s
 * for PRIMAL_INFEASIBLE, y and z for DUAL_INFEASIBLE: no number there to be taken for a
 * solution); a direction whose normalized numbers would not be finite (a descent near the
 * bottom of the double range) is not reported as a certificate. For SOLVED_INACCURATE and
 * MAX_ITER the best iterate: the smallest worst ratio of its residuals and gap to the
 * tolerances (docs/socp-runtime.md, "The best iterate").
 * TSCVX_SETUP_NO_SOLUTION (arrays untouched) before a solve since the last setup or data
 * update, after NUMERICAL_ERROR, and after a solve whose end check found the workspace
 * damaged (TSCVX_INVALID_INPUT). */
tscvx_setup_status tscvx_get_solution(const tscvx_workspace *ws, tscvx_float *x, tscvx_float *y,
                                      tscvx_float *z, tscvx_float *s);

tscvx_setup_status tscvx_get_info(const tscvx_workspace *ws, tscvx_info *info);

/* Row k (0 <= k <= info.iterations) of the last solve's iteration log;
 * TSCVX_SETUP_NO_SOLUTION before a solve (since setup or the last data update). Row 0 is
 * the start point (step 0). A solve that failed before it (TSCVX_NUMERICAL_ERROR with 0
 * iterations: the start's factorization or solves failed, e.g. on overflow) computed no
 * iterate: row 0 then holds iter 0, step 0 and NaN costs, gap, residuals and mu, and so
 * does the info (its costs, gaps, residuals and mu NaN, as before a solve). */
tscvx_setup_status tscvx_get_iter_log(const tscvx_workspace *ws, tscvx_int k,
                                      tscvx_iter_log *row);

/* Ends the workspace: every later call with it returns TSCVX_SETUP_NOT_READY (tscvx_solve:
 * TSCVX_INVALID_INPUT). Frees nothing: the arena is the caller's. Checks the mark only: a
 * workspace whose checksum no longer matches can be ended too. */
tscvx_setup_status tscvx_cleanup(tscvx_workspace *ws);

/* Why the calls would refuse `ws` (TSCVX_SETUP_NOT_READY; tscvx_solve: TSCVX_INVALID_INPUT),
 * in `message` (TSCVX_MESSAGE_LEN bytes; may be NULL): no set-up mark (not set up, cleaned
 * up, arena overwritten), the workspace damaged (its head or body checksum does not match:
 * set it up again; "workspace damaged during a solve: ..." or "... during a data update: ..."
 * when the end check of the last solve or data update found it), or the last data update
 * refused (or damaged during it); TSCVX_SETUP_OK and "" for a workspace ready
 * to solve. Checks the mark, head and body as tscvx_solve does, and writes nothing. */
tscvx_setup_status tscvx_check_workspace(const tscvx_workspace *ws, char *message);

#ifdef __cplusplus
}
#endif

#endif /* TSCVX_SOCP_H */
