"""Compiled rigid-body algorithms on a lowered model: kinematics, dynamics, their derivatives, frames.

Every function takes the lowered model ``rb`` (:class:`~.lowering.RigidBodyModel`) and a workspace ``ws``
(:class:`~.lowering.RigidBodyWorkspace`), writes into ``ws`` and the ``*_out`` arrays, allocates nothing,
and is callable from Python and from other compiled functions.  Shapes: ``q (nq,)``, ``v a tau (nv,)``.

Conventions (Pinocchio's).  A spatial motion is ``[linear; angular]``, a force ``[force; torque]``.  All
quantities are expressed in the world frame at the world origin.  For joint ``i`` with parent ``λ(i)``::

    oM_i  = oM_λ(i) · jointPlacement_i · M_J(q_i)          (R_i, p_i)
    oS_i  = oX_i S_i                                       world motion subspace columns (one per dof)
    ov_i  = ov_λ(i) + oS_i v_i
    oa_i  = oa_λ(i) + oS_i a_i + ov_i × oS_i v_i,          oa_0 = -gravity
    f_i   = oI_i oa_i + ov_i ×* (oI_i ov_i),               F_i = f_i + Σ_children F_c
    τ_i   = oS_iᵀ F_i + armature_i a_i                     (RNEA)
    M     = CRBA (composite inertias) + diag(armature),  L Lᵀ = M
    a     = M⁻¹ (τ - RNEA(q, v, 0))                        (forward dynamics)

where ``m × n = [m_ω × n_v + m_v × n_ω; m_ω × n_ω]`` and ``m ×* f = [m_ω × f_v; m_ω × f_ω + m_v × f_v]``.

Derivatives.  A configuration is perturbed in the joint's local frame, ``M_J(q ⊕ δ) = M_J(q) exp(S δ)``, so a
tangent ``δ_k`` of dof ``k`` of joint ``j`` (world column ``s = oS_k``) moves every placement of the subtree of
``j`` as ``d oX_i = s × oX_i``: ``d oS_i = s × oS_i``, ``d (oI_i m) = s ×* (oI_i m) - oI_i (s × m)``.
:func:`dynamics_derivatives` propagates these tangents through the recursions above (forward mode, one dof
at a time over its subtree; cost ``O(nv · subtree)``); the ancestors of ``j`` see ``d τ_l = oS_lᵀ dF_j``.
As in Pinocchio (4.0 and 4.1, measured), RNEA and CRBA include the armature, so ``∂τ/∂a = M``.

Frames.  ``reference`` is ``int(pin.WORLD) = 0``, ``int(pin.LOCAL) = 1`` or ``int(pin.LOCAL_WORLD_ALIGNED) = 2``.
A world motion ``m`` read in frame ``f`` (``oM_f = (R, p)``) is ``[Rᵀ(m_v - p × m_ω); Rᵀ m_ω]`` (LOCAL) or
``[m_v - p × m_ω; m_ω]`` (LOCAL_WORLD_ALIGNED).
"""

from __future__ import annotations

import math

import numpy as np

from crocopy.kernels import compiled

from .joint_types import FREEFLYER, PRISMATIC, REVOLUTE
from .lowering import RigidBodyModel, RigidBodyWorkspace

WORLD = 0
LOCAL = 1
LOCAL_WORLD_ALIGNED = 2


@compiled
def _motion_cross_add(m, n, scale, out):
    """``out += scale · (m × n)`` (``out`` may alias ``m`` or ``n``)."""
    x = m[4] * n[2] - m[5] * n[1] + m[1] * n[5] - m[2] * n[4]
    y = m[5] * n[0] - m[3] * n[2] + m[2] * n[3] - m[0] * n[5]
    z = m[3] * n[1] - m[4] * n[0] + m[0] * n[4] - m[1] * n[3]
    wx = m[4] * n[5] - m[5] * n[4]
    wy = m[5] * n[3] - m[3] * n[5]
    wz = m[3] * n[4] - m[4] * n[3]
    out[0] += scale * x
    out[1] += scale * y
    out[2] += scale * z
    out[3] += scale * wx
    out[4] += scale * wy
    out[5] += scale * wz


