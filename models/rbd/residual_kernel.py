"""The residual rows of a compiled node's cost stack (or constraint table) and their Jacobians, item by item.

Each item of ``ints`` (``ITEM_FIELDS`` integers from ``ints[ITEMS]``: kind, first row, rows, frame, reference,
parameter offset, and a user residual's fields, :mod:`.node_table`) writes its rows of the stacked residual ``r``
(:func:`residual_rows`) and of the stacked ``Jx`` (and, for the force residuals of a running node, ``Ju``;
:func:`residual_jacobians`), from the kinematics in the workspace ``ws`` (a forward kinematics at the node's ``(q,
v)``), the contact forces ``λ`` and their derivatives, and the residuals' parameters in ``par``:

* state ``r = x ⊖ x_ref``; control ``r = u - u_ref``;
* frame placement ``r = log6(M_ref⁻¹ oMf)``, translation ``r = p_f - p_ref``, rotation ``r = log3(R_refᵀ R_f)``,
  velocity ``r = v_f - v_ref`` in the item's reference frame;
* cones ``r = A λ_c`` (friction and wrench cones, the centre-of-pressure support, of an active contact), a contact
  force ``r = A λ_c - f_ref`` (``A`` selecting its components; 0 at a terminal node), centre of mass ``r = c - c_ref``;
* joint efforts ``r = u - u_ref`` (``Ju = I``) and joint accelerations ``r = a - a_ref`` (``Jx = ∂a/∂x``,
  ``Ju = ∂a/∂u``, after :func:`.euler_node_kernel._dynamics_jacobians`) of a forward-dynamics node, both 0 with zero
  Jacobians at a terminal node; the gravity-compensating control ``r = S u - g(q)`` (``-g(q)`` at a terminal node;
  ``Jx = [-∂g/∂q, 0]``, ``Ju = S``: :func:`.gravity_kernel.generalized_gravity`, ``gravity_derivatives``), and in a
  contact node ``r = S u - g(q) + Jcᵀ λ`` (``Jx = [-∂g/∂q + ∂(Jcᵀ λ)/∂q, 0] + Jcᵀ ∂λ/∂x``, ``λ`` held fixed in the
  first term as :func:`.contact_kernel.contact_force_derivatives` takes it, ``Ju = S + Jcᵀ ∂λ/∂u``; a terminal node
  has no force);
* the centroidal momentum ``r = h(q, v) - h_ref`` (``Jx = [∂h/∂q, Ag]``, :mod:`.com_kernel`); an impulse node's
  centre-of-mass velocity jump ``r = Jcom (v⁺ - v)`` (``Jx = [∂(Jcom Δv)/∂q|Δv, 0] + Jcom [∂v⁺/∂q, ∂v⁺/∂v - I]``,
  written by :func:`late_jacobians` after the impulses' derivatives);
* a user's :class:`~crocopy.models.residual_numba.ResidualModelNumba` through its callbacks
  (:mod:`.user_residual_kernel`).
"""

from __future__ import annotations

from crocopy.kernels import uncounted

from .com_kernel import center_of_mass, centroidal_momentum, centroidal_momentum_derivatives, com_velocity_derivatives
from .configuration_kernel import state_diff, state_jdiff
from .contact_kernel import contact_force_derivatives
from .dynamics_kernel import (
    forward_kinematics,
    frame_jacobian,
    frame_placement,
    frame_velocity,
    frame_velocity_derivatives,
)
from .gravity_kernel import generalized_gravity, gravity_derivatives
from .lie_kernel import jlog3, jlog6, log3, log6
from .node_table import (
    ACCELERATION,
    CENTROIDAL,
    COM,
    CONE,
    CONTACT_CONTROL_GRAV,
    CONTROL,
    CONTROL_GRAV,
    E_A,
    E_COM,
    E_DF_DU,
    E_DF_DX,
    E_DFU,
    E_DFX,
    E_J6,
    E_JCOM,
    E_JCS,
    E_JU,
    E_JX,
    E_K6,
    E_LAM,
    E_M6,
    E_P3,
    E_R,
    E_R3,
    E_REF_R,
    E_S,
    E_TAU,
    E_USER_RU,
    E_V6,
    E_XNEXT,
    EFFORT,
    FLAGS,
    FORCE,
    IMPULSE_COM,
    ITEM_FIELDS,
    ITEMS,
    LOCAL,
    LOCAL_WORLD_ALIGNED,
    N_CONTACTS,
    N_ITEMS,
    NC,
    NQ,
    NU,
    NV,
    PLACEMENT,
    RESIDUAL_ADDRESS,
    ROTATION,
    STATE,
    TERMINAL,
    TRANSLATION,
    U_START,
    USER,
    VELOCITY,
    contact_fields,
    cube,
    mat,
    vec,
)
from .user_residual_kernel import user_call, user_jacobians, user_kinematics


