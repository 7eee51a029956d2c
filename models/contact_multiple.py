"""Named sets of contacts, stacked into one constraint ``Jc a + a0 = 0``.

Active contacts are stacked in name order (as Crocoddyl's ordered map does) into the first ``nc``
rows of ``Jc (nc_total, nv)``, ``a0 (nc_total,)`` and ``da0_dx (nc_total, ndx)``; the rows of the
force vector ``λ (nc,)`` follow the same order.  ``fext`` holds, per joint, the sum of the forces
of the contacts attached to it, in the joint frame (the input of Pinocchio's RNEA).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from crocopy.named_items import NamedItems
from crocopy.state import StateAbstract

from .contact_base import ContactDataAbstract, ContactModelAbstract


@dataclass
class ContactItem:
    """Crocoddyl's ``ContactItem(name, contact, active=True)``."""

    name: str
    contact: ContactModelAbstract
    active: bool = True

    def __repr__(self) -> str:
        return f"{{{self.name}, {self.contact!r}, active={self.active}}}"


class ContactModelMultiple(NamedItems):
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

    def __init__(self, state: StateAbstract, nu: int | None = None) -> None:
        if not isinstance(getattr(state, "pinocchio", None), pin.Model):
            raise ValueError(f"state must be a StateMultibody, got {type(state).__name__}")
        self.state = state
        self.nu = state.nv if nu is None else int(nu)
        if self.nu < 0:
            raise ValueError(f"nu must be non-negative, got {self.nu}")
        self.computeAllContacts = False
        self._items: dict[str, ContactItem] = {}
        self._recount()

    @property
    def contacts(self) -> dict[str, ContactItem]:
        return self._items

    def _recount(self) -> None:
        self.nc = sum(c.contact.nc for c in self._items.values() if c.active)
        self.nc_total = sum(c.contact.nc for c in self._items.values())
        self._active = [(n, c.contact) for n, c in self._items.items() if c.active]
        self._inactive = [(n, c.contact) for n, c in self._items.items() if not c.active]
        self._lwa = [(n, c) for n, c in self._active if c.type != pin.LOCAL]
        frames = self.state.pinocchio.frames
        joints = [int(frames[c.id].parentJoint) for _, c in self._active]
        self._shared_joints = len(set(joints)) != len(joints)
        self._idle_joints = sorted({int(frames[c.id].parentJoint) for _, c in self._inactive} - set(joints))

    def addContact(self, name: str, contact: ContactModelAbstract, active: bool = True) -> None:
        """Add ``contact`` under ``name``.

        Raises
        ------
        ValueError
            If ``name`` is already used, or ``contact`` has another ``nu`` or another robot.
        """
        if not isinstance(contact, ContactModelAbstract):
            raise ValueError(f"contact must be a ContactModelAbstract, got {type(contact).__name__}")
        self._check_new_name(name)
        if contact.nu != self.nu:
            raise ValueError(f"contact {name!r} has nu = {contact.nu}, expected nu = {self.nu}")
        if contact.state.pinocchio is not self.state.pinocchio and (
            contact.state.nx != self.state.nx or contact.state.pinocchio.nframes != self.state.pinocchio.nframes
        ):
            raise ValueError(f"contact {name!r} was built on the model of another robot")
        self._insert(name, ContactItem(name, contact, bool(active)))

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
        i = 0
        for name, c in self._active:
            cd = data.contacts[name]
            c.calc(cd, x)
            data.Jc[i:i + c.nc] = cd.Jc
            data.a0[i:i + c.nc] = cd.a0
            i += c.nc
        if self.computeAllContacts:
            for name, c in self._inactive:
                c.calc(data.contacts[name], x)

    def calcDiff(self, data: "ContactDataMultiple", x: np.ndarray) -> None:
        """Evaluate the drift Jacobians of the active contacts and stack ``da0_dx``."""
        i = 0
        for name, c in self._active:
            cd = data.contacts[name]
            c.calcDiff(cd, x)
            data.da0_dx[i:i + c.nc] = cd.da0_dx
            i += c.nc
        if self.computeAllContacts:
            for name, c in self._inactive:
                c.calcDiff(data.contacts[name], x)

    def rigidConstraints(self, data: "ContactDataMultiple", pinocchio: pin.Data):
        """Pinocchio ``RigidConstraintModel``/``Data`` vectors of the active contacts, or ``None``.

        They reproduce these contacts exactly (same drift, Baumgarte terms and coordinates) when every
        active contact is a 3D contact, a LOCAL 6D contact or a 6D contact without position gain;
        ``None`` otherwise.  They are rebuilt (and ``initConstraintDynamics`` called) only when the
        active set, a reference or a gain changed.
        """
        key = []
        for name, c in self._active:
            rigid = getattr(c, "rigidConstraintModel", None)
            if rigid is None or (c.nc == 6 and c.type != pin.LOCAL and c.gains[0] != 0.0):
                return None
            key.append((name, c._version))
        key = tuple(key)
        if data.rigid_key != key:
            cms, cds = pin.StdVec_RigidConstraintModel(), pin.StdVec_RigidConstraintData()
            for _, c in self._active:
                rigid = c.rigidConstraintModel()
                cms.append(rigid)
                cds.append(rigid.createData())
            pin.initConstraintDynamics(self.state.pinocchio, pinocchio, cms, cds)
            data.rigid, data.rigid_key = RigidConstraintCache((cms, cds)), key
        return data.rigid

    def updateAcceleration(self, data: "ContactDataMultiple", dv: np.ndarray) -> None:
        """Store the constrained acceleration ``dv (nv,)``."""
        data.dv[:] = dv

    def updateAccelerationDiff(self, data: "ContactDataMultiple", ddv_dx: np.ndarray) -> None:
        """Store the Jacobian of the constrained acceleration ``ddv_dx (nv, ndx)``."""
        data.ddv_dx[:] = ddv_dx

    def updateForce(self, data: "ContactDataMultiple", force: np.ndarray) -> None:
        """Split ``force (nc,)`` into the active contacts and sum their joint forces into ``fext``.

        Raises
        ------
        ValueError
            If ``force`` does not have shape ``(nc,)``.
        """
        if getattr(force, "shape", None) != (self.nc,):
            force = np.asarray(force, dtype=float)
            if force.shape != (self.nc,):
                raise ValueError(f"force has shape {force.shape}, expected ({self.nc},)")
        i = 0
        for name, c in self._active:
            c.storeForce(data.contacts[name], force[i:i + c.nc])
            i += c.nc
        for name, c in self._inactive:
            c.setZeroForce(data.contacts[name])
        data.joint_forces_pending = True

    def updateJointForces(self, data: "ContactDataMultiple") -> None:
        """Refresh every contact's ``f_local``/``fext`` and the per-joint sums ``data.fext``.

        :meth:`updateForce` defers this work until ``data.fext`` is read.
        """
        fext, shared = data.fext_by_joint, self._shared_joints
        for j in data.touched if shared else self._idle_joints:
            fext[j] = data.zero_force
        for name, c in self._active:
            cd = data.contacts[name]
            c.updateJointForce(cd)
            fext[cd.joint] = fext[cd.joint] + cd.fext if shared else cd.fext
        data.joint_forces_pending = False

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
        i = 0
        for name, c in self._active:
            c.updateForceDiff(data.contacts[name], df_dx[i:i + c.nc], df_du[i:i + c.nc])
            i += c.nc
        for name, c in self._inactive:
            c.setZeroForceDiff(data.contacts[name])

    def updateRneaDiff(self, data: "ContactDataMultiple", pinocchio: pin.Data) -> None:
        """Add to ``pinocchio.dtau_dq`` the terms of the contacts whose forces are not in local coordinates."""
        if self._lwa:
            dtau_dq = pinocchio.dtau_dq
            for name, c in self._lwa:
                c.addRneaDiff(data.contacts[name], dtau_dq)

    def __repr__(self) -> str:
        return "ContactModelMultiple(" + ", ".join(f"{n}: {c.contact!r}" for n, c in self._items.items()) + ")"


