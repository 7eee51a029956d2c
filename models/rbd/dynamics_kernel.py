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
    M     = CRBA (composite inertias) + diag(armature),  Lᵀ L = M (L lower triangular, tree-sparse)
    a     = M⁻¹ (τ - RNEA(q, v, 0))                        (forward dynamics)

where ``m × n = [m_ω × n_v + m_v × n_ω; m_ω × n_ω]`` and ``m ×* f = [m_ω × f_v; m_ω × f_ω + m_v × f_v]``.

Derivatives.  A configuration is perturbed in the joint's local frame, ``M_J(q ⊕ δ) = M_J(q) exp(S δ)``, so a
tangent ``δ_k`` of dof ``k`` of joint ``j`` (world column ``s = oS_k``) moves every placement of the subtree of
``j`` as ``d oX_i = s × oX_i``: ``d oS_i = s × oS_i``, ``d (oI_i m) = s ×* (oI_i m) - oI_i (s × m)``.
:func:`dynamics_derivatives` propagates these tangents through the recursions above in closed form: the
subtree's velocities and accelerations move rigidly plus the terms ``ψ̇ = ov_λ(j) × s``, ``ψ̈ = oa_λ(j) × s +
ov_λ(j) × ψ̇`` (configuration) and ``φ = ψ̇ + ov_j × s`` (velocity), so each column only needs the composite
inertias ``Ic`` and composite ``Bc = Σ (ov ×* oI - oI ov× + (·) ×* oI ov)`` over subtrees: ``O(nv)`` 6x6
products, then ``O(nv · depth)`` 6-vector dot products; the ancestors of ``j`` see ``d τ_l = oS_lᵀ dF_j``.

One body on a free flyer (a quadrotor) takes the joint frame instead (:mod:`.free_body_kernel`).

Inner 6x6 loops are written out; the 6-vector helpers (:mod:`.spatial`) work on tuples and are inlined.  The
kernels keep no reference counts (:func:`crocopy.kernels.uncounted`): numba would otherwise count a reference to
every array of ``rb`` and ``ws`` around each call that passes them on (about 90 calls of its runtime).
As in Pinocchio (4.0 and 4.1, measured), RNEA and CRBA include the armature, so ``∂τ/∂a = M``.

