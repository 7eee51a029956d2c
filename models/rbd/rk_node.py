"""Compiled Runge-Kutta nodes of free or contact forward dynamics: one numba call per node evaluation inside a solve.

:class:`RKNode` is the evaluator (:mod:`crocopy.solvers.compiled_nodes`) of an ``IntegratedActionModelRK`` node
(RK2, RK3, RK4, the identity control parametrization; the exact class) over a differential model whose Euler nodes
compile (:mod:`.euler_node`).  Each stage ``i`` is such an Euler node's table (:class:`.euler_node.EulerNode`) over
the stage's own differential data ``data.differential[i]``: its dynamics, residuals, constraint rows and the
differential model's derivatives are the Euler kernels' (:func:`.euler_node_kernel.differential_calc`,
``differential_calc_diff``, which leave out the Euler step), and :mod:`.rk_node_kernel` chains the stages in one
call.  A stage's table lists the action-data arrays of a *stage data* (:class:`_StageData`): scratch arrays, except
the constraint rows of the first stage, which are the node's (its ``g``, ``Gx`` ... are the first stage's), and every
action array of the terminal node (which evaluates the differential model at ``x`` alone, as an Euler terminal
node: ``Fx`` the identity).

The stages' Euler nodes read the models' parameters, and keep them current, as Euler nodes do (``refresh``,
``refresh_values``, ``refresh_live``); a user's Python residual, which an Euler node of free dynamics evaluates
around its compiled call, has no place between the stages: such a node declines.  When ``solve`` returns,
:meth:`RKNode.fill` runs the model's own ``calc`` (the stages' Pinocchio and residual datas, ``y``, ``ki`` ...).
"""

from __future__ import annotations

import math
import weakref
from functools import partial

import numpy as np

from crocopy.not_compiled import decline

from . import euler_node_kernel as euler_kernel
from . import rk_node_kernel as kernel

ACTION_ARRAYS = ("xnext", "dx", "Fx", "Fu", "Lx", "Lu", "Lxx", "Lxu", "Luu")
"""The action-data arrays an Euler node's table lists."""
ROW_ARRAYS = ("g", "Gx", "Gu", "h", "Hx", "Hu")
"""The action data's constraint rows a table lists."""

_NODES: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
"""Node data → its :class:`RKNode`."""


class _StageData:
    """What the Euler node of one stage reads as its action data: the stage's differential data and the arrays its
    table lists (``compiled_stamp``: the stage's stamp, set by its Euler node)."""

    def __init__(self, differential, arrays: dict[str, np.ndarray]) -> None:
        self.differential = differential
        self.compiled_stamp: np.ndarray | None = None
        self.cost = 0.0
        for name, array in arrays.items():
            setattr(self, name, array)


def _stage_datas(data, terminal: bool) -> list[_StageData]:
    """One :class:`_StageData` per stage (the terminal node: one, the first stage's, over the node's own arrays)."""
    if terminal:
        return [_StageData(data.differential[0], {n: getattr(data, n) for n in ACTION_ARRAYS + ROW_ARRAYS})]
    stages = []
    for i, ddata in enumerate(data.differential):
        arrays = {n: np.zeros_like(getattr(data, n)) for n in ACTION_ARRAYS}
        arrays.update({n: getattr(data, n) if i == 0 else np.zeros_like(getattr(data, n)) for n in ROW_ARRAYS})
        stages.append(_StageData(ddata, arrays))
    return stages


def rk_node(iam, data, terminal: bool, memo: dict) -> RKNode | None:
    """The refreshed evaluator of the Runge-Kutta node ``(iam, data)``, or None if it does not qualify (the reason
    recorded in ``memo``, :mod:`crocopy.not_compiled`; the caller has checked the integrator's class and control)."""
    node = _NODES.get(data)
    if node is None or node.model is not iam or node.terminal != terminal:
        node = RKNode(iam, data, terminal)
        _NODES[data] = node
    return node if node.refresh(memo) else None


