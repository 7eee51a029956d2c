"""Named sets of impulses, stacked into one impact constraint ``Jc v⁺ = -e Jc v⁻``.

Active impulses are stacked in name order into the first ``nc`` rows of ``Jc (nc_total, nv)`` and
``dv0_dq (nc_total, nv)``; ``fext`` holds, per joint, the sum of the impulses attached to it
in the joint frame.  The bookkeeping shared with contact sets lives in
:mod:`~crocopy.models.force_base`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from crocopy.state import StateAbstract
from crocopy.validation import as_bool

from .force_base import ForceDataMultiple, ForceModelMultiple
from .impulse_base import ImpulseDataAbstract, ImpulseModelAbstract


@dataclass
class ImpulseItem:
    """Crocoddyl's ``ImpulseItem(name, impulse, active=True)``."""

    name: str
    impulse: ImpulseModelAbstract
    active: bool = True

    def __repr__(self) -> str:
        return f"{{{self.name}, {self.impulse!r}, active={self.active}}}"


class ImpulseModelMultiple(ForceModelMultiple):
    """Crocoddyl's ``ImpulseModelMultiple(state)``.

    Attributes
    ----------
    impulses : dict[str, ImpulseItem]
        All impulses, ordered by name.
    nc, nc_total : int
        Dimension of the active impulses, of all impulses.
    """

    _kind = "impulse"
    _model_type = ImpulseModelAbstract

    def __init__(self, state: StateAbstract) -> None:
        super().__init__(state, 0)

    @property
    def impulses(self) -> dict[str, ImpulseItem]:
        return self._items

    def addImpulse(self, name: str, impulse: ImpulseModelAbstract, active: bool = True) -> None:
        """Add ``impulse`` under ``name`` (``ValueError`` if it is no ``ImpulseModelAbstract``, the name is
        taken or the robot differs)."""
        self._add(name, impulse, ImpulseItem(name, impulse, as_bool(active, "active")))

    def removeImpulse(self, name: str) -> None:
        """Remove the impulse ``name`` (``KeyError`` if unknown)."""
        self._remove(name)

    def changeImpulseStatus(self, name: str, active: bool) -> None:
        """Activate or deactivate the impulse ``name`` (``KeyError`` if unknown)."""
        self._set_active(name, active)

    def getImpulseStatus(self, name: str) -> bool:
        """True if the impulse ``name`` is active (``KeyError`` if unknown)."""
        return self._get(name).active

    def createData(self, data: pin.Data) -> "ImpulseDataMultiple":
        return ImpulseDataMultiple(self, data)

    def calc(self, data: "ImpulseDataMultiple", x: np.ndarray) -> None:
        """Evaluate the active impulses and stack ``Jc``."""
        self._stack(data.items, x, False, ((data.Jc, "Jc"),))

    def calcDiff(self, data: "ImpulseDataMultiple", x: np.ndarray) -> None:
        """Evaluate and stack ``dv0_dq`` of the active impulses."""
        self._stack(data.items, x, True, ((data.dv0_dq, "dv0_dq"),))

    def updateVelocity(self, data: "ImpulseDataMultiple", vnext: np.ndarray) -> None:
        """Store the velocity after impact ``vnext (nv,)``."""
        data.vnext[:] = vnext

    def updateVelocityDiff(self, data: "ImpulseDataMultiple", dvnext_dx: np.ndarray) -> None:
        """Store the Jacobian of the velocity after impact ``dvnext_dx (nv, ndx)``."""
        data.dvnext_dx[:] = dvnext_dx

    def updateForce(self, data: "ImpulseDataMultiple", force: np.ndarray) -> None:
        """Split ``force (nc,)`` into the active impulses; their joint forces (``fext``) are brought up to
        date when ``data.fext`` is read (``updateJointForces``)."""
        self._store_forces(data, force)

    def updateForceDiff(self, data: "ImpulseDataMultiple", df_dx: np.ndarray) -> None:
        """Split the impulse Jacobian ``df_dx (nc, ndx)`` into the active impulses."""
        if np.shape(df_dx) != (self.nc, self.state.ndx):
            raise ValueError(f"df_dx has shape {np.shape(df_dx)}, expected ({self.nc}, {self.state.ndx})")
        self._split(data.items, "updateForceDiff", (df_dx,), "setZeroForceDiff")


class ImpulseDataMultiple(ForceDataMultiple):
    """Data of :class:`ImpulseModelMultiple`: ``impulses`` (name → data), ``Jc (nc_total, nv)``,
    ``dv0_dq (nc_total, nv)``, ``vnext (nv,)``, ``dvnext_dx (nv, ndx)`` and ``fext`` (per joint; it and
    the impulses' ``f_local``/``fext`` are brought up to date with the impulses when ``fext`` is read)."""

    def __init__(self, model: ImpulseModelMultiple, data: pin.Data) -> None:
        super().__init__(model, data)
        nv, ndx = model.state.nv, model.state.ndx
        self.impulses: dict[str, ImpulseDataAbstract] = self.items
        self.dv0_dq = np.zeros((model.nc_total, nv))
        self.vnext = np.zeros(nv)
        self.dvnext_dx = np.zeros((nv, ndx))
