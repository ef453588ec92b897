/* Initial guess: a transcription of guidance/guess.py (cubic Hermite landing profile, t_f
 * from a geometric grid, attitude along the required thrust, projection onto the boundary
 * conditions and the convex constraints). No optimization, no allocation. */
#include <math.h>
#include <stdio.h>

#include "pdg_internal.h"

#define BLEND_FRACTION 0.25
#define TF_GRID_N 60
#define TF_GRID_LO 0.5
#define TF_GRID_HI 20.0

static double norm3(const double *v) { return sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); }

/* numpy.geomspace(0.5, 20, 60)[i] (endpoints exact) */
static double tf_grid(int i)
{
    const double a = log10(TF_GRID_LO), b = log10(TF_GRID_HI);
    if (i == 0) {
        return TF_GRID_LO;
    }
    if (i == TF_GRID_N - 1) {
        return TF_GRID_HI;
    }
    return pow(10.0, a + i * ((b - a) / (TF_GRID_N - 1)));
}

static double node_s(int k, int N) { return k == N - 1 ? 1.0 : k * (1.0 / (N - 1)); }

/* Position, velocity and acceleration of the cubic Hermite curve at normalized time s. */
static void hermite(const double *r0, const double *v0, const double *rf, const double *vf,
                    double t_f, double s, double *r, double *v, double *a)
{
    const double s2 = s * s, s3 = s2 * s;
    const double h00 = 2 * s3 - 3 * s2 + 1, h10 = s3 - 2 * s2 + s, h01 = -2 * s3 + 3 * s2,
                 h11 = s3 - s2;
    const double d00 = 6 * s2 - 6 * s, d10 = 3 * s2 - 4 * s + 1, d01 = -6 * s2 + 6 * s,
                 d11 = 3 * s2 - 2 * s;
    const double a00 = 12 * s - 6, a10 = 6 * s - 4, a01 = -12 * s + 6, a11 = 6 * s - 2;
    int i;
    for (i = 0; i < 3; ++i) {
        const double m0 = v0[i] * t_f, m1 = vf[i] * t_f;
        r[i] = h00 * r0[i] + h10 * m0 + h01 * rf[i] + h11 * m1;
        v[i] = (d00 * r0[i] + d10 * m0 + d01 * rf[i] + d11 * m1) / t_f;
        a[i] = (a00 * r0[i] + a10 * m0 + a01 * rf[i] + a11 * m1) / (t_f * t_f);
    }
}

/* Profile for one t_f: r, v (N x 3), required thrust T_I (N x 3) and mass (N). */
static void required_thrust(const pdg_scenario *sc, double t_f, double *r, double *v,
                            double *T, double *m)
{
    const pdg_params *p = &sc->params;
    const int N = p->N;
    int k, i;
    m[0] = sc->m0;
    for (k = 0; k < N; ++k) {
        double a[3], vn;
        hermite(sc->r0, sc->v0, p->r_f, p->v_f, t_f, node_s(k, N), r + 3 * k, v + 3 * k, a);
        vn = norm3(v + 3 * k);
        for (i = 0; i < 3; ++i) {
            T[3 * k + i] = m[k] * (a[i] - p->g_I[i]) + p->aero_coeff * vn * v[3 * k + i];
        }
        if (k + 1 < N) {
            const double dt = t_f * (node_s(k + 1, N) - node_s(k, N));
            const double mdot = -p->alpha_mdot * norm3(T + 3 * k) - p->beta_mdot;
            m[k + 1] = m[k] + dt * mdot;
        }
    }
}

static double smoothstep(double a)
{
    a = a < 0.0 ? 0.0 : (a > 1.0 ? 1.0 : a);
    return a * a * (3.0 - 2.0 * a);
}

static void cross(const double *a, const double *b, double *c)
{
    c[0] = a[1] * b[2] - a[2] * b[1];
    c[1] = a[2] * b[0] - a[0] * b[2];
    c[2] = a[0] * b[1] - a[1] * b[0];
}

