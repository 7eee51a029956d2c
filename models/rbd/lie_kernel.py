"""Lie-group maps of SO(3), SE(3) and SE(2) (numba kernels), the ground of :mod:`.configuration_kernel`.

Every public function is compiled with :func:`crocopy.kernels.compiled`, callable from Python and from
other compiled functions, and writes into its ``out`` argument(s) (float64, C-contiguous); nothing is
allocated.  Conventions are Pinocchio's.  Public kernels: ``log3``, ``jlog3``, ``log6``, ``jlog6``; the joints'
configuration spaces, built on these maps, are in :mod:`.configuration_kernel`.

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
"""

from __future__ import annotations

import math

from crocopy.kernels import uncounted

SMALL = 1e-2
"""Below this angle the trigonometric coefficients use their Taylor series."""

IDENTITY = (1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0)


# --- 3x3 matrices as row-major 9-tuples (values, no allocation) --------------------------------------


@uncounted
def mm(a, b):
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
def tr(a):
    """``aᵀ``."""
    return (a[0], a[3], a[6], a[1], a[4], a[7], a[2], a[5], a[8])


@uncounted
def skew(x, y, z):
    """``[(x, y, z)]``, the matrix of the cross product."""
    return (0.0, -z, y, z, 0.0, -x, -y, x, 0.0)


@uncounted
def poly(a, b, w, ww):
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
def mv(a, x, y, z):
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
def store(a, out, r0, c0):
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
    if t < SMALL:
        t2 = t * t
        return 1.0 / 12.0 + t2 / 720.0 + t2 * t2 / 30240.0
    h = 0.5 * t
    return 1.0 / (t * t) - math.cos(h) / (2.0 * t * math.sin(h))


@uncounted
def exp3_t(x, y, z):
    t = math.sqrt(x * x + y * y + z * z)
    a, b, _ = _coefs(t)
    w = skew(x, y, z)
    return poly(a, b, w, mm(w, w))


@uncounted
def jr_t(x, y, z, sign):
    """``Jr(ω)`` (``sign = -1``) or ``Jl(ω) = Jr(ω)ᵀ`` (``sign = 1``)."""
    t = math.sqrt(x * x + y * y + z * z)
    _, b, c = _coefs(t)
    w = skew(x, y, z)
    return poly(sign * b, c, w, mm(w, w))


@uncounted
def log3_k_t(R):
    """``log3(R)`` as ``(x, y, z)`` and the ``[ω]²`` coefficient of ``Jr(ω)⁻¹`` at its angle (:func:`_inv_coef`); below
    ``θ = 2π/3`` from ``R``'s own ``sin θ, cos θ``: ``1/θ² - (1 + cos θ)/(2 θ sin θ)`` (no trigonometric call)."""
    ax, ay, az = 0.5 * (R[7] - R[5]), 0.5 * (R[2] - R[6]), 0.5 * (R[3] - R[1])
    s = math.sqrt(ax * ax + ay * ay + az * az)
    c = 0.5 * (R[0] + R[4] + R[8] - 1.0)
    t = math.atan2(s, c)
    if c > -0.5:
        if t < SMALL:
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
def log3_t(R):
    """``log3(R)`` as ``(x, y, z)``."""
    x, y, z, _ = log3_k_t(R)
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
    P = skew(rx, ry, rz)
    W = skew(x, y, z)
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
    w_out[0], w_out[1], w_out[2] = log3_t(_load(R))


@uncounted
def jlog3(R, J_out):
    """``J_out (3, 3) = Jlog3(R) = Jexp3(log3 R)⁻¹``."""
    x, y, z, k = log3_k_t(_load(R))
    w = skew(x, y, z)
    store(poly(0.5, k, w, mm(w, w)), J_out, 0, 0)


# --- SE(3) ---------------------------------------------------------------------------------------------


@uncounted
def exp6_t(vx, vy, vz, x, y, z):
    """``exp6([v; ω])`` as ``(R, p)`` tuples."""
    return exp3_t(x, y, z), mv(jr_t(x, y, z, 1.0), vx, vy, vz)


