"""Lie-group maps of SO(3)/SE(3) and the configuration space of a lowered multibody model (numba kernels).

Every public function is compiled with :func:`crocopy.kernels.compiled`, callable from Python and from
other compiled functions, and writes into its ``out`` argument(s) (float64, C-contiguous); nothing is
allocated.  Conventions are Pinocchio's.  Public kernels: ``log3``, ``jlog3``, ``log6``, ``jlog6``;
``integrate``, ``difference``, ``dintegrate`` (``dintegrate_blocks``: its diagonal blocks only); ``state_diff``,
``state_integrate``, ``state_jdiff``.

SO(3) and SE(3)
---------------
A rotation is ``R`` (3, 3); a placement ``M = (R, p)`` is ``R`` (3, 3) and ``p`` (3,), acting on points as
``x ↦ R x + p``; a twist is ``ν = [v; ω]`` (6,), linear part first.  With ``θ = |ω|`` and ``[ω]`` the
skew matrix of ``ω``:

* ``exp3(ω) = I + sin θ/θ [ω] + (1 - cos θ)/θ² [ω]²``; ``log3`` is its inverse with ``θ ∈ [0, π]``
  (the axis is read from the symmetric part of ``R`` near ``π``).
* ``Jr(ω) = I - (1 - cos θ)/θ² [ω] + (θ - sin θ)/θ³ [ω]²`` (the right Jacobian of ``exp3``:
  ``exp3(ω + δ) ≈ exp3(ω) exp3(Jr δ)``) and ``jlog3(R) = Jr(log3 R)⁻¹
  = I + [ω]/2 + (1/θ² - (1 + cos θ)/(2 θ sin θ)) [ω]²``.
* ``exp6(ν) = (exp3 ω, Jl(ω) v)`` with the left Jacobian ``Jl(ω) = Jr(ω)ᵀ``; ``log6`` is its inverse.
* ``jexp6(ν) = [[Jr(ω), Q(-v, -ω)], [0, Jr(ω)]]`` (6, 6), the right Jacobian of ``exp6``, with the block
  ``Q(ρ, φ)`` of SE(3)'s left Jacobian (Barfoot & Furgale 2014; Solà et al., "A micro Lie theory for
  state estimation in robotics", 2018), and
  ``jlog6(M) = jexp6(log6 M)⁻¹ = [[A, -A Q A], [0, A]]`` with ``A = Jr(ω)⁻¹``.
* ``Ad(M) = [[R, [p] R], [0, R]]`` (Pinocchio's ``SE3.action``).
* Quaternions are stored ``[x, y, z, w]`` (Pinocchio's configuration order).

``exp3``, ``Jr``, ``exp6``, ``jexp6`` and ``Ad`` are private tuple helpers used by the configuration-space
kernels below.  The coefficients of ``exp3``, ``Jr`` and ``Q`` are summed from their power series for
``θ < 1`` (to round-off), ``θ/sin θ``, ``sin(θ/2)/θ`` and ``Jr⁻¹``'s from a Taylor polynomial below
``θ = 1e-2``.  Pinocchio's own ``Jexp6``/``Jlog6`` lose up to 1e-7 for ``θ`` between about 1e-4 and 1e-2;
these do not.

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

_SMALL = 1e-2
"""Below this angle the trigonometric coefficients use their Taylor series."""

_IDENTITY = (1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0)


# --- 3x3 matrices as row-major 9-tuples (values, no allocation) --------------------------------------


@uncounted
def _mm(a, b):
    """``a @ b``."""
    return (
        a[0] * b[0] + a[1] * b[3] + a[2] * b[6], a[0] * b[1] + a[1] * b[4] + a[2] * b[7],
        a[0] * b[2] + a[1] * b[5] + a[2] * b[8],
        a[3] * b[0] + a[4] * b[3] + a[5] * b[6], a[3] * b[1] + a[4] * b[4] + a[5] * b[7],
        a[3] * b[2] + a[4] * b[5] + a[5] * b[8],
        a[6] * b[0] + a[7] * b[3] + a[8] * b[6], a[6] * b[1] + a[7] * b[4] + a[8] * b[7],
        a[6] * b[2] + a[7] * b[5] + a[8] * b[8],
    )


@uncounted
def _tr(a):
    """``aᵀ``."""
    return (a[0], a[3], a[6], a[1], a[4], a[7], a[2], a[5], a[8])


@uncounted
def _skew(x, y, z):
    """``[(x, y, z)]``, the matrix of the cross product."""
    return (0.0, -z, y, z, 0.0, -x, -y, x, 0.0)


@uncounted
def _poly(a, b, w, ww):
    """``I + a W + b WW``."""
    return (
        1.0 + a * w[0] + b * ww[0], a * w[1] + b * ww[1], a * w[2] + b * ww[2],
        a * w[3] + b * ww[3], 1.0 + a * w[4] + b * ww[4], a * w[5] + b * ww[5],
        a * w[6] + b * ww[6], a * w[7] + b * ww[7], 1.0 + a * w[8] + b * ww[8],
    )


@uncounted
def _lin(a, x, b, y, c, z, d, u):
    """``a x + b y + c z + d u`` for 9-tuples."""
    return (
        a * x[0] + b * y[0] + c * z[0] + d * u[0], a * x[1] + b * y[1] + c * z[1] + d * u[1],
        a * x[2] + b * y[2] + c * z[2] + d * u[2], a * x[3] + b * y[3] + c * z[3] + d * u[3],
        a * x[4] + b * y[4] + c * z[4] + d * u[4], a * x[5] + b * y[5] + c * z[5] + d * u[5],
        a * x[6] + b * y[6] + c * z[6] + d * u[6], a * x[7] + b * y[7] + c * z[7] + d * u[7],
        a * x[8] + b * y[8] + c * z[8] + d * u[8],
    )


@uncounted
def _add(a, b):
    """``a + b``."""
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2], a[3] + b[3], a[4] + b[4], a[5] + b[5], a[6] + b[6],
            a[7] + b[7], a[8] + b[8])


@uncounted
def _mv(a, x, y, z):
    """``a @ (x, y, z)``."""
    return (
        a[0] * x + a[1] * y + a[2] * z,
        a[3] * x + a[4] * y + a[5] * z,
        a[6] * x + a[7] * y + a[8] * z,
    )


@uncounted
def _load(R):
    """A (3, 3) array as a 9-tuple."""
    return (R[0, 0], R[0, 1], R[0, 2], R[1, 0], R[1, 1], R[1, 2], R[2, 0], R[2, 1], R[2, 2])


@uncounted
def _store(a, out, r0, c0):
    """``out[r0:r0+3, c0:c0+3] = a``."""
    for i in range(3):
        for j in range(3):
            out[r0 + i, c0 + j] = a[3 * i + j]


# --- SO(3) coefficients --------------------------------------------------------------------------------


@uncounted
def _series(t2, m, weighted):
    """``Σ_k (-t2)^k w_k/(2k + m)!`` with ``w_k = k + 1`` (``weighted``) or 1, to round-off for ``t2 < 1``.

    The terms decrease; the sum stops at the first one below a quarter of the last bit of the (positive) sum, which
    adding it and every later one would leave unchanged."""
    term = 1.0
    for i in range(2, m + 1):
        term /= i
    total = term
    for k in range(1, 12):
        term *= -t2 / ((2 * k + m - 1) * (2 * k + m))
        step = term * (k + 1) if weighted else term
        if abs(step) < 2.7e-17 * total:
            break
        total += step
    return total


@uncounted
def _coefs(t):
    """``(sin t/t, (1 - cos t)/t², (t - sin t)/t³)``."""
    if t < 1.0:
        t2 = t * t
        return _series(t2, 1, False), _series(t2, 2, False), _series(t2, 3, False)
    s, c = math.sin(t), math.cos(t)
    return (s / t, (1.0 - c) / (t * t), (t - s) / (t * t * t))


@uncounted
def _inv_coef(t):
    """``1/t² - (1 + cos t)/(2 t sin t)``, the ``[ω]²`` coefficient of ``Jr(ω)⁻¹`` (``t ∈ [0, π]``)."""
    if t < _SMALL:
        t2 = t * t
        return 1.0 / 12.0 + t2 / 720.0 + t2 * t2 / 30240.0
    h = 0.5 * t
    return 1.0 / (t * t) - math.cos(h) / (2.0 * t * math.sin(h))


@uncounted
def _exp3_t(x, y, z):
    t = math.sqrt(x * x + y * y + z * z)
    a, b, _ = _coefs(t)
    w = _skew(x, y, z)
    return _poly(a, b, w, _mm(w, w))


@uncounted
def _jr_t(x, y, z, sign):
    """``Jr(ω)`` (``sign = -1``) or ``Jl(ω) = Jr(ω)ᵀ`` (``sign = 1``)."""
    t = math.sqrt(x * x + y * y + z * z)
    _, b, c = _coefs(t)
    w = _skew(x, y, z)
    return _poly(sign * b, c, w, _mm(w, w))


@uncounted
def _log3_k_t(R):
    """``log3(R)`` as ``(x, y, z)`` and the ``[ω]²`` coefficient of ``Jr(ω)⁻¹`` at its angle (:func:`_inv_coef`); below
    ``θ = 2π/3`` from ``R``'s own ``sin θ, cos θ``: ``1/θ² - (1 + cos θ)/(2 θ sin θ)`` (no trigonometric call)."""
    ax, ay, az = 0.5 * (R[7] - R[5]), 0.5 * (R[2] - R[6]), 0.5 * (R[3] - R[1])
    s = math.sqrt(ax * ax + ay * ay + az * az)
    c = 0.5 * (R[0] + R[4] + R[8] - 1.0)
    t = math.atan2(s, c)
    if c > -0.5:
        if t < _SMALL:
            t2 = t * t
            f = 1.0 + t2 / 6.0 + 7.0 * t2 * t2 / 360.0
            k = 1.0 / 12.0 + t2 / 720.0 + t2 * t2 / 30240.0
        else:
            f = t / s
            k = 1.0 / (t * t) - (1.0 + c) / (2.0 * t * s)
        return f * ax, f * ay, f * az, k
    # near π: θ² k kᵀ = θ² (sym(R) - c I)/(1 - c); the largest diagonal entry fixes the axis, ``a`` its sign
    i = 0
    if R[4] > R[0]:
        i = 1
    if R[8] > R[3 * i + i]:
        i = 2
    d = 1.0 - c
    ki = math.sqrt(max((R[4 * i] - c) / d, 0.0))
    ai = ax if i == 0 else (ay if i == 1 else az)
    if ai < 0.0:
        ki = -ki
    f = 1.0 / (d * ki)
    k0 = ki if i == 0 else 0.5 * (R[i] + R[3 * i]) * f
    k1 = ki if i == 1 else 0.5 * (R[3 + i] + R[3 * i + 1]) * f
    k2 = ki if i == 2 else 0.5 * (R[6 + i] + R[3 * i + 2]) * f
    return t * k0, t * k1, t * k2, _inv_coef(t)


