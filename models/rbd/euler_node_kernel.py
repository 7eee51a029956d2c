"""The compiled calc and calcDiff of an Euler node of free or contact forward dynamics (see :mod:`.euler_node`).

One call evaluates a whole node: ``τ = S u`` (constant actuation matrix ``S (nv, nu)``), the forward
dynamics ``a = (M + diag(ε))⁻¹ (τ - b)``, the residuals of the cost stack, the activations and weighted
sums, the symplectic Euler step ``dx = ((v + a dt) dt, a dt)``, ``xnext = x ⊕ dx`` and, in ``calcDiff``,

    ∂a/∂x = -(M + diag(ε))⁻¹ (∂RNEA/∂q, ∂RNEA/∂v),   ∂a/∂u = (M + diag(ε))⁻¹ S,

With rigid contacts (``ints[N_CONTACTS] > 0``, the stacked rows of the contacts listed from ``ints[CONTACTS]``,
``CONTACT_FIELDS`` integers each: frame, rows, reference frame, first row), the dynamics and their derivatives
(``a``, the forces ``λ``, ``∂a/∂(x, u)``, ``∂λ/∂(x, u)``) are those of :mod:`.contact_kernel` with the damping
``par[1]``; the force residuals read ``λ`` and ``∂λ``.

then the residual Jacobians and the Euler chain rule of :mod:`crocopy.integrators.euler_kernel` (plus the
configuration's ``∂(q ⊕ dq)/∂(q, dq)`` on a Lie group).  The terminal node (``terminal`` set) has only
the costs of ``x``; its ``Fx`` is the identity.

The arrays arrive by address, in the table of :mod:`.node_table` (its layout and accessors); ``USER`` residual
items call their callbacks through :mod:`.user_residual_kernel`.  ``par[0]`` is the time step, ``par[1]``
the contact dynamics' damping.
"""

from __future__ import annotations

import math

from crocopy.costs.stack_kernel import stack_derivatives_and_sums, stack_values
from crocopy.integrators.euler_kernel import euler_chain
from crocopy.kernels import compiled, uncounted
from crocopy.solvers.riccati_kernel import feedback_control

