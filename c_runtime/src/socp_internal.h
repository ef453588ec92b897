/* Private definitions of the SOCP solver: arena, cones, KKT system, workspace. */
#ifndef TSCVX_SOCP_INTERNAL_H
#define TSCVX_SOCP_INTERNAL_H

#include <math.h>
#include <stddef.h>
#include <stdint.h>

#include "tscvx_socp.h"

/* ---- arena: bump allocator over the caller's memory -------------------------------------- */

typedef struct {
    unsigned char *base; /* caller memory, or NULL when only counting bytes */
    size_t cap;          /* bytes available */
    size_t top;          /* bytes in use */
    size_t high;         /* most bytes ever in use */
    int overflow;        /* set when a request did not fit */
    int too_large;       /* set when a request would take the count past SIZE_MAX / 2 bytes:
                            not counted (top, high unchanged), so no size may be reported */
} tscvx_arena;

/* 16-byte aligned block of `count * size` bytes; NULL on overflow or in counting mode. A count
 * past SIZE_MAX / 2 (2 GiB on the RAD750's 32-bit size_t) sets overflow and too_large. */
void *tscvx_arena_alloc(tscvx_arena *a, size_t count, size_t size);

/* ptr = `count` elements of `type` from arena a (tscvx_arena_alloc: NULL on overflow or in
 * counting mode); set-up's array claims, in api.c and the KKT methods. */
#define TSCVX_CLAIM(a, ptr, count, type) \
    ((ptr) = (type *)tscvx_arena_alloc((a), (size_t)(count), sizeof(type)))

/* A CSC matrix in the arena (values x[k] of entry k). */
typedef struct {
    tscvx_int nrow, ncol, nnz;
    tscvx_int *p; /* ncol+1 */
    tscvx_int *i; /* nnz */
    tscvx_float *x; /* nnz */
} tscvx_csc;

/* ---- cones: K = R_+^l x Q^{q_1} x ... ---------------------------------------------------- */

typedef struct {
    tscvx_int l;          /* nonnegative orthant dimension */
    tscvx_int nsoc;       /* number of second-order cones */
    const tscvx_int *q;   /* nsoc cone dimensions (in the arena) */
    const tscvx_int *off; /* nsoc row offsets of each SOC within the m cone rows */
    tscvx_int m;          /* l + sum(q) */
    tscvx_int degree;     /* l + nsoc, the barrier degree nu */
} tscvx_cones;

/* Nesterov-Todd scaling point of K, with W symmetric: lambda = W z = W^{-1} s. */
typedef struct {
    tscvx_float *w;   /* m: orthant rows sqrt(s_i/z_i); SOC rows the unit-det point wbar */
    tscvx_float *eta; /* nsoc: SOC scale eta = (det s / det z)^{1/4} */
} tscvx_nt;

/* u o v (Jordan product) */
void tscvx_cone_prod(const tscvx_cones *K, const tscvx_float *u, const tscvx_float *v,
                     tscvx_float *out);
/* w = u \ v, i.e. u o w = v (u in int K) */
void tscvx_cone_div(const tscvx_cones *K, const tscvx_float *u, const tscvx_float *v,
                    tscvx_float *out);
/* NT scaling of (s, z) in int K x int K and lambda = W z. Returns 0, or -1 if s or z left K. */
int tscvx_nt_scaling(const tscvx_cones *K, const tscvx_float *s, const tscvx_float *z,
                     tscvx_nt *W, tscvx_float *lambda);
/* out = W v, or W^{-1} v when inverse != 0 */
void tscvx_nt_apply(const tscvx_cones *K, const tscvx_nt *W, int inverse, const tscvx_float *v,
                    tscvx_float *out);
/* out = W (W v), one pass over the cones; work (m) receives W v only on the SOC rows */
void tscvx_nt_apply2(const tscvx_cones *K, const tscvx_nt *W, const tscvx_float *v,
                     tscvx_float *work, tscvx_float *out);
/* out = W (u \ v), one pass; work (m, may be v) receives u \ v only on the SOC rows */
void tscvx_nt_div_apply(const tscvx_cones *K, const tscvx_nt *W, const tscvx_float *u,
                        const tscvx_float *v, tscvx_float *work, tscvx_float *out);
/* Largest alpha <= alpha_max with u + alpha du in K (u in int K). */
tscvx_float tscvx_cone_max_step(const tscvx_cones *K, const tscvx_float *u,
                                const tscvx_float *du, tscvx_float alpha_max);