class RKNode:
    """The compiled ``calc``/``calcDiff`` of one Runge-Kutta node (see the module docstring).

    ``calc(x, u)`` writes ``data.xnext``, ``data.dx`` and ``data.cost``; ``calcDiff(x, u, synced)`` also ``Fx``,
    ``Fu``, ``Lx``, ``Lu``, ``Lxx``, ``Lxu``, ``Luu`` (and the stages' differential datas' values and derivatives).
    """

    refreshes = 0
    """How many times :meth:`refresh` ran (a selection of compiled nodes made before the last one is stale)."""

    def __init__(self, iam, data, terminal: bool) -> None:
        self.model = iam
        self.terminal = terminal
        self._data = weakref.ref(data)
        self.stamp = np.zeros(1)
        self.dts = np.zeros(1)
        self.stage_datas: list[_StageData] = []
        self.stages: list = []
        self.no_control = np.zeros(0)
        self._sizes: tuple = ()

    def refresh(self, memo: dict) -> bool:
        """Make or refresh the stages' Euler nodes and bind the node's arrays; False if a stage does not qualify (the
        reason recorded in ``memo``)."""
        iam, data = self.model, self._data()
        ni = 1 if self.terminal else len(iam.rk_c)
        if len(self.stage_datas) != ni or any(
                s.differential is not d for s, d in zip(self.stage_datas, data.differential)) \
                or any(getattr(self.stage_datas[0], n).shape != getattr(data, n).shape
                       for n in ACTION_ARRAYS + ROW_ARRAYS):
            self.stage_datas = _stage_datas(data, self.terminal)
        stages = []
        for stage_data in self.stage_datas:
            stage = iam.differential._compiled_euler_node(iam, stage_data, self.terminal, memo)
            if stage is None:
                return False
            if stage.python.items:
                decline(memo, "user Python residual in a Runge-Kutta node")
                return False
            stages.append(stage)
        self.stages = stages
        first = stages[0]
        if any(not np.array_equal(s.ints, first.ints) for s in stages[1:]):
            decline(memo, "Runge-Kutta stages of different layouts")
            return False
        self.tbls = np.stack([s.tbl for s in stages])
        self.ints, self.par = first.ints, first.par
        self.coef = np.array([iam.rk_c, iam.rk_b], dtype=float) if not self.terminal else np.zeros((2, 1))
        self._bind(data)
        self.refreshes += 1
        return True

    def _bind(self, data) -> None:
        """The time step, the stamp (spent) and the scratch of the kernels, made again for other sizes."""
        self.dts[0] = float(self.model.dt)
        self.stamp[0] = 0.0
        data.compiled_stamp = self.stages[0].stamp if self.terminal else self.stamp  # what the Python path spends
        ni, state, nu = len(self.stages), self.model.state, self.model.nu
        nx, ndx, nv = state.nx, state.ndx, state.nv
        if self._sizes != (ni, nx, ndx, nu):
            self._sizes = (ni, nx, ndx, nu)
            y, dy, k = np.zeros((ni, nx)), np.zeros((ni, ndx)), np.zeros((ni, ndx))
            self._work = (y, dy, k, np.zeros((nv, nv)), np.zeros((nv, nv)), np.zeros((ndx, ndx)), np.zeros((ndx, nu)))
            self._jac = tuple(np.zeros((ni, ndx, n)) for n in (ndx, nu, ndx, nu))
            self._sums = (np.zeros((ndx, ndx)), np.zeros((ndx, nu)))
            self._step = np.zeros(ndx)
        y, dy, k = self._work[:3]
        self._values = (y, dy, k, data.dx, data.xnext)
        self._out = (data.dx, data.xnext, data.Fx, data.Fu, *self._sums, data.Lx, data.Lu, data.Lxx, data.Lxu,
                     data.Luu)

    def _reread(self, memo: dict, method: str) -> bool:
        """``refresh_values``/``refresh_live`` of every stage, then the time step and the tableau, in place."""
        iam = self.model
        if not all(getattr(s, method)(memo) for s in self.stages):
            return False
        if not self.terminal:
            if len(iam.rk_c) != len(self.stages):
                return False
            self.coef[0], self.coef[1] = iam.rk_c, iam.rk_b
        self.dts[0] = float(iam.dt)
        self.stamp[0] = 0.0
        return True

    def refresh_values(self, memo: dict) -> bool:
        """After the parameter clock moved: every stage's :meth:`.euler_node.EulerNode.refresh_values`, the time step
        and the tableau; False when the node must be refreshed."""
        return self._reread(memo, "refresh_values")

    def refresh_live(self, memo: dict) -> bool:
        """Every stage's :meth:`.euler_node.EulerNode.refresh_live`, the time step and the tableau; False when the node
        must be refreshed."""
        return self._reread(memo, "refresh_live")

    def calc(self, x: np.ndarray, u: np.ndarray | None) -> None:
        if self.terminal:
            cost = euler_kernel.node_calc(self.tbls[0], self.ints, self.par, x, self.no_control)
        else:
            cost = kernel.rk_calc(self.tbls, self.ints, self.par, self.coef[0], self.coef[1], self.dts, self.stamp,
                                  x, u, *self._values)
        if math.isfinite(cost):
            self._data().cost = cost
        else:
            self.python_path(x, u, False)

    def calcDiff(self, x: np.ndarray, u: np.ndarray | None, synced: bool) -> None:
        if self.terminal:
            cost = euler_kernel.node_calc_diff(self.tbls[0], self.ints, self.par, x, self.no_control)
        else:
            cost = kernel.rk_calc_diff(self.tbls, self.ints, self.par, self.coef[0], self.coef[1], self.dts,
                                       self.stamp, x, u, self._work, self._jac, self._out)
        if math.isfinite(cost):
            self._data().cost = cost
        else:
            self.python_path(x, u, True)

    def python_path(self, x: np.ndarray, u: np.ndarray | None, derivatives: bool) -> float:
        """Evaluate the node on its Python path (a stage's acceleration is not finite); returns its cost."""
        model, data = self.model, self._data()
        model._raw_calc(data, x, u)
        if derivatives:
            model._raw_calcDiff(data, x, u)
        return data.cost

    def fill(self, x: np.ndarray, u: np.ndarray | None) -> None:
        """The node's data at ``(x, u)`` as its model's ``calc`` leaves it, at the end of a solve (the model's own
        ``calc``: the stages' nested datas are not the kernels')."""
        self.model._raw_calc(self._data(), x, u)

    @property
    def rollout_step(self):
        """One node of the DDP family's rollout (:func:`.rk_node_kernel.rk_rollout_step` on this node's arrays):
        ``rollout_step(x_ref, x, u_ref, k, K, alpha, lb, ub, u, dx, x_next, f, gap) -> cost``."""
        return partial(kernel.rk_rollout_step, self.tbls, self.ints, self.par, self.coef[0], self.coef[1], self.dts,
                       self.stamp, (*self._values, self._step))