from .configuration_kernel import dintegrate_blocks, state_diff, state_integrate
from .constraint_rows_kernel import constraint_table, has_rows, stack_rows
from .contact_kernel import (
    contact_calc,
    contact_calc_diff,
    contact_dynamics_derivatives,
    contact_force_derivatives,
    contact_forward_dynamics,
)
from .dynamics_kernel import (
    forward_dynamics,
    forward_kinematics,
    mass_inverse,
    rnea_derivatives,
)
from .node_table import (
    E_A,
    E_A0,
    E_ACT_KINDS,
    E_ACT_PARAMS,
    E_ACT_WEIGHTS,
    E_AR,
    E_ARR,
    E_COLS,
    E_DA0_DX,
    E_DF_DU,
    E_DF_DX,
    E_DFU,
    E_DFX,
    E_DLU,
    E_DLUU,
    E_DLX,
    E_DLXU,
    E_DLXX,
    E_DTAU_DQ,
    E_DTAU_DV,
    E_DX,
    E_FU,
    E_FX,
    E_GAINS,
    E_GAP,
    E_GRAD,
    E_ITEM_COSTS,
    E_ITEM_WEIGHTS,
    E_JCS,
    E_JQ,
    E_JU,
    E_JV,
    E_JX,
    E_LAM,
    E_LB,
    E_LU,
    E_LUU,
    E_LX,
    E_LXU,
    E_LXX,
    E_MINV,
    E_R,
    E_REF_P,
    E_REF_R,
    E_ROWS,
    E_S,
    E_STAMP,
    E_TAU,
    E_UB,
    E_WEIGHTS,
    E_XNEXT,
    EUCLIDEAN,
    N_CONTACTS,
    N_STACK,
    NC,
    NJOINTS,
    NQ,
    NU,
    NV,
    STARTS,
    TERMINAL,
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
from .residual_kernel import matmul, residual_jacobians, residual_rows


@uncounted
def _values(tbl, ints, par, x, u, rb, ws):
    """Dynamics (running node) and residuals at ``(x, u)``; returns the cost stack's weighted sum."""
    nq, nv, nu = ints[NQ], ints[NV], ints[NU]
    q, v = x[:nq], x[nq:]
    if ints[TERMINAL]:
        forward_kinematics(rb, ws, q, v)
        lam = vec(tbl, ints, E_LAM)
        for i in range(ints[NC]):
            lam[i] = 0.0
    else:
        Sm, tau, a = mat(tbl, ints, E_S), vec(tbl, ints, E_TAU), vec(tbl, ints, E_A)
        for i in range(nv):
            acc = 0.0
            for j in range(nu):
                acc += Sm[i, j] * u[j]
            tau[i] = acc
        forward_dynamics(rb, ws, q, v, tau, a)
        if ints[N_CONTACTS]:
            _contact_dynamics(tbl, ints, par, rb, ws, tau, a)
    residual_rows(tbl, ints, par, rb, ws, x, u)
    starts = ints[ints[STARTS]: ints[STARTS] + ints[N_STACK]]
    return stack_values(
        vec(tbl, ints, E_R), vec(tbl, ints, E_LB), vec(tbl, ints, E_UB), vec(tbl, ints, E_ACT_WEIGHTS), starts,
        ivec(tbl, ints, E_ACT_KINDS), vec(tbl, ints, E_ACT_PARAMS), vec(tbl, ints, E_ITEM_COSTS),
        vec(tbl, ints, E_ITEM_WEIGHTS),
    )


@compiled
def _constraints(tbl, ints, par, rb, ws, x, u, derivatives, stack):
    """The constraint manager's rows (:mod:`.constraint_rows_kernel`): its residuals by the cost items' kernels on the
    node's constraint table (and their Jacobians, if ``derivatives``), stacked into ``g``, ``h`` if ``stack`` (an
    impulse node stacks them after its impulses' derivatives)."""
    ctbl, cints = constraint_table(tbl, ints)
    if cints.shape[0]:
        residual_rows(ctbl, cints, par, rb, ws, x, u)
        if derivatives:
            residual_jacobians(ctbl, cints, par, rb, ws, x, u)
    if stack:
        stack_rows(tbl, ints, derivatives)


@uncounted
def _contact_dynamics(tbl, ints, par, rb, ws, tau, a):
    """The contacts' stacked ``Jc`` and drift, then ``a`` and ``λ`` of the contact dynamics (after the free
    :func:`~.dynamics_kernel.forward_dynamics` at the same state)."""
    cw, Jcs, a0 = entry_contact_workspace(tbl, ints), mat(tbl, ints, E_JCS), vec(tbl, ints, E_A0)
    gains, ref_R, ref_p = mat(tbl, ints, E_GAINS), cube(tbl, ints, E_REF_R), mat(tbl, ints, E_REF_P)
    for n in range(ints[N_CONTACTS]):
        fid, nc, ref, row = contact_fields(ints, n)
        contact_calc(rb, ws, cw, fid, nc, ref, gains[n, 0], gains[n, 1], ref_R[n], ref_p[n], row, Jcs, a0)
    contact_forward_dynamics(rb, ws, cw, tau, Jcs, a0, ints[NC], par[1], a, vec(tbl, ints, E_LAM))


@uncounted
def _step(tbl, ints, par, x, rb):
    """``dx`` and ``xnext`` of the Euler step (``xnext = x`` at the terminal node)."""
    nq, nv = ints[NQ], ints[NV]
    xnext = vec(tbl, ints, E_XNEXT)
    if ints[TERMINAL]:
        for i in range(nq + nv):
            xnext[i] = x[i]
        return
    dt, a, dx = par[0], vec(tbl, ints, E_A), vec(tbl, ints, E_DX)
    for i in range(nv):
        dv = a[i] * dt
        dx[nv + i] = dv
        dx[i] = (x[nq + i] + dv) * dt
    state_integrate(rb.jtype, rb.idx_q, rb.idx_v, nq, nv, x, dx, xnext)


@uncounted
def _singular(tbl, ints):
    """Whether the running node's acceleration is not finite: a contact set whose KKT system is singular at this
    state (the Python path then takes least squares), or a diverged state."""
    if ints[TERMINAL]:
        return False
    a = vec(tbl, ints, E_A)
    for i in range(a.shape[0]):
        if not math.isfinite(a[i]):
            return True
    return False


@uncounted
def _same(a, b):
    """Whether ``a`` and ``b`` hold the same numbers to the bit (a signed zero included; NaN is never the same)."""
    for i in range(a.shape[0]):
        if a[i] != b[i] or math.copysign(1.0, a[i]) != math.copysign(1.0, b[i]):
            return False
    return True


@uncounted
def _remember(stamp, x, u, value, mark):
    """Stamp the node's values as those of ``(x, u)`` (``value``: the stack's): ``mark = 1`` its own arrays and its
    data's, ``mark = 2`` its data's only (after derivatives, which overwrite some of its own arrays)."""
    if stamp.shape[0] == 0:
        return
    nx = x.shape[0]
    stamp[1] = value
    for i in range(nx):
        stamp[2 + i] = x[i]
    for i in range(u.shape[0]):
        stamp[2 + nx + i] = u[i]
    stamp[0] = mark


@uncounted
def stamp_current(stamp, x, u):
    """Whether the node's values (its own arrays, :data:`.node_table.OWN`) are those of ``(x, u)``."""
    if stamp.shape[0] == 0 or stamp[0] != 1.0:
        return False
    nx = x.shape[0]
    return _same(stamp[2: 2 + nx], x) and _same(stamp[2 + nx: 2 + nx + u.shape[0]], u)


@uncounted
def node_integrate(tbl, ints, x, step, out):
    """``out = x ⊕ step`` on the node's state (its lowered model's joints)."""
    rb = entry_model(tbl, ints)
    state_integrate(rb.jtype, rb.idx_q, rb.idx_v, ints[NQ], ints[NV], x, step, out)


@uncounted
def node_diff(tbl, ints, x0, x1, out):
    """``out = x1 ⊖ x0`` on the node's state (its lowered model's joints)."""
    rb = entry_model(tbl, ints)
    state_diff(rb.jtype, rb.idx_q, rb.idx_v, ints[NQ], ints[NV], x0, x1, out)


@uncounted
def values_current(stamp, x, u):
    """Whether the values in the node's data (``xnext``, the cost stack's rows and costs; the stack's value in
    ``stamp[1]``) are those of ``(x, u)``: after a :func:`node_calc` or a :func:`node_calc_diff` there."""
    if stamp.shape[0] == 0 or (stamp[0] != 1.0 and stamp[0] != 2.0):
        return False
    nx = x.shape[0]
    return _same(stamp[2: 2 + nx], x) and _same(stamp[2 + nx: 2 + nx + u.shape[0]], u)


@uncounted
def _evaluate(tbl, ints, par, x, u, step):
    """The node's values at ``(x, u)`` (with the Euler step if ``step``) and its constraint rows; returns the cost
    stack's value, NaN when the acceleration is not finite (:func:`_singular`: the caller evaluates the node on the
    Python path).  A finite evaluation is stamped with ``(x, u)`` (:func:`_remember`)."""
    rb, ws = entry_model(tbl, ints), entry_workspace(tbl, ints)
    stamp = vec(tbl, ints, E_STAMP)
    if stamp.shape[0]:
        stamp[0] = 0.0
    cost = _values(tbl, ints, par, x, u, rb, ws)
    if step:
        _step(tbl, ints, par, x, rb)
    if _singular(tbl, ints):
        return math.nan
    if has_rows(ints):
        _constraints(tbl, ints, par, rb, ws, x, u, False, True)
    _remember(stamp, x, u, cost, 1.0)
    return cost


@uncounted
def node_calc(tbl, ints, par, x, u):
    """``xnext`` of the node at ``(x, u)``; returns its cost (``dt`` times the stack's for a running node), NaN when
    the acceleration is not finite (:func:`_evaluate`)."""
    cost = _evaluate(tbl, ints, par, x, u, True)
    return cost if ints[TERMINAL] else par[0] * cost


@uncounted
def differential_calc(tbl, ints, par, x, u):
    """The differential model's values at ``(x, u)`` alone (no Euler step: the stages of a Runge-Kutta node,
    :mod:`.rk_node_kernel`); returns the cost stack's value (:func:`_evaluate`)."""
    return _evaluate(tbl, ints, par, x, u, False)


@uncounted
def node_rollout_step(tbl, ints, par, x_ref, x, u_ref, k, K, alpha, lb, ub, u, dx, x_next, f, gap):
    """One node of the DDP family's rollout (the node step of ``_trial_rollout``): ``dx = x ⊖ x_ref``,
    ``u = clamp(u_ref - α k - K dx, lb, ub)``, the node at ``(x, u)``, and ``x_next = xnext``, or
    ``xnext ⊕ ((α - 1) f)`` if ``gap``; returns the node's cost."""
    _step_control(tbl, ints, x_ref, x, u_ref, k, K, alpha, lb, ub, u, dx)
    cost = node_calc(tbl, ints, par, x, u)
    _step_next(tbl, ints, alpha, x_next, f, gap)
    return cost


@uncounted
def _step_control(tbl, ints, x_ref, x, u_ref, k, K, alpha, lb, ub, u, dx):
    """A rollout step's ``dx = x ⊖ x_ref`` and ``u = clamp(u_ref - α k - K dx, lb, ub)``."""
    rb = entry_model(tbl, ints)
    state_diff(rb.jtype, rb.idx_q, rb.idx_v, ints[NQ], ints[NV], x_ref, x, dx)
    feedback_control(u_ref, k, K, dx, alpha, lb, ub, u)


@uncounted
def _step_next(tbl, ints, alpha, x_next, f, gap):
    """A rollout step's ``x_next = xnext``, or ``xnext ⊕ ((α - 1) f)`` if ``gap``."""
    rb = entry_model(tbl, ints)
    nq, nv = ints[NQ], ints[NV]
    xnext = vec(tbl, ints, E_XNEXT)
    if gap:
        step = vec(tbl, ints, E_GAP)
        for i in range(2 * nv):
            step[i] = (alpha - 1.0) * f[i]
        state_integrate(rb.jtype, rb.idx_q, rb.idx_v, nq, nv, xnext, step, x_next)
    else:
        for i in range(nq + nv):
            x_next[i] = xnext[i]


@uncounted
def _dynamics_jacobians(tbl, ints, x, rb, ws):
    """``dFx = -(M + diag ε)⁻¹ ∂RNEA/∂(q, v)`` and ``dFu = (M + diag ε)⁻¹ S`` at the last ``calc`` point."""
    nv, nu = ints[NV], ints[NU]
    Minv, dq, dv = mat(tbl, ints, E_MINV), mat(tbl, ints, E_DTAU_DQ), mat(tbl, ints, E_DTAU_DV)
    dFx, dFu, Sm, a = mat(tbl, ints, E_DFX), mat(tbl, ints, E_DFU), mat(tbl, ints, E_S), vec(tbl, ints, E_A)
    rnea_derivatives(rb, ws, a, dq, dv)  # the kinematics of _values at (q, v) are still in ws
    if ints[N_CONTACTS]:
        cw, Jcs, lam, da0_dx = (entry_contact_workspace(tbl, ints), mat(tbl, ints, E_JCS), vec(tbl, ints, E_LAM),
                                mat(tbl, ints, E_DA0_DX))
        gains, ref_R, ref_p = mat(tbl, ints, E_GAINS), cube(tbl, ints, E_REF_R), mat(tbl, ints, E_REF_P)
        for n in range(ints[N_CONTACTS]):
            fid, nc, ref, row = contact_fields(ints, n)
            contact_force_derivatives(rb, ws, fid, nc, ref, ref_R[n], lam, row, dq)
            contact_calc_diff(rb, ws, cw, fid, nc, ref, gains[n, 0], gains[n, 1], ref_R[n], ref_p[n], row, da0_dx)
        contact_dynamics_derivatives(rb, ws, cw, Jcs, ints[NC], dq, dv, da0_dx, Sm, dFx, dFu,
                                     mat(tbl, ints, E_DF_DX), mat(tbl, ints, E_DF_DU))
        return
    mass_inverse(rb.dof_parent, ws.L, ws.dinv, Minv)
    for i in range(nv):
        for j in range(nv):
            sq = 0.0
            sv = 0.0
            for k in range(nv):
                sq += Minv[i, k] * dq[k, j]
                sv += Minv[i, k] * dv[k, j]
            dFx[i, j] = -sq
            dFx[i, nv + j] = -sv
    if _identity(Sm, nv, nu):  # full actuation: the product is M⁻¹ itself
        for i in range(nv):
            for j in range(nu):
                dFu[i, j] = Minv[i, j]
        return
    matmul(Minv, Sm, dFu, nv, nu, nv)


@uncounted
def _identity(A, rows, cols):
    """Whether ``A[:rows, :cols]`` is the identity."""
    if rows != cols:
        return False
    for i in range(rows):
        for j in range(cols):
            if A[i, j] != (1.0 if i == j else 0.0):
                return False
    return True


@uncounted
def _integrate_chain(tbl, ints, x, rb):
    """Lie-group end of the Euler chain rule, in place on the configuration rows ``[Fx Fu][:nv]`` of
    :func:`~crocopy.integrators.euler_kernel.euler_chain`: ``[Fx Fu][:nv] ← Jv [Fx Fu][:nv] + [Jq 0]`` and
    ``Fx[nv:, nv:] += I`` (as :func:`~crocopy.integrators.euler_kernel.add_integrate_jacobian` after the transport).
    ``Jq`` and ``Jv`` are block diagonal, one block per joint (only the blocks are written and read): each row sums
    over its joint's block, from a copy of the block's rows in ``E_ROWS``; a one-dof joint's blocks are ``1``, its
    rows stay and only ``Jq``'s ``1`` is added."""
    nv, nu = ints[NV], ints[NU]
    Fx, Fu, dx = mat(tbl, ints, E_FX), mat(tbl, ints, E_FU), vec(tbl, ints, E_DX)
    Jq, Jv, rows = mat(tbl, ints, E_JQ), mat(tbl, ints, E_JV), mat(tbl, ints, E_ROWS)
    dintegrate_blocks(rb.jtype, rb.idx_q, rb.idx_v, dx[:nv], 0, Jq)
    dintegrate_blocks(rb.jtype, rb.idx_q, rb.idx_v, dx[:nv], 1, Jv)
    ndx = 2 * nv
    for joint in range(1, ints[NJOINTS]):
        first = rb.idx_v[joint]
        last = first + rb.nvj[joint]
        if last - first == 1:
            Fx[first, first] += Jq[first, first]
            continue
        for i in range(first, last):
            for j in range(ndx):
                rows[i, j] = Fx[i, j]
            for j in range(nu):
                rows[i, ndx + j] = Fu[i, j]
        for i in range(first, last):  # row i of Jv rows, accumulated along contiguous rows (k in order)
            for j in range(ndx):
                Fx[i, j] = 0.0
            for j in range(nu):
                Fu[i, j] = 0.0
            for k in range(first, last):
                s = Jv[i, k]
                for j in range(ndx):
                    Fx[i, j] += s * rows[k, j]
                for j in range(nu):
                    Fu[i, j] += s * rows[k, ndx + j]
            for j in range(first, last):
                Fx[i, j] += Jq[i, j]
    for i in range(nv):
        Fx[nv + i, nv + i] += 1.0


@uncounted
def _derivatives(tbl, ints, par, x, u, step):
    """The values at ``(x, u)`` (with the Euler step if ``step``), unless they are those of the last :func:`node_calc`
    (its stamp is ``(x, u)`` to the bit, :func:`stamp_current`: the node's own arrays still hold what they left),
    then the dynamics' and residuals' Jacobians and the constraint rows; returns the cost stack's value, NaN when the
    acceleration is not finite.  The stamp is spent (the derivatives overwrite some of the node's own arrays)."""
    rb, ws = entry_model(tbl, ints), entry_workspace(tbl, ints)
    stamp = vec(tbl, ints, E_STAMP)
    if stamp_current(stamp, x, u):
        cost = stamp[1]
    else:
        cost = _values(tbl, ints, par, x, u, rb, ws)
        if step:
            _step(tbl, ints, par, x, rb)
        if _singular(tbl, ints):
            return math.nan
    if stamp.shape[0]:
        stamp[0] = 0.0
    if not ints[TERMINAL]:
        _dynamics_jacobians(tbl, ints, x, rb, ws)
    elif ints[NC]:
        df_dx = mat(tbl, ints, E_DF_DX)
        for i in range(ints[NC]):
            for j in range(df_dx.shape[1]):
                df_dx[i, j] = 0.0
    residual_jacobians(tbl, ints, par, rb, ws, x, u)
    if has_rows(ints):
        _constraints(tbl, ints, par, rb, ws, x, u, True, True)
    return cost


@uncounted
def node_calc_diff(tbl, ints, par, x, u):
    """Values and derivatives of the node at ``(x, u)`` (:func:`_derivatives`, then the sums and the chain rule);
    returns its cost, NaN when the acceleration is not finite (as :func:`node_calc`); the stamp then marks the data's
    values only (:func:`values_current`)."""
    cost = _derivatives(tbl, ints, par, x, u, True)
    if math.isnan(cost):
        return cost
    total = _sums_and_chain(tbl, ints, par, x, entry_model(tbl, ints), cost, ints[TERMINAL] != 0)
    if math.isfinite(total):
        _remember(vec(tbl, ints, E_STAMP), x, u, cost, 2.0)
    return total


@uncounted
def differential_calc_diff(tbl, ints, par, x, u):
    """The differential model's values (unless stamped, as :func:`node_calc_diff`) and derivatives at ``(x, u)`` of a
    running node's table, without the Euler chain rule: ``a``, ``dFx``, ``dFu`` and the stack's sums into ``dLx`` ...
    ``dLuu`` (the stages of a Runge-Kutta node, :mod:`.rk_node_kernel`); returns the cost stack's value."""
    cost = _derivatives(tbl, ints, par, x, u, False)
    if math.isnan(cost):
        return cost
    _stack_sums(tbl, ints, False)
    if math.isfinite(cost):
        _remember(vec(tbl, ints, E_STAMP), x, u, cost, 2.0)
    return cost


@uncounted
def _stack_sums(tbl, ints, terminal):
    """The cost stack's sums into the node's cost derivatives (``terminal``) or the differential ones (``dLx`` ...,
    those of a running node, with the controls' rows)."""
    if terminal:
        Lx, Lu, Lxx = vec(tbl, ints, E_LX), vec(tbl, ints, E_LU), mat(tbl, ints, E_LXX)
        Lxu, Luu = mat(tbl, ints, E_LXU), mat(tbl, ints, E_LUU)
    else:
        Lx, Lu, Lxx = vec(tbl, ints, E_DLX), vec(tbl, ints, E_DLU), mat(tbl, ints, E_DLXX)
        Lxu, Luu = mat(tbl, ints, E_DLXU), mat(tbl, ints, E_DLUU)
    r, lb, ub, act_w = vec(tbl, ints, E_R), vec(tbl, ints, E_LB), vec(tbl, ints, E_UB), vec(tbl, ints, E_ACT_WEIGHTS)
    weights, Ar, Arr = vec(tbl, ints, E_WEIGHTS), vec(tbl, ints, E_AR), vec(tbl, ints, E_ARR)
    Jx, Ju, u_start, cols = mat(tbl, ints, E_JX), mat(tbl, ints, E_JU), ints[U_START], ivec(tbl, ints, E_COLS)
    items = (vec(tbl, ints, E_GRAD), ints[ints[STARTS]: ints[STARTS] + ints[N_STACK]], ivec(tbl, ints, E_ACT_KINDS),
             vec(tbl, ints, E_ACT_PARAMS), vec(tbl, ints, E_ITEM_COSTS), vec(tbl, ints, E_ITEM_WEIGHTS))
    stack_derivatives_and_sums(r, lb, ub, act_w, weights, Ar, Arr, Jx, Ju, u_start, not terminal, Lx, Lu, Lxx, Lxu,
                               Luu, cols, *items)


@uncounted
def _sums_and_chain(tbl, ints, par, x, rb, cost, terminal):
    """The end of a node's ``calcDiff`` once its cost stack holds its residuals and Jacobians: the stack's sums into
    the node's cost derivatives, and for a running node the differential ones through the Euler chain rule (and its
    Lie-group end); returns the node's cost (``cost``, the stack's value, times ``dt`` for a running node)."""
    _stack_sums(tbl, ints, terminal)
    if terminal:
        Fx = mat(tbl, ints, E_FX)
        n = Fx.shape[0]
        for i in range(n):
            for j in range(n):
                Fx[i, j] = 1.0 if i == j else 0.0
        return cost
    euclidean = ints[EUCLIDEAN] != 0
    euler_chain(
        mat(tbl, ints, E_DFX), mat(tbl, ints, E_DFU), vec(tbl, ints, E_DLX), vec(tbl, ints, E_DLU),
        mat(tbl, ints, E_DLXX), mat(tbl, ints, E_DLXU), mat(tbl, ints, E_DLUU), par[0], euclidean,
        mat(tbl, ints, E_FX), mat(tbl, ints, E_FU), vec(tbl, ints, E_LX), vec(tbl, ints, E_LU),
        mat(tbl, ints, E_LXX), mat(tbl, ints, E_LXU), mat(tbl, ints, E_LUU),
    )
    if not euclidean:
        _integrate_chain(tbl, ints, x, rb)
    return par[0] * cost


constraint_values = _constraints
"""The constraint rows of a node's table (:func:`_constraints`), for the other compiled nodes
(:mod:`.impulse_node_kernel`)."""

euler_step, remember_values, sums_and_chain = _step, _remember, _sums_and_chain
step_control, step_next = _step_control, _step_next
"""The Euler step (:func:`_step`), the stamp (:func:`_remember`), the end of a ``calcDiff`` (:func:`_sums_and_chain`)
and the two ends of a rollout step (:func:`_step_control`, :func:`_step_next`) of a node's table, for the other
compiled nodes (:mod:`.invdyn_node_kernel`)."""
