"""The configuration space of a lowered multibody model and its state ``x = [q, v]`` (numba kernels), on the Lie-group
maps of :mod:`.lie_kernel`.

Every public function is compiled with :func:`crocopy.kernels.compiled`, callable from Python and from other compiled
functions, and writes into its ``out`` argument(s); nothing is allocated.  Conventions are Pinocchio's.  Public
kernels: ``integrate``, ``difference``, ``dintegrate`` (``dintegrate_blocks``: its diagonal blocks only);
``state_diff``, ``state_integrate``, ``state_jdiff``.

Configuration space
-------------------
The model is given by ``(jtype, idx_q, idx_v)`` of :func:`~crocopy.models.rbd.joint_types.joint_arrays`
(int64, (njoints,); entry 0, the universe, is skipped).  Per joint, ``q ⊕ v`` and ``q1 ⊖ q0`` are:

* ``FREEFLYER``: ``q = [p, quaternion]``; ``M(q) exp6(v)`` (the quaternion is the product of ``q``'s and
  ``exp3(ω)``'s, sign-aligned with ``q``'s and first-order normalised) and ``log6(M(q0)⁻¹ M(q1))``;
  ``∂(q ⊕ v)/∂q = Ad(exp6(v))⁻¹``, ``∂(q ⊕ v)/∂v = jexp6(v)``, ``∂(q1 ⊖ q0)/∂q1 = jlog6(M)`` and
  ``∂(q1 ⊖ q0)/∂q0 = -jlog6(M) Ad(M)⁻¹`` with ``M = M(q0)⁻¹ M(q1)``;
* ``SPHERICAL``: ``q`` a quaternion; ``R(q) exp3(v)`` (the quaternion as the free flyer's, not sign-aligned: as
  Pinocchio's SO(3)) and
  ``log3(R(q0)ᵀ R(q1))``; ``∂(q ⊕ v)/∂q = exp3(v)ᵀ``, ``∂(q ⊕ v)/∂v = Jr(v)``, ``∂(q1 ⊖ q0)/∂q1 = jlog3(R)`` and
  ``∂(q1 ⊖ q0)/∂q0 = -jlog3(R) Rᵀ`` with ``R = R(q0)ᵀ R(q1)``;
* ``PLANAR``: ``q = [x, y, cos θ, sin θ]``, a placement ``M(q) = (R(θ), (x, y))`` of SE(2) whose ``[cos θ, sin θ]``
  need not be unit (as in Pinocchio, ``R(θ)`` is read from them as they are and nothing is normalised); with
  ``v = [ρ; ω]``, ``exp2(v) = (R(ω), V(ω) ρ)``, ``V(ω) = [[a, -c], [c, a]]``, ``a = sin ω/ω``, ``c = (1 - cos ω)/ω``:
  ``M(q) exp2(v)`` and ``log2(M(q0)⁻¹ M(q1)) = [V(θ)⁻¹ t; θ]`` for the relative ``(R(θ), t)``; the right Jacobian
  of ``exp2`` is ``[[a, c, ρ₁ e - ρ₂ f], [-c, a, ρ₁ f + ρ₂ e], [0, 0, 1]]`` with ``f = (1 - cos ω)/ω²``,
  ``e = (ω - sin ω)/ω²`` (Solà et al. 2018), ``jlog2`` its inverse at ``log2 M``, the adjoint
  ``Ad(R, t) = [[R, -[1] t], [0, 1]]`` (``[1] = [[0, -1], [1, 0]]``), and the Jacobians are the free flyer's with
  these maps;
* ``REVOLUTE``, ``PRISMATIC``, ``HELICAL``: ``q + v`` and ``q1 - q0``, Jacobians ``±1``; ``TRANSLATION`` the same
  for its three coordinates (Jacobians ``±I``);
* ``REVOLUTE_UB``: ``q = [cos θ, sin θ]`` rotated by ``v`` (first-order normalised) and the angle
  ``atan2(s, c)`` from ``q0`` to ``q1`` (``c = q0·q1``, ``s = q0 × q1``), Jacobians ``±1``.  As
  Pinocchio does, the angle is 0 when the rounded ``c`` exceeds 1 (angles below about 1.5e-8 apart).

``integrate``/``difference`` write ``(nq,)``/``(nv,)``; ``dintegrate`` writes the block diagonal
``(nv, nv)`` Jacobian of ``q ⊕ v`` (``arg`` 0: w.r.t. ``q``, 1: w.r.t. ``v``).  The arrays are read and
written at ``idx_q``/``idx_v`` only, so ``q`` may be a whole state ``x = [q, v]`` and ``v`` a state
tangent ``dx = [dq, dv]``.

The state functions are those of :class:`~crocopy.models.state_multibody.StateMultibody`
(``x = [q, v]`` (nq + nv,), ``dx = [dq, dv]`` (2 nv,)):
``state_diff = [q1 ⊖ q0, v1 - v0]``, ``state_integrate = [q ⊕ dq, v + dv]`` and
``state_jdiff(first) = diag(∂(q1 ⊖ q0)/∂q0, -I)`` or ``diag(∂(q1 ⊖ q0)/∂q1, I)`` (2 nv, 2 nv).
"""

