"""Stacked residual costs of a cost sum: one set of array operations for all items.

A :class:`~crocopy.costs.CostModelSum` of residual costs with diagonal activations has the
Gauss-Newton derivatives

    Lx = Jxᵀ (w ∘ Ar),   Lxx = Jxᵀ diag(w ∘ Arr) Jx,   Lxu = Jxᵀ diag(w ∘ Arr) Ju,   ...

where ``r (nr,)``, ``Jx (nr, ndx)`` and ``Ju (nr, nu)`` stack the residuals and Jacobians of every
item and ``w`` repeats each item's weight over its rows.  :class:`CostStack` owns those stacked
arrays and makes each item's residual ``r``/``Rx``/``Ru`` and activation ``Ar``/``Arr_diag``/``a_value``
views into them, so residuals write straight into the stack.

Activations of the quadratic-barrier family (quadratic, weighted quadratic, quadratic barrier and
weighted quadratic barrier: ``a = ½ Σ aᵢ (rᵢ - clip(rᵢ, lbᵢ, ubᵢ))²``, ``Arr = aᵢ [rᵢ ≤ lbᵢ or
rᵢ ≥ ubᵢ]``, the quadratic ones with ``lb = ub = 0``; see ``barrier_form``) are evaluated for all
rows at once; other diagonal activations are called item by item.

Rows are ordered with the control-independent residuals first: ``Ju`` holds only the rows of the
control-dependent residuals (the tail of ``Jx``), so their zero ``Ru`` never enters a product.
Weights, bounds and activity are cached and re-read when an item, its activation or the
activation's bounds were touched since (:mod:`crocopy.versioning`), or the node kind changed.
"""

from __future__ import annotations

import numpy as np

from ..versioning import ParametersSeen
from . import stack_kernel as cost_stack_kernel