Frames.  ``reference`` is ``int(pin.WORLD) = 0``, ``int(pin.LOCAL) = 1`` or ``int(pin.LOCAL_WORLD_ALIGNED) = 2``.
A world motion ``m`` read in frame ``f`` (``oM_f = (R, p)``) is ``[Rᵀ(m_v - p × m_ω); Rᵀ m_ω]`` (LOCAL) or
``[m_v - p × m_ω; m_ω]`` (LOCAL_WORLD_ALIGNED).
"""

from __future__ import annotations

import math

import numpy as np

from crocopy.kernels import uncounted

from .free_body_kernel import free_body, free_body_bias, free_body_derivatives
from .joint_types import FREEFLYER, HELICAL, PLANAR, PRISMATIC, REVOLUTE, REVOLUTE_UB, SPHERICAL, TRANSLATION
from .lowering import RigidBodyModel, RigidBodyWorkspace
from .spatial import dot, fcross, get6, mcross, minus, plus, set6, times, unit

WORLD = 0
LOCAL = 1
LOCAL_WORLD_ALIGNED = 2


@uncounted
def forward_kinematics(rb: RigidBodyModel, ws: RigidBodyWorkspace, q: np.ndarray, v: np.ndarray) -> None:
    """``ws.oR, ws.op`` (``oMi``), ``ws.oS`` (world motion subspace), ``ws.ov``, ``ws.ow`` and ``ws.oI``."""
    oR, op, oS, ov, ow, oI = ws.oR, ws.op, ws.oS, ws.ov, ws.ow, ws.oI
    jR, jp, axis, com, Ic = rb.jR, rb.jp, rb.axis, rb.com, rb.inertia
    for r in range(3):
        op[0, r] = 0.0
        for c in range(3):
            oR[0, r, c] = 1.0 if r == c else 0.0
    for r in range(6):
        ov[0, r] = 0.0
        ow[0, r] = 0.0
    parent, jtype, idx_q, idx_v, nvj, mass = rb.parent, rb.jtype, rb.idx_q, rb.idx_v, rb.nvj, rb.mass
    A = ws.tmp
    for i in range(1, rb.njoints):
        par = parent[i]
        kind = jtype[i]
        ax, ay, az = axis[i, 0], axis[i, 1], axis[i, 2]
        # the joint's own transform M_J(q) (rotation J[0:9] row-major, translation J[9:12])
        iq = idx_q[i]
        if kind == FREEFLYER or kind == SPHERICAL:
            k = iq + 3 if kind == FREEFLYER else iq
            x, y, z, w = q[k], q[k + 1], q[k + 2], q[k + 3]
            tx, ty, tz = (q[iq], q[iq + 1], q[iq + 2]) if kind == FREEFLYER else (0.0, 0.0, 0.0)
            J = (
                1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y - z * w), 2.0 * (x * z + y * w),
                2.0 * (x * y + z * w), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z - x * w),
                2.0 * (x * z - y * w), 2.0 * (y * z + x * w), 1.0 - 2.0 * (x * x + y * y),
                tx, ty, tz,
            )
        elif kind == PLANAR:  # q = [x, y, cos θ, sin θ]: a rotation about z and a translation in the plane
            c, sn = q[iq + 2], q[iq + 3]
            J = (c, -sn, 0.0, sn, c, 0.0, 0.0, 0.0, 1.0, q[iq], q[iq + 1], 0.0)
        elif kind == TRANSLATION:
            J = (1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, q[iq], q[iq + 1], q[iq + 2])
        elif kind == PRISMATIC:
            J = (1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, ax * q[iq], ay * q[iq], az * q[iq])
        else:
            if kind == REVOLUTE_UB:  # q = [cos θ, sin θ]
                c, sn = q[iq], q[iq + 1]
            else:  # REVOLUTE, HELICAL
                c, sn = math.cos(q[iq]), math.sin(q[iq])
            t = 1.0 - c
            h = axis[i, 3] * q[iq] if kind == HELICAL else 0.0  # the helical joint's advance along its axis
            J = (
                c + t * ax * ax, t * ax * ay - sn * az, t * ax * az + sn * ay,
                t * ax * ay + sn * az, c + t * ay * ay, t * ay * az - sn * ax,
                t * ax * az - sn * ay, t * ay * az + sn * ax, c + t * az * az,
                h * ax, h * ay, h * az,
            )
        for r in range(3):
            acc = op[par, r]
            for c in range(3):
                acc += oR[par, r, c] * jp[i, c]
                A[r, c] = oR[par, r, 0] * jR[i, 0, c] + oR[par, r, 1] * jR[i, 1, c] + oR[par, r, 2] * jR[i, 2, c]
            op[i, r] = acc + A[r, 0] * J[9] + A[r, 1] * J[10] + A[r, 2] * J[11]
        for r in range(3):
            for c in range(3):
                oR[i, r, c] = A[r, 0] * J[c] + A[r, 1] * J[3 + c] + A[r, 2] * J[6 + c]
        px, py, pz = op[i, 0], op[i, 1], op[i, 2]
        iv = idx_v[i]
        wx = oR[i, 0, 0] * ax + oR[i, 0, 1] * ay + oR[i, 0, 2] * az
        wy = oR[i, 1, 0] * ax + oR[i, 1, 1] * ay + oR[i, 1, 2] * az
        wz = oR[i, 2, 0] * ax + oR[i, 2, 1] * ay + oR[i, 2, 2] * az
        for d in range(nvj[i]):
            lin_x = lin_y = lin_z = ang_x = ang_y = ang_z = 0.0
            if kind == PRISMATIC:
                lin_x, lin_y, lin_z = wx, wy, wz
            elif kind == REVOLUTE or kind == REVOLUTE_UB or kind == HELICAL:
                ang_x, ang_y, ang_z = wx, wy, wz
                if kind == HELICAL:
                    pitch = axis[i, 3]
                    lin_x, lin_y, lin_z = pitch * wx, pitch * wy, pitch * wz
            else:  # the joint frame's axis e, a translation or a rotation
                if kind == SPHERICAL:
                    e, linear = d, False
                elif kind == PLANAR:  # x, y, then the rotation about z
                    e, linear = d, d < 2
                else:  # FREEFLYER, TRANSLATION: the translations first
                    e, linear = (d, True) if d < 3 else (d - 3, False)
                if linear:
                    lin_x, lin_y, lin_z = oR[i, 0, e], oR[i, 1, e], oR[i, 2, e]
                else:
                    ang_x, ang_y, ang_z = oR[i, 0, e], oR[i, 1, e], oR[i, 2, e]
            k = iv + d
            oS[k, 0] = lin_x + py * ang_z - pz * ang_y
            oS[k, 1] = lin_y + pz * ang_x - px * ang_z
            oS[k, 2] = lin_z + px * ang_y - py * ang_x
            oS[k, 3], oS[k, 4], oS[k, 5] = ang_x, ang_y, ang_z
        for r in range(6):
            acc = 0.0
            for d in range(nvj[i]):
                acc += oS[iv + d, r] * v[iv + d]
            ow[i, r] = acc
            ov[i, r] = ov[par, r] + acc
        # body inertia at the world origin: [[m, -m[c]x], [m[c]x, R Ic Rᵀ - m [c]x [c]x]], c the world com
        m = mass[i]
        cx = px + oR[i, 0, 0] * com[i, 0] + oR[i, 0, 1] * com[i, 1] + oR[i, 0, 2] * com[i, 2]
        cy = py + oR[i, 1, 0] * com[i, 0] + oR[i, 1, 1] * com[i, 1] + oR[i, 1, 2] * com[i, 2]
        cz = pz + oR[i, 2, 0] * com[i, 0] + oR[i, 2, 1] * com[i, 1] + oR[i, 2, 2] * com[i, 2]
        for r in range(3):
            for c in range(3):
                A[3 + r, c] = oR[i, r, 0] * Ic[i, 0, c] + oR[i, r, 1] * Ic[i, 1, c] + oR[i, r, 2] * Ic[i, 2, c]
        for r in range(3):
            for c in range(3):
                oI[i, 3 + r, 3 + c] = A[3 + r, 0] * oR[i, c, 0] + A[3 + r, 1] * oR[i, c, 1] + A[3 + r, 2] * oR[i, c, 2]
                oI[i, r, c] = m if r == c else 0.0
        oI[i, 3, 0], oI[i, 3, 1], oI[i, 3, 2] = 0.0, -m * cz, m * cy
        oI[i, 4, 0], oI[i, 4, 1], oI[i, 4, 2] = m * cz, 0.0, -m * cx
        oI[i, 5, 0], oI[i, 5, 1], oI[i, 5, 2] = -m * cy, m * cx, 0.0
        for r in range(3):
            for c in range(3):
                oI[i, c, 3 + r] = oI[i, 3 + r, c]
        oI[i, 3, 3] += m * (cy * cy + cz * cz)
        oI[i, 4, 4] += m * (cx * cx + cz * cz)
        oI[i, 5, 5] += m * (cx * cx + cy * cy)
        oI[i, 3, 4] -= m * cx * cy
        oI[i, 4, 3] -= m * cx * cy
        oI[i, 3, 5] -= m * cx * cz
        oI[i, 5, 3] -= m * cx * cz
        oI[i, 4, 5] -= m * cy * cz
        oI[i, 5, 4] -= m * cy * cz


@uncounted
def _rnea_pass(rb, ws, a, tau):
    """RNEA on the kinematics in ``ws``: ``ws.oa, ws.oh, ws.oIa``, ``ws.of`` (subtree forces), ``tau (nv,)``."""
    oS, ov, ow, oa, oI, oh, oIa, of = ws.oS, ws.ov, ws.ow, ws.oa, ws.oI, ws.oh, ws.oIa, ws.of
    parent, idx_v, nvj, armature = rb.parent, rb.idx_v, rb.nvj, rb.armature
    g = rb.gravity
    set6(oa, 0, (-g[0], -g[1], -g[2], -g[3], -g[4], -g[5]))
    for i in range(1, rb.njoints):
        iv = idx_v[i]
        acc = get6(oa, parent[i])
        for d in range(nvj[i]):
            acc = plus(acc, times(get6(oS, iv + d), a[iv + d]))
        ovi = get6(ov, i)
        acc = plus(acc, mcross(ovi, get6(ow, i)))
        set6(oa, i, acc)
        for r in range(6):  # h = oI ov, oIa = oI oa
            h_r = ia_r = 0.0
            for c in range(6):
                h_r += oI[i, r, c] * ov[i, c]
                ia_r += oI[i, r, c] * oa[i, c]
            oh[i, r] = h_r
            oIa[i, r] = ia_r
        set6(of, i, plus(get6(oIa, i), fcross(ovi, get6(oh, i))))
    for i in range(rb.njoints - 1, 0, -1):
        iv = idx_v[i]
        fi = get6(of, i)
        for d in range(nvj[i]):
            tau[iv + d] = dot(get6(oS, iv + d), fi) + armature[iv + d] * a[iv + d]
        par = parent[i]
        if par > 0:
            set6(of, par, plus(get6(of, par), fi))


@uncounted
def _crba(rb, ws):
    """``ws.M``: the joint-space inertia matrix (armature included), from the composite inertias ``ws.oIc``."""
    M, oS, oI, oIc = ws.M, ws.oS, ws.oI, ws.oIc
    for r in range(rb.nv):
        for c in range(rb.nv):
            M[r, c] = 0.0
    for i in range(rb.njoints):
        for r in range(6):
            for c in range(6):
                oIc[i, r, c] = oI[i, r, c]
    parent, idx_v, nvj, armature = rb.parent, rb.idx_v, rb.nvj, rb.armature
    tmp = ws.tmp
    for i in range(rb.njoints - 1, 0, -1):
        iv = idx_v[i]
        for d in range(nvj[i]):
            for r in range(6):  # F = oIc_i S
                x = 0.0
                for c in range(6):
                    x += oIc[i, r, c] * oS[iv + d, c]
                tmp[0, r] = x
            F = get6(tmp, 0)
            j = i
            while j > 0:
                jv = idx_v[j]
                for e in range(nvj[j]):
                    x = dot(get6(oS, jv + e), F)
                    M[jv + e, iv + d] = x
                    M[iv + d, jv + e] = x
                j = parent[j]
            M[iv + d, iv + d] += armature[iv + d]
        par = parent[i]
        if par > 0:
            for r in range(6):
                for c in range(6):
                    oIc[par, r, c] += oIc[i, r, c]


@uncounted
def _factor(lam, M, L, dinv):
    """``L``: the lower-triangular ``L`` with ``M = Lᵀ L`` and the branch-induced sparsity of ``M``
    (Featherstone's LTL factorization: no fill-in, ``O(nv · depth²)``).  A pivot that is not positive (a
    singular ``M``: a moving joint whose subtree has no mass, no inertia about its axis and no armature) is
    NaN, so the dynamics come out NaN as Pinocchio's ABA gives them, instead of a division by zero.  ``lam``:
    ``rb.dof_parent``; ``dinv = 1 / diag(L)``; the workspace's arrays are passed one by one, not the workspace (a
    kernel receiving the workspace copies all its arrays' descriptors at every call)."""
    n = lam.shape[0]
    for r in range(n):
        for c in range(n):
            L[r, c] = M[r, c] if c <= r else 0.0
    for k in range(n - 1, -1, -1):
        d = math.sqrt(L[k, k]) if L[k, k] > 0.0 else math.nan
        L[k, k] = d
        dinv[k] = 1.0 / d
        i = lam[k]
        while i >= 0:
            L[k, i] /= d
            i = lam[i]
        i = lam[k]
        while i >= 0:
            x = L[k, i]
            j = i
            while j >= 0:
                L[i, j] -= x * L[k, j]
                j = lam[j]
            i = lam[i]


