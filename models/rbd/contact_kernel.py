"""Compiled rigid contacts on a lowered model: contact Jacobian and drift, their derivatives, the contact forces'
term of the RNEA derivatives, and the contact forward dynamics with its derivatives.

Conventions are :mod:`.dynamics_kernel`'s (world-frame spatial quantities at the world origin, ``[linear;
angular]``, reference codes ``LOCAL = 1``, ``LOCAL_WORLD_ALIGNED = 2``); the contacts are those of
:mod:`crocopy.models.contacts`, where ``WORLD`` means ``LOCAL_WORLD_ALIGNED``: so here does any code but LOCAL.
A contact acts on frame ``fid`` (placement ``oMf = (R, p)``) with ``nc = 3`` (a point: translation) or ``nc = 6`` rows
and Baumgarte gains ``(kp, kd)``.  With ``X = oXf`` the frame's action, ``J = X⁻¹ oS`` its LOCAL Jacobian and,
at joint acceleration ``a``, ``v_f = X⁻¹ ov_i``, ``a_f = X⁻¹ (oa_i + g)`` (``g`` the model gravity: ``ws.oa``
includes ``-g``) its LOCAL velocity ``(v_l, ω)`` and spatial acceleration::

    3D:  Jc = J_l,   c = a_f,l + ω × v_l + kp Rᵀ(p - p_ref) + kd v_l           (classical acceleration)
    6D:  Jc = J,     c = a_f + kp log6(M_ref⁻¹ oMf) + kd v_f
    LOCAL_WORLD_ALIGNED: Jc and c rotated by R (each 3-block).

``c(q, v, a) = Jc a + a0`` where the drift ``a0 = c(q, v, 0)``; the contact ``Jc a + a0 = 0`` holds at the
solution.  A tangent ``δ`` of dof ``k`` of joint ``j`` (``s = oS_k``, ``λ(j)`` its parent) on the support of
the frame's joint ``i`` moves (see :mod:`.dynamics_kernel`)::

    d v_f / dq_k = X⁻¹ (ov_λ(j) × s)
    d a_f / dq_k = X⁻¹ (oa_λ(j) × s + (ov_λ(j) × s) × (ov_i - ov_λ(j)))
    d a_f / dv_k = X⁻¹ (s × (ov_i - ov_λ(j)) + ov_j × s),        d v_f / dv_k = d a_f / da_k = J_k

(accelerations without gravity), ``d(Rᵀ(p - p_ref)) = J_l δ + [Rᵀ(p - p_ref)]× J_ω δ``, ``d log6(M_ref⁻¹ oMf)
= Jlog6 J δ`` and, in LOCAL_WORLD_ALIGNED, ``d(R c) = R (dc + J_ω δ × c)`` per 3-block.  These give
``∂c/∂(q, v)`` at the ``a`` the kinematics hold: ``da0_dx`` at ``a = 0`` and, at the contact solution, what
Crocoddyl's contact dynamics differentiate (``∂(Jc a + a0)/∂x`` with ``a`` fixed).

A 1D or 2D contact (``nc`` 1 or 2) is rows of a point contact: with ``P (nc, 3)`` the first ``nc`` rows of its
``ref_R`` (the projection, which it lowers there: ``e_zᵀ Raxis`` for a 1D contact, ``(e_x, e_z)ᵀ`` for a 2D one), its
rows are ``P`` times the 3D contact's (after the LOCAL_WORLD_ALIGNED rotation) and its force is ``Pᵀ λ`` in the 3D
contact's coordinates.  A 2D contact (LOCAL) compares the world position instead: its 3D rows have no ``kp`` term,
and ``kp (P p - ref_p)`` (``ref_p`` its first two entries) is added to the drift, ``kp P R J_l`` to ``∂c/∂q``.

Contact forces ``λ`` (``nc`` rows, in the contact's coordinates) enter the dynamics as ``M a + b = τ + Jcᵀ λ``.
With ``F = [R f_l; p × R f_l + R f_ω]`` (LOCAL) or ``[f_l; p × f_l + f_ω]`` (LOCAL_WORLD_ALIGNED) the world
wrench of ``λ = (f_l, f_ω)`` (``f_ω = 0`` in 3D), ``Jcᵀ λ = Σ_k oS_kᵀ F`` over the support and, for a dof ``k``
of joint ``j`` and a dof ``r`` of joint ``l`` on the support, ``∂(Jcᵀ λ)_r / ∂q_k = oS_rᵀ dF - [l ⪰ j] oS_rᵀ
(s ×* F)`` with ``dF = s ×* F`` (LOCAL: zero unless ``l`` is a strict ancestor of ``j``) or ``[0; (s_v + s_ω ×
p) × f_l]`` (LOCAL_WORLD_ALIGNED).

Contact forward dynamics (Pinocchio's ``forwardDynamics(model, data, tau, Jc, a0, damping)``)::

    a_free = M⁻¹ (τ - b),  Y = M⁻¹ Jcᵀ,  G = Jc Y + damping I = Lc Lcᵀ,
    λ = -G⁻¹ (a0 + Jc a_free),  a = a_free + Y λ

and, with ``∂ID/∂x`` the derivatives of ``RNEA(q, v, a) - Jcᵀ λ`` and ``∂τ/∂u = S`` (constant actuation),
column by column (the KKT inverse of Crocoddyl's ``calcDiff`` applied without forming it)::

    z = -M⁻¹ ∂ID/∂x_c,   w = G⁻¹ (Jc z + ∂c/∂x_c),   Fx_c = z - Y w,   ∂λ/∂x_c = -w
    z = M⁻¹ S_c,         w = G⁻¹ Jc z,               Fu_c = z - Y w,   ∂λ/∂u_c = -w

Kernels write into ``ws``, the contact workspace ``cw`` (:class:`ContactWorkspace`) and their ``*_out`` arrays
and allocate nothing; stacked arrays are addressed by a first ``row`` (no slices: one compiled type per array).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from crocopy.kernels import uncounted
from crocopy.solvers.riccati_kernel import cholesky_solve, triangular_solve

from .dynamics_kernel import LOCAL, LOCAL_WORLD_ALIGNED, factor_solve, frame_jacobian, frame_pose, to_reference
from .lie_kernel import jlog6, log6
from .lowering import RigidBodyModel, RigidBodyWorkspace
from .spatial import dot, fcross, get6, mcross, minus, plus, times

__all__ = [
    "LOCAL",
    "LOCAL_WORLD_ALIGNED",
    "ContactWorkspace",
    "contact_calc",
    "contact_calc_diff",
    "contact_dynamics_derivatives",
    "contact_force_derivatives",
    "contact_forward_dynamics",
    "make_contact_workspace",
]


class ContactWorkspace(NamedTuple):
    """Scratch of the contact kernels, for at most ``nc_max`` stacked contact rows.

    ``J6 (6, nv)``: the LOCAL Jacobian of the last contact frame.  ``Y (nv, nc_max)``: ``M⁻¹ Jcᵀ``;
    ``G (nc_max, nc_max)``: lower Cholesky factor of ``Jc M⁻¹ Jcᵀ + damping I`` (both from the last
    :func:`contact_forward_dynamics`).  ``m6 (6,)``, ``J66 (6, 6)``, ``R3 (3, 3)``, ``p3 (3,)``: scratch.
    """

    J6: np.ndarray
    Y: np.ndarray
    G: np.ndarray
    m6: np.ndarray
    J66: np.ndarray
    R3: np.ndarray
    p3: np.ndarray


CONTACT_WORKSPACE = {"J6": (6, "nv"), "Y": ("nv", "ncm"), "G": ("ncm", "ncm"),
                     "m6": (6,), "J66": (6, 6), "R3": (3, 3), "p3": (3,)}
"""The shapes of :class:`ContactWorkspace`'s fields (in their order; ``ncm = max(nc_max, 1)``)."""


