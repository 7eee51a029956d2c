"""Named sets of contacts, stacked into one constraint ``Jc a + a0 = 0``.

Active contacts are stacked in name order (as Crocoddyl's ordered map does) into the first ``nc``
rows of ``Jc (nc_total, nv)``, ``a0 (nc_total,)`` and ``da0_dx (nc_total, ndx)``; the rows of the
force vector ``λ (nc,)`` follow the same order.  ``fext`` holds, per joint, the sum of the forces
of the contacts attached to it, in the joint frame (the input of Pinocchio's RNEA).  The
bookkeeping shared with impulse sets lives in :mod:`~crocopy.models.force_base`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from crocopy.state import StateAbstract
from crocopy.validation import as_bool
from crocopy.versioning import ParametersSeen

from .contact_base import ContactDataAbstract, ContactModelAbstract
from .force_base import ForceDataMultiple, ForceModelMultiple


@dataclass
class ContactItem:
    """Crocoddyl's ``ContactItem(name, contact, active=True)``."""

    name: str
    contact: ContactModelAbstract
    active: bool = True

    def __repr__(self) -> str:
        return f"{{{self.name}, {self.contact!r}, active={self.active}}}"


class ContactModelMultiple(ForceModelMultiple):
    """Crocoddyl's ``ContactModelMultiple(state, nu=state.nv)``.

    Parameters
    ----------
    state : StateMultibody
        Multibody state.
    nu : int, optional
        Control dimension (default ``state.nv``).

    Attributes
    ----------
    contacts : dict[str, ContactItem]
        All contacts, ordered by name.
    nc, nc_total : int
        Dimension of the active contacts, of all contacts.
    computeAllContacts : bool
        Also evaluate inactive contacts in ``calc``/``calcDiff`` (default False).
    """

    _kind = "contact"
    _model_type = ContactModelAbstract

    def __init__(self, state: StateAbstract, nu: int | None = None) -> None:
        super().__init__(state, nu)
        self.computeAllContacts = False

    @property
    def contacts(self) -> dict[str, ContactItem]:
        return self._items

    def addContact(self, name: str, contact: ContactModelAbstract, active: bool = True) -> None:
        """Add ``contact`` under ``name``.

        Raises
        ------
        ValueError
            If ``contact`` is not a ``ContactModelAbstract``, ``name`` is already used, or ``contact``
            has another ``nu`` or another robot.
        """
        self._add(name, contact, ContactItem(name, contact, as_bool(active, "active")))

    def removeContact(self, name: str) -> None:
        """Remove the contact ``name`` (``KeyError`` if unknown)."""
        self._remove(name)

    def changeContactStatus(self, name: str, active: bool) -> None:
        """Activate or deactivate the contact ``name`` (``KeyError`` if unknown)."""
        self._set_active(name, active)

    def getContactStatus(self, name: str) -> bool:
        """True if the contact ``name`` is active (``KeyError`` if unknown)."""
        return self._get(name).active

    def createData(self, data: pin.Data) -> "ContactDataMultiple":
        """Allocate the data of every contact (on the node's ``pinocchio.Data``) and the stacked arrays."""
        return ContactDataMultiple(self, data)

    def calc(self, data: "ContactDataMultiple", x: np.ndarray) -> None:
        """Evaluate the active contacts and stack ``Jc``/``a0`` (inactive rows are zero)."""
        self._stack(data.items, x, False, ((data.Jc, "Jc"), (data.a0, "a0")))
        if self.computeAllContacts:
            for name, c in self._inactive:
                c.calc(data.items[name], x)

    def calcDiff(self, data: "ContactDataMultiple", x: np.ndarray) -> None:
        """Evaluate the drift Jacobians of the active contacts and stack ``da0_dx``."""
        self._stack(data.items, x, True, ((data.da0_dx, "da0_dx"),))
        if self.computeAllContacts:
            for name, c in self._inactive:
                c.calcDiff(data.items[name], x)

    def rigidConstraints(self, data: "ContactDataMultiple", pinocchio: pin.Data):
        """Pinocchio ``RigidConstraintModel``/``Data`` vectors of the active contacts, or ``None``.

        They reproduce these contacts exactly (same drift, Baumgarte terms and coordinates) when every
        active contact is a 3D contact, a LOCAL 6D contact or a 6D contact without position gain;
        ``None`` otherwise.  They are rebuilt (and ``initConstraintDynamics`` called) only when the
        active set, a reference or a gain changed (:mod:`crocopy.versioning`), or a 6D contact's live reference
        placement was changed in place.
        """
        if data.rigid_seen.stale(self._rigid_sources) or any(
            placement != seen for placement, seen in data.rigid_placements
        ):
            data.rigid = self._build_rigid(pinocchio)
            data.rigid_placements = [(c._pref, c._pref.copy()) for _, c in self._active if hasattr(c, "_pref")]
            data.rigid_seen.filled()
        return data.rigid

    def _rigid_sources(self) -> list:
        return [self, *(c for _, c in self._active)]

    def _build_rigid(self, pinocchio: pin.Data):
        for _, c in self._active:
            if getattr(c, "rigidConstraintModel", None) is None or (
                c.nc == 6 and c.type != pin.LOCAL and c.gains[0] != 0.0
            ):
                return None
        cms, cds = pin.StdVec_RigidConstraintModel(), pin.StdVec_RigidConstraintData()
        for _, c in self._active:
            rigid = c.rigidConstraintModel()
            cms.append(rigid)
            cds.append(rigid.createData())
        pin.initConstraintDynamics(self.state.pinocchio, pinocchio, cms, cds)
        return RigidConstraintCache((cms, cds))

    def updateAcceleration(self, data: "ContactDataMultiple", dv: np.ndarray) -> None:
        """Store the constrained acceleration ``dv (nv,)``."""
        data.dv[:] = dv

    def updateAccelerationDiff(self, data: "ContactDataMultiple", ddv_dx: np.ndarray) -> None:
        """Store the Jacobian of the constrained acceleration ``ddv_dx (nv, ndx)``."""
        data.ddv_dx[:] = ddv_dx

    def updateForce(self, data: "ContactDataMultiple", force: np.ndarray) -> None:
        """Split ``force (nc,)`` into the active contacts; their joint forces (``fext``) are brought up to
        date when ``data.fext`` is read (:meth:`updateJointForces`).

        Raises
        ------
        ValueError
            If ``force`` does not have shape ``(nc,)``.
        """
        self._store_forces(data, force)

    def updateForceDiff(self, data: "ContactDataMultiple", df_dx: np.ndarray, df_du: np.ndarray) -> None:
        """Split the force Jacobians ``df_dx (nc, ndx)`` and ``df_du (nc, nu)`` into the active contacts.

        Raises
        ------
        ValueError
            If the shapes are not ``(nc, ndx)`` and ``(nc, nu)``.
        """
        df_dx, df_du = np.asarray(df_dx), np.asarray(df_du)
        if df_dx.shape != (self.nc, self.state.ndx) or df_du.shape != (self.nc, self.nu):
            raise ValueError(
                f"df_dx, df_du have shapes {np.shape(df_dx)}, {np.shape(df_du)}, "
                f"expected ({self.nc}, {self.state.ndx}), ({self.nc}, {self.nu})"
            )
        self._split(data.items, "updateForceDiff", (df_dx, df_du), "setZeroForceDiff")