@uncounted
def _log3_t(R):
    """``log3(R)`` as ``(x, y, z)``."""
    x, y, z, _ = _log3_k_t(R)
    return x, y, z


@uncounted
def _q_t(rx, ry, rz, x, y, z):
    """Barfoot's ``Q(ρ, φ)``, the upper-right block of SE(3)'s left Jacobian."""
    t2 = x * x + y * y + z * z
    if t2 < 1.0:
        c2, c3, c4 = _series(t2, 3, False), _series(t2, 4, False), _series(t2, 5, True)
    else:
        t = math.sqrt(t2)
        s, c = math.sin(t), math.cos(t)
        c2 = (t - s) / (t2 * t)
        c3 = (t2 + 2.0 * c - 2.0) / (2.0 * t2 * t2)
        c4 = (2.0 * t - 3.0 * s + t * c) / (2.0 * t2 * t2 * t)
    # with W = [φ], P = [ρ], d = φ·ρ and n = φ × ρ: WP = ρφᵀ - d I, PW = φρᵀ - d I, WPW = -d W,
    # WWP + PWW = nφᵀ - φnᵀ - 2d W, WPWW = WWPW = -d (φφᵀ - θ² I)
    d = x * rx + y * ry + z * rz
    n = (y * rz - z * ry, z * rx - x * rz, x * ry - y * rx)
    f = (x, y, z)
    r = (rx, ry, rz)
    P = _skew(rx, ry, rz)
    W = _skew(x, y, z)
    dw = (c2 - c3) * d
    ff = 2.0 * c4 * d
    diag = 2.0 * d * (c4 * t2 - c2)
    return (
        0.5 * P[0] + c2 * 2.0 * r[0] * f[0] - ff * f[0] * f[0] + diag,
        0.5 * P[1] + c2 * (r[0] * f[1] + f[0] * r[1]) + c3 * (n[0] * f[1] - f[0] * n[1]) - dw * W[1] - ff * f[0] * f[1],
        0.5 * P[2] + c2 * (r[0] * f[2] + f[0] * r[2]) + c3 * (n[0] * f[2] - f[0] * n[2]) - dw * W[2] - ff * f[0] * f[2],
        0.5 * P[3] + c2 * (r[1] * f[0] + f[1] * r[0]) + c3 * (n[1] * f[0] - f[1] * n[0]) - dw * W[3] - ff * f[1] * f[0],
        0.5 * P[4] + c2 * 2.0 * r[1] * f[1] - ff * f[1] * f[1] + diag,
        0.5 * P[5] + c2 * (r[1] * f[2] + f[1] * r[2]) + c3 * (n[1] * f[2] - f[1] * n[2]) - dw * W[5] - ff * f[1] * f[2],
        0.5 * P[6] + c2 * (r[2] * f[0] + f[2] * r[0]) + c3 * (n[2] * f[0] - f[2] * n[0]) - dw * W[6] - ff * f[2] * f[0],
        0.5 * P[7] + c2 * (r[2] * f[1] + f[2] * r[1]) + c3 * (n[2] * f[1] - f[2] * n[1]) - dw * W[7] - ff * f[2] * f[1],
        0.5 * P[8] + c2 * 2.0 * r[2] * f[2] - ff * f[2] * f[2] + diag,
    )


