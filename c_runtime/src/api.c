/* Public API: settings, validation, size queries, setup, updates, results, messages. */
#include <limits.h>
#include <stdint.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "socp_internal.h"

/* ---- messages ---------------------------------------------------------------------------- */

static const char *const setup_messages[TSCVX_SETUP_NSTATUS] = {
    "ok",
    "a required pointer is NULL",
    "a setting is out of range",
    "bad dimensions (need n >= 1, p >= 0, m >= 0)",
    "cone dimensions invalid (each >= 1, l + sum(q) must equal the m rows of G)",
    "invalid CSC sparsity (pointers, row indices out of range, unsorted or duplicated)",
    "P has entries below the diagonal; give the upper triangle only",
    "NaN or infinity in the problem data",
    "scratch smaller than tscvx_scratch_size()",
    "arena smaller than tscvx_workspace_size()",
    "problem too large for the index type, or its workspace for the address space (more than "
    "SIZE_MAX / 2 bytes: 2 GiB with a 32-bit size_t)",
    "workspace not ready (not set up, cleaned up or overwritten; damaged: its set-up checksum "
    "does not match; or a data update failed); tscvx_check_workspace says which",
    "iteration-log index out of range",
    "the problem has no structure for the banded KKT method (variable groups larger than 32, "
    "more than 8 border variables, a variable in no cone and not on P's diagonal, an equality "
    "row of border variables only, or too wide a profile)",
    "P is not positive semidefinite (a negative diagonal entry, an entry with "
    "P_ij^2 > P_ii P_jj, or a factorization of P that shows a negative eigenvalue)",
    "no solution to return: no solve since setup or the last data update, or the last solve "
    "ended in a numerical error or found the workspace damaged during it",
};

static const char *const solve_messages[TSCVX_NSTATUS] = {
    "unsolved",
    "solved",
    "solved to reduced accuracy",
    "primal infeasible",
    "dual infeasible (unbounded)",
    "iteration limit reached",
    "numerical error",
    "invalid input: the workspace is not ready (not set up, cleaned up or overwritten; damaged: "
    "its set-up checksum does not match, at the start of the solve or at its end, when damaged "
    "during it: no answer; or a data update failed); tscvx_check_workspace says which",
};

const char *tscvx_setup_status_message(tscvx_setup_status status) {
    return (unsigned)status < TSCVX_SETUP_NSTATUS ? setup_messages[status] : "unknown status";
}

const char *tscvx_solve_status_message(tscvx_solve_status status) {
    return (unsigned)status < TSCVX_NSTATUS ? solve_messages[status] : "unknown status";
}

/* ---- arena ------------------------------------------------------------------------------- */

#define TSCVX_ALIGN 16u

void *tscvx_arena_alloc(tscvx_arena *a, size_t count, size_t size) {
    if (size != 0 && count > (SIZE_MAX / 2) / size) {
        a->overflow = a->too_large = 1;
        return NULL;
    }
    const size_t bytes = (count * size + TSCVX_ALIGN - 1) & ~(size_t)(TSCVX_ALIGN - 1);
    const size_t start = a->top;
    if (bytes > SIZE_MAX / 2 - start) {
        a->overflow = a->too_large = 1;
        return NULL;
    }
    a->top = start + bytes;
    if (a->top > a->high) a->high = a->top;
    if (a->top > a->cap) a->overflow = 1;
    if (a->base == NULL || a->overflow) return NULL;
    return a->base + start;
}

static void arena_init(tscvx_arena *a, void *mem, size_t bytes) {
    a->base = NULL, a->cap = SIZE_MAX / 2, a->top = 0, a->high = 0, a->overflow = 0;
    a->too_large = 0;
    if (mem == NULL) return; /* counting mode */
    const size_t pad = (TSCVX_ALIGN - (size_t)((uintptr_t)mem % TSCVX_ALIGN)) % TSCVX_ALIGN;
    a->base = (unsigned char *)mem + pad;
    a->cap = bytes > pad ? bytes - pad : 0;
}

/* ---- settings ---------------------------------------------------------------------------- */

tscvx_setup_status tscvx_default_settings(tscvx_settings *st) {
    if (st == NULL) return TSCVX_SETUP_NULL_ARGUMENT;
    st->max_iter = 100;
    st->tol_gap_abs = 1e-8;
    st->tol_gap_rel = 1e-8;
    st->tol_feas = 1e-8;
    st->tol_infeas = 1e-8;
    st->tol_gap_abs_inacc = 5e-5;
    st->tol_gap_rel_inacc = 5e-5;
    st->tol_feas_inacc = 1e-4;
    st->step_fraction = 0.99;
    st->static_reg = 1e-8;
    st->refine_iters = 3;
    st->ruiz_iters = 15;
    st->soc_dense_max = 16;
    st->kkt_backend = TSCVX_KKT_AUTO;
    return TSCVX_SETUP_OK;
}

/* ---- data validation --------------------------------------------------------------------- */

/* Index of the first entry of v that is NaN or infinite, or -1. */
static tscvx_int first_nonfinite(const tscvx_float *v, tscvx_int n) {
    for (tscvx_int i = 0; i < n; i++)
        if (!isfinite(v[i])) return i;
    return -1;
}

static int all_finite(const tscvx_float *v, tscvx_int n) { return first_nonfinite(v, n) < 0; }

/* Writes the reason for a refusal into msg (TSCVX_MESSAGE_LEN bytes; NULL: none) and
 * returns the status, so that each check is one statement. */
static tscvx_setup_status refuse(char *msg, tscvx_setup_status st, const char *fmt, ...) {
    if (msg) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(msg, TSCVX_MESSAGE_LEN, fmt, ap);
        va_end(ap);
    }
    return st;
}

/* The settings' ranges, in the order of the struct; the first one out of range is named with
 * its range and value in `msg` (TSCVX_MESSAGE_LEN bytes; may be NULL). */
