/*
 * fuzz_socp.c -- fuzz harness of the SOCP runtime's whole API (tscvx_socp.h).
 *
 * The input describes a problem: sizes n, p, l and the cones (sometimes made inconsistent
 * with m), each of P (upper triangle), A, G either a valid pattern from bit masks or raw CSC
 * (column pointers and row indices as signed bytes: unsorted, out of range, decreasing,
 * duplicated), values from fz_double (NaN, inf, huge, tiny, subnormal, raw bits), the
 * settings (some left at their defaults, some out of range), then the numbers of a data
 * update and of a warm start. The harness runs check_data -> scratch_size ->
 * workspace_size -> setup -> solve -> update_data -> warm_start -> solve, every array in a
 * heap block of exactly its size (scratch and arena too: ASan sees any byte beyond).
 * Oracle:
 *   - every status documented, with a non-empty message; tscvx_check_data and
 *     tscvx_check_settings agree with what the size queries and setup return;
 *   - info.arena_high_water <= the arena size asked;
 *   - when a solve says SOLVED: its answer, recomputed here from the raw data, meets the
 *     tolerances within a wide margin (1e3 x, plus rounding of the sums): primal residuals
 *     |Ax - b|, |Gx + s - h|, dual residual |Px + c + A'y + G'z|, s and z in the cones, and
 *     the duality gap |pcost - dcost|;
 *   - when it says PRIMAL_INFEASIBLE or DUAL_INFEASIBLE: its certificate, recomputed the same
 *     way, is one (check_certificate).
 */
#include "fuzz.h"

#include "tscvx_socp.h"

#define MAXN 8
#define MAXP 5
#define MAXM 14
#define MAXNNZ 128
#define WIDE 1e3    /* the oracle's margin over the tolerances */
#define ROUND 1e-9  /* rounding allowance per unit of the sums' absolute terms */

typedef struct {
    int present;             /* 0: NULL arrays */
    tscvx_int *p, *i;        /* column pointers (n + 1), row indices (nnz) */
    tscvx_float *x, *x2;     /* values, the update's values */
    tscvx_int nnz;           /* entries the values hold (0 when the pointers are invalid) */
} csc;

typedef struct {
    tscvx_data d;
    csc P, A, G;
    tscvx_float *c, *b, *h, *c2, *b2, *h2;
    tscvx_int *q;
    tscvx_settings st;
} problem;

static void *xcalloc(size_t n, size_t size)
{
    void *v = calloc(n ? n : 1, size);
    if (!v) {
        abort();
    }
    return v;
}

static tscvx_float *values(fz_reader *r, tscvx_int n)
{
    tscvx_float *v = (tscvx_float *)xcalloc((size_t)n, sizeof *v);
    tscvx_int k;
    for (k = 0; k < n; ++k) {
        v[k] = fz_double(r);
    }
    return v;
}

/* A pattern of nrow x ncol: valid (rows from bit masks; mode 1 and upper: the diagonal at
 * most; mode 2: every entry) or raw (mode 3: signed bytes, at most RAWNNZ entries). The row
 * indices and values in heap blocks of exactly the entries the last pointer says. */
#define RAWNNZ 40
static void pattern(fz_reader *r, csc *M, tscvx_int nrow, tscvx_int ncol, unsigned mode, int upper)
{
    tscvx_int j, k, nnz = 0, rows[MAXNNZ];
    M->p = (tscvx_int *)xcalloc((size_t)ncol + 1, sizeof *M->p);
    if (mode == 3) { /* raw */
        for (j = 0; j <= ncol; ++j) {
            M->p[j] = (tscvx_int)(int8_t)fz_u8(r) % (RAWNNZ + 2);
        }
        nnz = M->p[ncol] > 0 ? M->p[ncol] : 0;
        if (nnz > RAWNNZ) {
            nnz = RAWNNZ;
            M->p[ncol] = RAWNNZ;
        }
        for (k = 0; k < nnz; ++k) {
            rows[k] = (tscvx_int)(int8_t)fz_u8(r) % 20;
        }
    } else {
        for (j = 0; j < ncol; ++j) {
            const unsigned bits = mode == 2 ? 0xFFFFu : fz_u16(r);
            const tscvx_int top = upper ? j + 1 : nrow;
            for (k = upper && mode == 1 ? j : 0; k < top && k < 16; ++k) {
                if ((bits >> k) & 1u) {
                    rows[nnz++] = k;
                }
            }
            M->p[j + 1] = nnz;
        }
    }
    M->nnz = nnz;
    M->i = (tscvx_int *)xcalloc((size_t)nnz, sizeof *M->i);
    for (k = 0; k < nnz; ++k) {
        M->i[k] = rows[k];
    }
    M->x = values(r, nnz);
    M->x2 = values(r, nnz);
}

