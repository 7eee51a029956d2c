"""Joint type codes of a lowered model (``RigidBodyModel.jtype``), shared by the dynamics and Lie-group kernels.

=================  =====  ====  ====  ==========================================================
code               value  nq    nv    Pinocchio joint
=================  =====  ====  ====  ==========================================================
``FREEFLYER``      0      7     6     ``JointModelFreeFlyer`` (``q = [p, quaternion xyzw]``, SE(3))
``REVOLUTE``       1      1     1     ``JointModelRX/RY/RZ``, ``JointModelRevoluteUnaligned``
``REVOLUTE_UB``    2      2     1     ``JointModelRUBX/RUBY/RUBZ``, ``JointModelRevoluteUnboundedUnaligned``
                                       (``q = [cos θ, sin θ]``)
``PRISMATIC``      3      1     1     ``JointModelPX/PY/PZ``, ``JointModelPrismaticUnaligned``
``SPHERICAL``      4      4     3     ``JointModelSpherical`` (``q`` a quaternion xyzw, SO(3))
``PLANAR``         5      4     3     ``JointModelPlanar`` (``q = [x, y, cos θ, sin θ]``, SE(2); ``v = [vx, vy, ω]``)
``HELICAL``        6      1     1     ``JointModelHX/HY/HZ``, ``JointModelHelicalUnaligned`` (``θ`` about the
                                       axis and ``pitch · θ`` along it)
``TRANSLATION``    7      3     3     ``JointModelTranslation``
=================  =====  ====  ====  ==========================================================

In the joint's own frame the motion subspace ``S`` is constant: the free flyer's and the translation's translations
are the frame's axes, so are the spherical joint's rotations, the planar joint's are ``x``, ``y`` (translations) and
``z`` (rotation), a revolute joint's ``[0; a]``, a prismatic joint's ``[a; 0]`` and a helical joint's ``[pitch a; a]``.
The axis ``a`` of a revolute, prismatic or helical joint is stored apart (``RigidBodyModel.axis[:, :3]``, a helical
joint's pitch in ``axis[:, 3]``), so aligned and unaligned joints share a code.  The axis of an unaligned joint, and a
helical joint's axis and pitch, are read from its motion subspace ``S`` (Pinocchio's joint data after ``calc``), since
Pinocchio's binding exposes ``axis`` on some unaligned joints only (not on ``JointModelRevoluteUnboundedUnaligned``)
and a model's joints (the generic ``JointModel``) have no ``pitch``.  Every other joint type
(spherical ZYX, universal, ellipsoid, composite, mimic: their ``S`` moves with ``q``) is not lowered:
:class:`NotLowerable`, and the node keeps its Python path.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

FREEFLYER = 0
REVOLUTE = 1
REVOLUTE_UB = 2
PRISMATIC = 3
SPHERICAL = 4
PLANAR = 5
HELICAL = 6
TRANSLATION = 7

NQ = {FREEFLYER: 7, REVOLUTE: 1, REVOLUTE_UB: 2, PRISMATIC: 1, SPHERICAL: 4, PLANAR: 4, HELICAL: 1, TRANSLATION: 3}
NV = {FREEFLYER: 6, REVOLUTE: 1, REVOLUTE_UB: 1, PRISMATIC: 1, SPHERICAL: 3, PLANAR: 3, HELICAL: 1, TRANSLATION: 3}

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
    "JointModelHelicalUnaligned": HELICAL,
    "JointModelHX": HELICAL,  # the variant's binding has no ``pitch``: read it from ``S`` too
    "JointModelHY": HELICAL,
    "JointModelHZ": HELICAL,
}
_WHOLE = {
    "JointModelFreeFlyer": FREEFLYER,
    "JointModelSpherical": SPHERICAL,
    "JointModelPlanar": PLANAR,
    "JointModelTranslation": TRANSLATION,
}


class NotLowerable(ValueError):
    """A Pinocchio model the compiled kernels cannot represent (the message names the joint and its type;
    ``reason``, a short category such as ``"joint type JointModelSphericalZYX"``)."""

    def __init__(self, message: str, reason: str = "joint tree order") -> None:
        super().__init__(message)
        self.reason = reason


def joint_arrays(model: object) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``(jtype, idx_q, idx_v, axis)`` of a ``pinocchio.Model``; shapes ``(njoints,)`` ×3 and ``(njoints, 4)`` (the
    unit axis of a revolute, prismatic or helical joint, then a helical joint's pitch; zeros for the other joints).

    Entry 0 is the universe (``jtype[0] = -1``).  Raises :class:`NotLowerable` for any other joint type.
    """
    njoints = model.njoints
    jtype = np.full(njoints, -1, dtype=np.int64)
    idx_q = np.zeros(njoints, dtype=np.int64)
    idx_v = np.zeros(njoints, dtype=np.int64)
    axis = np.zeros((njoints, 4))
    for i in range(1, njoints):
        joint = model.joints[i]
        kind = joint.shortname()
        if kind in _WHOLE:
            jtype[i] = _WHOLE[kind]
        elif kind in _ALIGNED:
            jtype[i], k = _ALIGNED[kind]
            axis[i, k] = 1.0
        elif kind in _UNALIGNED:
            jtype[i] = _UNALIGNED[kind]
            axis[i] = _unaligned_axis(model, joint, jtype[i])
        else:
            raise NotLowerable(f"joint {model.names[i]!r} is a {kind}, which the compiled kernels do not support",
                               f"joint type {kind}")
        idx_q[i], idx_v[i] = joint.idx_q, joint.idx_v
    return jtype, idx_q, idx_v, axis


def _unaligned_axis(model: object, joint: object, kind: int) -> np.ndarray:
    """``[a, pitch] (4,)``: the unit axis ``a`` of an unaligned revolute, prismatic or helical joint and a helical
    joint's pitch (0 otherwise), from its motion subspace ``S`` at the neutral configuration (``[a; 0]``, ``[0; a]``
    or ``[pitch a; a]``)."""
    jdata = joint.createData()
    joint.calc(jdata, pin.neutral(model))
    S = np.asarray(jdata.S, dtype=float).reshape(6)
    if kind == PRISMATIC:
        return np.append(S[:3], 0.0)
    return np.append(S[3:], S[:3] @ S[3:] if kind == HELICAL else 0.0)
