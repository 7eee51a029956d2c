"""Point (3D) and rigid-frame (6D) contacts with Baumgarte stabilisation.

With ``J = (Jl; Ja)`` the LOCAL frame Jacobian, ``v = (vl, w)`` and ``a`` the LOCAL frame velocity
and spatial acceleration at zero joint acceleration, ``R`` the frame orientation, ``(kp, kd)`` the
gains:

- 3D, LOCAL: ``Jc = Jl``, ``a0 = al + w × vl + kp Rᵀ(p - xref) + kd vl`` (classical acceleration).
- 6D, LOCAL: ``Jc = J``, ``a0 = a + kp log6(prefᵀ oMf) + kd v``.
- LOCAL_WORLD_ALIGNED (and WORLD, which Crocoddyl treats alike): the same quantities rotated by ``R``
  (each 3-block), so that ``a0 = R a0_local`` and ``da0/dq = R da0_local/dq - R [a0_local]× Ja``.

The force maps (``f_local``, ``fext``, the RNEA correction in LOCAL_WORLD_ALIGNED) are those of
:class:`~crocopy.models.force_base.FrameForce`.  The reference and the gains change through their
setters only (read-only arrays), which :func:`~crocopy.versioning.touch` the contact so that contact
sets rebuild what they derived from them.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from crocopy.state import StateAbstract
from crocopy.validation import as_rotation, check_finite
from crocopy.versioning import frozen_copy, touch

from .contact_base import ContactDataAbstract, ContactModelAbstract, check_gains, check_position
from .force_base import FrameForce, frame_id, world_aligned
from .residuals_frame import frame_jacobian

_LOCAL = pin.LOCAL
_skew = pin.skew


def split_nu_gains(nu, gains):
    """Crocoddyl accepts ``(..., type, nu, gains)`` and ``(..., type, gains)``."""
    if nu is not None and not np.isscalar(nu):
        return None, nu
    return nu, gains


class _FrameContact(FrameForce, ContactModelAbstract):
    """What the 3D and 6D contacts share: frame, reference, Baumgarte gains, force maps, Pinocchio twin."""

    _rigid_kind: pin.ContactType

    def __init__(
        self, state: StateAbstract, id: int | str, reference, type: pin.ReferenceFrame, nc: int, nu, gains
    ) -> None:
        nu, gains = split_nu_gains(nu, gains)
        fid = frame_id(state, id)
        super().__init__(state, type, nc, nu)
        self.id = fid
        self.reference = reference
        self.gains = gains

    @property
    def gains(self) -> np.ndarray:
        """Baumgarte gains ``(kp, kd)`` (read-only; assign a new array to change them)."""
        return self._gains

    @gains.setter
    def gains(self, value: np.ndarray | None) -> None:
        self._gains = frozen_copy(check_gains(value))
        touch(self)

    def _reference_placement(self) -> pin.SE3:
        raise NotImplementedError

    def rigidConstraintModel(self) -> pin.RigidConstraintModel:
        """The same contact as a Pinocchio ``RigidConstraintModel`` (used by the fast contact dynamics):
        same frame, reference placement, coordinates and Baumgarte gains."""
        model = self.state.pinocchio
        frame = model.frames[self.id]
        rigid = pin.RigidConstraintModel(
            self._rigid_kind, model, frame.parentJoint, frame.placement, 0, self._reference_placement(),
            world_aligned(self.type),
        )
        params = rigid.m_baumgarte_parameters
        params.Kp = params.Kp * 0.0 + self._gains[0]
        params.Kd = params.Kd * 0.0 + self._gains[1]
        rigid.m_baumgarte_parameters = params
        return rigid


class ContactModel3D(_FrameContact):
    """Crocoddyl's ``ContactModel3D(state, id, xref, type, nu=state.nv, gains=[0, 0])``.

    Parameters
    ----------
    state : StateMultibody
        Multibody state.
    id : int or str
        Contact frame (index or name).
    xref : array_like, shape (3,)
        Contact position in the world, used by the Baumgarte position term.
    type : pinocchio.ReferenceFrame
        ``pinocchio.LOCAL``, ``pinocchio.LOCAL_WORLD_ALIGNED`` or ``pinocchio.WORLD`` (as ``LOCAL_WORLD_ALIGNED``).
    nu : int, optional
        Control dimension (default ``state.nv``).
    gains : array_like, shape (2,)
        Baumgarte gains ``(kp, kd)`` (default zeros).
    """

    _rigid_kind = pin.ContactType.CONTACT_3D

    def __init__(
        self,
        state: StateAbstract,
        id: int | str,
        xref: np.ndarray,
        type: pin.ReferenceFrame,
        nu: int | None = None,
        gains: np.ndarray | None = None,
    ) -> None:
        super().__init__(state, id, xref, type, 3, nu, gains)

    @property
    def reference(self) -> np.ndarray:
        """Contact position ``xref``, shape ``(3,)`` (read-only; assign a new array to change it)."""
        return self._xref

    @reference.setter
    def reference(self, value: np.ndarray) -> None:
        self._xref = frozen_copy(check_position(value, 3))
        touch(self)

    def _reference_placement(self) -> pin.SE3:
        return pin.SE3(np.eye(3), self._xref)

    def compiled_reference(self, R: np.ndarray, p: np.ndarray) -> None:
        """This contact's lowering: its reference position into ``p (3,)`` (``R (3, 3)`` unused)."""
        p[:] = self._xref

    def createData(self, data: pin.Data) -> "ContactData3D":
        return ContactData3D(self, data)

    def calc(self, data: "ContactData3D", x: np.ndarray) -> None:
        model, pd, fid = self.state.pinocchio, data.pinocchio, self.id
        J = data.fJf = frame_jacobian(model, pd, fid, _LOCAL)
        v = data.v = pin.getFrameVelocity(model, pd, fid, _LOCAL)
        data.vl, data.w = v.linear, v.angular
        a0l = pin.getFrameClassicalAcceleration(model, pd, fid, _LOCAL).linear
        kp, kd = self._gains
        oMf = pd.oMf[fid]
        R = data.R = oMf.rotation
        if kp != 0.0 or kd != 0.0:
            baum = data.baumgarte
            if kp != 0.0:
                np.subtract(oMf.translation, self._xref, out=data.dp)
                np.dot(data.dp, R, out=data.dp_local)
                np.multiply(data.dp_local, kp, out=baum)
                if kd != 0.0:
                    baum += kd * data.vl
            else:
                np.multiply(data.vl, kd, out=baum)
            a0l += baum
        data.a0_local = a0l
        if self.type == _LOCAL:
            data.Jc[:] = J[:3]
            data.a0[:] = a0l
        else:
            np.dot(R, J[:3], out=data.Jc)
            np.dot(R, a0l, out=data.a0)

    def calcDiff(self, data: "ContactData3D", x: np.ndarray) -> None:
        model, pd, fid, nv = self.state.pinocchio, data.pinocchio, self.id, self.state.nv
        vdq, adq, adv, ada = pin.getFrameAccelerationDerivatives(model, pd, fid, _LOCAL)
        data.v_partial_dq, data.a_partial_dq, data.a_partial_dv, data.a_partial_da = vdq, adq, adv, ada
        J = data.fJf
        kp, kd = self._gains
        # d(a + w × vl)/dx = a_partial + [[w]×, -[vl]×] dv/dx (+ kd dvl/dx)
        S = data.S
        S[:, :3] = _skew(data.w)
        S[:, 3:] = _skew(-data.vl)
        if kd != 0.0:
            S[data.d3, data.d3] += kd
        dq, dv = data.da0_local_dx[:, :nv], data.da0_local_dx[:, nv:]
        np.matmul(S, vdq, out=dq)
        dq += adq[:3]
        np.matmul(S, J, out=dv)
        dv += adv[:3]
        lwa = self.type != _LOCAL
        if kp != 0.0 or lwa:
            # kp d(Rᵀ(p - xref))/dq = kp [I, [dp_local]×] J;  LWA: -[acc]× Ja from the rotation R(q)
            K = data.K
            if kp != 0.0:
                K[data.d3, data.d3] = kp
                K[:, 3:] = _skew(kp * data.dp_local)
            else:
                K[:] = 0.0
            if lwa:
                acc = pin.getFrameClassicalAcceleration(model, pd, fid, _LOCAL).linear
                if kp != 0.0 or kd != 0.0:
                    acc += data.baumgarte
                K[:, 3:] -= _skew(acc)
                np.matmul(K, J, out=data.tmp)
                data.tmp += dq
                np.matmul(data.R, data.tmp, out=data.da0_dx[:, :nv])
                np.matmul(data.R, dv, out=data.da0_dx[:, nv:])
                return
            dq += K @ J
        data.da0_dx[:] = data.da0_local_dx

    def __repr__(self) -> str:
        return f"ContactModel3D(id={self.id}, type={self.type}, xref={self._xref}, gains={self._gains})"