/* Smallest rotation taking unit vector a to unit vector b. */
static void min_rotation(const double *a, const double *b, double R[3][3])
{
    double v[3], c = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    int i, j, k;
    cross(a, b, v);
    if (c < -1.0 + 1e-9) {
        double n[3], e[3] = {0.0, 0.0, 0.0}, nn;
        e[fabs(a[1]) < 0.9 ? 1 : 2] = 1.0;
        cross(a, e, n);
        nn = norm3(n);
        for (i = 0; i < 3; ++i) {
            n[i] /= nn;
        }
        for (i = 0; i < 3; ++i) {
            for (j = 0; j < 3; ++j) {
                R[i][j] = 2.0 * n[i] * n[j] - (i == j ? 1.0 : 0.0);
            }
        }
        return;
    }
    {
        const double vx[3][3] = {{0.0, -v[2], v[1]}, {v[2], 0.0, -v[0]}, {-v[1], v[0], 0.0}};
        for (i = 0; i < 3; ++i) {
            for (j = 0; j < 3; ++j) {
                double sq = 0.0;
                for (k = 0; k < 3; ++k) {
                    sq += vx[i][k] * vx[k][j];
                }
                R[i][j] = (i == j ? 1.0 : 0.0) + vx[i][j] + sq / (1.0 + c);
            }
        }
    }
}

/* Inverse of pdg_dcm_bi on rotations (Shepperd's method), normalized. */
static void quat_from_dcm_bi(double C[3][3], double *q)
{
    const double tr = C[0][0] + C[1][1] + C[2][2];
    const double cand[4] = {tr, C[0][0], C[1][1], C[2][2]};
    double n, w;
    int i, best = 0;
    for (i = 1; i < 4; ++i) {
        if (cand[i] > cand[best]) {
            best = i;
        }
    }
    if (best == 0) {
        w = 0.5 * sqrt(1.0 + tr);
        q[0] = w;
        q[1] = (C[1][2] - C[2][1]) / (4 * w);
        q[2] = (C[2][0] - C[0][2]) / (4 * w);
        q[3] = (C[0][1] - C[1][0]) / (4 * w);
    } else if (best == 1) {
        w = 0.5 * sqrt(1.0 + 2 * C[0][0] - tr);
        q[0] = (C[1][2] - C[2][1]) / (4 * w);
        q[1] = w;
        q[2] = (C[0][1] + C[1][0]) / (4 * w);
        q[3] = (C[0][2] + C[2][0]) / (4 * w);
    } else if (best == 2) {
        w = 0.5 * sqrt(1.0 + 2 * C[1][1] - tr);
        q[0] = (C[2][0] - C[0][2]) / (4 * w);
        q[1] = (C[0][1] + C[1][0]) / (4 * w);
        q[2] = w;
        q[3] = (C[1][2] + C[2][1]) / (4 * w);
    } else {
        w = 0.5 * sqrt(1.0 + 2 * C[2][2] - tr);
        q[0] = (C[0][1] - C[1][0]) / (4 * w);
        q[1] = (C[0][2] + C[2][0]) / (4 * w);
        q[2] = (C[1][2] + C[2][1]) / (4 * w);
        q[3] = w;
    }
    n = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    for (i = 0; i < 4; ++i) {
        q[i] /= n;
    }
}

/* numpy.gradient(f, t) along nodes for a column of stride `stride` (edge_order = 1). */
static double gradient_at(const double *f, int stride, const double *t, int N, int k)
{
    double hs, hd;
    if (k == 0) {
        return (f[stride] - f[0]) / (t[1] - t[0]);
    }
    if (k == N - 1) {
        return (f[(N - 1) * stride] - f[(N - 2) * stride]) / (t[N - 1] - t[N - 2]);
    }
    hs = t[k] - t[k - 1];
    hd = t[k + 1] - t[k];
    return (hs * hs * f[(k + 1) * stride] + (hd * hd - hs * hs) * f[k * stride] -
            hd * hd * f[(k - 1) * stride]) /
           (hs * hd * (hd + hs));
}

/* t_f: the cheapest profile within T_max on the grid; key (over, fuel or max thrust). The
 * arrays are the profile's scratch (required_thrust). */
