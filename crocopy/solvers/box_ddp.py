"""Control-limited DDP (Tassa, Mansard, Todorov, ICRA 2014; Crocoddyl's ``SolverBoxDDP``).

On a feasible iterate, every running node with control bounds ``u_lb <= u <= u_ub`` (shape
``(nu,)``) replaces the unconstrained minimisation of the Q-function by the box QP (Crocoddyl's
sign, ``δu = -k - K δx``)::

    k = -argmin_δu ½ δuᵀ Quu δu + Quᵀ δu   s.t.  u_lb - u <= δu <= u_ub - u,

solved by :class:`crocopy.solvers.box_qp.BoxQP` warm-started from the previous iteration's solution
``δu = -k`` (Box-FDDP paper eq. 15, projected into the box by the QP).  The
feedback acts on the free subspace only: ``K = Quu_inv Qux`` with ``Quu_inv`` the inverse of the
free block ``Quu_ff`` zero-padded to ``(nu, nu)`` (rows of clamped controls are zero).  The
forward pass clamps the applied controls, ``û = clamp(u - α k - K (x̂ ⊖ x), u_lb, u_ub)``, so the
returned ``us`` never leave the box (Tassa's reference code does the same; the paper leaves it
implicit).  Nodes without finite bounds use the plain Cholesky gains.

Two value-function variants (attribute ``general_value_update``):

* ``False`` (default, reproduces Crocoddyl 3.2 iterate for iterate): the DDP update
  ``Vx = Qx - Kᵀ Qu``, ``Vxx = Qxx - Qxu K``, and the ``Qu`` entries of clamped controls are zeroed
  after the QP, so the expected improvement ``d₀ = Σ Quᵀ k`` and the stopping test only see the
  free controls;
* ``True`` (Tassa's reference code, DIGEST §1.5): the exact update for a box-QP ``k``,
  ``Vx = Qx - Kᵀ Qu - Qxu k + Kᵀ Quu k``, and the full ``Qu`` in the expected improvement.

Both have the same fixed points.  A warm start declared feasible is used as given: its controls
must already respect the box (a rollout of clamped controls).  An infeasible iterate (a warm
start that is not a rollout) gets unconstrained gains, as in Box-FDDP and Crocoddyl; Tassa's
Box-DDP always starts from a rollout.

Settings the paper leaves open are Crocoddyl 3.2's (documented defaults, or measured as a black
box): ``th_stop = 5e-5``, regularisation ``reg_min = 1e-9`` (also the initial value), factors 10,
step lengths ``2^-n``, ``n = 0..9``; the box QP runs with ``maxiter = 100``,
``th_acceptStep = 0.1``, ``th_grad = 1e-5`` (infinity norm) and no extra regularisation (``preg`` is
already on ``Quu``).

``compat_crocoddyl = True`` (crocopy extension) reproduces three departures of Crocoddyl 3.2 from
the papers, found by comparing its iterates as a black box; with them crocopy follows Crocoddyl's
iterates to round-off (``crocopy bench --box-parity``):

1. the QP warm start is Crocoddyl's stored ``k`` itself, i.e. ``-δu`` of the previous iteration (a
   sign error against eq. 15: the mirrored guess is often clamped on the opposite bound);
2. the QP's line search accepts a cost increase of up to ``th_acceptStep`` times the predicted
   decrease (flipped Armijo sign, :mod:`crocopy.solvers.box_qp`);
3. Box-DDP from an infeasible iterate rolls out from ``x0`` but keeps the *last* gap open by
   ``(1 - α)`` and then declares the iterate feasible (and ``ffeas`` reports the gaps of iterates
   declared feasible).

Crocopy extensions: ``compat_crocoddyl``; ``nfactorizations`` and ``nqp`` count box-QP Cholesky
factorizations and QP solves since the last ``solve``.  While :func:`crocopy.kernels_enabled` the
recursion is one compiled call, :func:`.box_kernel.box_pass` (:mod:`.horizon`), which gives the numpy
path's numbers to round-off; a subclass that overrides ``computeActionValueFunction``, ``computeGains`` or
``computeValueFunction`` gets the numpy steps (logged once at DEBUG level on the ``"crocopy"`` logger).
"""

from __future__ import annotations

from operator import is_

import numpy as np

from .. import kernels
from ..shooting import ShootingProblem
from ..validation import as_bool, check_bounds
from . import box_kernel, horizon
from .base import BackwardPassError
from .box_qp import BoxQP, BoxQPError
from .ddp import SolverDDP

__all__ = ["SolverBoxDDP"]