@uncounted
def matmul(A, B, out, rows, cols, inner):
    """``out[:rows, :cols] = A[:rows, :inner] B[:inner, :cols]``."""
    for i in range(rows):
        for j in range(cols):
            acc = 0.0
            for k in range(inner):
                acc += A[i, k] * B[k, j]
            out[i, j] = acc


@uncounted
def _rotation_error(rb, ws, fid, par, o, R3):
    """``Rrefᵀ oRf`` into ``R3``; ``par[o:o+9]`` is ``Rrefᵀ`` (row-major); leaves ``oMf`` in ``ws.Rf, ws.pf``."""
    frame_placement(rb, ws, fid, ws.Rf, ws.pf)
    for i in range(3):
        for j in range(3):
            acc = 0.0
            for k in range(3):
                acc += par[o + 3 * i + k] * ws.Rf[k, j]
            R3[i, j] = acc


@uncounted
def _relative_frame(rb, ws, fid, par, o, R3, p3):
    """``pref⁻¹ oMf`` into ``(R3, p3)``; ``par[o:o+9]`` is ``pref⁻¹``'s rotation (row-major), then its translation."""
    _rotation_error(rb, ws, fid, par, o, R3)
    for i in range(3):
        acc = par[o + 9 + i]
        for k in range(3):
            acc += par[o + 3 * i + k] * ws.pf[k]
        p3[i] = acc


@uncounted
def residual_rows(tbl, ints, par, rb, ws, x, u):
    """Every compiled item's residual rows of the stack."""
    nq, nv = ints[NQ], ints[NV]
    r, R3, p3, v6 = vec(tbl, ints, E_R), mat(tbl, ints, E_R3), vec(tbl, ints, E_P3), vec(tbl, ints, E_V6)
    for n in range(ints[N_ITEMS]):
        b = ints[ITEMS] + ITEM_FIELDS * n
        kind, start, nr, fid, ref, o = ints[b], ints[b + 1], ints[b + 2], ints[b + 3], ints[b + 4], ints[b + 5]
        rows = r[start: start + nr]
        if kind == STATE:
            state_diff(rb.jtype, rb.idx_q, rb.idx_v, nq, nv, par[o: o + nq + nv], x, rows)
        elif kind == CONTROL:
            for i in range(nr):
                rows[i] = u[i] - par[o + i]
        elif kind == PLACEMENT:
            _relative_frame(rb, ws, fid, par, o, R3, p3)
            log6(R3, p3, rows)
        elif kind == TRANSLATION:
            frame_placement(rb, ws, fid, ws.Rf, ws.pf)
            for i in range(3):
                rows[i] = ws.pf[i] - par[o + i]
        elif kind == ROTATION:
            _rotation_error(rb, ws, fid, par, o, R3)
            log3(R3, rows)
        elif kind == VELOCITY:
            frame_velocity(rb, ws, fid, ref, v6)
            for i in range(6):
                rows[i] = v6[i] - par[o + i]
        elif kind == CONE or kind == FORCE:
            lam = vec(tbl, ints, E_LAM)
            for i in range(nr):
                acc = 0.0
                for j in range(ref):
                    acc += par[o + ref * i + j] * lam[fid + j]
                if kind == FORCE:  # no force at a terminal node, but an impulse node's items are flagged
                    acc = 0.0 if ints[TERMINAL] and not ints[b + FLAGS] else acc - par[o + ref * nr + i]
                rows[i] = acc
        elif kind == COM:
            com = vec(tbl, ints, E_COM)
            center_of_mass(rb, ws, com, mat(tbl, ints, E_JCOM))
            for i in range(3):
                rows[i] = com[i] - par[o + i]
        elif kind == CENTROIDAL:
            centroidal_momentum(rb, ws, vec(tbl, ints, E_COM), mat(tbl, ints, E_JCOM), rows)
            for i in range(6):
                rows[i] -= par[o + i]
        elif kind == IMPULSE_COM:
            Jcom, xnext = mat(tbl, ints, E_JCOM), vec(tbl, ints, E_XNEXT)
            center_of_mass(rb, ws, vec(tbl, ints, E_COM), Jcom)
            for i in range(3):
                acc = 0.0
                for k in range(nv):
                    acc += Jcom[i, k] * (xnext[nq + k] - x[nq + k])
                rows[i] = acc
        elif kind == CONTROL_GRAV or kind == CONTACT_CONTROL_GRAV:
            generalized_gravity(rb, ws, rows)
            tau = vec(tbl, ints, E_TAU)
            for i in range(nr):
                rows[i] = (0.0 if ints[TERMINAL] else tau[i]) - rows[i]
            if kind == CONTACT_CONTROL_GRAV and not ints[TERMINAL]:
                Jcs, lam = mat(tbl, ints, E_JCS), vec(tbl, ints, E_LAM)
                for i in range(nr):
                    acc = 0.0
                    for c in range(ints[NC]):
                        acc += Jcs[c, i] * lam[c]
                    rows[i] += acc
        elif kind == EFFORT or kind == ACCELERATION:
            if ints[TERMINAL]:
                for i in range(nr):
                    rows[i] = 0.0
            else:
                value = u if kind == EFFORT else vec(tbl, ints, E_A)
                for i in range(nr):
                    rows[i] = value[i] - par[o + i]
        elif kind == USER:
            user_kinematics(tbl, ints, rb, ws, fid, ref, ints[b + FLAGS], False)
            user_call(tbl, ints, par, b, x, u, ints[b + RESIDUAL_ADDRESS], rows, mat(tbl, ints, E_USER_RU))
        else:
            raise ValueError("compiled node: unknown residual kind")