static double cheapest_t_f(const pdg_scenario *sc, double *r, double *v, double *T, double *m)
{
    const pdg_params *p = &sc->params;
    const int N = p->N;
    double t_f = TF_GRID_LO, best_over = 0, best_val = 0;
    int i, k, have = 0;
    for (i = 0; i < TF_GRID_N; ++i) {
        const double tf = tf_grid(i);
        double tmax = 0.0, val;
        int over;
        required_thrust(sc, tf, r, v, T, m);
        for (k = 0; k < N; ++k) {
            const double tn = norm3(T + 3 * k);
            tmax = tn > tmax ? tn : tmax;
        }
        over = tmax > p->T_max;
        val = over ? tmax : sc->m0 - m[N - 1];
        if (!have || over < best_over || (over == best_over && val < best_val)) {
            have = 1;
            best_over = over;
            best_val = val;
            t_f = tf;
        }
    }
    return t_f;
}

/* q (N x 4): body axis 1 from the initial one, along the thrust T, to upright at the end
 * (d: N x 3 scratch) */
static void attitude_along_thrust(const pdg_scenario *sc, const double *T, double *d,
                                  double *q)
{
    const int N = sc->params.N;
    double C0[3][3], b0[3];
    int i, k, j;
    pdg_dcm_bi(sc->q0, C0); /* C_BI; C_IB = C0^T, so b0 = first column of C_IB = row 0 */
    for (i = 0; i < 3; ++i) {
        b0[i] = C0[0][i];
    }
    for (k = 0; k < N; ++k) {
        const double s = node_s(k, N);
        const double ws = smoothstep(1.0 - s / BLEND_FRACTION);
        const double we = smoothstep((s - (1.0 - BLEND_FRACTION)) / BLEND_FRACTION);
        double tn = norm3(T + 3 * k), dn;
        double *dk = d + 3 * k, R[3][3], CBI[3][3];
        tn = tn > 1e-9 ? tn : 1e-9;
        for (i = 0; i < 3; ++i) {
            dk[i] = ws * b0[i] + we * (i == 0 ? 1.0 : 0.0) + (1.0 - ws - we) * (T[3 * k + i] / tn);
        }
        dn = norm3(dk);
        dn = dn > 1e-9 ? dn : 1e-9;
        for (i = 0; i < 3; ++i) {
            dk[i] /= dn;
        }
        /* q_k from ((min_rotation(b0, d_k) C_IB0)^T) = C_BI0 R^T */
        min_rotation(b0, dk, R);
        for (i = 0; i < 3; ++i) {
            for (j = 0; j < 3; ++j) {
                double acc = 0.0;
                int l;
                for (l = 0; l < 3; ++l) {
                    acc += R[j][l] * C0[i][l]; /* (R C_IB)[j][i] = sum_l R[j][l] C_IB[l][i] */
                }
                CBI[i][j] = acc;
            }
        }
        quat_from_dcm_bi(CBI, q + 4 * k);
    }
}

/* q_k := -q_k where it points away from `ref` (the same attitude) */
static void same_hemisphere(double *qk, const double *ref)
{
    double dot = 0.0;
    int i;
    for (i = 0; i < 4; ++i) {
        dot += qk[i] * ref[i];
    }
    if (dot < 0) {
        for (i = 0; i < 4; ++i) {
            qk[i] = -qk[i];
        }
    }
}

/* Pinned final attitude: q blended into q_f over the last BLEND_FRACTION, renormalized */
static void blend_to_final_attitude(const pdg_params *p, double *q)
{
    int k, i;
    for (k = 0; k < p->N; ++k) {
        const double s = node_s(k, p->N);
        const double we = smoothstep((s - (1.0 - BLEND_FRACTION)) / BLEND_FRACTION);
        double dot = 0.0, sg, nq;
        for (i = 0; i < 4; ++i) {
            dot += q[4 * k + i] * p->q_f[i];
        }
        sg = dot < 0 ? -1.0 : 1.0;
        for (i = 0; i < 4; ++i) {
            q[4 * k + i] = (1.0 - we) * q[4 * k + i] + we * sg * p->q_f[i];
        }
        nq = sqrt(q[4 * k] * q[4 * k] + q[4 * k + 1] * q[4 * k + 1] +
                  q[4 * k + 2] * q[4 * k + 2] + q[4 * k + 3] * q[4 * k + 3]);
        for (i = 0; i < 4; ++i) {
            q[4 * k + i] /= nq;
        }
    }
}

