/* Internal declarations of the guidance layer (not part of the public API). */
#ifndef PDG_INTERNAL_H
#define PDG_INTERNAL_H

#include <stddef.h>
#include <stdint.h>

#include "foh.h"
#include "tscvx_guidance.h"
#include "tscvx_socp.h"

#define NX PDG_NX
#define NU PDG_NU
#define NC PDG_NCON
#define IM 13                 /* mass index in the state */
#define N_TR_SCALAR 6         /* states under the scalar part of the trust region */
#define N_TR_PAIRS 4          /* rotation-invariant pairs */
#define N_NU_BLOCKS (N_TR_SCALAR + N_TR_PAIRS)
#define SIGMA_MIN 1e-2        /* lower bound on t_f (guidance/subproblem.py) */
#define MASS_SCALE_FLOOR 1e-3 /* mass scale >= this x m0 (guidance/subproblem.py says why) */
#define TIGHT_DUAL_TOL 1e-5   /* guidance/constraints.py */
#define N_DISC (NX + NX * NX + 2 * NX * NU + 2 * NX) /* per interval: x_next A Bm Bp S z */

extern const int pdg_tr_scalar_states[N_TR_SCALAR];
extern const int pdg_tr_pairs[N_TR_PAIRS][2];

/* Offsets of one interval's discretization record (N_DISC doubles). A, Bm, Bp row-major. */
#define D_XN 0
#define D_A (D_XN + NX)
#define D_BM (D_A + NX * NX)
#define D_BP (D_BM + NX * NU)
#define D_S (D_BP + NX * NU)
#define D_Z (D_S + NX)

/* Index ranges of the decision vector (guidance/subproblem.py Layout). */
typedef struct {
    int N, ix, iu, isig, inu, ivc, ibuf, n, n_traj;
} pdg_layout;

/* Affine scaling x = Sx x_hat + cx, u = Su u_hat, t_f = Ss sigma_hat. */
typedef struct {
    double Sx[NX], cx[NX], Su, Ss;
} pdg_scaling;

/* Sink of the one routine that emits the subproblem: pattern at setup, numbers per solve. */
typedef struct {
    int mode;        /* 0: count, 1: record pattern (row, col), 2: write values */
    int cnt;         /* entries emitted so far */
    int p;           /* rows below p are equalities (A), the others cone rows (G) */
    int *row, *col;  /* mode 1 */
    const int *dest; /* mode 2: entry -> slot (A slot, or nnz_A + G slot) */
    double *Ax, *Gx; /* mode 2 */
    int nnz_A;
    int nnz;         /* mode 2: nnz_A + nnz_G, the slots dest may name */
    int bad_slot;    /* mode 2: a dest outside them was met (a corrupted map): nothing written */
    const unsigned char *phi_a; /* the entries of A_k the dynamics rows carry (foh.h) */
} pdg_emitter;

/* Values that the emission needs (mode 2). */
typedef struct {
    const pdg_scenario *scn;
    const pdg_scaling *sc;
    const double *disc;         /* (N-1) x N_DISC */
    const double *zref;         /* scaled iterate */
    const unsigned char *keep;  /* 7N, NULL = keep everything */
    double eta, lam, prox_u;
    double fuel;                /* weight of -m_hat(t_f): 1, 0 in the polish */
    double *b, *h, *c;          /* outputs: p, m, n */
} pdg_values;

/* Set by a successful pdg_setup: a workspace whose arena was reused or never set up is
 * refused instead of trusted (an int flag would pass on leftover bytes), and so is one whose
 * set-up constants (sizes, settings, layout, the pointers into the arena) no longer match
 * their checksum (a bit flipped in them would send a loop out of bounds). */
#define PDG_WS_MAGIC 0x50444757u /* "PDGW" */
#define PDG_WS_READY(ws) pdg_ws_ready(ws)