static void free_csc(csc *M)
{
    free(M->p);
    free(M->i);
    free(M->x);
    free(M->x2);
}

static void settings(fz_reader *r, tscvx_settings *st)
{
    const unsigned f = fz_u8(r);
    tscvx_default_settings(st);
    st->max_iter = 30; /* fast runs */
    if (f & 1u) {
        st->max_iter = (tscvx_int)fz_u8(r) - 2;
    }
    if (f & 2u) {
        st->kkt_backend = (tscvx_int)(fz_u8(r) % 5u);
    }
    if (f & 4u) {
        st->tol_feas = fz_double(r);
        st->tol_gap_abs = fz_double(r);
        st->tol_gap_rel = fz_double(r);
    }
    if (f & 8u) {
        st->static_reg = fz_double(r);
        st->step_fraction = fz_double(r);
    }
    if (f & 16u) {
        st->refine_iters = (tscvx_int)fz_u8(r) - 1;
        st->ruiz_iters = (tscvx_int)fz_u8(r) - 1;
    }
    if (f & 32u) {
        st->soc_dense_max = (tscvx_int)fz_u8(r) - 1;
    }
    if (f & 64u) {
        st->tol_infeas = fz_double(r);
        st->tol_feas_inacc = fz_double(r);
    }
}

static void build(fz_reader *r, problem *pb)
{
    tscvx_data *d = &pb->d;
    const unsigned f = fz_u8(r), modes = fz_u8(r);
    tscvx_int k, rows;
    memset(pb, 0, sizeof *pb);
    d->n = 1 + (tscvx_int)(fz_u8(r) % MAXN);
    d->p = (tscvx_int)(fz_u8(r) % (MAXP + 1));
    d->l = (tscvx_int)(fz_u8(r) % 7u);
    d->nsoc = (tscvx_int)(fz_u8(r) % 4u);
    pb->q = (tscvx_int *)xcalloc(4, sizeof *pb->q);
    rows = d->l;
    for (k = 0; k < d->nsoc; ++k) {
        pb->q[k] = 1 + (tscvx_int)(fz_u8(r) % 4u);
        if (f & 1u) {
            pb->q[k] -= 1; /* a cone of 0 rows */
        }
        rows += pb->q[k];
    }
    d->m = rows;
    if (f & 2u) {
        d->m += (tscvx_int)(fz_u8(r) % 3u) - 1; /* rows and cones disagree */
    }
    if (d->m < 0 || d->m > MAXM) {
        d->m = d->m < 0 ? d->m : MAXM;
    }
    d->q = d->nsoc ? pb->q : NULL;
    if (f & 4u) {
        d->nsoc = -d->nsoc;
    }
    pb->P.present = (f & 8u) != 0;
    pb->A.present = !(f & 16u) || d->p > 0;
    pb->G.present = !(f & 32u) || d->m > 0;
    pattern(r, &pb->P, d->n, d->n, modes & 3u, 1);
    pattern(r, &pb->A, d->p > 0 ? d->p : 0, d->n, (modes >> 2) & 3u, 0);
    pattern(r, &pb->G, d->m > 0 ? d->m : 0, d->n, (modes >> 4) & 3u, 0);
    if (pb->P.present && (modes & 0x40u)) { /* P = |P| on a diagonal pattern: PSD */
        for (k = 0; k < pb->P.nnz; ++k) {
            pb->P.x[k] = fabs(pb->P.x[k]);
            pb->P.x2[k] = fabs(pb->P.x2[k]);
        }
    }
    pb->c = values(r, d->n);
    pb->b = values(r, d->p > 0 ? d->p : 0);
    pb->h = values(r, d->m > 0 ? d->m : 0);
    pb->c2 = values(r, d->n);
    pb->b2 = values(r, d->p > 0 ? d->p : 0);
    pb->h2 = values(r, d->m > 0 ? d->m : 0);
    if (pb->P.present) {
        d->Pp = pb->P.p, d->Pi = pb->P.i, d->Px = pb->P.x;
    }
    if (pb->A.present) {
        d->Ap = pb->A.p, d->Ai = pb->A.i, d->Ax = pb->A.x;
    }
    if (pb->G.present) {
        d->Gp = pb->G.p, d->Gi = pb->G.i, d->Gx = pb->G.x;
    }
    d->c = pb->c, d->b = pb->b, d->h = pb->h;
    settings(r, &pb->st);
}