from __future__ import annotations

import math

from crocopy.kernels import uncounted

from .joint_types import FREEFLYER, PLANAR, REVOLUTE_UB, SPHERICAL, TRANSLATION
from .lie_kernel import (
    IDENTITY,
    SMALL,
    adjoint_into,
    exp2_t,
    exp3_t,
    exp6_t,
    inverse_adjoint2_t,
    inverse_t,
    jexp2_t,
    jexp6_into,
    jlog2_t,
    jlog6_into,
    jr_t,
    log2_t,
    log3_k_t,
    log3_t,
    log6_t,
    mm,
    mv,
    neg,
    planar_relative_t,
    poly,
    quat_rot_t,
    skew,
    store,
    tr,
)

# --- configuration space --------------------------------------------------------------------------------


@uncounted
def _placement_t(q, i):
    """``M(q[i:i+7])`` of a free-flyer configuration as ``(R, p)`` tuples."""
    return quat_rot_t(q[i + 3], q[i + 4], q[i + 5], q[i + 6]), (q[i], q[i + 1], q[i + 2])


@uncounted
def _relative_t(q0, q1, i):
    """``M(q0)⁻¹ M(q1)`` of the free flyer at ``q[i:i+7]`` as ``(R, p)`` tuples."""
    R0, p0 = _placement_t(q0, i)
    R1, p1 = _placement_t(q1, i)
    R0t = tr(R0)
    return mm(R0t, R1), mv(R0t, p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2])


@uncounted
def _quat_step(x0, y0, z0, w0, wx, wy, wz, align):
    """The quaternion of ``R(x0, y0, z0, w0) exp3(ω)``: the product with ``exp3(ω)``'s, sign-aligned with the first
    (``align``: as Pinocchio's SE(3), not its SO(3)) and first-order normalised, as a 4-tuple ``[x, y, z, w]``."""
    t = math.sqrt(wx * wx + wy * wy + wz * wz)
    if t < SMALL:
        t2 = t * t
        k = 0.5 - t2 / 48.0 + t2 * t2 / 3840.0
    else:
        k = math.sin(0.5 * t) / t
    ex, ey, ez, ew = k * wx, k * wy, k * wz, math.cos(0.5 * t)
    x = w0 * ex + ew * x0 + y0 * ez - z0 * ey
    y = w0 * ey + ew * y0 + z0 * ex - x0 * ez
    z = w0 * ez + ew * z0 + x0 * ey - y0 * ex
    w = w0 * ew - x0 * ex - y0 * ey - z0 * ez
    if align and x * x0 + y * y0 + z * z0 + w * w0 < 0.0:
        x, y, z, w = -x, -y, -z, -w
    f = 0.5 * (3.0 - (x * x + y * y + z * z + w * w))
    return f * x, f * y, f * z, f * w


@uncounted
def _integrate_freeflyer(q, iq, v, iv, q_out):
    x0, y0, z0, w0 = q[iq + 3], q[iq + 4], q[iq + 5], q[iq + 6]
    wx, wy, wz = v[iv + 3], v[iv + 4], v[iv + 5]
    x, y, z, w = _quat_step(x0, y0, z0, w0, wx, wy, wz, True)
    R0 = quat_rot_t(x0, y0, z0, w0)
    tx, ty, tz = mv(jr_t(wx, wy, wz, 1.0), v[iv], v[iv + 1], v[iv + 2])
    dx, dy, dz = mv(R0, tx, ty, tz)
    q_out[iq], q_out[iq + 1], q_out[iq + 2] = q[iq] + dx, q[iq + 1] + dy, q[iq + 2] + dz
    q_out[iq + 3], q_out[iq + 4], q_out[iq + 5], q_out[iq + 6] = x, y, z, w


@uncounted
def _sphere_relative_t(q0, q1, i):
    """``R(q0)ᵀ R(q1)`` of the spherical joint whose quaternion is at ``q[i:i+4]``."""
    R0 = quat_rot_t(q0[i], q0[i + 1], q0[i + 2], q0[i + 3])
    return mm(tr(R0), quat_rot_t(q1[i], q1[i + 1], q1[i + 2], q1[i + 3]))


