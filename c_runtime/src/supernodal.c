/* Supernodal LDL' backend (opt-in, tscvx_settings.kkt_backend): dense panels, no library
 * code per iteration.
 *
 * The KKT matrix is quasi-definite after the static regularization, so any symmetric
 * ordering has an LDL' factorization without pivoting; the ordering is AMD's (kkt.c). At
 * setup the elimination tree and column counts (LDL's ldl_symbolic) split the columns into
 * supernodes: runs of consecutive columns j, j+1, ... with parent(j) = j+1 and
 * |L(:,j)| = |L(:,j+1)| + 1, whose columns share one row structure below the diagonal block.
 * Each supernode s (columns f..f+w-1, rows R below) owns a dense column-major panel
 *
 *     X_s = [ L(f:f+w-1, f:f+w-1) ]   h x w,  h = w + |R|,
 *           [ L(R,       f:f+w-1) ]
 *
 * with D on the diagonal. Factorization (right-looking over supernodes, in column order):
 * assemble K into the panels through a map fixed at setup, then for each supernode s factor
 * its panel densely (X := L with D on the diagonal) and subtract its update
 * L(R,s) D_s L(R,s)' from the panels of the supernodes that own the columns in R (the rows
 * are located by a merge with the target's row list, both ascending). Solves run over the
 * panels: L y = b forward, y := D^{-1} y, L' x = y backward.
 *
 * Memory: panels (sum h w doubles), the row lists, 3 (nsuper+1) + dim + nnz(K) ints.
 */
#include <limits.h>
#include <math.h>

#include "ldl.h"
#include "socp_internal.h"

/* Supernode partition from the elimination tree and the off-diagonal column counts Lnz.
 * Column e+1 joins the supernode ending at e when parent(e) = e+1 (then the rows of the
 * supernode below e+1 are those of column e+1) and the explicit zeros that the common row
 * structure adds stay within SN_RELAX_ZEROS (relaxed supernodes: fewer, wider panels; on
 * the landing KKT 4..64 zeros bought nothing, so the default keeps exact supernodes).
 * first[] (nsuper+1) is written when not NULL. Returns the number of supernodes. */
#ifndef SN_RELAX_ZEROS
#define SN_RELAX_ZEROS 0
#endif
#define SN_MAX_WIDTH 64

static tscvx_int partition(tscvx_int dim, const tscvx_int *Parent, const tscvx_int *Lnz,
                           tscvx_int *first) {
    tscvx_int ns = 0;
    for (tscvx_int j = 0; j < dim;) {
        tscvx_int e = j;
        long sum = Lnz[j]; /* true entries below the diagonal in columns j..e */
        while (e + 1 < dim && Parent[e] == e + 1 && e + 2 - j <= SN_MAX_WIDTH) {
            const long w = e + 2 - j;
            const long zeros = w * (w - 1) / 2 + w * Lnz[e + 1] - (sum + Lnz[e + 1]);
            if (zeros > SN_RELAX_ZEROS) break;
            e++;
            sum += Lnz[e];
        }
        if (first) first[ns] = j;
        ns++;
        j = e + 1;
    }
    if (first) first[ns] = dim;
    return ns;
}

/* Sizes of the factor: supernodes, row-list entries, panel doubles, widest panel, largest
 * row list. `tmp` holds 4 dim + 1 free ints. Returns nnz(L), or -1 when too large. */
static long sn_symbolic(tscvx_kkt *k, tscvx_int *tmp) {
    const tscvx_int dim = k->dim;
    tscvx_int *Lp = tmp, *Parent = Lp + dim + 1, *Lnz = Parent + dim, *Flag = Lnz + dim;
    ldl_symbolic(dim, k->Kp, k->Ki, Lp, Parent, Lnz, Flag, NULL, NULL);
    tscvx_int *First = Flag + dim;
    const tscvx_int ns = partition(dim, Parent, Lnz, First);
    long nrow = 0, nlx = 0;
    tscvx_int wmax = 1, rmax = 0;
    for (tscvx_int t = 0; t < ns; t++) {
        const tscvx_int w = First[t + 1] - First[t], r = Lnz[First[t + 1] - 1];
        nrow += r;
        nlx += (long)(w + r) * w;
        wmax = w > wmax ? w : wmax;
        rmax = r > rmax ? r : rmax;
    }
    if (nlx > INT_MAX / 4 || nrow > INT_MAX / 4) return -1;
    k->nsuper = ns, k->nsrow = (tscvx_int)nrow, k->nslx = (tscvx_int)nlx;
    k->wmax = wmax, k->rmax = rmax;
    return (long)Lp[dim];
}

