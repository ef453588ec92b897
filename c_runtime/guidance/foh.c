/* First-order-hold discretization of one interval: a bounded loop over the generated RK4
 * step of the augmented system (see foh.h). */
#include "foh.h"

#include <math.h>
#include <stddef.h>

#include "tscvx_model.h"

static const unsigned char phi_a_patterns[TSCVX_PHI_A_NPATTERNS][PDG_NX * PDG_NX] =
    TSCVX_PHI_A_PATTERNS;
static const int phi_a_nnz[TSCVX_PHI_A_NPATTERNS] = TSCVX_PHI_A_NNZ;

const unsigned char *pdg_phi_a_pattern(const double *p, int *nnz)
{
    const int i = tscvx_phi_a_pattern_index(p);
    if (nnz) {
        *nnz = phi_a_nnz[i];
    }
    return phi_a_patterns[i];
}

static void initial_augmented_state(const double *x_k, double *P)
{
    int i;
    for (i = 0; i < PDG_NAUG; ++i) {
        P[i] = 0.0;
    }
    for (i = 0; i < PDG_NX; ++i) {
        P[PDG_AUG_X + i] = x_k[i];
        P[PDG_AUG_A + i * PDG_NX + i] = 1.0; /* Phi_A(0) = I */
    }
}

/* The augmented state at tau = dtau into aug: `substeps` RK4 steps of the generated
 * tscvx_foh_step from initial_augmented_state, ping-ponging between aug and work. 0, or -2
 * when the generated code fails. */
static int integrate(const double *x_k, const double *u_k, const double *u_k1, double sigma,
                     double dtau, const double *p, int substeps, double *aug, double *work)
{
    const double *arg[tscvx_foh_step_SZ_ARG];
    double *res[tscvx_foh_step_SZ_RES];
    double *cur = aug;
    double *next = work;
    double s = 0.0;
    const double h = dtau / substeps;
    int step, i;

    initial_augmented_state(x_k, cur);
    for (step = 0; step < substeps; ++step) {
        s = step * h;
        arg[0] = cur;
        arg[1] = &s;
        arg[2] = &h;
        arg[3] = u_k;
        arg[4] = u_k1;
        arg[5] = &sigma;
        arg[6] = &dtau;
        arg[7] = p;
        res[0] = next;
        if (tscvx_foh_step(arg, res, NULL, NULL, 0) != 0) {
            return -2;
        }
        { /* ping-pong the two buffers */
            double *t = cur;
            cur = next;
            next = t;
        }
    }
    if (cur != aug) {
        for (i = 0; i < PDG_NAUG; ++i) {
            aug[i] = cur[i];
        }
    }
    return 0;
}

/* z_k = x(dtau) - A x_k - B- u_k - B+ u_k1 - Sigma sigma (column-major blocks of aug) */
static void defect(const double *aug, const double *x_k, const double *u_k, const double *u_k1,
                   double sigma, double *z)
{
    int i, j;
    for (i = 0; i < PDG_NX; ++i) {
        double v = aug[PDG_AUG_X + i] - aug[PDG_AUG_S + i] * sigma;
        for (j = 0; j < PDG_NX; ++j) {
            v -= aug[PDG_AUG_A + j * PDG_NX + i] * x_k[j];
        }
        for (j = 0; j < PDG_NU; ++j) {
            v -= aug[PDG_AUG_BM + j * PDG_NX + i] * u_k[j] + aug[PDG_AUG_BP + j * PDG_NX + i] * u_k1[j];
        }
        z[i] = v;
    }
}

/* 0 when every entry is finite and A_k is exactly zero off the vehicle's structural pattern
 * (it is, for finite numbers: the subproblem leaves those entries out); -2 otherwise. */
static int check_result(const double *aug, const double *p)
{
    const unsigned char *pattern;
    int i, j;
    for (i = 0; i < PDG_NAUG; ++i) {
        if (!isfinite(aug[i])) {
            return -2;
        }
    }
    pattern = pdg_phi_a_pattern(p, NULL);
    for (i = 0; i < PDG_NX; ++i) {
        for (j = 0; j < PDG_NX; ++j) {
            if (!pattern[PDG_NX * i + j] && aug[PDG_AUG_A + j * PDG_NX + i] != 0.0) {
                return -2;
            }
        }
    }
    return 0;
}

/* The coarsest grid (N = 3) needs no more steps per interval than pdg_foh_interval takes. */
typedef char pdg_rk4_steps_fit[(PDG_RK4_MIN_STEPS_TOTAL + 1) / 2 <= PDG_MAX_SUBSTEPS ? 1 : -1];

int pdg_rk4_steps(int substeps, int N)
{
    int need;
    if (N < 3) {
        return substeps;
    }
    need = (PDG_RK4_MIN_STEPS_TOTAL + N - 2) / (N - 1); /* ceil(total / (N - 1)) */
    return substeps > need ? substeps : need;
}

int pdg_foh_interval(const double *x_k, const double *u_k, const double *u_k1, double sigma,
                     double dtau, const double *p, int substeps, double *aug, double *z,
                     double *work)
{
    if (!x_k || !u_k || !u_k1 || !p || !aug || !z || !work || substeps < 1 ||
        substeps > PDG_MAX_SUBSTEPS || !(dtau > 0.0) || !(sigma > 0.0)) {
        return -1;
    }
    if (integrate(x_k, u_k, u_k1, sigma, dtau, p, substeps, aug, work) != 0) {
        return -2;
    }
    defect(aug, x_k, u_k, u_k1, sigma, z);
    return check_result(aug, p);
}

int pdg_foh_all(int N, const double *x, const double *u, double sigma, const double *p,
                int substeps, double *aug, double *z, double *work)
{
    int k;
    if (N < 2 || N > PDG_MAX_NODES || !x || !u || !aug || !z) {
        return -1;
    }
    for (k = 0; k < N - 1; ++k) {
        int status = pdg_foh_interval(x + k * PDG_NX, u + k * PDG_NU, u + (k + 1) * PDG_NU, sigma,
                                      1.0 / (N - 1), p, substeps, aug + k * PDG_NAUG,
                                      z + k * PDG_NX, work);
        if (status != 0) {
            return status;
        }
    }
    return 0;
}