@uncounted
def factor_solve(lam: np.ndarray, L: np.ndarray, dinv: np.ndarray, x: np.ndarray) -> None:
    """``x (nv,) ← (Lᵀ L)⁻¹ x`` in place, with the factor of :func:`_factor`, ``dinv = 1 / diag(L)`` and
    ``lam = rb.dof_parent`` (arrays only: a call passing ``rb`` would count references to all its arrays)."""
    n = len(x)
    for k in range(n - 1, -1, -1):
        x[k] *= dinv[k]
        i = lam[k]
        while i >= 0:
            x[i] -= L[k, i] * x[k]
            i = lam[i]
    for k in range(n):
        i = lam[k]
        while i >= 0:
            x[k] -= L[k, i] * x[i]
            i = lam[i]
        x[k] *= dinv[k]


@uncounted
def forward_dynamics(
    rb: RigidBodyModel, ws: RigidBodyWorkspace, q: np.ndarray, v: np.ndarray, tau: np.ndarray, a_out: np.ndarray
) -> None:
    """``a_out = M⁻¹ (tau - RNEA(q, v, 0))``; leaves ``ws.M``, ``ws.L`` and the kinematics
    (``ws.oa`` holds the accelerations at zero joint acceleration)."""
    forward_kinematics(rb, ws, q, v)
    if free_body(rb):
        free_body_bias(rb.mass, rb.com, rb.inertia, rb.armature, rb.gravity, ws.oR, ws.op, v, ws.tmp, ws.M, ws.tau,
                       ws.oa)
    else:
        _rnea_pass(rb, ws, ws.zero, ws.tau)
        _crba(rb, ws)
    _factor(rb.dof_parent, ws.M, ws.L, ws.dinv)
    for k in range(rb.nv):
        a_out[k] = tau[k] - ws.tau[k]
    factor_solve(rb.dof_parent, ws.L, ws.dinv, a_out)