# --- public SO(3) -------------------------------------------------------------------------------------


@uncounted
def log3(R, w_out):
    """``w_out (3,) = log3(R (3, 3))``, angle in ``[0, π]``."""
    w_out[0], w_out[1], w_out[2] = _log3_t(_load(R))


@uncounted
def jlog3(R, J_out):
    """``J_out (3, 3) = Jlog3(R) = Jexp3(log3 R)⁻¹``."""
    x, y, z, k = _log3_k_t(_load(R))
    w = _skew(x, y, z)
    _store(_poly(0.5, k, w, _mm(w, w)), J_out, 0, 0)


# --- SE(3) ---------------------------------------------------------------------------------------------


@uncounted
def _exp6_t(vx, vy, vz, x, y, z):
    """``exp6([v; ω])`` as ``(R, p)`` tuples."""
    return _exp3_t(x, y, z), _mv(_jr_t(x, y, z, 1.0), vx, vy, vz)


@uncounted
def _log6_t(R, px, py, pz):
    """``log6(R, p)`` as ``(ρx, ρy, ρz, φx, φy, φz)``, then ``Jr(φ)⁻¹``'s coefficient ``k`` (:func:`_log3_k_t`)."""
    x, y, z, k = _log3_k_t(R)
    cx, cy, cz = y * pz - z * py, z * px - x * pz, x * py - y * px  # Jl(ω)⁻¹ p = p - ω × p / 2 + k ω × (ω × p)
    dx, dy, dz = y * cz - z * cy, z * cx - x * cz, x * cy - y * cx
    rx, ry, rz = px - 0.5 * cx + k * dx, py - 0.5 * cy + k * dy, pz - 0.5 * cz + k * dz
    return rx, ry, rz, x, y, z, k


