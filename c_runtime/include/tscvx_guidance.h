/*
 * tscvx_guidance.h -- flight guidance: successive convexification (SCvx, paper Algorithm 1)
 * of the 6-DoF powered-descent problem, with the T-SCvx hooks (per-iteration constraint
 * masks, external warm start) of Algorithm 2. The one public header of the guidance layer.
 *
 * Units and conventions: ../../shared/DESIGN.md (nondimensional U_L, U_T, U_M; e1 up; state
 * x = (r_I, v_I, q_B<-I scalar first, omega_B, m) in R^14, control u = T_B in R^3 with
 * first-order hold, t_f the time dilation). Angles in degrees where the scenario contract
 * uses degrees. The algorithm is the ground reference's (guidance/scvx.py, subproblem.py,
 * guess.py, constraints.py) transcribed: the same scaling, subproblem, penalty, trust-region
 * rules, convergence test and tight-constraint labelling, so both give the same trajectory.
 *
 * Lifecycle (memory is claimed in exactly one place, from ONE caller-provided arena):
 *
 *   1. pdg_default_settings(&st); pdg_default_scenario(&scn)      -- Table 1 values
 *   2. pdg_workspace_size(&scn.params, &st, scratch, nscratch, &need)
 *        lays out the subproblem pattern and runs the SOCP's symbolic analysis in caller
 *        scratch. If the scratch is too small it returns PDG_SETUP_SCRATCH_TOO_SMALL with
 *        `need` = a larger scratch size to retry with (at most two retries: the first learns
 *        the pattern size, the second the analysis size). On success `need` = arena bytes.
 *        The scratch may be the arena that will be given to pdg_setup; its contents are
 *        overwritten (a workspace set up in it is gone).
 *   3. pdg_setup(&ws, arena, bytes, &scn.params, &st)
 *        builds the subproblem's sparsity (CSC, fixed from now on), the SOCP workspace and
 *        every buffer (discretization, iterates, log, masks) inside the arena.
 *   4. pdg_solve(ws, &scenario, &options, &result)     -- any number of times; no allocation,
 *        no recursion, every loop bounded. The scenario is validated first (the same rules
 *        and field names as guidance/scenario.py): a bad one returns PDG_INVALID_INPUT with
 *        the message in result.message, and nothing is solved.
 *   5. pdg_get_log / pdg_get_mask / pdg_arena_high_water  -- the last solve's record.
 *   6. cleanup is trivial: the caller owns the arena.
 *
 * Callbacks (pdg_options.mask_fn, clock_s) may read the running solve's record and solve on
 * other workspaces. A call that would write the running workspace (pdg_solve,
 * pdg_solve_tscvx, pdg_tscvx_guess, pdg_debug_guess on it) is refused as busy, and leaves a
 * result it was given that is the running solve's own untouched. pdg_setup or
 * pdg_workspace_size over the running workspace's arena ends the solve when the callback
 * returns, whichever it is (the mask callback, or the clock before or after a subproblem's
 * conic solve): PDG_INVALID_INPUT, "... callback of iteration k set the workspace up again
 * or wrote over its arena", no trajectory, and nothing more written into the arena.
 *
 * Every call taking the workspace checks its mark and a checksum of what pdg_setup fixed (the
 * sizes, settings and layout, the pointers into the arena; then, through the pointer and
 * length they vouched for, the map of the subproblem's entries into its matrices): a
 * workspace whose arena was reused, or where one of those took a bit flip, is refused
 * (PDG_SETUP_NOT_READY, PDG_INVALID_INPUT from the solves), never followed. The SOCP
 * workspace inside it checks its own mark and set-up checksum on each of its calls
 * (tscvx_socp.h), and each tscvx_update_data and tscvx_solve again at its end: a flip there
 * ends the solve at that subproblem with PDG_SOLVER_ERROR and the SOCP runtime's reason in
 * the message ("conic solver returned invalid_input: workspace damaged: ...", "... damaged
 * during a solve: ..." or "... during a data update: ..." when it came during that
 * subproblem's), and so does every later solve until the workspace is set up again. The IPM
 * iterations of a conic solve whose end check failed count in the record (log row, result)
 * and the budget socp_max_iter_total all the same.
 * The solves (pdg_solve, pdg_solve_tscvx) check again at their end, before reporting an
 * answer (PDG_SOLVED, and the iterate of PDG_INFEASIBLE and PDG_MAX_ITERATIONS): the
 * guidance workspace's checksum, then the SOCP workspace's (tscvx_check_workspace), then
 * for pdg_solve_tscvx each network's (tscvx_nn_get_info). A bit flipped in any of them
 * during the call (after the start checks, or in the SOCP workspace after its last solve)
 * makes the call PDG_SOLVER_ERROR with "workspace damaged during the call (the end check:
 * ...)" or "nets: the ... network was damaged during the call (the end check: ...)" in the
 * message, naming the check that failed (the SOCP runtime's reason); result.x, u and t_f
 * then hold what the call computed, which is not an answer. A call that fails before its
 * end keeps its own status and reason.
 *
 * Each SCvx iteration writes new numbers into the fixed pattern: FOH discretization of the
 * N-1 intervals from the CasADi-generated model, the subproblem data (equalities A z = b:
 * dynamics with virtual control, boundary conditions; cone rows G z + s = h: virtual-control
 * epigraphs, virtual buffers, trust region, path constraints), one SOCP solve, the exact
 * penalty J on the FULL constraint set, rho = dJ / dL and the trust-region update.
 *
 * Constraint masks (T-SCvx): a mask has 7N bytes (node-major, entry 7k + c, nonzero = keep).
 * A masked-out path constraint keeps its place in the fixed pattern with zero coefficients
 * and a trivially met right-hand side, so it does not constrain the subproblem. The KKT size
 * stays that of the full problem: a pattern without the masked rows was measured at 6-8 %
 * fewer instructions per IPM iteration, but each change of mask then needs a new symbolic
 * set-up of the SOCP (about 9 M instructions), which is what the subproblem saves. T_min
 * (c = 6) is always kept. Before returning "solved", the full constraint set is checked and
 * any violated constraint the mask dropped is put back for the remaining iterations.
 */
