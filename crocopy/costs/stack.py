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
rows at once; other diagonal activations are called item by item, and so is a subclass that
overrides ``calc``/``calcDiff`` without declaring its own ``barrier_form`` (logged once at DEBUG
level on the ``"crocopy"`` logger).  Of those, the ones with an ``item_form`` (smooth 1-norm, quadratic-flat
exponential and logarithmic) are listed per item in ``act_kinds``/``act_params`` for compiled nodes, which evaluate
them in their kernel (:mod:`.stack_kernel`).

Rows are ordered with the control-independent residuals first: ``Ju`` holds only the rows of the
control-dependent residuals (the tail of ``Jx``), so their zero ``Ru`` never enters a product.
``calcDiff`` does not call a control residual's own ``calcDiff`` (``Ru = I`` is set once).
Weights, bounds and activity are cached and re-read when an item, its activation or the
activation's bounds were touched since (:mod:`crocopy.versioning`), or the node kind changed.
"""

from __future__ import annotations

import numpy as np

from .. import kernels
from ..kernels import log_fallback, overridden
from ..residuals.control import ResidualModelControl
from ..versioning import ParametersSeen, ParametersVersion
from . import stack_kernel


def _declared_form(activation, name: str, step: str | None = None) -> tuple | None:
    """``activation.<name>()`` (its ``barrier_form`` or ``item_form``), or None when it has none or its class overrides
    the ``calc``/``calcDiff`` of the class that declares the form (the override runs item by item; logged once at
    DEBUG level as ``step``, when given)."""
    form = getattr(activation, name)()
    if form is None:
        return None
    owner = next(c for c in type(activation).__mro__ if name in vars(c))
    steps = overridden(activation, owner, ("calc", "calcDiff"))
    if steps:
        if step is not None:
            log_fallback(type(activation), steps, step)
        return None
    return form


def _item_form(activation) -> tuple | None:
    """``(kind code, parameter)`` of the activation's ``item_form`` (:mod:`.stack_kernel`), or None
    (:func:`_declared_form`)."""
    form = _declared_form(activation, "item_form")
    return None if form is None else (stack_kernel.ITEM_KINDS[form[0]], float(form[1]))


def stackable_cost(cost) -> bool:
    """Whether a residual cost joins the stack: its activation is diagonal, or one of the dense item forms (Hessian
    ``d I + c r rᵀ``, :data:`.stack_kernel.DENSE`), and its residual has rows."""
    if not cost.residual.nr:
        return False
    if cost.activation.diagonal:
        return True
    form = _item_form(cost.activation)
    return form is not None and form[0] in stack_kernel.DENSE


def _constant_jacobians(residual) -> bool:
    """True for a :class:`~crocopy.residuals.ResidualModelControl` whose ``calcDiff`` is the class's own
    (it does nothing: ``Ru = I`` is set by ``createData``), which the stack then does not call."""
    return isinstance(residual, ResidualModelControl) and not overridden(residual, ResidualModelControl, ("calcDiff",))


class CostStack:
    """Stacked residuals, Jacobians, activation derivatives and weights of a cost sum's items.

    Parameters
    ----------
    items : list of (name, CostItem, CostDataResidual)
        The stackable items (residual costs with diagonal activations, ``nr > 0``) and their data.
    ndx, nu : int
        Tangent and control dimensions.

    Notes
    -----
    The activations and sums run :mod:`~crocopy.costs.stack_kernel`'s compiled kernels while
    :func:`crocopy.kernels_enabled`, else their numpy twins; ``calcDiff`` makes one kernel call
    (``derivatives_and_sums``) unless some activation runs item by item.
    """

    def __init__(self, items: list, ndx: int, nu: int) -> None:
        self.items = sorted(items, key=lambda it: it[1].cost.residual.u_dependent)
        nr = sum(it[1].cost.residual.nr for it in self.items)
        n = len(self.items)
        self.r, self.Jx = np.zeros(nr), np.zeros((nr, ndx))
        self.Ar, self.Arr = np.zeros(nr), np.zeros(nr)
        self.lb, self.ub = np.zeros(nr), np.zeros(nr)
        self.act_weights = np.ones(nr)
        self.weights = np.zeros(nr)
        self.item_costs, self.item_weights = np.zeros(n), np.zeros(n)
        self.act_kinds, self.act_params = np.zeros(n, dtype=np.int64), np.zeros(n)
        """Per item, the activation kind compiled nodes evaluate it with and its parameter (:mod:`.stack_kernel`:
        ``BARRIER`` for the fused family, whose rows ``lb``, ``ub``, ``act_weights`` hold its form)."""
        self.slices: list[slice] = []
        start = 0
        for _, item, _ in self.items:
            self.slices.append(slice(start, start + item.cost.residual.nr))
            start += item.cost.residual.nr
        self.starts = np.array([rows.start for rows in self.slices], dtype=np.intp)
        self.u_start = next((s.start for (_, it, _), s in zip(self.items, self.slices)
                             if it.cost.residual.u_dependent), nr)
        self.Ju = np.zeros((nr - self.u_start, nu))
        self.cols = np.zeros(ndx + nu, dtype=np.int64)
        """Scratch of the sums: a Jacobian row's nonzero columns (:func:`.stack_kernel.accumulate`)."""
        self.grad = np.zeros(ndx + nu)
        """Scratch of the compiled nodes' rank-one sums: a dense item's ``[Jx Ju]ᵀ r``
        (:func:`.stack_kernel.rank_one_sums`)."""
        for k, ((_, item, cdata), rows) in enumerate(zip(self.items, self.slices)):
            self._share(item, cdata, rows, k)
        self._seen = ParametersSeen()
        self._terminal: bool | None = None
        self.active: list = []
        self.varying: list = []
        self.unfused: list = []
        self.uncompiled: list = []
        """The active activations of :attr:`unfused` that compiled nodes cannot evaluate either (no item form)."""
        self.dense: list = []
        """The active items of a dense activation: ``(rows, activation data, residual data, with controls)``."""

    def __getstate__(self) -> dict:
        """Copy or pickle without the per-evaluation lists (they hold views; :meth:`refresh` rebuilds them)."""
        return {**self.__dict__, "active": [], "varying": [], "unfused": [], "uncompiled": [], "dense": []}

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

    def refresh(self, terminal: bool) -> bool:
        """Re-read weights, activity and activation parameters (for a terminal node if ``terminal``), in place; returns
        whether its layout changed: the node kind, or which items are evaluated and how (active, varying, unfused).
        Otherwise only values changed (weights, activation weights and bounds), in the same arrays."""
        before = self._layout()
        self.active, self.varying, self.unfused, self.uncompiled, self.dense = [], [], [], [], []
        for k, ((_, item, cdata), rows) in enumerate(zip(self.items, self.slices)):
            cost = item.cost
            cdata.zero = terminal and cost._terminal_zero
            cdata.with_u = not terminal and cost.residual.u_dependent
            on = item.active and not cdata.zero
            weight = item.weight if on else 0.0
            self.weights[rows] = weight
            self.item_weights[k] = weight
            form = _declared_form(cost.activation, "barrier_form", "the cost stack's fused activation step")
            self.act_kinds[k], self.act_params[k] = stack_kernel.BARRIER, 0.0
            if form is None:
                form = (0.0, 0.0, 1.0)
                if on:
                    self.unfused.append((cost.activation, cdata.activation, cdata.residual.r))
                    item = _item_form(cost.activation)
                    if item is None:
                        self.uncompiled.append(cost.activation)
                    else:
                        self.act_kinds[k], self.act_params[k] = item
                        if item[0] in stack_kernel.DENSE:
                            self.dense.append((rows, cdata.activation, cdata.residual, cdata.with_u))
            self.lb[rows], self.ub[rows], self.act_weights[rows] = form
            if on:
                self.active.append((cost.residual, cdata.residual))
                if not _constant_jacobians(cost.residual):
                    self.varying.append((cost.residual, cdata.residual))
            else:
                self.r[rows] = 0.0
                self.Jx[rows] = 0.0
        self._seen.filled()
        self._terminal = terminal
        return self._layout() != before

    def _layout(self) -> tuple:
        """The node kind and the items evaluated, each list by identity."""
        return (self._terminal, [id(r) for r, _ in self.active], [id(r) for r, _ in self.varying],
                [id(a) for a, _, _ in self.unfused])

    def refresh_if_stale(self, terminal: bool) -> bool:
        """:meth:`refresh` when the node kind changed or a parameter was touched since; True if its layout changed
        (a compiled node then reads its items again; after values only, it reads the same arrays)."""
        seen = self._seen
        if self._terminal != terminal or (
            seen.value != ParametersVersion.value and seen.stale(self._parameter_owners)
        ):
            return self.refresh(terminal)
        return False

    def _parameter_owners(self):
        """Every object whose parameters :meth:`refresh` reads: items, activations, activation bounds."""
        for _, item, _ in self.items:
            yield item
            yield item.cost.activation
            yield getattr(item.cost.activation, "bounds", None)

    def calc(self, x: np.ndarray, u: np.ndarray | None) -> float:
        """Residuals and activation values of every active item; returns ``Σ weight · cost``."""
        seen = self._seen
        if self._terminal != (u is None) or (
            seen.value != ParametersVersion.value and seen.stale(self._parameter_owners)
        ):
            self.refresh(u is None)
        for residual, rdata in self.active:
            residual._raw_calc(rdata, x, u)
        kernel = kernels.active
        values = stack_kernel.activation_values if kernel else stack_kernel.activation_values_numpy
        total = values(self.r, self.lb, self.ub, self.act_weights, self.starts, self.item_costs, self.item_weights)
        if not self.unfused:
            return total
        for activation, adata, r in self.unfused:
            activation._raw_calc(adata, r)
        return float(self.item_weights @ self.item_costs)

    def calc_residual_datas(self, x: np.ndarray, u: np.ndarray | None) -> None:
        """The ``calc`` of every active item's residual whose class keeps more than its rows (not those that declare
        ``rows_only`` in their own class body): after a compiled evaluation at ``(x, u)`` wrote the stack's arrays,
        what :meth:`calc` leaves besides them (a frame residual's placement in the Pinocchio data and its relative
        placement; :meth:`crocopy.models.rbd.euler_node.EulerNode.fill`)."""
        self.refresh_if_stale(u is None)
        for residual, rdata in self.active:
            if not type(residual).__dict__.get("rows_only", False):
                residual._raw_calc(rdata, x, u)

    def calcDiff(self, data, x: np.ndarray, u: np.ndarray | None) -> None:
        """Residual Jacobians, activation derivatives and the weighted sums into ``data``."""
        seen = self._seen
        if self._terminal != (u is None) or (
            seen.value != ParametersVersion.value and seen.stale(self._parameter_owners)
        ):
            self.refresh(u is None)
        for residual, rdata in self.varying:
            residual._raw_calcDiff(rdata, x, u)
        kernel = kernels.active
        if not self.unfused:
            fused = stack_kernel.derivatives_and_sums if kernel else stack_kernel.derivatives_and_sums_numpy
            fused(
                self.r, self.lb, self.ub, self.act_weights, self.weights, self.Ar, self.Arr, self.Jx, self.Ju,
                self.u_start, u is not None, data.Lx, data.Lu, data.Lxx, data.Lxu, data.Luu, self.cols,
            )
            return
        derivatives = stack_kernel.activation_derivatives if kernel else stack_kernel.activation_derivatives_numpy
        derivatives(self.r, self.lb, self.ub, self.act_weights, self.Ar, self.Arr)
        for activation, adata, r in self.unfused:
            activation._raw_calcDiff(adata, r)
        for rows, _, _, _ in self.dense:
            self.Arr[rows] = 0.0  # their gradient only: the dense Hessian follows
        accumulate = stack_kernel.accumulate if kernel else stack_kernel.accumulate_numpy
        accumulate(
            self.weights, self.Ar, self.Arr, self.Jx, self.Ju, self.u_start, u is not None,
            data.Lx, data.Lu, data.Lxx, data.Lxu, data.Luu, self.cols,
        )
        for rows, adata, rdata, with_u in self.dense:
            w = self.weights[rows.start]
            ArrRx = adata.Arr @ rdata.Rx
            data.Lxx += w * (rdata.Rx.T @ ArrRx)
            if with_u:
                ArrRu = adata.Arr @ rdata.Ru
                data.Lxu += w * (rdata.Rx.T @ ArrRu)
                data.Luu += w * (rdata.Ru.T @ ArrRu)