/* Position of row r in the panel of supernode s (r >= first column of s, r in its rows). */
static tscvx_int panel_row(const tscvx_kkt *k, tscvx_int s, tscvx_int r) {
    const tscvx_int f = k->sfirst[s], w = k->sfirst[s + 1] - f;
    if (r < f + w) return r - f;
    tscvx_int lo = k->srowp[s], hi = k->srowp[s + 1] - 1; /* binary search (setup only) */
    while (lo < hi) {
        const tscvx_int mid = lo + (hi - lo) / 2;
        if (k->srows[mid] < r) lo = mid + 1;
        else hi = mid;
    }
    return w + (lo - k->srowp[s]);
}

/* Claim the factor; with memory present, build the supernodes, row lists and the map from
 * KKT slots to panel slots (temporary ints above the claims, released again). */
static int sn_alloc(tscvx_kkt *k, tscvx_arena *a) {
    const tscvx_int dim = k->dim, ns = k->nsuper;
    k->sfirst = (tscvx_int *)tscvx_arena_alloc(a, (size_t)ns + 1, sizeof(tscvx_int));
    k->srowp = (tscvx_int *)tscvx_arena_alloc(a, (size_t)ns + 1, sizeof(tscvx_int));
    k->sxp = (tscvx_int *)tscvx_arena_alloc(a, (size_t)ns + 1, sizeof(tscvx_int));
    k->srows = (tscvx_int *)tscvx_arena_alloc(a, (size_t)k->nsrow + 1, sizeof(tscvx_int));
    k->col2sup = (tscvx_int *)tscvx_arena_alloc(a, (size_t)dim, sizeof(tscvx_int));
    k->kmap = (tscvx_int *)tscvx_arena_alloc(a, (size_t)k->nnz, sizeof(tscvx_int));
    k->srel = (tscvx_int *)tscvx_arena_alloc(a, (size_t)k->rmax + 1, sizeof(tscvx_int));
    k->SLx = (tscvx_float *)tscvx_arena_alloc(a, (size_t)k->nslx, sizeof(tscvx_float));
    k->swork = (tscvx_float *)tscvx_arena_alloc(a, (size_t)k->wmax + k->rmax + 1, sizeof(tscvx_float));
    k->D = (tscvx_float *)tscvx_arena_alloc(a, (size_t)dim, sizeof(tscvx_float));
    k->res = (tscvx_float *)tscvx_arena_alloc(a, (size_t)dim, sizeof(tscvx_float));
    const size_t mark = a->top;
    tscvx_int *Lp = (tscvx_int *)tscvx_arena_alloc(a, 4 * (size_t)dim + 1, sizeof(tscvx_int));
    const int ready = a->base != NULL && !a->overflow;
    a->top = mark;
    if (!ready) return 0; /* counting only */
    tscvx_int *Parent = Lp + dim + 1, *Lnz = Parent + dim, *Flag = Lnz + dim;
    ldl_symbolic(dim, k->Kp, k->Ki, Lp, Parent, Lnz, Flag, NULL, NULL);
    if (partition(dim, Parent, Lnz, k->sfirst) != ns) return -1;
    tscvx_int nrow = 0, nlx = 0;
    for (tscvx_int s = 0; s < ns; s++) {
        const tscvx_int f = k->sfirst[s], e = k->sfirst[s + 1] - 1, w = e - f + 1;
        k->srowp[s] = nrow, k->sxp[s] = nlx;
        nrow += Lnz[e], nlx += (w + Lnz[e]) * w;
        for (tscvx_int j = f; j <= e; j++) k->col2sup[j] = s;
        Lnz[s] = k->srowp[s]; /* fill pointer of the row list */
    }
    k->srowp[ns] = nrow, k->sxp[ns] = nlx;
    if (nrow != k->nsrow || nlx != k->nslx) return -1;
    /* row lists: row k enters supernode s when the etree walk from K(:,k) passes s's last
     * column (the walks visit rows in ascending order, so the lists come out sorted) */
    for (tscvx_int r = 0; r < dim; r++) {
        Flag[r] = r;
        for (tscvx_int t = k->Kp[r]; t < k->Kp[r + 1]; t++) {
            for (tscvx_int j = k->Ki[t]; Flag[j] != r; j = Parent[j]) {
                Flag[j] = r;
                const tscvx_int s = k->col2sup[j];
                if (j == k->sfirst[s + 1] - 1) {
                    if (Lnz[s] >= k->srowp[s + 1]) return -1;
                    k->srows[Lnz[s]++] = r;
                }
            }
        }
    }
    /* KKT slot -> panel slot: entry (i, r), i <= r, is L(r, i) in the panel of i's supernode */
    for (tscvx_int r = 0; r < dim; r++)
        for (tscvx_int t = k->Kp[r]; t < k->Kp[r + 1]; t++) {
            const tscvx_int i = k->Ki[t], s = k->col2sup[i];
            const tscvx_int f = k->sfirst[s], h = k->sfirst[s + 1] - f + k->srowp[s + 1] - k->srowp[s];
            k->kmap[t] = k->sxp[s] + (i - f) * h + panel_row(k, s, r);
        }
    return 0;
}