#ifndef TSCVX_GUIDANCE_H
#define TSCVX_GUIDANCE_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

#define PDG_NSTATE 14 /* state dimension */
#define PDG_NCTRL 3   /* control dimension */
#define PDG_NCON 7    /* path constraints per node (mask entries per node) */
#define PDG_N_MIN 3
#define PDG_N_MAX 400
#define PDG_MESSAGE_LEN 256
/* pdg_settings.socp_max_iter_total at most: 500 subproblems x 500 iterations x 2 (a failed
 * warm run and its cold rerun), the most the other limits allow */
#define PDG_MAX_ITER_TOTAL 500000
/* Largest magnitude of any real number in a scenario (guidance/scenario.py MAGNITUDE_MAX):
 * Table 1's landing is O(1) in these nondimensional units; beyond this input is refused. */
#define PDG_MAGNITUDE_MAX 1e4
/* Floors of two scales the solve divides by (guidance/scenario.py INERTIA_MIN,
 * OMEGA_MAX_DEG_MIN, which say why): each entry of J_B, and omega_max_deg in deg / U_T. */
#define PDG_INERTIA_MIN 1e-9
#define PDG_OMEGA_MAX_DEG_MIN 1e-3
/* A plan pdg_plan_remainder takes is checked as a trajectory file is (guidance/verify.py
 * VALUE_LIMIT and T_F_RANGE): its values at most PDG_PLAN_VALUE_MAX in magnitude, its t_f
 * within [PDG_PLAN_T_F_MIN, PDG_PLAN_T_F_MAX] U_T (a landing takes a few U_T). */
#define PDG_PLAN_VALUE_MAX 1e9
#define PDG_PLAN_T_F_MIN 1e-6
#define PDG_PLAN_T_F_MAX 1e4

/* ---- status codes ------------------------------------------------------------------------ */

typedef enum {
    PDG_SETUP_OK = 0,
    PDG_SETUP_NULL_ARGUMENT,     /* a required pointer is NULL */
    PDG_SETUP_BAD_SIZE,          /* N outside [PDG_N_MIN, PDG_N_MAX] */
    PDG_SETUP_BAD_SETTINGS,      /* a setting is NaN or outside its documented range */
    PDG_SETUP_SCRATCH_TOO_SMALL, /* retry pdg_workspace_size with the returned size */
    PDG_SETUP_ARENA_TOO_SMALL,   /* arena smaller than pdg_workspace_size() */
    PDG_SETUP_SOCP_ERROR,        /* the SOCP runtime refused the subproblem pattern */
    PDG_SETUP_NOT_READY,         /* workspace not set up, or its arena overwritten or damaged
                                    (a set-up checksum mismatch): set it up again */
    PDG_SETUP_BAD_INDEX,         /* log or mask index out of range */
    PDG_SETUP_BAD_VEHICLE,       /* a vehicle parameter is NaN or out of its range
                                    (pdg_check_vehicle names it) */
    PDG_SETUP_NSTATUS
} pdg_setup_status;