@uncounted
def _force_jacobians(tbl, ints, par, nr, row, ncf, o, Jx_rows, start):
    """``A ∂λ/∂x`` into ``Jx_rows`` and, at a running node, ``A ∂λ/∂u`` into the stacked ``Ju`` rows of stack row
    ``start`` (``A (nr, ncf)`` row-major at ``par[o]``, ``λ`` from stacked row ``row``)."""
    df_dx, nv = mat(tbl, ints, E_DF_DX), ints[NV]
    for i in range(nr):
        for c in range(2 * nv):
            acc = 0.0
            for j in range(ncf):
                acc += par[o + ncf * i + j] * df_dx[row + j, c]
            Jx_rows[i, c] = acc
    if ints[TERMINAL]:
        return
    df_du, Ju, nu, u0 = mat(tbl, ints, E_DF_DU), mat(tbl, ints, E_JU), ints[NU], start - ints[U_START]
    for i in range(nr):
        for c in range(nu):
            acc = 0.0
            for j in range(ncf):
                acc += par[o + ncf * i + j] * df_du[row + j, c]
            Ju[u0 + i, c] = acc


@uncounted
def late_jacobians(tbl, ints, par, rb, ws, x):
    """The rows of the stacked ``Jx`` (and ``Ju``) of the items that read an impulse node's impulse derivatives (the
    flagged force items and the centre-of-mass velocity jump, which :func:`residual_jacobians` leaves), after it: the
    node computes those derivatives after its other residuals' Jacobians, whose kinematics they replace.  Leaves the
    kinematics of the last centre-of-mass item (at ``(q, v⁺ - v)``) in ``ws``."""
    Jx = mat(tbl, ints, E_JX)
    for n in range(ints[N_ITEMS]):
        b = ints[ITEMS] + ITEM_FIELDS * n
        kind, start, nr = ints[b], ints[b + 1], ints[b + 2]
        if (kind == CONE or kind == FORCE) and ints[b + FLAGS]:
            _force_jacobians(tbl, ints, par, nr, ints[b + 3], ints[b + 4], ints[b + 5], Jx[start: start + nr], start)
        elif kind == IMPULSE_COM:
            _impulse_com_rows(tbl, ints, rb, ws, x, Jx[start: start + nr])


@uncounted
def _impulse_com_rows(tbl, ints, rb, ws, x, rows):
    """``[∂(Jcom Δv)/∂q|Δv, 0] + Jcom [∂v⁺/∂q, ∂v⁺/∂v - I]`` (``Δv = v⁺ - v``, ``∂v⁺/∂x`` in ``dFx``) into ``rows
    (3, 2 nv)``; the kinematics at ``(q, Δv)`` stay in ``ws``."""
    nq, nv = ints[NQ], ints[NV]
    xnext, dv, dFx = vec(tbl, ints, E_XNEXT), vec(tbl, ints, E_TAU), mat(tbl, ints, E_DFX)
    Jcom = mat(tbl, ints, E_JCOM)
    for k in range(nv):
        dv[k] = xnext[nq + k] - x[nq + k]
    forward_kinematics(rb, ws, x[:nq], dv)
    center_of_mass(rb, ws, vec(tbl, ints, E_COM), Jcom)
    com_velocity_derivatives(rb, ws, rows)
    for i in range(3):
        for c in range(2 * nv):
            acc = 0.0
            for k in range(nv):
                acc += Jcom[i, k] * dFx[k, c]
            rows[i, c] = (rows[i, c] if c < nv else 0.0) + acc
        for k in range(nv):
            rows[i, nv + k] -= Jcom[i, k]


