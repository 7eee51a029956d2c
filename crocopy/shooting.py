"""Shooting problem: running models ``0..T-1``, a terminal model, and one data per node.

``calc(xs, us)`` evaluates every node (``xs``: T+1 states of shape ``(nx,)``, ``us``: T controls)
and returns the total cost ``Σ l_t(x_t, u_t) + l_T(x_T)``; ``calcDiff`` fills the derivatives of
every node (it assumes ``calc`` was called at the same point) and returns the cost.

A user's call of ``calc``, ``calcDiff``, ``rollout`` and ``quasiStatic`` checks the trajectories
(lengths T+1 and T, shapes ``(nx,)``/``(nu,)`` per node, finite; lists and ``(n, 1)`` columns are
converted) and then runs unchecked; a solver calls them on the trusted path
(:mod:`crocopy.guards`), without the checks.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from .action_base import ActionDataAbstract, ActionModelAbstract
from .guards import Guard, Guarded
from .validation import ArgumentTypeError, as_count, as_vector, finite_stack, plain_vectors
from .versioning import STRUCTURE, any_stale, holds_stale_data


class StdVec_ActionModel(list):
    """Crocoddyl's vector of models or datas (``runningModels``, ``runningDatas``): a list with ``tolist()``."""

    def tolist(self) -> list:
        """A plain list of the same objects."""
        return list(self)


class NodeList(StdVec_ActionModel):
    """A problem's ``runningModels``/``runningDatas``: read-only (change a node with ``updateModel``,
    ``updateNode`` or ``circularAppend``, which keep the models, the datas and the solvers in step)."""

    def _read_only(self, *args, **kwargs):
        raise TypeError("problem.runningModels and problem.runningDatas are read-only: change a node with "
                        "problem.updateModel(t, model), problem.updateNode(t, model, data) or "
                        "problem.circularAppend(model); copy the list first (.tolist()) to edit a list of your own")

    __setitem__ = __delitem__ = __iadd__ = __imul__ = _read_only
    append = extend = insert = pop = remove = clear = sort = reverse = _read_only

    def __reduce__(self) -> tuple:
        return NodeList, (list(self),)


def _sequence(value: object, name: str) -> list:
    if value is None or isinstance(value, (str, bytes)) or not hasattr(value, "__len__"):
        raise ArgumentTypeError(f"{name} must be a list of vectors, got {type(value).__name__}")
    return list(value)


def _node_model(problem: "ShootingProblem", model: object, name: str) -> ActionModelAbstract:
    if not isinstance(model, ActionModelAbstract):
        raise ArgumentTypeError(f"{name} must be an ActionModelAbstract, got {type(model).__name__}")
    return model


def _node_index(problem: "ShootingProblem", i: object, name: str) -> int:
    return as_count(i, name)


def _trajectories(problem: "ShootingProblem", args: list, kwargs: dict) -> None:
    given = {**dict(zip(("xs", "us"), args)), **kwargs}
    if "xs" in given and "us" in given:
        xs, us = problem.check_trajectories(_sequence(given["xs"], "xs"), _sequence(given["us"], "us"))
        args[:] = [xs, us][: len(args)]
        kwargs.update({k: v for k, v in (("xs", xs), ("us", us)) if k in kwargs})


def _controls(problem: "ShootingProblem", us: object, name: str) -> list:
    us = _sequence(us, name)
    if len(us) != problem.T:
        raise ValueError(f"{name} has {len(us)} items, expected T = {problem.T}")
    return [as_vector(u, m.nu, f"{name}[{t}]") for t, (u, m) in enumerate(zip(us, problem.runningModels))]


def _states(problem: "ShootingProblem", xs: object, name: str) -> list:
    xs = _sequence(xs, name)
    if len(xs) not in (problem.T, problem.T + 1):
        raise ValueError(f"{name} has {len(xs)} items, expected T = {problem.T} or T + 1")
    models = [*problem.runningModels, problem.terminalModel]
    return [as_vector(x, m.state.nx, f"{name}[{t}]") for t, (x, m) in enumerate(zip(xs, models))]