def make_contact_workspace(rb: RigidBodyModel, nc_max: int) -> ContactWorkspace:
    """A zeroed :class:`ContactWorkspace` for ``rb`` and up to ``nc_max`` stacked contact rows."""
    sizes = {"nv": rb.nv, "ncm": max(int(nc_max), 1)}
    return ContactWorkspace(*(np.zeros(tuple(d if isinstance(d, int) else sizes[d] for d in shape))
                              for shape in CONTACT_WORKSPACE.values()))


@uncounted
def _cross(a0, a1, a2, b0, b1, b2):
    """``a × b`` of two 3-vectors given by their components."""
    return a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0


@uncounted
def _rotate(R, m):
    """``(R m_l, R m_ω)`` of a 6-tuple."""
    return (
        R[0, 0] * m[0] + R[0, 1] * m[1] + R[0, 2] * m[2],
        R[1, 0] * m[0] + R[1, 1] * m[1] + R[1, 2] * m[2],
        R[2, 0] * m[0] + R[2, 1] * m[1] + R[2, 2] * m[2],
        R[0, 0] * m[3] + R[0, 1] * m[4] + R[0, 2] * m[5],
        R[1, 0] * m[3] + R[1, 1] * m[4] + R[1, 2] * m[5],
        R[2, 0] * m[3] + R[2, 1] * m[4] + R[2, 2] * m[5],
    )