static void check_setup_status(tscvx_setup_status s, const char *where)
{
    const char *m;
    if ((unsigned)s >= (unsigned)TSCVX_SETUP_NSTATUS) {
        FZ_FAIL("%s: undocumented status %d", where, (int)s);
    }
    m = tscvx_setup_status_message(s);
    if (!m || !m[0]) {
        FZ_FAIL("%s: status %d without a message", where, (int)s);
    }
}

/* ---- the independent check of a SOLVED answer ------------------------------------------ */

/* Residual sum and the sum of its terms' magnitudes, in long double (x86: 64-bit mantissa,
 * 15-bit exponent): the sums of data near DBL_MAX neither overflow nor lose the answer. */
typedef long double ldouble;
typedef struct {
    ldouble r, slack;
} acc;

static double vmax(const double *v, tscvx_int n)
{
    double a = 0.0;
    tscvx_int k;
    for (k = 0; k < n; ++k) {
        a = fmax(a, fabs(v[k]));
    }
    return a;
}

static void addl(acc *a, ldouble t)
{
    a->r += t;
    a->slack += fabsl(t);
}

/* a += u v (u = 1: a term alone), in long double */
static void add(acc *a, double u, double v)
{
    addl(a, (ldouble)u * (ldouble)v);
}

/* y = M x (M not symmetric) or, for P, the symmetric product from the upper triangle;
 * and M' y into xt. Into accumulators (rounding allowance). */
static void mul(const csc *M, const tscvx_float *Mx, tscvx_int ncol, const double *x, acc *out,
                const double *y, acc *outt, int sym)
{
    tscvx_int j, k;
    for (j = 0; j < ncol; ++j) {
        for (k = M->p[j]; k < M->p[j + 1]; ++k) {
            const tscvx_int i = M->i[k];
            add(&out[i], Mx[k], x[j]);
            if (sym && i != j) {
                add(&out[j], Mx[k], x[i]);
            }
            if (outt) {
                add(&outt[j], Mx[k], y[i]);
            }
        }
    }
}

static int in_cone(const tscvx_data *d, const double *v, double tol)
{
    tscvx_int k, at = d->l, c;
    for (k = 0; k < d->l; ++k) {
        if (v[k] < -tol) {
            return 0;
        }
    }
    for (c = 0; c < d->nsoc; ++c) {
        double u = 0.0, big = 0.0;
        for (k = 1; k < d->q[c]; ++k) {
            big = fmax(big, fabs(v[at + k]));
        }
        for (k = 1; big > 0.0 && k < d->q[c]; ++k) { /* scaled: no overflow */
            u += (v[at + k] / big) * (v[at + k] / big);
        }
        if (v[at] < big * sqrt(u) - tol) {
            return 0;
        }
        at += d->q[c];
    }
    return 1;
}

#ifdef FUZZ_TRACE
static void dumpv(const char *name, const double *v, tscvx_int n)
{
    tscvx_int k;
    fprintf(stderr, "%s =", name);
    for (k = 0; k < n; ++k) {
        fprintf(stderr, " %.17g", v[k]);
    }
    fprintf(stderr, "\n");
}