/* Smallest t with u + t e in K, e the identity (t < 0 when u is interior). */
tscvx_float tscvx_cone_shift_needed(const tscvx_cones *K, const tscvx_float *u);
/* u += t e */
void tscvx_cone_add_identity(const tscvx_cones *K, tscvx_float *u, tscvx_float t);
/* dst = u on each cone (orthant row or SOC) where u is strictly inside it; elsewhere dst is
 * left as it is. */
void tscvx_cone_copy_interior(const tscvx_cones *K, const tscvx_float *u, tscvx_float *dst);
/* Centres a warm point: s += a e and z += b e on each cone, so that each cone's s'z grows by
 * mu/4 to 5 mu/4 (a, b in cones.c). */
void tscvx_cone_center_pair(const tscvx_cones *K, tscvx_float *s, tscvx_float *z,
                            tscvx_float mu);

/* ---- KKT system -------------------------------------------------------------------------- */
/*
 *  K = [ P + d I    A'      G'              ]   rows: x (n), y (p), z (m), extra (2 per
 *      [ A         -d I     0               ]         expanded SOC: v-row then u-row)
 *      [ G          0      -(W'W) - d I     ]
 *  stored as the upper triangle of the AMD-permuted matrix (CSC) so that LDL needs no
 *  permutation; the maps below send problem data and cone-block entries to their slots.
 */
typedef struct tscvx_kkt tscvx_kkt;

/* Row blocks of the KKT system; the static regularization is +d on x, -d on y and z, none on
 * the expansion rows. */
enum { KKT_ROW_X = 0, KKT_ROW_Y = 1, KKT_ROW_Z = 2, KKT_ROW_EXP = 3 };

/* Backend seam: the only door to the factorization. Setup calls symbolic (sizes), then
 * alloc (claims the factor memory and finishes the analysis); each IPM iteration numeric,
 * then solve. */
typedef struct {
    const char *name;
    /* analysis of kkt->Kp/Ki in `tmp` (>= 5 dim + 2 free ints, clobbered): writes the factor
     * sizes into kkt; returns nnz(L) or -1 */
    long (*symbolic)(tscvx_kkt *kkt, tscvx_int *tmp);
    /* claims the factor arrays from `a` (only counts while a->base is NULL or the arena
     * overflowed; else also finishes the analysis, temporary memory released); 0 or -1 */
    int (*alloc)(tscvx_kkt *kkt, tscvx_arena *a);
    /* numeric factorization of kkt->Kx with the inertia check; returns 0 or -1 */
    int (*numeric)(tscvx_kkt *kkt);
    /* x := K^{-1} x in permuted coordinates */
    void (*solve)(tscvx_kkt *kkt, tscvx_float *x);
} tscvx_backend;

struct tscvx_kkt {
    const tscvx_backend *backend;
    tscvx_int dim;        /* n + p + m + 2 * nexp */
    tscvx_int nnz;        /* entries of the permuted upper triangle */
    tscvx_int nexp;       /* SOCs with a sparse expansion */
    tscvx_int *Kp;        /* dim+1 column pointers (permuted upper triangle) */
    tscvx_int *Ki;        /* nnz row indices */
    tscvx_float *Kx;      /* nnz values */
    signed char *rowblk;  /* dim (permuted): block of each row, KKT_ROW_X/Y/Z/EXP */
    tscvx_int *pinv;      /* dim: inverse of perm */
    tscvx_int *mapP;      /* nnz(P): slot of each P entry */
    tscvx_int *mapA;      /* nnz(A): slot of each A entry */
    tscvx_int *mapG;      /* nnz(G): slot of each G entry */
    tscvx_int *mapDiag;   /* n + p: diagonal slots of the x and y blocks */
    tscvx_int *mapCone;   /* ncone: slots of the cone block, in the order of kkt_cone_values */
    tscvx_int ncone;      /* number of cone-block entries */
    tscvx_int *expanded;  /* nsoc: index of the expansion (0..nexp-1), or -1 for dense */
    tscvx_int lnz;        /* nnz(L) */
    tscvx_int npos;       /* expected positive pivots: n + nexp (inertia check) */
    tscvx_float delta;    /* static regularization in the stored values */
    tscvx_float kmax;     /* bound on the largest |entry| of the factored matrix (>= 1) */
    tscvx_float kmax_data; /* largest |entry| of the data part (P + d I, A, G, -d I) */
    tscvx_float *D;       /* dim: the pivots */
    /* SuiteSparse LDL backend: LDL' factors and work arrays (dim or nnz(L)) */
    tscvx_int *Lp, *Parent, *Lnz, *Flag, *Li;
    tscvx_int *Pattern;   /* dim: shares memory with sol (factorization vs. solves); the
                             static backend's column fill pointers */
    tscvx_float *Lx, *Y;
    /* static-pattern LDL' backend (ldlstatic.c): LDL's Lp, Li, Lx, D, Y and the pattern of
     * each row of L in ldl_numeric's order (Rp dim+1, Rj nnz(L)) */
    tscvx_int *Rp, *Rj;
    /* solve and refinement work (dim each, permuted); res is the backend's */
    tscvx_float *sol, *res;
};

