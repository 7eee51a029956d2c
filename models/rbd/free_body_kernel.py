"""One body on a free flyer (a quadrotor): its dynamics and RNEA derivatives in the joint frame.

When the lowered model is a single body on a free flyer (:func:`free_body`), :mod:`.dynamics_kernel` writes them in the
body's joint frame, where ``S = I`` and ``v`` is the body's twist: ``M = I + diag(armature)`` is constant (``I`` the
body's spatial inertia there), ``τ = I (a + ag) + v ×* (I v)`` with ``ag = X⁻¹ (-g)`` the world's ``-g`` read in the
body frame ``oM_1 = X``.  A tangent ``δ`` moves ``X`` to ``X exp(δ)``, so ``δag = ag × δ``: ``∂τ/∂q = I (ag ×)`` and
column ``j`` of ``∂τ/∂v`` is ``e_j ×* (I v) + v ×* (I e_j)``.  The world kinematics of
:func:`~.dynamics_kernel.forward_kinematics` stay as the other kernels read them; conventions are those of
:mod:`.dynamics_kernel` (motions ``[linear; angular]``, :mod:`.spatial`).  Tests: ``tests/test_rbd_free_body.py``
(Pinocchio, with a joint placement, an armature and a 6D gravity) and iris in ``tests/test_rbd_dynamics.py``.
"""

from __future__ import annotations

from crocopy.kernels import uncounted

from .joint_types import FREEFLYER
from .lowering import RigidBodyModel
from .spatial import fcross, get6, mcross, plus


@uncounted
def free_body(rb: RigidBodyModel) -> bool:
    """Whether the model is one body on a free flyer (a quadrotor): its dynamics are then written in the joint frame."""
    return rb.njoints == 2 and rb.jtype[1] == FREEFLYER


@uncounted
def _body_inertia(mass, com, Ic, I):
    """``I (6, 6)``: the spatial inertia of body 1 in its joint frame, ``[[m, -m[c]x], [m[c]x, Ic - m [c]x [c]x]]``
    (``mass``, ``com``, ``Ic``: the lowered model's per-body arrays)."""
    m = mass[1]
    cx, cy, cz = com[1, 0], com[1, 1], com[1, 2]
    for r in range(3):
        for c in range(3):
            I[r, c] = m if r == c else 0.0
            I[3 + r, 3 + c] = Ic[1, r, c]
    I[3, 0], I[3, 1], I[3, 2] = 0.0, -m * cz, m * cy
    I[4, 0], I[4, 1], I[4, 2] = m * cz, 0.0, -m * cx
    I[5, 0], I[5, 1], I[5, 2] = -m * cy, m * cx, 0.0
    for r in range(3):
        for c in range(3):
            I[c, 3 + r] = I[3 + r, c]
    I[3, 3] += m * (cy * cy + cz * cz)
    I[4, 4] += m * (cx * cx + cz * cz)
    I[5, 5] += m * (cx * cx + cy * cy)
    I[3, 4] -= m * cx * cy
    I[4, 3] -= m * cx * cy
    I[3, 5] -= m * cx * cz
    I[5, 3] -= m * cx * cz
    I[4, 5] -= m * cy * cz
    I[5, 4] -= m * cy * cz


@uncounted
def _in_body(R, p, m):
    """The world motion ``m`` (6-tuple) read in body 1's frame ``oM_1 = (R, p)`` (the workspace's ``oR``, ``op``):
    ``X⁻¹ m = [Rᵀ(m_v - p × m_ω); Rᵀ m_ω]``."""
    vx, vy, vz, wx, wy, wz = m
    px, py, pz = p[1, 0], p[1, 1], p[1, 2]
    vx, vy, vz = vx - (py * wz - pz * wy), vy - (pz * wx - px * wz), vz - (px * wy - py * wx)
    return (
        R[1, 0, 0] * vx + R[1, 1, 0] * vy + R[1, 2, 0] * vz,
        R[1, 0, 1] * vx + R[1, 1, 1] * vy + R[1, 2, 1] * vz,
        R[1, 0, 2] * vx + R[1, 1, 2] * vy + R[1, 2, 2] * vz,
        R[1, 0, 0] * wx + R[1, 1, 0] * wy + R[1, 2, 0] * wz,
        R[1, 0, 1] * wx + R[1, 1, 1] * wy + R[1, 2, 1] * wz,
        R[1, 0, 2] * wx + R[1, 1, 2] * wy + R[1, 2, 2] * wz,
    )


