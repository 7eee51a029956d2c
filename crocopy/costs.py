"""Cost models: an activation of a residual, and weighted sums of named costs.

For ``l = a(r(x, u))``: ``Lx = Rxᵀ Ar``, ``Lu = Ruᵀ Ar``, and the Gauss-Newton Hessians
``Lxx = Rxᵀ Arr Rx``, ``Lxu = Rxᵀ Arr Ru``, ``Luu = Ruᵀ Arr Ru``.  A cost sum adds
``weight * l`` over its active items.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .activations import ActivationModelAbstract, ActivationModelQuad
from .data_collector import DataCollectorAbstract
from .named_items import NamedItems
from .residual_base import ResidualModelAbstract
from .state import StateAbstract


class CostModelAbstract:
    """Abstract cost ``l(x, u)`` of an activation and a residual (Crocoddyl's ``CostModelAbstract``)."""

    def __init__(
        self, state: StateAbstract, activation: ActivationModelAbstract, residual: ResidualModelAbstract
    ) -> None:
        if activation.nr != residual.nr:
            raise ValueError(
                f"activation.nr = {activation.nr} does not match residual.nr = {residual.nr}"
            )
        if residual.state.nx != state.nx or residual.state.ndx != state.ndx:
            raise ValueError("residual was built on a different state than the cost")
        self.state = state
        self.activation = activation
        self.residual = residual
        self.nu = residual.nu

    def createData(self, data: DataCollectorAbstract | None = None) -> "CostDataAbstract":
        return CostDataAbstract(self, data)

    def calc(self, data: "CostDataAbstract", x: np.ndarray, u: np.ndarray | None = None) -> None:
        raise NotImplementedError

    def calcDiff(self, data: "CostDataAbstract", x: np.ndarray, u: np.ndarray | None = None) -> None:
        raise NotImplementedError

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.residual!r}, {self.activation!r})"


class CostDataAbstract:
    """Cost value and derivatives, with the residual and activation data."""

    def __init__(self, model: CostModelAbstract, data: DataCollectorAbstract | None) -> None:
        ndx, nu = model.state.ndx, model.nu
        self.shared = data
        self.cost = 0.0
        self.Lx = np.zeros(ndx)
        self.Lu = np.zeros(nu)
        self.Lxx = np.zeros((ndx, ndx))
        self.Lxu = np.zeros((ndx, nu))
        self.Luu = np.zeros((nu, nu))
        self.residual = model.residual.createData(data)
        self.activation = model.activation.createData()

    @property
    def r(self) -> np.ndarray:
        """Residual vector of this cost, shape ``(nr,)``."""
        return self.residual.r


class CostModelResidual(CostModelAbstract):
    """``CostModelResidual(state, activation, residual)`` or ``(state, residual)`` (quadratic activation)."""

    def __init__(self, state: StateAbstract, activation, residual: ResidualModelAbstract | None = None) -> None:
        if residual is None:
            residual, activation = activation, ActivationModelQuad(activation.nr)
        super().__init__(state, activation, residual)
        self._terminal_zero = not (residual.q_dependent or residual.v_dependent)

    def calc(self, data: CostDataAbstract, x: np.ndarray, u: np.ndarray | None = None) -> None:
        if u is None and self._terminal_zero:
            data.residual.r[:] = 0.0
            data.cost = 0.0
            return
        self.residual.calc(data.residual, x, u)
        self.activation.calc(data.activation, data.residual.r)
        data.cost = data.activation.a_value

    def calcDiff(self, data: CostDataAbstract, x: np.ndarray, u: np.ndarray | None = None) -> None:
        if u is None and self._terminal_zero:
            return
        rdata, adata = data.residual, data.activation
        self.residual.calcDiff(rdata, x, u)
        self.activation.calcDiff(adata, rdata.r)
        Rx = rdata.Rx
        if self.activation.diagonal:
            ArrRx = adata.Arr_diag[:, None] * Rx
        else:
            ArrRx = adata.Arr @ Rx
        np.dot(Rx.T, adata.Ar, out=data.Lx)
        np.dot(Rx.T, ArrRx, out=data.Lxx)
        if u is not None and self.residual.u_dependent:
            Ru = rdata.Ru
            ArrRu = adata.Arr_diag[:, None] * Ru if self.activation.diagonal else adata.Arr @ Ru
            np.dot(Ru.T, adata.Ar, out=data.Lu)
            np.dot(Rx.T, ArrRu, out=data.Lxu)
            np.dot(Ru.T, ArrRu, out=data.Luu)


