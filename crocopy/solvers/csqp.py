"""Constrained SQP (mim-solvers' ``SolverCSQP``): SQP whose QP has the nodes' constraint rows.

Each node contributes the rows ``g_lb - g <= Gx δx + Gu δu <= g_ub - g`` of its inequality constraints
(``ng`` rows on running nodes, the ``ng_T`` rows active on the terminal node) and, beyond
mim-solvers, ``-h <= Hx δx + Hu δu <= -h`` for Crocoddyl's equalities (``nh``/``nh_T``); a row with
``|lb - ub| <= 1e-6`` is an equality (a larger ``ρ``).  The QP is solved by the stagewise ADMM of
:mod:`.csqp_admm`; its multipliers ``y`` (> 0 when an upper bound is active) enter the KKT measure ::

    KKT = max( ‖Lx_t + Fx_tᵀ λ_{t+1} - λ_t + [t >= 1] Gx_tᵀ y_t‖∞, ‖Lu_t + Fu_tᵀ λ_{t+1} + Gu_tᵀ y_t‖∞,
               ‖Lx_T - λ_T + Gx_Tᵀ y_T‖∞, max_t ‖d_t‖∞, Ψ ),   Ψ = Σ_t ‖max(lb - g, 0)‖₁ + ‖max(g - ub, 0)‖₁

(``constraint_norm`` = Ψ, ``gap_norm`` = Γ = ``Σ_t ‖d_t‖₁``).  The filter holds ``(J, Γ, Ψ)``; the merit
is ``J + mu_dynamic Γ + mu_constraint Ψ`` (``J + lag_mul_inf_norm_coef · max(‖λ‖∞, ‖y‖∞) (Γ + Ψ)`` when
either weight is negative).  As in mim-solvers 0.3.0: every iteration re-evaluates the nodes; ``y``
and ``ρ̄`` persist between solves unless ``reset_y``/``reset_rho``; the regularisation goes down after
every accepted step; the solve stops (False) when no step is accepted.  Unlike it: ``stepLength``
reports the step actually taken, the rows are sized from ``ng_T`` on the terminal node (a constraint
present but inactive there is fine), equalities ``nh > 0`` are accepted, and ``rho_sparse`` set by the
user is the ``ρ̄`` each solve starts from.

With kernels on, the rows are read from the nodes' ``g, Gx, Gu, h, Hx, Hu`` in one compiled pass (which also
gives ``Ψ`` and ``gfeas``, the norm of the inequality rows' violation) and each QP's ADMM iterations run in
one compiled call (:mod:`.csqp_kernel`; one call per iteration when ``max_solve_time`` is finite or
``with_qp_callbacks`` prints them).
"""

from __future__ import annotations

import time
from collections.abc import Iterator
from operator import is_

import numpy as np

from .. import kernels
from ..enums import FeasibilityNorm
from ..shooting import ShootingProblem
from ..versioning import STRUCTURE, ParametersVersion, changes_since, parameter_owners
from . import csqp_kernel
from .base import BackwardPassError, CountSetting, FlagSetting, Setting
from .csqp_admm import StagewiseADMM
from .ddp import SolverDDP
from .horizon import stores
from .sqp import SolverSQP
from .std_vector import StdVec_VectorXs
from .stopwatch import profiling


def _manager(model):
    """The ``ConstraintModelManager`` of an action model (directly or through its differential model)."""
    for owner in (model, getattr(model, "differential", None)):
        manager = getattr(owner, "constraints", None)
        if manager is not None and hasattr(manager, "constraints"):
            return manager
    return None


def _bounds(model, terminal: bool) -> tuple[np.ndarray, np.ndarray]:
    """``(lb, ub)`` of a node's rows: its inequality bounds then zeros for its equalities."""
    ng, nh = (model.ng_T, model.nh_T) if terminal else (model.ng, model.nh)
    if not terminal or ng == model.ng:
        lb, ub = np.array(model.g_lb[:ng], dtype=float), np.array(model.g_ub[:ng], dtype=float)
    else:
        manager = _manager(model)
        if manager is None:
            raise ValueError(f"terminal model {type(model).__name__} has ng_T = {ng} != ng = {model.ng} "
                             "and no constraint manager to read the terminal bounds from")
        items = [i.constraint for i in manager.constraints.values()
                 if i.active and i.constraint.T_constraint and i.constraint.ng]
        lb = np.concatenate([c.lb for c in items]) if items else np.zeros(0)
        ub = np.concatenate([c.ub for c in items]) if items else np.zeros(0)
    return np.r_[lb, np.zeros(nh)], np.r_[ub, np.zeros(nh)]