/* omega (N x 3) at the times t: least squares of q' = 1/2 Omega(omega) q, i.e.
 * 2 M(q)' q' / |q|^2; the roll rate stays w0's (no roll torque) */
static void body_rates(const pdg_scenario *sc, const double *q, const double *t, double *w)
{
    const int N = sc->params.N;
    int k, i, j;
    for (k = 0; k < N; ++k) {
        const double *qk = q + 4 * k;
        double dq[4], nq2 = 0.0;
        for (i = 0; i < 4; ++i) {
            dq[i] = gradient_at(q + i, 4, t, N, k);
            nq2 += qk[i] * qk[i];
        }
        {
            const double M[4][3] = {{-qk[1], -qk[2], -qk[3]},
                                    {qk[0], -qk[3], qk[2]},
                                    {qk[3], qk[0], -qk[1]},
                                    {-qk[2], qk[1], qk[0]}};
            for (j = 0; j < 3; ++j) {
                double acc = 0.0;
                for (i = 0; i < 4; ++i) {
                    acc += M[i][j] * dq[i];
                }
                w[3 * k + j] = 2.0 * acc / nq2;
            }
        }
        w[3 * k] = sc->w0[0];
    }
}

/* The lateral thrust (u2, u3) whose gimbal torque gives the rates w at the times t:
 * r_T x T_B = J w' + w x J w (wd: N x 3 scratch) */
static void gimbal_for_rates(const pdg_params *p, const double *w, const double *t, double *wd,
                             double *u)
{
    int k, i;
    for (k = 0; k < p->N; ++k) {
        const double *wk = w + 3 * k;
        double Jw[3], wxJw[3], tau[3];
        for (i = 0; i < 3; ++i) {
            wd[i] = gradient_at(w + i, 3, t, p->N, k);
            Jw[i] = p->J_B[i] * wk[i];
        }
        cross(wk, Jw, wxJw);
        for (i = 0; i < 3; ++i) {
            tau[i] = p->J_B[i] * wd[i] + wxJw[i];
        }
        u[3 * k + 1] = tau[2] / p->r_T_B[0];
        u[3 * k + 2] = -tau[1] / p->r_T_B[0];
    }
}

void pdg_initial_guess(const pdg_scenario *sc, double *x, double *u, double *t_f_out,
                       double *work)
{
    const pdg_params *p = &sc->params;
    const int N = p->N;
    double *r = work, *v = r + 3 * N, *T = v + 3 * N, *m = T + 3 * N, *d = m + N;
    double *q = d + 3 * N, *t = q + 4 * N, *w = t + N, *wd = w + 3 * N; /* 25 N doubles */
    double t_f;
    int i, k;

    t_f = cheapest_t_f(sc, r, v, T, m);
    required_thrust(sc, t_f, r, v, T, m);
    attitude_along_thrust(sc, T, d, q);
    same_hemisphere(q, sc->q0); /* sign continuity from q0 */
    for (k = 1; k < N; ++k) {
        same_hemisphere(q + 4 * k, q + 4 * (k - 1));
    }
    if (!p->final_roll_free) {
        blend_to_final_attitude(p, q);
    }
    for (k = 0; k < N; ++k) {
        t[k] = node_s(k, N) * t_f;
    }
    body_rates(sc, q, t, w);
    for (k = 0; k < N; ++k) { /* the states, and the thrust T_I in the body frame */
        double *xk = x + NX * k, C[3][3];
        for (i = 0; i < 3; ++i) {
            xk[i] = r[3 * k + i];
            xk[3 + i] = v[3 * k + i];
            xk[10 + i] = w[3 * k + i];
        }
        for (i = 0; i < 4; ++i) {
            xk[6 + i] = q[4 * k + i];
        }
        xk[IM] = m[k] > p->m_dry ? m[k] : p->m_dry;
        pdg_dcm_bi(q + 4 * k, C);
        for (i = 0; i < 3; ++i) {
            u[3 * k + i] = C[i][0] * T[3 * k] + C[i][1] * T[3 * k + 1] + C[i][2] * T[3 * k + 2];
        }
    }
    gimbal_for_rates(p, w, t, wd, u);
    *t_f_out = t_f;
    pdg_project_guess(sc, x, u, t_f_out);
}

