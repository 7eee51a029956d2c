"""Point (3D) and rigid-frame (6D) impulses.

With ``J = (Jl; Ja)`` the LOCAL frame Jacobian and ``R`` the frame orientation:

- 3D: ``Jc = Jl`` (LOCAL) or ``R Jl`` (LOCAL_WORLD_ALIGNED);
- 6D: ``Jc = J`` (LOCAL) or ``(R Jl; R Ja)`` (LOCAL_WORLD_ALIGNED).

``dv0_local_dq`` is the derivative of the LOCAL frame velocity ``J(q) w`` (``getFrameVelocityDerivatives``);
in LOCAL_WORLD_ALIGNED, ``dv0_dq = R dv0_local_dq - R [J w]× Ja`` (per 3-block).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from crocopy.state import StateAbstract

from .force_base import frame_id
from .impulse_base import ImpulseDataAbstract, ImpulseModelAbstract
from .residuals_frame import frame_jacobian

_LOCAL = pin.LOCAL
_skew = pin.skew


class _ImpulseFrame(ImpulseModelAbstract):
    """An impulse of dimension ``_frame_nc`` (3: point, 6: rigid frame) on a frame.

    Parameters
    ----------
    state : StateMultibody
        Multibody state.
    frame : int or str
        Impulse frame (index or name).
    type : pinocchio.ReferenceFrame
        ``pinocchio.LOCAL`` (default), ``pinocchio.LOCAL_WORLD_ALIGNED`` or ``pinocchio.WORLD`` (the same
        as ``LOCAL_WORLD_ALIGNED``, as in Crocoddyl).
    """

    _frame_nc: int
    _data_class: type

    def __init__(self, state: StateAbstract, frame: int | str, type: pin.ReferenceFrame = pin.LOCAL) -> None:
        fid = frame_id(state, frame, "frame")
        super().__init__(state, type, self._frame_nc)
        self.id = fid

    def createData(self, data: pin.Data) -> ImpulseDataAbstract:
        return self._data_class(self, data)

    def calc(self, data: ImpulseDataAbstract, x: np.ndarray) -> None:
        model, pd, fid = self.state.pinocchio, data.pinocchio, self.id
        data.fJf[:] = frame_jacobian(model, pd, fid, _LOCAL)
        nc = self.nc
        if self.type == _LOCAL:
            data.Jc[:] = data.fJf[:nc]
        else:
            R = pd.oMf[fid].rotation
            for k in range(0, nc, 3):
                np.dot(R, data.fJf[k:k + 3], out=data.Jc[k:k + 3])

    def calcDiff(self, data: ImpulseDataAbstract, x: np.ndarray) -> None:
        model, pd, fid, nc = self.state.pinocchio, data.pinocchio, self.id, self.nc
        vdq, vdv = pin.getFrameVelocityDerivatives(model, pd, fid, _LOCAL)
        data.v_partial_dq[:] = vdq
        data.v_partial_dv[:] = vdv
        data.dv0_local_dq[:] = vdq[:nc]
        if self.type == _LOCAL:
            data.dv0_dq[:] = data.dv0_local_dq
            return
        R = pd.oMf[fid].rotation
        Ja = data.fJf[3:]
        w = pin.getFrameVelocity(model, pd, fid, _LOCAL).vector
        np.dot(R, vdq[:3] - _skew(w[:3]) @ Ja, out=data.dv0_dq[:3])
        if nc == 6:
            np.dot(R, vdq[3:] - _skew(w[3:]) @ Ja, out=data.dv0_dq[3:])


class ImpulseData3D(ImpulseDataAbstract):
    """Data of :class:`ImpulseModel3D` (the fields of :class:`~crocopy.models.impulse_base.ImpulseDataAbstract`)."""


class ImpulseData6D(ImpulseDataAbstract):
    """Data of :class:`ImpulseModel6D` (the fields of :class:`~crocopy.models.impulse_base.ImpulseDataAbstract`)."""


class ImpulseModel3D(_ImpulseFrame):
    """Crocoddyl's ``ImpulseModel3D(state, frame, type=pinocchio.LOCAL)``: a point impulse (``nc = 3``)."""

    _frame_nc = 3
    _data_class = ImpulseData3D


class ImpulseModel6D(_ImpulseFrame):
    """Crocoddyl's ``ImpulseModel6D(state, frame, type=pinocchio.LOCAL)``: a rigid-frame impulse (``nc = 6``)."""

    _frame_nc = 6
    _data_class = ImpulseData6D