static tscvx_setup_status check_settings(const tscvx_settings *st, char *msg) {
    const struct {
        const char *name;
        tscvx_float v;
    } tol[] = {{"tol_gap_abs", st->tol_gap_abs}, {"tol_gap_rel", st->tol_gap_rel},
               {"tol_feas", st->tol_feas},       {"tol_infeas", st->tol_infeas},
               {"tol_gap_abs_inacc", st->tol_gap_abs_inacc},
               {"tol_gap_rel_inacc", st->tol_gap_rel_inacc},
               {"tol_feas_inacc", st->tol_feas_inacc}};
    /* The first four bound a residual, gap or certificate relative to its data (the absolute
     * gap to an objective of order 1): at 1 or more they accept anything. tol_infeas = 10 passed
     * an early iterate of a bounded problem as DUAL_INFEASIBLE; tol_gap_* = 1 stopped a
     * problem whose optimum is -10 at its first iterate, -7.3, as SOLVED. The reduced
     * (_inacc) bars only label a best iterate SOLVED_INACCURATE: any positive value. */
    const int below_one = 4;
    if (msg) msg[0] = '\0';
    if (st->max_iter < 1 || st->max_iter > 500)
        return refuse(msg, TSCVX_SETUP_BAD_SETTINGS, "max_iter must lie within 1..500, got %d",
                      (int)st->max_iter);
    for (int i = 0; i < (int)(sizeof tol / sizeof tol[0]); i++) {
        if (!(isfinite(tol[i].v) && tol[i].v > 0.0))
            return refuse(msg, TSCVX_SETUP_BAD_SETTINGS, "%s must be finite and > 0, got %g",
                          tol[i].name, (double)tol[i].v);
        if (i < below_one && !(tol[i].v < 1.0))
            return refuse(msg, TSCVX_SETUP_BAD_SETTINGS, "%s must lie within (0, 1), got %g",
                          tol[i].name, (double)tol[i].v);
    }
    if (!(st->step_fraction > 0.0 && st->step_fraction < 1.0))
        return refuse(msg, TSCVX_SETUP_BAD_SETTINGS, "step_fraction must lie within (0, 1), got %g",
                      (double)st->step_fraction);
    if (!(st->static_reg > 0.0 && st->static_reg < 1.0))
        return refuse(msg, TSCVX_SETUP_BAD_SETTINGS, "static_reg must lie within (0, 1), got %g",
                      (double)st->static_reg);
    if (st->refine_iters < 0 || st->refine_iters > 20)
        return refuse(msg, TSCVX_SETUP_BAD_SETTINGS, "refine_iters must lie within 0..20, got %d",
                      (int)st->refine_iters);
    if (st->ruiz_iters < 0 || st->ruiz_iters > 50)
        return refuse(msg, TSCVX_SETUP_BAD_SETTINGS, "ruiz_iters must lie within 0..50, got %d",
                      (int)st->ruiz_iters);
    if (st->soc_dense_max < 1)
        return refuse(msg, TSCVX_SETUP_BAD_SETTINGS, "soc_dense_max must be >= 1, got %d",
                      (int)st->soc_dense_max);
    if (st->kkt_backend < TSCVX_KKT_AUTO || st->kkt_backend > TSCVX_KKT_BANDED)
        return refuse(msg, TSCVX_SETUP_BAD_SETTINGS,
                      "kkt_backend must be TSCVX_KKT_AUTO, _LDL, _STATIC or _BANDED (0..3), got %d",
                      (int)st->kkt_backend);
    return TSCVX_SETUP_OK;
}

tscvx_setup_status tscvx_check_settings(const tscvx_settings *settings, char *message) {
    if (settings == NULL) return refuse(message, TSCVX_SETUP_NULL_ARGUMENT, "settings is NULL");
    return check_settings(settings, message);
}

/* CSC of nrow x ncol: pointers monotone from 0, indices in range, strictly increasing.
 * upper != 0 additionally demands row <= col (P). The pointers are checked whole before any
 * index is read (Mi may be NULL where the pointers say there are no entries). */
static tscvx_setup_status check_csc(const char *M, const tscvx_int *Mp, const tscvx_int *Mi,
                                    tscvx_int nrow, tscvx_int ncol, int upper, char *msg) {
    const tscvx_setup_status bad = TSCVX_SETUP_BAD_SPARSITY;
    if (Mp[0] != 0) return refuse(msg, bad, "%s: column pointers start at %d, not 0", M, Mp[0]);
    for (tscvx_int j = 0; j < ncol; j++)
        if (Mp[j + 1] < Mp[j])
            return refuse(msg, bad, "%s: column pointers decrease at column %d", M, j);
    if (Mp[ncol] > 0 && Mi == NULL)
        return refuse(msg, TSCVX_SETUP_NULL_ARGUMENT, "%s: row indices NULL for %d entries", M,
                      Mp[ncol]);
    for (tscvx_int j = 0; j < ncol; j++) {
        for (tscvx_int k = Mp[j]; k < Mp[j + 1]; k++) {
            if (Mi[k] < 0 || Mi[k] >= nrow)
                return refuse(msg, bad, "%s: row index %d in column %d is outside 0..%d", M,
                              Mi[k], j, nrow - 1);
            if (k > Mp[j] && Mi[k] <= Mi[k - 1])
                return refuse(msg, bad, "%s: row indices of column %d not strictly increasing "
                              "(%d after %d)", M, j, Mi[k], Mi[k - 1]);
            if (upper && Mi[k] > j)
                return refuse(msg, TSCVX_SETUP_P_NOT_UPPER,
                              "%s: entry (%d, %d) below the diagonal; give the upper triangle",
                              M, Mi[k], j);
        }
    }
    if (Mp[ncol] > INT_MAX / 4)
        return refuse(msg, TSCVX_SETUP_TOO_LARGE, "%s: %d entries overflow the index type", M,
                      Mp[ncol]);
    return TSCVX_SETUP_OK;
}

static tscvx_int nnz_of(const tscvx_int *Mp, tscvx_int ncol) { return Mp ? Mp[ncol] : 0; }

/* P_jj, 0 when absent: the last entry of column j (rows ascend, none below the diagonal) */
static tscvx_float p_diag(const tscvx_int *Pp, const tscvx_int *Pi, const tscvx_float *Px,
                          tscvx_int j) {
    const tscvx_int k = Pp[j + 1] - 1;
    return k >= Pp[j] && Pi[k] == j ? Px[k] : 0.0;
}

/* Necessary for P >= 0, and cheap (the full test is a factorization): no negative diagonal
 * entry and no negative 2 x 2 principal minor, P_ij^2 <= P_ii P_jj. In units of the largest
 * diagonal entry (the products neither overflow nor underflow), to a relative PSD_TOL (P = v v'
 * in rounded numbers passes) plus an absolute PSD_TOL^2 (entries at the rounding level of that
 * largest diagonal). Finite values and a valid upper-triangle pattern are checked before. */
