"""Named sets of impulses, stacked into one impact constraint ``Jc v⁺ = -e Jc v⁻``.

Active impulses are stacked in name order into the first ``nc`` rows of ``Jc (nc_total, nv)`` and
``dv0_dq (nc_total, nv)``; ``fext`` holds, per joint, the sum of the impulses attached to it
in the joint frame.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from crocopy.named_items import NamedItems
from crocopy.state import StateAbstract

from .impulse_base import ImpulseDataAbstract, ImpulseModelAbstract


@dataclass
class ImpulseItem:
    """Crocoddyl's ``ImpulseItem(name, impulse, active=True)``."""

    name: str
    impulse: ImpulseModelAbstract
    active: bool = True

    def __repr__(self) -> str:
        return f"{{{self.name}, {self.impulse!r}, active={self.active}}}"


class ImpulseModelMultiple(NamedItems):
    """Crocoddyl's ``ImpulseModelMultiple(state)``.

    Attributes
    ----------
    impulses : dict[str, ImpulseItem]
        All impulses, ordered by name.
    nc, nc_total : int
        Dimension of the active impulses, of all impulses.
    """

    _kind = "impulse"

    def __init__(self, state: StateAbstract) -> None:
        if not isinstance(getattr(state, "pinocchio", None), pin.Model):
            raise ValueError(f"state must be a StateMultibody, got {type(state).__name__}")
        self.state = state
        self.nu = 0
        self._items: dict[str, ImpulseItem] = {}
        self._recount()

    @property
    def impulses(self) -> dict[str, ImpulseItem]:
        return self._items

    def _recount(self) -> None:
        self.nc = sum(c.impulse.nc for c in self._items.values() if c.active)
        self.nc_total = sum(c.impulse.nc for c in self._items.values())
        self._active = [(n, c.impulse) for n, c in self._items.items() if c.active]
        self._inactive = [(n, c.impulse) for n, c in self._items.items() if not c.active]
        self._lwa = [(n, c) for n, c in self._active if c.type != pin.LOCAL]

    def addImpulse(self, name: str, impulse: ImpulseModelAbstract, active: bool = True) -> None:
        """Add ``impulse`` under ``name`` (``ValueError`` if the name is taken or the robot differs)."""
        if not isinstance(impulse, ImpulseModelAbstract):
            raise ValueError(f"impulse must be an ImpulseModelAbstract, got {type(impulse).__name__}")
        self._check_new_name(name)
        if impulse.state.pinocchio is not self.state.pinocchio and (
            impulse.state.nx != self.state.nx or impulse.state.pinocchio.nframes != self.state.pinocchio.nframes
        ):
            raise ValueError(f"impulse {name!r} was built on the model of another robot")
        self._insert(name, ImpulseItem(name, impulse, bool(active)))

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
        i = 0
        for name, c in self._active:
            cd = data.impulses[name]
            c.calc(cd, x)
            data.Jc[i:i + c.nc] = cd.Jc
            i += c.nc

    def calcDiff(self, data: "ImpulseDataMultiple", x: np.ndarray) -> None:
        """Evaluate and stack ``dv0_dq`` of the active impulses."""
        i = 0
        for name, c in self._active:
            cd = data.impulses[name]
            c.calcDiff(cd, x)
            data.dv0_dq[i:i + c.nc] = cd.dv0_dq
            i += c.nc

    def updateVelocity(self, data: "ImpulseDataMultiple", vnext: np.ndarray) -> None:
        """Store the velocity after impact ``vnext (nv,)``."""
        data.vnext[:] = vnext

    def updateVelocityDiff(self, data: "ImpulseDataMultiple", dvnext_dx: np.ndarray) -> None:
        """Store the Jacobian of the velocity after impact ``dvnext_dx (nv, ndx)``."""
        data.dvnext_dx[:] = dvnext_dx

    def updateForce(self, data: "ImpulseDataMultiple", force: np.ndarray) -> None:
        """Split ``force (nc,)`` into the active impulses and sum their joint forces into ``fext``."""
        if np.shape(force) != (self.nc,):
            raise ValueError(f"force has shape {np.shape(force)}, expected ({self.nc},)")
        fext = data.fext
        for j in data.touched:
            fext[j] = data.zero_force
        i = 0
        for name, c in self._active:
            cd = data.impulses[name]
            c.updateForce(cd, force[i:i + c.nc])
            fext[cd.joint] = fext[cd.joint] + cd.fext
            i += c.nc
        for name, c in self._inactive:
            c.setZeroForce(data.impulses[name])

    def updateForceDiff(self, data: "ImpulseDataMultiple", df_dx: np.ndarray) -> None:
        """Split the impulse Jacobian ``df_dx (nc, ndx)`` into the active impulses."""
        if np.shape(df_dx) != (self.nc, self.state.ndx):
            raise ValueError(f"df_dx has shape {np.shape(df_dx)}, expected ({self.nc}, {self.state.ndx})")
        i = 0
        for name, c in self._active:
            c.updateForceDiff(data.impulses[name], df_dx[i:i + c.nc])
            i += c.nc
        for name, c in self._inactive:
            c.setZeroForceDiff(data.impulses[name])

    def updateRneaDiff(self, data: "ImpulseDataMultiple", pinocchio: pin.Data) -> None:
        """Add to ``pinocchio.dtau_dq`` the terms of impulses not expressed in local coordinates."""
        for name, c in self._lwa:
            c.addRneaDiff(data.impulses[name], pinocchio.dtau_dq)

    def __repr__(self) -> str:
        return "ImpulseModelMultiple(" + ", ".join(f"{n}: {c.impulse!r}" for n, c in self._items.items()) + ")"


class ImpulseDataMultiple:
    """Data of :class:`ImpulseModelMultiple`: ``impulses`` (name → data), ``Jc (nc_total, nv)``,
    ``dv0_dq (nc_total, nv)``, ``vnext (nv,)``, ``dvnext_dx (nv, ndx)`` and ``fext`` (per joint)."""

    def __init__(self, model: ImpulseModelMultiple, data: pin.Data) -> None:
        nv, ndx, nct = model.state.nv, model.state.ndx, model.nc_total
        self.impulses: dict[str, ImpulseDataAbstract] = {
            name: item.impulse.createData(data) for name, item in model.impulses.items()
        }
        self.Jc = np.zeros((nct, nv))
        self.dv0_dq = np.zeros((nct, nv))
        self.vnext = np.zeros(nv)
        self.dvnext_dx = np.zeros((nv, ndx))
        self.fext = pin.StdVec_Force()
        for _ in range(model.state.pinocchio.njoints):
            self.fext.append(pin.Force.Zero())
        self.zero_force = pin.Force.Zero()
        self.touched = sorted({cd.joint for cd in self.impulses.values()})
