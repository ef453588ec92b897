"""The SCvx convex subproblem (paper Eq. (7)-(9)) as a sparse conic program in Clarabel's form.

Variables are scaled to O(1) ranges, x = S_x x_hat + c_x, u = S_u u_hat, sigma = S_s sigma_hat
(the paper: "numerical scaling was used for variable ranges"); lambda and the trust radius act
on the scaled variables. The decision vector is

    z = [x_hat (N x 14, node-major) | u_hat (N x 3) | sigma_hat | nu ((N-1) x 14) |
         t ((N-1) x 10) | s' (N)]

with the virtual control nu (scaled state units), the epigraph t of its block norms (see
N_NU_BLOCKS) and the virtual buffer s' >= 0 of the linearized nonconvex T_min constraint.
The objective is -m_hat(t_f) + lambda (sum t + sum s').

The sparsity pattern depends only on N, the terminal condition and the constraint mask: it is
built once (:class:`SubproblemTemplate`) and every SCvx iteration only writes new numbers.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
import scipy.sparse as sp

from guidance.conic import ConeKind, ConicProblem, ConicSolution
from guidance.model import transition_pattern
from guidance.params import (
    ALWAYS_KEPT,
    CONSTRAINT_NAMES,
    IM,
    IR,
    IV,
    IW,
    NC,
    NU,
    NX,
    Params,
    Scenario,
)

# Cone dimension of each path constraint (mask order); 1 = a linear row.
CONE_DIMS = (1, 3, 3, 4, 4, 4, 1)
SIGMA_MIN = 1e-2  # lower bound on t_f (keeps the time dilation positive)
# The mass is scaled by the propellant m0 - m_dry, but by no less than MASS_SCALE_FLOOR m0.
# With almost no propellant the scaled mass rows of the dynamics would carry (mass flow x
# time step) / (m0 - m_dry), 2e7 at 1e-9 of propellant; both conic solvers then certified a
# subproblem infeasible that its virtual control makes feasible, and T-SCvx (whose start
# leaves little room) stopped with a solver error instead of an infeasible landing.
MASS_SCALE_FLOOR = 1e-3
# Trust region |z - z_ref| <= eta: the infinity norm over the scalar components and over the
# 2-norms of the pairs that a rotation about the up axis mixes (horizontal position and
# velocity; (q0, q1) and (q2, q3) of the quaternion). That keeps every subproblem, and so the
# whole iteration, exactly equivariant under such rotations (DESIGN.md's symmetry).
TR_SCALAR_STATES = (0, 3, 10, 11, 12, 13)
TR_PAIRS = ((1, 2), (4, 5), (6, 7), (8, 9))
# The virtual control is penalized in the same blocks: |nu_i| for the scalar states and
# |(nu_a, nu_b)|_2 for the pairs, through epigraph variables t (an exact penalty in this norm).
N_NU_BLOCKS = len(TR_SCALAR_STATES) + len(TR_PAIRS)


@dataclass(frozen=True)
class Scaling:
    """Affine maps between physical and scaled variables (rotation invariant by design)."""

    Sx: np.ndarray  # (14,) state scale
    cx: np.ndarray  # (14,) state offset
    Su: float  # thrust scale
    Ss: float  # t_f scale

    @staticmethod
    def for_scenario(scenario: Scenario, t_f_guess: float) -> Scaling:
        p, s = scenario.params, scenario.initial
        Sr = max(float(np.linalg.norm(s.r0)), 1.0)
        Sv = max(float(np.linalg.norm(s.v0)), 1.0)
        Sx = np.ones(NX)
        Sx[IR], Sx[IV], Sx[IW] = Sr, Sv, p.omega_max
        Sx[IM] = max(s.m0 - p.m_dry, MASS_SCALE_FLOOR * s.m0)
        cx = np.zeros(NX)
        cx[IM] = p.m_dry
        return Scaling(Sx=Sx, cx=cx, Su=p.T_max, Ss=t_f_guess)

    def scale_x(self, x: np.ndarray) -> np.ndarray:
        return (x - self.cx) / self.Sx

    def unscale_x(self, xh: np.ndarray) -> np.ndarray:
        return xh * self.Sx + self.cx


@dataclass(frozen=True)
class Layout:
    """Index ranges of the decision vector."""

    N: int

    @property
    def ix(self) -> int:
        return 0

    @property
    def iu(self) -> int:
        return self.N * NX

    @property
    def isig(self) -> int:
        return self.iu + self.N * NU

    @property
    def inu(self) -> int:
        """Virtual control nu ((N-1) x 14, free)."""
        return self.isig + 1

    @property
    def ivc(self) -> int:
        """Start of the penalized variables: the epigraph t of |nu| ((N-1) x 10), then s'."""
        return self.inu + (self.N - 1) * NX

    @property
    def ibuf(self) -> int:
        return self.ivc + (self.N - 1) * N_NU_BLOCKS

    @property
    def n(self) -> int:
        return self.ibuf + self.N

    @property
    def n_traj(self) -> int:
        """Number of trajectory variables (x_hat, u_hat, sigma_hat) under the trust region."""
        return self.isig + 1

    def x_index(self, k: int | np.ndarray, i: int | np.ndarray) -> np.ndarray:
        return np.asarray(self.ix + NX * np.asarray(k) + np.asarray(i))

    def u_index(self, k: int | np.ndarray, i: int | np.ndarray) -> np.ndarray:
        return np.asarray(self.iu + NU * np.asarray(k) + np.asarray(i))


