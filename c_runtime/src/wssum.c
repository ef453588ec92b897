/* The workspace's set-up checksum: two 64-bit sums of what tscvx_setup fixed and later calls
 * index or loop by, so that a bit flipped there (a single-event upset with the mark intact)
 * is refused instead of followed (api.c checks them; socp_internal.h lists what each covers).
 *
 *   head: the workspace struct's fixed fields: the settings, the sizes and counts, and every
 *         pointer into the arena (a few hundred bytes);
 *   body: the index arrays: the patterns of P, A and G, the cone sizes and offsets, and the
 *         chosen KKT method's maps, ordering and symbolic factor (sparse: the permuted KKT
 *         pattern, pinv, the data and cone maps, the row blocks, L's pattern and the row
 *         patterns or elimination tree; banded: groups, cones by group, G by rows, row
 *         lists, the band order and profile, offsets).
 * The head is checked first: the body's lengths and pointers are taken from it, so checking
 * never reads out of bounds. Numbers that change per update, solve or iteration (values,
 * iterates, scalings, factors, work) are not covered.
 *
 * The hash works a 64-bit word at a time: h = rotl(h ^ w, 29) * FNV prime (tscvx_wordsum of
 * tscvx_fnv1a.h, which the guidance workspace's checksum shares). Each step is a bijection
 * of h for a given word and of the word for a given h, so any change confined to one word
 * (any single bit flip, any burst within 8 bytes) changes the sum for certain; the rotation
 * carries a change in a word's high bits down, where the product spreads it (plain
 * word-wise FNV-1a would let two flips of bit 63 cancel). About 4 host instructions per 8
 * bytes, where the bytewise FNV-1a takes 4 per byte.
 */
#include <string.h>

#include "socp_internal.h"
#include "tscvx_fnv1a.h"

#define SUM_START TSCVX_FNV1A_START /* FNV-1a's offset basis */

static inline uint64_t mix(uint64_t h, uint64_t w) { return tscvx_wordmix(h, w); }

static inline uint64_t mix_ptr(uint64_t h, const void *p) { return mix(h, (uint64_t)(uintptr_t)p); }

static inline uint64_t mix_int(uint64_t h, tscvx_int v) { return mix(h, (uint64_t)(int64_t)v); }

static inline uint64_t mix_float(uint64_t h, tscvx_float v) {
    uint64_t w;
    memcpy(&w, &v, sizeof w);
    return mix(h, w);
}

/* `bytes` bytes at p, 8 at a time, the last few zero-padded to a word, then the length
 * (nothing beyond them is read). p may be NULL when bytes is 0. */
static uint64_t mix_bytes(uint64_t h, const void *p, size_t bytes) {
    return tscvx_wordsum(h, p, bytes);
}

/* One array of the body: `bytes` bytes at p. */
typedef struct {
    const void *p;
    size_t bytes;
} span;

/* The most arrays a body has: 8 of the problem, 16 of the sparse method, 23 of the banded */
#define MAX_SPANS 32

typedef struct {
    span s[MAX_SPANS];
    int n;
} span_list;

/* len ints, or bytes (len < 0 counts as 0: a damaged length never gets here, the head is
 * checked first) */
static void add_ints(span_list *L, const tscvx_int *v, tscvx_int len) {
    const span sp = {v, len > 0 ? (size_t)len * sizeof(tscvx_int) : 0};
    if (L->n < MAX_SPANS) L->s[L->n++] = sp;
}

static void add_chars(span_list *L, const signed char *v, tscvx_int len) {
    const span sp = {v, len > 0 ? (size_t)len : 0};
    if (L->n < MAX_SPANS) L->s[L->n++] = sp;
}

static uint64_t head_settings(uint64_t h, const tscvx_settings *st) {
    h = mix_int(h, st->max_iter);
    const tscvx_float f[] = {st->tol_gap_abs,       st->tol_gap_rel,       st->tol_feas,
                             st->tol_infeas,        st->tol_gap_abs_inacc, st->tol_gap_rel_inacc,
                             st->tol_feas_inacc,    st->step_fraction,     st->static_reg};
    for (size_t k = 0; k < sizeof f / sizeof f[0]; k++) h = mix_float(h, f[k]);
    h = mix_int(h, st->refine_iters);
    h = mix_int(h, st->ruiz_iters);
    h = mix_int(h, st->soc_dense_max);
    return mix_int(h, st->kkt_backend);
}

