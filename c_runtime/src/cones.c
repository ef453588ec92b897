/* Cone operations on K = R_+^l x Q^{q_1} x ... x Q^{q_nsoc}.
 *
 * SOC algebra (Jordan algebra of Q^q, u = (u0, u1)):
 *   u o v = (u'v, u0 v1 + v0 u1),  e = (1, 0),  det u = u0^2 - |u1|^2,  J = diag(1, -I).
 * Nesterov-Todd scaling (Vandenberghe, "The CVXOPT linear and quadratic cone program
 * solvers", sec. 4; ECOS paper sec. 3): with sbar = s/sqrt(det s), zbar = z/sqrt(det z),
 *   gamma = sqrt((1 + sbar'zbar)/2),  wbar = (sbar + J zbar)/(2 gamma)   (det wbar = 1),
 *   eta = (det s / det z)^{1/4},  W = eta Wbar,
 *   Wbar = [wbar0, wbar1'; wbar1, I + wbar1 wbar1'/(1 + wbar0)],  Wbar^{-1} = J Wbar J,
 *   W'W = eta^2 (2 wbar wbar' - J),  lambda = W z = W^{-1} s.
 */
#include <math.h>

#include "socp_internal.h"

/* f(q, ...) with q the constant 3 or 4 where it is one (the landing's cones), so that GCC
 * unrolls the short loops of the inlined kernel: the same operations in the same order. */
#define BY_SIZE(f, q, ...) \
    ((q) == 3 ? f(3, __VA_ARGS__) : (q) == 4 ? f(4, __VA_ARGS__) : f((q), __VA_ARGS__))
#if defined(__GNUC__)
#define SOC_KERNEL static inline __attribute__((always_inline))
#else
#define SOC_KERNEL static inline
#endif

SOC_KERNEL tscvx_float norm2(const tscvx_float *u, tscvx_int n) {
    return sqrt(tscvx_dot(u, u, n));
}

/* det u = u0^2 - |u1|^2, written as (u0 - |u1|)(u0 + |u1|) against cancellation */
SOC_KERNEL tscvx_float soc_det(const tscvx_float *u, tscvx_int q) {
    tscvx_float r = norm2(u + 1, q - 1);
    return (u[0] - r) * (u[0] + r);
}

/* u o v on one SOC (out may be u or v) */
SOC_KERNEL void soc_prod(tscvx_int q, const tscvx_float *u, const tscvx_float *v,
                         tscvx_float *out) {
    const tscvx_float u0 = u[0], v0 = v[0];
    const tscvx_float uv = tscvx_dot(u, v, q);
    for (tscvx_int j = 1; j < q; j++) out[j] = u0 * v[j] + v0 * u[j];
    out[0] = uv;
}

void tscvx_cone_prod(const tscvx_cones *K, const tscvx_float *u, const tscvx_float *v,
                     tscvx_float *out) {
    for (tscvx_int i = 0; i < K->l; i++) out[i] = u[i] * v[i];
    for (tscvx_int k = 0; k < K->nsoc; k++) {
        const tscvx_int o = K->off[k];
        BY_SIZE(soc_prod, K->q[k], u + o, v + o, out + o);
    }
}

/* u o w = v:  w0 = (u0 v0 - u1'v1)/det u,  w1 = (v1 - w0 u1)/u0  (one SOC; out may be v) */
SOC_KERNEL void soc_div(tscvx_int q, const tscvx_float *u, const tscvx_float *v,
                        tscvx_float *out) {
    const tscvx_float u0 = u[0];
    const tscvx_float w0 = (u0 * v[0] - tscvx_dot(u + 1, v + 1, q - 1)) / soc_det(u, q);
    for (tscvx_int j = 1; j < q; j++) out[j] = (v[j] - w0 * u[j]) / u0;
    out[0] = w0;
}

void tscvx_cone_div(const tscvx_cones *K, const tscvx_float *u, const tscvx_float *v,
                    tscvx_float *out) {
    for (tscvx_int i = 0; i < K->l; i++) out[i] = v[i] / u[i];
    for (tscvx_int k = 0; k < K->nsoc; k++) {
        const tscvx_int o = K->off[k];
        BY_SIZE(soc_div, K->q[k], u + o, v + o, out + o);
    }
}