@compiled
def _force_cross_add(m, f, scale, out):
    """``out += scale · (m ×* f)`` (``out`` may alias ``m`` or ``f``)."""
    x = m[4] * f[2] - m[5] * f[1]
    y = m[5] * f[0] - m[3] * f[2]
    z = m[3] * f[1] - m[4] * f[0]
    nx = m[4] * f[5] - m[5] * f[4] + m[1] * f[2] - m[2] * f[1]
    ny = m[5] * f[3] - m[3] * f[5] + m[2] * f[0] - m[0] * f[2]
    nz = m[3] * f[4] - m[4] * f[3] + m[0] * f[1] - m[1] * f[0]
    out[0] += scale * x
    out[1] += scale * y
    out[2] += scale * z
    out[3] += scale * nx
    out[4] += scale * ny
    out[5] += scale * nz


@compiled
def _inertia_add(inertia, m, scale, out):
    """``out += scale · inertia @ m`` for a 6x6 ``inertia`` (``out`` must not alias ``m``)."""
    for r in range(6):
        acc = 0.0
        for c in range(6):
            acc += inertia[r, c] * m[c]
        out[r] += scale * acc


@compiled
def _dot6(a, b):
    """``aᵀ b`` of two 6-vectors."""
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3] + a[4] * b[4] + a[5] * b[5]


@compiled
def _joint_transform(rb, i, q, R, p):
    """``M_J(q)`` of joint ``i`` into ``R (3, 3)``, ``p (3,)``."""
    kind = rb.jtype[i]
    iq = rb.idx_q[i]
    for r in range(3):
        p[r] = 0.0
        for c in range(3):
            R[r, c] = 1.0 if r == c else 0.0
    if kind == FREEFLYER:
        p[0], p[1], p[2] = q[iq], q[iq + 1], q[iq + 2]
        x, y, z, w = q[iq + 3], q[iq + 4], q[iq + 5], q[iq + 6]
        R[0, 0] = 1.0 - 2.0 * (y * y + z * z)
        R[0, 1] = 2.0 * (x * y - z * w)
        R[0, 2] = 2.0 * (x * z + y * w)
        R[1, 0] = 2.0 * (x * y + z * w)
        R[1, 1] = 1.0 - 2.0 * (x * x + z * z)
        R[1, 2] = 2.0 * (y * z - x * w)
        R[2, 0] = 2.0 * (x * z - y * w)
        R[2, 1] = 2.0 * (y * z + x * w)
        R[2, 2] = 1.0 - 2.0 * (x * x + y * y)
    elif kind == PRISMATIC:
        for r in range(3):
            p[r] = rb.axis[i, r] * q[iq]
    else:
        if kind == REVOLUTE:
            c, s = math.cos(q[iq]), math.sin(q[iq])
        else:  # REVOLUTE_UB: q = [cos θ, sin θ]
            c, s = q[iq], q[iq + 1]
        ax, ay, az = rb.axis[i, 0], rb.axis[i, 1], rb.axis[i, 2]
        t = 1.0 - c
        R[0, 0] = c + t * ax * ax
        R[0, 1] = t * ax * ay - s * az
        R[0, 2] = t * ax * az + s * ay
        R[1, 0] = t * ax * ay + s * az
        R[1, 1] = c + t * ay * ay
        R[1, 2] = t * ay * az - s * ax
        R[2, 0] = t * ax * az - s * ay
        R[2, 1] = t * ay * az + s * ax
        R[2, 2] = c + t * az * az