/* Outcome of pdg_solve (the same names as the Python reference's statuses). */
typedef enum {
    PDG_SOLVED = 0,        /* converged: small step, no virtual control, defects and path
                              constraints met (the FULL constraint set); a step rejected at
                              eta_lb from an iterate that meets them ends here with it */
    PDG_INFEASIBLE,        /* virtual control still > vc_tol after iter_max iterations */
    PDG_MAX_ITERATIONS,    /* virtual control zero but not converged, or the IPM iteration
                              budget (socp_max_iter_total) spent: the result is the last
                              accepted iterate */
    PDG_SOLVER_ERROR,      /* a subproblem could not be solved (or the model failed): x
                              and u hold the last accepted iterate; or the guidance
                              workspace's map, or the end check, found a workspace damaged
                              during the call (see above): nothing returned (t_f NaN, x and
                              u untouched); or the end check found a network damaged; or
                              (pdg_solve_tscvx) the solution network's prediction was not
                              finite: nothing solved, nothing returned (t_f NaN, x and u
                              untouched, the log empty), "solution network: ..." */
    PDG_INVALID_INPUT,     /* bad scenario, guess (NaN/inf, t_f <= 0, one of x, u alone),
                              mask or workspace: nothing was solved. A running solve stopped
                              by its mask callback (an error answer, or the workspace set up
                              again from it) ends so too: the log keeps the subproblems
                              solved before. Either way nothing is returned (t_f NaN, x and
                              u untouched). A finite guess where
                              the model cannot be evaluated (m = 0 at a node, far outside
                              the model's range) is PDG_SOLVER_ERROR, "model evaluation
                              failed at the initial guess"; one it evaluates but no landing
                              can follow (m < 0) is PDG_SOLVER_ERROR from its first
                              subproblem. Both as in the Python reference */
    PDG_NSTATUS
} pdg_status;

/* What became of the polish of a solve (pdg_settings.polish, pdg_result.polish). */
typedef enum {
    PDG_POLISH_OFF = 0,    /* not run: off, prox_u = 0, or the solve did not converge */
    PDG_POLISH_KEPT,       /* the answer is the polished iterate */
    PDG_POLISH_NO_BUDGET,  /* not run: the IPM iteration budget was spent */
    PDG_POLISH_FAILED,     /* its conic solve or the model evaluation failed; the converged
                              iterate kept */
    PDG_POLISH_NOT_BETTER, /* it left virtual control, no smaller defects or a path
                              constraint unmet; the converged iterate kept */
    PDG_POLISH_NSTATUS
} pdg_polish_status;

const char *pdg_setup_status_message(pdg_setup_status status);
const char *pdg_status_message(pdg_status status);
/* "solved", "infeasible", "max_iterations", "solver_error", "invalid_input" */
const char *pdg_status_name(pdg_status status);
const char *pdg_polish_message(pdg_polish_status polish);

/* ---- problem ----------------------------------------------------------------------------- */

/* Vehicle, environment, constraints and boundary conditions: the trajectory `params`
 * contract of DESIGN.md, field by field, same names and units (nondimensional: U_L length,
 * U_T time, U_M mass). The ranges are what pdg_check_vehicle and pdg_validate_scenario
 * enforce, in the order they check (the message names the field, "scenario field 'T_min':
 * ..."): every number finite and |value| <= PDG_MAGNITUDE_MAX, then the rules below. */
typedef struct {
    double g_I[3];          /* gravity, inertial frame, U_L / U_T^2: along -e1, g_I[0] < 0,
                               g_I[1] = g_I[2] = 0 */
    double J_B[3];          /* diagonal of the inertia, U_M U_L^2, each >= PDG_INERTIA_MIN */
    double r_T_B[3];        /* engine position, body frame, U_L: r_T_B[0] < 0 (below the
                               centre of mass) */
    double r_cp_B[3];       /* centre of pressure, body frame, U_L (any; not zero gives
                               another pattern: pdg_workspace_size) */
    double alpha_mdot;      /* 1 / (I_sp g0), U_T / U_L, > 0 */
    double beta_mdot;       /* back-pressure mass loss, U_M / U_T, >= 0 */
    double aero_coeff;      /* c_A in A_B = -c_A |v_B| v_B, U_M / U_L, > 0 */
    double m_dry;           /* dry mass, U_M, > 0 */
    double T_min, T_max;    /* thrust bounds, U_M U_L / U_T^2, 0 < T_min < T_max */
    double gimbal_max_deg;  /* deg, within (0, 90) */
    double tilt_max_deg;    /* deg, within (0, 180] */
    double glideslope_deg;  /* deg, within [0, 90) */
    double omega_max_deg;   /* deg / U_T, >= PDG_OMEGA_MAX_DEG_MIN */
    double r_f[3];          /* landing point, U_L: r_f[0] >= 0, inside the glideslope cone
                               (its boundary included, to 1e-12) */
    double v_f[3];          /* touchdown velocity, U_L / U_T: reaching r_f from inside the
                               glideslope cone */
    double q_f[4];          /* final attitude (scalar first): a unit quaternion (to 1e-6),
                               upright (q_f[2] = q_f[3] = 0) when roll-free, else tilted at
                               most tilt_max_deg */
    double omega_f[3];      /* final angular rate, rad / U_T: |omega_f| at most
                               omega_max_deg (in rad / U_T) */
    int final_roll_free;    /* 1: only q2(t_f) = q3(t_f) = 0; 0: q(t_f) = q_f (0 or 1) */
    int N;                  /* nodes, within [PDG_N_MIN, PDG_N_MAX]; must equal the
                               vehicle's given to pdg_setup */
} pdg_params;

