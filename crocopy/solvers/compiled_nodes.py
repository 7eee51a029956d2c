"""Compiled node evaluations inside a solve of the DDP family.

A node whose model can be evaluated by one compiled call offers an *evaluator*:
``model._compiled_node(data, terminal, memo)``, called at the start of a solve, returns an object
that has re-read the model's parameters (references, weights, time step) and has

* ``calc(x, u)``: writes ``data.xnext`` and ``data.cost`` (``u = None`` for the terminal node);
* ``calcDiff(x, u, synced)``: writes ``data.xnext``, ``data.cost``, ``Fx``, ``Fu``, ``Lx``, ``Lu``, ``Lxx``,
  ``Lxu`` and ``Luu``; it evaluates the node's values again unless its own last ``calc`` was at ``(x, u)`` to the
  bit (it never relies on the ``synced`` hint, nor on a ``model.calc`` that wrote the data in between: that one
  spends the stamp, ``data.compiled_stamp``, as every refresh does);
* optionally ``rollout_step(x_ref, x, u_ref, k, K, alpha, lb, ub, u, dx, x_next, f, gap) -> cost``: one
  node of the rollout (``dx = x ⊖ x_ref``, the clamped feedback control ``u``, ``calc``, and
  ``x_next = xnext``, or ``xnext ⊕ ((alpha - 1) f)`` when ``gap``) in one call; the caller stores the
  returned cost in ``data.cost``;
* optionally, on its class, ``horizon(evaluators, nus) -> horizon`` (``evaluators`` of the running nodes, ``None``
  where a node has none of that class; ``nus`` their control sizes): when every running node with a rollout step
  has an evaluator of that class and all share one state size, ``horizon.rollout(addresses, xs_try, us_try, alpha,
  gaps, gap_at, t0, t1) -> total`` runs the rollout steps of the nodes ``t0 <= t < t1`` in one call (``addresses``:
  of the solver's arrays, :func:`.rollout.horizon_addresses`; ``gap_at``: the one node whose gap stays open
  besides ``gaps``, -1 for none; a non-finite total: ``horizon.costs`` says from which node on, and
  ``horizon.fold(t0, t) -> total`` adds the costs before it), ``horizon.calc_diff_ranges(xs, us, fs, xs_at, us_at,
  fs_at, ranges) -> totals`` the ``calcDiff`` of the nodes of each range ``(t0, t1)`` (and their gaps ``fs[t+1]``
  when ``fs_at``, the gaps' addresses) and ``horizon.calc_ranges(xs, us, xs_at, us_at, ranges) -> totals`` their
  ``calc``, all the ranges in one go (several threads share their nodes out at once); each node's cost is in
  ``horizon.costs[t]``, which the caller stores in the datas; optionally ``horizon.trial(...)``, SolverSQP/
  SolverCSQP's trial point of a range (:meth:`CompiledNodes.trial`).  The calls cover each maximal range of such
  nodes (:attr:`CompiledNodes.segments`); the other nodes keep their Python step in between;

and optionally ``refreshes`` (how many times it re-read everything) with ``refresh_live(memo) -> bool`` (re-read in
place what may change without moving the parameter clock; False when it must be made again): a problem whose
evaluators all have them keeps its selection from one solve to the next while it is current (:class:`Selection`);

or ``None`` (models without the method, or nodes it cannot compile).  ``terminal`` tells whether the node is the
problem's terminal node; ``memo`` is a dictionary shared by the nodes of one solve (for what they
derive once from shared models).  Today the Euler- and Runge-Kutta-integrated free and contact forward dynamics of
a multibody system with residual costs have one (:mod:`crocopy.models.rbd.euler_node`,
:mod:`crocopy.models.rbd.rk_node`), which also writes the
constraint rows ``g, Gx, Gu, h, Hx, Hu`` of its constraint manager (:mod:`crocopy.models.rbd.constraint_rows`), and so
do their inverse-dynamics twins (:mod:`crocopy.models.rbd.invdyn_node`) and impulse nodes
(:mod:`crocopy.models.rbd.impulse_node`).

Inside ``solve`` those evaluators replace ``model.calc``/``model.calcDiff`` in the derivatives and the
rollout.  They write the action data fields above, and the arrays the nested datas share with them (the
differential data's ``xout``, ``Fx``, ``Fu``, ``Lx`` ... and the cost stack's residuals, Jacobians and
activation derivatives), not the rest of the nested datas (Pinocchio data, a residual's own
intermediates).  When ``solve`` returns, :meth:`CompiledNodes.fill` at the final iterate fills every value as
``problem.calc`` there leaves them (to round-off): an evaluator with a ``fill(x, u)`` keeps the compiled values and
writes the rest (a node of free dynamics: Pinocchio data, torques, residual and constraint datas,
:meth:`crocopy.models.rbd.euler_node.EulerNode.fill`), the other nodes run their model's ``calc``; the derivatives
are, as without compiled nodes, those of
the iterate the last direction was computed at, except the Pinocchio data's derivative fields and the
residuals' private intermediates (frame Jacobians), which compiled nodes do not write.  The compiled
nodes are used only while :func:`crocopy.kernels_enabled`, by the solver classes that declare
``_nodes_compiled = True`` in their own body (DDP, FDDP, Box-DDP, Box-FDDP, SQP, CSQP, Intro, projection; a subclass
may read nested datas mid-solve, so it opts in explicitly), and when every callback is one of crocopy's (a user
callback may read nested datas).
"""