@uncounted
def _jexp6_into(vx, vy, vz, x, y, z, J, r0, c0):
    """``J[r0:r0+6, c0:c0+6] = jexp6([v; ω])``."""
    A = _jr_t(x, y, z, -1.0)
    _store(A, J, r0, c0)
    _store(A, J, r0 + 3, c0 + 3)
    _store(_q_t(-vx, -vy, -vz, -x, -y, -z), J, r0, c0 + 3)
    for i in range(3):
        for j in range(3):
            J[r0 + 3 + i, c0 + j] = 0.0


@uncounted
def _jlog6_into(R, px, py, pz, J, r0, c0):
    """``J[r0:r0+6, c0:c0+6] = jlog6(R, p)``."""
    rx, ry, rz, x, y, z, k = _log6_t(R, px, py, pz)
    w = _skew(x, y, z)
    A = _poly(0.5, k, w, _mm(w, w))
    _store(A, J, r0, c0)
    _store(A, J, r0 + 3, c0 + 3)
    B = _mm(_mm(A, _q_t(-rx, -ry, -rz, -x, -y, -z)), A)
    for i in range(3):
        for j in range(3):
            J[r0 + i, c0 + 3 + j] = -B[3 * i + j]
            J[r0 + 3 + i, c0 + j] = 0.0