#define PSD_TOL 1e-12
static int p_maybe_psd(const tscvx_int *Pp, const tscvx_int *Pi, const tscvx_float *Px,
                       tscvx_int n) {
    tscvx_float dmax = 0.0;
    for (tscvx_int j = 0; j < n; j++) {
        const tscvx_float djj = p_diag(Pp, Pi, Px, j);
        if (djj < 0.0) return 0;
        dmax = fmax(dmax, djj);
    }
    /* a zero diagonal admits exact zeros only */
    const tscvx_float unit = dmax > 0.0 ? dmax : 1.0, tiny = dmax > 0.0 ? PSD_TOL * PSD_TOL : 0.0;
    for (tscvx_int j = 0; j < n; j++) {
        const tscvx_float djj = p_diag(Pp, Pi, Px, j) / unit;
        for (tscvx_int k = Pp[j]; k < Pp[j + 1] && Pi[k] < j; k++) {
            const tscvx_float pij = Px[k] / unit, dii = p_diag(Pp, Pi, Px, Pi[k]) / unit;
            if (pij * pij > (1.0 + PSD_TOL) * dii * djj + tiny) return 0;
        }
    }
    return 1;
}

/* Everything setup checks in the data before building anything (the factorization test of
 * P comes later); msg (may be NULL) receives the array and entry at fault. */
/* check_data's steps, in its order; each refuses with its status and message. */

/* Sizes in range, and every array that the sizes say is used given. */
static tscvx_setup_status check_sizes(const tscvx_data *d, char *msg) {
    if (d->n < 1 || d->p < 0 || d->m < 0)
        return refuse(msg, TSCVX_SETUP_BAD_DIMENSIONS, "n = %d, p = %d, m = %d: need n >= 1, "
                      "p >= 0, m >= 0", d->n, d->p, d->m);
    if (d->n > INT_MAX / 8 || d->p > INT_MAX / 8 || d->m > INT_MAX / 8)
        return refuse(msg, TSCVX_SETUP_TOO_LARGE, "n, p or m above %d", INT_MAX / 8);
    if (d->c == NULL) return refuse(msg, TSCVX_SETUP_NULL_ARGUMENT, "c is NULL");
    if (d->p > 0 && (d->Ap == NULL || d->Ai == NULL || d->Ax == NULL || d->b == NULL))
        return refuse(msg, TSCVX_SETUP_NULL_ARGUMENT, "Ap, Ai, Ax or b is NULL with p = %d",
                      d->p);
    if (d->m > 0 && (d->Gp == NULL || d->Gi == NULL || d->Gx == NULL || d->h == NULL))
        return refuse(msg, TSCVX_SETUP_NULL_ARGUMENT, "Gp, Gi, Gx or h is NULL with m = %d",
                      d->m);
    if (d->Pp != NULL && (d->Pi == NULL || d->Px == NULL))
        return refuse(msg, TSCVX_SETUP_NULL_ARGUMENT, "Pp given, Pi or Px NULL");
    return TSCVX_SETUP_OK;
}

/* The cones: l >= 0 orthant rows, then nsoc cones of q[k] >= 1 rows, m rows in all. */
static tscvx_setup_status check_cones(const tscvx_data *d, char *msg) {
    if (d->l < 0 || d->nsoc < 0)
        return refuse(msg, TSCVX_SETUP_BAD_CONES, "l = %d, nsoc = %d: need l, nsoc >= 0",
                      d->l, d->nsoc);
    if (d->nsoc > 0 && d->q == NULL)
        return refuse(msg, TSCVX_SETUP_NULL_ARGUMENT, "nsoc = %d, q NULL", d->nsoc);
    long long rows = d->l;
    for (tscvx_int k = 0; k < d->nsoc; k++) {
        if (d->q[k] < 1)
            return refuse(msg, TSCVX_SETUP_BAD_CONES, "q[%d] = %d: a cone has at least 1 row",
                          k, d->q[k]);
        rows += d->q[k];
        if (rows > d->m) /* cones larger than the rows */
            return refuse(msg, TSCVX_SETUP_BAD_CONES, "the cones up to q[%d] need %lld rows, "
                          "G has m = %d", k, rows, d->m);
    }
    if (rows != d->m)
        return refuse(msg, TSCVX_SETUP_BAD_CONES, "l + sum(q) = %lld rows, G has m = %d", rows,
                      d->m);
    return TSCVX_SETUP_OK;
}

/* P (upper triangle), A and G as valid CSC of their sizes. */
static tscvx_setup_status check_patterns(const tscvx_data *d, char *msg) {
    tscvx_setup_status s;
    if (d->Pp && (s = check_csc("P", d->Pp, d->Pi, d->n, d->n, 1, msg)) != TSCVX_SETUP_OK)
        return s;
    if (d->Ap && d->p == 0 && d->Ap[d->n] != 0)
        return refuse(msg, TSCVX_SETUP_BAD_SPARSITY, "A: %d entries with p = 0 rows",
                      d->Ap[d->n]);
    if (d->Ap && (s = check_csc("A", d->Ap, d->Ai, d->p, d->n, 0, msg)) != TSCVX_SETUP_OK)
        return s;
    if (d->Gp && d->m == 0 && d->Gp[d->n] != 0)
        return refuse(msg, TSCVX_SETUP_BAD_SPARSITY, "G: %d entries with m = 0 rows",
                      d->Gp[d->n]);
    if (d->Gp && (s = check_csc("G", d->Gp, d->Gi, d->m, d->n, 0, msg)) != TSCVX_SETUP_OK)
        return s;
    return TSCVX_SETUP_OK;
}

/* Every number finite, and P passing the cheap semidefiniteness test. */
static tscvx_setup_status check_values(const tscvx_data *d, char *msg) {
    const struct {
        const char *name;
        const tscvx_float *v;
        tscvx_int len;
    } arrays[] = {{"c", d->c, d->n},
                  {"b", d->b, d->p > 0 ? d->p : 0},
                  {"h", d->h, d->m > 0 ? d->m : 0},
                  {"Px", d->Px, d->Pp ? nnz_of(d->Pp, d->n) : 0},
                  {"Ax", d->Ax, d->Ap ? nnz_of(d->Ap, d->n) : 0},
                  {"Gx", d->Gx, d->Gp ? nnz_of(d->Gp, d->n) : 0}};
    for (size_t a = 0; a < sizeof arrays / sizeof arrays[0]; a++) {
        const tscvx_int i = arrays[a].len > 0 ? first_nonfinite(arrays[a].v, arrays[a].len) : -1;
        if (i >= 0)
            return refuse(msg, TSCVX_SETUP_NONFINITE_DATA, "%s[%d] = %g", arrays[a].name, i,
                          arrays[a].v[i]);
    }
    if (d->Pp && !p_maybe_psd(d->Pp, d->Pi, d->Px, d->n))
        return refuse(msg, TSCVX_SETUP_P_NOT_PSD, "P: a negative diagonal entry or an entry with "
                      "P_ij^2 > P_ii P_jj");
    return TSCVX_SETUP_OK;
}

