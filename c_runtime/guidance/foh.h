/*
 * foh.h -- first-order-hold discretization of one interval from the generated model.
 *
 * The augmented state P = (x, Phi_A, Phi_m, Phi_p, Phi_s) (14 + 196 + 42 + 42 + 14 = 308
 * numbers, matrices column-major) is advanced by `substeps` RK4 steps of the CasADi-generated
 * tscvx_foh_step (paper Eq. (10)'s discretization; see guidance/model.py). Then
 *     A_k = Phi_A, B-_k = Phi_m, B+_k = Phi_p, Sigma_k = Phi_s,
 *     z_k = x(dtau) - A_k x_k - B-_k u_k - B+_k u_k1 - Sigma_k sigma.
 */
#ifndef TSCVX_FOH_H
#define TSCVX_FOH_H

#define PDG_NX 14
#define PDG_NU 3
#define PDG_NP 13
#define PDG_NAUG (PDG_NX + PDG_NX * PDG_NX + 2 * PDG_NX * PDG_NU + PDG_NX)
#define PDG_MAX_SUBSTEPS 64
#define PDG_MAX_NODES 400
/* RK4 steps over the whole normalized time [0, 1] at least: 2 per interval at N = 50, the grid
 * the default rk4_substeps = 2 was chosen for (guidance/params.py RK4_MIN_STEPS_TOTAL). */
#define PDG_RK4_MIN_STEPS_TOTAL 98

/* Offsets of the blocks inside the augmented state. */
#define PDG_AUG_X 0
#define PDG_AUG_A (PDG_AUG_X + PDG_NX)
#define PDG_AUG_BM (PDG_AUG_A + PDG_NX * PDG_NX)
#define PDG_AUG_BP (PDG_AUG_BM + PDG_NX * PDG_NU)
#define PDG_AUG_S (PDG_AUG_BP + PDG_NX * PDG_NU)

/* The structural nonzeros of A_k for the parameter vector p (PDG_NP), row-major NX x NX, and
 * their count in *nnz (may be NULL): guidance.model.vehicle_pattern, generated. Every other
 * entry is 0.0 for finite numbers, and the subproblem leaves it out. Parameter vectors of one
 * pattern get the same pointer. */
const unsigned char *pdg_phi_a_pattern(const double *p, int *nnz);

/* RK4 steps of each of the N - 1 intervals (3 <= N <= PDG_MAX_NODES, the workspace's grids):
 * `substeps` at least, and enough for PDG_RK4_MIN_STEPS_TOTAL over all of them, so that a
 * coarse grid's steps are no longer than N = 50's (at most 49, at N = 3, within
 * PDG_MAX_SUBSTEPS): a step's error grows like its length^5. N < 3 gives `substeps`. */
int pdg_rk4_steps(int substeps, int N);

/* Discretizes one interval. `aug` (PDG_NAUG) receives x(dtau), A_k, B-_k, B+_k, Sigma_k;
 * `z` (PDG_NX) the defect term; `work` must hold PDG_NAUG doubles. Returns 0, or -1 for a bad
 * argument (NULL pointer, substeps outside [1, PDG_MAX_SUBSTEPS], dtau <= 0, sigma <= 0) and
 * -2 when the model evaluation fails, produces a non-finite number or a nonzero off
 * pdg_phi_a_pattern(p). */
int pdg_foh_interval(const double *x_k, const double *u_k, const double *u_k1, double sigma,
                     double dtau, const double *p, int substeps, double *aug, double *z,
                     double *work);

/* All N-1 intervals about the node values x (N x 14, row-major) and u (N x 3): interval k
 * writes aug + k * PDG_NAUG and z + k * PDG_NX. Same return codes; -1 also for N outside
 * [2, PDG_MAX_NODES]. */
int pdg_foh_all(int N, const double *x, const double *u, double sigma, const double *p,
                int substeps, double *aug, double *z, double *work);

#endif