@uncounted
def _dynamics_rows(tbl, ints, kind, nr, Jx_rows, start):
    """The Jacobian rows of a joint-effort (``Jx = 0``, ``Ju = I``) or joint-acceleration item (``Jx = ∂a/∂x``,
    ``Ju = ∂a/∂u``) of stack row ``start``: ``Jx_rows`` and, at a running node, its rows of the stacked ``Ju``."""
    terminal = ints[TERMINAL] != 0
    acceleration = kind == ACCELERATION and not terminal
    dFx = mat(tbl, ints, E_DFX)
    for i in range(nr):
        for c in range(Jx_rows.shape[1]):
            Jx_rows[i, c] = dFx[i, c] if acceleration else 0.0
    if terminal:
        return
    dFu, Ju, u0 = mat(tbl, ints, E_DFU), mat(tbl, ints, E_JU), start - ints[U_START]
    for i in range(nr):
        for c in range(ints[NU]):
            Ju[u0 + i, c] = dFu[i, c] if acceleration else (1.0 if i == c else 0.0)


@uncounted
def _gravity_rows(tbl, ints, rb, ws, nr, Jx_rows, start, forces):
    """The Jacobian rows of a gravity-compensating control item of stack row ``start``: ``Jx = [-∂g/∂q, 0]`` and, at a
    running node, ``Ju = S`` (its rows of the stacked ``Ju``); with ``forces`` (a contact node's, running) the contact
    forces' terms too: ``∂(Jcᵀ λ)/∂q`` at a fixed ``λ`` in the ``q`` columns, then ``Jcᵀ ∂λ/∂x`` and ``Jcᵀ ∂λ/∂u``."""
    gravity_derivatives(rb, ws, Jx_rows)
    if forces:  # ∂g/∂q - ∂(Jcᵀ λ)/∂q, negated below
        lam, projections = vec(tbl, ints, E_LAM), cube(tbl, ints, E_REF_R)
        for n in range(ints[N_CONTACTS]):
            fid, nc, ref, row = contact_fields(ints, n)
            contact_force_derivatives(rb, ws, fid, nc, ref, projections[n], lam, row, Jx_rows)
    nv, nu = ints[NV], ints[NU]
    for i in range(nr):
        for c in range(nv):
            Jx_rows[i, c] = -Jx_rows[i, c]
        for c in range(nv, Jx_rows.shape[1]):
            Jx_rows[i, c] = 0.0
    if ints[TERMINAL]:
        return
    Sm, Ju, u0 = mat(tbl, ints, E_S), mat(tbl, ints, E_JU), start - ints[U_START]
    for i in range(nr):
        for c in range(nu):
            Ju[u0 + i, c] = Sm[i, c]
    if not forces:
        return
    Jcs, df_dx, df_du = mat(tbl, ints, E_JCS), mat(tbl, ints, E_DF_DX), mat(tbl, ints, E_DF_DU)
    for i in range(nr):
        for c in range(2 * nv):
            acc = 0.0
            for k in range(ints[NC]):
                acc += Jcs[k, i] * df_dx[k, c]
            Jx_rows[i, c] += acc
        for c in range(nu):
            acc = 0.0
            for k in range(ints[NC]):
                acc += Jcs[k, i] * df_du[k, c]
            Ju[u0 + i, c] += acc