static tscvx_setup_status check_data(const tscvx_data *d, char *msg) {
    tscvx_setup_status s;
    if (msg) msg[0] = '\0';
    if ((s = check_sizes(d, msg)) != TSCVX_SETUP_OK || (s = check_cones(d, msg)) != TSCVX_SETUP_OK ||
        (s = check_patterns(d, msg)) != TSCVX_SETUP_OK)
        return s;
    return check_values(d, msg);
}

tscvx_setup_status tscvx_check_data(const tscvx_data *data, char *message) {
    if (data == NULL) return refuse(message, TSCVX_SETUP_NULL_ARGUMENT, "data is NULL");
    return check_data(data, message);
}

/* KKT upper-triangle entries, from the data (the order of kkt.c's enumerate()). */
static long long count_kkt_nnz(const tscvx_data *d, tscvx_int dense_max, tscvx_int *nexp,
                               tscvx_int *ncone) {
    long long cnt = (long long)nnz_of(d->Pp, d->n) + nnz_of(d->Ap, d->n) + d->p +
                    nnz_of(d->Gp, d->n);
    for (tscvx_int j = 0; j < d->n; j++) {
        int has_diag = 0;
        if (d->Pp)
            for (tscvx_int k = d->Pp[j]; k < d->Pp[j + 1]; k++) has_diag |= d->Pi[k] == j;
        cnt += !has_diag;
    }
    long long nc = d->l;
    *nexp = 0;
    for (tscvx_int k = 0; k < d->nsoc; k++) {
        const long long q = d->q[k];
        if (q > dense_max) {
            nc += 2 * q + 3;
            (*nexp)++;
        } else {
            nc += q * (q + 1) / 2;
        }
    }
    *ncone = nc > INT_MAX / 4 ? INT_MAX / 4 : (tscvx_int)nc;
    return cnt + nc;
}

/* ---- setup ------------------------------------------------------------------------------- */

enum { MODE_COUNT, MODE_ANALYSE, MODE_SETUP };

/* Claim the problem data: cones, P, A, G, c, b, h and the equilibration. The cone arrays
 * are read-only in the workspace; *q and *off are where set-up writes them. */
static void alloc_data(tscvx_workspace *ws, tscvx_arena *a, tscvx_int nnzP, tscvx_int nnzA,
                       tscvx_int nnzG, tscvx_int **q, tscvx_int **off) {
    const tscvx_int n = ws->n, p = ws->p, m = ws->m, nsoc = ws->K.nsoc;
    TSCVX_CLAIM(a, *q, nsoc, tscvx_int);
    TSCVX_CLAIM(a, *off, nsoc, tscvx_int);
    ws->K.q = *q, ws->K.off = *off;
    tscvx_csc *M[3] = {&ws->P, &ws->A, &ws->G};
    const tscvx_int nnz[3] = {nnzP, nnzA, nnzG};
    for (int k = 0; k < 3; k++) {
        TSCVX_CLAIM(a, M[k]->p, n + 1, tscvx_int);
        TSCVX_CLAIM(a, M[k]->i, nnz[k], tscvx_int);
        TSCVX_CLAIM(a, M[k]->x, nnz[k], tscvx_float);
    }
    TSCVX_CLAIM(a, ws->c, n, tscvx_float);
    TSCVX_CLAIM(a, ws->b, p, tscvx_float);
    TSCVX_CLAIM(a, ws->h, m, tscvx_float);
    TSCVX_CLAIM(a, ws->D, n, tscvx_float);
    TSCVX_CLAIM(a, ws->EA, p, tscvx_float);
    TSCVX_CLAIM(a, ws->EG, m, tscvx_float);
}

/* Claim the sparse method's KKT pattern and maps (its factor comes later). */
static void alloc_kkt(tscvx_workspace *ws, tscvx_arena *a) {
    tscvx_kkt *k = &ws->kkt;
    const tscvx_int dim = k->dim;
    TSCVX_CLAIM(a, k->Kp, dim + 1, tscvx_int);
    TSCVX_CLAIM(a, k->Ki, k->nnz, tscvx_int);
    TSCVX_CLAIM(a, k->Kx, k->nnz, tscvx_float);
    TSCVX_CLAIM(a, k->rowblk, dim, signed char);
    TSCVX_CLAIM(a, k->pinv, dim, tscvx_int);
    TSCVX_CLAIM(a, k->mapP, ws->P.nnz, tscvx_int);
    TSCVX_CLAIM(a, k->mapA, ws->A.nnz, tscvx_int);
    TSCVX_CLAIM(a, k->mapG, ws->G.nnz, tscvx_int);
    TSCVX_CLAIM(a, k->mapDiag, ws->n + ws->p, tscvx_int);
    TSCVX_CLAIM(a, k->mapCone, k->ncone, tscvx_int);
    TSCVX_CLAIM(a, k->expanded, ws->K.nsoc, tscvx_int);
}

/* Claim the iteration vectors (and, for the sparse method, the factor: the backend finishes
 * its analysis there). Returns 0, or -1 if the analysis failed. */
static int alloc_iterates(tscvx_workspace *ws, tscvx_arena *a) {
    const tscvx_int n = ws->n, p = ws->p, m = ws->m, nsoc = ws->K.nsoc;
    if (ws->method == &tscvx_method_sparse) {
        tscvx_kkt *k = &ws->kkt;
        if (k->backend->alloc(k, a) != 0) return -1;
        TSCVX_CLAIM(a, k->sol, k->dim, tscvx_float);
        k->Pattern = (tscvx_int *)k->sol; /* LDL's factorization work; sol is for solves only */
    }
    TSCVX_CLAIM(a, ws->W.w, m, tscvx_float);
    TSCVX_CLAIM(a, ws->W.eta, nsoc, tscvx_float);
    tscvx_float **nvec[] = {&ws->x, &ws->rx, &ws->Px, &ws->x1, &ws->dx, &ws->cx, &ws->wn,
                            &ws->bx};
    tscvx_float **pvec[] = {&ws->y, &ws->ry, &ws->y1, &ws->dy, &ws->cy, &ws->wp, &ws->by};
    tscvx_float **mvec[] = {&ws->z, &ws->s, &ws->lambda, &ws->rz, &ws->z1, &ws->wz1,
                            &ws->dz, &ws->wdz, &ws->cz, &ws->cwz, &ws->e, &ws->ds,
                            &ws->wm, &ws->wm2, &ws->bz, &ws->bs};
    for (size_t i = 0; i < sizeof nvec / sizeof nvec[0]; i++) {
        TSCVX_CLAIM(a, *nvec[i], n, tscvx_float);
    }
    for (size_t i = 0; i < sizeof pvec / sizeof pvec[0]; i++) {
        TSCVX_CLAIM(a, *pvec[i], p, tscvx_float);
    }
    for (size_t i = 0; i < sizeof mvec / sizeof mvec[0]; i++) {
        TSCVX_CLAIM(a, *mvec[i], m, tscvx_float);
    }
    TSCVX_CLAIM(a, ws->log, ws->st.max_iter + 1, tscvx_iter_log);
    return 0;
}