@uncounted
def integrate(jtype, idx_q, idx_v, q, v, q_out):
    """``q_out (nq,) = q ⊕ v`` (``pinocchio.integrate``)."""
    for j in range(1, jtype.shape[0]):
        kind, iq, iv = jtype[j], idx_q[j], idx_v[j]
        if kind == FREEFLYER:
            _integrate_freeflyer(q, iq, v, iv, q_out)
        elif kind == SPHERICAL:
            q_out[iq], q_out[iq + 1], q_out[iq + 2], q_out[iq + 3] = _quat_step(
                q[iq], q[iq + 1], q[iq + 2], q[iq + 3], v[iv], v[iv + 1], v[iv + 2], False)
        elif kind == PLANAR:
            c0, s0 = q[iq + 2], q[iq + 3]
            cw, sw, tx, ty = exp2_t(v[iv], v[iv + 1], v[iv + 2])
            q_out[iq], q_out[iq + 1] = q[iq] + c0 * tx - s0 * ty, q[iq + 1] + s0 * tx + c0 * ty
            q_out[iq + 2], q_out[iq + 3] = c0 * cw - s0 * sw, s0 * cw + c0 * sw
        elif kind == TRANSLATION:
            for k in range(3):
                q_out[iq + k] = q[iq + k] + v[iv + k]
        elif kind == REVOLUTE_UB:
            c0, s0 = q[iq], q[iq + 1]
            ca, sa = math.cos(v[iv]), math.sin(v[iv])
            c, s = c0 * ca - s0 * sa, s0 * ca + c0 * sa
            f = 0.5 * (3.0 - (c * c + s * s))
            q_out[iq], q_out[iq + 1] = f * c, f * s
        else:
            q_out[iq] = q[iq] + v[iv]


@uncounted
def difference(jtype, idx_q, idx_v, q0, q1, v_out):
    """``v_out (nv,) = q1 ⊖ q0`` (``pinocchio.difference``; a continuous joint's ``atan2(c0 s1 - s0 c1, c0 c1 + s0 s1)``
    also where ``c0 c1 + s0 s1`` rounds above 1, where Pinocchio returns 0)."""
    for j in range(1, jtype.shape[0]):
        kind, iq, iv = jtype[j], idx_q[j], idx_v[j]
        if kind == FREEFLYER:
            R, p = _relative_t(q0, q1, iq)
            res = log6_t(R, p[0], p[1], p[2])
            for k in range(6):
                v_out[iv + k] = res[k]
        elif kind == SPHERICAL:
            v_out[iv], v_out[iv + 1], v_out[iv + 2] = log3_t(_sphere_relative_t(q0, q1, iq))
        elif kind == PLANAR:
            c, s, tx, ty = planar_relative_t(q0, q1, iq)
            v_out[iv], v_out[iv + 1], v_out[iv + 2], _, _ = log2_t(c, s, tx, ty, True)
        elif kind == TRANSLATION:
            for k in range(3):
                v_out[iv + k] = q1[iq + k] - q0[iq + k]
        elif kind == REVOLUTE_UB:
            c0, s0, c1, s1 = q0[iq], q0[iq + 1], q1[iq], q1[iq + 1]
            v_out[iv] = math.atan2(c0 * s1 - s0 * c1, c0 * c1 + s0 * s1)
        else:
            v_out[iv] = q1[iq] - q0[iq]


@uncounted
def _ddifference_blocks(jtype, idx_q, idx_v, q0, q1, arg, J):
    """The diagonal blocks of ``∂(q1 ⊖ q0)/∂(q0 or q1)`` into ``J`` at ``(idx_v, idx_v)``."""
    for j in range(1, jtype.shape[0]):
        kind, iq, iv = jtype[j], idx_q[j], idx_v[j]
        if kind == SPHERICAL:
            R = _sphere_relative_t(q0, q1, iq)
            x, y, z, k = log3_k_t(R)
            w = skew(x, y, z)
            A = poly(0.5, k, w, mm(w, w))
            store(A if arg == 1 else neg(mm(A, tr(R))), J, iv, iv)
            continue
        if kind == PLANAR:
            c, s, tx, ty = planar_relative_t(q0, q1, iq)
            A = jlog2_t(c, s, tx, ty)
            store(A if arg == 1 else neg(mm(A, inverse_adjoint2_t(c, s, tx, ty))), J, iv, iv)
            continue
        if kind == TRANSLATION:
            store(IDENTITY if arg == 1 else neg(IDENTITY), J, iv, iv)
            continue
        if kind != FREEFLYER:
            J[iv, iv] = 1.0 if arg == 1 else -1.0
            continue
        R, p = _relative_t(q0, q1, iq)
        jlog6_into(R, p[0], p[1], p[2], J, iv, iv)
        if arg == 1:
            continue
        # J ← -Jlog6 Ad(M⁻¹), row by row, with Ad(M⁻¹) = [[Rᵀ, -Rᵀ[p]], [0, Rᵀ]]
        Rt = tr(R)
        B = mm(Rt, skew(p[0], p[1], p[2]))
        for r in range(6):
            a0, a1, a2 = J[iv + r, iv], J[iv + r, iv + 1], J[iv + r, iv + 2]
            b0, b1, b2 = J[iv + r, iv + 3], J[iv + r, iv + 4], J[iv + r, iv + 5]
            for c in range(3):
                left = a0 * Rt[c] + a1 * Rt[3 + c] + a2 * Rt[6 + c]
                right = -(a0 * B[c] + a1 * B[3 + c] + a2 * B[6 + c]) + b0 * Rt[c] + b1 * Rt[3 + c] + b2 * Rt[6 + c]
                J[iv + r, iv + c] = -left
                J[iv + r, iv + 3 + c] = -right