@uncounted
def _project(P, nc, m):
    """The rows of a 1D or 2D contact (``nc`` 1 or 2): ``P[:nc] m_l`` in a 6-tuple (zeros after)."""
    first = P[0, 0] * m[0] + P[0, 1] * m[1] + P[0, 2] * m[2]
    second = P[1, 0] * m[0] + P[1, 1] * m[1] + P[1, 2] * m[2] if nc == 2 else 0.0
    return first, second, 0.0, 0.0, 0.0, 0.0


@uncounted
def _no_gravity(rb, ws, i):
    """``oa_i + g``: the spatial acceleration of joint ``i`` without the gravity RNEA puts at the root."""
    g = rb.gravity
    return plus(get6(ws.oa, i), (g[0], g[1], g[2], g[3], g[4], g[5]))


@uncounted
def _frame_motion(rb, ws, cw, fid, nc, kp, kd, ref_R, ref_p):
    """Frame pose (``ws.Rf, ws.pf``), LOCAL Jacobian (``cw.J6``); returns the joint ``i``, ``v_f`` and the LOCAL
    contact acceleration ``c`` (6-tuple; 3D: zero angular part) at the kinematics in ``ws``.  For a 6D contact
    with ``kp ≠ 0`` leaves ``M_ref⁻¹ oMf`` in ``cw.R3, cw.p3``; for a 3D one, ``cw.p3 = Rᵀ(p - p_ref)``."""
    frame_jacobian(rb, ws, fid, LOCAL, cw.J6)
    i = rb.frame_joint[fid]
    R, p = ws.Rf, ws.pf
    vf = to_reference(R, p, get6(ws.ov, i), LOCAL)
    af = to_reference(R, p, _no_gravity(rb, ws, i), LOCAL)
    if nc == 3:
        wv = _cross(vf[3], vf[4], vf[5], vf[0], vf[1], vf[2])
        d = (p[0] - ref_p[0], p[1] - ref_p[1], p[2] - ref_p[2])
        for r in range(3):
            cw.p3[r] = R[0, r] * d[0] + R[1, r] * d[1] + R[2, r] * d[2]
        c = (
            af[0] + wv[0] + kp * cw.p3[0] + kd * vf[0],
            af[1] + wv[1] + kp * cw.p3[1] + kd * vf[1],
            af[2] + wv[2] + kp * cw.p3[2] + kd * vf[2],
            0.0, 0.0, 0.0,
        )
        return i, vf, c
    c = plus(af, times(vf, kd))
    if kp != 0.0:
        R3, p3 = cw.R3, cw.p3
        for r in range(3):
            p3[r] = ref_R[0, r] * (p[0] - ref_p[0]) + ref_R[1, r] * (p[1] - ref_p[1]) + ref_R[2, r] * (p[2] - ref_p[2])
            for k in range(3):
                R3[r, k] = ref_R[0, r] * R[0, k] + ref_R[1, r] * R[1, k] + ref_R[2, r] * R[2, k]
        log6(R3, p3, cw.m6)
        m = cw.m6
        c = plus(c, times((m[0], m[1], m[2], m[3], m[4], m[5]), kp))
    return i, vf, c


