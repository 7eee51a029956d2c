"""A one-dimensional point contact along a rotated axis (Crocoddyl's ``ContactModel1D``).

The contact holds the frame origin along one direction: with ``Rax`` the rotation ``rotation``
(Crocoddyl's ``Raxis``), ``e = Raxᵀ e_z`` the constrained axis and the 3D point contact of
:class:`~crocopy.models.contacts.ContactModel3D` on the same frame, type and gains, whose
reference is the world point ``xref Rax e_z``::

    Jc = e_zᵀ Rax Jc3,    a0 = e_zᵀ Rax a0_3,    da0_dx = e_zᵀ Rax da0_dx3       (nc = 1)

i.e. in LOCAL coordinates ``Jc = eᵀ Jl`` and
``a0 = eᵀ (al + w × vl + kp Rᵀ(p - xref Rax e_z) + kd vl)``; in LOCAL_WORLD_ALIGNED (and WORLD,
which Crocoddyl treats alike) every vector in brackets is first rotated by the frame orientation
``R``.  These are Crocoddyl 3.2.1's values, measured (a scalar ``xref`` is the world point
``xref Rax e_z``).

Force: the scalar ``λ`` is stored as ``f = (0, 0, λ, 0, 0, 0)`` (Crocoddyl's convention; the force
residuals read component 2, see ``force_rows``); the force at the frame is
``f_local = λ e`` (LOCAL) or ``λ Rᵀ Raxᵀ e_z`` (LOCAL_WORLD_ALIGNED), and ``fext = jMf.act(f_local)``.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from crocopy.state import StateAbstract
from crocopy.validation import as_number, as_rotation
from crocopy.versioning import frozen_copy, touch

from .contact_base import ContactDataAbstract, ContactModelAbstract
from .contacts import ContactModel3D, PointContactProjection
from .force_base import FrameForce, frame_id, world_aligned

_LOCAL = pin.LOCAL


def _check_rotation(rotation: np.ndarray) -> np.ndarray:
    return as_rotation(rotation, "rotation")


def _check_xref(xref: float) -> float:
    return as_number(xref, "xref")


class ContactModel1D(PointContactProjection, FrameForce, ContactModelAbstract):
    """Crocoddyl's ``ContactModel1D(state, id, xref, type, rotation, nu, gains=[0, 0])`` or
    ``ContactModel1D(state, id, xref, type, gains=[0, 0])`` (identity rotation, ``nu = state.nv``).

    Parameters
    ----------
    state : StateMultibody
        Multibody state.
    id : int or str
        Contact frame (index or name).
    xref : float
        Contact position along the axis, used by the Baumgarte position term.
    type : pinocchio.ReferenceFrame
        ``LOCAL``, ``LOCAL_WORLD_ALIGNED`` or ``WORLD`` (the same as ``LOCAL_WORLD_ALIGNED``).
    rotation : array_like, shape (3, 3), optional
        ``Raxis``: rotation of the reference frame's z axis (default identity).
    nu : int, optional
        Control dimension (default ``state.nv``).
    gains : array_like, shape (2,)
        Baumgarte gains ``(kp, kd)`` (default zeros).
    """

    def __init__(
        self,
        state: StateAbstract,
        id: int | str,
        xref: float,
        type: pin.ReferenceFrame,
        rotation: np.ndarray | None = None,
        nu: int | None = None,
        gains: np.ndarray | None = None,
    ) -> None:
        if rotation is not None and np.shape(rotation) == (2,) and nu is None and gains is None:
            rotation, gains = None, rotation
        fid = frame_id(state, id)
        super().__init__(state, type, 1, nu)
        self.id = fid
        self._point = ContactModel3D(state, fid, np.zeros(3), world_aligned(type), self.nu, gains)
        self._xref = 0.0
        self._Raxis = frozen_copy(np.eye(3))
        self.Raxis = np.eye(3) if rotation is None else rotation
        self.reference = xref

    @property
    def Raxis(self) -> np.ndarray:
        """Rotation of the reference frame's z axis, shape ``(3, 3)`` (read-only; assign to change it)."""
        return self._Raxis

    @Raxis.setter
    def Raxis(self, value: np.ndarray) -> None:
        self._Raxis = frozen_copy(_check_rotation(value))
        self._row = frozen_copy(self._Raxis[2:3].copy())
        self._point.reference = self._xref * self._Raxis[:, 2]
        touch(self)

    @property
    def reference(self) -> float:
        """Contact position ``xref`` along the axis."""
        return self._xref

    @reference.setter
    def reference(self, value: float) -> None:
        self._xref = _check_xref(value)
        self._point.reference = self._xref * self._Raxis[:, 2]
        touch(self)

    @property
    def gains(self) -> np.ndarray:
        """Baumgarte gains ``(kp, kd)`` (read-only; assign a new array to change them)."""
        return self._point.gains

    @gains.setter
    def gains(self, value: np.ndarray | None) -> None:
        self._point.gains = value
        touch(self)

    def compiled_reference(self, R: np.ndarray, p: np.ndarray) -> None:
        """This contact's lowering (:mod:`crocopy.models.rbd.contact_kernel`): its row ``e_zᵀ Raxis`` into ``R[0]``
        (the other rows zero) and its point contact's reference ``xref Raxis e_z`` into ``p (3,)``."""
        R[:] = 0.0
        R[0] = self._row[0]
        p[:] = self._point.reference

    def createData(self, data: pin.Data) -> "ContactData1D":
        return ContactData1D(self, data)

    def calc(self, data: "ContactData1D", x: np.ndarray) -> None:
        point = self._point_calc(data, x)
        data.oRf[:] = point.R
        data.row[:] = self._row
        np.dot(self._row, point.Jc, out=data.Jc)
        np.dot(self._row, point.a0, out=data.a0)

    def calcDiff(self, data: "ContactData1D", x: np.ndarray) -> None:
        point = self._point_calcDiff(data, x)
        np.dot(self._row, point.da0_dx, out=data.da0_dx)

    def storeForce(self, data: "ContactData1D", force: np.ndarray) -> None:
        """Store ``force (1,)`` as ``f = (0, 0, λ, 0, 0, 0)`` (``f_local``/``fext`` wait for
        :meth:`updateJointForce`)."""
        data.f.linear = data.axis * force[0]

    def updateJointForce(self, data: "ContactData1D") -> None:
        """``f_local`` (along the axis, in the frame) and ``fext`` (at the parent joint) from ``data.f``."""
        lam = data.f.linear[2]
        if self.type == _LOCAL:
            data.f_local.linear = lam * self._Raxis[2]
        else:
            data.f_local.linear = lam * (self._Raxis[2] @ data.pinocchio.oMf[self.id].rotation)
        data.fext = data.jMf.act(data.f_local)

    def __repr__(self) -> str:
        return f"ContactModel1D(id={self.id}, type={self.type}, xref={self._xref}, axis={self._Raxis[:, 2]})"