class ShootingProblem(Guarded):
    """Crocoddyl's ``ShootingProblem(x0, runningModels, terminalModel)``.

    Parameters
    ----------
    x0 : numpy.ndarray
        Initial state, shape ``(nx,)`` of the first node; finite.
    runningModels : sequence of ActionModelAbstract
        Models of nodes ``0..T-1``.
    terminalModel : ActionModelAbstract
        Model of node ``T`` (called without control).
    """

    _guards = {
        "calc": Guard((("xs", None), ("us", None)), check=_trajectories),
        "calcDiff": Guard((("xs", None), ("us", None)), check=_trajectories),
        "rollout": Guard((("us", _controls),)),
        "quasiStatic": Guard((("xs", _states),)),
        "updateModel": Guard((("i", _node_index), ("model", _node_model))),
        "updateNode": Guard((("i", _node_index), ("model", _node_model))),
        "circularAppend": Guard((("model", _node_model),)),
    }

    def __init__(
        self,
        x0: np.ndarray,
        runningModels: Sequence[ActionModelAbstract],
        terminalModel: ActionModelAbstract,
        runningDatas: Sequence[ActionDataAbstract] | None = None,
        terminalData: ActionDataAbstract | None = None,
    ) -> None:
        runningModels = list(runningModels)
        for i, m in enumerate([*runningModels, terminalModel]):
            if not isinstance(m, ActionModelAbstract):
                raise ValueError(f"node {i} must be an ActionModelAbstract, got {type(m).__name__}")
        self._check_chain(runningModels, terminalModel)
        self._runningModels = NodeList(runningModels)
        self._terminalModel = terminalModel
        self.x0 = x0
        self._structure_seen = STRUCTURE[0] if runningDatas is None and terminalData is None else -1
        if runningDatas is None:
            runningDatas = [m.createData() for m in runningModels]
        elif len(runningDatas) != len(runningModels):
            raise ValueError(f"runningDatas has {len(runningDatas)} items, expected {len(runningModels)}")
        self._runningDatas = NodeList(runningDatas)
        self._nodes_version = 0
        self._terminalData = terminalModel.createData() if terminalData is None else terminalData
        self.cost = 0.0
        self._nthreads = 1

    @property
    def nthreads(self) -> int:
        """Threads that evaluate the nodes (default 1, as Crocoddyl's).  With ``k > 1``, the compiled nodes'
        values and derivatives in a solve run on ``k`` threads, bit-identical to one thread's
        (:mod:`crocopy.models.rbd.node_threads`); the other nodes and the rollouts stay on the calling thread."""
        return self._nthreads

    @nthreads.setter
    def nthreads(self, value: int) -> None:
        self._nthreads = as_count(value, "nthreads", minimum=1)

    @staticmethod
    def _check_chain(runningModels: list, terminalModel: ActionModelAbstract) -> None:
        models = [*runningModels, terminalModel]
        for i in range(len(models) - 1):
            a, b = models[i].state, models[i + 1].state
            if a.nx != b.nx or a.ndx != b.ndx:
                raise ValueError(
                    f"node {i} has state (nx={a.nx}, ndx={a.ndx}) but node {i + 1} has (nx={b.nx}, ndx={b.ndx})"
                )

    @property
    def T(self) -> int:
        """Number of running nodes."""
        return len(self._runningModels)

    @property
    def x0(self) -> np.ndarray:
        """Initial state, shape ``(nx,)``."""
        return self._x0

    @x0.setter
    def x0(self, value: np.ndarray) -> None:
        first = self._runningModels[0] if self._runningModels else self._terminalModel
        self._x0 = as_vector(value, first.state.nx, "x0").copy()

    @property
    def runningModels(self) -> StdVec_ActionModel:
        """Models of nodes ``0..T-1`` (a list with Crocoddyl's ``tolist()``)."""
        return self._runningModels

    @property
    def terminalModel(self) -> ActionModelAbstract:
        return self._terminalModel

    @property
    def runningDatas(self) -> StdVec_ActionModel:
        """Datas of nodes ``0..T-1`` (a list with Crocoddyl's ``tolist()``)."""
        return self._runningDatas

    @property
    def terminalData(self) -> ActionDataAbstract:
        return self._terminalData

    @property
    def nx(self) -> int:
        return self._terminalModel.state.nx

    @property
    def ndx(self) -> int:
        return self._terminalModel.state.ndx

    @property
    def nu_max(self) -> int:
        return max((m.nu for m in self._runningModels), default=0)

    def check_trajectories(self, xs: Sequence[np.ndarray], us: Sequence[np.ndarray], xs_name="xs", us_name="us"):
        """Validate and convert ``xs`` (T+1 states) and ``us`` (T controls) or raise ``ValueError``."""
        T = self.T
        if len(xs) != T + 1:
            raise ValueError(f"{xs_name} has {len(xs)} items, expected T + 1 = {T + 1}")
        if len(us) != T:
            raise ValueError(f"{us_name} has {len(us)} items, expected T = {T}")
        x_shapes, u_shapes = self._trajectory_shapes()
        if plain_vectors(xs, x_shapes) and plain_vectors(us, u_shapes) and finite_stack([*xs, *us]) is not None:
            return list(xs), list(us)
        models = [*self._runningModels, self._terminalModel]
        xs = [as_vector(x, m.state.nx, f"{xs_name}[{t}]") for t, (x, m) in enumerate(zip(xs, models))]
        us = [as_vector(u, m.nu, f"{us_name}[{t}]") for t, (u, m) in enumerate(zip(us, self._runningModels))]
        return xs, us

    def _trajectory_shapes(self) -> tuple[list, list]:
        """The shapes ``(nx,)`` of the nodes' states and ``(nu,)`` of their controls (read again after a node
        changed)."""
        kept = self.__dict__.get("_shapes_seen")
        if kept is None or kept[0] != self._nodes_version:
            models = [*self._runningModels, self._terminalModel]
            kept = self.__dict__["_shapes_seen"] = (self._nodes_version, [(m.state.nx,) for m in models],
                                                    [(m.nu,) for m in self._runningModels])
        return kept[1], kept[2]

    def refresh_datas(self) -> list[int]:
        """Replace the node datas made before a registry in their model changed its item set (a cost, constraint,
        contact or impulse added or removed, a contact, impulse or constraint switched on or off) by new ones, as
        a freshly built problem would have (crocopy extension; ``calc``, ``calcDiff``, ``rollout`` and every
        solve call it first).  One integer comparison when no item set changed since the last call.

        Returns
        -------
        list of int
            The nodes whose data was replaced (``T`` for the terminal node).
        """
        if self._structure_seen == STRUCTURE[0]:
            return []
        if not any_stale():
            self._structure_seen = STRUCTURE[0]
            return []
        replaced = []
        for t, (m, d) in enumerate(zip(self._runningModels, self._runningDatas)):
            if holds_stale_data(d):
                list.__setitem__(self._runningDatas, t, m.createData())
                replaced.append(t)
        if holds_stale_data(self._terminalData):
            self._terminalData = self._terminalModel.createData()
            replaced.append(self.T)
        self._structure_seen = STRUCTURE[0]
        if replaced:
            self._nodes_version += 1
        return replaced

    def calc(self, xs: Sequence[np.ndarray], us: Sequence[np.ndarray]) -> float:
        """Evaluate every node at ``(xs, us)`` and return the total cost."""
        self.refresh_datas()
        cost = 0.0
        for m, d, x, u in zip(self._runningModels, self._runningDatas, xs, us):
            m._raw_calc(d, x, u)
            cost += d.cost
        self._terminalModel._raw_calc(self._terminalData, xs[-1])
        cost += self._terminalData.cost
        self.cost = cost
        return cost

    def calcDiff(self, xs: Sequence[np.ndarray], us: Sequence[np.ndarray]) -> float:
        """Compute every node's derivatives at ``(xs, us)`` (after :meth:`calc`) and return the cost."""
        self.refresh_datas()
        cost = 0.0
        for m, d, x, u in zip(self._runningModels, self._runningDatas, xs, us):
            m._raw_calcDiff(d, x, u)
            cost += d.cost
        self._terminalModel._raw_calcDiff(self._terminalData, xs[-1])
        cost += self._terminalData.cost
        self.cost = cost
        return cost

    def rollout(self, us: Sequence[np.ndarray]) -> list[np.ndarray]:
        """Integrate the dynamics from ``x0`` with controls ``us``; returns T+1 states."""
        self.refresh_datas()
        xs = [self._x0.copy()]
        for t, (m, d) in enumerate(zip(self._runningModels, self._runningDatas)):
            m._raw_calc(d, xs[-1], us[t])
            xs.append(d.xnext.copy())
        return xs

    def quasiStatic(self, xs: Sequence[np.ndarray]) -> list[np.ndarray]:
        """Quasi-static controls of the first T states of ``xs``."""
        return [m.quasiStatic(d, x) for m, d, x in zip(self._runningModels, self._runningDatas, xs)]

    def circularAppend(self, model: ActionModelAbstract, data: ActionDataAbstract | None = None) -> None:
        """Drop node 0 and append ``model`` (with ``data``) as node T-1 (receding horizon)."""
        self._check_chain([*self._runningModels[1:], model], self._terminalModel)
        self._runningModels = NodeList([*self._runningModels[1:], model])
        self._runningDatas = NodeList([*self._runningDatas[1:], model.createData() if data is None else data])
        self._nodes_version += 1

    def updateNode(self, i: int, model: ActionModelAbstract, data: ActionDataAbstract) -> None:
        """Replace node ``i`` (``i == T`` is the terminal node) by ``model`` and ``data``."""
        if not 0 <= i <= self.T:
            raise ValueError(f"node index i = {i} out of range [0, {self.T}]")
        if i == self.T:
            self._check_chain(self._runningModels, model)
            self._terminalModel, self._terminalData = model, data
        else:
            models = list(self._runningModels)
            models[i] = model
            self._check_chain(models, self._terminalModel)
            self._runningModels = NodeList(models)
            list.__setitem__(self._runningDatas, i, data)
        self._nodes_version += 1

    def updateModel(self, i: int, model: ActionModelAbstract) -> None:
        """Replace node ``i`` by ``model`` with fresh data."""
        self.updateNode(i, model, model.createData())

    def __getstate__(self) -> dict:
        """Pickle the models, not the datas (workspaces, often large): :meth:`__setstate__` recreates them."""
        state = self.__dict__.copy()
        del state["_runningDatas"], state["_terminalData"]
        return state

    def __setstate__(self, state: dict) -> None:
        self.__dict__.update(state)
        self._runningModels = NodeList(self._runningModels)
        self._runningDatas = NodeList(m.createData() for m in self._runningModels)
        self._terminalData = self._terminalModel.createData()
        self._structure_seen = STRUCTURE[0]

    def __repr__(self) -> str:
        return f"ShootingProblem(T={self.T}, nx={self.nx}, nu_max={self.nu_max})"