@uncounted
def contact_calc(
    rb: RigidBodyModel,
    ws: RigidBodyWorkspace,
    cw: ContactWorkspace,
    fid: int,
    nc: int,
    reference: int,
    kp: float,
    kd: float,
    ref_R: np.ndarray,
    ref_p: np.ndarray,
    row: int,
    Jc_out: np.ndarray,
    a0_out: np.ndarray,
) -> None:
    """Rows ``row`` to ``row + nc - 1`` of the stacked ``Jc_out (·, nv)`` and drift ``a0_out (·,)`` of a contact.

    ``nc`` is 3 (point contact, reference position ``ref_p (3,)``; ``ref_R`` unused), 6 (reference placement
    ``(ref_R (3, 3), ref_p (3,))``) or 1, 2 (rows ``ref_R[:nc]`` of a point contact, module docstring); ``reference``
    LOCAL or LOCAL_WORLD_ALIGNED.  Needs the kinematics at zero
    joint acceleration in ``ws`` (:func:`~.dynamics_kernel.forward_dynamics`).
    """
    _, _, c = _frame_motion(rb, ws, cw, fid, 6 if nc == 6 else 3, 0.0 if nc == 2 else kp, kd, ref_R, ref_p)
    R, p, J, lwa = ws.Rf, ws.pf, cw.J6, reference != LOCAL
    if lwa:
        c = _rotate(R, c)
    if nc < 3:
        c = _project(ref_R, nc, c)
        if nc == 2:
            c = plus(c, times(minus(_project(ref_R, 2, (p[0], p[1], p[2])), (ref_p[0], ref_p[1], 0.0, 0.0, 0.0, 0.0)),
                              kp))
    for r in range(nc):
        a0_out[row + r] = c[r]
    for k in range(rb.nv):
        col = (J[0, k], J[1, k], J[2, k], J[3, k], J[4, k], J[5, k])
        if lwa:
            col = _rotate(R, col)
        if nc < 3:
            col = _project(ref_R, nc, col)
        for r in range(nc):
            Jc_out[row + r, k] = col[r]


@uncounted
def contact_calc_diff(
    rb: RigidBodyModel,
    ws: RigidBodyWorkspace,
    cw: ContactWorkspace,
    fid: int,
    nc: int,
    reference: int,
    kp: float,
    kd: float,
    ref_R: np.ndarray,
    ref_p: np.ndarray,
    row: int,
    da0_dx_out: np.ndarray,
) -> None:
    """Rows ``row`` to ``row + nc - 1`` of ``da0_dx_out (·, 2 nv)``: ``∂c/∂q`` (tangent) then ``∂c/∂v`` of the contact
    acceleration ``c = Jc a + a0`` (arguments as :func:`contact_calc`) at the joint acceleration ``a`` of the
    kinematics in ``ws``: ``da0_dx`` after :func:`~.dynamics_kernel.forward_dynamics` (``a = 0``), the
    derivative Crocoddyl's contact dynamics use after :func:`~.dynamics_kernel.dynamics_derivatives` at ``a``.
    """
    kp_point = 0.0 if nc == 2 else kp
    point = nc != 6
    i, vf, c = _frame_motion(rb, ws, cw, fid, 3 if point else 6, kp_point, kd, ref_R, ref_p)
    R, p, J, oS, ov = ws.Rf, ws.pf, cw.J6, ws.oS, ws.ov
    nv, lwa = rb.nv, reference != LOCAL
    if nc == 6 and kp != 0.0:
        jlog6(cw.R3, cw.p3, cw.J66)
    L = cw.J66
    for r in range(nc):
        for k in range(2 * nv):
            da0_dx_out[row + r, k] = 0.0
    ovi = get6(ov, i)
    j = i
    while j > 0:
        par = rb.parent[j]
        ovp, oap, ovj = get6(ov, par), _no_gravity(rb, ws, par), get6(ov, j)
        for k in range(rb.idx_v[j], rb.idx_v[j] + rb.nvj[j]):
            s = get6(oS, k)
            Jk = (J[0, k], J[1, k], J[2, k], J[3, k], J[4, k], J[5, k])
            psi = mcross(ovp, s)
            vq = to_reference(R, p, psi, LOCAL)
            aq = to_reference(R, p, plus(mcross(oap, s), mcross(psi, minus(ovi, ovp))), LOCAL)
            av = to_reference(R, p, plus(mcross(s, minus(ovi, ovp)), mcross(ovj, s)), LOCAL)
            if point:
                x = _cross(vf[3], vf[4], vf[5], vq[0], vq[1], vq[2])
                y = _cross(vq[3], vq[4], vq[5], vf[0], vf[1], vf[2])
                e = _cross(cw.p3[0], cw.p3[1], cw.p3[2], Jk[3], Jk[4], Jk[5])
                dq = (
                    aq[0] + x[0] + y[0] + kd * vq[0] + kp_point * (Jk[0] + e[0]),
                    aq[1] + x[1] + y[1] + kd * vq[1] + kp_point * (Jk[1] + e[1]),
                    aq[2] + x[2] + y[2] + kd * vq[2] + kp_point * (Jk[2] + e[2]),
                    0.0, 0.0, 0.0,
                )
                x = _cross(vf[3], vf[4], vf[5], Jk[0], Jk[1], Jk[2])
                y = _cross(Jk[3], Jk[4], Jk[5], vf[0], vf[1], vf[2])
                dv = (av[0] + x[0] + y[0] + kd * Jk[0], av[1] + x[1] + y[1] + kd * Jk[1],
                      av[2] + x[2] + y[2] + kd * Jk[2], 0.0, 0.0, 0.0)
            else:
                dq = plus(aq, times(vq, kd))
                dv = plus(av, times(Jk, kd))
                if kp != 0.0:
                    lj = (dot(get6(L, 0), Jk), dot(get6(L, 1), Jk), dot(get6(L, 2), Jk),
                          dot(get6(L, 3), Jk), dot(get6(L, 4), Jk), dot(get6(L, 5), Jk))
                    dq = plus(dq, times(lj, kp))
            if lwa:
                x = _cross(Jk[3], Jk[4], Jk[5], c[0], c[1], c[2])
                y = _cross(Jk[3], Jk[4], Jk[5], c[3], c[4], c[5])
                dq = _rotate(R, (dq[0] + x[0], dq[1] + x[1], dq[2] + x[2], dq[3] + y[0], dq[4] + y[1], dq[5] + y[2]))
                dv = _rotate(R, dv)
            if nc < 3:
                dq, dv = _project(ref_R, nc, dq), _project(ref_R, nc, dv)
                if nc == 2:
                    dq = plus(dq, times(_project(ref_R, 2, _rotate(R, Jk)), kp))
            for r in range(nc):
                da0_dx_out[row + r, k] = dq[r]
                da0_dx_out[row + r, nv + k] = dv[r]
        j = par