def _no_cache() -> None:
    return None


class RigidConstraintCache(tuple):
    """``(models, datas)`` of Pinocchio constraints: a cache that copies and pickles as ``None``
    (Pinocchio cannot pickle them; their holders rebuild them on the next ``calc``)."""

    def __reduce__(self) -> tuple:
        return _no_cache, ()


class ContactDataMultiple:
    """Data of :class:`ContactModelMultiple`: ``contacts`` (name → data), ``Jc (nc_total, nv)``,
    ``a0 (nc_total,)``, ``da0_dx (nc_total, ndx)``, ``dv (nv,)``, ``ddv_dx (nv, ndx)`` and ``fext``
    (one ``pinocchio.Force`` per joint).

    ``fext`` and the contacts' ``f_local``/``fext`` are brought up to date with the forces when
    ``fext`` is read (the constrained dynamics do not need them).
    """

    def __init__(self, model: ContactModelMultiple, data: pin.Data) -> None:
        nv, ndx, nct = model.state.nv, model.state.ndx, model.nc_total
        self.contacts: dict[str, ContactDataAbstract] = {
            name: item.contact.createData(data) for name, item in model.contacts.items()
        }
        self.Jc = np.zeros((nct, nv))
        self.a0 = np.zeros(nct)
        self.da0_dx = np.zeros((nct, ndx))
        self.dv = np.zeros(nv)
        self.ddv_dx = np.zeros((nv, ndx))
        self.fext_by_joint = pin.StdVec_Force()
        for _ in range(model.state.pinocchio.njoints):
            self.fext_by_joint.append(pin.Force.Zero())
        self.joint_forces_pending = False
        self._model = model
        self.zero_force = pin.Force.Zero()
        self.touched = sorted({cd.joint for cd in self.contacts.values()})
        self.rigid = None
        self.rigid_key = None

    def __getstate__(self) -> dict:
        """Copy or pickle without the Pinocchio constraint cache (``rigid``, rebuilt on first use)."""
        return {**self.__dict__, "rigid": None, "rigid_key": None}

    @property
    def fext(self) -> pin.StdVec_Force:
        """External force at each joint (``njoints`` ``pinocchio.Force``, the same object every time)."""
        if self.joint_forces_pending:
            self._model.updateJointForces(self)
        return self.fext_by_joint