@uncounted
def _adjoint_into(R, px, py, pz, J, r0, c0):
    """``J[r0:r0+6, c0:c0+6] = Ad(R, p) = [[R, [p] R], [0, R]]``."""
    _store(R, J, r0, c0)
    _store(R, J, r0 + 3, c0 + 3)
    _store(_mm(_skew(px, py, pz), R), J, r0, c0 + 3)
    for i in range(3):
        for j in range(3):
            J[r0 + 3 + i, c0 + j] = 0.0


@uncounted
def _inverse_t(R, px, py, pz):
    """``(R, p)⁻¹ = (Rᵀ, -Rᵀ p)`` as tuples."""
    Rt = _tr(R)
    qx, qy, qz = _mv(Rt, px, py, pz)
    return Rt, (-qx, -qy, -qz)


@uncounted
def log6(R, p, out6):
    """``out6 (6,) = log6(R, p) = [v; ω]``."""
    res = _log6_t(_load(R), p[0], p[1], p[2])
    for k in range(6):
        out6[k] = res[k]


@uncounted
def jlog6(R, p, J_out):
    """``J_out (6, 6) = Jlog6(R, p)``."""
    _jlog6_into(_load(R), p[0], p[1], p[2], J_out, 0, 0)


# --- quaternions [x, y, z, w] -------------------------------------------------------------------------


@uncounted
def _quat_rot_t(x, y, z, w):
    """The rotation of a unit quaternion (Eigen's ``toRotationMatrix`` formula)."""
    return (
        1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y - z * w), 2.0 * (x * z + y * w),
        2.0 * (x * y + z * w), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z - x * w),
        2.0 * (x * z - y * w), 2.0 * (y * z + x * w), 1.0 - 2.0 * (x * x + y * y),
    )


# --- configuration space --------------------------------------------------------------------------------


@uncounted
def _placement_t(q, i):
    """``M(q[i:i+7])`` of a free-flyer configuration as ``(R, p)`` tuples."""
    return _quat_rot_t(q[i + 3], q[i + 4], q[i + 5], q[i + 6]), (q[i], q[i + 1], q[i + 2])


@uncounted
def _relative_t(q0, q1, i):
    """``M(q0)⁻¹ M(q1)`` of the free flyer at ``q[i:i+7]`` as ``(R, p)`` tuples."""
    R0, p0 = _placement_t(q0, i)
    R1, p1 = _placement_t(q1, i)
    R0t = _tr(R0)
    return _mm(R0t, R1), _mv(R0t, p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2])