class _Rows:
    """Accumulates constraint rows as COO triplets with a fixed order of entries."""

    def __init__(self) -> None:
        self.rows: list[np.ndarray] = []
        self.cols: list[np.ndarray] = []
        self.m = 0
        self.cones: list[tuple[ConeKind, int]] = []

    def add(self, kind: ConeKind, rows: np.ndarray, cols: np.ndarray, height: int) -> int:
        """Adds entries at local rows `rows` (relative) of a new block; returns its first row."""
        start = self.m
        self.rows.append(start + np.asarray(rows, dtype=np.int64).ravel())
        self.cols.append(np.asarray(cols, dtype=np.int64).ravel())
        self.m += height
        if self.cones and kind != "soc" and self.cones[-1][0] == kind:
            self.cones[-1] = (kind, self.cones[-1][1] + height)
        else:
            self.cones.append((kind, height))
        return start


class SubproblemTemplate:
    """Sparsity pattern, cone list and value maps of the subproblem for one N, BC and mask.

    ``mask`` (7N booleans, node-major bit 7k + c) selects which path constraints enter; the
    full problem uses all ones. Constraint 6 (T_min) is always kept (DESIGN.md).
    ``a_pattern``: the entries of A_k the dynamics rows carry (model.vehicle_pattern of the
    vehicle; the default, transition_pattern(), holds for every vehicle).
    """

    def __init__(
        self,
        N: int,
        final_roll_free: bool,
        mask: np.ndarray | None = None,
        a_pattern: np.ndarray | None = None,
    ) -> None:
        self.N = N
        self.a_pattern = transition_pattern() if a_pattern is None else a_pattern
        self.lay = Layout(N)
        self.final_roll_free = final_roll_free
        mask = np.ones(NC * N, dtype=bool) if mask is None else np.asarray(mask, dtype=bool)
        if mask.shape != (NC * N,):
            raise ValueError(f"mask must have {NC * N} entries (7N), got {mask.shape}")
        mask = mask.reshape(N, NC).copy()
        mask[:, [CONSTRAINT_NAMES.index(name) for name in ALWAYS_KEPT]] = True
        self.mask = mask
        self._build()

    # -- pattern --------------------------------------------------------------------------
    def _build(self) -> None:
        """The sparsity pattern, block by block in the row order of the module docstring,
        and its COO -> CSC permutation, computed once: csc.data = values[self.perm]."""
        R = _Rows()
        self._dynamics_rows(R)
        self._boundary_rows(R)
        self._nonneg_rows(R)
        self._path_cone_rows(R)
        self._pair_rows(R)
        rows = np.concatenate(R.rows)
        cols = np.concatenate(R.cols)
        self.m, self.n = R.m, self.lay.n
        self.cones = R.cones
        self.nnz = rows.size
        order = np.lexsort((rows, cols))
        self.perm = order
        self.indices = rows[order].astype(np.int64)
        self.indptr = np.searchsorted(cols[order], np.arange(self.n + 1)).astype(np.int64)
        if np.any((np.diff(rows[order]) == 0) & (np.diff(cols[order]) == 0)):
            raise AssertionError("duplicate entries in the subproblem pattern")
        self.row_ids = self._row_ids()

    def _dynamics_rows(self, R: _Rows) -> None:
        """Dynamics (zero cone), 14 rows per interval; entries in this order per interval:
        x_{k+1} (14), A_hat (its structural nonzeros, row-major), Bm_hat (14x3),
        Bp_hat (14x3), Sigma_hat (14), nu (14)."""
        L = self.lay
        eye_r = np.arange(NX)
        rr, cc = np.nonzero(self.a_pattern)  # row-major over (row, col)
        ru = np.repeat(eye_r, NU)
        cu = np.tile(np.arange(NU), NX)
        rows_d, cols_d = [], []
        for kk in range(self.N - 1):
            base = NX * kk
            rows_d += [base + eye_r, base + rr, base + ru, base + ru, base + eye_r, base + eye_r]
            cols_d += [
                L.x_index(kk + 1, eye_r),
                L.x_index(kk, cc),
                L.u_index(kk, cu),
                L.u_index(kk + 1, cu),
                np.full(NX, L.isig),
                L.inu + NX * kk + eye_r,
            ]
        self.r_dyn = R.add(
            "zero", np.concatenate(rows_d), np.concatenate(cols_d), NX * (self.N - 1)
        )

    def _boundary_rows(self, R: _Rows) -> None:
        """Boundary conditions (zero cone): full initial state, final r, v, omega, q."""
        L, eye_r = self.lay, np.arange(NX)
        self.r_x0 = R.add("zero", eye_r, L.x_index(0, eye_r), NX)
        fin = list(range(0, 6)) + list(range(10, 13))
        fin += [8, 9] if self.final_roll_free else [6, 7, 8, 9]
        self.final_idx = np.array(fin)
        last = L.x_index(self.N - 1, self.final_idx)
        self.r_xf = R.add("zero", np.arange(len(fin)), last, len(fin))

    def _nonneg_rows(self, R: _Rows) -> None:
        """Nonnegative rows: t_i - nu_i >= 0 and t_i + nu_i >= 0 (scalar blocks), s' >= 0,
        sigma bound, trust region, mass, T_min."""
        N, L = self.N, self.lay
        k = np.arange(N - 1)
        ns_nu = len(TR_SCALAR_STATES)
        t_idx = (L.ivc + N_NU_BLOCKS * k[:, None] + np.arange(ns_nu)[None, :]).ravel()
        nu_idx = (L.inu + NX * k[:, None] + np.array(TR_SCALAR_STATES)[None, :]).ravel()
        ne = t_idx.size
        self.r_nu = R.add(
            "nonneg",
            np.concatenate(
                [np.arange(ne), np.arange(ne), np.arange(ne, 2 * ne), np.arange(ne, 2 * ne)]
            ),
            np.concatenate([t_idx, nu_idx, t_idx, nu_idx]),
            2 * ne,
        )
        self.n_nu_scalar = ne
        self.r_buf = R.add("nonneg", np.arange(N), L.ibuf + np.arange(N), N)
        self.r_sig = R.add("nonneg", np.array([0]), np.array([L.isig]), 1)
        # Trust region, scalar part: |z_i - z_ref,i| <= eta as two rows each.
        nodes = np.arange(N)
        scal = [
            L.x_index(nodes[:, None], np.array(TR_SCALAR_STATES)[None, :]).ravel(),
            np.arange(L.iu, L.isig),
            np.array([L.isig]),
        ]
        self.tr_scalar = np.concatenate(scal)
        ns = self.tr_scalar.size
        self.r_tr = R.add(
            "nonneg", np.arange(2 * ns), np.concatenate([self.tr_scalar, self.tr_scalar]), 2 * ns
        )
        nodes_m = np.flatnonzero(self.mask[:, 0])
        self.nodes_mass = nodes_m
        self.r_mass = R.add("nonneg", np.arange(len(nodes_m)), L.x_index(nodes_m, IM), len(nodes_m))
        # T_min linearization at every node: (T_k / |T_k|) . u_hat + s'_k >= T_min / S_u.
        self.r_tmin = R.add(
            "nonneg",
            np.concatenate([np.repeat(np.arange(N), NU), np.arange(N)]),
            np.concatenate(
                [
                    L.u_index(np.repeat(np.arange(N), NU), np.tile(np.arange(NU), N)),
                    L.ibuf + np.arange(N),
                ]
            ),
            N,
        )

    def _path_cone_rows(self, R: _Rows) -> None:
        """The masked-in path-constraint cones, node-major, in constraint order 1..5."""
        self.soc_rows: dict[tuple[int, int], int] = {}
        for node in range(self.N):
            for c in range(1, 6):
                if not self.mask[node, c]:
                    continue
                rows, cols = self._soc_entries(node, c)
                self.soc_rows[(node, c)] = R.add("soc", rows, cols, CONE_DIMS[c])

    def _pair_rows(self, R: _Rows) -> None:
        """The rotation-invariant pairs in Q3: virtual control [t_p; nu_a; nu_b] per
        interval, then trust region |(z_a, z_b) - ref|_2 <= eta per node."""
        L = self.lay
        self.nu_pairs = []
        for kk in range(self.N - 1):
            for j, pair in enumerate(TR_PAIRS):
                t_col = L.ivc + N_NU_BLOCKS * kk + len(TR_SCALAR_STATES) + j
                cols = np.array([t_col, L.inu + NX * kk + pair[0], L.inu + NX * kk + pair[1]])
                self.nu_pairs.append(R.add("soc", np.arange(3), cols, 3))
        nodes = np.arange(self.N)
        self.tr_pairs = np.stack(
            [L.x_index(nodes[:, None], np.array(pair)[None, :]) for pair in TR_PAIRS], axis=1
        ).reshape(-1, 2)
        self.r_trp = R.m
        for cols in self.tr_pairs:
            R.add("soc", np.array([1, 2]), cols, 3)

    def _row_ids(self) -> np.ndarray:
        """Each row's index in the full subproblem's rows (the template of the all-ones
        mask): the rows of a masked template are the full one's with the dropped mass rows
        and path cones left out, the rest in the same order (carry_solution)."""
        N = self.N
        dims = np.array(CONE_DIMS)
        per_node = int(dims[1:6].sum())
        first = np.concatenate([[0], np.cumsum(dims[1:5])])  # offset of c = 1..5 in a node
        full_tmin = self.r_mass + N
        full_cones = full_tmin + N
        full_after = full_cones + N * per_node
        ids = [np.arange(self.r_mass), self.r_mass + self.nodes_mass, full_tmin + np.arange(N)]
        for node, c in self.soc_rows:  # node-major, c = 1..5, as _path_cone_rows adds them
            ids.append(full_cones + node * per_node + first[c - 1] + np.arange(dims[c]))
        cones_end = self.r_tmin + N + sum(int(dims[c]) for _, c in self.soc_rows)
        ids.append(full_after + np.arange(self.m - cones_end))
        return np.concatenate(ids).astype(np.int64)

    def trust_norm(self, dz: np.ndarray) -> float:
        """|dz| in the trust region's norm: the largest |component| of the scalar part and
        2-norm of a rotation pair (the step a radius must hold to leave the answer alone)."""
        pairs = np.hypot(dz[self.tr_pairs[:, 0]], dz[self.tr_pairs[:, 1]])
        return float(max(np.abs(dz[self.tr_scalar]).max(), pairs.max()))

    def _soc_entries(self, node: int, c: int) -> tuple[np.ndarray, np.ndarray]:
        L = self.lay
        if c == 1:  # [r1; tan(gs) r2; tan(gs) r3]
            return np.arange(3), L.x_index(node, np.array([0, 1, 2]))
        if c == 2:  # [q_max; q2; q3]
            return np.array([1, 2]), L.x_index(node, np.array([8, 9]))
        if c == 3:  # [omega_max / S_w; omega_hat]
            return np.array([1, 2, 3]), L.x_index(node, np.array([10, 11, 12]))
        if c == 4:  # [T_max / S_u; u_hat]
            return np.array([1, 2, 3]), L.u_index(node, np.arange(3))
        # c == 5: [u1; cos(delta) u_hat]
        return np.array([0, 1, 2, 3]), L.u_index(node, np.array([0, 0, 1, 2]))

    # -- numbers --------------------------------------------------------------------------
    def assemble(
        self,
        disc: dict[str, np.ndarray],
        z_ref: np.ndarray,
        eta: float,
        lam: float,
        scenario: Scenario,
        scaling: Scaling,
        prox_u: float = 0.0,
        fuel: float = 1.0,
    ) -> ConicProblem:
        """Writes the numbers of the subproblem linearized about the scaled iterate z_ref;
        prox_u > 0 adds (prox_u / 2) |u_hat - u_hat_ref|^2 (SCvxSettings.prox_u); ``fuel``
        weighs the final-mass term (0: the polish, SCvxSettings.polish). The blocks in the
        order of _build."""
        b = np.zeros(self.m)
        vals = [
            self._dynamics_values(disc, scaling, b),
            *self._boundary_values(scenario, scaling, b),
            *self._nonneg_values(z_ref, eta, scenario.params, scaling, b),
            *self._cone_values(z_ref, eta, scenario.params, scaling, b),
        ]
        data = np.concatenate(vals)[self.perm]
        Amat = sp.csc_matrix((data, self.indices, self.indptr), shape=(self.m, self.n))
        P, q = self._objective(z_ref, lam, prox_u, fuel)
        return ConicProblem(P=P, q=q, A=Amat, b=b, cones=list(self.cones))

    def _dynamics_values(
        self, disc: dict[str, np.ndarray], sc: Scaling, b: np.ndarray
    ) -> np.ndarray:
        """x_hat_{k+1} - A_hat x_hat_k - Bm_hat u_hat_k - Bp_hat u_hat_{k+1}
        - Sigma_hat sigma_hat - nu = Sx^-1 (A c_x + z - c_x)"""
        Sx, cx, Su, Ss = sc.Sx, sc.cx, sc.Su, sc.Ss
        A, Bm, Bp, S, zk = disc["A"], disc["Bm"], disc["Bp"], disc["Sigma"], disc["z"]
        inv = 1.0 / Sx
        Ah = -(inv[None, :, None] * A * Sx[None, None, :])
        Bmh = -(inv[None, :, None] * Bm * Su)
        Bph = -(inv[None, :, None] * Bp * Su)
        Sh = -(inv[None, :] * S * Ss)
        nI = self.N - 1
        ones = np.ones((nI, NX))
        Ah = Ah[:, self.a_pattern]  # its structural nonzeros, row-major
        dyn = np.concatenate(
            [ones, Ah, Bmh.reshape(nI, -1), Bph.reshape(nI, -1), Sh, -ones], axis=1
        )
        b[self.r_dyn : self.r_dyn + NX * nI] = (inv * (A @ cx + zk - cx)).ravel()
        return dyn.ravel()

    def _boundary_values(self, scenario: Scenario, sc: Scaling, b: np.ndarray) -> list[np.ndarray]:
        xf = scenario.x_final_target()
        b[self.r_x0 : self.r_x0 + NX] = sc.scale_x(scenario.x0)
        b[self.r_xf : self.r_xf + len(self.final_idx)] = ((xf - sc.cx) / sc.Sx)[self.final_idx]
        return [np.ones(NX), np.ones(len(self.final_idx))]

    def _nonneg_values(
        self, z_ref: np.ndarray, eta: float, p: Params, sc: Scaling, b: np.ndarray
    ) -> list[np.ndarray]:
        N, L, ne, ns = self.N, self.lay, self.n_nu_scalar, self.tr_scalar.size
        # T_min: -(T_ref/|T_ref|) . u_hat - s' + s = -T_min / S_u  (s >= 0).
        u_ref = z_ref[L.iu : L.isig].reshape(N, NU)
        dirs = u_ref / np.maximum(np.linalg.norm(u_ref, axis=1, keepdims=True), 1e-12)
        b[self.r_sig] = -SIGMA_MIN / sc.Ss  # sigma_hat >= SIGMA_MIN / Ss
        zr = z_ref[self.tr_scalar]  # trust region: eta -+ (z - z_ref) >= 0
        b[self.r_tr : self.r_tr + ns] = eta + zr
        b[self.r_tr + ns : self.r_tr + 2 * ns] = eta - zr
        b[self.r_tmin : self.r_tmin + N] = -p.T_min / sc.Su
        return [
            # epigraph of |nu_i|: s = t - nu >= 0 and s = t + nu >= 0; then s' >= 0
            np.concatenate([-np.ones(ne), np.ones(ne), -np.ones(ne), -np.ones(ne)]),
            -np.ones(N),
            -np.ones(1),
            np.concatenate([np.ones(ns), -np.ones(ns)]),
            -np.ones(len(self.nodes_mass)),  # m_hat >= 0 (m >= m_dry with c_m = m_dry)
            np.concatenate([-dirs.ravel(), -np.ones(N)]),
        ]

    def _cone_values(
        self, z_ref: np.ndarray, eta: float, p: Params, sc: Scaling, b: np.ndarray
    ) -> list[np.ndarray]:
        """The path-constraint cones (s = b - A z), then the virtual-control pairs
        s = [t; nu_a; nu_b] and the trust-region pairs s = [eta; z_a - ref_a; z_b - ref_b]."""
        tg, cg = p.tan_glideslope, p.cos_gimbal
        soc_vals = {
            1: np.array([-1.0, -tg, -tg]),
            2: np.array([-1.0, -1.0]),
            3: np.array([-1.0, -1.0, -1.0]),
            4: np.array([-1.0, -1.0, -1.0]),
            5: np.array([-1.0, -cg, -cg, -cg]),
        }
        head = {2: p.tilt_q_max / sc.Sx[8], 3: p.omega_max / sc.Sx[10], 4: p.T_max / sc.Su}
        vals = []
        for (_node, c), row in self.soc_rows.items():
            vals.append(soc_vals[c])
            if c in head:
                b[row] = head[c]
        vals.append(np.tile(-np.ones(3), len(self.nu_pairs)))
        npair = len(self.tr_pairs)
        vals.append(-np.ones(2 * npair))
        tb = np.zeros((npair, 3))
        tb[:, 0] = eta
        tb[:, 1:] = -z_ref[self.tr_pairs]
        b[self.r_trp : self.r_trp + 3 * npair] = tb.ravel()
        return vals

    def _objective(
        self, z_ref: np.ndarray, lam: float, prox_u: float, fuel: float
    ) -> tuple[sp.csc_matrix | None, np.ndarray]:
        """-fuel m_hat(t_f) + lambda (sum t + sum s'), plus (prox_u / 2) |u_hat - u_ref|^2 as
        its P part and linear part (the constant dropped)."""
        L = self.lay
        q = np.zeros(self.n)
        q[L.x_index(self.N - 1, IM)] = -fuel
        q[L.ivc :] = lam
        P = None
        if prox_u > 0.0:
            thrust = np.arange(L.iu, L.isig)
            P = sp.csc_matrix((np.full(thrust.size, prox_u), (thrust, thrust)), (self.n,) * 2)
            q[thrust] -= prox_u * z_ref[thrust]
        return P, q