extern const tscvx_backend tscvx_backend_ldl;
extern const tscvx_backend tscvx_backend_static;

/* Solve K [dx; dy; dz] = [rx; ry; rz] with iterative refinement; vectors in original order.
 * Returns the number of refinement steps, or -1 when the residual stays non-finite. */
int tscvx_kkt_solve(tscvx_kkt *kkt, tscvx_int n, tscvx_int p, tscvx_int m,
                    const tscvx_float *rx, const tscvx_float *ry, const tscvx_float *rz,
                    tscvx_float *dx, tscvx_float *dy, tscvx_float *dz, tscvx_int refine_iters);

/* Write the cone block -(W'W) - d I (and expansions) into the KKT values; sets kmax. */
void tscvx_kkt_cone_values(tscvx_kkt *kkt, const tscvx_cones *K, const tscvx_nt *W,
                           tscvx_float delta);

/* ---- banded KKT method (banded.c) ----------------------------------------------------------
 *
 * For problems with stage structure (optimal control: every cone and every P entry couples a
 * few variables of one stage, the equalities couple neighbouring stages): the KKT system
 *   [P + d I   A'    G'  ] [dx]   [rx]
 *   [A        -d I   0   ] [dy] = [ry]
 *   [G         0   -W'W  ] [dz]   [rz]
 * is reduced in three exact steps, each a small dense computation:
 *   1. cone rows, NT-scaled (CVXOPT's condensed solver): W dz = W^-1 (G dx - rz),
 *      H = P + d I + (W^-1 G)'(W^-1 G). H is block diagonal over the variable groups
 *      (connected components of "shares a cone or a P entry");
 *   2. groups:     dx_g = H_g^-1 (rx_g + G_g' W^-2 rz - A_g' dy),  H_g = L_g L_g' (L_g' by
 *      Givens rotations of the rows of W^-1 G_g: H_g itself is never formed);
 *   3. equalities: Y dy = ...,  Y = d I + sum_g A_g H_g^-1 A_g' = d I + sum_g C_g' C_g,
 *      C_g = L_g^-1 A_g', factored by a profile (envelope) Cholesky in a reverse Cuthill-McKee
 *      order of the equality rows: the stages' block-tridiagonal pattern, with dense kernels.
 * Groups coupled to very many rows (a free final time, say) would fill Y; they are the border,
 * eliminated last through the Schur complement S = H_B + A_B' Y^-1 A_B (nb x nb, dense).
 * Setup decides whether a problem has this structure (TSCVX_KKT_AUTO falls back to the sparse
 * LDL' method otherwise). */

#define TSCVX_BANDED_GROUP_MAX 32   /* largest variable group (dense H_g block) */
#define TSCVX_BANDED_BORDER_MAX 8   /* most border variables */
#define TSCVX_BANDED_ENV_AVG 64     /* envelope of Y at most this many entries per row on average */
#define TSCVX_BANDED_REG_SCALE 1e-4 /* its static regularization, relative to the IPM's delta */