/* The initial state (pdg_validate_scenario: inside the path constraints it will be held to) */
typedef struct {
    double r0[3];           /* U_L: inside the glideslope cone (its boundary included, to
                               1e-12) */
    double v0[3];           /* U_L / U_T */
    double q0[4];           /* scalar first: a unit quaternion (to 1e-6), tilted at most
                               tilt_max_deg */
    double w0[3];           /* rad / U_T: |w0| at most omega_max_deg (in rad / U_T);
                               w0[0] = omega_f[0] when the vehicle makes no roll torque
                               (J_B[1] = J_B[2], r_T_B and r_cp_B on the body axis) */
    double m0;              /* U_M, > m_dry */
    pdg_params params;
} pdg_scenario;

/* Paper Table 1 and the tolerances of guidance/params.py SCvxSettings. */
typedef struct {
    double lam;             /* penalty weight on virtual control and buffers, (0, PDG_LAM_MAX] */
    double rho0, rho1, rho2;/* acceptance / shrink / grow thresholds,
                               0 <= rho0 <= rho1 <= rho2 */
    double alpha;           /* trust-region shrink factor, >= PDG_ALPHA_MIN */
    double beta;            /* trust-region growth factor, >= 1 */
    double eta_init;        /* initial trust radius (scaled units), in [eta_lb, eta_ub] */
    double eta_lb, eta_ub;  /* trust-radius bounds, 0 < eta_lb <= eta_ub */
    int iter_max;           /* accepted steps at most, 1..100 */
    int max_subproblems;    /* subproblem solves at most (rejections included), 1..500 */
    double step_tol;        /* convergence: scaled inf-norm of an accepted step, >= 0 */
    double cost_tol;        /* or convergence: |dJ| of an accepted step (paper Algorithm 1's
                               eps_tol; J scaled, fuel over m0 - m_dry), >= 0 */
    double vc_tol;          /* convergence: virtual control + buffers (scaled), >= 0 */
    double defect_tol;      /* convergence: nonlinear defects and path constraints, >= 0 */
    int rk4_substeps;       /* RK4 steps per FOH interval at least, 1..64; a grid coarser
                               than N = 50 takes more: none longer than N = 50's */
    double tight_tol;       /* slack threshold of the tight-constraint labelling, >= 0 */
    /* conic subproblem solver (tscvx_socp.h) */
    double socp_tol;        /* gap and feasibility tolerances (the reference uses 1e-9),
                               (0, 1) */
    int socp_max_iter;      /* IPM iteration limit, 1..500 */
    int socp_max_iter_total;/* IPM iterations of the whole call at most, 1..500000: a
                               subproblem is given at most what is left of it (half of it
                               when warm-started: a failed warm run is run again cold), and
                               none once it is spent, which ends the call with
                               PDG_MAX_ITERATIONS. The default (24000, the 60 x 200 x 2 that
                               max_subproblems and socp_max_iter allow) never binds; a flight
                               configuration sets it to bound the call's time */
    int socp_warm_start;    /* 1: each subproblem's IPM starts from the last subproblem's
                               solution (tscvx_warm_start), 0: from the cold start
                               (0 or 1) */
    /* T-SCvx only: 1 = Algorithm 2's radius update (alpha^tau_r, beta^(1 - tau_r), tau_r the
     * fraction of bits in which the predicted masks of successions k+1 and k differ);
     * 0 = Eq. (15) of Algorithm 1 with the masks as well (0 or 1) */
    int tau_r_update;
    /* Beyond the paper: weight w >= 0 of (w/2)|u_hat - u_hat_ref|^2 on the scaled thrust in
     * the subproblem objective (not in L, Eq. (13)); it makes the subproblem's answer unique,
     * so that conic solvers agree. 0: the paper's linear objective; at most PDG_PROX_U_MAX.
     * Fixed at pdg_setup. */
    double prox_u;
    /* Beyond the paper, off by default: 1 = once converged, one more subproblem about the answer on the
     * full constraint set without the fuel term, min lam (sum t + sum s') +
     * (PDG_POLISH_WEIGHT / 2)|u_hat - u_hat_ref|^2 at radius eta_ub, solved to
     * PDG_POLISH_TOL_FACTOR x socp_tol: the least thrust change that meets the linearized
     * dynamics, which removes the defects the last trust-region steps left (of the order of
     * the step squared after it). Its answer is kept when it leaves no virtual control,
     * smaller defects and every path constraint met (pdg_result.polish). Needs prox_u > 0
     * (the P pattern). 0 (the default): the converged iterate as it is (the polish costs
     * 6.8 % more instructions on the default landing; docs/scvx.md). 0 or 1. */
    int polish;
} pdg_settings;