static void copy_ints(tscvx_int *dst, const tscvx_int *src, tscvx_int n) {
    for (tscvx_int i = 0; i < n; i++) dst[i] = src[i];
}

static void copy_floats(tscvx_float *dst, const tscvx_float *src, tscvx_int n) {
    for (tscvx_int i = 0; i < n; i++) dst[i] = src[i];
}

/* CSC copy (pattern and values) of a possibly absent matrix (absent = no entries) */
static void copy_csc(tscvx_csc *M, const tscvx_int *Mp, const tscvx_int *Mi,
                     const tscvx_float *Mx, tscvx_int nrow, tscvx_int ncol) {
    M->nrow = nrow, M->ncol = ncol, M->nnz = nnz_of(Mp, ncol);
    for (tscvx_int j = 0; j <= ncol; j++) M->p[j] = Mp ? Mp[j] : 0;
    if (M->nnz > 0) copy_ints(M->i, Mi, M->nnz);
    if (M->nnz > 0) copy_floats(M->x, Mx, M->nnz);
}

/* inf-norms of the caller's (unscaled) numbers, for relative residuals; NULL = unchanged */
static void data_norms(tscvx_workspace *ws, const tscvx_float *Px, const tscvx_float *c,
                       const tscvx_float *Ax, const tscvx_float *b, const tscvx_float *Gx,
                       const tscvx_float *h) {
    if (Px) ws->norm_P = tscvx_max_abs(Px, ws->P.nnz, 0.0);
    if (c) ws->norm_c = tscvx_max_abs(c, ws->n, 0.0);
    if (Ax) ws->norm_A = tscvx_max_abs(Ax, ws->A.nnz, 0.0);
    if (b) ws->norm_b = tscvx_max_abs(b, ws->p, 0.0);
    if (Gx) ws->norm_G = tscvx_max_abs(Gx, ws->G.nnz, 0.0);
    if (h) ws->norm_h = tscvx_max_abs(h, ws->m, 0.0);
}

/* The sparse method's set-up from the arena top: pattern and maps, then the ordering and
 * symbolic factorization in temporary memory (released). Counting mode claims only.
 * Returns 0, or -1 when the analysis failed. */
static int setup_sparse(tscvx_workspace *ws, tscvx_arena *a) {
    ws->method = &tscvx_method_sparse;
    alloc_kkt(ws, a);
    const size_t mark = a->top;
    const size_t tmp_ints = tscvx_kkt_temp_ints(ws->kkt.dim, ws->kkt.nnz);
    tscvx_int *tmp = (tscvx_int *)tscvx_arena_alloc(a, tmp_ints, sizeof(tscvx_int));
    if (a->base == NULL || a->overflow) return 0;
    const long lnz = tscvx_kkt_build(ws, tmp);
    if (lnz < 0 || lnz > INT_MAX / 4) return -1;
    a->top = mark;
    ws->kkt.lnz = (tscvx_int)lnz;
    return 0;
}

/* A cleared workspace with the settings and the sizes of the problem and its KKT system */
static void init_sizes(tscvx_workspace *ws, const tscvx_data *d, const tscvx_settings *st,
                       tscvx_int dim, tscvx_int nnzK, tscvx_int nexp, tscvx_int ncone) {
    memset(ws, 0, sizeof *ws);
    ws->st = *st;
    ws->n = d->n, ws->p = d->p, ws->m = d->m;
    ws->K.l = d->l, ws->K.nsoc = d->nsoc, ws->K.m = d->m, ws->K.degree = d->l + d->nsoc;
    ws->kkt.backend = st->kkt_backend == TSCVX_KKT_LDL ? &tscvx_backend_ldl
                                                       : &tscvx_backend_static;
    ws->kkt.dim = dim, ws->kkt.nnz = nnzK;
    ws->kkt.nexp = nexp, ws->kkt.ncone = ncone;
    ws->log_cap = st->max_iter + 1;
}

/* The problem data and cone sizes into the arena (q, off: alloc_data's cone arrays) */
static void copy_problem(tscvx_workspace *ws, const tscvx_data *d, tscvx_int *q,
                         tscvx_int *off) {
    for (tscvx_int k = 0, o = d->l; k < d->nsoc; k++) q[k] = d->q[k], off[k] = o, o += d->q[k];
    copy_csc(&ws->P, d->Pp, d->Pi, d->Px, d->n, d->n);
    copy_csc(&ws->A, d->Ap, d->Ai, d->Ax, d->p, d->n);
    copy_csc(&ws->G, d->Gp, d->Gi, d->Gx, d->m, d->n);
    copy_floats(ws->c, d->c, d->n);
    if (d->p > 0) copy_floats(ws->b, d->b, d->p);
    if (d->m > 0) copy_floats(ws->h, d->h, d->m);
}

/* New data (set up, taken or refused): info's status says so and no figure of the last solve is left
 * to be read as this data's. */
static void forget_solve(tscvx_workspace *ws, tscvx_solve_status status) {
    tscvx_info *in = &ws->info;
    in->status = status;
    in->iterations = in->factorizations = in->warm_started = in->restart_iterations = 0;
    in->pcost = in->dcost = in->gap_abs = in->gap_rel = NAN;
    in->pres = in->dres = in->mu = NAN;
}

