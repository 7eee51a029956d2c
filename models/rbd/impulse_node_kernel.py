"""The compiled calc and calcDiff of an impulse node (see :mod:`.impulse_node`).

One call evaluates the whole node of :class:`~crocopy.models.ActionModelImpulseFwdDynamics`: with ``M`` the
inertia (armature included), ``e = par[0]`` the restitution coefficient, ``μ = par[1]`` the damping and the
impulses' stacked ``Jc`` (rows ``Jc = J_l`` or ``R J_l`` of a 3D impulse, ``J`` or ``(R J_l; R J_ω)`` of a 6D one,
``J`` the LOCAL frame Jacobian, ``R`` the frame rotation)::

    Y = M⁻¹ Jcᵀ,  G = Jc Y + μ I = Lc Lcᵀ,  Λ = -(1 + e) G⁻¹ Jc v⁻,  v⁺ = v⁻ + Y Λ,   xnext = (q, v⁺)

(the solution of ``[M Jcᵀ; Jc -μI] [v⁺; -Λ] = [M v⁻; -e Jc v⁻]``), then the cost stack's residuals, activations
and weighted sums at ``x`` (the residual kernels of :mod:`.euler_node_kernel`, evaluated as at a node without
control).  ``calcDiff`` differentiates ``M(q)(v⁺ - v⁻) - Jcᵀ Λ = 0`` and ``Jc(q)(v⁺ + e v⁻) = 0``: with ``∂ID/∂q``
the RNEA derivatives at zero velocity and gravity with acceleration ``v⁺ - v⁻``, minus the impulses' term
(:func:`~.contact_kernel.contact_force_derivatives`), and ``dv0_dq = ∂(Jc(q) w)/∂q`` at ``w = v⁺ + e v⁻``
(LOCAL_WORLD_ALIGNED: ``R (∂v_l/∂q - [v_l]× J_ω)`` per 3-block), the KKT solve of
:func:`~.contact_kernel.contact_dynamics_derivatives` with the right-hand sides ``(-∂ID/∂q, -dv0_dq)`` (``q``
columns) and ``(M, -e Jc)`` (``v`` columns) gives ``∂v⁺/∂x`` (and ``∂Λ/∂x``), and
``Fx = [[I, 0], [∂v⁺/∂q, ∂v⁺/∂v⁻]]``.

The arrays arrive in the table of :mod:`.node_table` (the Euler node's layout, so that the residual kernels read
theirs): the impulses are listed as contacts (``CONTACT_FIELDS`` integers each: frame, rows, reference frame,
first row), their stacked rows use the contact scratch (``Jcs``, ``lam``, ``da0_dx``, ``df_dx``, the contact
workspace), ``dFx`` holds ``∂v⁺/∂x``; the table's gravity entry is a zero vector (only the RNEA derivatives read
it).
"""

from __future__ import annotations

from crocopy.costs.stack_kernel import activation_values, derivatives_and_sums
from crocopy.kernels import compiled, uncounted
from crocopy.solvers.riccati_kernel import cholesky_solve

from .constraint_rows_kernel import constraint_table, has_rows, stack_rows
from .contact_kernel import contact_dynamics_derivatives, contact_force_derivatives, schur_factor
from .dynamics_kernel import (
    dynamics_derivatives,
    forward_dynamics,
    forward_kinematics,
    frame_jacobian,
    frame_velocity,
    frame_velocity_derivatives,
)
from .euler_node_kernel import constraint_values
from .node_table import (
    E_A,
    E_ACT_WEIGHTS,
    E_AR,
    E_ARR,
    E_COLS,
    E_DA0_DX,
    E_DF_DU,
    E_DF_DX,
    E_DFU,
    E_DFX,
    E_DTAU_DQ,
    E_DTAU_DV,
    E_FX,
    E_ITEM_COSTS,
    E_ITEM_WEIGHTS,
    E_J6,
    E_JCS,
    E_JU,
    E_JX,
    E_K6,
    E_LAM,
    E_LB,
    E_LU,
    E_LUU,
    E_LX,
    E_LXU,
    E_LXX,
    E_R,
    E_REF_R,
    E_S,
    E_TAU,
    E_UB,
    E_V6,
    E_WEIGHTS,
    E_XNEXT,
    LOCAL,
    N_CONTACTS,
    N_STACK,
    NC,
    NQ,
    NV,
    STARTS,
    U_START,
    contact_fields,
    cube,
    entry_contact_workspace,
    entry_model,
    entry_workspace,
    ivec,
    mat,
    vec,
)
from .residual_kernel import late_jacobians, residual_jacobians, residual_rows