/* pdg_settings.lam at most (guidance/params.py LAM_MAX, which says why) */
#define PDG_LAM_MAX 1e8
/* pdg_settings.alpha at least and prox_u at most (guidance/params.py ALPHA_MIN, PROX_U_MAX,
 * which say why: nearer 1 a rejected step is retried at almost the same radius; a larger
 * weight stops SCvx short of the optimum with a "solved" that wastes propellant) */
#define PDG_ALPHA_MIN 1.1
#define PDG_PROX_U_MAX 0.03

#define PDG_POLISH_WEIGHT 1.0     /* guidance/scvx.py POLISH_WEIGHT */
#define PDG_POLISH_TOL_FACTOR 1e-2 /* guidance/scvx.py POLISH_TOL_FACTOR */

/* Returns k-th mask (7N bytes, nonzero = keep) into `mask` for SCvx iteration k = 1, 2, ...;
 * returns 1 when it wrote a mask, 0 to solve the full problem at that iteration. Any other
 * answer (an error code) stops the solve with PDG_INVALID_INPUT and a "masks:" message;
 * nothing is returned (t_f NaN, x and u untouched). A solve with masks (table or callback) is T-SCvx
 * even where a mask is full: its trust radius follows Algorithm 2 (pdg_settings.tau_r_update). */
typedef int (*pdg_mask_fn)(void *ctx, int k, unsigned char *mask, int n_entries);

typedef struct {
    /* Warm start (all three or none): x (N x 14, node-major), u (N x 3), t_f. Used as given,
     * as the Python reference's solve(guess=...) does (no projection; t_f also sets the
     * sigma scaling). NULL: the built-in guess (cubic Hermite + projection, guess.py). */
    const double *guess_x;
    const double *guess_u;
    double guess_t_f;
    /* Masks, either a table (n_masks rows of 7N bytes; iteration k uses row
     * min(k, n_masks) - 1) or a callback. Both NULL: plain SCvx (no masks). */
    const unsigned char *masks;
    int n_masks;
    pdg_mask_fn mask_fn;
    void *mask_ctx;
    /* Optional monotonic clock (seconds) for the log's subproblem times; NULL = no timing. */
    double (*clock_s)(void);
} pdg_options;

typedef struct {
    pdg_status status;
    char message[PDG_MESSAGE_LEN]; /* why (the reason of the Python reference), or the input
                                      error as "scenario field 'q0': ..." */
    double *x;                /* caller array N x 14 (node-major): the trajectory */
    double *u;                /* caller array N x 3: thrust T_B at the nodes (FOH) */
    double t_f;               /* NaN, x and u untouched: nothing returned (PDG_INVALID_INPUT,
                                 the model failing at the guess, a workspace damaged during
                                 the call, the solution network's prediction not finite) */
    int iterations;           /* accepted steps */
    int subproblems_solved;   /* convex subproblems solved, rejections included */
    double max_defect;        /* max |x_{k+1} - F(x_k, u_k, u_k+1, t_f)|, physical units */
    double max_violation;     /* max path-constraint value h (<= 0 when met) */
    int socp_iterations;      /* IPM iterations summed over the subproblems (the polish's
                                 included) */
    pdg_polish_status polish; /* what became of the polish (pdg_settings.polish) */
    int polish_iterations;    /* its IPM iterations (0: not run) */
    double defect_before_polish; /* max_defect and the final mass of the converged iterate */
    double m_f_before_polish;    /* (NaN: the solve did not converge) */
} pdg_result;