@uncounted
def mass_inverse(lam: np.ndarray, L: np.ndarray, dinv: np.ndarray, Minv_out: np.ndarray) -> None:
    """``Minv_out (nv, nv) = M⁻¹`` (armature included) from the factor ``L = ws.L`` (``dinv = ws.dinv``) of the last
    :func:`forward_dynamics`, one sparse solve per column (``O(nv² · depth)``), then mirrored to be symmetric
    (``lam = rb.dof_parent``)."""
    n = lam.shape[0]
    x = Minv_out
    for j in range(n):  # row j = column j, contiguous
        for k in range(n):
            x[j, k] = 0.0
        x[j, j] = 1.0
        k = j
        while k >= 0:  # Lᵀ y = e_j: only the ancestors of j are reached
            x[j, k] *= dinv[k]
            i = lam[k]
            while i >= 0:
                x[j, i] -= L[k, i] * x[j, k]
                i = lam[i]
            k = lam[k]
        for k in range(n):
            acc = x[j, k]
            i = lam[k]
            while i >= 0:
                acc -= L[k, i] * x[j, i]
                i = lam[i]
            x[j, k] = acc * dinv[k]
    for j in range(n):
        for i in range(j):
            Minv_out[i, j] = Minv_out[j, i]


@uncounted
def _composite_coriolis(rb, ws):
    """``ws.oIc``, ``ws.oBc``: composite inertias and composite ``B_i = ov_i ×* oI_i - oI_i (ov_i ×) + (· ×* h_i)``.

    With ``P = oI_i (ov_i ×)`` and ``oI_i`` symmetric, ``(ov_i ×*) oI_i = -(ov_i ×)ᵀ oI_i = -Pᵀ``, so
    ``B_i = H - P - Pᵀ`` (``H``'s column ``c``: ``e_c ×* h_i``).  A row ``g = [g_v, g_ω]`` of ``oI_i`` times
    ``(ov ×) = [[ω×, v×], [0, ω×]]`` is ``[g_v × ω, g_v × v + g_ω × ω]`` (a row times ``a×`` is the row ``× a``)."""
    oI, oBc, ov, oh, P = ws.oI, ws.oBc, ws.ov, ws.oh, ws.tmp
    for i in range(1, rb.njoints):
        vx, vy, vz, wx, wy, wz = get6(ov, i)
        for r in range(6):
            ax, ay, az = oI[i, r, 0], oI[i, r, 1], oI[i, r, 2]
            bx, by, bz = oI[i, r, 3], oI[i, r, 4], oI[i, r, 5]
            P[r, 0] = ay * wz - az * wy
            P[r, 1] = az * wx - ax * wz
            P[r, 2] = ax * wy - ay * wx
            P[r, 3] = ay * vz - az * vy + by * wz - bz * wy
            P[r, 4] = az * vx - ax * vz + bz * wx - bx * wz
            P[r, 5] = ax * vy - ay * vx + bx * wy - by * wx
        h = get6(oh, i)
        for c in range(6):
            hx = fcross(unit(c), h)
            for r in range(6):
                oBc[i, r, c] = hx[r] - P[r, c] - P[c, r]
    _to_parents(rb.parent, oBc)
    composite_inertias(rb, ws)