@uncounted
def _quat_step(x0, y0, z0, w0, wx, wy, wz, align):
    """The quaternion of ``R(x0, y0, z0, w0) exp3(ω)``: the product with ``exp3(ω)``'s, sign-aligned with the first
    (``align``: as Pinocchio's SE(3), not its SO(3)) and first-order normalised, as a 4-tuple ``[x, y, z, w]``."""
    t = math.sqrt(wx * wx + wy * wy + wz * wz)
    if t < _SMALL:
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
    R0 = _quat_rot_t(x0, y0, z0, w0)
    tx, ty, tz = _mv(_jr_t(wx, wy, wz, 1.0), v[iv], v[iv + 1], v[iv + 2])
    dx, dy, dz = _mv(R0, tx, ty, tz)
    q_out[iq], q_out[iq + 1], q_out[iq + 2] = q[iq] + dx, q[iq + 1] + dy, q[iq + 2] + dz
    q_out[iq + 3], q_out[iq + 4], q_out[iq + 5], q_out[iq + 6] = x, y, z, w


@uncounted
def _sphere_relative_t(q0, q1, i):
    """``R(q0)ᵀ R(q1)`` of the spherical joint whose quaternion is at ``q[i:i+4]``."""
    R0 = _quat_rot_t(q0[i], q0[i + 1], q0[i + 2], q0[i + 3])
    return _mm(_tr(R0), _quat_rot_t(q1[i], q1[i + 1], q1[i + 2], q1[i + 3]))


# --- SE(2) (the planar joint) ----------------------------------------------------------------------------


@uncounted
def _se2_coefs(w):
    """``(a, c, e, f)`` of the module docstring at the angle ``w`` (any sign): ``sin w/w``, ``(1 - cos w)/w``,
    ``(w - sin w)/w²`` and ``(1 - cos w)/w²``."""
    a, f, g = _coefs(abs(w))
    return a, w * f, w * g, f


@uncounted
def _exp2_t(vx, vy, w):
    """``exp2([vx, vy, w])`` as ``(cos w, sin w, tx, ty)``."""
    a, c, _, _ = _se2_coefs(w)
    return math.cos(w), math.sin(w), a * vx - c * vy, c * vx + a * vy


@uncounted
def _planar_relative_t(q0, q1, i):
    """``M(q0)⁻¹ M(q1)`` of the planar joint at ``q[i:i+4]`` as ``(cos, sin, tx, ty)`` of ``(R0ᵀ R1, R0ᵀ (t1 - t0))``
    (the rotation's two entries as Pinocchio reads them: ``R0ᵀ R1`` from the raw ``[cos, sin]``)."""
    c0, s0, c1, s1 = q0[i + 2], q0[i + 3], q1[i + 2], q1[i + 3]
    dx, dy = q1[i] - q0[i], q1[i + 1] - q0[i + 1]
    return c0 * c1 + s0 * s1, c0 * s1 - s0 * c1, c0 * dx + s0 * dy, c0 * dy - s0 * dx


@uncounted
def _log2_t(c, s, tx, ty, clamp):
    """``log2`` of the SE(2) placement ``([[c, -s], [s, c]], t)`` as ``(ρx, ρy, θ)``, then ``α = a/(a² + c²)`` and
    ``β = θ/2``, the entries of ``V(θ)⁻¹ = [[α, β], [-β, α]]``.  With ``clamp``, as Pinocchio's ``difference``, the
    angle is 0 where ``c`` rounds above 1 (Pinocchio's ``dDifference`` does not clamp it; unlike the continuous joint's
    difference, made exact, a planar joint's stays Pinocchio's)."""
    w = 0.0 if clamp and c > 1.0 else math.atan2(s, c)
    a, _, _, f = _se2_coefs(w)
    alpha, beta = a / (2.0 * f), 0.5 * w
    return alpha * tx + beta * ty, alpha * ty - beta * tx, w, alpha, beta


@uncounted
def _jexp2_t(vx, vy, w):
    """The right Jacobian of ``exp2`` at ``[vx, vy, w]`` as a row-major 9-tuple."""
    a, c, e, f = _se2_coefs(w)
    return a, c, vx * e - vy * f, -c, a, vx * f + vy * e, 0.0, 0.0, 1.0


@uncounted
def _jlog2_t(c, s, tx, ty):
    """``jlog2(M)``, the inverse of ``exp2``'s right Jacobian at ``log2 M``, as a 9-tuple: ``[[A⁻¹, -A⁻¹ b], [0, 1]]``
    with ``A⁻¹ = [[α, -β], [β, α]]`` and ``b`` that Jacobian's last column."""
    rx, ry, w, alpha, beta = _log2_t(c, s, tx, ty, False)
    _, _, e, f = _se2_coefs(w)
    bx, by = rx * e - ry * f, rx * f + ry * e
    return alpha, -beta, beta * by - alpha * bx, beta, alpha, -(beta * bx + alpha * by), 0.0, 0.0, 1.0


