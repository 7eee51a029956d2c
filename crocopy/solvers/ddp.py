"""Differential dynamic programming (Crocoddyl's ``SolverDDP``).

Sign convention (Crocoddyl's): the control update is ``û = u - α k - K (x̂ ⊖ x)`` with
``k = Quu⁻¹ Qu`` and ``K = Quu⁻¹ Qux``.  Backward pass (Gauss-Newton, t = T-1..0)::

    Qx  = Lx  + Fxᵀ V'x        Qu  = Lu  + Fuᵀ V'x
    Qxx = Lxx + Fxᵀ V'xx Fx    Qxu = Lxu + Fxᵀ V'xx Fu    Quu = Luu + Fuᵀ V'xx Fu + preg I
    Vx  = Qx - Kᵀ Qu           Vxx = Qxx - Qxu K (+ preg I, symmetrised)

With open gaps ``fs`` the stored gradient is deflected, ``Vx ← Vx + Vxx fs``.  Expected
improvement ``dVexp(α) = α (d₀ + ½ α d₁)`` with ``d₀ = Σ Quᵀk``, ``d₁ = -Σ kᵀ Quu k``; the
stopping test is ``stop = |d₀ + ½ d₁| < th_stop`` on a feasible iterate.

Subclass hooks: ``computeActionValueFunction``, ``computeGains`` and ``computeValueFunction`` are
the three steps of one node of the backward pass; while :func:`crocopy.kernels_enabled` the whole
recursion is one compiled call, :func:`~crocopy.solvers.riccati_kernel.riccati_pass`, on the solver's
stacked arrays and the nodes' derivatives (:mod:`.horizon`).  A
subclass that overrides any of them gets the numpy steps for the whole recursion (its override
runs), logged once at DEBUG level on the ``"crocopy"`` logger.  ``forwardPass`` runs
:meth:`SolverDDP._trial_rollout`, the rollout of the whole DDP family, parameterised by the gaps
it keeps open and by the control bounds.

NaN/inf (:mod:`.nonfinite`): one test per phase on aggregated quantities (the cost, ``d``,
``Vx₀``/``Vxx₀``, the trial's cost and last state, the whole trajectory of a trial about to be
accepted), a per-node search only when it fails.  A non-finite
direction stops the solve (more regularisation cannot cure an overflow) with ``solve() -> False``
and ``reason`` naming the node and quantity (also printed by :class:`~crocopy.CallbackVerbose`); a
non-finite trial rollout is rejected like any other trial.  Every False return leaves the best
finite iterate visited (lowest cost among the feasible ones, else the newest), with ``cost`` its
cost.  A guess whose cost is not finite raises ValueError.  ``solve`` re-allocates the solver's
buffers when ``problem.updateModel``/``circularAppend`` changed a node's ``nx``, ``ndx`` or ``nu``.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.linalg.lapack import dpotrf, dpotrs

from .. import kernels
from ..enums import FeasibilityNorm
from ..kernels import log_fallback, overridden
from ..shooting import ShootingProblem
from . import compiled_nodes, horizon, line_search, riccati_kernel, rollout, sqp_kernel
from .base import BackwardPassError, ForwardPassError, SolverAbstract
from .horizon import Horizon, NodeDerivatives
from .nonfinite import (
    NonFiniteError,
    locate_cost,
    locate_in_backward_pass,
    locate_in_derivatives,
    locate_in_rollout,
    trajectory_finite,
)
from .std_vector import allocate
from .trajectories import TrajectoryAddresses, accept_trial


class SolverDDP(SolverAbstract):
    """Crocoddyl's ``SolverDDP(problem)``: regularised DDP with a backtracking line search."""

    _nodes_compiled = True
    _line_search = (False, False)
    """``(negative, bounded)`` of the compiled line search (:mod:`.line_search`)."""
    _nodes: compiled_nodes.CompiledNodes | None = None

    def __init__(self, problem: ShootingProblem) -> None:
        super().__init__(problem)
        self.reg_incFactor = 10.0
        self.reg_decFactor = 10.0
        self.reg_min = 1e-9
        self.reg_max = 1e9
        self.th_stepDec = 0.5
        self.th_stepInc = 0.01
        self.th_grad = 1e-12
        self.alphas = [2.0 ** (-n) for n in range(10)]
        self.cost_try = 0.0
        self._models = (*problem.runningModels, problem.terminalModel)
        self._nodes_seen = problem._nodes_version
        self._layout = self._shapes()
        self._best: tuple | None = None
        self._allocate()
        self._prepare_kernels()

    def _shapes(self) -> tuple:
        return tuple((m.state.nx, m.state.ndx, m.nu) for m in self._models)

    def _sync_problem(self) -> None:
        """Follow ``updateModel``/``circularAppend`` (the problem's node version moved): re-allocate when a node's
        dimensions changed."""
        problem = self.problem
        if self._nodes_seen == problem._nodes_version:
            return
        self._nodes_seen = problem._nodes_version
        self._models = (*problem.runningModels, problem.terminalModel)
        self._derivatives = NodeDerivatives()
        self._on_problem_change()

    def _on_problem_change(self) -> bool:
        """The nodes' models were replaced: re-allocate if their dimensions changed (then True).

        Subclasses extend it for what they derive from the models."""
        layout = self._shapes()
        if layout == self._layout:
            return False
        self._layout = layout
        models = self._models
        allocate(self, "xs", [m.state.zero() for m in models])
        allocate(self, "us", [np.zeros(m.nu) for m in models[:-1]])
        self._allocate()
        return True

    def _allocate(self) -> None:
        """The per-node arrays: views of one :class:`~crocopy.solvers.horizon.Horizon` buffer (zeros)."""
        problem = self.problem
        models = [*problem.runningModels, problem.terminalModel]
        self._horizon = Horizon([m.state.ndx for m in models], [m.nu for m in problem.runningModels])
        self._node_dims = [(m.state.ndx, m.nu) for m in problem.runningModels]
        self._derivatives = NodeDerivatives()
        self._bind_views()
        self._dx_try = [np.zeros(m.state.ndx) if m.nu else None for m in problem.runningModels] + [None]
        """``x̂_t ⊖ x_t`` of the last rollout at the nodes with controls (None elsewhere: not computed)."""
        allocate(self, "xs_try", [m.state.zero() for m in models])
        allocate(self, "us_try", [np.zeros(m.nu) for m in problem.runningModels])
        self._rhs = [np.zeros((m.nu, 1 + m.state.ndx)) for m in problem.runningModels]
        self._unbounded = {m.nu: (np.full(m.nu, -np.inf), np.full(m.nu, np.inf)) for m in problem.runningModels}
        self._bound_addresses = None
        self._trajectory_addresses = None
        self._synced = False
        self._diverged_steps: set[float] = set()
        """Step lengths whose last trial had a compiled step diverge (:func:`.rollout.segment_rollout`)."""
        self._last_trial_diverged = False

    def _prepare_kernels(self) -> None:
        """With kernels on, what the first solve would otherwise make, as Crocoddyl's solvers allocate their
        workspace when they are made: the compiled nodes' tables (:func:`.compiled_nodes.prepare`) and the addresses
        of the trajectories and of the nodes' derivatives (a solve re-reads the models' parameters)."""
        if not kernels.active:
            return
        compiled_nodes.prepare(self)
        self._addresses()
        try:
            self._derivative_addresses()
        except ValueError:  # a derivative array of the wrong size: the solve reports it
            self._derivatives = NodeDerivatives()

    def _derivative_addresses(self) -> np.ndarray:
        """Where the running nodes' ``Fx, Fu, Lxx, Lxu, Luu, Lx, Lu`` are (:class:`.horizon.NodeDerivatives`)."""
        self._sync_problem()  # updateModel/circularAppend since the last solve
        return self._derivatives.update(self.problem.runningDatas, self._node_dims)

    _views = ("Vxx", "Vx", "fs", "Qxx", "Qxu", "Quu", "Qx", "Qu", "K", "k")
    """Attributes holding views of the horizon's buffer: not pickled, bound again to the copy's buffer."""

    def _bind_views(self) -> None:
        """Point the per-node lists at the views of :attr:`_horizon` (after allocating or unpickling)."""
        h = self._horizon
        self.Vxx, self.Vx = h.views(horizon.VXX), h.views(horizon.VX)
        allocate(self, "fs", h.views(horizon.FS))
        self.Qxx, self.Qxu, self.Quu, self.Qx, self.Qu, self.K, self.k = (
            h.views(j, running=True)
            for j in (horizon.QXX, horizon.QXU, horizon.QUU, horizon.QX, horizon.QU, horizon.KM, horizon.KV)
        )

    def __getstate__(self) -> dict:
        state = self.__dict__.copy()
        for name in (*self._views, "_nodes", "_trajectory_addresses", "_bound_addresses"):
            state.pop(name, None)
        return state

    def __setstate__(self, state: dict) -> None:
        self.__dict__.update(state)
        self._bound_addresses = None
        self._bind_views()

    # ------------------------------------------------------------------ regularisation
    def increaseRegularization(self) -> None:
        """Multiply ``preg``/``dreg`` by ``reg_incFactor`` (capped at ``reg_max``)."""
        self.preg = min(self.preg * self.reg_incFactor, self.reg_max)
        self.dreg = min(self.dreg * self.reg_incFactor, self.reg_max)

    def decreaseRegularization(self) -> None:
        """Divide ``preg``/``dreg`` by ``reg_decFactor`` (floored at ``reg_min``)."""
        self.preg = max(self.preg / self.reg_decFactor, self.reg_min)
        self.dreg = max(self.dreg / self.reg_decFactor, self.reg_min)

    # ------------------------------------------------------------------ main loop
    def _start(self, init_xs, init_us, is_feasible: bool, init_reg) -> None:
        self._check_x0()
        self._sync_problem()
        self._best = None
        self.setCandidate(init_xs, init_us, is_feasible)
        reg = self.reg_min if init_reg is None or np.isnan(init_reg) else float(init_reg)
        if not np.isfinite(reg) or reg < 0:
            raise ValueError(f"init_reg must be a non-negative number, got {init_reg}")
        self.preg = self.dreg = reg
        self.reason = ""
        self.stop = 0.0
        self.d[:] = 0.0
        self.dV = self.dVexp = 0.0
        self._synced = False

    def _fail(self, reason: str, nonfinite: bool = False) -> bool:
        """Stop with False: state ``reason``, go back to the best iterate, announce a NaN/inf stop."""
        self.reason = reason
        self._restore_best()
        if nonfinite:
            for callback in self._callbacks:
                stopped = getattr(callback, "stopped", None)
                if stopped is not None:
                    stopped(self)
        return False

    def solve(self, init_xs=None, init_us=None, maxiter: int = 100, is_feasible: bool = False, init_reg=None) -> bool:
        """Solve from the guess ``(init_xs, init_us)``; returns True on convergence (see ``reason`` otherwise).

        Raises
        ------
        ValueError
            If the cost of the guess is not finite (the message names the node).
        """
        self._start(init_xs, init_us, is_feasible, init_reg)
        self._nodes = compiled_nodes.select(self)
        try:
            with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
                try:
                    solved = self._iterate(maxiter)
                except NonFiniteError as exc:
                    if exc.where == "problem evaluation" and self.iter == 0:
                        raise ValueError(f"solve: the cost of the initial guess is not finite ({exc})") from exc
                    solved = self._fail(f"{exc} (kept the best finite iterate)", nonfinite=True)
        finally:
            nodes, self._nodes = self._nodes, None
        if nodes is not None:
            nodes.fill(self.problem, self.xs, self.us)
        return solved

    def _iterate(self, maxiter: int) -> bool:
        """The iterations of :meth:`solve`; raises NonFiniteError where NaN/inf arise."""
        was_feasible = False
        for self.iter in range(maxiter):
            if not self._regularised_direction():
                return self._fail(f"regularization reached reg_max = {self.reg_max:g} in the backward pass")
            self.expectedImprovement()
            self._check_direction()
            rollout_error = None
            i, n = 0, len(self.alphas)
            while i < n:
                i, accepted = line_search.compiled_trials(self, i)
                if accepted:
                    feasible = self.isFeasible
                    taken, rollout_error = self._take_trial(self.stepLength)
                    if taken:
                        was_feasible = feasible
                        break
                    continue
                if i == n:
                    break
                alpha = self.alphas[i]
                i += 1
                self.stepLength = alpha
                try:
                    self.dV = self.tryStep(alpha)
                except ForwardPassError:
                    self._synced = False
                    rollout_error = locate_in_rollout(self.problem, self.xs_try, self.us_try)
                    continue
                self.dVexp = alpha * (self.d[0] + 0.5 * alpha * self.d[1])
                if self._accept(alpha):
                    feasible = self.isFeasible
                    taken, rollout_error = self._take_trial(alpha)
                    if taken:
                        was_feasible = feasible
                        break
                    continue
                self._synced = False
            outcome = self._close_iteration(was_feasible, rollout_error)
            if outcome is not None:
                return outcome
        self.iter = maxiter
        return self._fail(f"maximum number of iterations ({maxiter}) reached")

    def _take_trial(self, alpha: float) -> tuple[bool, str | None]:
        """Take the trial of step ``alpha``, accepted by the line search: ``(True, None)``; ``(False, why)`` where a
        trial state or control is not finite (the iterate is kept)."""
        if not self._trial_finite():
            self._synced = False
            return False, locate_in_rollout(self.problem, self.xs_try, self.us_try)
        self._accept_trial(alpha)
        return True, None

    def _trial_finite(self) -> bool:
        """Whether ``xs_try`` and ``us_try`` are finite (one compiled pass over their addresses while
        :func:`crocopy.kernels_enabled`)."""
        if kernels.active:
            a = self._addresses()
            return sqp_kernel.all_finite(a.xs_try, a.nx) and sqp_kernel.all_finite(a.us_try, a.nu)
        return trajectory_finite(self.xs_try, self.us_try)

    def _close_iteration(self, was_feasible: bool, rollout_error: str | None = None) -> bool | None:
        """After the line search: regularisation update, stopping value, callbacks; True once converged,
        False on failure (``rollout_error``: why the last trial failed, if it did), None to go on."""
        if self.stepLength > self.th_stepDec:
            self.decreaseRegularization()
        if self.stepLength <= self.th_stepInc:
            self.increaseRegularization()
            if self.preg >= self.reg_max:
                self.stoppingCriteria()
                self._run_callbacks()
                last = f" (last trial: {rollout_error})" if rollout_error is not None else ""
                return self._fail(f"no step accepted and regularization reached reg_max = {self.reg_max:g}{last}")
        self.stoppingCriteria()
        self._run_callbacks()
        if was_feasible and self.stop < self.th_stop:
            self.reason = "converged"
            return True
        return None

    def _regularised_direction(self) -> bool:
        """``computeDirection``, raising the regularisation while ``Quu`` is not positive definite;
        False once ``preg`` reaches ``reg_max``."""
        recalc = True
        while True:
            try:
                self.computeDirection(recalc)
            except BackwardPassError:
                recalc = False
                self.increaseRegularization()
                if self.preg >= self.reg_max:
                    return False
                continue
            return True

    def _check_direction(self) -> None:
        """One finiteness test of the direction (``d``, ``Vx₀``, ``Vxx₀``); on failure, find where it arose."""
        if math.isfinite(self.d.sum() + self.Vx[0].sum() + self.Vxx[0].sum()) or (
                np.isfinite(self.d).all() and np.isfinite(self.Vx[0]).all() and np.isfinite(self.Vxx[0]).all()):
            return
        raise (locate_in_derivatives(self.problem) or locate_in_backward_pass(self)
               or NonFiniteError("expected improvement", None, "backward pass"))

    def _node_failure(self, t: int) -> Exception:
        """Why the gains of node ``t`` failed: NaN/inf (located) or a ``Quu`` not positive definite."""
        if np.isfinite(self.Quu[t]).all():
            return BackwardPassError(f"Quu is not positive definite at node {t}")
        return locate_in_derivatives(self.problem) or locate_in_backward_pass(self) or NonFiniteError("Quu", t,
                                                                                                      "backward pass")

    def _score(self) -> float:
        """What the best-iterate bookkeeping minimises over feasible iterates (the cost)."""
        return self.cost

    def _score_try(self) -> float:
        return self.cost_try

    def _track_best(self) -> None:
        """Before a trial replaces a feasible iterate: keep a copy of the iterate if the trial is worse."""
        if not self.isFeasible:
            return
        trial = self._score_try()
        if self._best is None:
            if trial > self._score():
                self._best = ([x.copy() for x in self.xs], [u.copy() for u in self.us], self._score())
        elif trial <= self._best[2]:
            self._best = None

    def _restore_best(self) -> None:
        """Make the best iterate kept by :meth:`_track_best` current again (cost and datas re-evaluated)."""
        if self._best is None:
            return
        self.xs, self.us = self._best[0], self._best[1]
        self._best = None
        self.isFeasible = True
        self.cost = self.problem.calc(self.xs, self.us)
        for f in self.fs:
            f[:] = 0.0
        self.ffeas = 0.0
        self._synced = False

    def _addresses(self) -> TrajectoryAddresses:
        """Where the solver's trajectories are (read once per allocation)."""
        a = self._trajectory_addresses
        if a is None:
            a = self._trajectory_addresses = TrajectoryAddresses(self)
        return a

    def _accept(self, alpha: float) -> bool:
        if self.dVexp >= 0:
            return abs(self.d[0]) < self.th_grad or not self.isFeasible or self.dV > self.th_acceptStep * self.dVexp
        return False

    def _accept_trial(self, alpha: float) -> None:
        self._track_best()
        accept_trial(self)
        self.isFeasible = True
        self.cost = self.cost_try
        self._synced = True

    # ------------------------------------------------------------------ direction
    def computeDirection(self, recalc: bool = True) -> None:
        """Compute the derivatives (if ``recalc``) and run the backward pass."""
        if recalc:
            self.calcDiff()
        self.backwardPass()

    def calcDiff(self) -> float:
        """Evaluate (if needed) and differentiate every node at the current iterate; update the gaps and the
        constraints' norms ``gfeas``, ``hfeas``."""
        self._differentiate()
        self.computeInequalityFeasibility()
        self.computeEqualityFeasibility()
        return self.cost

    def _differentiate(self) -> None:
        """:meth:`calcDiff` but the constraints' norms."""
        problem = self.problem
        nodes = self._nodes
        feasible = self.isFeasible
        reported = feasible and self._reports_feasible_gaps()
        gaps_compiled = nodes is not None and nodes.horizon is not None and (not feasible or reported)
        if nodes is not None:
            self.cost = nodes.calcDiff(problem, self.xs, self.us, self._synced, self.fs if gaps_compiled else None,
                                       self._addresses())
        else:
            if not self._synced:
                problem.calc(self.xs, self.us)
            self.cost = problem.calcDiff(self.xs, self.us)
        self._synced = True
        if not math.isfinite(self.cost):
            raise locate_cost(problem)
        if gaps_compiled:
            self._close_gaps()
        elif not feasible or reported:
            self.computeDynamicFeasibility()
        if feasible:
            self._zero_gaps()
            if not reported:
                self.ffeas = 0.0

    def _zero_gaps(self) -> None:
        """``fs[t] = 0`` for every node (one compiled call on the horizon's buffer while
        :func:`crocopy.kernels_enabled`)."""
        if kernels.active:
            sqp_kernel.zero_gaps(self._horizon.dims, self._horizon.addr)
            return
        for f in self.fs:
            f[:] = 0.0

    def _gaps_norm(self) -> float:
        """The norm of all the gaps (``feasNorm``): the ∞-norm in one compiled call on the horizon's buffer
        (:func:`.sqp_kernel.gap_linf`) while :func:`crocopy.kernels_enabled`."""
        if kernels.active and self.feasNorm == FeasibilityNorm.LInf:
            return sqp_kernel.gap_linf(self._horizon.dims, self._horizon.addr)
        return self._norm(self.fs)

    def _reports_feasible_gaps(self) -> bool:
        """Whether ``ffeas`` reports the gaps of a feasible iterate (whose ``fs`` the backward pass sees as zero)."""
        return False

    def _kernel_applies(self, owner: type, kernel: str) -> bool:
        """True when no subclass replaces a node step as ``owner`` defines it (else log it once)."""
        steps = overridden(self, owner, ("computeActionValueFunction", "computeGains", "computeValueFunction"))
        if steps:
            log_fallback(type(self), steps, kernel)
        return not steps

    def backwardPass(self) -> None:
        """Riccati recursion over the stored derivatives (fills Q terms, gains and value function).

        Uses the compiled pass of :mod:`.riccati_kernel` when :func:`crocopy.kernels_enabled` and no
        subclass overrides a node step; otherwise the numpy steps below (same numbers to round-off).
        """
        if kernels.active and self._kernel_applies(SolverDDP, "the compiled Riccati pass"):
            self._backward_pass_kernel()
        else:
            self._backward_pass_numpy()

    def _backward_pass_numpy(self) -> None:
        """The recursion through the node steps (``computeActionValueFunction``, ``computeGains``,
        ``computeValueFunction``)."""
        problem = self.problem
        self._terminal_value_function()
        for t in range(problem.T - 1, -1, -1):
            model, data = problem.runningModels[t], problem.runningDatas[t]
            self.computeActionValueFunction(t, model, data)
            if model.nu:
                self.computeGains(t)
            self.computeValueFunction(t, model)

    def _terminal_value_function(self) -> bool:
        """``V_T`` from the terminal cost (+ ``preg`` I, gap-deflected); returns True when gaps are open."""
        T = self.problem.T
        td = self.problem.terminalData
        gaps = not self.isFeasible
        value = riccati_kernel.terminal_value if kernels.active else riccati_kernel.terminal_value_numpy
        readable = sqp_kernel.readable
        value(readable(td.Lxx), readable(td.Lx), float(self.preg), self.fs[T], gaps, self.Vxx[T], self.Vx[T])
        return gaps

    def _backward_pass_kernel(self) -> None:
        """The whole recursion in one compiled call (:meth:`_compiled_pass`) over the stacked arrays of
        :mod:`.horizon`; the first node whose ``Quu`` is not positive definite or not finite raises."""
        self._sync_problem()  # updateModel/circularAppend since the last solve (before V_T: it may remake buffers)
        gaps = self._terminal_value_function()
        t = self._compiled_pass(self._derivative_addresses(), float(self.preg), gaps)
        if t >= 0:
            raise self._node_failure(t)

    def _compiled_pass(self, daddr: np.ndarray, preg: float, gaps: bool) -> int:
        """:func:`.riccati_kernel.riccati_pass` (``daddr``: the derivatives' addresses); -1, or the first node
        (from the end) whose gains failed."""
        h = self._horizon
        return riccati_kernel.riccati_pass(daddr, h.addr, h.dims, preg, gaps)

    def computeActionValueFunction(self, t: int, model, data) -> None:
        """Q terms of node ``t`` from its derivatives and the next value function."""
        Vxx_p, Vx_p = self.Vxx[t + 1], self.Vx[t + 1]
        FxTV = data.Fx.T @ Vxx_p
        np.dot(FxTV, data.Fx, out=self.Qxx[t])
        self.Qxx[t] += data.Lxx
        np.dot(data.Fx.T, Vx_p, out=self.Qx[t])
        self.Qx[t] += data.Lx
        if model.nu:
            FuTV = data.Fu.T @ Vxx_p
            Quu = self.Quu[t]
            np.dot(FuTV, data.Fu, out=Quu)
            Quu += data.Luu
            np.dot(FxTV, data.Fu, out=self.Qxu[t])
            self.Qxu[t] += data.Lxu
            np.dot(data.Fu.T, Vx_p, out=self.Qu[t])
            self.Qu[t] += data.Lu
            if self.preg:
                Quu.flat[:: Quu.shape[0] + 1] += self.preg

    def computeGains(self, t: int) -> None:
        """``k = Quu⁻¹ Qu`` and ``K = Quu⁻¹ Qux`` by Cholesky; raises BackwardPassError if ``Quu`` is not PD."""
        chol, info = dpotrf(self.Quu[t], lower=0, clean=0)
        if info != 0:
            raise self._node_failure(t)
        rhs = self._rhs[t]
        rhs[:, 0] = self.Qu[t]
        rhs[:, 1:] = self.Qxu[t].T
        sol, info = dpotrs(chol, rhs, lower=0)
        self.k[t][:] = sol[:, 0]
        self.K[t][:] = sol[:, 1:]

    def computeValueFunction(self, t: int, model) -> None:
        """Value function of node ``t`` from its Q terms and gains (gap-deflected when infeasible)."""
        Vx, Vxx = self.Vx[t], self.Vxx[t]
        Vx[:] = self.Qx[t]
        Vxx[:] = self.Qxx[t]
        if model.nu:
            Vx -= self.K[t].T @ self.Qu[t]
            Vxx -= self.Qxu[t] @ self.K[t]
        self._finish_value_function(t)

    def _finish_value_function(self, t: int) -> None:
        """Symmetrise ``Vxx[t]``, add ``preg`` to it and deflect ``Vx[t]`` by the gap when infeasible."""
        Vx, Vxx = self.Vx[t], self.Vxx[t]
        Vxx += Vxx.T
        Vxx *= 0.5
        if self.preg:
            Vxx.flat[:: Vxx.shape[0] + 1] += self.preg
        if not self.isFeasible:
            Vx += Vxx @ self.fs[t]

    # ------------------------------------------------------------------ step
    def expectedImprovement(self) -> np.ndarray:
        """``d = (Σ Quᵀk, -Σ kᵀ Quu k)`` over the running nodes."""
        d0 = d1 = 0.0
        for Qu, Quu, k in zip(self.Qu, self.Quu, self.k):
            if k.size:
                d0 += Qu @ k
                d1 -= k @ Quu @ k
        self.d[0], self.d[1] = d0, d1
        return self.d

    def tryStep(self, steplength: float = 1.0) -> float:
        """Roll out with step ``steplength``; returns the actual cost reduction ``cost - cost_try``."""
        self.forwardPass(steplength)
        return self.cost - self.cost_try

    def forwardPass(self, steplength: float) -> None:
        """Nonlinear rollout from ``x0`` with ``û = u - α k - K (x̂ ⊖ x)``; raises ForwardPassError on NaN."""
        self._trial_rollout(steplength)

    def _trial_rollout(self, steplength: float, gaps: bool = False, bounds: tuple[list, list] | None = None,
                       last_gap: bool = False) -> None:
        """The DDP family's rollout into ``xs_try``/``us_try``/``cost_try``
        (:func:`~crocopy.solvers.rollout.trial_rollout`); raises ForwardPassError on NaN."""
        rollout.trial_rollout(self, steplength, gaps, bounds, last_gap)

    def stoppingCriteria(self) -> float:
        """``stop = |d₀ + ½ d₁|``: the expected reduction of a full step."""
        self.stop = abs(self.d[0] + 0.5 * self.d[1])
        return self.stop