/* What set-up reports in info: the method and the size of what it factors */
static void report_setup(tscvx_workspace *ws, int banded) {
    forget_solve(ws, TSCVX_UNSOLVED);
    ws->info.kkt_backend = ws->method->id == TSCVX_KKT_BANDED ? TSCVX_KKT_BANDED
                           : ws->kkt.backend == &tscvx_backend_ldl ? TSCVX_KKT_LDL
                                                                   : TSCVX_KKT_STATIC;
    if (banded) { /* the factored matrices: Y (p x p profile) and the groups' blocks */
        ws->info.kkt_dim = ws->p;
        ws->info.kkt_nnz = (tscvx_int)ws->bd.nY;
        ws->info.factor_nnz = (tscvx_int)(ws->bd.nY + ws->bd.nH);
    } else {
        ws->info.kkt_dim = ws->kkt.dim, ws->info.kkt_nnz = ws->kkt.nnz;
        ws->info.factor_nnz = ws->kkt.lnz;
    }
    ws->info.arena_used = ws->arena_used, ws->info.arena_high_water = ws->arena_high;
}

/* The KKT method: banded when asked for (or, by default, when the problem has the
 * structure), else the sparse LDL' of the whole KKT matrix. *banded: the banded analysis
 * found the structure. Returns the status that ends set-up, or OK. */
static tscvx_setup_status choose_method(tscvx_workspace *ws, const tscvx_settings *st,
                                        tscvx_arena *a, int mode,
                                        tscvx_setup_status short_memory, int *banded) {
    const size_t mark = a->top;
    if (st->kkt_backend == TSCVX_KKT_AUTO || st->kkt_backend == TSCVX_KKT_BANDED) {
        *banded = tscvx_banded_analyse(ws, a); /* counting mode: claims, says 1 */
        if (*banded < 0) return short_memory;
        if (!*banded && st->kkt_backend == TSCVX_KKT_BANDED) return TSCVX_SETUP_NOT_BANDED;
        ws->method = &tscvx_method_banded;
    }
    if (mode == MODE_COUNT) {
        if (st->kkt_backend != TSCVX_KKT_BANDED) { /* the sparse method may be needed too */
            a->top = mark;
            if (setup_sparse(ws, a) != 0) return TSCVX_SETUP_TOO_LARGE;
        }
        return TSCVX_SETUP_OK;
    }
    if (!*banded && setup_sparse(ws, a) != 0) return TSCVX_SETUP_TOO_LARGE;
    if (a->overflow && (mode == MODE_SETUP || ws->method == &tscvx_method_sparse))
        return short_memory; /* the analysis itself did not fit */
    return TSCVX_SETUP_OK;
}

/* The one set-up path. MODE_COUNT only counts bytes (scratch size); MODE_ANALYSE runs up to
 * the symbolic analysis and reports the arena size; MODE_SETUP builds the workspace. */
static tscvx_setup_status build(const tscvx_data *d, const tscvx_settings *st, tscvx_arena *a,
                                int mode, tscvx_workspace **out, size_t *need) {
    if (d == NULL || st == NULL) return TSCVX_SETUP_NULL_ARGUMENT;
    tscvx_setup_status status = check_settings(st, NULL);
    if (status == TSCVX_SETUP_OK) status = check_data(d, NULL);
    if (status != TSCVX_SETUP_OK) return status;
    const tscvx_setup_status short_memory =
        mode == MODE_SETUP ? TSCVX_SETUP_ARENA_TOO_SMALL : TSCVX_SETUP_SCRATCH_TOO_SMALL;

    tscvx_int nexp, ncone;
    const long long nnzK = count_kkt_nnz(d, st->soc_dense_max, &nexp, &ncone);
    const long long dim = (long long)d->n + d->p + d->m + 2LL * nexp;
    if (nnzK > INT_MAX / 8 || dim > INT_MAX / 16) return TSCVX_SETUP_TOO_LARGE;

    tscvx_workspace local;
    tscvx_workspace *ws = (tscvx_workspace *)tscvx_arena_alloc(a, 1, sizeof(tscvx_workspace));
    if (mode == MODE_COUNT) ws = &local;
    if (ws == NULL) return short_memory;
    init_sizes(ws, d, st, (tscvx_int)dim, (tscvx_int)nnzK, nexp, ncone);
    const tscvx_int nnzP = nnz_of(d->Pp, d->n), nnzA = nnz_of(d->Ap, d->n);
    const tscvx_int nnzG = nnz_of(d->Gp, d->n);
    tscvx_int *q, *off;
    alloc_data(ws, a, nnzP, nnzA, nnzG, &q, &off);
    ws->P.nnz = nnzP, ws->A.nnz = nnzA, ws->G.nnz = nnzG;
    /* a size past the address space's half was not counted: no size, no arena holds it */
    if (a->too_large) return TSCVX_SETUP_TOO_LARGE;
    if (a->overflow && mode != MODE_COUNT) return short_memory;
    if (mode != MODE_COUNT) copy_problem(ws, d, q, off);

    int banded = 0;
    status = choose_method(ws, st, a, mode, short_memory, &banded);
    if (a->too_large) return TSCVX_SETUP_TOO_LARGE;
    if (status != TSCVX_SETUP_OK) return status;
    if (mode == MODE_COUNT) {
        *need = a->high + TSCVX_ALIGN; /* + worst-case alignment of the caller's pointer */
        return TSCVX_SETUP_OK;
    }
    if (alloc_iterates(ws, a) != 0 || a->too_large) return TSCVX_SETUP_TOO_LARGE;
    if (mode == MODE_ANALYSE) {
        *need = a->high + TSCVX_ALIGN;
        return TSCVX_SETUP_OK;
    }
    if (a->overflow) return TSCVX_SETUP_ARENA_TOO_SMALL;

    data_norms(ws, d->Pp ? d->Px : NULL, d->c, d->Ax, d->b, d->Gx, d->h);
    tscvx_equilibrate(ws);
    if (ws->P.nnz > 0 && ws->method->check_p(ws) != 0) return TSCVX_SETUP_P_NOT_PSD;
    ws->arena_used = a->top, ws->arena_high = a->high;
    report_setup(ws, banded);
    ws->ready = 1;
    ws->head_sum = tscvx_ws_head_sum(ws);
    ws->body_sum = tscvx_ws_body_sum(ws);
    ws->magic = TSCVX_WS_MAGIC;
    *out = ws;
    return TSCVX_SETUP_OK;
}

tscvx_setup_status tscvx_scratch_size(const tscvx_data *data, const tscvx_settings *settings,
                                      size_t *scratch_bytes) {
    if (scratch_bytes == NULL) return TSCVX_SETUP_NULL_ARGUMENT;
    tscvx_arena a;
    arena_init(&a, NULL, 0);
    return build(data, settings, &a, MODE_COUNT, NULL, scratch_bytes);
}