static void dumpm(const char *name, const csc *M, const tscvx_float *Mx, tscvx_int ncol)
{
    tscvx_int j, k;
    fprintf(stderr, "%s:", name);
    for (j = 0; j < ncol; ++j) {
        for (k = M->p[j]; k < M->p[j + 1]; ++k) {
            fprintf(stderr, " (%d,%d)=%.17g", (int)M->i[k], (int)j, Mx[k]);
        }
    }
    fprintf(stderr, "\n");
}

static void dump(const problem *pb, const tscvx_float *Px, const tscvx_float *Ax,
                 const tscvx_float *Gx, const tscvx_float *c, const tscvx_float *b,
                 const tscvx_float *h, const double *x, const double *y, const double *z,
                 const double *s)
{
    const tscvx_data *d = &pb->d;
    tscvx_int k;
    fprintf(stderr, "n %d p %d m %d l %d cones", (int)d->n, (int)d->p, (int)d->m, (int)d->l);
    for (k = 0; k < d->nsoc; ++k) {
        fprintf(stderr, " %d", (int)d->q[k]);
    }
    fprintf(stderr, " backend %d max_iter %d tol_feas %g gap_abs %g gap_rel %g infeas %g "
            "static_reg %g step %g refine %d ruiz %d soc_dense %d\n", (int)pb->st.kkt_backend,
            (int)pb->st.max_iter, pb->st.tol_feas, pb->st.tol_gap_abs, pb->st.tol_gap_rel,
            pb->st.tol_infeas, pb->st.static_reg, pb->st.step_fraction, (int)pb->st.refine_iters,
            (int)pb->st.ruiz_iters, (int)pb->st.soc_dense_max);
    if (d->Pp) {
        dumpm("P", &pb->P, Px, d->n);
    }
    if (d->Ap) {
        dumpm("A", &pb->A, Ax, d->n);
    }
    if (d->Gp) {
        dumpm("G", &pb->G, Gx, d->n);
    }
    dumpv("c", c, d->n), dumpv("b", b, d->p), dumpv("h", h, d->m);
    dumpv("x", x, d->n), dumpv("y", y, d->p), dumpv("z", z, d->m), dumpv("s", s, d->m);
}
#endif

