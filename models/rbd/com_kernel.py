"""Compiled centre of mass of a lowered model and its Jacobian (Pinocchio's ``centerOfMass`` and
``jacobianCenterOfMass``).

With ``m_i`` the body masses (joints ``1 .. njoints - 1``), ``c_i = p_i + R_i com_i`` their world centres of
mass and ``m = Σ m_i``::

    com = Σ m_i c_i / m,     Jcom_k = (m_j s_v + s_ω × h_j) / m

for a dof ``k`` of joint ``j`` with world column ``s = oS_k = [s_v; s_ω]`` (the velocity of a point ``c`` moved by
``s`` is ``s_v + s_ω × c``), ``m_j = Σ m_i`` and ``h_j = Σ m_i c_i`` over the subtree of ``j``.  The subtree
sums are taken per joint (``O(njoints²)`` flops, no scratch).  Shapes: ``com_out (3,)``, ``Jcom_out (3, nv)``.

The centroidal momentum (Pinocchio's ``computeCentroidalMomentum``, ``h = (h_l, h_ω)`` at the centre of mass, world
axes) from the world momentum ``H = Σ oI_i ov_i`` at the origin: ``h_l = H_l``, ``h_ω = H_ω - com × H_l``.  A tangent
of dof ``k`` of joint ``j`` (``s = oS_k``) moves the subtree of ``j`` (``d oI_i = s ×* oI_i - oI_i s×``, ``d ov_i =
s × (ov_i - ov_λ(j))``), so ``∂H/∂q_k = s ×* H_j - Ic_j (s × ov_λ(j))`` and ``∂H/∂v_k = Ic_j s`` with ``H_j`` the
subtree's momentum and ``Ic_j`` its composite inertia; then ``∂h_ω = ∂H_ω - Jcom_k × H_l - com × ∂H_l``
(Pinocchio's ``dh_dq`` and ``Ag``).  Shape ``h_out (6,)``, ``dh_out (6, 2 nv)``.  The linear part alone,
``∂H_l/∂q_k = s_ω × L_j - (m_j y_l - h_j × y_ω)`` with ``y = s × ov_λ(j)``, ``L_j`` the subtree's linear momentum,
``m_j``, ``h_j`` its mass and first moment, is the derivative of the centre of mass velocity ``Jcom v = H_l / m``
at a fixed ``v`` (Pinocchio's ``getCenterOfMassVelocityDerivatives``; :func:`com_velocity_derivatives`).
"""

from __future__ import annotations

import math

import numpy as np

from crocopy.kernels import uncounted

from .dynamics_kernel import composite_inertias
from .lowering import RigidBodyModel, RigidBodyWorkspace
from .spatial import fcross, get6, mcross


@uncounted
def _subtree_moment(rb, ws, j):
    """``(m_j, h_j)``: mass and first moment ``Σ m_i c_i`` (world) of the subtree of joint ``j``."""
    oR, op, com, mass = ws.oR, ws.op, rb.com, rb.mass
    m = hx = hy = hz = 0.0
    for i in range(j, rb.subtree_end[j]):
        if i == 0:
            continue
        mi = mass[i]
        m += mi
        hx += mi * (op[i, 0] + oR[i, 0, 0] * com[i, 0] + oR[i, 0, 1] * com[i, 1] + oR[i, 0, 2] * com[i, 2])
        hy += mi * (op[i, 1] + oR[i, 1, 0] * com[i, 0] + oR[i, 1, 1] * com[i, 1] + oR[i, 1, 2] * com[i, 2])
        hz += mi * (op[i, 2] + oR[i, 2, 0] * com[i, 0] + oR[i, 2, 1] * com[i, 1] + oR[i, 2, 2] * com[i, 2])
    return m, hx, hy, hz


@uncounted
def center_of_mass(rb: RigidBodyModel, ws: RigidBodyWorkspace, com_out: np.ndarray, Jcom_out: np.ndarray) -> None:
    """``com_out (3,)``: the world centre of mass; ``Jcom_out (3, nv)``: its Jacobian (after
    :func:`~.dynamics_kernel.forward_kinematics`)."""
    m, hx, hy, hz = _subtree_moment(rb, ws, 0)
    inv = 1.0 / m if m > 0.0 else math.nan  # a massless robot: NaN, as Pinocchio's centerOfMass
    com_out[0], com_out[1], com_out[2] = hx * inv, hy * inv, hz * inv
    oS = ws.oS
    for j in range(1, rb.njoints):
        mj, hx, hy, hz = _subtree_moment(rb, ws, j)
        for k in range(rb.idx_v[j], rb.idx_v[j] + rb.nvj[j]):
            Jcom_out[0, k] = (mj * oS[k, 0] + oS[k, 4] * hz - oS[k, 5] * hy) * inv
            Jcom_out[1, k] = (mj * oS[k, 1] + oS[k, 5] * hx - oS[k, 3] * hz) * inv
            Jcom_out[2, k] = (mj * oS[k, 2] + oS[k, 3] * hy - oS[k, 4] * hx) * inv


@uncounted
def _subtree_momentum(rb, ws, j):
    """``Σ oI_i ov_i`` (world, at the origin) over the bodies of the subtree of joint ``j`` (a 6-tuple)."""
    oI, ov = ws.oI, ws.ov
    h0 = h1 = h2 = h3 = h4 = h5 = 0.0
    for i in range(max(j, 1), rb.subtree_end[j]):
        v = get6(ov, i)
        h0 += _row(oI, i, 0, v)
        h1 += _row(oI, i, 1, v)
        h2 += _row(oI, i, 2, v)
        h3 += _row(oI, i, 3, v)
        h4 += _row(oI, i, 4, v)
        h5 += _row(oI, i, 5, v)
    return h0, h1, h2, h3, h4, h5


