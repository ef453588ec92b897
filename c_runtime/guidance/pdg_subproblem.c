/* The SCvx convex subproblem (paper Eq. (7)-(9)): a transcription of guidance/subproblem.py.
 *
 * Decision vector (scaled units, x = Sx x_hat + cx, u = Su u_hat, t_f = Ss sigma_hat):
 *     z = [x_hat (N x 14) | u_hat (N x 3) | sigma_hat | nu ((N-1) x 14) |
 *          t ((N-1) x 10) | s' (N)]
 * Objective: -m_hat(t_f) + lambda (sum t + sum s').
 *
 * Rows in the reference's (Clarabel) order; the first p are equalities (A z = b), the others
 * cone rows (G z + s = h, s in K):
 *   A: dynamics 14 (N-1) | initial state 14 | final r, v, omega and q2, q3 (or all of q)
 *   G nonnegative: |nu| epigraph 2 x 6 (N-1) | s' >= 0 (N) | sigma bound | trust region,
 *                  scalar part 2 (6N + 3N + 1) | mass (N) | linearized T_min (N)
 *   G second-order cones: per node glideslope 3, tilt 3, rate 4, T_max 4, gimbal 4 |
 *                  virtual-control pairs 4 (N-1) x 3 | trust-region pairs 4N x 3
 *
 * ONE routine (pdg_emit) writes both the sparsity pattern (at setup) and the numbers (every
 * iteration), entry by entry in the same order, so the two cannot disagree.
 */
#include <math.h>

#include "pdg_internal.h"

const int pdg_tr_scalar_states[N_TR_SCALAR] = {0, 3, 10, 11, 12, 13};
const int pdg_tr_pairs[N_TR_PAIRS][2] = {{1, 2}, {4, 5}, {6, 7}, {8, 9}};
static const int cone_dims[NC] = {1, 3, 3, 4, 4, 4, 1};

void pdg_layout_init(pdg_layout *L, int N)
{
    L->N = N;
    L->ix = 0;
    L->iu = N * NX;
    L->isig = L->iu + N * NU;
    L->inu = L->isig + 1;
    L->ivc = L->inu + (N - 1) * NX;
    L->ibuf = L->ivc + (N - 1) * N_NU_BLOCKS;
    L->n = L->ibuf + N;
    L->n_traj = L->isig + 1;
}

int pdg_rows_eq(int N, int roll_free) { return NX * (N - 1) + NX + 9 + (roll_free ? 2 : 4); }

/* Nonnegative orthant size and the SOC list (q may be NULL). */
void pdg_cone_dims(int N, int *l, int *nsoc, int *q)
{
    const int ne = N_TR_SCALAR * (N - 1), ns = N_TR_SCALAR * N + NU * N + 1;
    int k, c, j, i = 0;
    *l = 2 * ne + N + 1 + 2 * ns + N + N;
    for (k = 0; k < N; ++k) {
        for (c = 1; c <= 5; ++c) {
            if (q) {
                q[i] = cone_dims[c];
            }
            ++i;
        }
    }
    for (k = 0; k < N - 1; ++k) {
        for (j = 0; j < N_TR_PAIRS; ++j) {
            if (q) {
                q[i] = 3;
            }
            ++i;
        }
    }
    for (k = 0; k < N; ++k) {
        for (j = 0; j < N_TR_PAIRS; ++j) {
            if (q) {
                q[i] = 3;
            }
            ++i;
        }
    }
    *nsoc = i;
}