@uncounted
def _impulse_jacobian(tbl, ints, rb, ws, Jcs):
    """The impulses' stacked ``Jc`` into ``Jcs`` (after the kinematics at ``q``)."""
    J6, nv = mat(tbl, ints, E_J6), ints[NV]
    for n in range(ints[N_CONTACTS]):
        fid, nc, ref, row = contact_fields(ints, n)
        frame_jacobian(rb, ws, fid, LOCAL, J6)
        R = ws.Rf
        for r in range(nc):
            b, i = r - r % 3, r % 3
            for k in range(nv):
                if ref == LOCAL:
                    Jcs[row + r, k] = J6[r, k]
                else:
                    Jcs[row + r, k] = R[i, 0] * J6[b, k] + R[i, 1] * J6[b + 1, k] + R[i, 2] * J6[b + 2, k]


@uncounted
def _impulse_velocity(rb, ws, cw, Jc, nc, e, damping, v, vnext, lam):
    """``vnext = v⁺`` and ``lam[:nc] = Λ`` (see the module docstring); leaves ``cw.Y`` and ``cw.G`` as
    :func:`~.contact_kernel.contact_forward_dynamics` does.  Needs the factor of ``M`` in ``ws``.  Not a number
    (never a division by zero) if ``G`` is not positive definite."""
    nv, Y = rb.nv, cw.Y
    schur_factor(rb, ws, cw, Jc, nc, damping)
    for r in range(nc):
        acc = 0.0
        for k in range(nv):
            acc += Jc[r, k] * v[k]
        lam[r] = -(1.0 + e) * acc
    cholesky_solve(cw.G, nc, lam)
    for k in range(nv):
        vnext[k] = v[k]
    for r in range(nc):
        for k in range(nv):
            vnext[k] += Y[k, r] * lam[r]


@uncounted
def _values(tbl, ints, par, x, u, rb, ws):
    """``xnext`` and the impulses at ``x``, the residuals; returns the cost stack's weighted sum.  Leaves the
    kinematics at ``x`` in ``ws``."""
    nq, nc = ints[NQ], ints[NC]
    q, v = x[:nq], x[nq:]
    forward_dynamics(rb, ws, q, v, ws.zero, vec(tbl, ints, E_A))  # the kinematics and the factor of M
    Jcs, xnext = mat(tbl, ints, E_JCS), vec(tbl, ints, E_XNEXT)
    _impulse_jacobian(tbl, ints, rb, ws, Jcs)
    for i in range(nq):
        xnext[i] = q[i]
    _impulse_velocity(rb, ws, entry_contact_workspace(tbl, ints), Jcs, nc, par[0], par[1], v, xnext[nq:],
                      vec(tbl, ints, E_LAM))
    residual_rows(tbl, ints, par, rb, ws, x, u)
    starts = ints[ints[STARTS]: ints[STARTS] + ints[N_STACK]]
    return activation_values(
        vec(tbl, ints, E_R), vec(tbl, ints, E_LB), vec(tbl, ints, E_UB), vec(tbl, ints, E_ACT_WEIGHTS), starts,
        vec(tbl, ints, E_ITEM_COSTS), vec(tbl, ints, E_ITEM_WEIGHTS),
    )


@uncounted
def impulse_calc(tbl, ints, par, x, u):
    """``xnext`` of the impulse node at ``x`` (``u`` has no entries) and its constraint rows; returns its cost."""
    rb, ws = entry_model(tbl, ints), entry_workspace(tbl, ints)
    cost = _values(tbl, ints, par, x, u, rb, ws)
    if has_rows(ints):
        constraint_values(tbl, ints, par, rb, ws, x, u, False, True)
    return cost


@uncounted
def _velocity_rows(tbl, ints, rb, ws, da0_dx):
    """``dv0_dq`` of every impulse into the first ``nv`` columns of ``da0_dx`` (after the kinematics at ``(q, w)``)."""
    nv = ints[NV]
    dq, J, v6 = mat(tbl, ints, E_J6), mat(tbl, ints, E_K6), vec(tbl, ints, E_V6)
    for n in range(ints[N_CONTACTS]):
        fid, nc, ref, row = contact_fields(ints, n)
        frame_velocity_derivatives(rb, ws, fid, LOCAL, dq, J)
        if ref == LOCAL:
            for r in range(nc):
                for k in range(nv):
                    da0_dx[row + r, k] = dq[r, k]
            continue
        frame_velocity(rb, ws, fid, LOCAL, v6)  # leaves the frame rotation in ws.Rf
        R = ws.Rf
        for s in range(0, nc, 3):
            for k in range(nv):
                c0 = dq[s, k] - (v6[s + 1] * J[5, k] - v6[s + 2] * J[4, k])
                c1 = dq[s + 1, k] - (v6[s + 2] * J[3, k] - v6[s] * J[5, k])
                c2 = dq[s + 2, k] - (v6[s] * J[4, k] - v6[s + 1] * J[3, k])
                for i in range(3):
                    da0_dx[row + s + i, k] = R[i, 0] * c0 + R[i, 1] * c1 + R[i, 2] * c2