_ROW_NAMES = ("g", "h", "Gx", "Gu", "Hx", "Hu")
"""The data arrays a node's QP rows are read from (:func:`.csqp_kernel.node_rows`)."""


class _Terminal:
    """The terminal node's LQ terms under the names the Riccati pass reads (``Lx``, ``Lxx``)."""

    def __init__(self, data) -> None:
        self.Lx, self.Lxx = data.Lx, data.Lxx


class SolverCSQP(SolverSQP):
    """mim-solvers' ``SolverCSQP(problem)``: SQP with inequality (and equality) rows, QP by ADMM.

    Settings (mim-solvers' names and defaults): those of :class:`~crocopy.solvers.sqp.SolverSQP`
    with ``mu_dynamic = mu_constraint = 10``, plus ``lag_mul_inf_norm_coef = 10``,
    ``max_qp_iters = 1000``, ``eps_abs = eps_rel = 1e-4``, ``sigma = 1e-6``, ``alpha = 1.6``,
    ``rho_sparse = 0.1``, ``rho_min = 1e-6``, ``rho_max = 1e3``, ``rho_update_interval = 25``,
    ``adaptive_rho_tolerance = 5``, ``equality_qp_initial_guess = True``, ``reset_y = reset_rho = False``,
    ``update_rho_with_heuristic = False``, ``remove_reg = False``, ``with_qp_callbacks = False``,
    ``max_solve_time = inf`` (seconds).  Read-outs: ``KKT``, ``merit``, ``gap_norm``, ``constraint_norm``,
    ``qp_iters``, ``norm_primal``, ``norm_dual``, ``norm_primal_rel``, ``norm_dual_rel``, ``dx``, ``du``,
    ``dx_tilde``, ``du_tilde``, ``lag_mul``, ``y``, ``z``, ``rho_vec``, ``max_solve_time_reached``.
    """

    # Compiled nodes write the rows CSQP reads (g, h and their Jacobians in the action datas: constraint_rows.py).
    _nodes_compiled = True

    #: Settings checked on assignment (ValueError or TypeError naming the setting, its range and the value given);
    #: a negative ``mu_dynamic``/``mu_constraint`` selects the merit weighted by the multipliers.
    mu_constraint = Setting(None, allow_inf=False)
    lag_mul_inf_norm_coef = Setting(allow_inf=False)
    max_qp_iters = CountSetting()
    eps_abs = Setting(allow_inf=False)
    eps_rel = Setting(allow_inf=False)
    sigma = Setting(allow_inf=False)
    alpha = Setting(0.0, strict=True, allow_inf=False, maximum=2.0)
    rho_min = Setting(0.0, strict=True, allow_inf=False)
    rho_max = Setting(0.0, strict=True)
    rho_update_interval = CountSetting(1)
    adaptive_rho_tolerance = Setting(0.0, strict=True, allow_inf=False)
    equality_qp_initial_guess = FlagSetting()
    reset_y = FlagSetting()
    reset_rho = FlagSetting()
    update_rho_with_heuristic = FlagSetting()
    remove_reg = FlagSetting()
    with_qp_callbacks = FlagSetting()
    max_solve_time = Setting()

    def __init__(self, problem: ShootingProblem) -> None:
        super().__init__(problem)
        self.mu_dynamic = 10.0
        self.mu_constraint = 10.0
        self.lag_mul_inf_norm_coef = 10.0
        self.max_qp_iters = 1000
        self.eps_abs = 1e-4
        self.eps_rel = 1e-4
        self.sigma = 1e-6
        self.alpha = 1.6
        self.rho_min = 1e-6
        self.rho_max = 1e3
        self.rho_update_interval = 25
        self.adaptive_rho_tolerance = 5
        self.equality_qp_initial_guess = True
        self.reset_y = False
        self.reset_rho = False
        self.update_rho_with_heuristic = False
        self.remove_reg = False
        self.with_qp_callbacks = False
        self.max_solve_time = np.inf
        self.max_solve_time_reached = False
        self.constraint_norm = 0.0
        self.constraint_norm_try = 0.0
        self.qp_iters = 0.0
        self.norm_primal = self.norm_dual = self.norm_primal_rel = self.norm_dual_rel = 0.0
        self._rho_base = 0.1
        self._build_qp()

    def _node_bounds(self) -> list[tuple[np.ndarray, np.ndarray]]:
        models = [*self.problem.runningModels, self.problem.terminalModel]
        self._bounds_seen = (ParametersVersion.value, STRUCTURE[0])
        owners = {id(o): o for m in models for o in parameter_owners(_manager(m) or m)}
        self._bounds_owners = list(owners.values())
        return [_bounds(m, t == self.problem.T) for t, m in enumerate(models)]

    def _build_qp(self, bounds: list[tuple[np.ndarray, np.ndarray]] | None = None) -> None:
        problem = self.problem
        models = [*problem.runningModels, problem.terminalModel]
        ndx = [m.state.ndx for m in models]
        nu = [m.nu for m in problem.runningModels] + [0]
        self._qp = qp = StagewiseADMM(ndx, nu, self._node_bounds() if bounds is None else bounds)
        self._ngh = np.array([(m.ng_T, m.nh_T) if t == problem.T else (m.ng, m.nh) for t, m in enumerate(models)],
                             dtype=np.int64)
        self._row_addr = np.zeros((len(models), len(_ROW_NAMES)), dtype=np.int64)
        self._row_seen: list = []
        self._row_datas: list = []
        self._row_watch = True
        self._row_out = np.zeros(3)
        qp.rho_bar = self._rho_base
        qp.assign_rho(self.rho_min)

    def _on_problem_change(self) -> bool:
        changed = super()._on_problem_change()
        self._build_qp()
        return changed

    def __setstate__(self, state: dict) -> None:
        super().__setstate__(state)
        self._row_datas, self._row_seen, self._row_watch = [], [], True  # addresses are not valid in a copy

    # ------------------------------------------------------------------ read-outs
    @property
    def rho_sparse(self) -> float:
        """The ADMM's current base ``ρ̄``; assigning it sets the ``ρ̄`` each solve starts from too."""
        return self._qp.rho_bar

    @rho_sparse.setter
    def rho_sparse(self, value: float) -> None:
        value = float(value)
        if not value > 0.0:
            raise ValueError(f"rho_sparse must be positive, got {value}")
        self._rho_base = self._qp.rho_bar = value
        self._qp.assign_rho(self.rho_min)

    @property
    def y(self) -> StdVec_VectorXs:
        """Multipliers of each node's rows (T+1 vectors)."""
        return StdVec_VectorXs(r.y for r in self._qp.rows)

    @property
    def z(self) -> StdVec_VectorXs:
        return StdVec_VectorXs(r.z for r in self._qp.rows)

    @property
    def rho_vec(self) -> StdVec_VectorXs:
        return StdVec_VectorXs(r.rho for r in self._qp.rows)

    @property
    def dx_tilde(self) -> StdVec_VectorXs:
        return StdVec_VectorXs(self._qp.dx)

    @property
    def du_tilde(self) -> StdVec_VectorXs:
        return StdVec_VectorXs(self._qp.du)

    # ------------------------------------------------------------------ solve
    def _follow_bounds(self) -> None:
        """Follow the constraints' bounds (``updateBounds``) and rows (a constraint switched on or off) when the
        clocks moved since they were read: new bounds of the same shapes are taken in place (the ADMM state is kept,
        as mim-solvers reads its bounds at every QP), new shapes make the QP again."""
        clock, structure = self._bounds_seen
        if structure == STRUCTURE[0] and (clock == ParametersVersion.value
                                          or not changes_since(self._bounds_owners, clock)):
            self._bounds_seen = (ParametersVersion.value, structure)
            return
        bounds = self._node_bounds()
        rows = self._qp.rows
        if any(lb.shape != r.lb.shape for (lb, _), r in zip(bounds, rows)):
            self._build_qp(bounds)
        elif any(not np.array_equal(lb, r.lb) or not np.array_equal(ub, r.ub) for (lb, ub), r in zip(bounds, rows)):
            self._qp.update_bounds(bounds)

    def _start_sqp(self, init_xs, init_us, regInit) -> None:
        super()._start_sqp(init_xs, init_us, regInit)
        self._follow_bounds()
        if self.remove_reg:
            self.preg = self.dreg = 0.0
        self.max_solve_time_reached = False

    def _timed_out(self) -> bool:
        if time.perf_counter() - self._t0 >= self.max_solve_time:
            self.max_solve_time_reached = True
        return self.max_solve_time_reached

    def _iterate_sqp(self, maxiter: int) -> bool:
        if maxiter == 0:
            self.calc(True)
            self._reset_rho()
        for self.iter in range(maxiter):
            if self._timed_out():
                return self._stop(f"max_solve_time = {self.max_solve_time:g} s reached")
            self.calc(True)
            if self.iter == 0 and not self.reset_rho:
                self._reset_rho()
            if not self._solve_qp():
                return self._stop(f"regularization reached reg_max = {self.reg_max:g} in the QP")
            if self.qp_iters == 0:
                return self._stop(f"max_solve_time = {self.max_solve_time:g} s reached in the QP")
            self.checkKKTConditions()
            self._run_callbacks()
            if self.KKT <= self.termination_tolerance:
                return self._converged()
            self._filter.append(self._measures())
            self._update_merit()
            if not self._line_search():
                self.reason = "no step accepted by the line search"
                return self._extra_iteration(self.reason)
            if not self.remove_reg:
                self.decreaseRegularization()
        self.iter = maxiter
        return self._extra_iteration(f"maximum number of iterations ({maxiter}) reached")

    def _extra_iteration(self, reason: str) -> bool:
        if self.extra_iteration_for_last_kkt and not self.max_solve_time_reached:
            self.calc(True)
            if self._solve_qp():
                self.checkKKTConditions()
                if self.KKT <= self.termination_tolerance:
                    return self._converged()
        return self._stop(reason)

    def calc(self, recalc: bool = True) -> float:
        """Evaluate and differentiate every node at the current iterate (if ``recalc``); update the gaps,
        ``gap_norm``, the QP rows' data, ``constraint_norm``, ``gfeas`` and ``hfeas``."""
        if recalc:
            self._synced = False
            if type(self).calcDiff is SolverDDP.calcDiff and not profiling():
                self._differentiate()  # calcDiff's gfeas is the one _row_values writes below
                self.computeEqualityFeasibility()
            else:
                self.calcDiff()
        self.gap_norm = self._gap_norm()
        self.constraint_norm = self._row_values(True)
        return self.cost

    def computeInequalityFeasibility(self) -> float:
        """``gfeas``: the norm (``feasNorm``) of ``max(lb - g, 0, g - ub)`` over the QP's inequality rows (the
        terminal node's ``ng_T`` rows with their own bounds)."""
        self._row_values(False)
        return self.gfeas

    def _row_values(self, load: bool) -> float:
        """``Ψ`` (returned) and ``gfeas`` at the nodes' last ``calc``; if ``load``, the QP rows too (``C``, ``D``
        from ``Gx, Gu`` and ``Hx, Hu``, ``lo/hi = lb/ub - (g, h)``)."""
        qp = self._qp
        if not qp.active:  # no node has a row
            self.gfeas = 0.0
            return 0.0
        saddr = self._row_addresses() if kernels.active else None
        if saddr is None:
            psi, vinf, v1 = self._row_values_numpy(load)
        else:
            out = self._row_out
            csqp_kernel.node_rows(qp.dims, self._ngh, saddr, qp.lb, qp.ub, load, qp.C, qp.D, qp.lo, qp.hi, out)
            psi, vinf, v1 = float(out[0]), float(out[1]), float(out[2])
        self.gfeas = vinf if self.feasNorm == FeasibilityNorm.LInf else v1
        return psi

    def _row_addresses(self) -> np.ndarray | None:
        """Where each node's ``g, h, Gx, Gu, Hx, Hu`` are (rows of the nodes with QP rows), or None when one cannot
        be read in place (not C-contiguous float64: the numpy twin reads it).  Data fields own their arrays
        (:mod:`crocopy.stored`), so the addresses are read once per list of datas (a new list, after the problem's
        nodes changed, comes with a new QP: :meth:`_build_qp`); a data class that makes one of them a property of its
        own has its arrays compared at every call."""
        same = bool(self._row_datas)
        if same and not self._row_watch:
            return self._row_addr
        datas = [*self.problem.runningDatas, self.problem.terminalData]
        active = [datas[t] for t in self._qp.active]
        arrays = [getattr(d, name) for d in active for name in _ROW_NAMES]
        if same and all(map(is_, arrays, self._row_seen)):
            return self._row_addr
        if not all(isinstance(a, np.ndarray) and a.dtype == np.float64 and a.flags.c_contiguous for a in arrays):
            return None
        self._row_datas, self._row_seen = active, arrays
        self._row_watch = not all(stores(type(d), name) for d in active for name in _ROW_NAMES)
        self._row_addr[:] = 0
        for i, t in enumerate(self._qp.active):
            self._row_addr[t] = [a.__array_interface__["data"][0] for a in arrays[6 * i:6 * i + 6]]
        return self._row_addr

    def _node_rows(self, problem) -> Iterator[tuple]:
        """``(t, rows, data, ng, nh, c)`` of every node with QP rows, ``c = (g, h)`` at the node's last ``calc``."""
        datas = [*problem.runningDatas, problem.terminalData]
        for t in self._qp.active:
            d = datas[t]
            ng, nh = self._ngh[t]
            yield t, self._qp.rows[t], d, ng, nh, np.r_[d.g[:ng], d.h[:nh]]

    def _row_values_numpy(self, load: bool) -> tuple[float, float, float]:
        """Numpy twin of :func:`.csqp_kernel.node_rows`: ``(Ψ, ‖v‖∞, ‖v‖₁)``."""
        problem = self.problem
        psi = vinf = v1 = 0.0
        for t, r, d, ng, nh, c in self._node_rows(problem):
            if load:
                r.C[:ng], r.C[ng:] = d.Gx[:ng], d.Hx[:nh]
                if t < problem.T:
                    r.D[:ng], r.D[ng:] = d.Gu[:ng], d.Hu[:nh]
                np.subtract(r.lb, c, out=r.lo)
                np.subtract(r.ub, c, out=r.hi)
            psi += float(np.maximum(r.lb - c, 0.0).sum() + np.maximum(c - r.ub, 0.0).sum())
            v = np.abs(np.maximum(np.maximum(r.lb[:ng] - c[:ng], 0.0), c[:ng] - r.ub[:ng]))
            vinf, v1 = max(vinf, float(v.max(initial=0.0))), v1 + float(v.sum())
        return psi, vinf, v1

    def _reset_rho(self) -> None:
        self._qp.rho_bar = self._rho_base
        self._qp.assign_rho(self.rho_min)

    def computeDirection(self, recalcDiff: bool = True) -> None:
        """Evaluate the nodes (``recalcDiff`` is ignored, as in mim-solvers: they always are) and solve the QP."""
        self.calc(True)
        if not self._solve_qp():
            raise BackwardPassError(f"regularization reached reg_max = {self.reg_max:g} in the QP")

    def _solve_qp(self) -> bool:
        """Solve the QP at the current iterate (raising the regularisation on a failed factorisation);
        False at ``reg_max``.  Leaves the step in ``dx``/``du`` and the multipliers in ``lag_mul``/``y``."""
        while True:
            try:
                self._admm()
                break
            except BackwardPassError:
                self.preg = self.dreg = min(max(self.preg, self.reg_min) * self.reg_incFactor, self.reg_max)
                if self.preg >= self.reg_max:
                    return False
        qp = self._qp
        dx, du, lam = self._steps
        np.copyto(dx, qp.dx_s)
        np.copyto(du, qp.du_s)
        if kernels.active:
            qp.multipliers_into(lam)
        else:
            for a, b in zip(self.lag_mul, qp.multipliers()):
                a[:] = b
        self.norm_primal, self.norm_dual = qp.r_prim, qp.r_dual
        self.norm_primal_rel, self.norm_dual_rel = qp.s_prim, qp.s_dual
        return True

    def _admm(self) -> None:
        qp, problem = self._qp, self.problem
        mu = 0.0 if self.remove_reg else float(self.preg)
        qp.z[:] = 0.0
        if self.reset_y:
            qp.y[:] = 0.0
        if self.reset_rho:
            self._reset_rho()
        else:
            qp.assign_rho(self.rho_min)
        if kernels.active:
            self._admm_compiled(mu)
            return
        lq = [*problem.runningDatas, _Terminal(problem.terminalData)]
        if self.equality_qp_initial_guess:
            self.backwardPass_without_constraints(lq, mu)
        interval = max(int(self.rho_update_interval), 1)
        self.qp_iters = float(self.max_qp_iters + 1)
        for j in range(1, int(self.max_qp_iters) + 1):
            if self._timed_out():
                self.qp_iters = 0.0 if j == 1 else float(j - 1)
                return
            qp.riccati(lq, self.fs, self.sigma, mu, True, interval == 1 or j % interval == 1)
            qp.rollout(lq, self.fs)
            if qp.iterate(j, self):
                self.qp_iters = float(j)
                return

    def _admm_compiled(self, mu: float) -> None:
        """The ADMM iterations in one compiled call (:meth:`.StagewiseADMM.run`), or one call per iteration when
        the QP prints its iterations or the solve has a time limit (checked before each iteration)."""
        qp, problem = self._qp, self.problem
        args = (self._derivative_addresses(), self._horizon.addr, problem.terminalData, self, mu)
        last = int(self.max_qp_iters)
        self.qp_iters = float(last + 1)
        if not self.with_qp_callbacks and self.max_solve_time == np.inf:
            j = qp.run(*args, 1, last + 1, self.equality_qp_initial_guess)
            if j:
                self.qp_iters = float(j)
            return
        if self.equality_qp_initial_guess:
            qp.run(*args, 1, 1, True)
        interval = max(int(self.rho_update_interval), 1)
        for j in range(1, last + 1):
            if self._timed_out():
                self.qp_iters = 0.0 if j == 1 else float(j - 1)
                return
            done = qp.run(*args, j, j + 1, False)
            if j % interval == 0 and self.with_qp_callbacks:
                qp.stopping_test(j, self)  # prints the iteration
            if done:
                self.qp_iters = float(j)
                return

    def backwardPass_without_constraints(self, lq=None, mu: float | None = None) -> None:
        """The QP without rows and without ``σ`` (its step becomes the ADMM's anchor ``w̄``)."""
        problem = self.problem
        lq = [*problem.runningDatas, _Terminal(problem.terminalData)] if lq is None else lq
        mu = float(self.preg) if mu is None else mu
        self._qp.riccati(lq, self.fs, 0.0, mu, False, True)
        self._qp.rollout(lq, self.fs)
        self._qp.set_anchor()

    # ------------------------------------------------------------------ KKT, merit, line search
    def _kkt_rows(self) -> tuple:
        qp = self._qp
        return qp.dims, qp.C, qp.D, qp.y

    def _constraint_force_x(self, t: int) -> np.ndarray | float:
        r = self._qp.rows[t]
        return r.C.T @ r.y if t and r.lb.size else 0.0

    def _constraint_force_u(self, t: int) -> np.ndarray | float:
        r = self._qp.rows[t]
        return r.D.T @ r.y if r.lb.size else 0.0

    def _kkt_constraint_term(self) -> float:
        return self.constraint_norm

    def _measures(self) -> tuple:
        return (self.cost, self.gap_norm, self.constraint_norm)

    def _trial_measures(self) -> tuple:
        return (self.cost_try, self.gap_norm_try, self.constraint_norm_try)

    def _weights(self) -> tuple[float, float]:
        if self.mu_dynamic >= 0.0 and self.mu_constraint >= 0.0:
            return self.mu_dynamic, self.mu_constraint
        lam = max(max(float(np.abs(v).max(initial=0.0)) for v in self.lag_mul),
                  max(float(np.abs(r.y).max(initial=0.0)) for r in self._qp.rows))
        w = self.lag_mul_inf_norm_coef * lam
        return w, w

    def _update_merit(self) -> None:
        self._merit_weights = self._weights()
        wd, wc = self._merit_weights
        self.merit = self.cost + wd * self.gap_norm + wc * self.constraint_norm

    def _trial_merit(self) -> float:
        wd, wc = getattr(self, "_merit_weights", (self.mu_dynamic, self.mu_constraint))
        return self.cost_try + wd * self.gap_norm_try + wc * self.constraint_norm_try

    def _after_trial(self) -> None:
        self.constraint_norm_try = self._row_values(False)