@uncounted
def _at_com(c, m):
    """A world momentum ``m`` (at the origin) at the point ``c``: ``(m_l, m_ω - c × m_l)``."""
    return (m[0], m[1], m[2], m[3] - (c[1] * m[2] - c[2] * m[1]), m[4] - (c[2] * m[0] - c[0] * m[2]),
            m[5] - (c[0] * m[1] - c[1] * m[0]))


@uncounted
def centroidal_momentum(rb: RigidBodyModel, ws: RigidBodyWorkspace, com_out: np.ndarray, Jcom_out: np.ndarray,
                        h_out: np.ndarray) -> None:
    """``h_out (6,)``: the centroidal momentum (module docstring), with the centre of mass and its Jacobian into
    ``com_out``, ``Jcom_out`` (after :func:`~.dynamics_kernel.forward_kinematics` at ``(q, v)``)."""
    center_of_mass(rb, ws, com_out, Jcom_out)
    h = _at_com(com_out, _subtree_momentum(rb, ws, 0))
    for r in range(6):
        h_out[r] = h[r]


@uncounted
def centroidal_momentum_derivatives(rb: RigidBodyModel, ws: RigidBodyWorkspace, com: np.ndarray, Jcom: np.ndarray,
                                    dh_out: np.ndarray) -> None:
    """``dh_out (6, 2 nv) = [∂h/∂q, ∂h/∂v]`` of :func:`centroidal_momentum` (module docstring; ``com``, ``Jcom`` as it
    leaves them; ``ws.oIc`` is written, which every other user recomputes)."""
    composite_inertias(rb, ws)
    oS, ov, oIc, nv = ws.oS, ws.ov, ws.oIc, rb.nv
    H = _subtree_momentum(rb, ws, 0)
    for j in range(1, rb.njoints):
        Hj = _subtree_momentum(rb, ws, j)
        vp = get6(ov, rb.parent[j])
        for k in range(rb.idx_v[j], rb.idx_v[j] + rb.nvj[j]):
            s = get6(oS, k)
            w = mcross(s, vp)
            f = fcross(s, Hj)
            dq = (f[0] - _row(oIc, j, 0, w), f[1] - _row(oIc, j, 1, w), f[2] - _row(oIc, j, 2, w),
                  f[3] - _row(oIc, j, 3, w), f[4] - _row(oIc, j, 4, w), f[5] - _row(oIc, j, 5, w))
            dv = (_row(oIc, j, 0, s), _row(oIc, j, 1, s), _row(oIc, j, 2, s), _row(oIc, j, 3, s), _row(oIc, j, 4, s),
                  _row(oIc, j, 5, s))
            dq = _at_com(com, dq)
            dv = _at_com(com, dv)
            jx, jy, jz = Jcom[0, k], Jcom[1, k], Jcom[2, k]
            for r in range(3):
                dh_out[r, k] = dq[r]
                dh_out[r, nv + k] = dv[r]
            dh_out[3, k] = dq[3] - (jy * H[2] - jz * H[1])
            dh_out[4, k] = dq[4] - (jz * H[0] - jx * H[2])
            dh_out[5, k] = dq[5] - (jx * H[1] - jy * H[0])
            for r in range(3, 6):
                dh_out[r, nv + k] = dv[r]


@uncounted
def _row(A, j, r, m):
    """``A[j, r] · m`` (a row of joint ``j``'s 6×6 matrix times a 6-tuple)."""
    return A[j, r, 0] * m[0] + A[j, r, 1] * m[1] + A[j, r, 2] * m[2] + A[j, r, 3] * m[3] + A[j, r, 4] * m[4] + \
        A[j, r, 5] * m[5]


@uncounted
def com_velocity_derivatives(rb: RigidBodyModel, ws: RigidBodyWorkspace, dvc_out: np.ndarray) -> None:
    """``dvc_out[:, :nv] = ∂(Jcom(q) v)/∂q`` at the velocity ``v`` of the kinematics in ``ws`` (module docstring;
    after :func:`~.dynamics_kernel.forward_kinematics` at ``(q, v)``)."""
    oS, ov = ws.oS, ws.ov
    m = _subtree_moment(rb, ws, 0)[0]
    inv = 1.0 / m if m > 0.0 else math.nan
    for j in range(1, rb.njoints):
        mj, hx, hy, hz = _subtree_moment(rb, ws, j)
        L = _subtree_momentum(rb, ws, j)
        vp = get6(ov, rb.parent[j])
        for k in range(rb.idx_v[j], rb.idx_v[j] + rb.nvj[j]):
            s = get6(oS, k)
            y = mcross(s, vp)
            dvc_out[0, k] = (s[4] * L[2] - s[5] * L[1] - (mj * y[0] - (hy * y[5] - hz * y[4]))) * inv
            dvc_out[1, k] = (s[5] * L[0] - s[3] * L[2] - (mj * y[1] - (hz * y[3] - hx * y[5]))) * inv
            dvc_out[2, k] = (s[3] * L[1] - s[4] * L[0] - (mj * y[2] - (hx * y[4] - hy * y[3]))) * inv