def pack(xh: np.ndarray, uh: np.ndarray, sh: float, lay: Layout) -> np.ndarray:
    z = np.zeros(lay.n)
    z[: lay.iu] = xh.ravel()
    z[lay.iu : lay.isig] = uh.ravel()
    z[lay.isig] = sh
    return z


def unpack(z: np.ndarray, lay: Layout) -> tuple[np.ndarray, np.ndarray, float]:
    N = lay.N
    return (
        z[: lay.iu].reshape(N, NX).copy(),
        z[lay.iu : lay.isig].reshape(N, NU).copy(),
        float(z[lay.isig]),
    )


def physical(z: np.ndarray, lay: Layout, sc: Scaling) -> tuple[np.ndarray, np.ndarray, float]:
    xh, uh, sh = unpack(z, lay)
    return sc.unscale_x(xh), uh * sc.Su, sh * sc.Ss


def scaled(x: np.ndarray, u: np.ndarray, t_f: float, lay: Layout, sc: Scaling) -> np.ndarray:
    return pack(sc.scale_x(x), u / sc.Su, t_f / sc.Ss, lay)


def carry_solution(
    sol: ConicSolution, src: SubproblemTemplate, dst: SubproblemTemplate
) -> ConicSolution:
    """``sol``, an answer to a subproblem of template ``src``, as a starting point of one of
    template ``dst`` (another mask): the rows both keep carry their slack and dual; a row
    only ``dst`` keeps starts at its cone's identity (s = e, z = 0), as the C loop's dropped
    rows (G = 0, h = e, one pattern for every mask) end a solve. The runtime's warm start
    then centres the point on the new data."""
    if src is dst:
        return sol
    pos = np.full(int(max(src.row_ids.max(), dst.row_ids.max())) + 1, -1, dtype=np.int64)
    pos[src.row_ids] = np.arange(src.m)
    j = pos[dst.row_ids]
    have = j >= 0
    s_new = _cone_identity(dst.cones)
    z_new = np.zeros(dst.m)
    s_new[have] = sol.s[j[have]]
    z_new[have] = sol.z[j[have]]
    return replace(sol, s=s_new, z=z_new)


def _cone_identity(cones: list[tuple[ConeKind, int]]) -> np.ndarray:
    """e of a cone list: 0 on the zero cone, 1 on the orthant, (1, 0, ...) on each SOC."""
    parts = []
    for kind, height in cones:
        e = np.zeros(height) if kind == "zero" else np.ones(height)
        if kind == "soc":
            e[1:] = 0.0
        parts.append(e)
    return np.concatenate(parts)