static void check_solved(tscvx_workspace *ws, const problem *pb, const tscvx_float *Px,
                         const tscvx_float *Ax, const tscvx_float *Gx, const tscvx_float *c,
                         const tscvx_float *b, const tscvx_float *h, const char *when)
{
    const tscvx_data *d = &pb->d;
    const tscvx_settings *st = &pb->st;
    double x[MAXN], y[MAXP + 1], z[MAXM + 1], s[MAXM + 1];
    acc rx[MAXN], ry[MAXP + 1], rz[MAXM + 1], xPx = {0, 0}, lin = {0, 0};
    tscvx_int k;
    tscvx_info info;
    double nb = vmax(b, d->p), nh = vmax(h, d->m), nc = vmax(c, d->n);
    ldouble pcost, dcost, gap, gtol;
    if (tscvx_get_solution(ws, x, y, z, s) != TSCVX_SETUP_OK
        || tscvx_get_info(ws, &info) != TSCVX_SETUP_OK) {
        FZ_FAIL("%s: SOLVED but no solution or info", when);
    }
#ifdef FUZZ_TRACE
    dump(pb, Px, Ax, Gx, c, b, h, x, y, z, s);
#endif
    memset(rx, 0, sizeof rx), memset(ry, 0, sizeof ry), memset(rz, 0, sizeof rz);
    for (k = 0; k < d->n; ++k) {
        add(&rx[k], 1.0, c[k]);
    }
    for (k = 0; k < d->p; ++k) {
        add(&ry[k], -1.0, b[k]);
    }
    for (k = 0; k < d->m; ++k) {
        add(&rz[k], 1.0, s[k]);
        add(&rz[k], -1.0, h[k]);
    }
    if (d->Pp) {
        mul(&pb->P, Px, d->n, x, rx, NULL, NULL, 1);
    }
    if (d->Ap && d->p > 0) {
        mul(&pb->A, Ax, d->n, x, ry, y, rx, 0);
    }
    if (d->Gp && d->m > 0) {
        mul(&pb->G, Gx, d->n, x, rz, z, rx, 0);
    }
    for (k = 0; k < d->p; ++k) {
        if (!(fabsl(ry[k].r) <= (ldouble)WIDE * st->tol_feas * (1 + (ldouble)nb) + ROUND * ry[k].slack)) {
            FZ_FAIL("%s: SOLVED with |Ax - b|[%d] = %g (tol_feas %g, |b| %g, info.pres %g)",
                    when, k, (double)ry[k].r, st->tol_feas, nb, info.pres);
        }
    }
    for (k = 0; k < d->m; ++k) {
        if (!(fabsl(rz[k].r) <= (ldouble)WIDE * st->tol_feas * (1 + (ldouble)nh) + ROUND * rz[k].slack)) {
            FZ_FAIL("%s: SOLVED with |Gx + s - h|[%d] = %g (tol_feas %g, |h| %g, info.pres %g)",
                    when, k, (double)rz[k].r, st->tol_feas, nh, info.pres);
        }
    }
    for (k = 0; k < d->n; ++k) {
        if (!(fabsl(rx[k].r) <= (ldouble)WIDE * st->tol_feas * (1 + (ldouble)nc) + ROUND * rx[k].slack)) {
            FZ_FAIL("%s: SOLVED with dual residual [%d] = %g (tol_feas %g, |c| %g, info.dres %g)",
                    when, k, (double)rx[k].r, st->tol_feas, nc, info.dres);
        }
    }
    if (!in_cone(d, s, WIDE * st->tol_feas * (1 + vmax(s, d->m)))
        || !in_cone(d, z, WIDE * st->tol_feas * (1 + vmax(z, d->m)))) {
        FZ_FAIL("%s: SOLVED with s or z outside the cones", when);
    }
    /* gap: pcost - dcost = x'Px + c'x + b'y + h'z */
    if (d->Pp) {
        acc px[MAXN];
        memset(px, 0, sizeof px);
        mul(&pb->P, Px, d->n, x, px, NULL, NULL, 1);
        for (k = 0; k < d->n; ++k) {
            addl(&xPx, (ldouble)x[k] * px[k].r);
            xPx.slack += fabsl((ldouble)x[k] * px[k].slack);
        }
    }
    for (k = 0; k < d->n; ++k) {
        add(&lin, c[k], x[k]);
    }
    pcost = 0.5 * xPx.r + lin.r;
    for (k = 0; k < d->p; ++k) {
        add(&lin, b[k], y[k]);
    }
    for (k = 0; k < d->m; ++k) {
        add(&lin, h[k], z[k]);
    }
    gap = xPx.r + lin.r;
    dcost = pcost - gap;
    gtol = fmaxl(st->tol_gap_abs, st->tol_gap_rel * fmaxl(1.0L, fminl(fabsl(pcost), fabsl(dcost))));
    if (!(fabsl(gap) <= WIDE * gtol + ROUND * (xPx.slack + lin.slack))) {
        FZ_FAIL("%s: SOLVED with duality gap %g (pcost %g, dcost %g; info gap %g)", when,
                (double)gap, (double)pcost, (double)dcost, info.gap_abs);
    }
}

/* A certificate of infeasibility, checked from the raw data: primal (y, z): A'y + G'z = 0,
 * z in K, b'y + h'z = -1; dual (x, s): Px = 0, Ax = 0, Gx + s = 0, s in K, c'x = -1 (the
 * header's normalization), each residual within WIDE x tol_infeas relative to the data and
 * the certificate's size (|A, G| |y, z|; |A, G| |x| + |s|; |P| |x|): scale-free, so a
 * certificate of data of 1e300 is judged as one of data of 1, and a wrong one (residuals of
 * the order of its terms) still fails. */