@uncounted
def contact_force_derivatives(
    rb: RigidBodyModel,
    ws: RigidBodyWorkspace,
    fid: int,
    nc: int,
    reference: int,
    P: np.ndarray,
    lam: np.ndarray,
    row: int,
    dtau_dq_inout: np.ndarray,
) -> None:
    """``dtau_dq_inout (nv, nv) -= ∂(Jcᵀ λ)/∂q`` for the contact force ``λ = lam[row : row + nc]`` (in the
    contact's coordinates, ``nc`` 3 or 6, or 1, 2 with the projection ``P[:nc]`` (the force ``Pᵀ λ`` of a point
    contact), ``reference`` LOCAL or LOCAL_WORLD_ALIGNED), ``λ`` held fixed: added
    to :func:`~.dynamics_kernel.dynamics_derivatives`' ``∂RNEA/∂q`` it gives ``∂(RNEA - Σ Jcᵀ λ)/∂q`` (what
    ``computeRNEADerivatives`` with the contact forces as ``fext`` and ``updateRneaDiff`` give).  Needs the
    kinematics in ``ws``; ``O(depth²)``."""
    i = frame_pose(rb, ws, fid)
    R, p, oS = ws.Rf, ws.pf, ws.oS
    if nc < 3:
        l1 = lam[row + 1] if nc == 2 else 0.0
        fl = (P[0, 0] * lam[row] + P[1, 0] * l1, P[0, 1] * lam[row] + P[1, 1] * l1, P[0, 2] * lam[row] + P[1, 2] * l1)
    else:
        fl = (lam[row], lam[row + 1], lam[row + 2])
    fa = (lam[row + 3], lam[row + 4], lam[row + 5]) if nc == 6 else (0.0, 0.0, 0.0)
    if reference == LOCAL:
        w = _rotate(R, (fl[0], fl[1], fl[2], fa[0], fa[1], fa[2]))
        fl, fa = (w[0], w[1], w[2]), (w[3], w[4], w[5])
    t = _cross(p[0], p[1], p[2], fl[0], fl[1], fl[2])
    F = (fl[0], fl[1], fl[2], fa[0] + t[0], fa[1] + t[1], fa[2] + t[2])
    parent, idx_v, nvj = rb.parent, rb.idx_v, rb.nvj
    j = i
    while j > 0:
        for k in range(idx_v[j], idx_v[j] + nvj[j]):
            s = get6(oS, k)
            sf = fcross(s, F)
            if reference == LOCAL:
                dF = sf
            else:
                sp = _cross(s[3], s[4], s[5], p[0], p[1], p[2])
                d = _cross(s[0] + sp[0], s[1] + sp[1], s[2] + sp[2], fl[0], fl[1], fl[2])
                dF = (0.0, 0.0, 0.0, d[0], d[1], d[2])
            l = i
            while l > 0:
                g = minus(dF, sf) if l >= j else dF
                for r in range(idx_v[l], idx_v[l] + nvj[l]):
                    s_r = get6(oS, r)
                    dtau_dq_inout[r, k] -= (
                        s_r[0] * g[0] + s_r[1] * g[1] + s_r[2] * g[2] + s_r[3] * g[3] + s_r[4] * g[4] + s_r[5] * g[5]
                    )
                l = parent[l]
        j = parent[j]