typedef struct {
    /* variable groups */
    tscvx_int ngroup;
    tscvx_int *gp;       /* ngroup+1: group g holds gvar[gp[g] .. gp[g+1]) */
    tscvx_int *gvar;     /* n: the variables by group; within a group those without
                            equality entries first (ga0 of them), each part ascending */
    tscvx_int *loc;      /* n: position of each variable within its group */
    signed char *border; /* ngroup: 1 for a border group */
    tscvx_int *hp;       /* ngroup+1: offset of group g's s_g x s_g blocks in H and PF */
    tscvx_float *H;      /* L_g, the factor of H_g = L_g L_g' (column-major lower) */
    tscvx_int *mapP;     /* nnz(P): slot of each P entry in a group block (lower part) */
    signed char *hasP;   /* ngroup: the group has P entries */
    tscvx_float *PF;     /* P_gg's factor (column-major lower), when P is present */
    tscvx_int *gcp, *gcone; /* ngroup+1, l+nsoc: the cones of group g: gcone[gcp[g] ..] */
    /* G by rows: row i's entries are Gr_k[Grp[i] .. Grp[i+1]) (index into G.x) with the
     * column's position within its group Gr_loc[.]; cgroup: the group of each cone (orthant
     * rows first, then the SOCs), -1 for a cone without entries */
    tscvx_int *Grp, *Gr_k, *Gr_loc, *cgroup;
    /* equality rows of each non-border group: rrow[rp[g] .. rp[g+1]), band positions,
     * ascending; posA[k]: position of A entry k's row in its group's list (-1: border) */
    tscvx_int *rp, *rrow, *posA;
    tscvx_int *cp;       /* ngroup+1: offset of C_g' (|R_g| x s_g, row-major) */
    tscvx_float *CT;     /* C_g' = (L_g^-1 A_g')' */
    /* Y in profile form, band order: row i holds columns yfirst[i] .. i at Y[yp[i] ..] */
    tscvx_int *perm;     /* p: band position -> equality row */
    tscvx_int *iperm;    /* p: equality row -> band position */
    tscvx_int *yfirst;   /* p */
    tscvx_int *yp;       /* p+1 */
    tscvx_float *Y;      /* yp[p]: Y, then its Cholesky factor */
    tscvx_float *Ydinv;  /* p: 1 / diagonal of Y's factor */
    tscvx_float *Hdinv;  /* n: 1 / diagonal of each L_g, in group order */
    /* border */
    tscvx_int nb;                          /* border variables */
    tscvx_int bvar[TSCVX_BANDED_BORDER_MAX];   /* the border variables, group by group */
    tscvx_int bgroup[TSCVX_BANDED_BORDER_MAX]; /* the group of each */
    tscvx_float *V;      /* p x nb, column-major, band order: Y^-1 A_B */
    tscvx_float S[TSCVX_BANDED_BORDER_MAX * TSCVX_BANDED_BORDER_MAX]; /* H_B + A_B' V, factored */
    tscvx_int *bp;       /* nsoc+1: offset of SOC k's block W_k^-1 G_k (q x s_g, row-major) */
    tscvx_float *B;      /* those blocks, from the last factorization */
    tscvx_int *ga0;      /* ngroup: how many of the group's variables have no equality entry */
    /* sizes of the value arrays (set by the analysis) */
    size_t nH, nCT, nY;
    tscvx_float kmax_data; /* largest |entry| of P, A, G and d */
    tscvx_float kmax;    /* ... and of W (the scaled cone rows; refinement floor) */
    /* work: xg (n, group order), yb (p, band order), t (m) = W^-1 rz; refinement:
     * residuals (n, p, m) and corrections (n, p, m, m: W ez) */
    tscvx_float *xg, *yb, *t, *res_x, *res_y, *res_z, *ex, *ey, *ez, *ewz;
} tscvx_banded;

/* Analysis at setup: claims the banded method's memory from `a` (temporary memory above it,
 * released). Returns 1 if the problem has the structure (memory claimed; with a->base NULL
 * or an overflowed arena only counted), 0 if not (nothing kept), -1 when the memory for the
 * analysis itself is short.
 * `ws` holds the data (patterns, values) and cones. */
int tscvx_banded_analyse(tscvx_workspace *ws, tscvx_arena *a);

/* ---- the KKT method seam ----------------------------------------------------------------- */

/* How the IPM solves its Newton systems: the sparse quasi-definite LDL' of the whole KKT
 * matrix (kkt.c, behind the factorization backend above) or the banded reduction. */