@uncounted
def log6_t(R, px, py, pz):
    """``log6(R, p)`` as ``(ρx, ρy, ρz, φx, φy, φz)``, then ``Jr(φ)⁻¹``'s coefficient ``k`` (:func:`log3_k_t`)."""
    x, y, z, k = log3_k_t(R)
    cx, cy, cz = y * pz - z * py, z * px - x * pz, x * py - y * px  # Jl(ω)⁻¹ p = p - ω × p / 2 + k ω × (ω × p)
    dx, dy, dz = y * cz - z * cy, z * cx - x * cz, x * cy - y * cx
    rx, ry, rz = px - 0.5 * cx + k * dx, py - 0.5 * cy + k * dy, pz - 0.5 * cz + k * dz
    return rx, ry, rz, x, y, z, k


@uncounted
def jexp6_into(vx, vy, vz, x, y, z, J, r0, c0):
    """``J[r0:r0+6, c0:c0+6] = jexp6([v; ω])``."""
    A = jr_t(x, y, z, -1.0)
    store(A, J, r0, c0)
    store(A, J, r0 + 3, c0 + 3)
    store(_q_t(-vx, -vy, -vz, -x, -y, -z), J, r0, c0 + 3)
    for i in range(3):
        for j in range(3):
            J[r0 + 3 + i, c0 + j] = 0.0


@uncounted
def jlog6_into(R, px, py, pz, J, r0, c0):
    """``J[r0:r0+6, c0:c0+6] = jlog6(R, p)``."""
    rx, ry, rz, x, y, z, k = log6_t(R, px, py, pz)
    w = skew(x, y, z)
    A = poly(0.5, k, w, mm(w, w))
    store(A, J, r0, c0)
    store(A, J, r0 + 3, c0 + 3)
    B = mm(mm(A, _q_t(-rx, -ry, -rz, -x, -y, -z)), A)
    for i in range(3):
        for j in range(3):
            J[r0 + i, c0 + 3 + j] = -B[3 * i + j]
            J[r0 + 3 + i, c0 + j] = 0.0


@uncounted
def adjoint_into(R, px, py, pz, J, r0, c0):
    """``J[r0:r0+6, c0:c0+6] = Ad(R, p) = [[R, [p] R], [0, R]]``."""
    store(R, J, r0, c0)
    store(R, J, r0 + 3, c0 + 3)
    store(mm(skew(px, py, pz), R), J, r0, c0 + 3)
    for i in range(3):
        for j in range(3):
            J[r0 + 3 + i, c0 + j] = 0.0


@uncounted
def inverse_t(R, px, py, pz):
    """``(R, p)⁻¹ = (Rᵀ, -Rᵀ p)`` as tuples."""
    Rt = tr(R)
    qx, qy, qz = mv(Rt, px, py, pz)
    return Rt, (-qx, -qy, -qz)


@uncounted
def log6(R, p, out6):
    """``out6 (6,) = log6(R, p) = [v; ω]``."""
    res = log6_t(_load(R), p[0], p[1], p[2])
    for k in range(6):
        out6[k] = res[k]


@uncounted
def jlog6(R, p, J_out):
    """``J_out (6, 6) = Jlog6(R, p)``."""
    jlog6_into(_load(R), p[0], p[1], p[2], J_out, 0, 0)


# --- quaternions [x, y, z, w] -------------------------------------------------------------------------


@uncounted
def quat_rot_t(x, y, z, w):
    """The rotation of a unit quaternion (Eigen's ``toRotationMatrix`` formula)."""
    return (
        1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y - z * w), 2.0 * (x * z + y * w),
        2.0 * (x * y + z * w), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z - x * w),
        2.0 * (x * z - y * w), 2.0 * (y * z + x * w), 1.0 - 2.0 * (x * x + y * y),
    )


# --- SE(2) (the planar joint) ----------------------------------------------------------------------------