tscvx_setup_status tscvx_workspace_size(const tscvx_data *data, const tscvx_settings *settings,
                                        void *scratch, size_t scratch_bytes,
                                        size_t *arena_bytes) {
    if (scratch == NULL || arena_bytes == NULL) return TSCVX_SETUP_NULL_ARGUMENT;
    tscvx_arena a;
    arena_init(&a, scratch, scratch_bytes);
    return build(data, settings, &a, MODE_ANALYSE, NULL, arena_bytes);
}

tscvx_setup_status tscvx_setup(tscvx_workspace **ws, void *arena, size_t arena_bytes,
                               const tscvx_data *data, const tscvx_settings *settings) {
    if (ws == NULL) return TSCVX_SETUP_NULL_ARGUMENT;
    *ws = NULL; /* whatever is refused below: no workspace */
    if (arena == NULL) return TSCVX_SETUP_NULL_ARGUMENT;
    tscvx_arena a;
    arena_init(&a, arena, arena_bytes);
    size_t unused = 0;
    return build(data, settings, &a, MODE_SETUP, ws, &unused);
}

/* ---- workspace validity ------------------------------------------------------------------ */

/* The magic of a successful setup and KKT method pointers that are ours: checked before
 * anything else of the workspace is read (a stale one holds garbage pointers). */
static int ws_live(const tscvx_workspace *ws) {
    if (ws->magic != TSCVX_WS_MAGIC) return 0;
    if (ws->method == &tscvx_method_banded) return 1;
    return ws->method == &tscvx_method_sparse &&
           (ws->kkt.backend == &tscvx_backend_static || ws->kkt.backend == &tscvx_backend_ldl);
}

/* How a workspace stands, in the order checked: each check reads only what the ones before
 * it vouched for (the body's lengths and pointers are in the head). */
enum { WS_INTACT, WS_NO_MARK, WS_HEAD_DAMAGED, WS_BODY_DAMAGED };

/* The mark, then the head checksum (sizes, settings, pointers), then with `body` the index
 * arrays'. A call follows only what it checked: the body's arrays only after the body. */
static int ws_state(const tscvx_workspace *ws, int body) {
    if (!ws_live(ws)) return WS_NO_MARK;
    if (ws->head_sum != tscvx_ws_head_sum(ws)) return WS_HEAD_DAMAGED;
    if (body && ws->body_sum != tscvx_ws_body_sum(ws)) return WS_BODY_DAMAGED;
    return WS_INTACT;
}

/* For the calls that index only by the head's sizes and pointers (warm start, getters,
 * settings) */
static int ws_head_intact(const tscvx_workspace *ws) { return ws_state(ws, 0) == WS_INTACT; }

/* For the calls that follow the index arrays (data updates, solves) */
static int ws_intact(const tscvx_workspace *ws) { return ws_state(ws, 1) == WS_INTACT; }

tscvx_setup_status tscvx_check_workspace(const tscvx_workspace *ws, char *message) {
    if (ws == NULL) return refuse(message, TSCVX_SETUP_NULL_ARGUMENT, "workspace is NULL");
    /* found by the end check of the last solve or data update: the damage came during it */
    const char *when = ws->damaged_during == TSCVX_DAMAGED_IN_SOLVE    ? " during a solve"
                       : ws->damaged_during == TSCVX_DAMAGED_IN_UPDATE ? " during a data update"
                                                                        : "";
    switch (ws_state(ws, 1)) {
    case WS_NO_MARK:
        return refuse(message, TSCVX_SETUP_NOT_READY, "no set-up mark%s%s%s: the workspace was "
                      "not set up, was cleaned up, or its arena was overwritten",
                      when[0] ? " (lost" : "", when, when[0] ? ")" : "");
    case WS_HEAD_DAMAGED:
        return refuse(message, TSCVX_SETUP_NOT_READY, "workspace damaged%s: set-up checksum "
                      "mismatch in its sizes, settings or pointers; set it up again", when);
    case WS_BODY_DAMAGED:
        return refuse(message, TSCVX_SETUP_NOT_READY, "workspace damaged%s: set-up checksum "
                      "mismatch in its index arrays (patterns, cones, KKT maps, ordering, "
                      "symbolic factor); set it up again", when);
    default:
        break;
    }
    if (!ws->ready)
        return refuse(message, TSCVX_SETUP_NOT_READY, "the last data update was refused (a "
                      "non-finite number, a P not positive semidefinite, or damage during "
                      "it): the workspace waits for a valid update");
    if (message) message[0] = '\0';
    return TSCVX_SETUP_OK;
}

/* Ends a workspace that carries the mark, damaged or not: it follows no pointer. */
tscvx_setup_status tscvx_cleanup(tscvx_workspace *ws) {
    if (ws == NULL) return TSCVX_SETUP_NULL_ARGUMENT;
    if (!ws_live(ws)) return TSCVX_SETUP_NOT_READY;
    ws->magic = 0, ws->ready = 0;
    return TSCVX_SETUP_OK;
}

/* ---- updates ----------------------------------------------------------------------------- */

tscvx_setup_status tscvx_update_data(tscvx_workspace *ws, const tscvx_float *Px,
                                     const tscvx_float *c, const tscvx_float *Ax,
                                     const tscvx_float *b, const tscvx_float *Gx,
                                     const tscvx_float *h) {
    if (ws == NULL) return TSCVX_SETUP_NULL_ARGUMENT;
    if (!ws_intact(ws)) return TSCVX_SETUP_NOT_READY; /* nothing written */
    ws->damaged_during = 0;
    tscvx_setup_status s = TSCVX_SETUP_OK;
    if ((Px && !all_finite(Px, ws->P.nnz)) || (c && !all_finite(c, ws->n)) ||
        (Ax && !all_finite(Ax, ws->A.nnz)) || (b && !all_finite(b, ws->p)) ||
        (Gx && !all_finite(Gx, ws->G.nnz)) || (h && !all_finite(h, ws->m)))
        s = TSCVX_SETUP_NONFINITE_DATA;
    else if (Px && !p_maybe_psd(ws->P.p, ws->P.i, Px, ws->n)) /* the setup pattern */
        s = TSCVX_SETUP_P_NOT_PSD;
    if (s != TSCVX_SETUP_OK) { /* not ready until a valid update */
        ws->ready = 0;
        forget_solve(ws, TSCVX_INVALID_INPUT);
        return s;
    }
    data_norms(ws, Px, c, Ax, b, Gx, h);
    tscvx_update_equilibrate(ws, Px, c, Ax, b, Gx, h);
    /* the factorization test sees P only once it is stored: a P it refused stays refused, and
     * is tested again, until an update replaces it */
    if ((Px || ws->p_refused) && ws->P.nnz > 0) ws->p_refused = ws->method->check_p(ws) != 0;
    /* The end check, as tscvx_solve's: a bit flipped during the intake (after the start
     * check, in what it indexes by) is said by this call, not the next. The numbers taken
     * went through it: not ready until a valid update, as a refused one, and
     * tscvx_check_workspace says the damage came during a data update. The writes are to
     * the struct's own fields, outside the sums. */
    if (!ws_intact(ws)) {
        ws->damaged_during = TSCVX_DAMAGED_IN_UPDATE;
        ws->ready = 0;
        forget_solve(ws, TSCVX_INVALID_INPUT);
        return TSCVX_SETUP_NOT_READY;
    }
    if (ws->p_refused) { /* not ready, as above */
        ws->ready = 0;
        forget_solve(ws, TSCVX_INVALID_INPUT);
        return TSCVX_SETUP_P_NOT_PSD;
    }
    ws->ready = 1;
    forget_solve(ws, TSCVX_UNSOLVED);
    return TSCVX_SETUP_OK;
}