from __future__ import annotations

import contextlib
import math
import weakref
from collections.abc import Callable
from itertools import groupby, islice
from operator import is_

import numpy as np

from .. import kernels
from ..versioning import STRUCTURE, ParametersVersion, any_stale
from .trajectories import TrajectoryAddresses, addresses


def _python_calc(model, data) -> Callable:
    def calc(x, u):
        model.calc(data, x, u)

    return calc


def _python_fill(model, data) -> Callable:
    def fill(x, u):
        model._raw_calc(data, x, u)

    return fill


def _python_calc_diff(model, data) -> Callable:
    def calc_diff(x, u, synced):
        if not synced:
            model.calc(data, x, u)
        model.calcDiff(data, x, u)

    return calc_diff


def _node_by_node(problem, steps: list[Callable], xs, us) -> float:
    """``steps[t](xs[t], us[t])`` for every running node, then ``steps[-1](xs[-1], None)``; returns the sum of the
    datas' costs in node order (also ``problem.cost``)."""
    cost = 0.0
    for step, d, x, u in zip(steps, problem.runningDatas, xs, us):
        step(x, u)
        cost += d.cost
    steps[-1](xs[-1], None)
    cost += problem.terminalData.cost
    problem.cost = cost
    return cost


class CompiledNodes:
    """Per-node ``calc(x, u)`` and ``calcDiff(x, u, synced)`` of one solve: the compiled evaluators
    where the nodes offer one, the models' own methods elsewhere (the terminal node last)."""

    def __init__(self, calcs: list[Callable], calc_diffs: list[Callable], steps: list[Callable | None],
                 fills: list[Callable], horizon: Callable | None = None, problem=None, terminal=None) -> None:
        self.calcs = calcs
        self.fills = fills
        """Per node, what :meth:`fill` calls: the evaluator's ``fill(x, u)``, or the model's own ``calc``."""
        self.terminal = terminal
        """The terminal node's evaluator, or None (its model's own methods)."""
        self.calc_diffs = calc_diffs
        self.steps = steps
        self.horizon = horizon
        models = [] if problem is None else problem.runningModels
        self.nu = [m.nu for m in models]
        self.nx = [m.state.nx for m in models]
        self.ndx = [m.state.ndx for m in models]
        in_horizon = [horizon is not None and step is not None for step in steps]
        self.segments: dict[int, int] = {}
        """First node → one past the last node of each maximal range of nodes the horizon runs."""
        t = 0
        for inside, run in groupby(in_horizon):
            end = t + len(list(run))
            if inside:
                self.segments[t] = end
            t = end
        self.ranges = list(self.segments.items())
        """The same ranges as ``(first, one past the last)`` pairs, in node order (what the horizon's calls take)."""
        self.in_horizon = in_horizon
        self.inside = np.array(in_horizon + [False], dtype=np.int64)
        """1 at the running nodes inside the horizon's ranges, 0 elsewhere and at the terminal node."""
        self.python_nodes = [t for t, inside in enumerate(in_horizon) if not inside]
        """The running nodes outside the horizon's ranges."""
        self._whole = bool(steps) and self.ranges == [(0, len(steps))]
        """Whether the horizon runs every running node (then :meth:`calcDiff` and :meth:`trial` may take one call)."""
        self._out = np.zeros(1)

    def bounds(self, lbs: list | None, ubs: list | None, unbounded: dict) -> tuple[list, list]:
        """Per running node, the control bounds of the rollout: ``lbs[t]``/``ubs[t]``, or ``unbounded[nu]`` where
        ``lbs`` is None or its entry is None."""
        lb_list, ub_list = [], []
        for t, nu in enumerate(self.nu):
            lb = None if lbs is None else lbs[t]
            lb, ub = unbounded[nu] if lb is None else (lb, ubs[t])
            lb_list.append(lb)
            ub_list.append(ub)
        return lb_list, ub_list

    def calc(self, problem, xs, us, at: TrajectoryAddresses | None = None) -> float:
        """Every node's value at ``(xs, us)`` (``at``: where they are, when they are a solver's trajectories);
        returns the total cost."""
        if self.horizon is None:
            return _node_by_node(problem, self.calcs, xs, us)
        cost = 0.0
        datas, horizon = problem.runningDatas, self.horizon
        xa, ua = (addresses(xs), addresses(us)) if at is None else (at.xs, at.us)
        ranges = self.ranges
        for (t0, t1), total in zip(ranges, horizon.calc_ranges(xs, us, xa, ua, ranges)):
            cost += total
            for d, c in zip(islice(datas, t0, t1), horizon.costs[t0:t1].tolist()):
                d.cost = c
        for t in self.python_nodes:
            self.calcs[t](xs[t], us[t])
            cost += datas[t].cost
        self.calcs[-1](xs[-1], None)
        cost += problem.terminalData.cost
        problem.cost = cost
        return cost

    def fill(self, problem, xs, us) -> float:
        """At the end of a solve: every node's data at ``(xs, us)`` as ``problem.calc`` leaves it (each evaluator's
        ``fill``, which keeps its compiled values and writes the rest of the nested datas; the model's own ``calc``
        elsewhere); returns the total cost (also ``problem.cost``)."""
        return _node_by_node(problem, self.fills, xs, us)

    def calcDiff(self, problem, xs, us, synced: bool, fs: list | None = None,
                 at: TrajectoryAddresses | None = None) -> float:
        """Derivatives (and values, unless ``synced``) of every node; returns the total cost.  With ``fs``
        (only with a :attr:`horizon`, which computes its nodes' in the same call), also the gaps
        ``fs[t+1] = xnext_t ⊖ xs[t+1]`` (``fs[0]`` is the caller's).  ``at``: where ``xs``, ``us`` and ``fs`` are,
        when they are a solver's trajectories (else they are read here)."""
        if at is not None and self._whole:
            cost = self._calc_diff_all(problem, at, fs is not None)
            if cost is not None:
                return cost
        if self.horizon is not None:
            cost = 0.0
            datas, horizon = problem.runningDatas, self.horizon
            if at is None:
                xa, ua, fa = addresses(xs), addresses(us), None if fs is None else addresses(fs)
            else:
                xa, ua, fa = at.xs, at.us, at.fs
            ranges = self.ranges
            for (t0, t1), total in zip(ranges, horizon.calc_diff_ranges(xs, us, fs, xa, ua, fa, ranges)):
                cost += total
                for d, c in zip(islice(datas, t0, t1), horizon.costs[t0:t1].tolist()):
                    d.cost = c
            for t in self.python_nodes:
                self.calc_diffs[t](xs[t], us[t], synced)
                d = datas[t]
                cost += d.cost
                if fs is not None:
                    problem.runningModels[t].state._diff_into(xs[t + 1], d.xnext, fs[t + 1])
        else:
            cost = 0.0
            for calc_diff, d, x, u in zip(self.calc_diffs, problem.runningDatas, xs, us):
                calc_diff(x, u, synced)
                cost += d.cost
        self.calc_diffs[-1](xs[-1], None, synced)
        cost += problem.terminalData.cost
        problem.cost = cost
        return cost

    def _calc_diff_all(self, problem, at: TrajectoryAddresses, gaps: bool) -> float | None:
        """:meth:`calcDiff` in one compiled call (the horizon's ``calc_diff_all``), with the same numbers; None where
        it does not apply or a cost is not finite."""
        total = self.horizon.calc_diff_all(at.xs, at.us, at.fs if gaps else None, self.terminal, self._out)
        return self._whole_costs(problem, total)

    def _trial_all(self, problem, alpha: float, at: TrajectoryAddresses, stacks: tuple) -> float | None:
        """:meth:`trial` in one compiled call (the horizon's ``trial_all``), with the same numbers; None where it does
        not apply or a cost is not finite."""
        total = self.horizon.trial_all((at.xs, at.us, at.xs_try, at.us_try), problem.x0, *stacks[:2], alpha,
                                       *stacks[2:], self.terminal, self._out)
        return self._whole_costs(problem, total)

    def _whole_costs(self, problem, total: float | None) -> float | None:
        """After a call over every node whose running total is ``total`` (None: it did not apply): the running nodes'
        costs (the horizon's) and the terminal one (``_out[0]``) into the datas; returns the total cost, added as the
        node by node path adds it, or None (nothing written) where a cost is not finite."""
        if total is None or not math.isfinite(total) or not math.isfinite(self._out[0]):
            return None
        for d, c in zip(problem.runningDatas, self.horizon.costs.tolist()):
            d.cost = c
        terminal = problem.terminalData.cost = float(self._out[0])
        cost = 0.0
        cost += total
        cost += terminal
        problem.cost = cost
        return cost

    def trial(self, problem, xs, us, dx, du, alpha: float, trajectories: tuple, at: TrajectoryAddresses,
              stacks: tuple) -> float:
        """SolverSQP/SolverCSQP's trial point: ``x̂_t = x_t ⊕ α δx_t``, ``û_t = u_t + α δu_t``, every node's value
        there and the gaps ``f̂_{t+1} = xnext_t ⊖ x̂_{t+1}``, ``f̂_0 = x0 ⊖ x̂_0``; returns the total cost.

        ``trajectories = (xs_try, us_try, fs_try)``, the lists written (the solver's own arrays, at the addresses
        ``at``); ``stacks = (dx, du, fs, step)``: the padded stacks ``(T+1, n)``/``(T+1, m)`` the lists ``dx``, ``du``,
        ``fs_try`` are views of, and a scratch of at least ``n`` entries.  Each range of nodes of a horizon with a
        ``trial(addresses, x0, dx, du, alpha, fs, step, trajectories, t0, t1) -> total`` is one call (its nodes' costs
        in ``horizon.costs``); the other nodes go one by one (their states and controls first, so a range reads the
        state after it)."""
        if self._whole:
            cost = self._trial_all(problem, alpha, at, stacks)
            if cost is not None:
                return cost
        xs_try, us_try, fs_try = trajectories
        models, datas, x0 = problem.runningModels, problem.runningDatas, problem.x0
        trial = getattr(self.horizon, "trial", None)
        segments = self.segments if trial is not None else {}
        outside = self.python_nodes if trial is not None else range(problem.T)
        for t in outside:
            models[t].state._integrate_into(xs[t], alpha * dx[t], xs_try[t])
            np.add(us[t], alpha * du[t], out=us_try[t])
        integrate = getattr(self.terminal, "integrate", None) or problem.terminalModel.state._integrate_into
        integrate(xs[-1], alpha * dx[-1], xs_try[-1])
        cost = 0.0
        if segments:
            horizon = self.horizon
            addresses = (at.xs, at.us, at.xs_try, at.us_try)
            for t0, t1 in segments.items():
                cost += trial(addresses, x0, *stacks[:2], alpha, *stacks[2:], trajectories, t0, t1)
                for d, c in zip(islice(datas, t0, t1), horizon.costs[t0:t1].tolist()):
                    d.cost = c
        for t in outside:
            self.calcs[t](xs_try[t], us_try[t])
            d = datas[t]
            cost += d.cost
            models[t].state._diff_into(xs_try[t + 1], d.xnext, fs_try[t + 1])
        if 0 not in segments:
            if problem.T:
                models[0].state._diff_into(xs_try[0], x0, fs_try[0])
            else:
                fs_try[0][:] = 0.0
        self.calcs[-1](xs_try[-1], None)
        cost += problem.terminalData.cost
        problem.cost = cost
        return cost