void pdg_scaling_init(pdg_scaling *sc, const pdg_scenario *s, double t_f_guess)
{
    const pdg_params *p = &s->params;
    double Sr = sqrt(s->r0[0] * s->r0[0] + s->r0[1] * s->r0[1] + s->r0[2] * s->r0[2]);
    double Sv = sqrt(s->v0[0] * s->v0[0] + s->v0[1] * s->v0[1] + s->v0[2] * s->v0[2]);
    int i;
    Sr = Sr > 1.0 ? Sr : 1.0;
    Sv = Sv > 1.0 ? Sv : 1.0;
    for (i = 0; i < NX; ++i) {
        sc->Sx[i] = 1.0;
        sc->cx[i] = 0.0;
    }
    for (i = 0; i < 3; ++i) {
        sc->Sx[i] = Sr;
        sc->Sx[3 + i] = Sv;
        sc->Sx[10 + i] = pdg_omega_max(p);
    }
    sc->Sx[IM] = s->m0 - p->m_dry; /* the propellant, but at least MASS_SCALE_FLOOR m0 */
    if (sc->Sx[IM] < MASS_SCALE_FLOOR * s->m0) sc->Sx[IM] = MASS_SCALE_FLOOR * s->m0;
    sc->cx[IM] = p->m_dry;
    sc->Su = p->T_max;
    sc->Ss = t_f_guess;
}

/* One matrix entry at global (reference) row `row`, column `col`. */
static void put(pdg_emitter *e, int row, int col, double val)
{
    if (e->mode == 1) {
        e->row[e->cnt] = row;
        e->col[e->cnt] = col;
    } else if (e->mode == 2) {
        const int d = e->dest[e->cnt];
        if (d < 0 || d >= e->nnz) { /* an upset in the map: refuse, never write outside */
            e->bad_slot = 1;
        } else if (d < e->nnz_A) {
            e->Ax[d] = val;
        } else {
            e->Gx[d - e->nnz_A] = val;
        }
    }
    e->cnt++;
}

/* Right-hand side of global row `row` (values mode only). */
static void rhs(const pdg_emitter *e, const pdg_values *v, int row, double val)
{
    if (e->mode != 2) {
        return;
    }
    if (row < e->p) {
        v->b[row] = val;
    } else {
        v->h[row - e->p] = val;
    }
}

#define XI(k, i) (L->ix + NX * (k) + (i))
#define UI(k, i) (L->iu + NU * (k) + (i))

/* What every block of rows reads; the numbers only in values mode (vals), zeros otherwise. */
typedef struct {
    pdg_emitter *e;
    const pdg_layout *L;
    const pdg_values *v;
    const pdg_scaling *sc;
    const pdg_params *p;
    int vals;
    double inv[NX]; /* 1 / Sx */
    double tg;      /* tan of the glideslope angle */
    double cg;      /* cos of the gimbal limit */
    double eta;     /* trust radius */
} emit_ctx;

/* c = lam on the virtual control and buffers, -fuel on the final mass, and the linear part
 * -w u_ref of the proximal term (w/2)|u_hat - u_ref|^2 */
static void objective(const pdg_layout *L, const pdg_values *v)
{
    int i;
    for (i = 0; i < L->n; ++i) {
        v->c[i] = i >= L->ivc ? v->lam : 0.0;
    }
    v->c[XI(L->N - 1, IM)] = -v->fuel;
    for (i = L->iu; i < L->isig; ++i) {
        v->c[i] -= v->prox_u * v->zref[i];
    }
}

/* dynamics: x_{k+1} - A_hat x_k - Bm_hat u_k - Bp_hat u_{k+1} - S_hat sigma - nu
 *           = Sx^-1 (A c_x + z - c_x); returns the rows written */