@compiled
def _world_inertia(rb, ws, i):
    """``ws.oI[i]``: the body inertia of joint ``i`` in the world frame at the origin (6x6)."""
    R = ws.oR[i]
    out = ws.oI[i]
    m = rb.mass[i]
    cx = ws.op[i, 0] + R[0, 0] * rb.com[i, 0] + R[0, 1] * rb.com[i, 1] + R[0, 2] * rb.com[i, 2]
    cy = ws.op[i, 1] + R[1, 0] * rb.com[i, 0] + R[1, 1] * rb.com[i, 1] + R[1, 2] * rb.com[i, 2]
    cz = ws.op[i, 2] + R[2, 0] * rb.com[i, 0] + R[2, 1] * rb.com[i, 1] + R[2, 2] * rb.com[i, 2]
    for r in range(3):
        for c in range(3):
            acc = 0.0
            for k in range(3):
                for n in range(3):
                    acc += R[r, k] * rb.inertia[i, k, n] * R[c, n]
            out[3 + r, 3 + c] = acc
            out[r, c] = m if r == c else 0.0
    # m [c]x in the lower-left block, its transpose (-m [c]x) upper-right, -m [c]x [c]x added to the inertia
    out[3, 0], out[3, 1], out[3, 2] = 0.0, -m * cz, m * cy
    out[4, 0], out[4, 1], out[4, 2] = m * cz, 0.0, -m * cx
    out[5, 0], out[5, 1], out[5, 2] = -m * cy, m * cx, 0.0
    for r in range(3):
        for c in range(3):
            out[c, 3 + r] = out[3 + r, c]
    out[3, 3] += m * (cy * cy + cz * cz)
    out[4, 4] += m * (cx * cx + cz * cz)
    out[5, 5] += m * (cx * cx + cy * cy)
    out[3, 4] -= m * cx * cy
    out[4, 3] -= m * cx * cy
    out[3, 5] -= m * cx * cz
    out[5, 3] -= m * cx * cz
    out[4, 5] -= m * cy * cz
    out[5, 4] -= m * cy * cz


@compiled
def forward_kinematics(rb: RigidBodyModel, ws: RigidBodyWorkspace, q: np.ndarray, v: np.ndarray) -> None:
    """``ws.oR, ws.op`` (``oMi``), ``ws.oS`` (world motion subspace), ``ws.ov``, ``ws.ow`` and ``ws.oI``."""
    for r in range(3):
        ws.op[0, r] = 0.0
        for c in range(3):
            ws.oR[0, r, c] = 1.0 if r == c else 0.0
    for r in range(6):
        ws.ov[0, r] = 0.0
        ws.ow[0, r] = 0.0
    RJ = ws.tmp[0:3, 0:3]
    A = ws.tmp[3:6, 0:3]
    pJ = ws.tmp[0, 3:6]
    for i in range(1, rb.njoints):
        par = rb.parent[i]
        _joint_transform(rb, i, q, RJ, pJ)
        Rp = ws.oR[par]
        for r in range(3):
            acc = ws.op[par, r]
            for c in range(3):
                acc += Rp[r, c] * rb.jp[i, c]
                x = 0.0
                for k in range(3):
                    x += Rp[r, k] * rb.jR[i, k, c]
                A[r, c] = x
            ws.op[i, r] = acc
        for r in range(3):
            for c in range(3):
                ws.oR[i, r, c] = A[r, 0] * RJ[0, c] + A[r, 1] * RJ[1, c] + A[r, 2] * RJ[2, c]
            ws.op[i, r] += A[r, 0] * pJ[0] + A[r, 1] * pJ[1] + A[r, 2] * pJ[2]
        R = ws.oR[i]
        px, py, pz = ws.op[i, 0], ws.op[i, 1], ws.op[i, 2]
        iv = rb.idx_v[i]
        for d in range(rb.nvj[i]):
            col = ws.oS[iv + d]
            lin_x = lin_y = lin_z = ang_x = ang_y = ang_z = 0.0
            if rb.jtype[i] == FREEFLYER:
                if d < 3:
                    lin_x, lin_y, lin_z = R[0, d], R[1, d], R[2, d]
                else:
                    ang_x, ang_y, ang_z = R[0, d - 3], R[1, d - 3], R[2, d - 3]
            else:
                ax, ay, az = rb.axis[i, 0], rb.axis[i, 1], rb.axis[i, 2]
                wx = R[0, 0] * ax + R[0, 1] * ay + R[0, 2] * az
                wy = R[1, 0] * ax + R[1, 1] * ay + R[1, 2] * az
                wz = R[2, 0] * ax + R[2, 1] * ay + R[2, 2] * az
                if rb.jtype[i] == PRISMATIC:
                    lin_x, lin_y, lin_z = wx, wy, wz
                else:
                    ang_x, ang_y, ang_z = wx, wy, wz
            col[0] = lin_x + py * ang_z - pz * ang_y
            col[1] = lin_y + pz * ang_x - px * ang_z
            col[2] = lin_z + px * ang_y - py * ang_x
            col[3], col[4], col[5] = ang_x, ang_y, ang_z
        for r in range(6):
            acc = 0.0
            for d in range(rb.nvj[i]):
                acc += ws.oS[iv + d, r] * v[iv + d]
            ws.ow[i, r] = acc
            ws.ov[i, r] = ws.ov[par, r] + acc
        _world_inertia(rb, ws, i)