def select(solver) -> CompiledNodes | None:
    """The compiled nodes of ``solver.problem`` for this solve, or None (no node has one, or the
    solver, a callback or the kernel switch rules them out; see the module docstring).  The problem's last selection
    is reused while it is current (:class:`Selection`)."""
    if not kernels.active or not type(solver).__dict__.get("_nodes_compiled", False):
        return None
    if any(not type(c).__module__.startswith("crocopy.") for c in solver.getCallbacks()):
        return None
    problem = solver.problem
    last = _SELECTIONS.pop(problem, None)
    if last is not None and last.current(problem):
        _SELECTIONS[problem] = last
        return last.nodes
    calcs, calc_diffs, steps, evaluators, fills = [], [], [], [], []
    found = False
    memo: dict = {}
    nodes = [*zip(problem.runningModels, problem.runningDatas), (problem.terminalModel, problem.terminalData)]
    for t, (model, data) in enumerate(nodes):
        make = getattr(model, "_compiled_node", None)
        evaluator = None if make is None else make(data, t == problem.T, memo)
        evaluators.append(evaluator)
        fill = getattr(evaluator, "fill", None)
        fills.append(_python_fill(model, data) if fill is None else fill)
        if evaluator is None:
            calcs.append(_python_calc(model, data))
            calc_diffs.append(_python_calc_diff(model, data))
            steps.append(None)
        else:
            found = True
            calcs.append(evaluator.calc)
            calc_diffs.append(evaluator.calcDiff)
            steps.append(getattr(evaluator, "rollout_step", None) if model.nu else None)
    if not found:
        return None
    running = evaluators[:-1]
    stepping = [e for e, step in zip(running, steps) if step is not None]
    kind = type(stepping[0]) if stepping else None
    horizon = None
    if stepping and all(type(e) is kind for e in stepping) and len({m.state.nx for m in problem.runningModels}) == 1:
        make_horizon = getattr(kind, "horizon", None)
        if make_horizon is not None:
            horizon = make_horizon([e if step is not None else None for e, step in zip(running, steps)],
                                   [m.nu for m in problem.runningModels], problem.nthreads)
            steps = [None if step is None else e.rollout_step for e, step in zip(running, steps)]  # its arrays
    selected = CompiledNodes(calcs, calc_diffs, steps[:problem.T], fills, horizon, problem, evaluators[-1])
    if all(e is None or hasattr(e, "refresh_live") for e in evaluators):
        _SELECTIONS[problem] = Selection(problem, selected, evaluators)
    return selected