static int emit_dynamics(const emit_ctx *c)
{
    const pdg_layout *L = c->L;
    const pdg_scaling *sc = c->sc;
    const double *inv = c->inv;
    pdg_emitter *e = c->e;
    const int vals = c->vals;
    int k, i, j;
    for (k = 0; k < L->N - 1; ++k) {
        const double *D = vals ? c->v->disc + (size_t)k * N_DISC : 0;
        const int base = NX * k;
        for (i = 0; i < NX; ++i) {
            put(e, base + i, XI(k + 1, i), 1.0);
        }
        for (i = 0; i < NX; ++i) {
            for (j = 0; j < NX; ++j) {
                if (e->phi_a[NX * i + j]) {
                    put(e, base + i, XI(k, j), vals ? -(inv[i] * D[D_A + NX * i + j] * sc->Sx[j]) : 0);
                }
            }
        }
        for (i = 0; i < NX; ++i) {
            for (j = 0; j < NU; ++j) {
                put(e, base + i, UI(k, j), vals ? -(inv[i] * D[D_BM + NU * i + j] * sc->Su) : 0);
            }
        }
        for (i = 0; i < NX; ++i) {
            for (j = 0; j < NU; ++j) {
                put(e, base + i, UI(k + 1, j),
                    vals ? -(inv[i] * D[D_BP + NU * i + j] * sc->Su) : 0);
            }
        }
        for (i = 0; i < NX; ++i) {
            put(e, base + i, L->isig, vals ? -(inv[i] * D[D_S + i] * sc->Ss) : 0);
        }
        for (i = 0; i < NX; ++i) {
            put(e, base + i, L->inu + NX * k + i, -1.0);
        }
        if (vals) {
            for (i = 0; i < NX; ++i) {
                const double Acx = D[D_A + NX * i + IM] * sc->cx[IM];
                rhs(e, c->v, base + i, inv[i] * (Acx + D[D_Z + i] - sc->cx[i]));
            }
        }
    }
    return NX * (L->N - 1);
}

/* boundary conditions from `row`: the initial state, the final r, v, omega and q2, q3 (or
 * all of q); returns the next row */
static int emit_boundary(const emit_ctx *c, int row, int roll_free)
{
    static const int fin_free[11] = {0, 1, 2, 3, 4, 5, 10, 11, 12, 8, 9};
    static const int fin_pin[13] = {0, 1, 2, 3, 4, 5, 10, 11, 12, 6, 7, 8, 9};
    const int *fin = roll_free ? fin_free : fin_pin;
    const int nf = roll_free ? 11 : 13;
    const pdg_layout *L = c->L;
    const pdg_scaling *sc = c->sc;
    double x0[NX], xf[NX];
    int i;
    if (c->vals) {
        pdg_initial_state(c->v->scn, x0);
        pdg_x_final_target(c->v->scn, xf);
    } else { /* not read; set so that no path reads an unset value */
        for (i = 0; i < NX; ++i) {
            x0[i] = xf[i] = 0.0;
        }
    }
    for (i = 0; i < NX; ++i) {
        put(c->e, row + i, XI(0, i), 1.0);
        if (c->vals) {
            rhs(c->e, c->v, row + i, (x0[i] - sc->cx[i]) / sc->Sx[i]);
        }
    }
    row += NX;
    for (i = 0; i < nf; ++i) {
        put(c->e, row + i, XI(L->N - 1, fin[i]), 1.0);
        if (c->vals) {
            rhs(c->e, c->v, row + i, (xf[fin[i]] - sc->cx[fin[i]]) / sc->Sx[fin[i]]);
        }
    }
    return row + nf;
}

/* |nu_i| epigraph (scalar blocks): s = t - nu >= 0 and s = t + nu >= 0; returns the next row */
static int emit_nu_epigraph(const emit_ctx *c, int row)
{
    const pdg_layout *L = c->L;
    const int ne = N_TR_SCALAR * (L->N - 1);
    int k, j, side;
    for (side = 0; side < 2; ++side) {
        for (k = 0; k < L->N - 1; ++k) {
            for (j = 0; j < N_TR_SCALAR; ++j) {
                const int r = row + side * ne + N_TR_SCALAR * k + j;
                put(c->e, r, L->ivc + N_NU_BLOCKS * k + j, -1.0);
                put(c->e, r, L->inu + NX * k + pdg_tr_scalar_states[j], side ? -1.0 : 1.0);
                rhs(c->e, c->v, r, 0.0);
            }
        }
    }
    return row + 2 * ne;
}