static void check_certificate(tscvx_workspace *ws, const problem *pb, tscvx_solve_status so,
                              const tscvx_float *Px, const tscvx_float *Ax, const tscvx_float *Gx,
                              const tscvx_float *c, const tscvx_float *b, const tscvx_float *h,
                              const char *when)
{
    const tscvx_data *d = &pb->d;
    double tol = WIDE * pb->st.tol_infeas;
    double x[MAXN], y[MAXP + 1], z[MAXM + 1], s[MAXM + 1];
    acc rx[MAXN], ry[MAXP + 1], rz[MAXM + 1], obj = {0, 0};
    const double nAG = fmax(d->Ap && d->p > 0 ? vmax(Ax, pb->A.nnz) : 0.0,
                            d->Gp && d->m > 0 ? vmax(Gx, pb->G.nnz) : 0.0);
    tscvx_int k;
    if (tscvx_get_solution(ws, x, y, z, s) != TSCVX_SETUP_OK) {
        FZ_FAIL("%s: a certificate but no solution", when);
    }
#ifdef FUZZ_TRACE
    dump(pb, Px, Ax, Gx, c, b, h, x, y, z, s);
#endif
    memset(rx, 0, sizeof rx), memset(ry, 0, sizeof ry), memset(rz, 0, sizeof rz);
    if (so == TSCVX_PRIMAL_INFEASIBLE) {
        tol *= fmax(1.0, nAG * fmax(vmax(y, d->p), vmax(z, d->m)));
        if (d->Ap && d->p > 0) {
            mul(&pb->A, Ax, d->n, x, ry, y, rx, 0); /* ry (from the NaN x) unused */
        }
        if (d->Gp && d->m > 0) {
            mul(&pb->G, Gx, d->n, x, rz, z, rx, 0);
        }
        for (k = 0; k < d->p; ++k) {
            add(&obj, b[k], y[k]);
        }
        for (k = 0; k < d->m; ++k) {
            add(&obj, h[k], z[k]);
        }
        for (k = 0; k < d->n; ++k) {
            if (!(fabsl(rx[k].r) <= tol + ROUND * rx[k].slack)) {
                FZ_FAIL("%s: PRIMAL_INFEASIBLE with (A'y + G'z)[%d] = %g", when, k,
                        (double)rx[k].r);
            }
        }
        if (!(fabsl(obj.r + 1.0L) <= 1e-6L + ROUND * obj.slack)
            || !in_cone(d, z, WIDE * pb->st.tol_infeas * (1 + vmax(z, d->m)))) {
            FZ_FAIL("%s: PRIMAL_INFEASIBLE with b'y + h'z = %g or z outside the cones", when,
                    (double)obj.r);
        }
        return;
    }
    {
        acc px[MAXN];
        double pmax = 0.0;
        const double tol_px = tol;
        tol *= fmax(1.0, nAG * vmax(x, d->n) + vmax(s, d->m));
        memset(px, 0, sizeof px);
        if (d->Pp) {
            mul(&pb->P, Px, d->n, x, px, NULL, NULL, 1);
            pmax = vmax(Px, pb->P.nnz);
        }
        if (d->Ap && d->p > 0) {
            mul(&pb->A, Ax, d->n, x, ry, NULL, NULL, 0);
        }
        if (d->Gp && d->m > 0) {
            mul(&pb->G, Gx, d->n, x, rz, NULL, NULL, 0);
        }
        for (k = 0; k < d->n; ++k) {
            add(&obj, c[k], x[k]);
            if (!(fabsl(px[k].r) <= fmax(tol_px, tol_px * pmax * vmax(x, d->n)) + ROUND * px[k].slack)) {
                FZ_FAIL("%s: DUAL_INFEASIBLE with (Px)[%d] = %g", when, k, (double)px[k].r);
            }
        }
        for (k = 0; k < d->p; ++k) {
            if (!(fabsl(ry[k].r) <= tol + ROUND * ry[k].slack)) {
                FZ_FAIL("%s: DUAL_INFEASIBLE with (Ax)[%d] = %g", when, k, (double)ry[k].r);
            }
        }
        for (k = 0; k < d->m; ++k) {
            add(&rz[k], 1.0, s[k]);
            if (!(fabsl(rz[k].r) <= tol + ROUND * rz[k].slack)) {
                FZ_FAIL("%s: DUAL_INFEASIBLE with (Gx + s)[%d] = %g", when, k, (double)rz[k].r);
            }
        }
        if (!(fabsl(obj.r + 1.0L) <= 1e-6L + ROUND * obj.slack)
            || !in_cone(d, s, WIDE * pb->st.tol_infeas * (1 + vmax(s, d->m)))) {
            FZ_FAIL("%s: DUAL_INFEASIBLE with c'x = %g or s outside the cones", when,
                    (double)obj.r);
        }
    }
}