/* The boundary conditions on the first and last node: x_0 the initial state; r, v, omega and
 * q (q2 = q3 = 0 when the final roll is free) the final target's */
static void pin_boundary(const pdg_scenario *sc, double *x)
{
    const pdg_params *p = &sc->params;
    double xf[NX], *xl = x + NX * (p->N - 1);
    int i;
    pdg_x_final_target(sc, xf);
    pdg_initial_state(sc, x);
    for (i = 0; i < 6; ++i) {
        xl[i] = xf[i];
    }
    for (i = 10; i < 13; ++i) {
        xl[i] = xf[i];
    }
    if (p->final_roll_free) {
        xl[8] = xl[9] = 0.0;
    } else {
        for (i = 6; i < 10; ++i) {
            xl[i] = xf[i];
        }
    }
}

/* One node's state into the convex constraints: q normalized and within the tilt limit,
 * omega within omega_max, the mass within [m_dry, m0], r1 above the glideslope */
static void project_state(const pdg_scenario *sc, double *xk)
{
    const pdg_params *p = &sc->params;
    const double qmax = pdg_tilt_q_max(p), wmax = pdg_omega_max(p);
    const double tg = pdg_tan_glideslope(p);
    double *q = xk + 6, nq, tilt, wn, horiz;
    int i;
    nq = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    nq = nq > 1e-12 ? nq : 1e-12;
    for (i = 0; i < 4; ++i) {
        q[i] /= nq;
    }
    tilt = sqrt(q[2] * q[2] + q[3] * q[3]);
    if (tilt > qmax) { /* shrink (q2, q3) onto the tilt limit, keep (q0, q1) direction */
        const double rest = sqrt(q[0] * q[0] + q[1] * q[1]);
        const double room = sqrt(1.0 - qmax * qmax);
        q[2] *= qmax / tilt;
        q[3] *= qmax / tilt;
        if (rest > 1e-12) {
            q[0] = q[0] / rest * room;
            q[1] = q[1] / rest * room;
        } else {
            q[0] = room;
            q[1] = 0.0;
        }
    }
    wn = norm3(xk + 10);
    wn = wmax / (wn > 1e-12 ? wn : 1e-12);
    wn = wn < 1.0 ? wn : 1.0;
    for (i = 10; i < 13; ++i) {
        xk[i] *= wn;
    }
    /* the mass only falls: within [m_dry, m0] (a prediction above m0 is hundreds of trust
     * radii away in the scaled mass, (m - m_dry) / (m0 - m_dry), when little propellant is
     * left) */
    xk[IM] = xk[IM] > p->m_dry ? xk[IM] : p->m_dry;
    xk[IM] = xk[IM] < sc->m0 ? xk[IM] : sc->m0;
    horiz = sqrt(xk[1] * xk[1] + xk[2] * xk[2]);
    xk[0] = xk[0] > tg * horiz ? xk[0] : tg * horiz;
}

/* One node's thrust: into the gimbal cone about body axis 1, then into [T_min, T_max] */
static void project_thrust(const pdg_params *p, double *uk)
{
    const double cg = pdg_cos_gimbal(p);
    const double tan_d = tan(acos(cg)), cone0 = cg, cone1 = sqrt(1 - cg * cg);
    const double lateral = sqrt(uk[1] * uk[1] + uk[2] * uk[2]);
    const double axial = uk[0] > 0.0 ? uk[0] : 0.0;
    double new_axial = uk[0], new_lat = lateral, scale_lat, un, cl;
    int i;
    if (lateral > tan_d * axial) {
        double proj = uk[0] * cone0 + lateral * cone1;
        proj = proj > 1e-9 ? proj : 1e-9;
        new_axial = proj * cone0;
        new_lat = proj * cone1;
    }
    scale_lat = lateral > 1e-12 ? new_lat / lateral : 0.0;
    uk[0] = new_axial;
    uk[1] *= scale_lat;
    uk[2] *= scale_lat;
    un = norm3(uk);
    un = un > 1e-12 ? un : 1e-12;
    cl = un < p->T_min ? p->T_min : (un > p->T_max ? p->T_max : un);
    for (i = 0; i < 3; ++i) {
        uk[i] *= cl / un;
    }
}

