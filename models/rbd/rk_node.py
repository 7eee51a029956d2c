"""Compiled Runge-Kutta nodes of free or contact forward dynamics, and Euler nodes with a control parametrization:
one numba call per node evaluation inside a solve.

:class:`RKNode` is the evaluator (:mod:`crocopy.solvers.compiled_nodes`) of an ``IntegratedActionModelRK`` node
(RK2, RK3, RK4; the exact class) over a differential model whose Euler nodes compile (:mod:`.euler_node`), with
crocopy's polynomial control parametrizations (``PolyZero``, ``PolyOne``, ``PolyTwoRK``: stage ``i`` reads
``wᵢ = w(cᵢ, u)``, its control derivatives and the node's constraint Jacobians ``Gu``, ``Hu`` mapped to ``u`` by
:mod:`.control_map_kernel`).  Each stage ``i`` is such an Euler node's table
(:class:`.euler_node.EulerNode`) over the stage's own differential data ``data.differential[i]``: its dynamics,
residuals, constraint rows and the differential model's derivatives are the Euler kernels'
(:func:`.euler_node_kernel.differential_calc`, ``differential_calc_diff``, which leave out the Euler step), and
:mod:`.rk_node_kernel` chains the stages in one call.  A stage's table lists the action-data arrays of a *stage
data* (:class:`_StageData`): scratch arrays, except the constraint rows of the first stage, which are the node's (its
``g``, ``Gx`` ... are the first stage's), and every action array of the terminal node (which evaluates the
differential model at ``x`` alone, as an Euler terminal
node: ``Fx`` the identity).

The stages' Euler nodes read the models' parameters, and keep them current, as Euler nodes do (``refresh``,
``refresh_values``, ``refresh_live``); a user's Python residual, which an Euler node of free dynamics evaluates
around its compiled call, has no place between the stages: such a node declines.  When ``solve`` returns,
:meth:`RKNode.fill` runs the model's own ``calc`` (the stages' Pinocchio and residual datas, ``y``, ``ki`` ...).

:class:`ControlledEulerNode` is the evaluator of an Euler node with a ``PolyOne`` or ``PolyTwoRK`` parametrization:
one stage, an Euler node's table over the node's own arrays (scratch for those sized by the controls), at
``w = w(0, u)``, its ``Fu``, ``Lu``, ``Lxu``, ``Luu``, ``Gu``, ``Hu`` mapped to ``u``.
"""

from __future__ import annotations

import math
import weakref
from functools import partial

import numpy as np

from crocopy.integrators.rk import IntegratedActionModelRK
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
        for name, array in arrays.items():
            setattr(self, name, array)


CONTROL_ARRAYS = ("Fu", "Lu", "Lxu", "Luu", "Gu", "Hu")
"""The arrays sized by the controls: a stage's are of the differential model's ``w`` (``nw``), the node's of ``u``."""


def _stage_datas(data, differentials: list, own: bool, nw: int) -> list[_StageData]:
    """One :class:`_StageData` per differential data of ``differentials`` (the stages'), its arrays sized by the
    stage's controls ``nw``: the node's own action arrays where ``own`` (a terminal node, an Euler node), else
    scratch; the node's constraint rows at the first stage; scratch where the node's, sized by ``u``, differ."""
    same = data.Fu.shape[1] == nw

    def stage_array(name: str, node_array: bool) -> np.ndarray:
        array = getattr(data, name)
        if name in CONTROL_ARRAYS and not same:
            return np.zeros((*array.shape[:-1], nw) if name != "Luu" else (nw, nw))
        return array if node_array else np.zeros_like(array)

    return [_StageData(ddata, {**{n: stage_array(n, own) for n in ACTION_ARRAYS},
                               **{n: stage_array(n, own or i == 0) for n in ROW_ARRAYS}})
            for i, ddata in enumerate(differentials)]


