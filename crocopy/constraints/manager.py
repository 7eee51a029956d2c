"""Named stacks of constraints (Crocoddyl's ``ConstraintModelManager``), ordered by name."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..action_common import constraint_arrays
from ..array_views import share_arrays
from ..data_collector import DataCollectorAbstract
from ..guards import Guarded, point_control_guards
from ..named_items import ModelItems
from ..validation import as_bool
from ..versioning import made_from
from .base import ConstraintModelAbstract


@dataclass
class ConstraintItem:
    """A named constraint in a :class:`ConstraintModelManager`."""

    name: str
    constraint: ConstraintModelAbstract
    active: bool = True

    def __repr__(self) -> str:
        return f"{{{self.constraint!r}}}"


class ConstraintModelManager(ModelItems, Guarded):
    """Named constraints stacked into one ``g``/``h`` (Crocoddyl's ``ConstraintModelManager``).

    Parameters
    ----------
    state : StateAbstract
        State manifold.
    nu : int, optional
        Control dimension (default ``state.nv``).
    """

    _kind = "constraint"
    _model_type = ConstraintModelAbstract
    _guards = point_control_guards()

    @property
    def constraints(self) -> dict[str, ConstraintItem]:
        """All items (active or not), ordered by name."""
        return self._items

    def _recount(self) -> None:
        active = [c.constraint for c in self._items.values() if c.active]
        self.ng = sum(c.ng for c in active)
        self.nh = sum(c.nh for c in active)
        self.ng_T = sum(c.ng for c in active if c.T_constraint)
        self.nh_T = sum(c.nh for c in active if c.T_constraint)
        self._running = active
        self._terminal = [c for c in active if c.T_constraint]

    @property
    def g_lb(self) -> np.ndarray:
        """Stacked lower bounds of the active inequality rows, shape ``(ng,)``."""
        parts = [c.lb for c in self._running if c.ng]
        return np.concatenate(parts) if parts else np.zeros(0)

    @property
    def g_ub(self) -> np.ndarray:
        """Stacked upper bounds of the active inequality rows, shape ``(ng,)``."""
        parts = [c.ub for c in self._running if c.ng]
        return np.concatenate(parts) if parts else np.zeros(0)

    def addConstraint(self, name: str, constraint: ConstraintModelAbstract, active: bool = True) -> None:
        """Add ``constraint`` under ``name`` (items are kept ordered by name).

        Raises
        ------
        ValueError
            If ``constraint`` is not a ``ConstraintModelAbstract``, ``name`` is taken, or ``constraint``
            has another ``nu`` or another state dimension.
        """
        self._check_model(name, constraint)
        self._insert(name, ConstraintItem(name, constraint, as_bool(active, "active")))

    def removeConstraint(self, name: str) -> None:
        """Remove the constraint ``name``."""
        self._remove(name)

    def changeConstraintStatus(self, name: str, active: bool) -> None:
        """Activate or deactivate the constraint ``name``."""
        self._set_active(name, active)

    def getConstraintStatus(self, name: str) -> bool:
        """True if the constraint ``name`` is active."""
        return self._get(name).active

    def createData(self, data: DataCollectorAbstract | None = None) -> "ConstraintDataManager":
        """Allocate one data per item plus the stacked arrays, sized for the current active set."""
        return ConstraintDataManager(self, data)

    def _check(self, data: "ConstraintDataManager") -> None:
        if data.g.shape[0] != self.ng or data.h.shape[0] != self.nh:
            raise ValueError(
                f"constraint data holds ng={data.g.shape[0]}, nh={data.h.shape[0]} but the manager now has "
                f"ng={self.ng}, nh={self.nh}: create the data again after changing the active set"
            )

    def _applying(self, data: "ConstraintDataManager", u: np.ndarray | None) -> list:
        """``(constraint, data)`` of the active constraints, only ``T_constraint`` ones when ``u`` is None."""
        self._check(data)
        return [
            (item.constraint, data.constraints[name])
            for name, item in self._items.items()
            if item.active and (u is not None or item.constraint.T_constraint)
        ]

    def calc(self, data: "ConstraintDataManager", x: np.ndarray, u: np.ndarray | None = None) -> None:
        """Stack the active constraints (only ``T_constraint`` ones when ``u`` is None) into ``g``/``h``."""
        if not self._items:  # nothing to stack (the data's g and h are empty once it is checked)
            self._check(data)
            return
        ig = ih = 0
        for c, cd in self._applying(data, u):
            c.calc(cd, x, u)
            if c.ng:
                data.g[ig:ig + c.ng] = cd.g
                ig += c.ng
            if c.nh:
                data.h[ih:ih + c.nh] = cd.h
                ih += c.nh
        data.g[ig:] = 0.0
        data.h[ih:] = 0.0

    def calcDiff(self, data: "ConstraintDataManager", x: np.ndarray, u: np.ndarray | None = None) -> None:
        """Stack the Jacobians of the active constraints into ``Gx, Gu, Hx, Hu`` (same rows as :meth:`calc`)."""
        ig = ih = 0
        for c, cd in self._applying(data, u):
            c.calcDiff(cd, x, u)
            if c.ng:
                data.Gx[ig:ig + c.ng] = cd.Gx
                data.Gu[ig:ig + c.ng] = cd.Gu
                ig += c.ng
            if c.nh:
                data.Hx[ih:ih + c.nh] = cd.Hx
                data.Hu[ih:ih + c.nh] = cd.Hu
                ih += c.nh
        data.Gx[ig:] = 0.0
        data.Gu[ig:] = 0.0
        data.Hx[ih:] = 0.0
        data.Hu[ih:] = 0.0


class ConstraintDataManager:
    """Data of a :class:`ConstraintModelManager`: per-item data in ``constraints`` plus stacked arrays."""

    def __init__(self, model: ConstraintModelManager, data: DataCollectorAbstract | None) -> None:
        ndx, nu = model.state.ndx, model.nu
        self.shared = data
        made_from(model, self)
        self.constraints = {name: item.constraint.createData(data) for name, item in model.constraints.items()}
        self.g, self.Gx, self.Gu, self.h, self.Hx, self.Hu = constraint_arrays(model.ng, model.nh, ndx, nu)

    def shareMemory(self, data) -> None:
        """Write straight into ``data``'s ``g, Gx, Gu, h, Hx, Hu`` (an action or differential data).

        Raises
        ------
        ValueError
            If ``data``'s arrays do not have this manager data's shapes.
        """
        share_arrays(self, data, ("g", "Gx", "Gu", "h", "Hx", "Hu"))