/* NT scaling of one SOC: w = wbar, *eta, lambda = W z; -1 if s or z is not interior */
SOC_KERNEL int soc_nt(tscvx_int q, const tscvx_float *s, const tscvx_float *z,
                      tscvx_float *w, tscvx_float *eta, tscvx_float *lam) {
    const tscvx_float sdet = soc_det(s, q), zdet = soc_det(z, q);
    if (!(sdet > 0.0) || !(zdet > 0.0) || !(s[0] > 0.0) || !(z[0] > 0.0)) return -1;
    const tscvx_float sn = sqrt(sdet), zn = sqrt(zdet);
    /* w = sbar + J zbar, normalized: |w|_J = 2 gamma */
    w[0] = s[0] / sn + z[0] / zn;
    for (tscvx_int j = 1; j < q; j++) w[j] = s[j] / sn - z[j] / zn;
    const tscvx_float wdet = soc_det(w, q);
    if (!(wdet > 0.0)) return -1;
    const tscvx_float wn = sqrt(wdet), gamma = 0.5 * wn;
    for (tscvx_int j = 1; j < q; j++) w[j] /= wn;
    w[0] = sqrt(1.0 + tscvx_dot(w + 1, w + 1, q - 1)); /* det wbar = 1 exactly */
    *eta = sqrt(sn / zn);
    /* lambda = W z without cancellation (CVXOPT cone notes):
     *  lambda0 = gamma,  lambda1 = (c1 s1 + c2 z1)/(sbar0 + zbar0 + 2 gamma),
     *  c1 = (gamma + zbar0)/|s|_J, c2 = (gamma + sbar0)/|z|_J, all times sqrt(|s|_J |z|_J) */
    const tscvx_float scale = sqrt(sn * zn);
    const tscvx_float coef = 1.0 / (s[0] / sn + z[0] / zn + 2.0 * gamma);
    const tscvx_float c1 = (gamma + z[0] / zn) / sn, c2 = (gamma + s[0] / sn) / zn;
    lam[0] = gamma * scale;
    for (tscvx_int j = 1; j < q; j++) lam[j] = scale * coef * (c1 * s[j] + c2 * z[j]);
    return 0;
}

int tscvx_nt_scaling(const tscvx_cones *K, const tscvx_float *s, const tscvx_float *z,
                     tscvx_nt *W, tscvx_float *lambda) {
    for (tscvx_int i = 0; i < K->l; i++) {
        if (!(s[i] > 0.0) || !(z[i] > 0.0)) return -1;
        W->w[i] = sqrt(s[i] / z[i]);
        lambda[i] = sqrt(s[i] * z[i]);
    }
    for (tscvx_int k = 0; k < K->nsoc; k++) {
        const tscvx_int o = K->off[k];
        if (BY_SIZE(soc_nt, K->q[k], s + o, z + o, W->w + o, W->eta + k, lambda + o) != 0)
            return -1;
    }
    return 0;
}

/* out = W v (or W^{-1} v) on one SOC (out != v): eta Wbar v, Wbar^{-1} = J Wbar J */
SOC_KERNEL void soc_apply(tscvx_int q, const tscvx_float *w, tscvx_float eta, int inverse,
                          const tscvx_float *v, tscvx_float *out) {
    const tscvx_float sgn = inverse ? -1.0 : 1.0;
    const tscvx_float scale = inverse ? 1.0 / eta : eta;
    const tscvx_float w1v1 = tscvx_dot(w + 1, v + 1, q - 1);
    const tscvx_float v0 = v[0];
    const tscvx_float coef = sgn * v0 + w1v1 / (1.0 + w[0]);
    for (tscvx_int j = 1; j < q; j++) out[j] = scale * (v[j] + coef * w[j]);
    out[0] = scale * (w[0] * v0 + sgn * w1v1);
}

/* out = W (W v) on one SOC (work: W v) */
SOC_KERNEL void soc_apply2(tscvx_int q, const tscvx_float *w, tscvx_float eta,
                           const tscvx_float *v, tscvx_float *work, tscvx_float *out) {
    soc_apply(q, w, eta, 0, v, work);
    soc_apply(q, w, eta, 0, work, out);
}

/* out = W (u \ v) on one SOC (work: u \ v) */
SOC_KERNEL void soc_div_apply(tscvx_int q, const tscvx_float *w, tscvx_float eta,
                              const tscvx_float *u, const tscvx_float *v, tscvx_float *work,
                              tscvx_float *out) {
    soc_div(q, u, v, work);
    soc_apply(q, w, eta, 0, work, out);
}

void tscvx_nt_apply(const tscvx_cones *K, const tscvx_nt *W, int inverse, const tscvx_float *v,
                    tscvx_float *out) {
    if (inverse)
        for (tscvx_int i = 0; i < K->l; i++) out[i] = v[i] / W->w[i];
    else
        for (tscvx_int i = 0; i < K->l; i++) out[i] = v[i] * W->w[i];
    for (tscvx_int k = 0; k < K->nsoc; k++) {
        const tscvx_int o = K->off[k];
        BY_SIZE(soc_apply, K->q[k], W->w + o, W->eta[k], inverse, v + o, out + o);
    }
}

void tscvx_nt_apply2(const tscvx_cones *K, const tscvx_nt *W, const tscvx_float *v,
                     tscvx_float *work, tscvx_float *out) {
    for (tscvx_int i = 0; i < K->l; i++) {
        const tscvx_float t = v[i] * W->w[i];
        out[i] = t * W->w[i];
    }
    for (tscvx_int k = 0; k < K->nsoc; k++) {
        const tscvx_int o = K->off[k];
        BY_SIZE(soc_apply2, K->q[k], W->w + o, W->eta[k], v + o, work + o, out + o);
    }
}

