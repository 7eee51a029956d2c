"""Multiple-shooting SQP with a filter line search (mim-solvers' ``SolverSQP``, Jordana et al. 2023).

At an iterate ``(xs, us)`` with gaps ``d_{t+1} = f(x_t, u_t) ⊖ x_{t+1}`` (``fs``), the step solves the
Gauss-Newton QP ::

    min Σ_t ½ δx_tᵀ Lxx δx_t + δx_tᵀ Lxu δu_t + ½ δu_tᵀ Luu δu_t + Lxᵀ δx_t + Luᵀ δu_t + (terminal)
    s.t. δx_0 = 0,   δx_{t+1} = Fx δx_t + Fu δu_t + d_{t+1}

by the Riccati recursion with gaps (FDDP's backward pass, :meth:`SolverDDP.backwardPass`) and one
*linear* rollout ``δu_t = -k_t - K_t δx_t`` (``dx``, ``du``).  The multipliers of the dynamics are
``λ_t = p_t + P_t δx_t`` (``lag_mul``; ``p_t = Vx_t - Vxx_t d_t`` undoes the gap deflection).

Trial points lie on the straight line ``x_t ⊕ α δx_t``, ``u_t + α δu_t`` (no feedback).  A trial is
accepted by the filter (``use_filter_line_search``, default) when no entry ``(J, Γ)`` among the last
``filter_size`` pushed in this solve has both a cost and a gap norm at most the trial's, or by the merit
``J + mu_dynamic Γ`` decreasing; ``Γ = Σ_t ‖d_t‖₁`` (``gap_norm``).  The stopping measure, computed
before the step from the current derivatives, is ::

    KKT = max( max_t ‖Lx_t + Fx_tᵀ λ_{t+1} - λ_t‖∞, max_t ‖Lu_t + Fu_tᵀ λ_{t+1}‖∞, ‖Lx_T - λ_T‖∞, max_t ‖d_t‖∞ )

and ``solve`` returns True once ``KKT <= termination_tolerance``.  Regularisation: ``preg = dreg``
start at ``regInit`` (``reg_min`` when None), go down after a step longer than ``th_stepDec``, up after
one of at most ``th_stepInc`` (False at ``reg_max``).  The constraints of the nodes are ignored, as in
mim-solvers (:class:`~crocopy.solvers.csqp.SolverCSQP` enforces them).

``dx``, ``du``, ``lag_mul`` and ``fs_try`` are views of padded stacks ``(T+1, max ndx)``/``(T+1, max nu)``; with
kernels on, the linear rollout, the KKT measure and the gap norms run compiled on them
(:mod:`.sqp_kernel`), the backward pass is the DDP family's compiled Riccati pass, and over compiled nodes
(:mod:`.compiled_nodes`) each range of nodes evaluates its trial point (``x ⊕ α δx``, ``u + α δu``, the nodes, the
trial gaps) in one call.  Those nodes' tables and the addresses the kernels read are made with the solver
(:func:`.compiled_nodes.prepare`), as Crocoddyl's solvers allocate their workspace; each solve re-reads the models'
parameters.
"""

from __future__ import annotations

import time

import numpy as np

from .. import kernels
from ..guards import trusted_path
from ..shooting import ShootingProblem
from . import compiled_nodes, sqp_kernel
from .base import CountSetting, FlagSetting, Setting, check_solve_arguments
from .ddp import SolverDDP
from .std_vector import StdVecAttribute, allocate
from .stopwatch import profiled
from .trajectories import accept_trial


