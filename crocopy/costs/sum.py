"""Weighted sums of named costs (Crocoddyl's ``CostModelSum``), ordered by name."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..array_views import share_arrays
from ..data_collector import DataCollectorAbstract
from ..guards import Guarded, point_control_guards
from ..named_items import ModelItems
from ..validation import as_bool, as_number, warn_after
from ..versioning import ParametersSeen, ParametersVersion, made_from, touch
from .base import CostModelAbstract, CostModelResidual
from .stack import CostStack, stackable_cost


@dataclass
class CostItem:
    """A named, weighted cost in a :class:`CostModelSum` (changing ``weight``/``active`` is seen by its data)."""

    name: str
    cost: CostModelAbstract
    weight: float
    active: bool = True

    def __setattr__(self, name: str, value: object) -> None:
        if name == "weight":
            value = as_number(value, f"weight of cost {self.__dict__.get('name')!r}")
        elif name == "active":
            value = as_bool(value, "active")
        object.__setattr__(self, name, value)
        touch(self, name != "weight")  # a weight is a value (compiled nodes re-read it in place)

    def __repr__(self) -> str:
        return f"{{w={self.weight}, {self.cost!r}}}"


class CostModelSum(ModelItems, Guarded):
    """Weighted sum of named costs (Crocoddyl's ``CostModelSum``).

    Parameters
    ----------
    state : StateAbstract
        State manifold.
    nu : int, optional
        Control dimension (default ``state.nv``).
    """

    _kind = "cost"
    _model_type = CostModelAbstract
    _guards = point_control_guards(warn_after("cost", diff=("Lx", "Lu", "Lxx", "Lxu", "Luu")))

    @property
    def costs(self) -> dict[str, CostItem]:
        """All items (active or not), ordered by name as in Crocoddyl."""
        return self._items

    def _recount(self) -> None:
        self.nr = sum(c.cost.activation.nr for c in self._items.values() if c.active)
        self.nr_total = sum(c.cost.activation.nr for c in self._items.values())

    def addCost(self, name: str, cost: CostModelAbstract, weight: float, active: bool = True) -> None:
        """Add ``weight * cost`` under ``name``.

        Raises
        ------
        ValueError
            If ``cost`` is not a ``CostModelAbstract``, ``name`` is taken, ``cost`` has another ``nu`` or
            another state dimension, or ``weight`` is not finite.
        """
        self._check_model(name, cost)
        self._insert(name, CostItem(name, cost, weight, active))

    def removeCost(self, name: str) -> None:
        """Remove the cost ``name``."""
        self._remove(name)

    def changeCostStatus(self, name: str, active: bool) -> None:
        """Activate or deactivate the cost ``name`` (a data made before keeps its shape: no rebuild)."""
        self._get(name).active = as_bool(active, "active")
        self._changed(structural=False)

    def getCostStatus(self, name: str) -> bool:
        """True if the cost ``name`` is active (``KeyError`` if unknown)."""
        return self._get(name).active

    def createData(self, data: DataCollectorAbstract | None = None) -> "CostDataSum":
        return CostDataSum(self, data)

    def calc(self, data: "CostDataSum", x: np.ndarray, u: np.ndarray | None = None) -> None:
        """Weighted sum of the active costs into ``data.cost``.

        Raises
        ------
        ValueError
            If ``data`` was created before a cost was added or removed (as Crocoddyl).
        """
        seen = data.items_seen
        if seen.value != ParametersVersion.value and seen.stale(self._items_owner):
            self._check_data(data)
        total = data.stack.calc(x, u)
        for name in data.generic:
            item = self._items[name]
            if item.active:
                cd = data.costs[name]
                item.cost._raw_calc(cd, x, u)
                total += item.weight * cd.cost
        data.cost = total

    def _check_data(self, data: "CostDataSum") -> None:
        """After an item was added, removed or switched: ``data`` must hold one data per cost."""
        if data.costs.keys() != self._items.keys():
            raise ValueError(
                f"data holds cost datas {sorted(data.costs)} but the model has costs {sorted(self._items)}:"
                " a cost was added or removed after createData(); create the data again"
            )
        data.items_seen.filled()

    def _items_owner(self) -> tuple:
        """What a data's ``items_seen`` follows: this sum (touched when an item is added, removed or switched)."""
        return (self,)

    def calcDiff(self, data: "CostDataSum", x: np.ndarray, u: np.ndarray | None = None) -> None:
        with_u = u is not None
        data.stack.calcDiff(data, x, u)
        for name in data.generic:
            item = self._items[name]
            if not item.active:
                continue
            cd = data.costs[name]
            item.cost._raw_calcDiff(cd, x, u)
            w = item.weight
            data.Lx += w * cd.Lx
            data.Lxx += w * cd.Lxx
            if with_u and item.cost.residual.u_dependent:
                data.Lu += w * cd.Lu
                data.Lxu += w * cd.Lxu
                data.Luu += w * cd.Luu


class CostDataSum:
    """Data of a :class:`CostModelSum`: one data per item in ``costs`` plus the sums.

    Residual costs with diagonal activations share a :class:`~crocopy.costs.stack.CostStack`
    (``stack``); the other items (``generic``) add their own derivatives.
    """

    def __init__(self, model: CostModelSum, data: DataCollectorAbstract | None) -> None:
        ndx, nu = model.state.ndx, model.nu
        self.shared = data
        made_from(model, self)
        self.items_seen = ParametersSeen()
        self.items_seen.filled()
        self.costs = {name: item.cost.createData(data) for name, item in model.costs.items()}
        self.cost = 0.0
        self.Lx = np.zeros(ndx)
        self.Lu = np.zeros(nu)
        self.Lxx = np.zeros((ndx, ndx))
        self.Lxu = np.zeros((ndx, nu))
        self.Luu = np.zeros((nu, nu))
        stackable = [
            (name, item, self.costs[name])
            for name, item in model.costs.items()
            if isinstance(item.cost, CostModelResidual) and stackable_cost(item.cost)
        ]
        self.stack = CostStack(stackable, ndx, nu)
        stacked = {name for name, _, _ in stackable}
        self.generic = [name for name in model.costs if name not in stacked]

    def shareMemory(self, data) -> None:
        """Write the derivatives straight into ``data``'s ``Lx, Lu, Lxx, Lxu, Luu`` (an action or
        differential action data), as Crocoddyl's ``CostDataSum.shareMemory``.

        Raises
        ------
        ValueError
            If ``data``'s arrays do not have this cost data's shapes.
        """
        share_arrays(self, data, ("Lx", "Lu", "Lxx", "Lxu", "Luu"))
