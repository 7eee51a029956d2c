"""Joint type codes of a lowered model (``RigidBodyModel.jtype``), shared by the dynamics and Lie-group kernels.

=================  =====  ====  ====  ==========================================================
code               value  nq    nv    Pinocchio joint
=================  =====  ====  ====  ==========================================================
``FREEFLYER``      0      7     6     ``JointModelFreeFlyer`` (``q = [p, quaternion xyzw]``, SE(3))
``REVOLUTE``       1      1     1     ``JointModelRX/RY/RZ``, ``JointModelRevoluteUnaligned``
``REVOLUTE_UB``    2      2     1     ``JointModelRUBX/RUBY/RUBZ``, ``JointModelRevoluteUnboundedUnaligned``
                                       (``q = [cos θ, sin θ]``)
``PRISMATIC``      3      1     1     ``JointModelPX/PY/PZ``, ``JointModelPrismaticUnaligned``
=================  =====  ====  ====  ==========================================================

The axis of a revolute or prismatic joint is stored apart (``RigidBodyModel.axis``), so aligned and
unaligned joints share a code.  The axis of an unaligned joint is read from its motion subspace ``S``
(Pinocchio's joint data after ``calc``: ``S = [0; axis]`` for a revolute, ``[axis; 0]`` for a prismatic joint),
since Pinocchio's binding exposes ``axis`` on some unaligned joints only (not on
``JointModelRevoluteUnboundedUnaligned``).  Every other joint type (spherical, spherical ZYX, planar,
translation, helical, universal, ellipsoid, composite, mimic) is not lowered: :class:`NotLowerable`, and the
node keeps its Python path.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

FREEFLYER = 0
REVOLUTE = 1
REVOLUTE_UB = 2
PRISMATIC = 3

NQ = {FREEFLYER: 7, REVOLUTE: 1, REVOLUTE_UB: 2, PRISMATIC: 1}
NV = {FREEFLYER: 6, REVOLUTE: 1, REVOLUTE_UB: 1, PRISMATIC: 1}

_ALIGNED = {
    "JointModelRX": (REVOLUTE, 0),
    "JointModelRY": (REVOLUTE, 1),
    "JointModelRZ": (REVOLUTE, 2),
    "JointModelRUBX": (REVOLUTE_UB, 0),
    "JointModelRUBY": (REVOLUTE_UB, 1),
    "JointModelRUBZ": (REVOLUTE_UB, 2),
    "JointModelPX": (PRISMATIC, 0),
    "JointModelPY": (PRISMATIC, 1),
    "JointModelPZ": (PRISMATIC, 2),
}
_UNALIGNED = {
    "JointModelRevoluteUnaligned": REVOLUTE,
    "JointModelRevoluteUnboundedUnaligned": REVOLUTE_UB,
    "JointModelPrismaticUnaligned": PRISMATIC,
}


class NotLowerable(ValueError):
    """A Pinocchio model the compiled kernels cannot represent (the message names the joint and its type;
    ``reason``, a short category such as ``"joint type JointModelSpherical"``)."""

    def __init__(self, message: str, reason: str = "joint tree order") -> None:
        super().__init__(message)
        self.reason = reason


def joint_arrays(model: object) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``(jtype, idx_q, idx_v, axis)`` of a ``pinocchio.Model``; shapes ``(njoints,)`` ×3 and ``(njoints, 3)``.

    Entry 0 is the universe (``jtype[0] = -1``).  Raises :class:`NotLowerable` for any other joint type.
    """
    njoints = model.njoints
    jtype = np.full(njoints, -1, dtype=np.int64)
    idx_q = np.zeros(njoints, dtype=np.int64)
    idx_v = np.zeros(njoints, dtype=np.int64)
    axis = np.zeros((njoints, 3))
    for i in range(1, njoints):
        joint = model.joints[i]
        kind = joint.shortname()
        if kind == "JointModelFreeFlyer":
            jtype[i] = FREEFLYER
        elif kind in _ALIGNED:
            jtype[i], k = _ALIGNED[kind]
            axis[i, k] = 1.0
        elif kind in _UNALIGNED:
            jtype[i] = _UNALIGNED[kind]
            axis[i] = _unaligned_axis(model, joint, jtype[i] == PRISMATIC)
        else:
            raise NotLowerable(f"joint {model.names[i]!r} is a {kind}, which the compiled kernels do not support",
                               f"joint type {kind}")
        idx_q[i], idx_v[i] = joint.idx_q, joint.idx_v
    return jtype, idx_q, idx_v, axis


def _unaligned_axis(model: object, joint: object, prismatic: bool) -> np.ndarray:
    """The unit axis ``(3,)`` of an unaligned revolute or prismatic joint, from its motion subspace at the
    neutral configuration."""
    jdata = joint.createData()
    joint.calc(jdata, pin.neutral(model))
    S = np.asarray(jdata.S, dtype=float).reshape(6)
    return S[:3].copy() if prismatic else S[3:].copy()
