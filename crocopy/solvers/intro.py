"""Equality-constrained feasibility-driven DDP (Crocoddyl's ``SolverIntro``).

Each running node's equality rows ``h(x, u) = 0`` (``data.h[:nh]``, ``Hx``, ``Hu``) are linearised,
``Hx δx + Hu δu + h = 0``, and enforced exactly by the node's policy ``δu = -k - K δx`` (Crocoddyl's
sign, ``û = u - α k - K (x̂ ⊖ x)``), so ``Hu k = h`` and ``Hu K = Hx``.  Three ways to get it
(``eq_solver``, :class:`EqualitySolverType`):

* ``LuNull`` / ``QrNull`` (nullspace): ``[Y Z] = YZ`` spans the row space of ``Hu`` (``Y``, ``r =
  Hu_rank`` columns) and its kernel (``Z``), from a fully pivoted LU of ``Hu`` (``Y = Huᵀ`` of the
  pivot rows, ``Z`` the LU kernel) or a column-pivoted QR of ``Huᵀ`` (``Y, Z`` orthonormal).  With
  ``Hy = Hu Y``: ``ks = Hy⁺ h``, ``Ks = Hy⁺ Hx`` and their images ``kz = Y ks``, ``Kz = Y Ks``; the
  rest of the control minimises the Q-function in the kernel, with ``Qzz = Zᵀ Quu Z``,
  ``Qz = Qzz⁻¹ Zᵀ (Qu - Quu Y ks)``, ``Qxz = (Qzz⁻¹ Zᵀ (Qux - Quu Y Ks))ᵀ``, ``Quz = Quu Z Qzz⁻¹``:
  ``k = Y ks + Z Qz``, ``K = Y Ks + Z Qxzᵀ``.
* ``Schur``: the node's KKT system ``[Quu Huᵀ; Hu 0]`` by the Schur complement
  ``Qzz = Hu Quu⁻¹ Huᵀ``: with the right-hand sides ``ks = h - Hu Quu⁻¹ Qu``,
  ``Ks = Hx - Hu Quu⁻¹ Qux`` and ``[λ Λ] = Qzz⁻¹ [ks Ks]``, ``k = Quu⁻¹ (Qu + Huᵀ λ)``,
  ``K = Quu⁻¹ (Qux + Huᵀ Λ)`` (the nullspace attributes are zero).

These attributes hold what Crocoddyl's hold (measured on the same problems).
All three give the same ``k, K`` when ``Hu`` has full row rank.  Nodes without equality rows take the
DDP step.  The value function is the Q-function along the constrained policy,
``Vx = Qx - Kᵀ Qu - Qxu k + Kᵀ Quu k``, ``Vxx = Qxx - Qxu K - Kᵀ Qux + Kᵀ Quu K`` (gap-deflected as
in FDDP).  Pure-state rows (rows ``Hu`` cannot reach) and terminal rows are not enforced by the
policy; they only count in ``hfeas``.

Globalisation (FDDP's rollout and expected improvement ``d``, plus a merit on the equality
feasibility ``hfeas``, all measured against Crocoddyl 3.2.1):

* after the backward pass the penalty grows to ``upsilon = max(upsilon, (d₀ + ½ d₁) / ((1 - rho) h))``
  with ``h`` the ``hfeas`` held before the derivatives (the last accepted iterate's); no update on the
  first iteration of a solve (``iter = 0``), a reused solver's too, whose ``hfeas`` is its last solve's
  (``upsilon`` itself persists from solve to solve unless ``zero_upsilon``);
* a trial step ``α`` changes the merit ``merit = cost + upsilon hfeas`` by ``dPhi = dV + upsilon dfeas``
  (``dfeas = hfeas - hfeas_try``), predicted as ``dPhiexp = dVexp + α upsilon dfeas``; it is accepted
  when ``dPhi > th_acceptStep dPhiexp`` if ``dPhiexp >= 0``, else when ``dV > th_acceptNegStep dVexp``
  (or when ``|d₀| < th_grad``);
* ``stop = max(|d₀ + ½ d₁|, hfeas)``; after the callbacks, ``preg`` decreases after a step longer
  than ``th_stepDec`` that lowered the cost and increases after a step of at most ``th_stepInc`` or
  once ``|d₁| <= th_feas`` (near convergence).
"""

from __future__ import annotations

import enum
import math

import numpy as np
import scipy.linalg