typedef struct {
    const char *name;
    tscvx_int id;                         /* TSCVX_KKT_STATIC, _LDL or _BANDED */
    /* the data or ws->delta changed; 0, or -1 when P is found indefinite (banded: the
     * factors of its diagonal blocks) */
    int (*load)(tscvx_workspace *ws);
    /* setup and data updates: 0 when P is positive semidefinite, -1 when a factorization of
     * P shows it indefinite (the full test behind the cheap necessary one in api.c) */
    int (*check_p)(tscvx_workspace *ws);
    /* the NT scaling ws->W changed: factor with regularization ws->delta; 0 or -1 */
    int (*factor)(tscvx_workspace *ws);
    /* solve the unregularized system for (rx, ry, rz) (original order) by the factored one
     * with up to `refine` refinement steps, into (dx, dy, dz) and wdz = W dz (the IPM's ds
     * needs W dz; computed as the method can best); outputs may not alias inputs; returns
     * the steps taken or -1 when the residual is not finite */
    int (*solve)(tscvx_workspace *ws, const tscvx_float *rx, const tscvx_float *ry,
                 const tscvx_float *rz, tscvx_float *dx, tscvx_float *dy, tscvx_float *dz,
                 tscvx_float *wdz, tscvx_int refine);
} tscvx_kkt_method;

extern const tscvx_kkt_method tscvx_method_sparse;
extern const tscvx_kkt_method tscvx_method_banded;

/* Iterative refinement stops at |r| <= REFINE_TOL (1 + |rhs|), at the rounding floor
 * |r| <= REFINE_FLOOR |K| |x| (backward stable: nothing left to gain), or when a step gains
 * less than 2x. */
#define TSCVX_REFINE_TOL 1e-10
#define TSCVX_REFINE_FLOOR 1e-15
#define TSCVX_REFINE_RATIO 0.5

/* Sparse products (ipm.c): yt += M' u and y += M x in one pass; y = P x (P upper part). */
void tscvx_spmv_both(const tscvx_csc *M, const tscvx_float *u, tscvx_float *yt,
                     const tscvx_float *x, tscvx_float *y);
void tscvx_spmv_sym(const tscvx_csc *P, const tscvx_float *x, tscvx_float *y);

/* ---- workspace --------------------------------------------------------------------------- */

/* Set as the last step of a successful setup and cleared by tscvx_cleanup: every public call
 * checks it first, so a workspace whose arena was reused or overwritten is refused instead of
 * having its (garbage) pointers followed. */
#define TSCVX_WS_MAGIC 0x54534F43u /* "TSOC" */

struct tscvx_workspace {
    uint32_t magic; /* TSCVX_WS_MAGIC while set up */
    /* set-up checksum (wssum.c): head_sum of the fixed fields of this struct (settings,
     * sizes, counts, pointers), body_sum of the index arrays set-up fixed (patterns, cones,
     * the KKT method's maps, ordering and symbolic factor); written by setup (head_sum again
     * by tscvx_update_settings) and checked by every call that follows them */
    uint64_t head_sum, body_sum;
    tscvx_settings st;
    tscvx_int n, p, m;
    tscvx_cones K;
    /* equilibrated data: Ps = cs D P D, cs = cost scale, As = EA A D, Gs = EG G D */
    tscvx_csc P, A, G;
    tscvx_float *c, *b, *h; /* n, p, m: cs D c, EA b, EG h */
    tscvx_float *D, *EA, *EG; /* n, p, m: Ruiz scalings (EG constant on each SOC) */
    tscvx_float cs;           /* cost scaling */
    tscvx_float norm_b, norm_h, norm_c, norm_P; /* inf-norms of the original b, h, c, P */
    tscvx_float norm_A, norm_G; /* ... and of the original A and G (certificate tests) */
    const tscvx_kkt_method *method; /* how the Newton systems are solved */
    tscvx_kkt kkt;                  /* the sparse method's KKT matrix and factor */
    tscvx_banded bd;                /* the banded method */
    tscvx_nt W;
    /* iterates (scaled space, homogeneous): x n, y p, z m, s m, tau, kappa */
    tscvx_float *x, *y, *z, *s, tau, kappa;
    tscvx_float *lambda; /* m: scaled variable lambda = W z */
    /* residuals: rx n, ry p, rz m, rtau; Px n */
    tscvx_float *rx, *ry, *rz, rtau, *Px;
    /* Newton directions: constant part (x1, y1, z1), varying part (x2, y2, z2), step */
    tscvx_float *x1, *y1, *z1, *wz1; /* wz1 = W z1 */
    tscvx_float *dx, *dy, *dz, *ds, dtau, dkappa; /* (x2, y2, z2) are solved into (dx, dy, dz) */
    tscvx_float *wdz;    /* m: W dz */
    tscvx_float *e;      /* m: the direction's error in the primal row */
    tscvx_float *cx, *cy, *cz, *cwz; /* correction of the direction (n, p, m, m: W cz) */
    tscvx_float tau_den; /* denominator of the tau row (fixed per factorization) */
    tscvx_float delta;   /* current static regularization */
    tscvx_int refine_now; /* refinement steps allowed in this iteration */
    tscvx_float *wm, *wm2;       /* m: work vectors in the cone space */
    tscvx_float *wn;             /* n: work vector */
    tscvx_float *wp;             /* p: work vector (right-hand sides of the y rows) */
    /* best iterate so far; between solves, the warm-start point (original units) */
    tscvx_float *bx, *by, *bz, *bs, btau, bkappa;
    tscvx_float bfeas, bgap; /* its max(pres, dres) and gap_abs (ipm.c, update_best) */
    tscvx_int best_iter;
    int warm; /* bx, by, bz, bs hold a point from tscvx_warm_start for the next solve */
    /* results (original units) */
    tscvx_info info;
    tscvx_iter_log *log; /* max_iter + 1 rows */
    tscvx_int log_cap;
    int ready;     /* data valid and set up */
    int p_refused; /* the stored P failed the factorization test (tscvx_update_data) */
    int damaged_during; /* TSCVX_DAMAGED_IN_SOLVE or _IN_UPDATE: the end check of the last
                           tscvx_solve or tscvx_update_data found a checksum broken; 0: neither
                           (for tscvx_check_workspace's message; outside the sums) */
    size_t arena_used, arena_high;
};