void pdg_project_guess(const pdg_scenario *sc, double *x, double *u, double *t_f)
{
    int k;
    pin_boundary(sc, x);
    for (k = 0; k < sc->params.N; ++k) {
        /* node 0 is the initial state as given (checked at input): normalizing its q again
         * moved it by an ulp off the subproblem's boundary condition */
        if (k > 0) project_state(sc, x + NX * k);
        project_thrust(&sc->params, u + 3 * k);
    }
    *t_f = *t_f > 1e-2 ? *t_f : 1e-2;
}

/* The message (PDG_MESSAGE_LEN bytes, may be NULL) of a refused call; PDG_INVALID_INPUT. */
/* Largest |v_i| of n finite numbers. */
static double max_abs(const double *v, size_t n)
{
    double m = 0.0;
    size_t i;
    for (i = 0; i < n; ++i) {
        const double a = fabs(v[i]);
        m = a > m ? a : m;
    }
    return m;
}

static int refuse(char *message, const char *text)
{
    if (message) {
        snprintf(message, PDG_MESSAGE_LEN, "plan remainder: %s", text);
    }
    return PDG_INVALID_INPUT;
}

/* In-flight re-planning: the plan (x, u, t_f on the scenario's N nodes from t = 0) from time
 * t1 on, on N nodes over [t1, t_f] -- the states linearly interpolated between the plan's
 * nodes, the thrust as its first-order hold (exactly) -- then projected as every guess is, so
 * that node 0 is the scenario's initial state (the state measured at t1). The arithmetic of
 * guidance/guess.py plan_remainder, operation for operation. */
int pdg_plan_remainder(const pdg_scenario *scenario, const double *x, const double *u,
                       double t_f, double t1, double *gx, double *gu, double *gt_f,
                       char *message)
{
    int N, k, i;
    double h;
    if (!scenario || !x || !u || !gx || !gu || !gt_f) {
        return refuse(message, "a required pointer is NULL");
    }
    if (pdg_validate_scenario(scenario, message) != 0) {
        return PDG_INVALID_INPUT;
    }
    N = scenario->params.N;
    if (!pdg_all_finite(x, (size_t)N * NX) || !pdg_all_finite(u, (size_t)N * NU) ||
        !isfinite(t_f) || !(t_f > 0.0)) {
        return refuse(message, "x, u and t_f must be finite and t_f positive");
    }
    if (max_abs(x, (size_t)N * NX) > PDG_PLAN_VALUE_MAX ||
        max_abs(u, (size_t)N * NU) > PDG_PLAN_VALUE_MAX) {
        return refuse(message, "x, u: values beyond 1e9, outside any landing");
    }
    if (!(t_f >= PDG_PLAN_T_F_MIN && t_f <= PDG_PLAN_T_F_MAX)) {
        char text[160];
        snprintf(text, sizeof text, "t_f = %g is outside [%g, %g] U_T, no landing's", t_f,
                 PDG_PLAN_T_F_MIN, PDG_PLAN_T_F_MAX);
        return refuse(message, text);
    }
    if (!(t1 >= 0.0 && t1 < t_f)) { /* NaN fails too */
        char text[160];
        snprintf(text, sizeof text, "t1 = %g is not within the plan's [0, %g) U_T", t1, t_f);
        return refuse(message, text);
    }
    h = t_f / (N - 1);
    for (k = 0; k < N; ++k) {
        const double t = t1 + (t_f - t1) * node_s(k, N);
        int j = (int)(t / h); /* the plan's interval holding t (t >= 0: truncation floors) */
        double a;
        j = j < N - 2 ? j : N - 2;
        a = (t - j * h) / h;
        a = a < 0.0 ? 0.0 : (a > 1.0 ? 1.0 : a);
        for (i = 0; i < NX; ++i) {
            gx[NX * k + i] = x[NX * j + i] + a * (x[NX * (j + 1) + i] - x[NX * j + i]);
        }
        for (i = 0; i < NU; ++i) {
            gu[NU * k + i] = u[NU * j + i] + a * (u[NU * (j + 1) + i] - u[NU * j + i]);
        }
    }
    *gt_f = t_f - t1;
    pdg_project_guess(scenario, gx, gu, gt_f);
    return 0;
}