from .. import kernels
from ..enums import FeasibilityNorm
from ..kernels import log_fallback, overridden
from ..shooting import ShootingProblem
from ..versioning import STRUCTURE
from . import intro_kernel, intro_riccati_kernel
from .base import BackwardPassError, FlagSetting, Setting
from .fddp import SolverFDDP
from .intro_buffers import READOUTS, IntroBuffers

__all__ = ["EqualitySolverType", "SolverIntro"]


class EqualitySolverType(enum.IntEnum):
    """How :class:`SolverIntro` enforces the linearised equality rows at a node."""

    LuNull = 0
    QrNull = 1
    Schur = 2

    def __str__(self) -> str:
        return self.name


def full_pivot_lu(A: np.ndarray, rtol: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """``P A Q = L U`` with full pivoting (largest remaining entry first; compiled while
    :func:`crocopy.kernels_enabled`, :mod:`.intro_kernel`, else these numpy steps: the same numbers).

    Returns ``(U, rows, cols, rank)``: ``U`` the upper factor (same shape as ``A``), ``rows``/``cols``
    the permutations (``A[rows][:, cols] = L U``) and the number of pivots above ``rtol`` times the
    largest one.
    """
    U = np.array(A, dtype=float)
    m, n = U.shape
    rows, cols = np.arange(m), np.arange(n)
    if kernels.active:
        rank = intro_kernel.full_pivot_lu_kernel(U, rows, cols, float(rtol))
        return np.triu(U), rows, cols, rank
    rank, first = 0, 0.0
    for k in range(min(m, n)):
        block = np.abs(U[k:, k:])
        i, j = np.unravel_index(int(np.argmax(block.T)), block.T.shape)[::-1]
        pivot = block[i, j]
        if k == 0:
            first = pivot
        if pivot <= rtol * first or pivot == 0.0:
            break
        i, j = i + k, j + k
        U[[k, i]] = U[[i, k]]
        rows[[k, i]] = rows[[i, k]]
        U[:, [k, j]] = U[:, [j, k]]
        cols[[k, j]] = cols[[j, k]]
        factors = U[k + 1 :, k] / U[k, k]
        U[k + 1 :, k:] -= np.outer(factors, U[k, k:])
        U[k + 1 :, k] = factors
        rank += 1
    return np.triu(U), rows, cols, rank


def lu_range_kernel(Hu: np.ndarray, rtol: float) -> tuple[np.ndarray, int]:
    """``[Y Z]`` of ``Hu`` (nh, nu) by fully pivoted LU: ``Y = Huᵀ`` of the pivot rows (in pivot
    order) and ``Z`` the LU kernel basis (identity on the free columns)."""
    U, rows, cols, r = full_pivot_lu(Hu, rtol)
    nu = Hu.shape[1]
    Z = np.zeros((nu, nu - r))
    if nu > r:
        free = np.zeros((nu, nu - r))
        free[:r] = -_triangular_solve(U[:r, :r], U[:r, r:]) if r else 0.0
        free[r:] = np.eye(nu - r)
        Z[cols] = free
    Y = Hu[rows[:r]].T
    return np.hstack([Y, Z]), r


def qr_range_kernel(Hu: np.ndarray, rtol: float) -> tuple[np.ndarray, int]:
    """``[Y Z]`` of ``Hu`` (nh, nu) by column-pivoted Householder QR of ``Huᵀ`` (orthonormal)."""
    nu = Hu.shape[1]
    if not Hu.size:
        return np.eye(nu), 0
    if not np.isfinite(Hu).all():
        raise BackwardPassError("non-finite equality rows")
    Q, R, _ = scipy.linalg.qr(Hu.T, pivoting=True, check_finite=False)
    d = np.abs(np.diag(R))
    r = int(np.sum(d > rtol * d[0])) if d.size and d[0] > 0 else 0
    return Q, r


class SolverIntro(SolverFDDP):
    """Crocoddyl's ``SolverIntro(problem)``: FDDP with equality constraints by nullspace or Schur.

    Parameters
    ----------
    problem : ShootingProblem
        Problem whose running nodes may expose equality rows ``h``/``Hx``/``Hu`` (``nh``).

    Attributes
    ----------
    eq_solver : EqualitySolverType
        ``LuNull`` (default), ``QrNull`` or ``Schur``.
    th_feas : float
        Threshold to define feasibility (default ``1e-4``).
    rho : float
        Fraction in ``[0, 1)`` of the expected reduction kept by the penalty update (default ``0.3``).
    upsilon : float
        Merit penalty on ``hfeas`` (only grows; read-only in Crocoddyl).
    zero_upsilon : bool
        Reset ``upsilon`` to 0 at each :meth:`solve` (default False: it persists).
    Hu_rank, YZ, Hy, Qz, Qzz, Qxz, Quz, kz, Kz, ks, Ks : list
        Per running node, as described in the module docstring (empty for nodes without rows).
    dfeas : float
        ``hfeas - hfeas_try`` of the last trial step.
    th_rank : float
        crocopy's: relative pivot threshold of the rank decisions (machine epsilon, times ``min(nh, nu)``).
    """

    _nodes_compiled = True  # reads only the action datas' values, derivatives and rows (compiled nodes write them)
    th_feas = Setting(allow_inf=False)
    rho = Setting(0.0, maximum=1.0)
    zero_upsilon = FlagSetting()
    x_reg = Setting(allow_inf=False)
    u_reg = Setting(allow_inf=False)
    th_rank = Setting(allow_inf=False)

    def __init__(self, problem: ShootingProblem) -> None:
        super().__init__(problem)
        self.eq_solver = EqualitySolverType.LuNull
        self.th_feas = 1e-4
        self.rho = 0.3
        self._upsilon = 0.0
        self.zero_upsilon = False
        self.dfeas = 0.0
        self.feas = 0.0
        self.x_reg = 0.0
        self.u_reg = 0.0
        self.th_rank = np.finfo(float).eps
        models = problem.runningModels
        self.Hu_rank = [0 for _ in models]
        self.YZ = [np.eye(m.nu) for m in models]
        self.Hy = [np.zeros((m.nh, 0)) for m in models]
        self.Qz = [np.zeros(0) for _ in models]
        self.Qzz = [np.zeros((0, 0)) for _ in models]
        self.Qxz = [np.zeros((m.state.ndx, 0)) for m in models]
        self.Quz = [np.zeros((m.nu, 0)) for m in models]
        self.kz = [np.zeros(0) for _ in models]
        self.Kz = [np.zeros((0, m.state.ndx)) for m in models]
        self.ks = [np.zeros(0) for _ in models]
        self.Ks = [np.zeros((0, m.state.ndx)) for m in models]

    @property
    def upsilon(self) -> float:
        return self._upsilon

    @property
    def eq_solver(self) -> EqualitySolverType:
        return self._eq_solver

    @eq_solver.setter
    def eq_solver(self, value: EqualitySolverType) -> None:
        try:
            self._eq_solver = EqualitySolverType(value)
        except ValueError as exc:
            raise ValueError(f"eq_solver must be an EqualitySolverType (LuNull, QrNull, Schur), got {value!r}") from exc

    # ------------------------------------------------------------------ main loop
    def _start(self, init_xs, init_us, is_feasible: bool, init_reg) -> None:
        super()._start(init_xs, init_us, is_feasible, init_reg)
        if self.zero_upsilon:
            self._upsilon = 0.0

    def computeDirection(self, recalc: bool = True) -> None:
        """Derivatives (if ``recalc``), constrained backward pass, and the penalty update.

        The update divides by the equality feasibility held before the derivatives refreshed it:
        the previous accepted iterate's; none at a solve's first iteration (``iter = 0``).
        """
        hfeas = self.hfeas if self.iter else 0.0
        super().computeDirection(recalc)
        if hfeas > 0.0:
            self._upsilon = max(self._upsilon, (self._dg + 0.5 * self._dq) / ((1.0 - self.rho) * hfeas))

    def _equality_norm(self) -> float:
        """The norm (``feasNorm``) of every node's ``h``: one compiled call over the datas' rows while
        :func:`crocopy.kernels_enabled` (:func:`.intro_riccati_kernel.row_norm`)."""
        p = self.problem
        if kernels.active:
            tables = self._intro_tables()
            linf = self.feasNorm == FeasibilityNorm.LInf
            return intro_riccati_kernel.row_norm(tables.row_addresses(p), tables.h_rows, linf)
        return self._norm([d.h for d in (*p.runningDatas, p.terminalData)])

    def computeEqualityFeasibility(self) -> float:
        """Norm of the equality-constraint values ``h`` over all nodes (:meth:`_equality_norm`)."""
        self.hfeas = self._equality_norm()
        return self.hfeas

    def tryStep(self, steplength: float = 1.0) -> float:
        """Roll out with step ``steplength``; returns the cost reduction ``dV``.

        Also sets ``hfeas_try``, ``dfeas``, ``dPhi`` and the predictions ``dVexp``, ``dPhiexp``.
        """
        self.forwardPass(steplength)
        self.expectedImprovement()
        self.hfeas_try = self._equality_norm()
        self.dfeas = self.hfeas - self.hfeas_try
        self.dV = self.cost - self.cost_try
        self.dPhi = self.dV + self._upsilon * self.dfeas
        self.dVexp = steplength * (self.d[0] + 0.5 * steplength * self.d[1])
        self.dPhiexp = self.dVexp + steplength * self._upsilon * self.dfeas
        return self.dV

    def _accept(self, alpha: float) -> bool:
        if self.dPhiexp >= 0:
            return abs(self.d[0]) < self.th_grad or self.dPhi > self.th_acceptStep * self.dPhiexp
        return abs(self.d[0]) < self.th_grad or self.dV > self.th_acceptNegStep * self.dVexp

    def _accept_trial(self, alpha: float) -> None:
        super()._accept_trial(alpha)
        self.hfeas = self.hfeas_try
        self.merit = self.cost + self._upsilon * self.hfeas

    def _close_iteration(self, was_feasible: bool, rollout_error: str | None = None) -> bool | None:
        """Stopping value and callbacks, then the regularisation update of Crocoddyl's SolverIntro.

        The update comes after the callbacks (the verbose line shows the ``preg`` the iteration used):
        ``preg`` decreases after a step longer than ``th_stepDec`` that lowered the cost, and increases
        after a step of at most ``th_stepInc`` or once ``|d₁| <= th_feas``.
        """
        self.stoppingCriteria()
        self._run_callbacks()
        if was_feasible and self.stop < self.th_stop:
            self.reason = "converged"
            return True
        if self.stepLength > self.th_stepDec and self.dV >= 0.0:
            self.decreaseRegularization()
        if self.stepLength <= self.th_stepInc or abs(self.d[1]) <= self.th_feas:
            self.increaseRegularization()
            if self.preg >= self.reg_max:
                last = f" (last trial: {rollout_error})" if rollout_error is not None else ""
                return self._fail(f"regularization reached reg_max = {self.reg_max:g}{last}")
        return None

    def stoppingCriteria(self) -> float:
        """``stop = max(|d₀ + ½ d₁|, hfeas)``."""
        self.stop = max(abs(self.d[0] + 0.5 * self.d[1]), self.hfeas)
        return self.stop

    def __getstate__(self) -> dict:
        state = super().__getstate__()
        state.pop("_intro_held", None)
        state["_readout_key"] = None
        return state

    # ------------------------------------------------------------------ backward pass
    _node_steps = (
        "computeActionValueFunction",
        "computeGains",
        "computeValueFunction",
        "_finish_value_function",
        "_constrained_gains",
        "_schur_gains",
        "_constrained_value_function",
    )
    """The node steps the compiled constrained pass fuses: a subclass overriding one gets the Python steps."""

    def backwardPass(self) -> None:
        """Riccati recursion with each node's equality rows enforced by ``eq_solver``; without equality rows on a
        node with controls, FDDP's (compiled where it applies: the same node steps).

        While :func:`crocopy.kernels_enabled` and no subclass overrides a node step, the whole constrained
        recursion is one compiled call (:func:`.intro_riccati_kernel.intro_pass`, the same steps; the per-node
        read-outs ``YZ`` ... ``Quz`` are then views of its buffer); else the Python steps below.
        """
        if not self._equality_nodes():
            super().backwardPass()
            return
        if kernels.active:
            steps = overridden(self, SolverIntro, self._node_steps)
            if not steps:
                self._constrained_pass_kernel()
                return
            log_fallback(type(self), steps, "the compiled constrained pass")
        self._readout_key = None
        problem = self.problem
        self._terminal_value_function()
        for t in range(problem.T - 1, -1, -1):
            model, data = problem.runningModels[t], problem.runningDatas[t]
            self.computeActionValueFunction(t, model, data)
            if model.nu and model.nh:
                self._constrained_gains(t, data.h[: model.nh], data.Hx[: model.nh], data.Hu[: model.nh])
                self._constrained_value_function(t)
            else:
                if model.nu:
                    self.computeGains(t)
                self.computeValueFunction(t, model)
            if not (np.isfinite(self.Vx[t]).all() and np.isfinite(self.Vxx[t]).all()):
                raise BackwardPassError(f"non-finite value function at node {t}")

    def _constrained_pass_kernel(self) -> None:
        """The constrained recursion in one compiled call; raises what the Python steps raise at the first node
        (from the end) that fails."""
        problem = self.problem
        self._sync_problem()
        tables = self._intro_tables()
        gaps = self._terminal_value_function()
        h = self._horizon
        t, outcome = intro_riccati_kernel.intro_pass(
            self._derivative_addresses(),
            h.addr,
            h.dims,
            tables.row_addresses(problem),
            tables.nh,
            tables.oaddr,
            tables.ranks,
            float(self.preg),
            gaps,
            int(self._eq_solver),
            float(self.th_rank),
        )
        self._sync_readouts(tables)
        if t >= 0:
            raise self._kernel_failure(t, outcome)

    def _kernel_failure(self, t: int, outcome: int) -> Exception:
        """What the Python steps raise where the compiled pass stopped (node ``t``, ``outcome``)."""
        k = intro_riccati_kernel
        if outcome == k.QUU_NOT_PD:
            return self._node_failure(t)
        return BackwardPassError(
            {
                k.QZZ_NOT_PD: f"the reduced Hessian Qzz is not positive definite at node {t}",
                k.SCHUR_QUU_NOT_PD: f"Quu is not positive definite at node {t}",
                k.SCHUR_SINGULAR: f"the Schur complement Hu Quu⁻¹ Huᵀ is singular at node {t}",
                k.NONFINITE_ROWS: "non-finite equality rows",
            }.get(outcome, f"non-finite value function at node {t}")
        )

    def _intro_tables(self) -> IntroBuffers:
        """The compiled pass's tables (:class:`~.intro_buffers.IntroBuffers`), made again when the problem, its nodes
        or a registry's item set changed."""
        problem = self.problem
        key = (id(problem), problem._nodes_version, STRUCTURE[0])
        held = self.__dict__.get("_intro_held")
        if held is None or held[0] != key:
            held = self.__dict__["_intro_held"] = (key, IntroBuffers(problem.runningModels, problem.terminalModel))
            self._readout_key = None
        return held[1]

    def _sync_readouts(self, tables: IntroBuffers) -> None:
        """Point the read-out lists of the constrained nodes at the compiled pass's buffer, shaped by the ranks and
        the method (again only when one of them changed: the views show whatever the pass wrote)."""
        method = int(self._eq_solver)
        key = (method, tables.ranks.tobytes())
        if self.__dict__.get("_readout_key") == key:
            return
        lists = [getattr(self, name) for name in READOUTS]
        for t in tables.constrained:
            for held, view in zip(lists, tables.views(t, method)):
                held[t] = view
            self.Hu_rank[t] = int(tables.ranks[t])
        self._readout_key = key

    def _equality_nodes(self) -> bool:
        """Whether a running node with controls has equality rows (found again when the problem, its nodes or a
        registry's item set changed)."""
        problem = self.problem
        key = (id(problem), problem._nodes_version, STRUCTURE[0])
        held = self.__dict__.get("_equality_seen")
        if held is None or held[0] != key:
            held = self.__dict__["_equality_seen"] = (key, any(m.nu and m.nh for m in problem.runningModels))
        return held[1]

    def _constrained_gains(self, t: int, h: np.ndarray, Hx: np.ndarray, Hu: np.ndarray) -> None:
        Quu, Qu, Qxu = self.Quu[t], self.Qu[t], self.Qxu[t]
        if self._eq_solver == EqualitySolverType.Schur:
            self._schur_gains(t, h, Hx, Hu, Quu, Qu, Qxu)
            return
        if self._eq_solver == EqualitySolverType.LuNull:
            YZ, r = lu_range_kernel(Hu, self.th_rank * min(Hu.shape))
        else:
            YZ, r = qr_range_kernel(Hu, self.th_rank * min(Hu.shape))
        Y, Z = YZ[:, :r], YZ[:, r:]
        Hy = Hu @ Y
        ks, Ks = _least_squares(Hy, h, Hx)
        Yks, YKs = Y @ ks, Y @ Ks
        QuuZ = Quu @ Z
        Qzz = Z.T @ QuuZ
        kz = Z.T @ Qu - QuuZ.T @ Yks
        Kz = Z.T @ Qxu.T - QuuZ.T @ YKs
        Quz = QuuZ
        if Z.shape[1]:
            chol, info = scipy.linalg.lapack.dpotrf(Qzz, lower=0, clean=1)
            if info != 0:
                raise BackwardPassError(f"the reduced Hessian Qzz is not positive definite at node {t}")
            kz = _cholesky_solve(chol, kz)
            Kz = _cholesky_solve(chol, Kz)
            Quz = _cholesky_solve(chol, QuuZ.T).T
        self.k[t][:] = Yks + Z @ kz
        self.K[t][:] = YKs + Z @ Kz
        self.Hu_rank[t], self.YZ[t], self.Hy[t] = r, YZ, Hy
        self.ks[t], self.Ks[t], self.kz[t], self.Kz[t] = ks, Ks, Yks, YKs
        self.Qz[t], self.Qzz[t], self.Qxz[t], self.Quz[t] = kz, Qzz, Kz.T, Quz

    def _schur_gains(self, t, h, Hx, Hu, Quu, Qu, Qxu) -> None:
        chol, info = scipy.linalg.lapack.dpotrf(Quu, lower=0, clean=1)
        if info != 0:
            raise BackwardPassError(f"Quu is not positive definite at node {t}")
        QuuinvHuT = _cholesky_solve(chol, Hu.T)
        Qzz = Hu @ QuuinvHuT
        kq = _cholesky_solve(chol, np.column_stack([Qu, Qxu.T]))
        rhs = np.column_stack([h, Hx]) - Hu @ kq
        try:
            lam = scipy.linalg.solve(Qzz, rhs, assume_a="pos")
        except (np.linalg.LinAlgError, ValueError) as exc:
            raise BackwardPassError(f"the Schur complement Hu Quu⁻¹ Huᵀ is singular at node {t}") from exc
        self.k[t][:] = kq[:, 0] + QuuinvHuT @ lam[:, 0]
        self.K[t][:] = kq[:, 1:] + QuuinvHuT @ lam[:, 1:]
        nu, nh, ndx = Hu.shape[1], Hu.shape[0], Hx.shape[1]
        self.Hu_rank[t] = int(np.linalg.matrix_rank(Hu))
        self.ks[t], self.Ks[t], self.Qzz[t] = rhs[:, 0], rhs[:, 1:], Qzz
        self.YZ[t], self.Hy[t], self.Qz[t] = np.zeros((nu, nu)), np.zeros((nh, nh)), np.zeros(nh)
        self.Qxz[t], self.Quz[t] = np.zeros((ndx, nh)), np.zeros((nu, nh))
        self.kz[t], self.Kz[t] = np.zeros(nu), np.zeros((nu, ndx))

    def _constrained_value_function(self, t: int) -> None:
        """``V`` of node ``t`` along the constrained policy (gap-deflected when infeasible)."""
        Qx, Qu, Qxx, Qxu, Quu = self.Qx[t], self.Qu[t], self.Qxx[t], self.Qxu[t], self.Quu[t]
        k, K = self.k[t], self.K[t]
        QuuK = Quu @ K
        self.Vx[t][:] = Qx - K.T @ Qu - Qxu @ k + QuuK.T @ k
        self.Vxx[t][:] = Qxx - Qxu @ K - K.T @ Qxu.T + K.T @ QuuK
        self._finish_value_function(t)


def _cholesky_solve(chol: np.ndarray, B: np.ndarray) -> np.ndarray:
    """``A⁻¹ B`` from the upper Cholesky factor of ``A`` (LAPACK's ``dpotrs``, as ``scipy.linalg.cho_solve`` calls it,
    without its input checks: non-finite values reach the backward pass's own check)."""
    return scipy.linalg.lapack.dpotrs(chol, B, lower=0)[0]


def _triangular_solve(U: np.ndarray, B: np.ndarray) -> np.ndarray:
    """``U⁻¹ B`` for an upper triangular ``U`` (LAPACK's ``dtrtrs``, as ``scipy.linalg.solve_triangular`` calls it)."""
    return scipy.linalg.lapack.dtrtrs(U, B, lower=0)[0]


def _least_squares(A: np.ndarray, b: np.ndarray, B: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``A⁺ b`` and ``A⁺ B`` (A of full column rank; least squares when it has more rows); BackwardPassError on
    non-finite rows (before LAPACK sees them) or where LAPACK fails."""
    if not A.shape[1]:
        return np.zeros(0), np.zeros((0, B.shape[1]))
    rhs = np.column_stack([b, B])
    total = A.sum() + rhs.sum()
    if not math.isfinite(total) and not (np.isfinite(A).all() and np.isfinite(rhs).all()):
        raise BackwardPassError("non-finite equality rows")
    try:
        sol = np.linalg.lstsq(A, rhs, rcond=None)[0]
    except np.linalg.LinAlgError as exc:
        raise BackwardPassError(f"the equality rows' least squares failed ({exc})") from exc
    return sol[:, 0], sol[:, 1:]