@dataclass
class CostItem:
    """A named, weighted cost in a :class:`CostModelSum`."""

    name: str
    cost: CostModelAbstract
    weight: float
    active: bool = True

    def __repr__(self) -> str:
        return f"{{w={self.weight}, {self.cost!r}}}"


class CostModelSum(NamedItems):
    """Weighted sum of named costs (Crocoddyl's ``CostModelSum``).

    Parameters
    ----------
    state : StateAbstract
        State manifold.
    nu : int, optional
        Control dimension (default ``state.nv``).
    """

    _kind = "cost"
    _sorted = False

    def __init__(self, state: StateAbstract, nu: int | None = None) -> None:
        self.state = state
        self.nu = state.nv if nu is None else int(nu)
        self._items: dict[str, CostItem] = {}
        self.nr = 0
        self.nr_total = 0

    @property
    def costs(self) -> dict[str, CostItem]:
        """All items (active or not), in insertion order."""
        return self._items

    def _recount(self) -> None:
        self.nr = sum(c.cost.activation.nr for c in self._items.values() if c.active)
        self.nr_total = sum(c.cost.activation.nr for c in self._items.values())

    def addCost(self, name: str, cost: CostModelAbstract, weight: float, active: bool = True) -> None:
        """Add ``weight * cost`` under ``name``."""
        self._check_new_name(name)
        if cost.nu != self.nu:
            raise ValueError(f"cost {name!r} has nu = {cost.nu}, expected nu = {self.nu}")
        if cost.state.nx != self.state.nx or cost.state.ndx != self.state.ndx:
            raise ValueError(f"cost {name!r} was built on a state of another dimension")
        if not np.isfinite(weight):
            raise ValueError(f"weight of cost {name!r} must be finite, got {weight}")
        self._insert(name, CostItem(name, cost, float(weight), bool(active)))

    def removeCost(self, name: str) -> None:
        """Remove the cost ``name``."""
        self._remove(name)

    def changeCostStatus(self, name: str, active: bool) -> None:
        """Activate or deactivate the cost ``name``."""
        self._set_active(name, active)

    def createData(self, data: DataCollectorAbstract | None = None) -> "CostDataSum":
        return CostDataSum(self, data)

    def calc(self, data: "CostDataSum", x: np.ndarray, u: np.ndarray | None = None) -> None:
        total = 0.0
        for name, item in self.costs.items():
            if item.active:
                cd = data.costs[name]
                item.cost.calc(cd, x, u)
                total += item.weight * cd.cost
        data.cost = total

    def calcDiff(self, data: "CostDataSum", x: np.ndarray, u: np.ndarray | None = None) -> None:
        data.Lx[:] = 0.0
        data.Lxx[:] = 0.0
        with_u = u is not None
        if with_u:
            data.Lu[:] = 0.0
            data.Lxu[:] = 0.0
            data.Luu[:] = 0.0
        for name, item in self.costs.items():
            if not item.active:
                continue
            cd = data.costs[name]
            cost = item.cost
            cost.calcDiff(cd, x, u)
            w = item.weight
            data.Lx += w * cd.Lx
            data.Lxx += w * cd.Lxx
            if with_u and cost.residual.u_dependent:
                data.Lu += w * cd.Lu
                data.Lxu += w * cd.Lxu
                data.Luu += w * cd.Luu

    def __repr__(self) -> str:
        return "CostModelSum(" + ", ".join(f"{n}: {c!r}" for n, c in self.costs.items()) + ")"


class CostDataSum:
    """Data of a :class:`CostModelSum`: one data per item in ``costs`` plus the sums."""

    def __init__(self, model: CostModelSum, data: DataCollectorAbstract | None) -> None:
        ndx, nu = model.state.ndx, model.nu
        self.shared = data
        self.costs = {name: item.cost.createData(data) for name, item in model.costs.items()}
        self.cost = 0.0
        self.Lx = np.zeros(ndx)
        self.Lu = np.zeros(nu)
        self.Lxx = np.zeros((ndx, ndx))
        self.Lxu = np.zeros((ndx, nu))
        self.Luu = np.zeros((nu, nu))