@uncounted
def _inverse_adjoint2_t(c, s, tx, ty):
    """``Ad(M)⁻¹ = [[Rᵀ, [1] Rᵀ t], [0, 1]]`` of the SE(2) placement ``(R(c, s), t)`` as a 9-tuple."""
    ux, uy = c * tx + s * ty, c * ty - s * tx
    return c, s, -uy, -s, c, ux, 0.0, 0.0, 1.0


@uncounted
def _neg(a):
    """``-a`` for a 9-tuple."""
    return (-a[0], -a[1], -a[2], -a[3], -a[4], -a[5], -a[6], -a[7], -a[8])


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
            cw, sw, tx, ty = _exp2_t(v[iv], v[iv + 1], v[iv + 2])
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
            res = _log6_t(R, p[0], p[1], p[2])
            for k in range(6):
                v_out[iv + k] = res[k]
        elif kind == SPHERICAL:
            v_out[iv], v_out[iv + 1], v_out[iv + 2] = _log3_t(_sphere_relative_t(q0, q1, iq))
        elif kind == PLANAR:
            c, s, tx, ty = _planar_relative_t(q0, q1, iq)
            v_out[iv], v_out[iv + 1], v_out[iv + 2], _, _ = _log2_t(c, s, tx, ty, True)
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
            x, y, z, k = _log3_k_t(R)
            w = _skew(x, y, z)
            A = _poly(0.5, k, w, _mm(w, w))
            _store(A if arg == 1 else _neg(_mm(A, _tr(R))), J, iv, iv)
            continue
        if kind == PLANAR:
            c, s, tx, ty = _planar_relative_t(q0, q1, iq)
            A = _jlog2_t(c, s, tx, ty)
            _store(A if arg == 1 else _neg(_mm(A, _inverse_adjoint2_t(c, s, tx, ty))), J, iv, iv)
            continue
        if kind == TRANSLATION:
            _store(_IDENTITY if arg == 1 else _neg(_IDENTITY), J, iv, iv)
            continue
        if kind != FREEFLYER:
            J[iv, iv] = 1.0 if arg == 1 else -1.0
            continue
        R, p = _relative_t(q0, q1, iq)
        _jlog6_into(R, p[0], p[1], p[2], J, iv, iv)
        if arg == 1:
            continue
        # J ← -Jlog6 Ad(M⁻¹), row by row, with Ad(M⁻¹) = [[Rᵀ, -Rᵀ[p]], [0, Rᵀ]]
        Rt = _tr(R)
        B = _mm(Rt, _skew(p[0], p[1], p[2]))
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
            _store(_jr_t(x, y, z, -1.0) if arg == 1 else _tr(_exp3_t(x, y, z)), J, iv, iv)
        elif kind == PLANAR:
            x, y, w = v[iv], v[iv + 1], v[iv + 2]
            if arg == 1:
                _store(_jexp2_t(x, y, w), J, iv, iv)
            else:
                cw, sw, tx, ty = _exp2_t(x, y, w)
                _store(_inverse_adjoint2_t(cw, sw, tx, ty), J, iv, iv)
        elif kind == TRANSLATION:
            _store(_IDENTITY, J, iv, iv)
        elif kind != FREEFLYER:
            J[iv, iv] = 1.0
        elif arg == 1:
            _jexp6_into(v[iv], v[iv + 1], v[iv + 2], v[iv + 3], v[iv + 4], v[iv + 5], J, iv, iv)
        else:
            R, p = _exp6_t(v[iv], v[iv + 1], v[iv + 2], v[iv + 3], v[iv + 4], v[iv + 5])
            Rt, pt = _inverse_t(R, p[0], p[1], p[2])
            _adjoint_into(Rt, pt[0], pt[1], pt[2], J, iv, iv)


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