enum { TSCVX_DAMAGED_IN_SOLVE = 1, TSCVX_DAMAGED_IN_UPDATE = 2 }; /* damaged_during */

/* The set-up checksum (wssum.c): head over the struct's fixed fields, body over the index
 * arrays (lengths and pointers from the head: check the head first). */
uint64_t tscvx_ws_head_sum(const tscvx_workspace *ws);
uint64_t tscvx_ws_body_sum(const tscvx_workspace *ws);

/* Ruiz equilibration in place (setup), and again with updated numbers (NULL = unchanged). */
void tscvx_equilibrate(tscvx_workspace *ws);
void tscvx_update_equilibrate(tscvx_workspace *ws, const tscvx_float *Px, const tscvx_float *c,
                              const tscvx_float *Ax, const tscvx_float *b,
                              const tscvx_float *Gx, const tscvx_float *h);

/* Solution in original units (certificates normalized), from the final iterate. */
void tscvx_unscale_solution(const tscvx_workspace *ws, tscvx_float *x, tscvx_float *y,
                            tscvx_float *z, tscvx_float *s);

/* The interior-point loop. */
tscvx_solve_status tscvx_ipm(tscvx_workspace *ws);

/* Temporary ints of tscvx_kkt_build, and the build itself (AMD ordering, permuted pattern,
 * maps, symbolic factorization; returns nnz(L) or -1). */
size_t tscvx_kkt_temp_ints(tscvx_int dim, tscvx_int nnz);
long tscvx_kkt_build(tscvx_workspace *ws, tscvx_int *tmp);

/* Fill the static (data) part of the KKT values from the scaled data; cone block zero. */
void tscvx_kkt_data_values(tscvx_workspace *ws, tscvx_float delta);

/* max(a, b) for a that is never NaN (a running maximum): b when b > a, so a NaN b is
 * skipped as fmax skips it, without fmax's library call in the loops. */
static inline tscvx_float tscvx_max(tscvx_float a, tscvx_float b) { return b > a ? b : a; }

/* max(r, |v|_inf) */
static inline tscvx_float tscvx_max_abs(const tscvx_float *v, tscvx_int n, tscvx_float r) {
    for (tscvx_int i = 0; i < n; i++) r = tscvx_max(r, fabs(v[i]));
    return r;
}

/* u'v, two terms per pass into one sum: half the loop overhead on the small cones, the same
 * rounding as one term per pass */
static inline tscvx_float tscvx_dot(const tscvx_float *u, const tscvx_float *v, tscvx_int n) {
    tscvx_float d = 0.0;
    tscvx_int i = 0;
    for (; i + 2 <= n; i += 2) {
        d += u[i] * v[i];
        d += u[i + 1] * v[i + 1];
    }
    if (i < n) d += u[i] * v[i];
    return d;
}

#endif /* TSCVX_SOCP_INTERNAL_H */