/* One row of the iteration log (the Python reference's columns). */
typedef struct {
    int k;                    /* iteration (succession) the subproblem belongs to */
    double J;                 /* penalty at the subproblem's solution */
    double dJ, dL, rho;       /* actual and predicted change, their ratio */
    double eta;               /* trust radius used */
    double vc_norm1;          /* virtual control (block norm) + buffers, scaled */
    int n_tight;              /* tight constraints at the solution */
    double subproblem_time_s; /* the conic solve (tscvx_solve) alone; 0 without options.clock_s */
    int accepted;
    int solver_status;        /* tscvx_solve_status of the subproblem */
    int solver_iterations;    /* IPM iterations the conic solve ran (a cold rerun of a failed
                                 warm start included), whatever its outcome */
    int restored;             /* T-SCvx: dropped constraints the full-constraint guard put
                                 back (the step is then rejected at the same radius) */
} pdg_log_row;

typedef struct pdg_workspace pdg_workspace; /* opaque, lives in the arena */

/* ---- API --------------------------------------------------------------------------------- */

/* Table 1's settings and DESIGN.md's vehicle; PDG_SETUP_NULL_ARGUMENT for NULL. */
pdg_setup_status pdg_default_settings(pdg_settings *settings);
pdg_setup_status pdg_default_params(pdg_params *params);
/* The default scenario of DESIGN.md (r0 = (4, 4, 0), v0 = (0, -1, -2), m0 = 3, ...). */
pdg_setup_status pdg_default_scenario(pdg_scenario *scenario);

/* PDG_SETUP_OK and "" in `message` (PDG_MESSAGE_LEN bytes; may be NULL), or
 * PDG_SETUP_BAD_SETTINGS with the field, its range and the value in it: what
 * pdg_workspace_size and pdg_setup refuse. PDG_SETUP_NULL_ARGUMENT, "settings is NULL". */
pdg_setup_status pdg_check_settings(const pdg_settings *settings, char *message);

/* PDG_SETUP_OK and "" in `message` (PDG_MESSAGE_LEN bytes; may be NULL), or
 * PDG_SETUP_BAD_VEHICLE with the field and why in it (PDG_SETUP_NULL_ARGUMENT, "vehicle is
 * NULL"), by the rules pdg_validate_scenario applies to a scenario's params:
 * what pdg_workspace_size and pdg_setup refuse (a NaN r_cp_B used to set up a workspace that
 * then refused every scenario as "a vehicle with r_cp_B not zero"). */
pdg_setup_status pdg_check_vehicle(const pdg_params *vehicle, char *message);

/* The workspace is built for a vehicle: its N, its terminal condition (final_roll_free) and
 * the structure of its dynamics' Jacobian (whether r_cp_B is zero, which removes entries of
 * A_k from the subproblem). pdg_solve takes scenarios whose params agree with it on these;
 * every other field may change from one solve to the next. */
pdg_setup_status pdg_workspace_size(const pdg_params *vehicle, const pdg_settings *settings,
                                    void *scratch, size_t scratch_bytes, size_t *bytes);

/* Builds the workspace in `arena` (arena_bytes from pdg_workspace_size). On success *ws
 * points into the arena; on any refusal (a NULL arena included) *ws is NULL (ws itself
 * NULL: PDG_SETUP_NULL_ARGUMENT, nothing written). */
pdg_setup_status pdg_setup(pdg_workspace **ws, void *arena, size_t arena_bytes,
                           const pdg_params *vehicle, const pdg_settings *settings);

/* Validates the scenario as guidance/scenario.py does (every number finite and within
 * PDG_MAGNITUDE_MAX, then the physics): 0 and "" in `message` when valid, otherwise
 * PDG_INVALID_INPUT with the message ("scenario field 'm0': ...") in `message`
 * (PDG_MESSAGE_LEN bytes; may be NULL). */
int pdg_validate_scenario(const pdg_scenario *scenario, char *message);

/* Runs SCvx (T-SCvx with masks). `options` may be NULL. result->x and result->u must point
 * to N x 14 and N x 3 doubles. */
pdg_status pdg_solve(pdg_workspace *ws, const pdg_scenario *scenario,
                     const pdg_options *options, pdg_result *result);

/* The last solve's record: its log rows 0 .. rows - 1 (pdg_log_length) and its
 * accepted-iteration masks 0 .. iterations - 1 (7N bytes each: the tight-constraint labels of
 * the accepted solution). Each returns PDG_SETUP_NULL_ARGUMENT for a NULL pointer,
 * PDG_SETUP_NOT_READY (outputs untouched) for a workspace not set up, PDG_SETUP_BAD_INDEX
 * for a row or mask out of range. */
pdg_setup_status pdg_log_length(const pdg_workspace *ws, int *rows);
pdg_setup_status pdg_get_log(const pdg_workspace *ws, int i, pdg_log_row *row);
pdg_setup_status pdg_get_mask(const pdg_workspace *ws, int k, unsigned char *mask);