class BoxSolverMixin:
    """Box-QP gains, the general value update and the clamped rollout shared by Box-DDP/Box-FDDP."""

    def _init_box(self) -> None:
        self.th_stop = 5e-5
        self._qps: dict[int, BoxQP] = {}
        self._lb: list[np.ndarray | None] = []
        self._ub: list[np.ndarray | None] = []
        self.nqp = 0
        self._kernel_fact = 0
        self.general_value_update = False
        self._compat = False
        self._allocate_box()
        self._read_bounds()

    def _allocate_box(self) -> None:
        """Per-node box buffers, and one box QP per control dimension (kept across re-allocations)."""
        problem = self.problem
        for m in problem.runningModels:
            if m.nu and m.nu not in self._qps:
                qp = self._qps[m.nu] = BoxQP(m.nu, maxiter=100, th_acceptStep=0.1, th_grad=1e-5, reg=0.0)
                qp.compat_crocoddyl = self._compat
        self._clamped = np.zeros(problem.T, dtype=np.bool_)

    _views = (*SolverDDP._views, "Quu_inv")

    def _bind_views(self) -> None:
        super()._bind_views()
        self.Quu_inv = self._horizon.views(horizon.QUU_INV, running=True)

    def _on_problem_change(self) -> bool:
        changed = super()._on_problem_change()
        if changed:
            self._allocate_box()
        return changed

    def _read_bounds(self) -> None:
        """Fetch and check every running model's control bounds (called at each ``solve``); also stacked
        for the compiled pass (infinite where a node is unbounded).  Bounds that are the same arrays holding the same
        values as at the last read, on the same nodes and buffers, are taken as they were (checked then)."""
        models = self.problem.runningModels
        lbs, ubs = [m.u_lb for m in models], [m.u_ub for m in models]
        version = self.problem._nodes_version
        seen = self.__dict__.get("_bounds_seen")
        if (seen is not None and seen[0] == version and self._bounds_for is self._horizon
                and _same_bounds(lbs, seen[1]) and _same_bounds(ubs, seen[2])):
            return
        self._lb, self._ub = [], []
        for t, (m, lb, ub) in enumerate(zip(models, lbs, ubs)):
            lb, ub = np.asarray(lb, dtype=float), np.asarray(ub, dtype=float)
            if lb.shape != (m.nu,) or ub.shape != (m.nu,):
                raise ValueError(f"running model {t}: u_lb/u_ub must have shape ({m.nu},)")
            if np.isnan(lb).any() or np.isnan(ub).any():
                raise ValueError(f"running model {t}: u_lb/u_ub contain NaN")
            check_bounds(lb, ub, f"runningModels[{t}].u_lb", f"runningModels[{t}].u_ub")
            bounded = m.nu > 0 and bool(np.isfinite(lb).any() or np.isfinite(ub).any())
            self._lb.append(lb if bounded else None)
            self._ub.append(ub if bounded else None)
        nus = [m.nu for m in self.problem.runningModels]
        self._uoff = np.concatenate(([0], np.cumsum(nus, dtype=np.int64)))
        self._bounded = np.array([lb is not None for lb in self._lb], dtype=np.bool_)
        self._unboxed = np.zeros(len(nus), dtype=np.bool_)
        self._lb_stack = np.concatenate([np.full(n, -np.inf) if lb is None else lb for n, lb in zip(nus, self._lb)]
                                        or [np.zeros(0)])
        self._ub_stack = np.concatenate([np.full(n, np.inf) if ub is None else ub for n, ub in zip(nus, self._ub)]
                                        or [np.zeros(0)])
        self._us_stack = np.zeros(self._uoff[-1])
        self._bounds_for = self._horizon
        self._bound_addresses = None
        self._bounds_seen = (version, _snapshot(lbs), _snapshot(ubs))

    def _start(self, init_xs, init_us, is_feasible: bool, init_reg) -> None:
        self._read_bounds()
        for qp in self._qps.values():
            qp.nfactorizations = 0
        self.nqp = 0
        self._kernel_fact = 0
        super()._start(init_xs, init_us, is_feasible, init_reg)

    def _reports_feasible_gaps(self) -> bool:
        return self._compat  # Crocoddyl reports the gaps, its backward pass ignores them

    @property
    def compat_crocoddyl(self) -> bool:
        """Reproduce Crocoddyl 3.2's departures from the papers (crocopy extension, default False)."""
        return self._compat

    @compat_crocoddyl.setter
    def compat_crocoddyl(self, value: bool) -> None:
        self._compat = as_bool(value, "compat_crocoddyl")
        for qp in self._qps.values():
            qp.compat_crocoddyl = self._compat

    @property
    def nfactorizations(self) -> int:
        """Box-QP factorizations since the last ``solve`` (all nodes, all iterations)."""
        return self._kernel_fact + sum(qp.nfactorizations for qp in self._qps.values())

    def backwardPass(self) -> None:
        """Riccati recursion with box-QP gains; one compiled call while :func:`crocopy.kernels_enabled`.

        The compiled pass (:func:`.box_kernel.box_pass`) gives the numbers of the node steps
        ``computeActionValueFunction`` / ``computeGains`` / ``computeValueFunction`` to round-off; a subclass
        overriding one of them gets the numpy steps (logged once at DEBUG level on the ``"crocopy"`` logger).
        """
        if kernels.active and self._kernel_applies(SolverBoxDDP, "the compiled box-QP backward pass"):
            self._backward_pass_kernel()
        else:
            self._backward_pass_numpy()

    def _compiled_pass(self, daddr: np.ndarray, preg: float, gaps: bool) -> int:
        """:func:`.box_kernel.box_pass`: the box QP at the bounded nodes of a feasible iterate, the Riccati
        step elsewhere; -1, or the first node (from the end) whose gains failed."""
        if self._bounds_for is not self._horizon:  # re-allocated since the bounds were read
            self._read_bounds()
        boxed = self._bounded if self._box_mode() else self._unboxed
        if boxed is self._bounded and self.us:
            np.concatenate(self.us, out=self._us_stack)
        compat = self._compat
        qp = next(iter(self._qps.values()), None)  # the QPs of every control size share their settings
        th_grad, th_acc, maxiter = (1e-5, 0.1, 100) if qp is None else (qp.th_grad, qp.th_acceptStep, qp.maxiter)
        counts = np.zeros(2, dtype=np.int64)
        h = self._horizon
        t = box_kernel.box_pass(
            daddr, h.addr, h.dims, preg, gaps, boxed, self._lb_stack, self._ub_stack, self._us_stack,
            self._uoff, th_grad, -th_acc if compat else th_acc, 1.0 if compat else -1.0, maxiter,
            bool(self.general_value_update), self._clamped, counts,
        )
        self._kernel_fact += int(counts[0])
        self.nqp += int(counts[1])
        return t

    def _box_mode(self) -> bool:
        return self.isFeasible

    def computeGains(self, t: int) -> None:
        """Box-QP feed-forward and free-subspace feedback at node ``t`` (Cholesky gains if unbounded)."""
        lb = self._lb[t]
        if lb is None or not self._box_mode():
            self._clamped[t] = False
            super().computeGains(t)
            return
        u = self.us[t]
        k = self.k[t]
        qp = self._qps[u.size]
        try:
            sol = qp._solve(self.Quu[t], self.Qu[t], lb - u, self._ub[t] - u, k if self._compat else -k)
        except BoxQPError as exc:
            failure = self._node_failure(t)
            if isinstance(failure, BackwardPassError):
                failure = BackwardPassError(f"box QP failed at node {t}: {exc}")
            raise failure from exc
        self.nqp += 1
        np.negative(sol.x, out=k)
        Quu_inv = self.Quu_inv[t]
        mask = sol._free_mask
        if mask is None:
            Quu_inv[:] = sol.Hff_inv
            self._clamped[t] = False
        else:
            Quu_inv.fill(0.0)
            f = sol.free_idx
            if f:
                Quu_inv[np.ix_(f, f)] = sol.Hff_inv
            self._clamped[t] = True
        np.dot(Quu_inv, self.Qxu[t].T, out=self.K[t])
        if mask is not None and not self.general_value_update:
            self.Qu[t][~mask] = 0.0

    def computeValueFunction(self, t: int, model) -> None:
        """Value function; with ``general_value_update``, the exact gradient update where controls are clamped."""
        super().computeValueFunction(t, model)
        if self._clamped[t] and self.general_value_update:
            k, K = self.k[t], self.K[t]
            self.Vx[t] += K.T @ (self.Quu[t] @ k) - self.Qxu[t] @ k