@compiled
def _rnea_pass(rb, ws, a, tau):
    """RNEA on the kinematics in ``ws``: ``ws.oa, ws.oh, ws.oIa``, ``ws.of`` (subtree forces), ``tau (nv,)``."""
    for r in range(6):
        ws.oa[0, r] = -rb.gravity[r]
    for i in range(1, rb.njoints):
        par = rb.parent[i]
        iv = rb.idx_v[i]
        oa = ws.oa[i]
        for r in range(6):
            acc = ws.oa[par, r]
            for d in range(rb.nvj[i]):
                acc += ws.oS[iv + d, r] * a[iv + d]
            oa[r] = acc
        _motion_cross_add(ws.ov[i], ws.ow[i], 1.0, oa)
        for r in range(6):
            ws.oh[i, r] = 0.0
            ws.oIa[i, r] = 0.0
        _inertia_add(ws.oI[i], ws.ov[i], 1.0, ws.oh[i])
        _inertia_add(ws.oI[i], oa, 1.0, ws.oIa[i])
        for r in range(6):
            ws.of[i, r] = ws.oIa[i, r]
        _force_cross_add(ws.ov[i], ws.oh[i], 1.0, ws.of[i])
    for i in range(rb.njoints - 1, 0, -1):
        iv = rb.idx_v[i]
        for d in range(rb.nvj[i]):
            tau[iv + d] = _dot6(ws.oS[iv + d], ws.of[i]) + rb.armature[iv + d] * a[iv + d]
        par = rb.parent[i]
        if par > 0:
            for r in range(6):
                ws.of[par, r] += ws.of[i, r]


@compiled
def _crba(rb, ws):
    """``ws.M``: the joint-space inertia matrix (armature included), from the composite inertias ``ws.oIc``."""
    for r in range(rb.nv):
        for c in range(rb.nv):
            ws.M[r, c] = 0.0
    for i in range(rb.njoints):
        for r in range(6):
            for c in range(6):
                ws.oIc[i, r, c] = ws.oI[i, r, c]
    F = ws.tmp[0]
    for i in range(rb.njoints - 1, 0, -1):
        iv = rb.idx_v[i]
        for d in range(rb.nvj[i]):
            for r in range(6):
                F[r] = 0.0
            _inertia_add(ws.oIc[i], ws.oS[iv + d], 1.0, F)
            j = i
            while j > 0:
                jv = rb.idx_v[j]
                for e in range(rb.nvj[j]):
                    x = _dot6(ws.oS[jv + e], F)
                    ws.M[jv + e, iv + d] = x
                    ws.M[iv + d, jv + e] = x
                j = rb.parent[j]
            ws.M[iv + d, iv + d] += rb.armature[iv + d]
        par = rb.parent[i]
        if par > 0:
            for r in range(6):
                for c in range(6):
                    ws.oIc[par, r, c] += ws.oIc[i, r, c]


@compiled
def _cholesky(rb, ws):
    """``ws.L``: lower Cholesky factor of ``ws.M``."""
    n = rb.nv
    L = ws.L
    for j in range(n):
        acc = ws.M[j, j]
        for k in range(j):
            acc -= L[j, k] * L[j, k]
        d = math.sqrt(acc)
        L[j, j] = d
        for i in range(j + 1, n):
            x = ws.M[i, j]
            for k in range(j):
                x -= L[i, k] * L[j, k]
            L[i, j] = x / d
        for i in range(j):
            L[i, j] = 0.0


@compiled
def _cholesky_solve(L, x):
    """``x ← (L Lᵀ)⁻¹ x`` in place."""
    n = x.shape[0]
    for i in range(n):
        acc = x[i]
        for k in range(i):
            acc -= L[i, k] * x[k]
        x[i] = acc / L[i, i]
    for i in range(n - 1, -1, -1):
        acc = x[i]
        for k in range(i + 1, n):
            acc -= L[k, i] * x[k]
        x[i] = acc / L[i, i]


