/* Static-pattern LDL' backend (default, tscvx_settings.kkt_backend = TSCVX_KKT_STATIC): the
 * arithmetic of SuiteSparse LDL with its symbolic work done once, at setup.
 *
 * The KKT matrix is quasi-definite after the static regularization, so the AMD ordering
 * (kkt.c) has an LDL' factorization without pivoting. SuiteSparse's ldl_numeric is
 * up-looking: row k of L solves L(0:k,0:k) y = K(0:k,k), and it finds the row's pattern at
 * every factorization by walking the elimination tree from each nonzero of K(0:k,k) (with a
 * flag per node), then appends L(k,j) to each column j. The pattern, and where each L(k,j)
 * lands, do not change between factorizations, so setup records them once:
 *   Lp, Li   the column structure of L (rows ascending), as LDL would write it;
 *   Rp, Rj   row k's pattern, in the order ldl_numeric visits it (a topological order).
 * The factorization then runs the same operations in the same order as ldl_numeric, so the
 * factor is bitwise that of SuiteSparse LDL, and the solves (L, D, L' sweeps as ldl_lsolve,
 * ldl_dsolve, ldl_ltsolve) give the same numbers too, with less loop overhead.
 *
 * Memory: LDL's Lp, Li, Lx, D and work vector, plus the row patterns (dim + 1 + nnz(L) ints);
 * LDL's Parent, Lnz and Flag are not kept, the column fill pointers share the solves' vector.
 */
#include <math.h>

#include "ldl.h"
#include "socp_internal.h"

/* Sizes of the factor: the column counts of LDL's symbolic analysis. `tmp` holds 4 dim + 1
 * free ints. Returns nnz(L). */
static long st_symbolic(tscvx_kkt *k, tscvx_int *tmp) {
    tscvx_int *Lp = tmp, *Parent = Lp + k->dim + 1, *Lnz = Parent + k->dim, *Flag = Lnz + k->dim;
    ldl_symbolic(k->dim, k->Kp, k->Ki, Lp, Parent, Lnz, Flag, NULL, NULL);
    return (long)Lp[k->dim];
}

/* Claim the factor; with memory present, record the patterns (temporary ints above the
 * claims for the elimination tree, counts and flags, released again). */
static int st_alloc(tscvx_kkt *k, tscvx_arena *a) {
    const tscvx_int dim = k->dim, lnz = k->lnz;
    TSCVX_CLAIM(a, k->Lp, (size_t)dim + 1, tscvx_int);
    TSCVX_CLAIM(a, k->Li, (size_t)lnz + 1, tscvx_int);
    TSCVX_CLAIM(a, k->Lx, (size_t)lnz + 1, tscvx_float);
    TSCVX_CLAIM(a, k->Rp, (size_t)dim + 1, tscvx_int);
    TSCVX_CLAIM(a, k->Rj, (size_t)lnz + 1, tscvx_int);
    TSCVX_CLAIM(a, k->D, (size_t)dim, tscvx_float);
    TSCVX_CLAIM(a, k->Y, (size_t)dim, tscvx_float);
    k->res = k->Y; /* the factorization's work vector is free during solves */
    const size_t mark = a->top;
    tscvx_int *Parent = (tscvx_int *)tscvx_arena_alloc(a, 4 * (size_t)dim, sizeof(tscvx_int));
    const int ready = a->base != NULL && !a->overflow;
    a->top = mark;
    if (!ready) return 0; /* counting only */
    tscvx_int *Cnt = Parent + dim, *Flag = Cnt + dim, *Pattern = Flag + dim;
    const tscvx_int *Lp = k->Lp;
    ldl_symbolic(dim, k->Kp, k->Ki, k->Lp, Parent, Cnt, Flag, NULL, NULL);
    if (Lp[dim] != lnz) return -1;
    /* ldl_numeric's walk: from each K(i,r), i < r, up the tree to the first node already
     * flagged for row r; each path is put in front of the previous ones */
    for (tscvx_int j = 0; j < dim; j++) Cnt[j] = 0, Flag[j] = -1; /* symbolic left flags */
    tscvx_int nz = 0;
    for (tscvx_int r = 0; r < dim; r++) {
        tscvx_int top = dim;
        Flag[r] = r;
        for (tscvx_int t = k->Kp[r]; t < k->Kp[r + 1]; t++) {
            tscvx_int len = 0;
            for (tscvx_int j = k->Ki[t];; j = Parent[j]) { /* <= r + 1 steps: r is flagged */
                if (j < 0 || j > r || len >= top) return -1; /* not an elimination tree */
                if (Flag[j] == r) break;
                Pattern[len++] = j;
                Flag[j] = r;
            }
            while (len > 0) Pattern[--top] = Pattern[--len];
        }
        k->Rp[r] = nz;
        if (nz + (dim - top) > lnz) return -1;
        for (; top < dim; top++) {
            const tscvx_int j = Pattern[top];
            if (Lp[j] + Cnt[j] >= Lp[j + 1]) return -1;
            k->Li[Lp[j] + Cnt[j]++] = r;
            k->Rj[nz++] = j;
        }
    }
    k->Rp[dim] = nz;
    return nz == lnz ? 0 : -1;
}