class SolverSQP(SolverDDP):
    """mim-solvers' ``SolverSQP(problem)``: Gauss-Newton multiple-shooting SQP.

    Settings (mim-solvers' names and defaults): ``termination_tolerance = 1e-6``,
    ``use_filter_line_search = True``, ``filter_size = 1``, ``mu_dynamic = 1.0``,
    ``extra_iteration_for_last_kkt = False``, and the regularisation settings of
    :class:`~crocopy.SolverDDP`.  Read-outs: ``KKT``, ``merit``, ``gap_norm``, ``dx``, ``du``,
    ``lag_mul`` (T+1 vectors), ``xs_try``, ``us_try``, ``fs_try``, ``cost_try``.
    """

    _nodes_compiled = True  # SQP reads only what compiled nodes write (values and derivatives, no constraints)
    dx = StdVecAttribute()
    du = StdVecAttribute()
    lag_mul = StdVecAttribute()
    fs_try = StdVecAttribute()

    #: Settings checked on assignment (ValueError or TypeError naming the setting, its range and the value given).
    termination_tolerance = Setting()
    use_filter_line_search = FlagSetting()
    filter_size = CountSetting(1)
    mu_dynamic = Setting(None, allow_inf=False)
    extra_iteration_for_last_kkt = FlagSetting()

    def __init__(self, problem: ShootingProblem) -> None:
        super().__init__(problem)
        self.termination_tolerance = 1e-6
        self.use_filter_line_search = True
        self.filter_size = 1
        self.mu_dynamic = 1.0
        self.extra_iteration_for_last_kkt = False
        self.KKT = np.inf
        self.gap_norm = 0.0
        self.gap_norm_try = 0.0
        self._allocate_sqp()

    def _allocate_sqp(self) -> None:
        """The steps ``dx``, ``du``, the multipliers ``lag_mul`` and ``fs_try``: views of padded stacks
        ``(T+1, max ndx)``, ``(T+1, max nu)`` (what the compiled glue of :mod:`.sqp_kernel` writes)."""
        models = [*self.problem.runningModels, self.problem.terminalModel]
        ndx, nu = [m.state.ndx for m in models], [m.nu for m in models[:-1]] + [0]
        n, m = max(ndx), max(nu)
        self._steps = np.zeros((len(ndx), n)), np.zeros((len(ndx), m)), np.zeros((len(ndx), n))
        self._fs_try = np.zeros((len(ndx), n))
        self._sqp_dims = np.array([ndx, nu, [0] * len(ndx)], dtype=np.int64).T.copy()
        self._no_rows = (np.zeros((len(ndx), 0, n)), np.zeros((len(ndx), 0, m)), np.zeros((len(ndx), 0)))
        self._scratch = np.zeros(max(n, m, 1))
        self._bind_sqp_views()

    def _bind_sqp_views(self) -> None:
        """Make ``dx``, ``du``, ``lag_mul``, ``fs_try`` the views of their stacks (after allocating or unpickling;
        assigning them later copies into these views, :class:`~.std_vector.Trajectory`)."""
        (dx, du, lam), dims = self._steps, self._sqp_dims
        allocate(self, "dx", [dx[t, :k] for t, k in enumerate(dims[:, 0])])
        allocate(self, "du", [du[t, :k] for t, k in enumerate(dims[:-1, 1])])
        allocate(self, "lag_mul", [lam[t, :k] for t, k in enumerate(dims[:, 0])])
        allocate(self, "fs_try", [self._fs_try[t, :k] for t, k in enumerate(dims[:, 0])])

    def __setstate__(self, state: dict) -> None:
        super().__setstate__(state)
        self._bind_sqp_views()

    def _on_problem_change(self) -> bool:
        changed = super()._on_problem_change()
        if changed:
            self._allocate_sqp()
        return changed

    # ------------------------------------------------------------------ solve
    def _solve(self, init_xs=None, init_us=None, maxiter: int = 100, isFeasible: bool = False,
               regInit: float | None = None) -> bool:
        """Solve from ``(init_xs, init_us)`` (``init_xs[0]`` is replaced by ``x0``); True once
        ``KKT <= termination_tolerance``, else False with ``reason``.  ``isFeasible`` is ignored (the gaps
        are always part of the QP), as in mim-solvers."""
        maxiter, _, regInit = check_solve_arguments(self, maxiter, isFeasible, regInit)
        with trusted_path(), np.errstate(over="ignore", invalid="ignore", divide="ignore"):
            self._start_sqp(init_xs, init_us, regInit)
            self._nodes = compiled_nodes.select(self)
            try:
                return self._iterate_sqp(maxiter)
            finally:
                nodes, self._nodes = self._nodes, None
                if nodes is not None:
                    nodes.fill(self.problem, self.xs, self.us)  # the datas as problem.calc there leaves them

    def _start_sqp(self, init_xs, init_us, regInit) -> None:
        self._check_x0()
        self._sync_problem()
        self.setCandidate(init_xs, init_us, False)
        self.xs[0] = self.problem.x0.copy()
        self.isFeasible = False
        reg = self.reg_min if regInit is None or np.isnan(regInit) else float(regInit)
        self.preg = self.dreg = reg
        self.reason = ""
        self.KKT = np.inf
        self._filter: list[tuple] = []
        self._synced = False
        self._t0 = time.perf_counter()

    def _iterate_sqp(self, maxiter: int) -> bool:
        for self.iter in range(maxiter):
            if not self._regularised_direction():
                return self._stop(f"regularization reached reg_max = {self.reg_max:g} in the backward pass")
            self.checkKKTConditions()
            self._run_callbacks()
            if self.KKT <= self.termination_tolerance:
                return self._converged()
            self._filter.append(self._measures())
            accepted = self._line_search()
            if not self._after_line_search(accepted):
                return self._stop(f"no step accepted and regularization reached reg_max = {self.reg_max:g}")
        self.iter = maxiter
        if self.extra_iteration_for_last_kkt and self._regularised_direction():
            self.checkKKTConditions()
            if self.KKT <= self.termination_tolerance:
                return self._converged()
        return self._stop(f"maximum number of iterations ({maxiter}) reached")

    def _converged(self) -> bool:
        self.reason = "converged"
        return True

    def _stop(self, reason: str) -> bool:
        self.reason = reason
        return False

    def computeDirection(self, recalc: bool = True) -> None:
        """The QP step at the current iterate: derivatives, gaps, ``gap_norm`` and ``merit`` (if ``recalc``),
        the backward pass, then ``dx``, ``du`` and ``lag_mul``.  Raises BackwardPassError."""
        if recalc:
            self.calcDiff()
            self.gap_norm = self._gap_norm()
            self.merit = self.cost + self.mu_dynamic * self.gap_norm
        self.backwardPass()
        self._linear_rollout()

    def _gap_norm(self) -> float:
        """``Γ = Σ_t ‖f_t‖₁``."""
        if kernels.active:
            return sqp_kernel.gap_l1(self._horizon.dims, self._horizon.addr)
        return float(sum(np.abs(f).sum() for f in self.fs))

    def _linear_rollout(self) -> None:
        """``δu_t = -k_t - K_t δx_t``, ``δx_{t+1} = Fx δx_t + Fu δu_t + d_{t+1}`` and ``λ_t = p_t + P_t δx_t``."""
        problem = self.problem
        if kernels.active:
            sqp_kernel.linear_rollout(self._sqp_dims, self._derivative_addresses(), self._horizon.addr,
                                      *self._steps)
            return
        dx, du, fs = self.dx, self.du, self.fs
        dx[0][:] = fs[0]
        for t, d in enumerate(problem.runningDatas):
            np.negative(self.k[t], out=du[t])
            du[t] -= self.K[t] @ dx[t]
            np.dot(d.Fx, dx[t], out=dx[t + 1])
            dx[t + 1] += d.Fu @ du[t]
            dx[t + 1] += fs[t + 1]
        for t, lam in enumerate(self.lag_mul):
            np.dot(self.Vxx[t], dx[t] - fs[t], out=lam)
            lam += self.Vx[t]

    def checkKKTConditions(self) -> float:
        """``KKT``: the ∞-norm of the Lagrangian's gradient at the current iterate (with ``lag_mul``) and
        of the gaps (mim-solvers' definition, see the module docstring)."""
        problem = self.problem
        if kernels.active:
            dims, C, D, y = self._kkt_rows()
            worst = sqp_kernel.kkt(dims, self._derivative_addresses(), self._horizon.addr,
                                   sqp_kernel.readable(problem.terminalData.Lx), self._steps[2], C, D, y, self._scratch)
            self.KKT = max(worst, self._kkt_constraint_term())
            self.stop = self.KKT
            return self.KKT
        lam = self.lag_mul
        worst = 0.0
        for t, d in enumerate(problem.runningDatas):
            gx = d.Lx + d.Fx.T @ lam[t + 1] - lam[t] + self._constraint_force_x(t)
            worst = max(worst, float(np.abs(gx).max(initial=0.0)))
            if d.Lu.size:
                gu = d.Lu + d.Fu.T @ lam[t + 1] + self._constraint_force_u(t)
                worst = max(worst, float(np.abs(gu).max()))
        gT = problem.terminalData.Lx - lam[-1] + self._constraint_force_x(problem.T)
        worst = max(worst, float(np.abs(gT).max(initial=0.0)), max(float(np.abs(f).max(initial=0.0)) for f in self.fs))
        self.KKT = max(worst, self._kkt_constraint_term())
        self.stop = self.KKT
        return self.KKT

    def _kkt_rows(self) -> tuple:
        """``(dims, C, D, y)`` of the rows whose multipliers enter the KKT measure (none in SQP)."""
        return (self._sqp_dims, *self._no_rows)

    def _constraint_force_x(self, t: int) -> np.ndarray | float:
        return 0.0

    def _constraint_force_u(self, t: int) -> np.ndarray | float:
        return 0.0

    def _kkt_constraint_term(self) -> float:
        return 0.0

    # ------------------------------------------------------------------ line search
    def _measures(self) -> tuple:
        """The filter's entry of the current iterate: ``(cost, gap_norm)``."""
        return (self.cost, self.gap_norm)

    def _trial_measures(self) -> tuple:
        return (self.cost_try, self.gap_norm_try)

    def _trial_merit(self) -> float:
        return self.cost_try + self.mu_dynamic * self.gap_norm_try

    def _line_search(self) -> bool:
        """Try ``alphas`` in order; swap in the first accepted trial.  ``stepLength`` is the α used."""
        recent = self._filter[-min(self.filter_size, len(self._filter)):]
        for alpha in self.alphas:
            self.stepLength = alpha
            merit_try = self.tryStep(alpha)
            if not np.isfinite(self.cost_try):
                continue
            if self.use_filter_line_search:
                trial = self._trial_measures()
                ok = not any(all(e <= v for e, v in zip(entry, trial)) for entry in recent)
            else:
                ok = merit_try < self.merit
            if ok and self._trial_finite():
                accept_trial(self)  # xs ← xs_try, us ← us_try (copies: the solver's arrays never move)
                self.cost = self.cost_try
                self._synced = True
                return True
        self._synced = False
        return False

    def _after_line_search(self, accepted: bool) -> bool:
        """The regularisation schedule; False when it reaches ``reg_max`` after a too short step."""
        if self.stepLength > self.th_stepDec:
            self.decreaseRegularization()
        if self.stepLength <= self.th_stepInc:
            self.increaseRegularization()
            if self.preg >= self.reg_max:
                return False
        return True

    def tryStep(self, steplength: float = 1.0) -> float:
        """Evaluate the trial ``x ⊕ α δx``, ``u + α δu`` (``xs_try``, ``us_try``, ``cost_try``, ``fs_try``,
        ``gap_norm_try``) and return its merit."""
        nodes = self._nodes
        if nodes is None:
            self._python_trial(steplength)
        else:
            self.cost_try = nodes.trial(self.problem, self.xs, self.us, self.dx, self.du, steplength,
                                        (self.xs_try, self.us_try, self.fs_try), self._addresses(),
                                        (*self._steps[:2], self._fs_try, self._scratch))
        fs_try = self.fs_try
        if kernels.active:
            self.gap_norm_try = sqp_kernel.stack_l1(self._sqp_dims, self._fs_try)
        else:
            self.gap_norm_try = float(sum(np.abs(f).sum() for f in fs_try))
        self._after_trial()
        return self._trial_merit()

    def _python_trial(self, steplength: float) -> None:
        """The trial point node by node (without compiled nodes): ``xs_try``, ``us_try``, ``cost_try``, ``fs_try``."""
        problem = self.problem
        models = [*problem.runningModels, problem.terminalModel]
        for t, m in enumerate(models):
            m.state._integrate_into(self.xs[t], steplength * self.dx[t], self.xs_try[t])
        for t, u in enumerate(self.us):
            np.add(u, steplength * self.du[t], out=self.us_try[t])
        self.cost_try = problem.calc(self.xs_try, self.us_try)
        fs_try = self.fs_try
        fs_try[0][:] = models[0].state.diff(self.xs_try[0], problem.x0) if problem.T else 0.0
        for t, (m, d) in enumerate(zip(problem.runningModels, problem.runningDatas)):
            m.state._diff_into(self.xs_try[t + 1], d.xnext, fs_try[t + 1])

    def _after_trial(self) -> None:
        """Hook: what a subclass measures at a trial point besides the cost and the gaps."""

    def stoppingCriteria(self) -> float:
        """``stop = KKT`` (the value the solve compares with ``termination_tolerance``)."""
        self.stop = self.KKT
        return self.stop


#: mim-solvers' ``solve(init_xs, init_us, maxiter=100, isFeasible=False, regInit=None)`` (its argument
#: names, not Crocoddyl's ``is_feasible``/``init_reg``), checked by ``_solve`` itself.
SolverSQP.solve = profiled("SolverSQP::solve", SolverSQP._solve)