static uint64_t head_csc(uint64_t h, const tscvx_csc *M) {
    h = mix_int(h, M->nrow);
    h = mix_int(h, M->ncol);
    h = mix_int(h, M->nnz);
    h = mix_ptr(h, M->p);
    h = mix_ptr(h, M->i);
    return mix_ptr(h, M->x);
}

/* The sparse method's sizes and pointers (delta, kmax and kmax_data are numbers) */
static uint64_t head_kkt(uint64_t h, const tscvx_kkt *k) {
    h = mix_ptr(h, k->backend);
    const tscvx_int sizes[] = {k->dim, k->nnz, k->nexp, k->ncone, k->lnz, k->npos};
    for (size_t t = 0; t < sizeof sizes / sizeof sizes[0]; t++) h = mix_int(h, sizes[t]);
    const void *const ptr[] = {k->Kp,      k->Ki,      k->Kx,  k->rowblk, k->pinv, k->mapP,
                               k->mapA,    k->mapG,    k->mapDiag, k->mapCone, k->expanded,
                               k->D,       k->Lp,      k->Parent,  k->Lnz,  k->Flag, k->Li,
                               k->Pattern, k->Lx,      k->Y,   k->Rp,     k->Rj,   k->sol,
                               k->res};
    for (size_t t = 0; t < sizeof ptr / sizeof ptr[0]; t++) h = mix_ptr(h, ptr[t]);
    return h;
}

/* The banded method's sizes and pointers (S, kmax and kmax_data are numbers) */
static uint64_t head_banded(uint64_t h, const tscvx_banded *bd) {
    h = mix_int(h, bd->ngroup);
    h = mix_int(h, bd->nb);
    for (int b = 0; b < TSCVX_BANDED_BORDER_MAX; b++) {
        h = mix_int(h, bd->bvar[b]);
        h = mix_int(h, bd->bgroup[b]);
    }
    h = mix(h, (uint64_t)bd->nH);
    h = mix(h, (uint64_t)bd->nCT);
    h = mix(h, (uint64_t)bd->nY);
    const void *const ptr[] = {bd->gp,    bd->gvar,  bd->loc,    bd->border, bd->hp,
                               bd->H,     bd->mapP,  bd->hasP,   bd->PF,     bd->gcp,
                               bd->gcone, bd->Grp,   bd->Gr_k,   bd->Gr_loc, bd->cgroup,
                               bd->rp,    bd->rrow,  bd->posA,   bd->cp,     bd->CT,
                               bd->perm,  bd->iperm, bd->yfirst, bd->yp,     bd->Y,
                               bd->Ydinv, bd->Hdinv, bd->V,      bd->bp,     bd->B,
                               bd->ga0,   bd->xg,    bd->yb,     bd->t,      bd->res_x,
                               bd->res_y, bd->res_z, bd->ex,     bd->ey,     bd->ez,
                               bd->ewz};
    for (size_t t = 0; t < sizeof ptr / sizeof ptr[0]; t++) h = mix_ptr(h, ptr[t]);
    return h;
}

uint64_t tscvx_ws_head_sum(const tscvx_workspace *ws) {
    uint64_t h = SUM_START;
    h = head_settings(h, &ws->st);
    h = mix_int(h, ws->n);
    h = mix_int(h, ws->p);
    h = mix_int(h, ws->m);
    const tscvx_cones *K = &ws->K;
    h = mix_int(h, K->l);
    h = mix_int(h, K->nsoc);
    h = mix_int(h, K->m);
    h = mix_int(h, K->degree);
    h = mix_ptr(h, K->q);
    h = mix_ptr(h, K->off);
    h = head_csc(h, &ws->P);
    h = head_csc(h, &ws->A);
    h = head_csc(h, &ws->G);
    h = mix_ptr(h, ws->method);
    h = head_kkt(h, &ws->kkt);
    h = head_banded(h, &ws->bd);
    const void *const ptr[] = {ws->c,   ws->b,   ws->h,   ws->D,      ws->EA,  ws->EG,
                               ws->W.w, ws->W.eta, ws->x, ws->y,      ws->z,   ws->s,
                               ws->lambda, ws->rx, ws->ry, ws->rz,    ws->Px,  ws->x1,
                               ws->y1,  ws->z1,  ws->wz1, ws->dx,     ws->dy,  ws->dz,
                               ws->ds,  ws->wdz, ws->e,   ws->cx,     ws->cy,  ws->cz,
                               ws->cwz, ws->wm,  ws->wm2, ws->wn,     ws->wp,  ws->bx,
                               ws->by,  ws->bz,  ws->bs,  ws->log};
    for (size_t t = 0; t < sizeof ptr / sizeof ptr[0]; t++) h = mix_ptr(h, ptr[t]);
    h = mix_int(h, ws->log_cap);
    h = mix(h, (uint64_t)ws->arena_used);
    return mix(h, (uint64_t)ws->arena_high);
}

