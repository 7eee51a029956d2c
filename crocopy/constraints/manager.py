"""Named stacks of constraints (Crocoddyl's ``ConstraintModelManager``), ordered by name."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..array_views import share_arrays
from ..data_collector import DataCollectorAbstract
from ..named_items import NamedItems
from ..state import StateAbstract
from .base import ConstraintModelAbstract


@dataclass
class ConstraintItem:
    """A named constraint in a :class:`ConstraintModelManager`."""

    name: str
    constraint: ConstraintModelAbstract
    active: bool = True

    def __repr__(self) -> str:
        return f"{{{self.constraint!r}}}"


class ConstraintModelManager(NamedItems):
    """Named constraints stacked into one ``g``/``h`` (Crocoddyl's ``ConstraintModelManager``).

    Parameters
    ----------
    state : StateAbstract
        State manifold.
    nu : int, optional
        Control dimension (default ``state.nv``).
    """

    _kind = "constraint"

    def __init__(self, state: StateAbstract, nu: int | None = None) -> None:
        if not isinstance(state, StateAbstract):
            raise ValueError(f"state must be a StateAbstract, got {type(state).__name__}")
        self.state = state
        self.nu = state.nv if nu is None else int(nu)
        if self.nu < 0:
            raise ValueError(f"nu must be non-negative, got {self.nu}")
        self._items: dict[str, ConstraintItem] = {}
        self._recount()

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
        """Add ``constraint`` under ``name`` (items are kept ordered by name)."""
        if not isinstance(constraint, ConstraintModelAbstract):
            raise ValueError(f"constraint must be a ConstraintModelAbstract, got {type(constraint).__name__}")
        self._check_new_name(name)
        if constraint.nu != self.nu:
            raise ValueError(f"constraint {name!r} has nu = {constraint.nu}, expected nu = {self.nu}")
        if constraint.state.nx != self.state.nx or constraint.state.ndx != self.state.ndx:
            raise ValueError(f"constraint {name!r} was built on a state of another dimension")
        self._insert(name, ConstraintItem(name, constraint, bool(active)))

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

    def calc(self, data: "ConstraintDataManager", x: np.ndarray, u: np.ndarray | None = None) -> None:
        """Stack the active constraints (only ``T_constraint`` ones when ``u`` is None) into ``g``/``h``."""
        self._check(data)
        ig = ih = 0
        for name, item in self._items.items():
            c = item.constraint
            if not item.active or (u is None and not c.T_constraint):
                continue
            cd = data.constraints[name]
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
        self._check(data)
        ig = ih = 0
        for name, item in self._items.items():
            c = item.constraint
            if not item.active or (u is None and not c.T_constraint):
                continue
            cd = data.constraints[name]
            c.calcDiff(cd, x, u)
            if c.ng:
                data.Gx[ig:ig + c.ng] = cd.Gx
                data.Gu[ig:ig + c.ng] = cd.Gu
                ig += c.ng
            if c.nh:
                data.Hx[ih:ih + c.nh] = cd.Hx
                data.Hu[ih:ih + c.nh] = cd.Hu
                ih += c.nh
        for J in (data.Gx, data.Gu):
            J[ig:] = 0.0
        for J in (data.Hx, data.Hu):
            J[ih:] = 0.0

    def __repr__(self) -> str:
        return "ConstraintModelManager(" + ", ".join(f"{n}: {c!r}" for n, c in self._items.items()) + ")"


class ConstraintDataManager:
    """Data of a :class:`ConstraintModelManager`: per-item data in ``constraints`` plus stacked arrays."""

    def __init__(self, model: ConstraintModelManager, data: DataCollectorAbstract | None) -> None:
        ndx, nu = model.state.ndx, model.nu
        self.shared = data
        self.constraints = {name: item.constraint.createData(data) for name, item in model.constraints.items()}
        self.g = np.zeros(model.ng)
        self.Gx = np.zeros((model.ng, ndx))
        self.Gu = np.zeros((model.ng, nu))
        self.h = np.zeros(model.nh)
        self.Hx = np.zeros((model.nh, ndx))
        self.Hu = np.zeros((model.nh, nu))

    def shareMemory(self, data) -> None:
        """Write straight into ``data``'s ``g, Gx, Gu, h, Hx, Hu`` (an action or differential data).

        Raises
        ------
        ValueError
            If ``data``'s arrays do not have this manager data's shapes.
        """
        share_arrays(self, data, ("g", "Gx", "Gu", "h", "Hx", "Hu"))