void tscvx_nt_div_apply(const tscvx_cones *K, const tscvx_nt *W, const tscvx_float *u,
                        const tscvx_float *v, tscvx_float *work, tscvx_float *out) {
    for (tscvx_int i = 0; i < K->l; i++) {
        const tscvx_float t = v[i] / u[i];
        out[i] = t * W->w[i];
    }
    for (tscvx_int k = 0; k < K->nsoc; k++) {
        const tscvx_int o = K->off[k];
        BY_SIZE(soc_div_apply, K->q[k], W->w + o, W->eta[k], u + o, v + o, work + o, out + o);
    }
}

/* SOC: with f(a) = det(u + a du) = A a^2 + 2 B a + C, C > 0, the boundary is first met at
 * a = C / (sqrt(B^2 - A C) - B) unless du is in K (then never). Returns the step limit
 * min(alpha, that), or -1 when u is not interior. */
SOC_KERNEL tscvx_float soc_max_step(tscvx_int q, const tscvx_float *u, const tscvx_float *du,
                                    tscvx_float alpha) {
    const tscvx_float dn = norm2(du + 1, q - 1);
    if (du[0] >= dn) return alpha; /* direction inside the cone */
    const tscvx_float A = (du[0] - dn) * (du[0] + dn);
    const tscvx_float B = u[0] * du[0] - tscvx_dot(u + 1, du + 1, q - 1);
    const tscvx_float C = soc_det(u, q);
    if (!(C > 0.0)) return -1.0;
    tscvx_float disc = B * B - A * C;
    if (disc < 0.0) disc = 0.0;
    const tscvx_float den = sqrt(disc) - B;
    return den > 0.0 && C < alpha * den ? C / den : alpha;
}

tscvx_float tscvx_cone_max_step(const tscvx_cones *K, const tscvx_float *u,
                                const tscvx_float *du, tscvx_float alpha_max) {
    tscvx_float alpha = alpha_max;
    for (tscvx_int i = 0; i < K->l; i++)
        if (du[i] < 0.0 && u[i] < alpha * -du[i]) alpha = -u[i] / du[i];
    for (tscvx_int k = 0; k < K->nsoc; k++) {
        const tscvx_int o = K->off[k];
        alpha = BY_SIZE(soc_max_step, K->q[k], u + o, du + o, alpha);
        if (alpha < 0.0) return 0.0;
    }
    return alpha;
}

tscvx_float tscvx_cone_shift_needed(const tscvx_cones *K, const tscvx_float *u) {
    tscvx_float t = -INFINITY;
    for (tscvx_int i = 0; i < K->l; i++)
        if (-u[i] > t) t = -u[i];
    for (tscvx_int k = 0; k < K->nsoc; k++) {
        const tscvx_int o = K->off[k], q = K->q[k];
        const tscvx_float v = norm2(u + o + 1, q - 1) - u[o];
        if (v > t) t = v;
    }
    return t;
}

void tscvx_cone_add_identity(const tscvx_cones *K, tscvx_float *u, tscvx_float t) {
    for (tscvx_int i = 0; i < K->l; i++) u[i] += t;
    for (tscvx_int k = 0; k < K->nsoc; k++) u[K->off[k]] += t;
}

void tscvx_cone_copy_interior(const tscvx_cones *K, const tscvx_float *u, tscvx_float *dst) {
    for (tscvx_int i = 0; i < K->l; i++)
        if (u[i] > 0.0) dst[i] = u[i];
    for (tscvx_int k = 0; k < K->nsoc; k++) {
        const tscvx_int o = K->off[k], q = K->q[k];
        if (norm2(u + o + 1, q - 1) < u[o])
            for (tscvx_int j = 0; j < q; j++) dst[o + j] = u[o + j];
    }
}

/* Centring of a warm point, one cone at a time: s += a e, z += b e with
 *   a = mu / (2 max(z_0, sqrt mu)),  b = mu / (2 max(s_0, sqrt mu)),
 * so s'z grows by a z_0 + b s_0 + ab (e'z = z_0 on each cone), between mu/4 and 5 mu/4
 * whatever the sizes of s and z: a complementary pair (s'z = 0) leaves each cone with
 * complementarity of the order of mu. Used on s and z in K, it leaves them strictly inside. */
void tscvx_cone_center_pair(const tscvx_cones *K, tscvx_float *s, tscvx_float *z,
                            tscvx_float mu) {
    const tscvx_float rt = sqrt(mu);
    for (tscvx_int c = 0; c < K->l + K->nsoc; c++) {
        const tscvx_int o = c < K->l ? c : K->off[c - K->l];
        const tscvx_float s0 = s[o], z0 = z[o];
        s[o] = s0 + mu / (2.0 * (z0 > rt ? z0 : rt));
        z[o] = z0 + mu / (2.0 * (s0 > rt ? s0 : rt));
    }
}
