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
        if (d < e->nnz_A) {
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

void pdg_emit(pdg_emitter *e, const pdg_layout *L, int roll_free, const pdg_values *v)
{
    const int N = L->N, nI = N - 1, ne = N_TR_SCALAR * (N - 1);
    const int ns = N_TR_SCALAR * N + NU * N + 1;
    const int vals = e->mode == 2;
    const pdg_scaling *sc = vals ? v->sc : 0;
    const pdg_params *p = vals ? &v->scn->params : 0;
    double inv[NX], xf[NX];
    double tg = 0.0, cg = 0.0, eta = 0.0;
    int row = 0, k, i, j, c;

    if (vals) {
        for (i = 0; i < NX; ++i) {
            inv[i] = 1.0 / sc->Sx[i];
        }
        pdg_x_final_target(v->scn, xf);
        tg = pdg_tan_glideslope(p);
        cg = pdg_cos_gimbal(p);
        eta = v->eta;
        for (i = 0; i < L->n; ++i) {
            v->c[i] = i >= L->ivc ? v->lam : 0.0;
        }
        v->c[XI(N - 1, IM)] = -1.0;
        /* proximal term (w/2)|u_hat - u_ref|^2: its linear part -w u_ref */
        for (i = L->iu; i < L->isig; ++i) {
            v->c[i] -= v->prox_u * v->zref[i];
        }
    }
    /* ---- dynamics: x_{k+1} - A_hat x_k - Bm_hat u_k - Bp_hat u_{k+1} - S_hat sigma - nu
     *      = Sx^-1 (A c_x + z - c_x) */
    for (k = 0; k < nI; ++k) {
        const double *D = vals ? v->disc + (size_t)k * N_DISC : 0;
        const int base = row + NX * k;
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
                rhs(e, v, base + i, inv[i] * (Acx + D[D_Z + i] - sc->cx[i]));
            }
        }
    }
    row += NX * nI;
    /* ---- boundary conditions */
    {
        double x0[NX];
        if (vals) {
            pdg_initial_state(v->scn, x0);
        }
        for (i = 0; i < NX; ++i) {
            put(e, row + i, XI(0, i), 1.0);
            if (vals) {
                rhs(e, v, row + i, (x0[i] - sc->cx[i]) / sc->Sx[i]);
            }
        }
    }
    row += NX;
    {
        static const int fin_free[11] = {0, 1, 2, 3, 4, 5, 10, 11, 12, 8, 9};
        static const int fin_pin[13] = {0, 1, 2, 3, 4, 5, 10, 11, 12, 6, 7, 8, 9};
        const int *fin = roll_free ? fin_free : fin_pin;
        const int nf = roll_free ? 11 : 13;
        for (i = 0; i < nf; ++i) {
            put(e, row + i, XI(N - 1, fin[i]), 1.0);
            if (vals) {
                rhs(e, v, row + i, (xf[fin[i]] - sc->cx[fin[i]]) / sc->Sx[fin[i]]);
            }
        }
        row += nf;
    }
    /* ---- |nu_i| epigraph (scalar blocks): s = t - nu >= 0 and s = t + nu >= 0 */
    for (k = 0; k < nI; ++k) {
        for (j = 0; j < N_TR_SCALAR; ++j) {
            const int r = row + N_TR_SCALAR * k + j;
            put(e, r, L->ivc + N_NU_BLOCKS * k + j, -1.0);
            put(e, r, L->inu + NX * k + pdg_tr_scalar_states[j], 1.0);
            rhs(e, v, r, 0.0);
        }
    }
    for (k = 0; k < nI; ++k) {
        for (j = 0; j < N_TR_SCALAR; ++j) {
            const int r = row + ne + N_TR_SCALAR * k + j;
            put(e, r, L->ivc + N_NU_BLOCKS * k + j, -1.0);
            put(e, r, L->inu + NX * k + pdg_tr_scalar_states[j], -1.0);
            rhs(e, v, r, 0.0);
        }
    }
    row += 2 * ne;
    /* ---- s' >= 0 */
    for (k = 0; k < N; ++k) {
        put(e, row + k, L->ibuf + k, -1.0);
        rhs(e, v, row + k, 0.0);
    }
    row += N;
    /* ---- sigma_hat >= SIGMA_MIN / Ss */
    put(e, row, L->isig, -1.0);
    rhs(e, v, row, vals ? -SIGMA_MIN / sc->Ss : 0.0);
    row += 1;
    /* ---- trust region, scalars: eta -+ (z - z_ref) >= 0 over (x scalars, u, sigma) */
    for (i = 0; i < ns; ++i) {
        const int col = i < N_TR_SCALAR * N
                            ? XI(i / N_TR_SCALAR, pdg_tr_scalar_states[i % N_TR_SCALAR])
                            : L->iu + (i - N_TR_SCALAR * N);
        put(e, row + i, col, 1.0);
        put(e, row + ns + i, col, -1.0);
        if (vals) {
            rhs(e, v, row + i, eta + v->zref[col]);
            rhs(e, v, row + ns + i, eta - v->zref[col]);
        }
    }
    row += 2 * ns;
    /* ---- mass: m_hat >= 0 (a masked-out node gets 0 >= -1) */
    for (k = 0; k < N; ++k) {
        const int keep = !vals || !v->keep || v->keep[NC * k];
        put(e, row + k, XI(k, IM), keep ? -1.0 : 0.0);
        rhs(e, v, row + k, keep ? 0.0 : 1.0);
    }
    row += N;
    /* ---- T_min linearized: -(T_ref/|T_ref|) . u_hat - s' + s = -T_min / Su */
    for (k = 0; k < N; ++k) {
        double dir[NU] = {0.0, 0.0, 0.0};
        if (vals) {
            const double *ur = v->zref + L->iu + NU * k;
            double un = sqrt(ur[0] * ur[0] + ur[1] * ur[1] + ur[2] * ur[2]);
            un = un > 1e-12 ? un : 1e-12;
            for (j = 0; j < NU; ++j) {
                dir[j] = ur[j] / un;
            }
        }
        for (j = 0; j < NU; ++j) {
            put(e, row + k, UI(k, j), -dir[j]);
        }
        put(e, row + k, L->ibuf + k, -1.0);
        rhs(e, v, row + k, vals ? -p->T_min / sc->Su : 0.0);
    }
    row += N;
    /* ---- path-constraint cones, node-major, c = 1..5 (masked out: zero rows, head 1) */
    for (k = 0; k < N; ++k) {
        for (c = 1; c <= 5; ++c) {
            const int keep = !vals || !v->keep || v->keep[NC * k + c];
            const double on = keep ? 1.0 : 0.0;
            double head = 0.0;
            if (c == 1) { /* [r1; tan(gs) r2; tan(gs) r3] */
                put(e, row, XI(k, 0), -on);
                put(e, row + 1, XI(k, 1), -tg * on);
                put(e, row + 2, XI(k, 2), -tg * on);
            } else if (c == 2) { /* [q_max; q2; q3] */
                put(e, row + 1, XI(k, 8), -on);
                put(e, row + 2, XI(k, 9), -on);
                head = vals ? pdg_tilt_q_max(p) / sc->Sx[8] : 0.0;
            } else if (c == 3) { /* [omega_max / S_w; omega_hat] */
                for (j = 0; j < 3; ++j) {
                    put(e, row + 1 + j, XI(k, 10 + j), -on);
                }
                head = vals ? pdg_omega_max(p) / sc->Sx[10] : 0.0;
            } else if (c == 4) { /* [T_max / Su; u_hat] */
                for (j = 0; j < 3; ++j) {
                    put(e, row + 1 + j, UI(k, j), -on);
                }
                head = vals ? p->T_max / sc->Su : 0.0;
            } else { /* [u1; cos(delta) u_hat] */
                put(e, row, UI(k, 0), -on);
                put(e, row + 1, UI(k, 0), -cg * on);
                put(e, row + 2, UI(k, 1), -cg * on);
                put(e, row + 3, UI(k, 2), -cg * on);
            }
            for (j = 0; j < cone_dims[c]; ++j) {
                rhs(e, v, row + j, j == 0 ? (keep ? head : 1.0) : 0.0);
            }
            row += cone_dims[c];
        }
    }
    /* ---- virtual-control pairs: [t_p; nu_a; nu_b] in Q3 */
    for (k = 0; k < nI; ++k) {
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
    /* ---- trust region, rotation-invariant pairs: [eta; z_a - ref_a; z_b - ref_b] in Q3 */
    for (k = 0; k < N; ++k) {
        for (j = 0; j < N_TR_PAIRS; ++j) {
            const int ca = XI(k, pdg_tr_pairs[j][0]), cb = XI(k, pdg_tr_pairs[j][1]);
            put(e, row + 1, ca, -1.0);
            put(e, row + 2, cb, -1.0);
            if (vals) {
                rhs(e, v, row, eta);
                rhs(e, v, row + 1, -v->zref[ca]);
                rhs(e, v, row + 2, -v->zref[cb]);
            }
            row += 3;
        }
    }
}