@uncounted
def _se2_coefs(w):
    """``(a, c, e, f)`` of the module docstring at the angle ``w`` (any sign): ``sin w/w``, ``(1 - cos w)/w``,
    ``(w - sin w)/w²`` and ``(1 - cos w)/w²``."""
    a, f, g = _coefs(abs(w))
    return a, w * f, w * g, f


@uncounted
def exp2_t(vx, vy, w):
    """``exp2([vx, vy, w])`` as ``(cos w, sin w, tx, ty)``."""
    a, c, _, _ = _se2_coefs(w)
    return math.cos(w), math.sin(w), a * vx - c * vy, c * vx + a * vy


@uncounted
def planar_relative_t(q0, q1, i):
    """``M(q0)⁻¹ M(q1)`` of the planar joint at ``q[i:i+4]`` as ``(cos, sin, tx, ty)`` of ``(R0ᵀ R1, R0ᵀ (t1 - t0))``
    (the rotation's two entries as Pinocchio reads them: ``R0ᵀ R1`` from the raw ``[cos, sin]``)."""
    c0, s0, c1, s1 = q0[i + 2], q0[i + 3], q1[i + 2], q1[i + 3]
    dx, dy = q1[i] - q0[i], q1[i + 1] - q0[i + 1]
    return c0 * c1 + s0 * s1, c0 * s1 - s0 * c1, c0 * dx + s0 * dy, c0 * dy - s0 * dx


@uncounted
def log2_t(c, s, tx, ty, clamp):
    """``log2`` of the SE(2) placement ``([[c, -s], [s, c]], t)`` as ``(ρx, ρy, θ)``, then ``α = a/(a² + c²)`` and
    ``β = θ/2``, the entries of ``V(θ)⁻¹ = [[α, β], [-β, α]]``.  With ``clamp``, as Pinocchio's ``difference``, the
    angle is 0 where ``c`` rounds above 1 (Pinocchio's ``dDifference`` does not clamp it; unlike the continuous joint's
    difference, made exact, a planar joint's stays Pinocchio's)."""
    w = 0.0 if clamp and c > 1.0 else math.atan2(s, c)
    a, _, _, f = _se2_coefs(w)
    alpha, beta = a / (2.0 * f), 0.5 * w
    return alpha * tx + beta * ty, alpha * ty - beta * tx, w, alpha, beta


@uncounted
def jexp2_t(vx, vy, w):
    """The right Jacobian of ``exp2`` at ``[vx, vy, w]`` as a row-major 9-tuple."""
    a, c, e, f = _se2_coefs(w)
    return a, c, vx * e - vy * f, -c, a, vx * f + vy * e, 0.0, 0.0, 1.0


@uncounted
def jlog2_t(c, s, tx, ty):
    """``jlog2(M)``, the inverse of ``exp2``'s right Jacobian at ``log2 M``, as a 9-tuple: ``[[A⁻¹, -A⁻¹ b], [0, 1]]``
    with ``A⁻¹ = [[α, -β], [β, α]]`` and ``b`` that Jacobian's last column."""
    rx, ry, w, alpha, beta = log2_t(c, s, tx, ty, False)
    _, _, e, f = _se2_coefs(w)
    bx, by = rx * e - ry * f, rx * f + ry * e
    return alpha, -beta, beta * by - alpha * bx, beta, alpha, -(beta * bx + alpha * by), 0.0, 0.0, 1.0


@uncounted
def inverse_adjoint2_t(c, s, tx, ty):
    """``Ad(M)⁻¹ = [[Rᵀ, [1] Rᵀ t], [0, 1]]`` of the SE(2) placement ``(R(c, s), t)`` as a 9-tuple."""
    ux, uy = c * tx + s * ty, c * ty - s * tx
    return c, s, -uy, -s, c, ux, 0.0, 0.0, 1.0


@uncounted
def neg(a):
    """``-a`` for a 9-tuple."""
    return (-a[0], -a[1], -a[2], -a[3], -a[4], -a[5], -a[6], -a[7], -a[8])