@uncounted
def composite_inertias(rb, ws):
    """``ws.oIc``: the composite inertia of each joint's subtree (world frame, at the world origin), from ``ws.oI``."""
    oI, oIc = ws.oI, ws.oIc
    for i in range(1, rb.njoints):
        for r in range(6):
            for c in range(6):
                oIc[i, r, c] = oI[i, r, c]
    _to_parents(rb.parent, oIc)


@uncounted
def _to_parents(parent, A):
    """``A (njoints, 6, 6)`` summed over subtrees in place: each joint's entry added to its parent's, leaves first."""
    for i in range(A.shape[0] - 1, 0, -1):
        par = parent[i]
        if par > 0:
            for r in range(6):
                for c in range(6):
                    A[par, r, c] += A[i, r, c]


@uncounted
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
    ``ws.M``).  Runs the kinematics and a RNEA pass itself; overwrites ``ws.oIc``, leaves ``ws.M, ws.L``.

    Column ``k`` (dof of joint ``j``, ``s = oS_k``): a dof ``c`` of joint ``l`` in the subtree of ``j`` gets
    ``S_cᵀ (Ic_l ψ̈ + Bc_l ψ̇)`` and ``S_cᵀ (Bc_l s + Ic_l φ)``, i.e. dot products with ``ws.IcS[c] = Ic_l S_c`` and
    ``ws.BcS[c] = Bc_lᵀ S_c``; a dof of a strict ancestor the same with ``l = j``, plus ``S_cᵀ (s ×* F_j)`` in q.
    """
    forward_kinematics(rb, ws, q, v)
    rnea_derivatives(rb, ws, a, dtau_dq_out, dtau_dv_out)


@uncounted
def rnea_derivatives(
    rb: RigidBodyModel, ws: RigidBodyWorkspace, a: np.ndarray, dtau_dq_out: np.ndarray, dtau_dv_out: np.ndarray
) -> None:
    """:func:`dynamics_derivatives` on the kinematics already in ``ws`` (a :func:`forward_kinematics` at the same
    ``(q, v)``, e.g. the one of :func:`forward_dynamics`)."""
    _rnea_pass(rb, ws, a, ws.tau)
    if free_body(rb):
        free_body_derivatives(rb.mass, rb.com, rb.inertia, rb.gravity, ws.oR, ws.op, ws.ov, ws.tmp, dtau_dq_out,
                              dtau_dv_out)
        return
    _composite_coriolis(rb, ws)
    oS, ov, oa, of, oIc, oBc, Y, Z = ws.oS, ws.ov, ws.oa, ws.of, ws.oIc, ws.oBc, ws.IcS, ws.BcS
    parent, idx_v, nvj = rb.parent, rb.idx_v, rb.nvj
    dof_joint, subtree_end = rb.dof_joint, rb.subtree_end
    tmp = ws.tmp
    for c in range(rb.nv):
        l = dof_joint[c]
        for r in range(6):
            y = z = 0.0
            for k in range(6):
                y += oIc[l, r, k] * oS[c, k]
                z += oBc[l, k, r] * oS[c, k]
            Y[c, r] = y
            Z[c, r] = z
    for r in range(rb.nv):
        for c in range(rb.nv):
            dtau_dq_out[r, c] = 0.0
            dtau_dv_out[r, c] = 0.0
    for k in range(rb.nv):
        j = dof_joint[k]
        s = get6(oS, k)
        ovp = get6(ov, parent[j])
        psi_d = mcross(ovp, s)
        psi_dd = plus(mcross(get6(oa, parent[j]), s), mcross(ovp, psi_d))
        phi = plus(psi_d, mcross(get6(ov, j), s))
        for c in range(idx_v[j], idx_v[subtree_end[j] - 1] + nvj[subtree_end[j] - 1]):
            y, z = get6(Y, c), get6(Z, c)
            dtau_dq_out[c, k] = dot(y, psi_dd) + dot(z, psi_d)
            dtau_dv_out[c, k] = dot(z, s) + dot(y, phi)
        i = parent[j]
        if i == 0:
            continue
        set6(tmp, 0, s)
        set6(tmp, 1, psi_d)
        set6(tmp, 2, psi_dd)
        set6(tmp, 3, phi)
        for r in range(6):  # gq = Ic_j ψ̈ + Bc_j ψ̇,  gv = Bc_j s + Ic_j φ
            x = y = 0.0
            for c in range(6):
                x += oIc[j, r, c] * tmp[2, c] + oBc[j, r, c] * tmp[1, c]
                y += oBc[j, r, c] * tmp[0, c] + oIc[j, r, c] * tmp[3, c]
            tmp[4, r] = x
            tmp[5, r] = y
        gq = plus(get6(tmp, 4), fcross(s, get6(of, j)))
        gv = get6(tmp, 5)
        while i > 0:
            for d in range(nvj[i]):
                col = get6(oS, idx_v[i] + d)
                dtau_dq_out[idx_v[i] + d, k] = dot(col, gq)
                dtau_dv_out[idx_v[i] + d, k] = dot(col, gv)
            i = parent[i]


@uncounted
def frame_pose(rb: RigidBodyModel, ws: RigidBodyWorkspace, fid: int) -> int:
    """``ws.Rf, ws.pf``: ``oMf`` of frame ``fid``; returns its parent joint."""
    i = rb.frame_joint[fid]
    oR, Rf, fR = ws.oR, ws.Rf, rb.fR
    fp, op, pf = rb.fp, ws.op, ws.pf
    for r in range(3):
        acc = op[i, r]
        for c in range(3):
            acc += oR[i, r, c] * fp[fid, c]
            Rf[r, c] = oR[i, r, 0] * fR[fid, 0, c] + oR[i, r, 1] * fR[fid, 1, c] + oR[i, r, 2] * fR[fid, 2, c]
        pf[r] = acc
    return i


@uncounted
def to_reference(R: np.ndarray, p: np.ndarray, m: tuple, reference: int) -> tuple:
    """The world motion ``m`` (6-tuple) read in ``reference`` at the frame ``(R (3, 3), p (3,))``."""
    vx, vy, vz, wx, wy, wz = m
    if reference == WORLD:
        return m
    px, py, pz = p[0], p[1], p[2]
    vx, vy, vz = vx - (py * wz - pz * wy), vy - (pz * wx - px * wz), vz - (px * wy - py * wx)
    if reference == LOCAL_WORLD_ALIGNED:
        return vx, vy, vz, wx, wy, wz
    return (
        R[0, 0] * vx + R[1, 0] * vy + R[2, 0] * vz,
        R[0, 1] * vx + R[1, 1] * vy + R[2, 1] * vz,
        R[0, 2] * vx + R[1, 2] * vy + R[2, 2] * vz,
        R[0, 0] * wx + R[1, 0] * wy + R[2, 0] * wz,
        R[0, 1] * wx + R[1, 1] * wy + R[2, 1] * wz,
        R[0, 2] * wx + R[1, 2] * wy + R[2, 2] * wz,
    )


@uncounted
def frame_placement(rb: RigidBodyModel, ws: RigidBodyWorkspace, fid: int, R_out: np.ndarray, p_out: np.ndarray) -> None:
    """``oMf`` of frame ``fid`` (``R_out (3, 3)``, ``p_out (3,)``) after :func:`forward_kinematics`."""
    frame_pose(rb, ws, fid)
    for r in range(3):
        p_out[r] = ws.pf[r]
        for c in range(3):
            R_out[r, c] = ws.Rf[r, c]


@uncounted
def frame_jacobian(rb: RigidBodyModel, ws: RigidBodyWorkspace, fid: int, reference: int, J_out: np.ndarray) -> None:
    """``J_out (6, nv)``: the Jacobian of frame ``fid`` in ``reference`` (zero outside its support)."""
    i = frame_pose(rb, ws, fid)
    Rf, pf, oS = ws.Rf, ws.pf, ws.oS
    idx_v, nvj, parent = rb.idx_v, rb.nvj, rb.parent
    for r in range(6):
        for c in range(rb.nv):
            J_out[r, c] = 0.0
    while i > 0:
        iv = idx_v[i]
        for d in range(nvj[i]):
            col = to_reference(Rf, pf, get6(oS, iv + d), reference)
            for r in range(6):
                J_out[r, iv + d] = col[r]
        i = parent[i]


@uncounted
def frame_velocity(rb: RigidBodyModel, ws: RigidBodyWorkspace, fid: int, reference: int, out6: np.ndarray) -> None:
    """``out6 (6,)``: the spatial velocity of frame ``fid`` in ``reference``, linear then angular."""
    i = frame_pose(rb, ws, fid)
    m = to_reference(ws.Rf, ws.pf, get6(ws.ov, i), reference)
    for r in range(6):
        out6[r] = m[r]


@uncounted
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
    Rf, pf, oS, ov = ws.Rf, ws.pf, ws.oS, ws.ov
    parent, idx_v, nvj = rb.parent, rb.idx_v, rb.nvj
    for r in range(6):
        for c in range(rb.nv):
            dv_dq_out[r, c] = 0.0
    ovi = get6(ov, i)
    j = i
    while j > 0:
        par = parent[j]
        jv = idx_v[j]
        ovp = get6(ov, par)
        for d in range(nvj[j]):
            s = get6(oS, jv + d)
            if reference == LOCAL:
                col = to_reference(Rf, pf, mcross(ovp, s), LOCAL)
            else:
                col = to_reference(Rf, pf, mcross(s, minus(ovi, ovp)), reference)
            for r in range(6):
                dv_dq_out[r, jv + d] = col[r]
        j = par


rnea_pass, crba = _rnea_pass, _crba
"""RNEA on the kinematics in ``ws`` (:func:`_rnea_pass`) and ``ws.M`` from them (:func:`_crba`), for the compiled
inverse-dynamics nodes (:mod:`.invdyn_node_kernel`)."""