@compiled
def forward_dynamics(
    rb: RigidBodyModel, ws: RigidBodyWorkspace, q: np.ndarray, v: np.ndarray, tau: np.ndarray, a_out: np.ndarray
) -> None:
    """``a_out = M⁻¹ (tau - RNEA(q, v, 0))``; leaves ``ws.M``, ``ws.L`` and the kinematics
    (``ws.oa`` holds the accelerations at zero joint acceleration)."""
    forward_kinematics(rb, ws, q, v)
    _rnea_pass(rb, ws, ws.zero, ws.tau)
    _crba(rb, ws)
    _cholesky(rb, ws)
    for k in range(rb.nv):
        a_out[k] = tau[k] - ws.tau[k]
    _cholesky_solve(ws.L, a_out)


@compiled
def mass_inverse(rb: RigidBodyModel, ws: RigidBodyWorkspace, Minv_out: np.ndarray) -> None:
    """``Minv_out (nv, nv) = M⁻¹`` (armature included) from the factor ``ws.L`` of the last
    :func:`forward_dynamics` (symmetric: the lower triangle is solved and mirrored)."""
    n = rb.nv
    L = ws.L
    for j in range(n):
        for i in range(j):
            Minv_out[i, j] = 0.0
        for i in range(j, n):
            acc = 1.0 if i == j else 0.0
            for k in range(j, i):
                acc -= L[i, k] * Minv_out[k, j]
            Minv_out[i, j] = acc / L[i, i]
        for i in range(n - 1, j - 1, -1):
            acc = Minv_out[i, j]
            for k in range(i + 1, n):
                acc -= L[k, i] * Minv_out[k, j]
            Minv_out[i, j] = acc / L[i, i]
    for j in range(n):
        for i in range(j):
            Minv_out[i, j] = Minv_out[j, i]


@compiled
def gravity_torque(rb: RigidBodyModel, ws: RigidBodyWorkspace, q: np.ndarray, out: np.ndarray) -> None:
    """``out (nv,) = RNEA(q, 0, 0)``, the generalized gravity."""
    forward_kinematics(rb, ws, q, ws.zero)
    _rnea_pass(rb, ws, ws.zero, out)


@compiled
def _subtree_torques(rb, ws, j, k, with_q, out):
    """Column ``k`` of a RNEA derivative from the tangents ``ws.df`` of the subtree of ``j`` (summed here)."""
    end = rb.subtree_end[j]
    for r in range(rb.nv):
        out[r, k] = 0.0
    for i in range(end - 1, j, -1):
        par = rb.parent[i]
        for r in range(6):
            ws.df[par, r] += ws.df[i, r]
    s = ws.oS[k]
    dS = ws.tmp[3]
    for i in range(j, end):
        iv = rb.idx_v[i]
        for d in range(rb.nvj[i]):
            x = _dot6(ws.oS[iv + d], ws.df[i])
            if with_q:
                for r in range(6):
                    dS[r] = 0.0
                _motion_cross_add(s, ws.oS[iv + d], 1.0, dS)
                x += _dot6(dS, ws.of[i])
            out[iv + d, k] = x
    a = rb.parent[j]
    while a > 0:
        av = rb.idx_v[a]
        for d in range(rb.nvj[a]):
            out[av + d, k] = _dot6(ws.oS[av + d], ws.df[j])
        a = rb.parent[a]