@uncounted
def dintegrate_blocks(jtype, idx_q, idx_v, v, arg, J):
    """The diagonal blocks of ``∂(q ⊕ v)/∂(q or v)`` into ``J`` at ``(idx_v, idx_v)`` (independent of ``q``); the
    entries outside the blocks are not written."""
    for j in range(1, jtype.shape[0]):
        kind, iv = jtype[j], idx_v[j]
        if kind == SPHERICAL:
            x, y, z = v[iv], v[iv + 1], v[iv + 2]
            store(jr_t(x, y, z, -1.0) if arg == 1 else tr(exp3_t(x, y, z)), J, iv, iv)
        elif kind == PLANAR:
            x, y, w = v[iv], v[iv + 1], v[iv + 2]
            if arg == 1:
                store(jexp2_t(x, y, w), J, iv, iv)
            else:
                cw, sw, tx, ty = exp2_t(x, y, w)
                store(inverse_adjoint2_t(cw, sw, tx, ty), J, iv, iv)
        elif kind == TRANSLATION:
            store(IDENTITY, J, iv, iv)
        elif kind != FREEFLYER:
            J[iv, iv] = 1.0
        elif arg == 1:
            jexp6_into(v[iv], v[iv + 1], v[iv + 2], v[iv + 3], v[iv + 4], v[iv + 5], J, iv, iv)
        else:
            R, p = exp6_t(v[iv], v[iv + 1], v[iv + 2], v[iv + 3], v[iv + 4], v[iv + 5])
            Rt, pt = inverse_t(R, p[0], p[1], p[2])
            adjoint_into(Rt, pt[0], pt[1], pt[2], J, iv, iv)


@uncounted
def _zero(J):
    for r in range(J.shape[0]):
        for c in range(J.shape[1]):
            J[r, c] = 0.0


@uncounted
def dintegrate(jtype, idx_q, idx_v, q, v, arg, J_out):
    """``J_out (nv, nv) = ∂(q ⊕ v)/∂q`` (``arg = 0``) or ``∂(q ⊕ v)/∂v`` (``arg = 1``) (``pinocchio.dIntegrate``)."""
    _zero(J_out)
    dintegrate_blocks(jtype, idx_q, idx_v, v, arg, J_out)


# --- multibody state x = [q, v] ---------------------------------------------------------------------------


@uncounted
def state_diff(jtype, idx_q, idx_v, nq, nv, x0, x1, out):
    """``out (2 nv,) = [q1 ⊖ q0, v1 - v0]`` (``StateMultibody.diff``)."""
    difference(jtype, idx_q, idx_v, x0, x1, out)
    for k in range(nv):
        out[nv + k] = x1[nq + k] - x0[nq + k]


@uncounted
def state_integrate(jtype, idx_q, idx_v, nq, nv, x, dx, out):
    """``out (nq + nv,) = [q ⊕ dq, v + dv]`` (``StateMultibody.integrate``)."""
    integrate(jtype, idx_q, idx_v, x, dx, out)
    for k in range(nv):
        out[nq + k] = x[nq + k] + dx[nv + k]


@uncounted
def state_jdiff(jtype, idx_q, idx_v, nq, nv, x0, x1, first, J_out):
    """``J_out (2 nv, 2 nv)``: ``StateMultibody.Jdiff(x0, x1)[0]`` (``first``) or ``[1]``."""
    _zero(J_out)
    _ddifference_blocks(jtype, idx_q, idx_v, x0, x1, 0 if first else 1, J_out)
    d = -1.0 if first else 1.0
    for k in range(nv):
        J_out[nv + k, nv + k] = d