/* Most bytes of the arena ever used, setup scratch included (statuses as above), and the size
 * of the subproblem: variables n, equality rows p, cone rows m, nonzeros of A and G (any
 * output may be NULL; PDG_SETUP_NULL_ARGUMENT for a NULL workspace, PDG_SETUP_NOT_READY,
 * outputs untouched, when not set up). */
pdg_setup_status pdg_arena_high_water(const pdg_workspace *ws, size_t *bytes);
pdg_setup_status pdg_problem_size(const pdg_workspace *ws, int *n, int *p, int *m, int *nnz_A,
                                  int *nnz_G);

/* ---- T-SCvx on board (paper Algorithm 2, pdg_tscvx.c) ---------------------------------------
 *
 * One complete flight guidance call: scenario vector theta (16 numbers, the order of
 * guidance/dataset.py theta_of: r0 (3), v0 (3), q0 (4, scalar first), w0 (3, rad / U_T), m0,
 * glideslope_deg, tilt_max_deg) -> solution network -> warm start (x, u, t_f) projected onto
 * the boundary conditions and every convex path constraint (the same projection as the
 * built-in guess and as guidance/guess.py project_guess, which the Python `--method tscvx`
 * uses) -> SCvx from the reduced trust radius (PDG_TSCVX_ETA_INIT) -> optionally, at every
 * subproblem of iteration k = 1, 2, ..., the constraint network's tight mask (input theta
 * and k, tscvx_nn_tight_mask). The penalty and the final check are on the FULL constraint set
 * as in pdg_solve.
 *
 * The networks are built by the caller with tscvx_nn_init in their own arenas (sized by
 * tscvx_nn_arena_size); the call's own buffers (network output, logits) are in the guidance
 * arena (pdg_workspace_size counts them). No allocation. Every input is checked before
 * anything runs: a network of the wrong kind, or whose sizes / N do not fit the workspace,
 * returns PDG_INVALID_INPUT with "nets: ..." in result.message.
 *
 * Masks are optional (constraint = NULL) because in this runtime they do not pay: the KKT
 * pattern is fixed (a masked-out cone keeps its place), so a mask saves no factorization work
 * and its wrong guesses cost rejected steps, while the warm start saves about a quarter of the
 * subproblems (`guidance bench --backend c --tscvx-landings 12`).
 */
#define PDG_TSCVX_ETA_INIT 0.01 /* Table 1: eta_reduced,init (guidance/tscvx.py) */
#define PDG_THETA_LEN 16

struct tscvx_nn; /* tscvx_nn.h */

typedef struct {
    struct tscvx_nn *solution;   /* solution network: theta (16) -> x (N x 14), u (N x 3), t_f.
                                    NULL: the built-in guess and the settings' eta_init */
    struct tscvx_nn *constraint; /* constraint network: theta + k (17) -> 7N logits.
                                    NULL: no masks (every subproblem is the full one) */
    double eta_init;             /* initial trust radius with the warm start, within
                                    [eta_lb, eta_ub]; 0: PDG_TSCVX_ETA_INIT. Anything else
                                    is refused (PDG_INVALID_INPUT), with or without a
                                    solution network; without one the solve starts from the
                                    built-in guess at the settings' eta_init, as SCvx */
    double (*clock_s)(void);     /* optional clock for the log's subproblem times */
} pdg_tscvx_options;

/* What the networks did in the last pdg_solve_tscvx (may be NULL in the call). */
typedef struct {
    int warm_started;      /* 1: the solution network's projected prediction was the guess */
    int masks_predicted;   /* subproblems that used a constraint-network mask */
    int mask_failures;     /* mask inferences refused by the network (non-finite output):
                              those subproblems were the full one */
    double eta_init;       /* trust radius the solve started from; 0 when no solve
                              started (a refusal, or the solution network's prediction not
                              finite) */
} pdg_tscvx_report;

/* theta of a scenario (PDG_THETA_LEN numbers, guidance/dataset.py theta_of);
 * PDG_SETUP_NULL_ARGUMENT for NULL. */
pdg_setup_status pdg_theta_of(const pdg_scenario *scenario, double *theta);

/* The projected warm start of the solution network for `scenario` into x (N x 14), u (N x 3),
 * t_f: for tests and ground tools (pdg_solve_tscvx does the same internally). Returns 0 or a
 * pdg_status with the reason in `message` (PDG_MESSAGE_LEN bytes; may be NULL), x, u and t_f
 * then untouched: PDG_INVALID_INPUT (a NULL pointer, a workspace not set up or busy, a
 * scenario it refuses, a network of the wrong kind, size or problem: "nets: ...") or
 * PDG_SOLVER_ERROR (the network's output is not finite: "solution network: ..."). */
