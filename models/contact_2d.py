"""A planar (x, z) point contact (Crocoddyl's ``ContactModel2D``), in LOCAL coordinates only.

With ``S = (e_x, e_z)ᵀ`` the selection of the x and z rows, ``J = (Jl; Ja)`` the LOCAL frame
Jacobian, ``vl``, ``w``, ``al`` the LOCAL frame velocity and acceleration at zero joint acceleration,
``p`` the frame position in the world and ``(kp, kd)`` the gains::

    Jc = S Jl,    a0 = S (al + w × vl + kd vl) + kp (S p - xref)                      (nc = 2)

The position term compares the world x and z of the frame with ``xref`` (a planar robot moving in
the world's x-z plane), as Crocoddyl 3.2.1 does (measured), so
``da0/dq = S (d(al + w × vl + kd vl)/dq) + kp S R Jl``.  The velocity terms are those of the LOCAL
:class:`~crocopy.models.contacts.ContactModel3D` with gains ``(0, kd)``.

Force: ``λ = (λx, λz)`` is ``f = (λx, 0, λz, 0, 0, 0)`` in the frame (``force_rows = (0, 2)``),
``fext = jMf.act(f)``.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from crocopy.state import StateAbstract
from crocopy.versioning import frozen_copy, touch

from .contact_base import ContactDataAbstract, ContactModelAbstract, check_gains, check_position
from .contacts import ContactModel3D, PointContactProjection, split_nu_gains
from .force_base import frame_id

_XZ = np.array([0, 2])


class ContactModel2D(PointContactProjection, ContactModelAbstract):
    """Crocoddyl's ``ContactModel2D(state, id, xref, nu=state.nv, gains=[0, 0])`` (``type`` is LOCAL).

    Parameters
    ----------
    state : StateMultibody
        Multibody state.
    id : int or str
        Contact frame (index or name).
    xref : array_like, shape (2,)
        Contact position (world x, z), used by the Baumgarte position term.
    nu : int, optional
        Control dimension (default ``state.nv``).
    gains : array_like, shape (2,)
        Baumgarte gains ``(kp, kd)`` (default zeros).
    """

    def __init__(
        self, state: StateAbstract, id: int | str, xref: np.ndarray, nu: int | None = None,
        gains: np.ndarray | None = None,
    ) -> None:
        nu, gains = split_nu_gains(nu, gains)
        fid = frame_id(state, id)
        super().__init__(state, pin.LOCAL, 2, nu)
        self.id = fid
        self._point = ContactModel3D(state, fid, np.zeros(3), pin.LOCAL, self.nu)
        self.reference = xref
        self.gains = gains

    @property
    def reference(self) -> np.ndarray:
        """Contact position ``xref`` (world x, z), shape ``(2,)`` (read-only; assign to change it)."""
        return self._xref

    @reference.setter
    def reference(self, value: np.ndarray) -> None:
        self._xref = frozen_copy(check_position(value, 2))
        touch(self)

    @property
    def gains(self) -> np.ndarray:
        """Baumgarte gains ``(kp, kd)`` (read-only; assign a new array to change them)."""
        return self._gains

    @gains.setter
    def gains(self, value: np.ndarray | None) -> None:
        self._gains = frozen_copy(check_gains(value))
        self._point.gains = np.array([0.0, self._gains[1]])
        touch(self)

    def compiled_reference(self, R: np.ndarray, p: np.ndarray) -> None:
        """This contact's lowering (:mod:`crocopy.models.rbd.contact_kernel`): its rows ``(e_x, e_z)ᵀ`` into
        ``R[:2]`` (the last row zero) and ``xref`` into ``p[:2]`` (``p[2] = 0``)."""
        R[:] = 0.0
        R[0, 0] = R[1, 2] = 1.0
        p[:2] = self._xref
        p[2] = 0.0

    def createData(self, data: pin.Data) -> "ContactData2D":
        return ContactData2D(self, data)

    def calc(self, data: "ContactData2D", x: np.ndarray) -> None:
        point = self._point_calc(data, x)
        data.Jc[:] = point.Jc[_XZ]
        data.a0[:] = point.a0[_XZ]
        kp = self._gains[0]
        oMf = data.pinocchio.oMf[self.id]
        data.oRf[:] = oMf.rotation[np.ix_(_XZ, _XZ)]
        if kp != 0.0:
            data.a0 += kp * (oMf.translation[_XZ] - self._xref)

    def calcDiff(self, data: "ContactData2D", x: np.ndarray) -> None:
        nv = self.state.nv
        point = self._point_calcDiff(data, x)
        data.da0_dx[:] = point.da0_dx[_XZ]
        kp = self._gains[0]
        if kp != 0.0:
            R = data.pinocchio.oMf[self.id].rotation
            data.da0_dx[:, :nv] += kp * (R[_XZ] @ data.fJf[:3])

    def updateForce(self, data: "ContactData2D", force: np.ndarray) -> None:
        """Store ``force (2,)`` as ``f = (λx, 0, λz, 0, 0, 0)`` and its joint-frame image in ``fext``.

        Raises
        ------
        ValueError
            If ``force`` does not have shape ``(2,)``.
        """
        if np.shape(force) != (2,):
            raise ValueError(f"force has shape {np.shape(force)}, expected (2,)")
        self.storeForce(data, force)
        self.updateJointForce(data)

    def storeForce(self, data: "ContactData2D", force: np.ndarray) -> None:
        """Store ``force (2,)`` in ``data.f`` only (``fext`` waits for :meth:`updateJointForce`)."""
        data.f.linear = np.array([force[0], 0.0, force[1]])

    def updateJointForce(self, data: "ContactData2D") -> None:
        """``f_local = f`` and ``fext = jMf.act(f)``."""
        data.f_local.vector = data.f.vector
        data.fext = data.jMf.act(data.f_local)

    def __repr__(self) -> str:
        return f"ContactModel2D(id={self.id}, xref={self._xref}, gains={self._gains})"


class ContactData2D(ContactDataAbstract):
    """Data of :class:`ContactModel2D`: ``point`` (the data of the underlying LOCAL 3D point contact
    with gains ``(0, kd)``) and ``oRf (2, 2)`` (the x-z block of the frame rotation)."""

    force_rows = (0, 2)

    def __init__(self, model: ContactModel2D, data: pin.Data) -> None:
        super().__init__(model, data)
        self.point = model._point.createData(data)
        self.oRf = np.zeros((2, 2))

    def contact_jacobian(self, J: np.ndarray, R: np.ndarray) -> np.ndarray:
        """``Jc (2, nv)``: the x and z rows of the LOCAL frame Jacobian ``J (6, nv)``."""
        return J[_XZ]