def _no_cache() -> None:
    return None


class RigidConstraintCache(tuple):
    """``(models, datas)`` of Pinocchio constraints: a cache that copies and pickles as ``None``
    (Pinocchio cannot pickle them; their holders rebuild them on the next ``calc``)."""

    def __reduce__(self) -> tuple:
        return _no_cache, ()


class ContactDataMultiple(ForceDataMultiple):
    """Data of :class:`ContactModelMultiple`: ``contacts`` (name → data), ``Jc (nc_total, nv)``,
    ``a0 (nc_total,)``, ``da0_dx (nc_total, ndx)``, ``dv (nv,)``, ``ddv_dx (nv, ndx)`` and ``fext``
    (one ``pinocchio.Force`` per joint).

    ``fext`` and the contacts' ``f_local``/``fext`` are brought up to date with the forces when
    ``fext`` is read (the constrained dynamics do not need them).  ``rigid`` caches
    :meth:`ContactModelMultiple.rigidConstraints` (filled at the clock value ``rigid_seen``).
    """

    def __init__(self, model: ContactModelMultiple, data: pin.Data) -> None:
        super().__init__(model, data)
        nv, ndx, nct = model.state.nv, model.state.ndx, model.nc_total
        self.contacts: dict[str, ContactDataAbstract] = self.items
        self.a0 = np.zeros(nct)
        self.da0_dx = np.zeros((nct, ndx))
        self.dv = np.zeros(nv)
        self.ddv_dx = np.zeros((nv, ndx))
        self.rigid = None
        self.rigid_seen = ParametersSeen()
        self.rigid_placements: list = []

    def __getstate__(self) -> dict:
        """Copy or pickle without the Pinocchio constraint cache (``rigid``, rebuilt on first use)."""
        return {**self.__dict__, "rigid": None, "rigid_placements": []}