@uncounted
def _impulse_derivatives(tbl, ints, par, x, rb, ws):
    """``dFx = ∂v⁺/∂x`` and ``df_dx = ∂Λ/∂x`` (see the module docstring), after :func:`_values` at ``x``."""
    nq, nv, nc = ints[NQ], ints[NV], ints[NC]
    q, v, e = x[:nq], x[nq:], par[0]
    xnext, Jcs, lam = vec(tbl, ints, E_XNEXT), mat(tbl, ints, E_JCS), vec(tbl, ints, E_LAM)
    da0_dx, w = mat(tbl, ints, E_DA0_DX), vec(tbl, ints, E_TAU)
    for k in range(nv):
        w[k] = xnext[nq + k] + e * v[k]
    forward_kinematics(rb, ws, q, w)
    _velocity_rows(tbl, ints, rb, ws, da0_dx)
    for r in range(nc):
        for k in range(nv):
            da0_dx[r, nv + k] = e * Jcs[r, k]
    for k in range(nv):
        w[k] = xnext[nq + k] - v[k]
    dq, dv = mat(tbl, ints, E_DTAU_DQ), mat(tbl, ints, E_DTAU_DV)
    dynamics_derivatives(rb, ws, q, ws.zero, w, dq, dv)
    projections = cube(tbl, ints, E_REF_R)
    for n in range(ints[N_CONTACTS]):
        fid, nci, ref, row = contact_fields(ints, n)
        contact_force_derivatives(rb, ws, fid, nci, ref, projections[n], lam, row, dq)
    M = ws.M
    for i in range(nv):
        for j in range(nv):
            dv[i, j] = -M[i, j]
    contact_dynamics_derivatives(rb, ws, entry_contact_workspace(tbl, ints), Jcs, nc, dq, dv, da0_dx,
                                 mat(tbl, ints, E_S), mat(tbl, ints, E_DFX), mat(tbl, ints, E_DFU),
                                 mat(tbl, ints, E_DF_DX), mat(tbl, ints, E_DF_DU))


@compiled
def _late_constraint_rows(tbl, ints, par, rb, ws, x):
    """The constraint rows' Jacobians that follow the impulses' derivatives (:func:`.residual_kernel.late_jacobians`
    on the constraint table), then every row stacked into ``g``, ``h`` and their Jacobians."""
    ctbl, cints = constraint_table(tbl, ints)
    if cints.shape[0]:
        late_jacobians(ctbl, cints, par, rb, ws, x)
    stack_rows(tbl, ints, True)


@uncounted
def impulse_calc_diff(tbl, ints, par, x, u):
    """Values and derivatives of the impulse node at ``x`` (self-contained); returns its cost."""
    rb, ws = entry_model(tbl, ints), entry_workspace(tbl, ints)
    cost = _values(tbl, ints, par, x, u, rb, ws)
    residual_jacobians(tbl, ints, par, rb, ws, x, u)
    if has_rows(ints):  # stacked after the impulses' derivatives
        constraint_values(tbl, ints, par, rb, ws, x, u, True, False)
    _impulse_derivatives(tbl, ints, par, x, rb, ws)
    late_jacobians(tbl, ints, par, rb, ws, x)  # from the impulses' derivatives just computed
    if has_rows(ints):
        _late_constraint_rows(tbl, ints, par, rb, ws, x)
    r, lb, ub, act_w = vec(tbl, ints, E_R), vec(tbl, ints, E_LB), vec(tbl, ints, E_UB), vec(tbl, ints, E_ACT_WEIGHTS)
    derivatives_and_sums(
        r, lb, ub, act_w, vec(tbl, ints, E_WEIGHTS), vec(tbl, ints, E_AR), vec(tbl, ints, E_ARR),
        mat(tbl, ints, E_JX), mat(tbl, ints, E_JU), ints[U_START], False, vec(tbl, ints, E_LX),
        vec(tbl, ints, E_LU), mat(tbl, ints, E_LXX), mat(tbl, ints, E_LXU), mat(tbl, ints, E_LUU),
        ivec(tbl, ints, E_COLS),
    )
    nv, Fx, dFx = ints[NV], mat(tbl, ints, E_FX), mat(tbl, ints, E_DFX)
    for i in range(nv):
        for j in range(2 * nv):
            Fx[i, j] = 1.0 if i == j else 0.0
            Fx[nv + i, j] = dFx[i, j]
    return cost