struct pdg_workspace {
    unsigned magic;
    int N, roll_free;
    const unsigned char *phi_a; /* A_k's structural pattern for the vehicle (foh.h) */
    int phi_a_nnz;
    pdg_settings st;
    pdg_layout lay;
    int n, p, m, nnz_A, nnz_G, nnz;
    int l, nsoc;
    /* rows of G (0-based within G) of the blocks the labelling reads */
    int g_mass, g_tmin, g_soc;
    /* pattern (fixed at setup) */
    int *Ap, *Ai, *Gp, *Gi, *q, *dest;
    /* subproblem numbers */
    double *Ax, *Gx, *b, *h, *c;
    int *Pp, *Pi;   /* prox_u > 0: P = prox_u I on the thrust columns */
    double *Px;
    tscvx_workspace *socp;
    /* scenario-dependent */
    pdg_scenario scn;
    double pvec[PDG_NP];
    pdg_scaling sc;
    double scales[NC];
    /* iterates, discretizations and buffers */
    double *z, *znew, *zdual;
    double *ydual, *slack;          /* the rest of the last subproblem solution (warm start) */
    double *disc, *disc_new, *aug, *augw;
    double *x, *u, *xn, *un, *hval; /* physical iterate, candidate, path constraint values */
    /* masks (7N): pred, the prediction for this succession; prev_mask, that of the last
     * accepted one (tau_r); mask = pred | forced (put back by the guard); keep = mask with
     * T_min; tight, the candidate's tight constraints */
    unsigned char *mask, *prev_mask, *pred, *forced, *tight, *keep;
    double *gwork;                  /* guess work space */
    double *nn_out, *nn_logits;     /* T-SCvx: solution-network output, constraint logits */
    /* record of the last solve */
    pdg_log_row *log;
    int n_log;
    unsigned char *masks_out;
    int n_masks_out;
    size_t arena_bytes, arena_high;
    /* 1 while a solve runs: a callback calling back into this workspace (another solve, a
     * T-SCvx guess) would overwrite the running solve's buffers, so it is refused */
    int busy;
    /* the running solve's result: a refused call from its callback leaves it untouched (its
     * IPM iteration count is the call's budget) */
    const pdg_result *running;
    /* the SOCP runtime's iteration limit now: socp_max_iter, or less where the call's
     * budget (socp_max_iter_total) binds */
    int socp_cap;
    int socp_polish; /* 1: the SOCP runtime's tolerances are now the polish's */
    uint64_t layout_sum; /* word-wise sum of the set-up constants above (pdg_layout_sum) */
    uint64_t map_sum;    /* of the map dest, read once layout_sum vouched for its pointer and
                            length (pdg_map_sum) */
};

uint64_t pdg_layout_sum(const pdg_workspace *ws);
uint64_t pdg_map_sum(const pdg_workspace *ws);
int pdg_ws_ready(const pdg_workspace *ws);
/* Set up (pdg_ws_ready) and no solve running on it: the calls that write its buffers. */
int pdg_ws_idle(const pdg_workspace *ws);
#define PDG_BUSY_MESSAGE "workspace busy: called from inside a callback of a solve running on it"

/* pdg_scvx.c */
/* Clears `res` to "invalid input" and, when `ws` is set up, the record of its last solve (log
 * and masks: a refused call leaves none to read): 0 to go on, -1 (message set) if not set up. */
int pdg_result_begin(pdg_workspace *ws, pdg_result *res);
int pdg_check_workspace_scenario(const pdg_workspace *ws, const pdg_scenario *s, char *msg);
/* 1 for the outcomes that report an answer (solved, and the last accepted iterate of
 * infeasible and max_iterations): what the end check of a solve guards */
int pdg_reports_answer(pdg_status status);
/* pdg_solve from the trust radius eta_init (> 0) instead of the settings' (0: theirs); the
 * end check of the guidance and SOCP workspaces included (pdg_solve_tscvx adds the nets') */
pdg_status pdg_solve_from(pdg_workspace *ws, const pdg_scenario *scenario,
                          const pdg_options *opt, pdg_result *res, double eta_init);

/* pdg_scenario.c */
int pdg_check_scenario(const pdg_scenario *s, char *msg);
int pdg_all_finite(const double *v, size_t n); /* 1 when no NaN or inf among v[0..n) */
double pdg_hypot(double a, double b); /* libm's hypot, the same bits on every host */
void pdg_param_vector(const pdg_params *p, double *pv);
double pdg_tan_glideslope(const pdg_params *p);
double pdg_cos_gimbal(const pdg_params *p);
double pdg_tilt_q_max(const pdg_params *p);
double pdg_omega_max(const pdg_params *p);
void pdg_x_final_target(const pdg_scenario *s, double *xf);
/* x0 (NX) of a scenario in the state order of DESIGN.md */
void pdg_initial_state(const pdg_scenario *s, double *x0);
void pdg_dcm_bi(const double *q, double C[3][3]);

/* pdg_guess.c: needs 40 N doubles of work */
#define PDG_GUESS_WORK_PER_NODE 40
void pdg_initial_guess(const pdg_scenario *s, double *x, double *u, double *t_f, double *work);
void pdg_project_guess(const pdg_scenario *s, double *x, double *u, double *t_f);

/* pdg_subproblem.c */
void pdg_layout_init(pdg_layout *lay, int N);
void pdg_emit(pdg_emitter *e, const pdg_layout *lay, int roll_free, const pdg_values *v);
void pdg_cone_dims(int N, int *l, int *nsoc, int *q);
int pdg_rows_eq(int N, int roll_free);
void pdg_scaling_init(pdg_scaling *sc, const pdg_scenario *s, double t_f_guess);

#endif