class Selection:
    """A problem's compiled nodes kept from one solve to the next.

    It is current while the problem's node version, its ``nthreads``, its models and datas (the same objects) have
    not changed, the structure clock (:data:`~crocopy.versioning.STRUCTURE`) stood still or moved without making a
    data stale that is still alive (:func:`~crocopy.versioning.any_stale`: another problem built; a solve replaces
    its problem's stale datas with ``problem.refresh_datas()`` first, which moves the node version), no evaluator
    was refreshed by another selection since (``evaluator.refreshes``), every evaluator re-read in place what it
    reads at a solve's start (False if it cannot: its Pinocchio model changed, ...), and the nodes without an
    evaluator, offered again, still decline (their refusals are class checks, except those that depend on a
    Pinocchio model).  While the parameter
    clock (:class:`~crocopy.versioning.ParametersVersion`) stands still, an evaluator re-reads what may change
    unannounced (``refresh_live(memo)``: Pinocchio's objects, a user residual's ``parameters()``); once it moved
    (a setter called anywhere), all its parameters (``refresh_values(memo)``: False where what it read as its layout
    was touched, a frame or a residual replaced).  Otherwise :func:`select` makes the selection again.
    """

    def __init__(self, problem, nodes: CompiledNodes, evaluators: list) -> None:
        self.nodes = nodes
        self.clocks = self._clocks(problem)
        self.models = (*problem.runningModels, problem.terminalModel)
        self.datas = (*problem.runningDatas, problem.terminalData)
        self.evaluators = [(e, e.refreshes) for e in evaluators if e is not None]
        self.declined = [(t, m, d) for t, (m, d, e) in enumerate(zip(self.models, self.datas, evaluators))
                         if e is None and hasattr(m, "_compiled_node")]

    @staticmethod
    def _clocks(problem) -> tuple:
        return ParametersVersion.value, STRUCTURE[0], problem._nodes_version, problem.nthreads

    def current(self, problem) -> bool:
        """Whether the selection still holds (see the class docstring); re-reads the live parameters in place, and
        after the parameter clock alone moved, every evaluator's parameters (``refresh_values``: False where what
        it read as its layout was touched)."""
        clocks = self._clocks(problem)
        if self.clocks[2:] != clocks[2:] or (self.clocks[1] != clocks[1] and any_stale()):
            return False
        values = self.clocks[0] != clocks[0]
        models, datas = problem.runningModels, problem.runningDatas
        if len(models) + 1 != len(self.models) or not all(map(is_, models, self.models)) \
                or not all(map(is_, datas, self.datas)) or problem.terminalModel is not self.models[-1] \
                or problem.terminalData is not self.datas[-1]:
            return False
        memo: dict = {}
        T = problem.T
        if not (all(e.refreshes == n and (e.refresh_values(memo) if values else e.refresh_live(memo))
                    for e, n in self.evaluators)
                and all(m._compiled_node(d, t == T, memo) is None for t, m, d in self.declined)):
            return False
        self.clocks = clocks
        return True


_SELECTIONS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
"""Problem → its last :class:`Selection`."""


def attach(solver) -> CompiledNodes | None:
    """Select the compiled nodes for ``solver`` and keep them on it, as ``solve`` does for its duration, so that
    ``solver.calcDiff``/``tryStep`` called outside ``solve`` run them too (benchmarks timing a solve's phases).
    The datas are then those of a solve (the nested ones not updated) until ``problem.calc``/``calcDiff``."""
    solver._nodes = select(solver)
    return solver._nodes


def prepare(solver) -> None:
    """Make the compiled evaluators of ``solver.problem``'s nodes now (their tables of addresses, checked), which the
    first solve would otherwise make, as Crocoddyl's and mim-solvers' solvers allocate their workspace when they are
    made.  A solve reuses them while they are current (:class:`Selection`: the parameters that may change unannounced
    are re-read).  An array a node cannot list (ValueError) is left for the solve to report."""
    with contextlib.suppress(ValueError):
        select(solver)