class ContactData3D(ContactDataAbstract):
    """Data of :class:`ContactModel3D`; adds ``a0_local``, ``da0_local_dx``, ``dp``, ``dp_local`` and work arrays."""

    def __init__(self, model: ContactModel3D, data: pin.Data) -> None:
        super().__init__(model, data)
        self.a0_local = np.zeros(3)
        self.baumgarte = np.zeros(3)
        self.R = np.eye(3)
        self.vl = np.zeros(3)
        self.w = np.zeros(3)
        self.S = np.zeros((3, 6))
        self.K = np.zeros((3, 6))
        self.tmp = np.zeros((3, model.state.nv))
        self.d3 = np.arange(3)
        self.da0_local_dx = np.zeros((3, model.state.ndx))
        self.dp = np.zeros(3)
        self.dp_local = np.zeros(3)


class ContactModel6D(_FrameContact):
    """Crocoddyl's ``ContactModel6D(state, id, pref, type, nu=state.nv, gains=[0, 0])``.

    Parameters
    ----------
    pref : pinocchio.SE3
        Contact placement used by the Baumgarte position term.
    state, id, type, nu, gains
        As for :class:`ContactModel3D`.
    """

    _rigid_kind = pin.ContactType.CONTACT_6D

    def __init__(
        self,
        state: StateAbstract,
        id: int | str,
        pref: pin.SE3,
        type: pin.ReferenceFrame,
        nu: int | None = None,
        gains: np.ndarray | None = None,
    ) -> None:
        super().__init__(state, id, pref, type, 6, nu, gains)

    @property
    def reference(self) -> pin.SE3:
        """Contact placement ``pref`` (live: a change made in place is seen by the next evaluation)."""
        return self._pref

    @reference.setter
    def reference(self, value: pin.SE3) -> None:
        if not isinstance(value, pin.SE3):
            raise ValueError(f"pref must be a pinocchio.SE3, got {type(value).__name__}")
        check_finite(value.homogeneous, "pref")
        as_rotation(value.rotation, "pref.rotation")
        self._pref = value.copy()
        touch(self)

    def compiled_reference(self, R: np.ndarray, p: np.ndarray) -> None:
        """This contact's lowering: its reference placement into ``R (3, 3)`` and ``p (3,)``."""
        R[:] = self._pref.rotation
        p[:] = self._pref.translation

    def _reference_placement(self) -> pin.SE3:
        return self._pref

    def createData(self, data: pin.Data) -> "ContactData6D":
        return ContactData6D(self, data)

    def calc(self, data: "ContactData6D", x: np.ndarray) -> None:
        model, pd, fid = self.state.pinocchio, data.pinocchio, self.id
        data.fJf[:] = frame_jacobian(model, pd, fid, _LOCAL)
        v = data.v = pin.getFrameVelocity(model, pd, fid, _LOCAL)
        a0l = data.a0_local
        a0l[:] = pin.getFrameAcceleration(model, pd, fid, _LOCAL).vector
        data.drift_local[:] = a0l
        kp, kd = self._gains
        oMf = pd.oMf[fid]
        if kp != 0.0:
            data.rMf = self._pref.actInv(oMf)
            a0l += kp * pin.log6(data.rMf).vector
        if kd != 0.0:
            a0l += kd * v.vector
        if self.type == _LOCAL:
            data.Jc[:] = data.fJf
            data.a0[:] = a0l
        else:
            R = oMf.rotation
            np.dot(R, data.fJf[:3], out=data.Jc[:3])
            np.dot(R, data.fJf[3:], out=data.Jc[3:])
            np.dot(R, a0l[:3], out=data.a0[:3])
            np.dot(R, a0l[3:], out=data.a0[3:])

    def calcDiff(self, data: "ContactData6D", x: np.ndarray) -> None:
        model, pd, fid, nv = self.state.pinocchio, data.pinocchio, self.id, self.state.nv
        vdq, adq, adv, ada = pin.getFrameAccelerationDerivatives(model, pd, fid, _LOCAL)
        data.v_partial_dq[:], data.a_partial_dq[:], data.a_partial_dv[:], data.a_partial_da[:] = vdq, adq, adv, ada
        dq, dv = data.da0_local_dx[:, :nv], data.da0_local_dx[:, nv:]
        dq[:] = adq
        dv[:] = adv
        kp, kd = self._gains
        if kp != 0.0:
            dq += kp * (pin.Jlog6(data.rMf) @ data.fJf)
        if kd != 0.0:
            dq += kd * vdq
            dv += kd * data.fJf
        if self.type == _LOCAL:
            data.da0_dx[:] = data.da0_local_dx
        else:
            R = pd.oMf[fid].rotation
            Ja = data.fJf[3:]
            acc = pin.getFrameAcceleration(model, pd, fid, _LOCAL).vector
            acc += data.a0_local - data.drift_local
            np.dot(R, data.da0_local_dx[:3], out=data.da0_dx[:3])
            np.dot(R, data.da0_local_dx[3:], out=data.da0_dx[3:])
            data.da0_dx[:3, :nv] -= (R @ _skew(acc[:3])) @ Ja
            data.da0_dx[3:, :nv] -= (R @ _skew(acc[3:])) @ Ja

    def __repr__(self) -> str:
        return f"ContactModel6D(id={self.id}, type={self.type}, gains={self._gains})"