@compiled
def dynamics_derivatives(
    rb: RigidBodyModel,
    ws: RigidBodyWorkspace,
    q: np.ndarray,
    v: np.ndarray,
    a: np.ndarray,
    dtau_dq_out: np.ndarray,
    dtau_dv_out: np.ndarray,
) -> None:
    """``∂RNEA/∂q`` and ``∂RNEA/∂v`` at ``(q, v, a)`` into ``(nv, nv)`` arrays (``∂/∂a`` is :func:`forward_dynamics`'
    ``ws.M``).  Runs the kinematics and a RNEA pass itself; leaves ``ws.L`` untouched."""
    forward_kinematics(rb, ws, q, v)
    _rnea_pass(rb, ws, a, ws.tau)
    dw = ws.tmp[0]
    acc = ws.tmp[1]
    dh = ws.tmp[2]
    for k in range(rb.nv):
        j = rb.dof_joint[k]
        s = ws.oS[k]
        end = rb.subtree_end[j]
        # configuration tangent
        for i in range(j, end):
            par = rb.parent[i]
            iv = rb.idx_v[i]
            dvi = ws.dv[i]
            dai = ws.da[i]
            for r in range(6):
                dw[r] = 0.0
                acc[r] = 0.0
                for d in range(rb.nvj[i]):
                    acc[r] += ws.oS[iv + d, r] * a[iv + d]
                dvi[r] = ws.dv[par, r] if i != j else 0.0
                dai[r] = ws.da[par, r] if i != j else 0.0
            _motion_cross_add(s, ws.ow[i], 1.0, dw)
            for r in range(6):
                dvi[r] += dw[r]
            _motion_cross_add(s, acc, 1.0, dai)
            _motion_cross_add(dvi, ws.ow[i], 1.0, dai)
            _motion_cross_add(ws.ov[i], dw, 1.0, dai)
            # dh = s ×* h + oI (dv - s × ov);  df = s ×* oIa + oI (da - s × oa) + dv ×* h + ov ×* dh
            for r in range(6):
                acc[r] = dvi[r]
                dh[r] = 0.0
            _motion_cross_add(s, ws.ov[i], -1.0, acc)
            _inertia_add(ws.oI[i], acc, 1.0, dh)
            _force_cross_add(s, ws.oh[i], 1.0, dh)
            dfi = ws.df[i]
            for r in range(6):
                acc[r] = dai[r]
                dfi[r] = 0.0
            _motion_cross_add(s, ws.oa[i], -1.0, acc)
            _inertia_add(ws.oI[i], acc, 1.0, dfi)
            _force_cross_add(s, ws.oIa[i], 1.0, dfi)
            _force_cross_add(dvi, ws.oh[i], 1.0, dfi)
            _force_cross_add(ws.ov[i], dh, 1.0, dfi)
        _subtree_torques(rb, ws, j, k, True, dtau_dq_out)
        # velocity tangent
        for i in range(j, end):
            par = rb.parent[i]
            dvi = ws.dv[i]
            dai = ws.da[i]
            for r in range(6):
                dvi[r] = ws.dv[par, r] if i != j else s[r]
                dai[r] = ws.da[par, r] if i != j else 0.0
            _motion_cross_add(dvi, ws.ow[i], 1.0, dai)
            if i == j:
                _motion_cross_add(ws.ov[i], s, 1.0, dai)
            dfi = ws.df[i]
            for r in range(6):
                dh[r] = 0.0
                dfi[r] = 0.0
            _inertia_add(ws.oI[i], dvi, 1.0, dh)
            _inertia_add(ws.oI[i], dai, 1.0, dfi)
            _force_cross_add(dvi, ws.oh[i], 1.0, dfi)
            _force_cross_add(ws.ov[i], dh, 1.0, dfi)
        _subtree_torques(rb, ws, j, k, False, dtau_dv_out)


@compiled
def _frame_pose(rb, ws, fid):
    """``ws.Rf, ws.pf``: ``oMf`` of frame ``fid``; returns its parent joint."""
    i = rb.frame_joint[fid]
    for r in range(3):
        acc = ws.op[i, r]
        for c in range(3):
            acc += ws.oR[i, r, c] * rb.fp[fid, c]
            x = 0.0
            for k in range(3):
                x += ws.oR[i, r, k] * rb.fR[fid, k, c]
            ws.Rf[r, c] = x
        ws.pf[r] = acc
    return i


@compiled
def _to_reference(ws, m, reference, out):
    """``out (6,)``: the world motion ``m`` read in ``reference`` at the frame ``ws.Rf, ws.pf``."""
    vx, vy, vz, wx, wy, wz = m[0], m[1], m[2], m[3], m[4], m[5]
    if reference != WORLD:
        px, py, pz = ws.pf[0], ws.pf[1], ws.pf[2]
        vx, vy, vz = vx - (py * wz - pz * wy), vy - (pz * wx - px * wz), vz - (px * wy - py * wx)
    if reference == LOCAL:
        R = ws.Rf
        out[0] = R[0, 0] * vx + R[1, 0] * vy + R[2, 0] * vz
        out[1] = R[0, 1] * vx + R[1, 1] * vy + R[2, 1] * vz
        out[2] = R[0, 2] * vx + R[1, 2] * vy + R[2, 2] * vz
        out[3] = R[0, 0] * wx + R[1, 0] * wy + R[2, 0] * wz
        out[4] = R[0, 1] * wx + R[1, 1] * wy + R[2, 1] * wz
        out[5] = R[0, 2] * wx + R[1, 2] * wy + R[2, 2] * wz
    else:
        out[0], out[1], out[2], out[3], out[4], out[5] = vx, vy, vz, wx, wy, wz