static int st_numeric(tscvx_kkt *k) {
    const tscvx_int *Kp = k->Kp, *Ki = k->Ki, *Lp = k->Lp, *Li = k->Li;
    const tscvx_int *Rp = k->Rp, *Rj = k->Rj;
    const tscvx_float *Kx = k->Kx;
    tscvx_float *Lx = k->Lx, *D = k->D, *Y = k->Y;
    tscvx_int *Next = k->Pattern; /* next free slot of each column */
    const tscvx_int dim = k->dim;
    for (tscvx_int j = 0; j < dim; j++) Y[j] = 0.0, Next[j] = Lp[j];
    tscvx_int npos = 0;
    for (tscvx_int r = 0; r < dim; r++) {
        for (tscvx_int t = Kp[r]; t < Kp[r + 1]; t++) Y[Ki[t]] = Kx[t]; /* Y was 0 there */
        tscvx_float d = Y[r];
        Y[r] = 0.0;
        for (tscvx_int t = Rp[r]; t < Rp[r + 1]; t++) {
            const tscvx_int j = Rj[t];
            const tscvx_float yj = Y[j];
            Y[j] = 0.0;
            const tscvx_int p1 = Next[j];
            tscvx_int p = Lp[j];
            for (; p + 1 < p1; p += 2) Y[Li[p]] -= Lx[p] * yj, Y[Li[p + 1]] -= Lx[p + 1] * yj;
            if (p < p1) Y[Li[p]] -= Lx[p] * yj;
            const tscvx_float l = yj / D[j];
            d -= l * yj;
            Lx[p1] = l;
            Next[j] = p1 + 1;
        }
        /* a zero or non-finite pivot fails, as in LDL; the inertia is checked at the end */
        if (!(d != 0.0) || !isfinite(d)) return -1;
        D[r] = d;
        npos += d > 0.0;
    }
    return npos == k->npos ? 0 : -1;
}

/* x := L^{-T} D^{-1} L^{-1} x, the operations of ldl_lsolve, ldl_dsolve, ldl_ltsolve */
static void st_solve(tscvx_kkt *k, tscvx_float *x) {
    const tscvx_int dim = k->dim, *Lp = k->Lp, *Li = k->Li;
    const tscvx_float *Lx = k->Lx, *D = k->D;
    for (tscvx_int j = 0; j < dim; j++) { /* L y = b, by columns */
        const tscvx_float xj = x[j];
        tscvx_int p = Lp[j];
        const tscvx_int p1 = Lp[j + 1];
        for (; p + 1 < p1; p += 2) x[Li[p]] -= Lx[p] * xj, x[Li[p + 1]] -= Lx[p + 1] * xj;
        if (p < p1) x[Li[p]] -= Lx[p] * xj;
    }
    for (tscvx_int j = dim - 1; j >= 0; j--) { /* y ./ d, then L' x = y, by columns */
        tscvx_float xj = x[j] / D[j];
        tscvx_int p = Lp[j];
        const tscvx_int p1 = Lp[j + 1];
        for (; p + 1 < p1; p += 2) xj -= Lx[p] * x[Li[p]], xj -= Lx[p + 1] * x[Li[p + 1]];
        if (p < p1) xj -= Lx[p] * x[Li[p]];
        x[j] = xj;
    }
}

const tscvx_backend tscvx_backend_static = {"static-ldl", st_symbolic, st_alloc, st_numeric,
                                            st_solve};