class ContactData6D(ContactDataAbstract):
    """Data of :class:`ContactModel6D`; adds ``a0_local``, ``drift_local``, ``da0_local_dx`` and ``rMf``."""

    def __init__(self, model: ContactModel6D, data: pin.Data) -> None:
        super().__init__(model, data)
        self.a0_local = np.zeros(6)
        self.drift_local = np.zeros(6)
        self.da0_local_dx = np.zeros((6, model.state.ndx))
        self.rMf = pin.SE3.Identity()


class PointContactProjection:
    """What the 1D and 2D contacts share: a 3D point contact ``_point`` on their frame, evaluated into
    their data's ``point``, whose frame Jacobian, velocity and acceleration derivatives they expose."""

    _point: ContactModel3D

    def _point_calc(self, data: ContactDataAbstract, x: np.ndarray) -> ContactData3D:
        point = data.point
        self._point.calc(point, x)
        data.fJf[:] = point.fJf
        data.v = point.v
        return point

    def _point_calcDiff(self, data: ContactDataAbstract, x: np.ndarray) -> ContactData3D:
        point = data.point
        self._point.calcDiff(point, x)
        data.v_partial_dq[:] = point.v_partial_dq
        data.a_partial_dq[:] = point.a_partial_dq
        data.a_partial_dv[:] = point.a_partial_dv
        data.a_partial_da[:] = point.a_partial_da
        return point