class CostStack:
    """Stacked residuals, Jacobians, activation derivatives and weights of a cost sum's items.

    Parameters
    ----------
    items : list of (name, CostItem, CostDataResidual)
        The stackable items (residual costs with diagonal activations, ``nr > 0``) and their data.
    ndx, nu : int
        Tangent and control dimensions.

    Attributes
    ----------
    use_kernel : bool
        Evaluate the activations and sums with :mod:`~crocopy.costs.stack_kernel` (default when numba is
        available) instead of the numpy steps.
    """

    use_kernel = cost_stack_kernel.available

    def __init__(self, items: list, ndx: int, nu: int) -> None:
        self.items = sorted(items, key=lambda it: it[1].cost.residual.u_dependent)
        nr = sum(it[1].cost.residual.nr for it in self.items)
        n = len(self.items)
        self.r, self.Jx = np.zeros(nr), np.zeros((nr, ndx))
        self.Ar, self.Arr, self.excess = np.zeros(nr), np.zeros(nr), np.zeros(nr)
        self.lb, self.ub = np.zeros(nr), np.zeros(nr)
        self.act_weights = np.ones(nr)
        self.below, self.above = np.zeros(nr, dtype=bool), np.zeros(nr, dtype=bool)
        self.weights, self.wAr, self.wArr = np.zeros(nr), np.zeros(nr), np.zeros(nr)
        self.HJx, self.row_costs = np.zeros((nr, ndx)), np.zeros(nr)
        self.item_costs, self.item_weights = np.zeros(n), np.zeros(n)
        self.slices: list[slice] = []
        start = 0
        for _, item, _ in self.items:
            self.slices.append(slice(start, start + item.cost.residual.nr))
            start += item.cost.residual.nr
        self.starts = np.array([rows.start for rows in self.slices], dtype=np.intp)
        self.u_start = next((s.start for (_, it, _), s in zip(self.items, self.slices)
                             if it.cost.residual.u_dependent), nr)
        self.Ju = np.zeros((nr - self.u_start, nu))
        self.HJu = np.zeros_like(self.Ju)
        self.Jc, self.Juc = np.zeros_like(self.Jx), np.zeros_like(self.Ju)
        for k, ((_, item, cdata), rows) in enumerate(zip(self.items, self.slices)):
            self._share(item, cdata, rows, k)
        self._seen = ParametersSeen()
        self._terminal: bool | None = None
        self.active: list = []
        self.unfused: list = []

    def __getstate__(self) -> dict:
        """Copy or pickle without the per-evaluation lists (they hold views; :meth:`refresh` rebuilds them)."""
        return {**self.__dict__, "active": [], "unfused": []}

    def _share(self, item, cdata, rows: slice, k: int) -> None:
        """Make the item's residual and activation arrays views into the stack."""
        rdata, adata = cdata.residual, cdata.activation
        for name, stacked in (("r", self.r), ("Rx", self.Jx)):
            stacked[rows] = getattr(rdata, name)
            setattr(rdata, name, stacked[rows].view(type(getattr(rdata, name))))
        if item.cost.residual.u_dependent:
            urows = slice(rows.start - self.u_start, rows.stop - self.u_start)
            self.Ju[urows] = rdata.Ru
            rdata.Ru = self.Ju[urows].view(type(rdata.Ru))
        for name, stacked in (("Ar", self.Ar), ("Arr_diag", self.Arr)):
            stacked[rows] = getattr(adata, name)
            setattr(adata, name, stacked[rows])
        self.item_costs[k] = adata.a_value
        adata._a_store = self.item_costs[k : k + 1]

    def refresh(self, terminal: bool) -> None:
        """Re-read weights, activity and activation parameters (for a terminal node if ``terminal``)."""
        self.active, self.unfused = [], []
        for k, ((_, item, cdata), rows) in enumerate(zip(self.items, self.slices)):
            cost = item.cost
            cdata.zero = terminal and cost._terminal_zero
            cdata.with_u = not terminal and cost.residual.u_dependent
            on = item.active and not cdata.zero
            weight = item.weight if on else 0.0
            self.weights[rows] = weight
            self.item_weights[k] = weight
            form = cost.activation.barrier_form()
            if form is None:
                form = (0.0, 0.0, 1.0)
                if on:
                    self.unfused.append((cost.activation, cdata.activation, cdata.residual.r))
            self.lb[rows], self.ub[rows], self.act_weights[rows] = form
            if on:
                self.active.append((cost.residual, cdata.residual))
            else:
                self.r[rows] = 0.0
                self.Jx[rows] = 0.0
        self._seen.filled()
        self._terminal = terminal

    def _parameter_owners(self):
        """Every object whose parameters :meth:`refresh` reads: items, activations, activation bounds."""
        for _, item, _ in self.items:
            yield item
            yield item.cost.activation
            yield getattr(item.cost.activation, "bounds", None)

    def _excess(self) -> np.ndarray:
        e = self.excess
        np.minimum(self.r, self.ub, out=e)
        np.maximum(e, self.lb, out=e)
        np.subtract(self.r, e, out=e)
        return e

    def calc(self, x: np.ndarray, u: np.ndarray | None) -> float:
        """Residuals and activation values of every active item; returns ``Σ weight · cost``."""
        if self._terminal != (u is None) or self._seen.stale(self._parameter_owners):
            self.refresh(u is None)
        for residual, rdata in self.active:
            residual.calc(rdata, x, u)
        if self.use_kernel:
            total = cost_stack_kernel.activation_values(
                self.r, self.lb, self.ub, self.act_weights, self.starts, self.item_costs, self.item_weights
            )
            if not self.unfused:
                return total
        else:
            self._values()
        for activation, adata, r in self.unfused:
            activation.calc(adata, r)
        return float(self.item_weights @ self.item_costs)

    def _values(self) -> None:
        e = self._excess()
        with np.errstate(over="ignore", invalid="ignore"):
            np.multiply(e, e, out=self.row_costs)
            self.row_costs *= self.act_weights
        np.add.reduceat(self.row_costs, self.starts, out=self.item_costs)
        self.item_costs *= 0.5

    def calcDiff(self, data, x: np.ndarray, u: np.ndarray | None) -> None:
        """Residual Jacobians, activation derivatives and the weighted sums into ``data``."""
        if self._terminal != (u is None) or self._seen.stale(self._parameter_owners):
            self.refresh(u is None)
        for residual, rdata in self.active:
            residual.calcDiff(rdata, x, u)
        if self.use_kernel:
            cost_stack_kernel.activation_derivatives(self.r, self.lb, self.ub, self.act_weights, self.Ar, self.Arr)
        else:
            self._derivatives()
        for activation, adata, r in self.unfused:
            activation.calcDiff(adata, r)
        if self.use_kernel:
            cost_stack_kernel.accumulate(
                self.weights, self.Ar, self.Arr, self.Jx, self.Ju, self.u_start, u is not None,
                self.Jc, self.HJx, self.Juc, self.HJu, data.Lx, data.Lu, data.Lxx, data.Lxu, data.Luu,
            )
        else:
            self._accumulate(data, u is not None)

    def _derivatives(self) -> None:
        e = self._excess()
        np.multiply(self.act_weights, e, out=self.Ar)
        np.less_equal(self.r, self.lb, out=self.below)
        np.greater_equal(self.r, self.ub, out=self.above)
        np.logical_or(self.below, self.above, out=self.below)
        np.multiply(self.below, self.act_weights, out=self.Arr)

    def _accumulate(self, data, with_u: bool) -> None:
        np.multiply(self.weights, self.Ar, out=self.wAr)
        np.multiply(self.weights, self.Arr, out=self.wArr)
        np.dot(self.Jx.T, self.wAr, out=data.Lx)
        np.multiply(self.wArr[:, None], self.Jx, out=self.HJx)
        np.dot(self.Jx.T, self.HJx, out=data.Lxx)
        if with_u:
            u0 = self.u_start
            np.dot(self.Ju.T, self.wAr[u0:], out=data.Lu)
            np.multiply(self.wArr[u0:, None], self.Ju, out=self.HJu)
            np.dot(self.Jx[u0:].T, self.HJu, out=data.Lxu)
            np.dot(self.Ju.T, self.HJu, out=data.Luu)