def control_coefficients(control, times) -> np.ndarray:
    """``cw[i, k] = cₖ(τᵢ)``: the coefficients of ``∂w/∂u`` at each stage time ``τᵢ`` of ``times``
    (:mod:`.control_map_kernel`), read from the parametrization's own ``calcDiff``."""
    nw, nu = control.nw, control.nu
    cdata = control.createData()
    cw = np.zeros((len(times), nu // nw))
    for i, t in enumerate(times):
        control.calcDiff(cdata, t, np.zeros(nu))
        cw[i] = cdata.dw_du[0, ::nw]
    return cw


def staged_node(iam, data, terminal: bool, memo: dict) -> RKNode | None:
    """The refreshed evaluator of the Runge-Kutta node, or of the Euler node with a control parametrization,
    ``(iam, data)``, or None if it does not qualify (the reason recorded in ``memo``, :mod:`crocopy.not_compiled`;
    the caller has checked the integrator's class and control)."""
    node = _NODES.get(data)
    kind = RKNode if type(iam) is IntegratedActionModelRK else ControlledEulerNode
    if node is None or node.model is not iam or node.terminal != terminal or type(node) is not kind:
        node = kind(iam, data, terminal)
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
        nw, differentials = iam.differential.nu, self._differentials(data)
        if len(self.stage_datas) != len(differentials) or any(
                s.differential is not d for s, d in zip(self.stage_datas, differentials)) \
                or any(getattr(self.stage_datas[0], n).shape[0] != getattr(data, n).shape[0]
                       for n in ACTION_ARRAYS + ROW_ARRAYS if n not in ("Lu", "Luu")):  # sized by w at a stage
            self.stage_datas = _stage_datas(data, differentials, self.terminal or self.single, nw)
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
        self.coef = np.array(self._tableau(), dtype=float)
        self.cw = control_coefficients(iam.control, self.coef[0])
        self._bind(data)
        self.refreshes += 1
        return True

    single = False
    """Whether the node has one stage over its own action arrays (an Euler node)."""

    def _differentials(self, data) -> list:
        """The stages' differential datas (the terminal node: the first)."""
        return data.differential[:1] if self.terminal else data.differential

    def _tableau(self) -> tuple:
        """The stages' times and weights ``(c, b)`` (the terminal node: one stage at time 0)."""
        return ((0.0,), (0.0,)) if self.terminal else (self.model.rk_c, self.model.rk_b)

    def _bind(self, data) -> None:
        """The time step, the stamp (spent) and the scratch of the kernels, made again for other sizes."""
        self.dts[0] = float(self.model.dt)
        self.stamp[0] = 0.0
        data.compiled_stamp = self.stages[0].stamp if self.terminal or self.single else self.stamp  # Python spends it
        ni, state, nu, nw = len(self.stages), self.model.state, self.model.nu, self.model.differential.nu
        nx, ndx, nv = state.nx, state.ndx, state.nv
        if self._sizes != (ni, nx, ndx, nu, nw):
            self._sizes = (ni, nx, ndx, nu, nw)
            self.w = np.zeros((ni, nw))
            self._mapped = (np.zeros((nv, nu)), np.zeros(nu), np.zeros((ndx, nu)), np.zeros((nu, nu)))
            y, dy, k = np.zeros((ni, nx)), np.zeros((ni, ndx)), np.zeros((ni, ndx))
            self._work = (y, dy, k, np.zeros((nv, nv)), np.zeros((nv, nv)), np.zeros((ndx, ndx)), np.zeros((ndx, nu)))
            self._jac = tuple(np.zeros((ni, ndx, n)) for n in (ndx, nu, ndx, nu))
            self._sums = (np.zeros((ndx, ndx)), np.zeros((ndx, nu)))
            self._step = np.zeros(ndx)
        y, dy, k = self._work[:3]
        self._values = (y, dy, k, data.dx, data.xnext)
        none = np.zeros((0, nu))  # the identity: the first stage's rows are the node's own arrays
        self._rows = (data.Gu, data.Hu) if nu != nw else (none, none)
        self._out = (data.dx, data.xnext, data.Fx, data.Fu, *self._sums, data.Lx, data.Lu, data.Lxx, data.Lxu,
                     data.Luu)

    def _reread(self, memo: dict, method: str) -> bool:
        """``refresh_values``/``refresh_live`` of every stage, then the time step and the tableau, in place."""
        iam = self.model
        if not all(getattr(s, method)(memo) for s in self.stages):
            return False
        c, b = self._tableau()
        if len(c) != len(self.stages):
            return False
        if not np.array_equal(self.coef[0], c):  # the stage times moved: their control coefficients too
            self.coef[0] = c
            self.cw[:] = control_coefficients(iam.control, self.coef[0])
        self.coef[1] = b
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
                                  self.cw, self.w, x, u, *self._values)
        self._store(cost, x, u, False)

    def calcDiff(self, x: np.ndarray, u: np.ndarray | None, synced: bool) -> None:
        if self.terminal:
            cost = euler_kernel.node_calc_diff(self.tbls[0], self.ints, self.par, x, self.no_control)
        else:
            cost = kernel.rk_calc_diff(self.tbls, self.ints, self.par, self.coef[0], self.coef[1], self.dts,
                                       self.stamp, self.cw, self.w, x, u, self._work, self._jac, self._mapped,
                                       self._rows, self._out)
        self._store(cost, x, u, True)

    def _store(self, cost: float, x: np.ndarray, u: np.ndarray | None, derivatives: bool) -> None:
        """The node's cost into its data, or, where a stage's acceleration is not finite (NaN), its Python path."""
        if math.isfinite(cost):
            self._data().cost = cost
        else:
            self.python_path(x, u, derivatives)

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
                       self.stamp, self.cw, self.w, (*self._values, self._step))


class ControlledEulerNode(RKNode):
    """The compiled ``calc``/``calcDiff`` of an Euler node with a polynomial control parametrization: its Euler table
    (sized by ``w``) over the node's own action arrays at ``w = w(0, u)``, the control derivatives mapped to ``u``
    (:mod:`.control_map_kernel`)."""

    single = True

    def _differentials(self, data) -> list:
        return [data.differential]

    def _tableau(self) -> tuple:
        return (0.0,), (1.0,)

    def calc(self, x: np.ndarray, u: np.ndarray | None) -> None:
        if self.terminal:
            super().calc(x, u)
            return
        self._store(kernel.controlled_euler_calc(self.tbls[0], self.ints, self.par, self.cw, self.w, x, u), x, u,
                    False)

    def calcDiff(self, x: np.ndarray, u: np.ndarray | None, synced: bool) -> None:
        if self.terminal:
            super().calcDiff(x, u, synced)
            return
        data = self._data()
        cost = kernel.controlled_euler_calc_diff(self.tbls[0], self.ints, self.par, self.cw, self.w, x, u, data.Fu,
                                                 data.Lu, data.Lxu, data.Luu, self._rows)
        self._store(cost, x, u, True)

    @property
    def rollout_step(self):
        """One node of the DDP family's rollout (:func:`.rk_node_kernel.controlled_euler_rollout_step`)."""
        return partial(kernel.controlled_euler_rollout_step, self.tbls[0], self.ints, self.par, self.cw, self.w)