/* s' >= 0, sigma_hat >= SIGMA_MIN / Ss, and the trust region's scalar rows
 * eta -+ (z - z_ref) >= 0 over (x scalars, u, sigma); returns the next row */
static int emit_bounds(const emit_ctx *c, int row)
{
    const pdg_layout *L = c->L;
    const int N = L->N, ns = N_TR_SCALAR * N + NU * N + 1;
    int k, i;
    for (k = 0; k < N; ++k) {
        put(c->e, row + k, L->ibuf + k, -1.0);
        rhs(c->e, c->v, row + k, 0.0);
    }
    row += N;
    put(c->e, row, L->isig, -1.0);
    rhs(c->e, c->v, row, c->vals ? -SIGMA_MIN / c->sc->Ss : 0.0);
    row += 1;
    for (i = 0; i < ns; ++i) {
        const int col = i < N_TR_SCALAR * N
                            ? XI(i / N_TR_SCALAR, pdg_tr_scalar_states[i % N_TR_SCALAR])
                            : L->iu + (i - N_TR_SCALAR * N);
        put(c->e, row + i, col, 1.0);
        put(c->e, row + ns + i, col, -1.0);
        if (c->vals) {
            rhs(c->e, c->v, row + i, c->eta + c->v->zref[col]);
            rhs(c->e, c->v, row + ns + i, c->eta - c->v->zref[col]);
        }
    }
    return row + 2 * ns;
}

/* mass m_hat >= 0 (a masked-out node gets 0 >= -1) and T_min linearized,
 * -(T_ref/|T_ref|) . u_hat - s' + s = -T_min / Su; returns the next row */
static int emit_mass_tmin(const emit_ctx *c, int row)
{
    const pdg_layout *L = c->L;
    const pdg_values *v = c->v;
    const int N = L->N;
    int k, j;
    for (k = 0; k < N; ++k) {
        const int keep = !c->vals || !v->keep || v->keep[NC * k];
        put(c->e, row + k, XI(k, IM), keep ? -1.0 : 0.0);
        rhs(c->e, v, row + k, keep ? 0.0 : 1.0);
    }
    row += N;
    for (k = 0; k < N; ++k) {
        double dir[NU] = {0.0, 0.0, 0.0};
        if (c->vals) {
            const double *ur = v->zref + L->iu + NU * k;
            double un = sqrt(ur[0] * ur[0] + ur[1] * ur[1] + ur[2] * ur[2]);
            un = un > 1e-12 ? un : 1e-12;
            for (j = 0; j < NU; ++j) {
                dir[j] = ur[j] / un;
            }
        }
        for (j = 0; j < NU; ++j) {
            put(c->e, row + k, UI(k, j), -dir[j]);
        }
        put(c->e, row + k, L->ibuf + k, -1.0);
        rhs(c->e, v, row + k, c->vals ? -c->p->T_min / c->sc->Su : 0.0);
    }
    return row + N;
}

/* Path constraint `con` (1..5) of node k as one cone at `row` (masked out: zero rows, head 1);
 * returns the next row */