/* x[0..n) = v with plain stores, four per pass. (Called with a zero computed at run time, so
 * the compiler does not turn the loop into memset, whose byte-wise `rep stos` the host
 * instruction count would overstate; a scalar target zeroes with stores as well.) */
static void fill(tscvx_float *x, tscvx_int n, tscvx_float v) {
    tscvx_int i = 0;
    for (; i + 4 <= n; i += 4) x[i] = v, x[i + 1] = v, x[i + 2] = v, x[i + 3] = v;
    for (; i < n; i++) x[i] = v;
}

/* y[0..n) -= X[0..n) t0 + X[h..h+n) t1 + ...: the columns of a panel (stride h) times t[0..w),
 * four columns per pass (the loop overhead and the loads of y shared). */
static void panel_gemv(const tscvx_float *X, tscvx_int h, const tscvx_float *t, tscvx_int w,
                       tscvx_float *y, tscvx_int n) {
    tscvx_int q = 0;
    for (; q + 4 <= w; q += 4) {
        const tscvx_float *x0 = X + (size_t)q * h, *x1 = x0 + h, *x2 = x1 + h, *x3 = x2 + h;
        const tscvx_float t0 = t[q], t1 = t[q + 1], t2 = t[q + 2], t3 = t[q + 3];
        for (tscvx_int i = 0; i < n; i++) y[i] -= x0[i] * t0 + x1[i] * t1 + x2[i] * t2 + x3[i] * t3;
    }
    for (; q + 2 <= w; q += 2) {
        const tscvx_float *x0 = X + (size_t)q * h, *x1 = x0 + h;
        const tscvx_float t0 = t[q], t1 = t[q + 1];
        for (tscvx_int i = 0; i < n; i++) y[i] -= x0[i] * t0 + x1[i] * t1;
    }
    if (q < w) {
        const tscvx_float *x0 = X + (size_t)q * h;
        const tscvx_float t0 = t[q];
        for (tscvx_int i = 0; i < n; i++) y[i] -= x0[i] * t0;
    }
}

/* Subtract the update L(R,s) D_s L(R,s)' of the factored supernode s from the panels of the
 * supernodes that own the columns in R. */