@uncounted
def residual_jacobians(tbl, ints, par, rb, ws, x, u):
    """Every compiled item's rows of the stacked ``Jx`` (a control residual's are zero and stay so) and the force
    residuals' rows of ``Ju`` (after :func:`.euler_node_kernel._dynamics_jacobians` at a running node)."""
    nq, nv = ints[NQ], ints[NV]
    Jx, J6, K6, m6 = mat(tbl, ints, E_JX), mat(tbl, ints, E_J6), mat(tbl, ints, E_K6), mat(tbl, ints, E_M6)
    R3, p3, v6 = mat(tbl, ints, E_R3), vec(tbl, ints, E_P3), vec(tbl, ints, E_V6)
    ndx = 2 * nv
    for n in range(ints[N_ITEMS]):
        b = ints[ITEMS] + ITEM_FIELDS * n
        kind, start, nr, fid, ref, o = ints[b], ints[b + 1], ints[b + 2], ints[b + 3], ints[b + 4], ints[b + 5]
        if kind == CONTROL or kind == IMPULSE_COM:  # an impulse CoM's rows: late_jacobians
            continue
        rows = Jx[start: start + nr]
        if kind == STATE:
            state_jdiff(rb.jtype, rb.idx_q, rb.idx_v, nq, nv, par[o: o + nq + nv], x, False, rows)
            continue
        if kind == VELOCITY:
            _velocity_jacobian(rb, ws, fid, ref, J6, K6, m6, v6, rows, nv)
            continue
        if kind == CONE or kind == FORCE:
            if not ints[b + FLAGS]:  # a flagged one (an impulse node's): late_jacobians
                _force_jacobians(tbl, ints, par, nr, fid, ref, o, rows, start)
            continue
        if kind == USER:
            user_jacobians(tbl, ints, par, rb, ws, b, x, u, rows)
            continue
        if kind == EFFORT or kind == ACCELERATION:
            _dynamics_rows(tbl, ints, kind, nr, rows, start)
            continue
        if kind == CONTROL_GRAV or kind == CONTACT_CONTROL_GRAV:
            _gravity_rows(tbl, ints, rb, ws, nr, rows, start, kind == CONTACT_CONTROL_GRAV and not ints[TERMINAL])
            continue
        if kind == CENTROIDAL:
            com, Jcom = vec(tbl, ints, E_COM), mat(tbl, ints, E_JCOM)
            centroidal_momentum(rb, ws, com, Jcom, v6)
            centroidal_momentum_derivatives(rb, ws, com, Jcom, rows)
            continue
        for i in range(nr):
            for j in range(nv, ndx):
                rows[i, j] = 0.0
        if kind == TRANSLATION:
            frame_jacobian(rb, ws, fid, LOCAL_WORLD_ALIGNED, J6)
            for i in range(3):
                for j in range(nv):
                    rows[i, j] = J6[i, j]
        elif kind == PLACEMENT:
            frame_jacobian(rb, ws, fid, LOCAL, J6)
            _relative_frame(rb, ws, fid, par, o, R3, p3)
            jlog6(R3, p3, m6)
            matmul(m6, J6, rows, 6, nv, 6)
        elif kind == COM:
            Jcom = mat(tbl, ints, E_JCOM)
            center_of_mass(rb, ws, vec(tbl, ints, E_COM), Jcom)
            for i in range(3):
                for j in range(nv):
                    rows[i, j] = Jcom[i, j]
        else:
            frame_jacobian(rb, ws, fid, LOCAL, J6)
            _rotation_error(rb, ws, fid, par, o, R3)
            jlog3(R3, m6[:3, :3])
            for i in range(3):
                for j in range(nv):
                    acc = 0.0
                    for k in range(3):
                        acc += m6[i, k] * J6[3 + k, j]
                    rows[i, j] = acc


@uncounted
def _velocity_jacobian(rb, ws, fid, ref, dq, dv, m6, v6, rows, nv):
    """``(∂v_f/∂q, ∂v_f/∂v)`` in frame ``ref``; LOCAL_WORLD_ALIGNED as ``R (∂v_l/∂q - [v_l]× J_ω)`` (see
    :class:`~crocopy.models.ResidualModelFrameVelocity`), ``R`` the frame rotation."""
    if ref != LOCAL_WORLD_ALIGNED:
        frame_velocity_derivatives(rb, ws, fid, ref, dq, dv)
        for i in range(6):
            for j in range(nv):
                rows[i, j] = dq[i, j]
                rows[i, nv + j] = dv[i, j]
        return
    frame_velocity_derivatives(rb, ws, fid, LOCAL, dq, dv)
    frame_velocity(rb, ws, fid, LOCAL, v6)
    frame_placement(rb, ws, fid, ws.Rf, ws.pf)
    R = ws.Rf
    for half in range(2):
        s = 3 * half
        for j in range(nv):
            # (∂v_l/∂q - [v_l]× J_ω) column j for rows s..s+2, J_ω = dv[3:6] (the LOCAL Jacobian)
            c0 = dq[s, j] - (v6[s + 1] * dv[5, j] - v6[s + 2] * dv[4, j])
            c1 = dq[s + 1, j] - (v6[s + 2] * dv[3, j] - v6[s] * dv[5, j])
            c2 = dq[s + 2, j] - (v6[s] * dv[4, j] - v6[s + 1] * dv[3, j])
            for i in range(3):
                rows[s + i, j] = R[i, 0] * c0 + R[i, 1] * c1 + R[i, 2] * c2
                rows[s + i, nv + j] = R[i, 0] * dv[s, j] + R[i, 1] * dv[s + 1, j] + R[i, 2] * dv[s + 2, j]