static int emit_path_cone(const emit_ctx *c, int k, int con, int row)
{
    const pdg_layout *L = c->L;
    const pdg_values *v = c->v;
    pdg_emitter *e = c->e;
    const int keep = !c->vals || !v->keep || v->keep[NC * k + con];
    const double on = keep ? 1.0 : 0.0;
    double head = 0.0;
    int j;
    if (con == 1) { /* [r1; tan(gs) r2; tan(gs) r3] */
        put(e, row, XI(k, 0), -on);
        put(e, row + 1, XI(k, 1), -c->tg * on);
        put(e, row + 2, XI(k, 2), -c->tg * on);
    } else if (con == 2) { /* [q_max; q2; q3] */
        put(e, row + 1, XI(k, 8), -on);
        put(e, row + 2, XI(k, 9), -on);
        head = c->vals ? pdg_tilt_q_max(c->p) / c->sc->Sx[8] : 0.0;
    } else if (con == 3) { /* [omega_max / S_w; omega_hat] */
        for (j = 0; j < 3; ++j) {
            put(e, row + 1 + j, XI(k, 10 + j), -on);
        }
        head = c->vals ? pdg_omega_max(c->p) / c->sc->Sx[10] : 0.0;
    } else if (con == 4) { /* [T_max / Su; u_hat] */
        for (j = 0; j < 3; ++j) {
            put(e, row + 1 + j, UI(k, j), -on);
        }
        head = c->vals ? c->p->T_max / c->sc->Su : 0.0;
    } else { /* [u1; cos(delta) u_hat] */
        put(e, row, UI(k, 0), -on);
        put(e, row + 1, UI(k, 0), -c->cg * on);
        put(e, row + 2, UI(k, 1), -c->cg * on);
        put(e, row + 3, UI(k, 2), -c->cg * on);
    }
    for (j = 0; j < cone_dims[con]; ++j) {
        rhs(e, v, row + j, j == 0 ? (keep ? head : 1.0) : 0.0);
    }
    return row + cone_dims[con];
}

/* The rotation-invariant pairs in Q3: virtual control [t_p; nu_a; nu_b] per interval, then
 * trust region [eta; z_a - ref_a; z_b - ref_b] per node; returns the next row */
static int emit_pairs(const emit_ctx *c, int row)
{
    const pdg_layout *L = c->L;
    const pdg_values *v = c->v;
    pdg_emitter *e = c->e;
    int k, j;
    for (k = 0; k < L->N - 1; ++k) {
        for (j = 0; j < N_TR_PAIRS; ++j) {
            put(e, row, L->ivc + N_NU_BLOCKS * k + N_TR_SCALAR + j, -1.0);
            put(e, row + 1, L->inu + NX * k + pdg_tr_pairs[j][0], -1.0);
            put(e, row + 2, L->inu + NX * k + pdg_tr_pairs[j][1], -1.0);
            rhs(e, v, row, 0.0);
            rhs(e, v, row + 1, 0.0);
            rhs(e, v, row + 2, 0.0);
            row += 3;
        }
    }
    for (k = 0; k < L->N; ++k) {
        for (j = 0; j < N_TR_PAIRS; ++j) {
            const int ca = XI(k, pdg_tr_pairs[j][0]), cb = XI(k, pdg_tr_pairs[j][1]);
            put(e, row + 1, ca, -1.0);
            put(e, row + 2, cb, -1.0);
            if (c->vals) {
                rhs(e, v, row, c->eta);
                rhs(e, v, row + 1, -v->zref[ca]);
                rhs(e, v, row + 2, -v->zref[cb]);
            }
            row += 3;
        }
    }
    return row;
}

void pdg_emit(pdg_emitter *e, const pdg_layout *L, int roll_free, const pdg_values *v)
{
    emit_ctx c;
    int row, k, con, i;
    c.e = e;
    c.L = L;
    c.v = v;
    c.vals = e->mode == 2;
    c.sc = c.vals ? v->sc : 0;
    c.p = c.vals ? &v->scn->params : 0;
    c.tg = c.cg = c.eta = 0.0;
    if (c.vals) {
        for (i = 0; i < NX; ++i) {
            c.inv[i] = 1.0 / c.sc->Sx[i];
        }
        c.tg = pdg_tan_glideslope(c.p);
        c.cg = pdg_cos_gimbal(c.p);
        c.eta = v->eta;
        objective(L, v);
    }
    row = emit_dynamics(&c);
    row = emit_boundary(&c, row, roll_free);
    row = emit_nu_epigraph(&c, row);
    row = emit_bounds(&c, row);
    row = emit_mass_tmin(&c, row);
    for (k = 0; k < L->N; ++k) { /* path-constraint cones, node-major */
        for (con = 1; con <= 5; ++con) {
            row = emit_path_cone(&c, k, con, row);
        }
    }
    emit_pairs(&c, row);
}