static void after_solve(tscvx_workspace *ws, const problem *pb, tscvx_solve_status s, int updated,
                        size_t narena)
{
    tscvx_info info;
    const char *m = tscvx_solve_status_message(s);
#ifdef FUZZ_TRACE
    fprintf(stderr, "solve%s: %s\n", updated ? " after update" : "", m);
#endif
    if ((unsigned)s >= (unsigned)TSCVX_NSTATUS || !m || !m[0]) {
        FZ_FAIL("solve: undocumented status %d or no message", (int)s);
    }
    if (tscvx_get_info(ws, &info) != TSCVX_SETUP_OK) {
        FZ_FAIL("get_info after a solve refused");
    }
    if (info.status != s) {
        FZ_FAIL("info.status %d, solve returned %d", (int)info.status, (int)s);
    }
    if (info.arena_high_water > narena || info.arena_used > narena) {
        FZ_FAIL("arena high water %zu / used %zu beyond the %zu bytes asked",
                info.arena_high_water, info.arena_used, narena);
    }
    if (s == TSCVX_SOLVED || s == TSCVX_PRIMAL_INFEASIBLE || s == TSCVX_DUAL_INFEASIBLE) {
        const tscvx_data *d = &pb->d;
        const char *when = updated ? "solve after update" : "first solve";
        const tscvx_float *Px = updated ? (d->Pp ? pb->P.x2 : NULL) : d->Px;
        const tscvx_float *Ax = updated ? (d->Ap ? pb->A.x2 : NULL) : d->Ax;
        const tscvx_float *Gx = updated ? (d->Gp ? pb->G.x2 : NULL) : d->Gx;
        const tscvx_float *c = updated ? pb->c2 : d->c, *b = updated ? pb->b2 : d->b;
        const tscvx_float *h = updated ? pb->h2 : d->h;
        if (s == TSCVX_SOLVED) {
            check_solved(ws, pb, Px, Ax, Gx, c, b, h, when);
        } else {
            check_certificate(ws, pb, s, Px, Ax, Gx, c, b, h, when);
        }
    }
}