class ContactData1D(ContactDataAbstract):
    """Data of :class:`ContactModel1D`: ``point`` (the data of the underlying 3D point contact, whose
    ``a0_local``, ``da0_local_dx``, ``dp`` and ``dp_local`` are also exposed here), ``oRf`` and ``row``
    (``e_zᵀ Raxis`` at the last ``calc``)."""

    force_rows = (2,)

    def __init__(self, model: ContactModel1D, data: pin.Data) -> None:
        super().__init__(model, data)
        self.point = model._point.createData(data)
        self.oRf = np.eye(3)
        self.axis = np.array([0.0, 0.0, 1.0])
        self.row = model._row.copy()

    def contact_jacobian(self, J: np.ndarray, R: np.ndarray) -> np.ndarray:
        """``Jc (1, nv)`` from the LOCAL frame Jacobian ``J (6, nv)`` and the frame rotation ``R``."""
        return self.row @ (J[:3] if self.type == _LOCAL else R @ J[:3])

    @property
    def a0_local(self) -> np.ndarray:
        """Drift of the 3D point contact in the frame, shape ``(3,)``."""
        return self.point.a0_local

    @property
    def da0_local_dx(self) -> np.ndarray:
        """Jacobian of :attr:`a0_local`, shape ``(3, ndx)``."""
        return self.point.da0_local_dx

    @property
    def dp(self) -> np.ndarray:
        """Position error ``p - xref Rax e_z`` in the world, shape ``(3,)``."""
        return self.point.dp

    @property
    def dp_local(self) -> np.ndarray:
        """Position error in the frame, shape ``(3,)``."""
        return self.point.dp_local