@compiled
def frame_placement(rb: RigidBodyModel, ws: RigidBodyWorkspace, fid: int, R_out: np.ndarray, p_out: np.ndarray) -> None:
    """``oMf`` of frame ``fid`` (``R_out (3, 3)``, ``p_out (3,)``) after :func:`forward_kinematics`."""
    _frame_pose(rb, ws, fid)
    for r in range(3):
        p_out[r] = ws.pf[r]
        for c in range(3):
            R_out[r, c] = ws.Rf[r, c]


@compiled
def frame_jacobian(rb: RigidBodyModel, ws: RigidBodyWorkspace, fid: int, reference: int, J_out: np.ndarray) -> None:
    """``J_out (6, nv)``: the Jacobian of frame ``fid`` in ``reference`` (zero outside its support)."""
    i = _frame_pose(rb, ws, fid)
    for r in range(6):
        for c in range(rb.nv):
            J_out[r, c] = 0.0
    col = ws.tmp[5]
    while i > 0:
        iv = rb.idx_v[i]
        for d in range(rb.nvj[i]):
            _to_reference(ws, ws.oS[iv + d], reference, col)
            for r in range(6):
                J_out[r, iv + d] = col[r]
        i = rb.parent[i]


@compiled
def frame_velocity(rb: RigidBodyModel, ws: RigidBodyWorkspace, fid: int, reference: int, out6: np.ndarray) -> None:
    """``out6 (6,)``: the spatial velocity of frame ``fid`` in ``reference``, linear then angular."""
    i = _frame_pose(rb, ws, fid)
    _to_reference(ws, ws.ov[i], reference, out6)


@compiled
def frame_velocity_derivatives(
    rb: RigidBodyModel, ws: RigidBodyWorkspace, fid: int, reference: int, dv_dq_out: np.ndarray, dv_dv_out: np.ndarray
) -> None:
    """``(6, nv)`` derivatives of :func:`frame_velocity` w.r.t. ``q`` (tangent) and ``v`` (the frame Jacobian).

    For a dof ``k`` of joint ``j`` in the support (``s = oS_k``): ``d ov_i = s × (ov_i - ov_λ(j))`` (WORLD);
    LOCAL reads ``ov_λ(j) × s`` in the frame.  LOCAL_WORLD_ALIGNED follows Pinocchio: ``d ov_i`` read at the
    frame origin held fixed, i.e. without the term ``ω × (s_v + s_ω × p)`` the moving origin adds to the
    derivative of ``getFrameVelocity(..., LOCAL_WORLD_ALIGNED)``.
    """
    frame_jacobian(rb, ws, fid, reference, dv_dv_out)
    i = rb.frame_joint[fid]
    for r in range(6):
        for c in range(rb.nv):
            dv_dq_out[r, c] = 0.0
    t = ws.tmp[0]
    out = ws.tmp[1]
    j = i
    while j > 0:
        par = rb.parent[j]
        jv = rb.idx_v[j]
        for d in range(rb.nvj[j]):
            s = ws.oS[jv + d]
            for r in range(6):
                t[r] = 0.0
            if reference == LOCAL:
                _motion_cross_add(ws.ov[par], s, 1.0, t)
                _to_reference(ws, t, LOCAL, out)
            else:
                for r in range(6):
                    out[r] = ws.ov[i, r] - ws.ov[par, r]
                _motion_cross_add(s, out, 1.0, t)
                if reference == WORLD:
                    for r in range(6):
                        out[r] = t[r]
                else:
                    _to_reference(ws, t, LOCAL_WORLD_ALIGNED, out)
            for r in range(6):
                dv_dq_out[r, jv + d] = out[r]
        j = par