/* The sparse method: the permuted KKT pattern, its row blocks and pinv, the maps of the data
 * and of the cone block, which SOCs are expanded; then the factor's symbolic data: the
 * static backend's L pattern (Lp, Li) and row patterns (Rp, Rj), or SuiteSparse LDL's Lp and
 * elimination tree (its Li is rewritten by every factorization, Lnz and Flag are work). */
static void body_sparse(span_list *L, const tscvx_workspace *ws) {
    const tscvx_kkt *k = &ws->kkt;
    add_ints(L, k->Kp, k->dim + 1);
    add_ints(L, k->Ki, k->nnz);
    add_chars(L, k->rowblk, k->dim);
    add_ints(L, k->pinv, k->dim);
    add_ints(L, k->mapP, ws->P.nnz);
    add_ints(L, k->mapA, ws->A.nnz);
    add_ints(L, k->mapG, ws->G.nnz);
    add_ints(L, k->mapDiag, ws->n + ws->p);
    add_ints(L, k->mapCone, k->ncone);
    add_ints(L, k->expanded, ws->K.nsoc);
    add_ints(L, k->Lp, k->dim + 1);
    if (k->backend == &tscvx_backend_static) {
        add_ints(L, k->Li, k->lnz);
        add_ints(L, k->Rp, k->dim + 1);
        add_ints(L, k->Rj, k->lnz);
    } else {
        add_ints(L, k->Parent, k->dim);
    }
}

/* The banded method: groups (gp, gvar, loc, ga0, border, hasP), P's slots, the cones of each
 * group and the group of each cone, G by rows, the row lists of the groups and the place of
 * each A entry in them, the band order and Y's profile, the offsets of the value blocks.
 * The arrays claimed per variable but used per group are covered over the ngroup groups. */
static void body_banded(span_list *L, const tscvx_workspace *ws) {
    const tscvx_banded *bd = &ws->bd;
    const tscvx_int n = ws->n, p = ws->p, m = ws->m, ng = bd->ngroup;
    const tscvx_int ncone = ws->K.l + ws->K.nsoc, nnzA = ws->A.nnz, nnzG = ws->G.nnz;
    add_ints(L, bd->gp, ng + 1);
    add_ints(L, bd->gvar, n);
    add_ints(L, bd->loc, n);
    add_ints(L, bd->ga0, ng);
    add_chars(L, bd->border, ng);
    add_chars(L, bd->hasP, ng);
    add_ints(L, bd->hp, ng + 1);
    add_ints(L, bd->mapP, ws->P.nnz);
    add_ints(L, bd->gcp, ng + 1);
    add_ints(L, bd->gcone, ncone);
    add_ints(L, bd->cgroup, ncone);
    add_ints(L, bd->Grp, m + 1);
    add_ints(L, bd->Gr_k, nnzG);
    add_ints(L, bd->Gr_loc, nnzG);
    add_ints(L, bd->rp, ng + 1);
    add_ints(L, bd->rrow, nnzA);
    add_ints(L, bd->posA, nnzA);
    add_ints(L, bd->cp, ng + 1);
    add_ints(L, bd->perm, p);
    add_ints(L, bd->iperm, p);
    add_ints(L, bd->yfirst, p);
    add_ints(L, bd->yp, p + 1);
    add_ints(L, bd->bp, ws->K.nsoc + 1);
}

uint64_t tscvx_ws_body_sum(const tscvx_workspace *ws) {
    span_list list;
    span_list *L = &list;
    L->n = 0;
    add_ints(L, ws->K.q, ws->K.nsoc);
    add_ints(L, ws->K.off, ws->K.nsoc);
    const tscvx_csc *M[3] = {&ws->P, &ws->A, &ws->G};
    for (int k = 0; k < 3; k++) {
        add_ints(L, M[k]->p, M[k]->ncol + 1);
        add_ints(L, M[k]->i, M[k]->nnz);
    }
    if (ws->method == &tscvx_method_banded)
        body_banded(L, ws);
    else
        body_sparse(L, ws);
    uint64_t h = SUM_START;
    for (int k = 0; k < L->n; k++) h = mix_bytes(h, L->s[k].p, L->s[k].bytes);
    return mix(h, (uint64_t)L->n);
}