@uncounted
def free_body_bias(mass, com, inertia, armature, g, oR, op, v, I, M, tau, oa) -> None:
    """The forward dynamics' terms of the module docstring (``v (6,)`` the body's twist): ``M = I + diag(armature)``,
    ``tau = b = I ag + v ×* (I v)`` and ``oa = -g`` (the world acceleration at zero joint acceleration, ``ov × ow
    = 0`` for the root): what the generic RNEA pass and CRBA leave in the workspace that later kernels read.  The
    lowered model's arrays (``mass``, ``com``, ``inertia``, ``armature``, the gravity ``g``) and the workspace's
    (``oR``, ``op``, the scratch ``I = tmp``, ``M``, ``tau``, ``oa``) come one by one, not as the model and the
    workspace (a kernel receiving those copies all their arrays' descriptors at every call)."""
    _body_inertia(mass, com, inertia, I)
    ag = _in_body(oR, op, (-g[0], -g[1], -g[2], -g[3], -g[4], -g[5]))
    vv = (v[0], v[1], v[2], v[3], v[4], v[5])
    b = plus(_times6(I, ag), fcross(vv, _times6(I, vv)))
    for r in range(6):
        for c in range(6):
            M[r, c] = I[r, c]
        M[r, r] += armature[r]
        tau[r] = b[r]
        oa[0, r] = -g[r]
        oa[1, r] = -g[r]


@uncounted
def _times6(A, t):
    """``A (6, 6) t`` of a 6-tuple ``t``, as a 6-tuple."""
    return (
        A[0, 0] * t[0] + A[0, 1] * t[1] + A[0, 2] * t[2] + A[0, 3] * t[3] + A[0, 4] * t[4] + A[0, 5] * t[5],
        A[1, 0] * t[0] + A[1, 1] * t[1] + A[1, 2] * t[2] + A[1, 3] * t[3] + A[1, 4] * t[4] + A[1, 5] * t[5],
        A[2, 0] * t[0] + A[2, 1] * t[1] + A[2, 2] * t[2] + A[2, 3] * t[3] + A[2, 4] * t[4] + A[2, 5] * t[5],
        A[3, 0] * t[0] + A[3, 1] * t[1] + A[3, 2] * t[2] + A[3, 3] * t[3] + A[3, 4] * t[4] + A[3, 5] * t[5],
        A[4, 0] * t[0] + A[4, 1] * t[1] + A[4, 2] * t[2] + A[4, 3] * t[3] + A[4, 4] * t[4] + A[4, 5] * t[5],
        A[5, 0] * t[0] + A[5, 1] * t[1] + A[5, 2] * t[2] + A[5, 3] * t[3] + A[5, 4] * t[4] + A[5, 5] * t[5],
    )


@uncounted
def free_body_derivatives(mass, com, inertia, g, oR, op, ov, I, dtau_dq_out, dtau_dv_out) -> None:
    """``∂τ/∂q = I (ag ×)`` and ``∂τ/∂v`` (columns ``e_j ×* (I v) + v ×* (I e_j)``, ``v = X⁻¹ ov``) into ``(6, 6)``
    arrays, after the RNEA pass of :func:`~.dynamics_kernel.rnea_derivatives` (module docstring); the arrays one by
    one as in :func:`free_body_bias` (``I``: the workspace's scratch ``tmp``)."""
    _body_inertia(mass, com, inertia, I)
    ag = _in_body(oR, op, (-g[0], -g[1], -g[2], -g[3], -g[4], -g[5]))
    v = _in_body(oR, op, get6(ov, 1))
    h = _times6(I, v)
    for j in range(6):
        e = (1.0 if j == 0 else 0.0, 1.0 if j == 1 else 0.0, 1.0 if j == 2 else 0.0,
             1.0 if j == 3 else 0.0, 1.0 if j == 4 else 0.0, 1.0 if j == 5 else 0.0)
        dq = _times6(I, mcross(ag, e))
        dv = plus(fcross(e, h), fcross(v, _column6(I, j)))
        for r in range(6):
            dtau_dq_out[r, j] = dq[r]
            dtau_dv_out[r, j] = dv[r]


@uncounted
def _column6(A, j):
    """Column ``j`` of a ``(6, 6)`` array as a tuple."""
    return A[0, j], A[1, j], A[2, j], A[3, j], A[4, j], A[5, j]