@uncounted
def schur_factor(rb: RigidBodyModel, ws: RigidBodyWorkspace, cw: ContactWorkspace, Jc: np.ndarray, nc: int,
                 damping: float) -> None:
    """``cw.Y[:, :nc] = M⁻¹ Jcᵀ`` and ``cw.G``, the lower Cholesky factor of ``Jc M⁻¹ Jcᵀ + damping I`` (first ``nc``
    rows of ``Jc``), with the factor of ``M`` in ``ws``; ``G`` holds NaN (never a division by zero) where the
    matrix is not positive definite.  The ``nc`` solves run at once, the contact rows innermost."""
    nv, Y, G = rb.nv, cw.Y, cw.G
    for k in range(nv):
        for r in range(nc):
            Y[k, r] = Jc[r, k]
    _factor_solve_columns(rb.dof_parent, ws.L, ws.dinv, Y, nc)
    for r in range(nc):
        for c in range(r + 1):
            G[r, c] = 0.0
        G[r, r] = damping
        for k in range(nv):
            j = Jc[r, k]
            for c in range(r + 1):
                G[r, c] += j * Y[k, c]
        for c in range(r + 1):
            acc = G[r, c]
            for k in range(c):
                acc -= G[r, k] * G[c, k]
            G[r, c] = (math.sqrt(acc) if acc > 0.0 else math.nan) if r == c else acc / G[c, c]


@uncounted
def contact_forward_dynamics(
    rb: RigidBodyModel,
    ws: RigidBodyWorkspace,
    cw: ContactWorkspace,
    tau: np.ndarray,
    Jc: np.ndarray,
    a0: np.ndarray,
    nc: int,
    damping: float,
    a_out: np.ndarray,
    lam_out: np.ndarray,
) -> None:
    """``a_out (nv,)`` and ``lam_out[:nc]`` of the contact forward dynamics with the first ``nc`` rows of the stacked
    ``Jc (·, nv)`` and ``a0 (·,)`` (see the module docstring).  Needs :func:`~.dynamics_kernel.forward_dynamics`
    at the same ``(q, v)`` (its factor of ``M`` and ``ws.tau = b``); leaves ``cw.Y`` and ``cw.G``.  ``nc = 0`` is
    free dynamics.  Not a number (never a division by zero) if ``Jc M⁻¹ Jcᵀ + damping I`` is not positive
    definite."""
    nv, Y = rb.nv, cw.Y
    for k in range(nv):
        a_out[k] = tau[k] - ws.tau[k]
    factor_solve(rb.dof_parent, ws.L, ws.dinv, a_out)
    schur_factor(rb, ws, cw, Jc, nc, damping)
    for r in range(nc):
        acc = a0[r]
        for k in range(nv):
            acc += Jc[r, k] * a_out[k]
        lam_out[r] = -acc
    cholesky_solve(cw.G, nc, lam_out)
    for r in range(nc):
        for k in range(nv):
            a_out[k] += Y[k, r] * lam_out[r]