static void push_update(tscvx_kkt *k, tscvx_int s) {
    const tscvx_int f = k->sfirst[s], w = k->sfirst[s + 1] - f;
    const tscvx_int *R = k->srows + k->srowp[s];
    const tscvx_int nr = k->srowp[s + 1] - k->srowp[s], h = w + nr;
    const tscvx_float *X = k->SLx + k->sxp[s], *D = k->D + f;
    tscvx_int *rel = k->srel;
    tscvx_float *tv = k->swork, *acc = k->swork + w;
    for (tscvx_int a = 0; a < nr;) {
        /* target supernode T owns column R[a]; rows R[a..] are rows of T's panel */
        const tscvx_int T = k->col2sup[R[a]], fT = k->sfirst[T], wT = k->sfirst[T + 1] - fT;
        const tscvx_int *RT = k->srows + k->srowp[T];
        const tscvx_int hT = wT + k->srowp[T + 1] - k->srowp[T];
        tscvx_float *XT = k->SLx + k->sxp[T];
        tscvx_int a2 = a, p = 0;
        for (tscvx_int b = a; b < nr; b++) {
            const tscvx_int r = R[b];
            if (r < fT + wT) {
                rel[b] = r - fT;
                a2 = b + 1;
            } else {
                while (RT[p] != r) p++;
                rel[b] = wT + p;
            }
        }
        if (w == 1) { /* rank one: two target columns per pass */
            const tscvx_float *l = X + 1;
            tscvx_int b = a;
            for (; b + 1 < a2; b += 2) {
                tscvx_float *c0 = XT + (size_t)rel[b] * hT, *c1 = XT + (size_t)rel[b + 1] * hT;
                const tscvx_float t0 = D[0] * l[b], t1 = D[0] * l[b + 1];
                c0[rel[b]] -= l[b] * t0;
                for (tscvx_int c = b + 1; c < nr; c++) {
                    const tscvx_float lc = l[c];
                    const tscvx_int rc = rel[c];
                    c0[rc] -= lc * t0;
                    c1[rc] -= lc * t1;
                }
            }
            if (b < a2) {
                tscvx_float *c0 = XT + (size_t)rel[b] * hT;
                const tscvx_float t0 = D[0] * l[b];
                for (tscvx_int c = b; c < nr; c++) c0[rel[c]] -= l[c] * t0;
            }
        } else {
            for (tscvx_int b = a; b < a2; b++) {
                tscvx_float *col = XT + (size_t)rel[b] * hT;
                for (tscvx_int q = 0; q < w; q++) tv[q] = D[q] * X[(size_t)q * h + w + b];
                const tscvx_int n = nr - b;
                for (tscvx_int c = 0; c < n; c++) acc[c] = 0.0;
                panel_gemv(X + w + b, h, tv, w, acc, n); /* acc = -L(R[b..], s) tv */
                for (tscvx_int c = 0; c < n; c++) col[rel[b + c]] += acc[c];
            }
        }
        a = a2;
    }
}

static int sn_numeric(tscvx_kkt *k) {
    tscvx_float *SLx = k->SLx, *tv = k->swork;
    fill(SLx, k->nslx, 0.0 * k->delta); /* delta is finite: +0 */
    for (tscvx_int t = 0; t < k->nnz; t++) SLx[k->kmap[t]] = k->Kx[t];
    tscvx_int npos = 0;
    for (tscvx_int s = 0; s < k->nsuper; s++) {
        const tscvx_int f = k->sfirst[s], w = k->sfirst[s + 1] - f;
        const tscvx_int h = w + k->srowp[s + 1] - k->srowp[s];
        tscvx_float *X = SLx + k->sxp[s];
        /* dense LDL' of the panel, left-looking within it:
         *   X(j:h, j) -= X(j:h, 0:j) t,  t = D(0:j) .* X(j, 0:j)';  d_j = X(j,j); scale */
        for (tscvx_int j = 0; j < w; j++) {
            tscvx_float *cj = X + (size_t)j * h;
            if (j > 0) {
                for (tscvx_int c = 0; c < j; c++) tv[c] = k->D[f + c] * X[(size_t)c * h + j];
                panel_gemv(X + j, h, tv, j, cj + j, h - j);
            }
            const tscvx_float d = cj[j];
            if (!(d != 0.0) || !isfinite(d)) return -1;
            k->D[f + j] = d;
            npos += d > 0.0;
            for (tscvx_int i = j + 1; i < h; i++) cj[i] /= d; /* division: as exact as LDL's */
        }
        if (h > w) push_update(k, s);
    }
    return npos == k->npos ? 0 : -1;
}