class SolverBoxDDP(BoxSolverMixin, SolverDDP):
    """Crocoddyl's ``SolverBoxDDP(problem)``: DDP with a box QP per node and a clamped rollout.

    Parameters
    ----------
    problem : ShootingProblem
        Problem whose running models carry the control bounds ``u_lb``/``u_ub``.
    """

    _nodes_compiled = True
    _line_search = (False, True)
    """``(negative, bounded)`` of the compiled line search (:mod:`.line_search`)."""

    def __init__(self, problem: ShootingProblem) -> None:
        super().__init__(problem)
        self._init_box()

    def forwardPass(self, steplength: float) -> None:
        """Rollout with ``û = clamp(u - α k - K (x̂ ⊖ x))``; raises ForwardPassError on NaN.

        In ``compat_crocoddyl`` mode an infeasible iterate keeps its last gap open by ``(1 - α)``.
        """
        last_gap = self.compat_crocoddyl and not self.isFeasible and steplength != 1.0
        self._trial_rollout(steplength, bounds=(self._lb, self._ub), last_gap=last_gap)


def _values(bounds: list) -> np.ndarray:
    """The bounds' values, stacked as floats."""
    return np.concatenate([np.asarray(b, dtype=float).ravel() for b in bounds] or [np.zeros(0)])


def _snapshot(bounds: list) -> tuple:
    """The bound arrays themselves and a copy of their values (what :func:`_same_bounds` compares)."""
    return bounds, _values(bounds)


def _same_bounds(bounds: list, snapshot: tuple) -> bool:
    """Whether ``bounds`` are the arrays of ``snapshot`` holding its values to the bit (a signed zero included)."""
    arrays, values = snapshot
    if len(bounds) != len(arrays) or not all(map(is_, bounds, arrays)):
        return False
    now = _values(bounds)
    return now.shape == values.shape and bool((now.view(np.int64) == values.view(np.int64)).all())