tscvx_setup_status tscvx_update_settings(tscvx_workspace *ws, const tscvx_settings *st) {
    if (ws == NULL || st == NULL) return TSCVX_SETUP_NULL_ARGUMENT;
    if (!ws_head_intact(ws)) return TSCVX_SETUP_NOT_READY;
    const tscvx_setup_status s = check_settings(st, NULL);
    if (s != TSCVX_SETUP_OK) return s;
    if (st->max_iter > ws->log_cap - 1 || st->soc_dense_max != ws->st.soc_dense_max ||
        st->ruiz_iters != ws->st.ruiz_iters || st->kkt_backend != ws->st.kkt_backend)
        return TSCVX_SETUP_BAD_SETTINGS; /* structural: fixed at setup */
    ws->st = *st;
    ws->head_sum = tscvx_ws_head_sum(ws); /* the settings are in it */
    return TSCVX_SETUP_OK;
}

/* ---- solve and results ------------------------------------------------------------------- */

tscvx_setup_status tscvx_warm_start(tscvx_workspace *ws, const tscvx_float *x,
                                    const tscvx_float *y, const tscvx_float *z,
                                    const tscvx_float *s) {
    if (ws == NULL) return TSCVX_SETUP_NULL_ARGUMENT;
    if (!ws_head_intact(ws)) return TSCVX_SETUP_NOT_READY;
    ws->warm = 0; /* a refused point also drops the one given before */
    if (x == NULL || (y == NULL && ws->p > 0) || ((z == NULL || s == NULL) && ws->m > 0))
        return TSCVX_SETUP_NULL_ARGUMENT;
    if (!all_finite(x, ws->n) || !all_finite(y, ws->p) || !all_finite(z, ws->m) ||
        !all_finite(s, ws->m))
        return TSCVX_SETUP_NONFINITE_DATA;
    /* the best-iterate buffers are free between solves; the IPM scales the point at start */
    for (tscvx_int j = 0; j < ws->n; j++) ws->bx[j] = x[j];
    for (tscvx_int i = 0; i < ws->p; i++) ws->by[i] = y[i];
    for (tscvx_int i = 0; i < ws->m; i++) ws->bz[i] = z[i], ws->bs[i] = s[i];
    ws->warm = 1;
    return TSCVX_SETUP_OK;
}

tscvx_solve_status tscvx_solve(tscvx_workspace *ws) {
    if (ws == NULL || !ws_intact(ws)) return TSCVX_INVALID_INPUT; /* nothing written */
    if (!ws->ready) {
        ws->warm = 0; /* only the next solve may use the point */
        ws->info.status = TSCVX_INVALID_INPUT;
        return TSCVX_INVALID_INPUT;
    }
    ws->damaged_during = 0;
    const tscvx_solve_status status = tscvx_ipm(ws);
    /* The end check: the same sums again, so that a bit flipped during the solve (after the
     * start check, in what the iterations index by) is said by this solve, not the next.
     * No answer then: the status and info say invalid input, tscvx_get_solution gives no
     * iterate (TSCVX_SETUP_NO_SOLUTION), tscvx_check_workspace says it came during a solve.
     * The writes are to the struct's own fields, outside the sums: no pointer followed. */
    if (!ws_intact(ws)) {
        ws->damaged_during = TSCVX_DAMAGED_IN_SOLVE;
        ws->info.status = TSCVX_INVALID_INPUT;
        return TSCVX_INVALID_INPUT;
    }
    return status;
}

tscvx_setup_status tscvx_get_solution(const tscvx_workspace *ws, tscvx_float *x, tscvx_float *y,
                                      tscvx_float *z, tscvx_float *s) {
    if (ws == NULL) return TSCVX_SETUP_NULL_ARGUMENT;
    if (!ws_head_intact(ws) || !ws->ready) return TSCVX_SETUP_NOT_READY;
    if (ws->info.status == TSCVX_UNSOLVED || ws->info.status == TSCVX_NUMERICAL_ERROR ||
        ws->info.status == TSCVX_INVALID_INPUT)
        return TSCVX_SETUP_NO_SOLUTION; /* nothing solved since the data, no point kept, or
                                           the workspace damaged during the last solve */
    tscvx_unscale_solution(ws, x, y, z, s);
    return TSCVX_SETUP_OK;
}

tscvx_setup_status tscvx_get_info(const tscvx_workspace *ws, tscvx_info *info) {
    if (ws == NULL || info == NULL) return TSCVX_SETUP_NULL_ARGUMENT;
    if (!ws_head_intact(ws)) return TSCVX_SETUP_NOT_READY;
    *info = ws->info;
    return TSCVX_SETUP_OK;
}

tscvx_setup_status tscvx_get_iter_log(const tscvx_workspace *ws, tscvx_int k,
                                      tscvx_iter_log *row) {
    if (ws == NULL || row == NULL) return TSCVX_SETUP_NULL_ARGUMENT;
    if (!ws_head_intact(ws) || !ws->ready) return TSCVX_SETUP_NOT_READY;
    if (ws->info.status == TSCVX_UNSOLVED) return TSCVX_SETUP_NO_SOLUTION; /* no log since the data */
    if (k < 0 || k >= ws->log_cap || k > ws->info.iterations) return TSCVX_SETUP_BAD_INDEX;
    *row = ws->log[k];
    return TSCVX_SETUP_OK;
}