@uncounted
def contact_dynamics_derivatives(
    rb: RigidBodyModel,
    ws: RigidBodyWorkspace,
    cw: ContactWorkspace,
    Jc: np.ndarray,
    nc: int,
    did_dq: np.ndarray,
    did_dv: np.ndarray,
    da0_dx: np.ndarray,
    S: np.ndarray,
    Fx_out: np.ndarray,
    Fu_out: np.ndarray,
    df_dx_out: np.ndarray,
    df_du_out: np.ndarray,
) -> None:
    """``Fx_out (nv, 2 nv)``, ``Fu_out (nv, nu)`` and rows ``:nc`` of ``df_dx_out (·, 2 nv)``, ``df_du_out (·, nu)``:
    the derivatives of the contact forward dynamics' ``a`` and ``λ`` for ``τ = S u`` (``S (nv, nu)`` constant).

    ``did_dq, did_dv (nv, nv)``: ``∂(RNEA - Σ Jcᵀ λ)/∂(q, v)`` at the solution ``(a, λ)``
    (:func:`~.dynamics_kernel.dynamics_derivatives` then :func:`contact_force_derivatives`); ``da0_dx (·, 2 nv)``:
    :func:`contact_calc_diff` at ``a``.  Uses the factors left by :func:`contact_forward_dynamics` (``ws.L``,
    ``cw.Y``, ``cw.G``); ``O((2 nv + nu) (nv · depth + nc nv))``.
    """
    nv, nu, dof_parent, L, dinv = rb.nv, S.shape[1], rb.dof_parent, ws.L, ws.dinv
    W = df_dx_out[:nc]
    for k in range(nv):
        for c in range(nv):
            Fx_out[k, c] = -did_dq[k, c]
            Fx_out[k, nv + c] = -did_dv[k, c]
    for r in range(nc):
        for c in range(2 * nv):
            W[r, c] = da0_dx[r, c]
    _kkt_columns(dof_parent, L, dinv, Jc, cw.Y, cw.G, nc, Fx_out, W)
    W = df_du_out[:nc]
    for k in range(nv):
        for c in range(nu):
            Fu_out[k, c] = S[k, c]
    for r in range(nc):
        for c in range(nu):
            W[r, c] = 0.0
    _kkt_columns(dof_parent, L, dinv, Jc, cw.Y, cw.G, nc, Fu_out, W)


@uncounted
def _kkt_columns(dof_parent, L, dinv, Jc, Y, G, nc, Z, W):
    """Each column ``(z, w)`` of ``Z (nv, m)``, ``W (nc, m)`` (right-hand sides ``r`` and ``∂c/∂x`` terms ``e``) ←
    the contact KKT solution ``z = M⁻¹ (r - Jcᵀ w')``, ``w = -w'`` with ``w' = G⁻ᵀ G⁻¹ (Jc M⁻¹ r + e)``, by the
    factors of :func:`contact_forward_dynamics`.  Every column goes through the operations a single right-hand side
    would, in the same order (the same numbers to the bit), with the loop over the columns innermost (vectorised)."""
    nv, m = Z.shape[0], Z.shape[1]
    _factor_solve_columns(dof_parent, L, dinv, Z, m)
    for r in range(nc):
        for k in range(nv):
            j = Jc[r, k]
            for c in range(m):
                W[r, c] += j * Z[k, c]
    triangular_solve(G, W, False)  # W has nc rows: (G Gᵀ)⁻¹ on each column, the columns innermost
    triangular_solve(G, W, True)
    for r in range(nc):
        for k in range(nv):
            y = Y[k, r]
            for c in range(m):
                Z[k, c] -= y * W[r, c]
    for r in range(nc):
        for c in range(m):
            W[r, c] = -W[r, c]


@uncounted
def _factor_solve_columns(lam, L, dinv, X, m):
    """:func:`~.dynamics_kernel.factor_solve` on the first ``m`` columns of ``X (nv, ·)``, the columns innermost."""
    n = X.shape[0]
    for k in range(n - 1, -1, -1):
        d = dinv[k]
        for c in range(m):
            X[k, c] *= d
        i = lam[k]
        while i >= 0:
            f = L[k, i]
            for c in range(m):
                X[i, c] -= f * X[k, c]
            i = lam[i]
    for k in range(n):
        i = lam[k]
        while i >= 0:
            f = L[k, i]
            for c in range(m):
                X[k, c] -= f * X[i, c]
            i = lam[i]
        d = dinv[k]
        for c in range(m):
            X[k, c] *= d