/* x := L^{-T} D^{-1} L^{-1} x over the panels */
static void sn_solve(tscvx_kkt *k, tscvx_float *x) {
    const tscvx_int ns = k->nsuper;
    tscvx_float *acc = k->swork;
    for (tscvx_int s = 0; s < ns; s++) { /* L y = b */
        const tscvx_int f = k->sfirst[s], w = k->sfirst[s + 1] - f;
        const tscvx_int *R = k->srows + k->srowp[s];
        const tscvx_int nr = k->srowp[s + 1] - k->srowp[s], h = w + nr;
        const tscvx_float *X = k->SLx + k->sxp[s];
        tscvx_float *xs = x + f;
        if (w == 1) {
            const tscvx_float x0 = xs[0], *l = X + 1;
            tscvx_int b = 0;
            for (; b + 2 <= nr; b += 2) x[R[b]] -= l[b] * x0, x[R[b + 1]] -= l[b + 1] * x0;
            if (b < nr) x[R[b]] -= l[b] * x0;
            continue;
        }
        for (tscvx_int c = 0; c < w; c++) {
            const tscvx_float *col = X + (size_t)c * h;
            const tscvx_float xc = xs[c];
            for (tscvx_int i = c + 1; i < w; i++) xs[i] -= col[i] * xc;
        }
        for (tscvx_int b = 0; b < nr; b++) acc[b] = 0.0;
        panel_gemv(X + w, h, xs, w, acc, nr); /* acc = -L(R, s) x_s */
        for (tscvx_int b = 0; b < nr; b++) x[R[b]] += acc[b];
    }
    for (tscvx_int i = 0; i < k->dim; i++) x[i] /= k->D[i];
    for (tscvx_int s = ns - 1; s >= 0; s--) { /* L' x = y */
        const tscvx_int f = k->sfirst[s], w = k->sfirst[s + 1] - f;
        const tscvx_int *R = k->srows + k->srowp[s];
        const tscvx_int nr = k->srowp[s + 1] - k->srowp[s], h = w + nr;
        const tscvx_float *X = k->SLx + k->sxp[s];
        tscvx_float *xs = x + f;
        if (w == 1) {
            const tscvx_float *l = X + 1;
            tscvx_float a0 = xs[0], a1 = 0.0;
            tscvx_int b = 0;
            for (; b + 2 <= nr; b += 2) a0 -= l[b] * x[R[b]], a1 -= l[b + 1] * x[R[b + 1]];
            if (b < nr) a0 -= l[b] * x[R[b]];
            xs[0] = a0 + a1;
            continue;
        }
        for (tscvx_int b = 0; b < nr; b++) acc[b] = x[R[b]]; /* gather once */
        for (tscvx_int c = w - 1; c >= 0; c--) {
            const tscvx_float *col = X + (size_t)c * h;
            tscvx_float a0 = xs[c], a1 = 0.0;
            tscvx_int b = 0;
            for (; b + 1 < nr; b += 2) a0 -= col[w + b] * acc[b], a1 -= col[w + b + 1] * acc[b + 1];
            if (b < nr) a0 -= col[w + b] * acc[b];
            for (tscvx_int i = c + 1; i < w; i++) a0 -= col[i] * xs[i];
            xs[c] = a0 + a1;
        }
    }
}

const tscvx_backend tscvx_backend_supernodal = {"supernodal", sn_symbolic, sn_alloc,
                                                sn_numeric, sn_solve};