static void run(fz_reader *r, problem *pb)
{
    const tscvx_data *d = &pb->d;
    char msg[TSCVX_MESSAGE_LEN];
    size_t nscratch = 0, narena = 0;
    void *scratch, *arena;
    tscvx_workspace *ws = NULL;
    tscvx_setup_status s_data, s_set, s;
    tscvx_solve_status so;
    unsigned f;

    s_data = tscvx_check_data(d, msg);
    check_setup_status(s_data, "check_data");
    if (s_data != TSCVX_SETUP_OK && !msg[0]) {
        FZ_FAIL("check_data refused (%d) without a message", (int)s_data);
    }
    s_set = tscvx_check_settings(&pb->st, msg);
    check_setup_status(s_set, "check_settings");
    if (s_set != TSCVX_SETUP_OK && !msg[0]) {
        FZ_FAIL("check_settings refused without a message");
    }
    s = tscvx_scratch_size(d, &pb->st, &nscratch);
    check_setup_status(s, "scratch_size");
#ifdef FUZZ_TRACE
    fprintf(stderr, "n %d p %d m %d: check_data %d (%s), scratch_size %d\n", (int)d->n,
            (int)d->p, (int)d->m, (int)s_data, msg, (int)s);
#endif
    if (s != TSCVX_SETUP_OK) {
        if (s_data == TSCVX_SETUP_OK && s_set == TSCVX_SETUP_OK && s != TSCVX_SETUP_TOO_LARGE) {
            FZ_FAIL("scratch_size refused (%d) what check_data and check_settings accept",
                    (int)s);
        }
        return;
    }
    if (s_data != TSCVX_SETUP_OK && s_data != TSCVX_SETUP_P_NOT_PSD) {
        FZ_FAIL("scratch_size accepted what check_data refuses (%d)", (int)s_data);
    }
    if (s_set != TSCVX_SETUP_OK) {
        FZ_FAIL("scratch_size accepted what check_settings refuses");
    }
    scratch = xcalloc(nscratch, 1);
    s = tscvx_workspace_size(d, &pb->st, scratch, nscratch, &narena);
    check_setup_status(s, "workspace_size");
    free(scratch);
    if (s != TSCVX_SETUP_OK) {
        return;
    }
    arena = malloc(narena ? narena : 1);
    if (!arena) {
        abort();
    }
    s = tscvx_setup(&ws, arena, narena, d, &pb->st);
    check_setup_status(s, "setup");
    if (s != TSCVX_SETUP_OK) {
        if (s != TSCVX_SETUP_P_NOT_PSD && s != TSCVX_SETUP_NOT_BANDED && s != TSCVX_SETUP_TOO_LARGE) {
            FZ_FAIL("setup refused (%d) what workspace_size sized", (int)s);
        }
        free(arena);
        return;
    }
    so = tscvx_solve(ws);
    after_solve(ws, pb, so, 0, narena);

    f = fz_u8(r);
    s = tscvx_update_data(ws, d->Pp ? pb->P.x2 : NULL, pb->c2, d->Ap ? pb->A.x2 : NULL, pb->b2,
                          d->Gp ? pb->G.x2 : NULL, pb->h2);
    check_setup_status(s, "update_data");
    if (f & 1u) { /* warm start from the last answer, or from the bytes */
        double x[MAXN], y[MAXP + 1], z[MAXM + 1], sv[MAXM + 1];
        tscvx_int k;
        if (!(f & 2u) || tscvx_get_solution(ws, x, y, z, sv) != TSCVX_SETUP_OK) {
            for (k = 0; k < d->n; ++k) {
                x[k] = fz_double(r);
            }
            for (k = 0; k < MAXP + 1; ++k) {
                y[k] = fz_double(r);
            }
            for (k = 0; k < MAXM + 1; ++k) {
                z[k] = fz_double(r), sv[k] = fz_double(r);
            }
        }
#ifdef FUZZ_TRACE
        fprintf(stderr, "warm start (%s):", f & 2u ? "the last answer" : "from the input");
        for (k = 0; k < d->n; ++k) {
            fprintf(stderr, " x %.17g", x[k]);
        }
        for (k = 0; k < MAXP + 1; ++k) {
            fprintf(stderr, " y %.17g", y[k]);
        }
        for (k = 0; k < MAXM + 1; ++k) {
            fprintf(stderr, " z %.17g s %.17g", z[k], sv[k]);
        }
        fprintf(stderr, "\n");
#endif
        check_setup_status(tscvx_warm_start(ws, x, y, z, sv), "warm_start");
    }
    so = tscvx_solve(ws);
    if (s != TSCVX_SETUP_OK && so != TSCVX_INVALID_INPUT) {
        FZ_FAIL("solve after a refused update (%d) returned %d", (int)s, (int)so);
    }
    if (s == TSCVX_SETUP_OK) {
        after_solve(ws, pb, so, 1, narena);
    }
    check_setup_status(tscvx_cleanup(ws), "cleanup");
    if (tscvx_solve(ws) != TSCVX_INVALID_INPUT) {
        FZ_FAIL("solve after cleanup not refused");
    }
    free(arena);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fz_reader r = {data, size, 0};
    problem pb;
    build(&r, &pb);
    run(&r, &pb);
    free_csc(&pb.P);
    free_csc(&pb.A);
    free_csc(&pb.G);
    free(pb.c), free(pb.b), free(pb.h), free(pb.c2), free(pb.b2), free(pb.h2), free(pb.q);
    return 0;
}
