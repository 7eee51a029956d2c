"""Where a solve met NaN/inf: the error, the per-node search run only after a cheap check failed.

A solver tests finiteness once per phase on aggregated quantities (the cost, the expected
improvement ``d``, ``Vx₀``/``Vxx₀`` after the backward pass, the cost and last state of a trial
rollout, and the whole trajectory of a trial about to be accepted).  Only when such a test fails
does it call the searches below, which walk the nodes and name the first non-finite quantity where
it arose:

* :func:`locate_cost`: the first node whose cost is not finite;
* :func:`locate_in_derivatives`: the nodes' ``cost``, ``Fx``, ``Fu``, ``Lx``, ``Lu``, ``Lxx``,
  ``Lxu``, ``Luu`` (t = 0..T; a model produced it);
* :func:`locate_in_backward_pass`: the solver's ``Vxx``/``Vx`` at T, then ``Qxx, Qxu, Quu, Qx, Qu,
  K, k, Vxx, Vx`` from t = T-1 down to 0 (the recursion's order, so the first hit is the origin);
* :func:`locate_in_rollout`: ``xs_try``, ``us_try`` and the node costs, t = 0..T.

The solver stops with ``solve() -> False``, keeps its best finite iterate and states the result in
``solver.reason``, e.g. ``"non-finite Quu at node 9 in the backward pass"``.  When the first non-finite
quantity of a node's evaluation is found, the node's model (or the differential model it integrates) may name
the cause through a method ``nonfinite_cause() -> str | None`` (crocopy extension, called only then), which is
appended: ``"non-finite Fx at node 0 in the derivatives: the mass matrix is singular (...)"``.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np

_RUNNING_DERIVATIVES = ("Fx", "Fu", "Lx", "Lu", "Lxx", "Lxu", "Luu")
_TERMINAL_DERIVATIVES = ("Lx", "Lxx")
_BACKWARD_TERMS = ("Qxx", "Qxu", "Quu", "Qx", "Qu", "K", "k", "Vxx", "Vx")


class NonFiniteError(RuntimeError):
    """A solve met NaN/inf; ``node`` and ``quantity`` say where (``node`` is None if not found).

    Parameters
    ----------
    quantity : str
        Name of the first non-finite quantity (``"cost"``, ``"Fu"``, ``"Quu"``, ...).
    node : int or None
        Its node, 0..T.
    where : str
        Phase of the iteration (``"derivatives"``, ``"backward pass"``, ``"rollout"``, ...).
    """

    def __init__(self, quantity: str, node: int | None, where: str,
                 cause: str | Callable[[], str | None] | None = None) -> None:
        at = "" if node is None else f" at node {node}"
        self._text = f"non-finite {quantity}{at} in the {where}"
        self._cause = cause
        super().__init__(self._text if callable(cause) else self._text + (f": {cause}" if cause else ""))
        self.quantity = quantity
        self.node = node
        self.where = where

    def __str__(self) -> str:
        """The message; a ``cause`` given as a function is asked for then (a model's diagnosis, which may cost a
        factorisation: the error of a rejected trial is often never read)."""
        cause = self._cause
        if callable(cause):
            cause = self._cause = cause()
            self.args = (self._text + (f": {cause}" if cause else ""),)
        return str(self.args[0])


def _finite(value) -> bool:
    return bool(np.isfinite(value).all())


def _cause(problem, t: int | None) -> Callable[[], str | None] | None:
    """What the model of node ``t`` (or the differential model it integrates) says caused its NaN/inf, if anything:
    a function asked when the message is read."""
    if t is None:
        return None
    model = problem.runningModels[t] if t < problem.T else problem.terminalModel
    explain = getattr(getattr(model, "differential", model), "nonfinite_cause", None)
    return explain if callable(explain) else None


def locate_in_derivatives(problem) -> NonFiniteError | None:
    """The first non-finite cost or derivative of the problem's nodes (None if all are finite)."""
    datas = [*problem.runningDatas, problem.terminalData]
    for t, d in enumerate(datas):
        names = _RUNNING_DERIVATIVES if t < problem.T else _TERMINAL_DERIVATIVES
        if not np.isfinite(d.cost):
            return NonFiniteError("cost", t, "problem evaluation", _cause(problem, t))
        for name in names:
            if not _finite(getattr(d, name)):
                return NonFiniteError(name, t, "derivatives", _cause(problem, t))
    return None


def locate_cost(problem) -> NonFiniteError:
    """The first node whose cost is not finite (after ``problem.calc``/``calcDiff`` gave a non-finite total)."""
    datas = [*problem.runningDatas, problem.terminalData]
    node = next((t for t, d in enumerate(datas) if not np.isfinite(d.cost)), None)
    return NonFiniteError("cost", node, "problem evaluation", _cause(problem, node))


def locate_in_backward_pass(solver) -> NonFiniteError | None:
    """The first non-finite term of the backward pass in the order it was computed (None if all are finite)."""
    T = solver.problem.T
    for name in ("Vxx", "Vx"):
        if not _finite(getattr(solver, name)[T]):
            return NonFiniteError(name, T, "backward pass")
    for t in range(T - 1, -1, -1):
        for name in _BACKWARD_TERMS:
            if not _finite(getattr(solver, name)[t]):
                return NonFiniteError(name, t, "backward pass")
    return None


def locate_in_rollout(problem, xs: Sequence[np.ndarray], us: Sequence[np.ndarray]) -> NonFiniteError | None:
    """The first non-finite state, control or node cost of a rollout (None if all are finite): at the first node
    where one is, the state first, then the control, then the cost."""
    datas = [*problem.runningDatas, problem.terminalData]
    n = min(len(xs), len(datas))
    costs = np.fromiter((d.cost for d in datas[:n]), dtype=float, count=n)
    bad_costs = np.flatnonzero(~np.isfinite(costs))
    firsts = (_first_nonfinite(xs[:n]), _first_nonfinite(us[:n]), int(bad_costs[0]) if bad_costs.size else None)
    found = [(t, rank) for rank, t in enumerate(firsts) if t is not None]
    if not found:
        return None
    t, rank = min(found)
    if rank == 0:
        return NonFiniteError("state", t, "rollout", _cause(problem, t - 1) if t else None)
    if rank == 1:
        return NonFiniteError("control", t, "rollout")
    return NonFiniteError("cost", t, "rollout", _cause(problem, t))


def _first_nonfinite(arrays: Sequence[np.ndarray]) -> int | None:
    """The index of the first array of ``arrays`` with a NaN/inf entry, None if all are finite."""
    if not len(arrays):
        return None
    try:
        flat = np.concatenate(arrays)
    except ValueError:  # not all of one dimension
        flat = np.concatenate([np.ravel(a) for a in arrays])
    finite = np.isfinite(flat)
    if finite.all():
        return None
    ends = np.cumsum([a.size for a in arrays])
    return int(np.searchsorted(ends, np.argmin(finite), side="right"))


def trajectory_finite(xs: Sequence[np.ndarray], us: Sequence[np.ndarray]) -> bool:
    """True when every state and control is finite (the sum of all entries; entry-wise if it overflowed)."""
    parts = [*xs, *us]
    if not parts:
        return True
    flat = np.concatenate(parts)
    return math.isfinite(flat.sum()) or bool(np.isfinite(flat).all())