int pdg_tscvx_guess(pdg_workspace *ws, const pdg_scenario *scenario, struct tscvx_nn *solution,
                    double *x, double *u, double *t_f, char *message);

/* In-flight re-planning: the remainder of a plan (x N x 14, u N x 3, t_f: a solve's answer on
 * the scenario's N nodes from t = 0) from time t1 in [0, t_f) on, as the guess (x, u, t_f) of a
 * solve of `scenario`, the landing from the state at t1: N nodes over [t1, t_f], the states
 * linearly interpolated between the plan's nodes, the thrust as its first-order hold, then
 * projected onto the scenario's boundary conditions (node 0 its initial state) and convex
 * path constraints as the built-in guess is. For options.guess_x/guess_u/guess_t_f of
 * pdg_solve. Returns 0, or PDG_INVALID_INPUT with the reason in `message` (PDG_MESSAGE_LEN
 * bytes, may be NULL): a scenario pdg_validate_scenario refuses, NULL or non-finite input, a
 * value beyond PDG_PLAN_VALUE_MAX, t_f outside [PDG_PLAN_T_F_MIN, PDG_PLAN_T_F_MAX], t1
 * outside [0, t_f). No workspace, no allocation. */
int pdg_plan_remainder(const pdg_scenario *scenario, const double *x, const double *u,
                       double t_f, double t1, double *gx, double *gu, double *gt_f,
                       char *message);

/* The landing from a measured state x (PDG_NSTATE numbers in DESIGN.md's order: r, v, q, w, m)
 * with base's vehicle and targets, into `out`: what a re-plan in flight solves (with
 * pdg_plan_remainder's guess). The quaternion is renormalized; the roll rate, which this
 * vehicle cannot change (no roll torque), must be rounding noise, |w_x| <= PDG_ROLL_NOISE, and
 * is set to 0. Returns 0, or PDG_INVALID_INPUT with the reason in `message` (PDG_MESSAGE_LEN
 * bytes, may be NULL): NULL or non-finite input, a roll rate beyond noise, a zero quaternion,
 * or a landing pdg_validate_scenario refuses (`out` then holds it, for the message's sake).
 * guidance/closed_loop.py state_scenario is the same rule. */
#define PDG_ROLL_NOISE 1e-9 /* rad/U_T; guidance/closed_loop.py ROLL_NOISE */
int pdg_scenario_at_state(const pdg_scenario *base, const double *x, pdg_scenario *out,
                          char *message);

/* T-SCvx: the complete guidance call described above (both networks NULL: plain SCvx, as
 * pdg_solve). result as pdg_solve; `report` may be NULL. */
pdg_status pdg_solve_tscvx(pdg_workspace *ws, const pdg_scenario *scenario,
                           const pdg_tscvx_options *options, pdg_result *result,
                           pdg_tscvx_report *report);

/* For tests: assembles the subproblem about the physical iterate (x, u, t_f) of `scenario`
 * with trust radius eta (scaling, guess-independent: Ss = t_f) and copies its data out:
 * c (n), A values (nnz_A, the CSC order of Ap/Ai), b (p), G values, h (m), and the pattern
 * (Ap n+1, Ai, Gp n+1, Gi; any of these may be NULL). Returns 0, PDG_INVALID_INPUT (a
 * workspace not set up or busy, a scenario the workspace refuses, non-finite x or u, t_f or
 * eta not finite and positive) or PDG_SOLVER_ERROR (the model evaluation failed, or the SOCP
 * runtime refused the numbers), with the reason in `message` (PDG_MESSAGE_LEN bytes, may be
 * NULL; "" on success). */
int pdg_debug_assemble(pdg_workspace *ws, const pdg_scenario *scenario, const double *x,
                       const double *u, double t_f, double eta, double *c, double *Ax,
                       double *b, double *Gx, double *h, int *Ap, int *Ai, int *Gp, int *Gi,
                       char *message);

/* For tests: the initial guess (cubic Hermite + projection) into x (N x 14), u, t_f. Returns
 * 0 or PDG_INVALID_INPUT (a workspace not set up or busy, a NULL output, a scenario the
 * workspace refuses) with the reason in `message` (PDG_MESSAGE_LEN bytes, may be NULL). */
int pdg_debug_guess(pdg_workspace *ws, const pdg_scenario *scenario, double *x, double *u,
                    double *t_f, char *message);

#ifdef __cplusplus
}
#endif

#endif /* TSCVX_GUIDANCE_H */
