"""The compiled calc and calcDiff of an Euler node of free or contact inverse dynamics (see :mod:`.invdyn_node`).

The control is ``u = (a, f)``: the joint acceleration ``a (nv,)``, then the forces ``f`` of the node's contacts
(``nc`` rows, every contact active, stacked in the contact set's order; none in the free case).  One call evaluates a
whole node::

    xout = a,   τ = RNEA(q, v, a) - Jcᵀ f,   c = Jc a + a0(x)   (the contacts' acceleration, Baumgarte terms included)

then the cost stack's residuals (the Euler node's kinds, :mod:`.residual_kernel`, with the contact forces
``λ = f``, ``∂λ/∂x = 0``, ``∂λ/∂u = (0, I)``) and the *inverse-dynamics items* below, the activations and sums, the
Euler step ``dx = ((v + a dt) dt, a dt)``, ``xnext = x ⊕ dx``, and the constraint manager's rows
(:mod:`.constraint_rows_kernel`, the inverse-dynamics items writing their rows of ``cr``).  ``calcDiff`` adds
``∂τ/∂x = (∂RNEA/∂q - ∂(Jcᵀ f)/∂q, ∂RNEA/∂v)``, ``∂τ/∂u = (M, -Jcᵀ)``, the contacts' ``∂c/∂x``, the differential
``Fx = 0``, ``Fu = (I, 0)`` and the Euler chain rule of :mod:`.euler_node_kernel`.  The terminal node evaluates the
kinematics and the costs of ``x`` (forces zero), ``Fx = I``.

Inverse-dynamics items (``ITEM_FIELDS`` integers each in ``iints``: kind, first row, rows, contact row, parameter
offset, flag; ``iints[0]`` cost items then ``iints[1]`` constraint items from ``iints[2]`` on), rows ``r`` with
Jacobians ``(Rx, Ru)``:

* ``ACTUATION``: ``r = τ[rows]`` (the rows the actuation cannot set, ``par[o:o+nr]``), ``(∂τ/∂x, ∂τ/∂u)[rows]``;
* ``EFFORT``: ``r = P τ - uref`` (``P (nr, nv)`` the actuation's commands of the torques, row-major at ``par[o]``,
  then ``uref``), ``(P ∂τ/∂x, P ∂τ/∂u)`` (``Rx = 0`` with the flag: a ``fwddyn`` residual); zero at the terminal node;
* ``ACCELERATION``: ``r = a - aref`` (``par[o:o+nv]``), ``(0, (I, 0))``; zero at the terminal node;
* ``CONTACT``: ``r = c`` of the contact whose first row is the contact row, ``(∂c/∂x, (Jc, 0))``.

The arrays arrive in the Euler node's table (:mod:`.node_table`): ``τ`` in the scratch ``tau``, ``∂τ/∂(q, v)`` in
``dtau_dq``/``dtau_dv``, ``M`` in the workspace, the contacts' ``Jc``, ``c``, ``λ``, ``∂c/∂x``, ``∂λ`` in ``Jcs``,
``a0``, ``lam``, ``da0_dx``, ``df_dx``, ``df_du``.  ``par[0]`` is the time step.
"""

from __future__ import annotations

from crocopy.costs.stack_kernel import activation_values
from crocopy.kernels import uncounted

from .constraint_rows_kernel import constraint_table, has_rows, stack_rows
from .contact_kernel import contact_calc, contact_calc_diff, contact_force_derivatives
from .dynamics_kernel import crba, forward_kinematics, rnea_derivatives, rnea_pass
from .euler_node_kernel import euler_step, remember_values, stamp_current, step_control, step_next, sums_and_chain
from .node_table import (
    E_A,
    E_A0,
    E_ACT_WEIGHTS,
    E_CJU,
    E_CJX,
    E_CR,
    E_DA0_DX,
    E_DF_DU,
    E_DF_DX,
    E_DFU,
    E_DFX,
    E_DTAU_DQ,
    E_DTAU_DV,
    E_GAINS,
    E_ITEM_COSTS,
    E_ITEM_WEIGHTS,
    E_JCS,
    E_JU,
    E_JX,
    E_LAM,
    E_LB,
    E_R,
    E_REF_P,
    E_REF_R,
    E_STAMP,
    E_TAU,
    E_UB,
    N_CONTACTS,
    N_STACK,
    NC,
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
    mat,
    vec,
)
from .residual_kernel import residual_jacobians, residual_rows

ACTUATION, EFFORT, ACCELERATION, CONTACT = range(4)
"""Kinds of the inverse-dynamics items (see the module docstring)."""
ITEM_FIELDS = 6
HEADER = 2


@uncounted
def _item_rows(tbl, ints, par, iints, first, count, r, u):
    """Rows of ``count`` inverse-dynamics items from item ``first`` into ``r``."""
    nv, terminal = ints[NV], ints[TERMINAL] != 0
    tau, c = vec(tbl, ints, E_TAU), vec(tbl, ints, E_A0)
    for n in range(first, first + count):
        b = HEADER + ITEM_FIELDS * n
        kind, start, nr, row, o = iints[b], iints[b + 1], iints[b + 2], iints[b + 3], iints[b + 4]
        for i in range(nr):
            if kind == ACTUATION:
                r[start + i] = tau[int(par[o + i])]
            elif kind == CONTACT:
                r[start + i] = c[row + i]
            elif terminal:
                r[start + i] = 0.0
            elif kind == EFFORT:
                acc = -par[o + nr * nv + i]
                for k in range(nv):
                    acc += par[o + nv * i + k] * tau[k]
                r[start + i] = acc
            else:
                r[start + i] = u[i] - par[o + i]


@uncounted
def _tau_du(ws, Jcs, nv, k, col):
    """``∂τ_k/∂u_col``: ``M[k, col]``, or ``-Jc[col - nv, k]`` for a force."""
    return ws.M[k, col] if col < nv else -Jcs[col - nv, k]


@uncounted
def _item_jacobians(tbl, ints, par, iints, first, count, ws, Jx, Ju, u_start):
    """Jacobians of ``count`` inverse-dynamics items from item ``first``: rows of ``Jx`` and (running node) of ``Ju``
    (row ``start - u_start``)."""
    nv, nu, terminal = ints[NV], ints[NU], ints[TERMINAL] != 0
    dq, dv, Jcs, dc = mat(tbl, ints, E_DTAU_DQ), mat(tbl, ints, E_DTAU_DV), mat(tbl, ints, E_JCS), mat(tbl, ints,
                                                                                                        E_DA0_DX)
    for n in range(first, first + count):
        b = HEADER + ITEM_FIELDS * n
        kind, start, nr, row, o, flag = (iints[b], iints[b + 1], iints[b + 2], iints[b + 3], iints[b + 4],
                                         iints[b + 5])
        for i in range(nr):
            s, ju = start + i, start - u_start + i
            if terminal:
                for j in range(2 * nv):
                    Jx[s, j] = 0.0
                continue
            if kind == ACTUATION:
                k = int(par[o + i])
                for j in range(nv):
                    Jx[s, j] = dq[k, j]
                    Jx[s, nv + j] = dv[k, j]
                for j in range(nu):
                    Ju[ju, j] = _tau_du(ws, Jcs, nv, k, j)
            elif kind == EFFORT:
                p = o + nv * i
                for j in range(nv):
                    aq = av = 0.0
                    for k in range(nv):
                        aq += par[p + k] * dq[k, j]
                        av += par[p + k] * dv[k, j]
                    Jx[s, j] = 0.0 if flag else aq
                    Jx[s, nv + j] = 0.0 if flag else av
                for j in range(nu):
                    acc = 0.0
                    for k in range(nv):
                        acc += par[p + k] * _tau_du(ws, Jcs, nv, k, j)
                    Ju[ju, j] = acc
            elif kind == ACCELERATION:
                for j in range(2 * nv):
                    Jx[s, j] = 0.0
                for j in range(nu):
                    Ju[ju, j] = 1.0 if j == i else 0.0
            else:
                for j in range(2 * nv):
                    Jx[s, j] = dc[row + i, j]
                for j in range(nu):
                    Ju[ju, j] = Jcs[row + i, j] if j < nv else 0.0


@uncounted
def _values(tbl, ints, par, iints, x, u, rb, ws):
    """Inverse dynamics (running node), contacts and every residual at ``(x, u)``; returns the stack's weighted sum."""
    nq, nv, nc = ints[NQ], ints[NV], ints[NC]
    q, v = x[:nq], x[nq:]
    forward_kinematics(rb, ws, q, v)
    lam = vec(tbl, ints, E_LAM)
    if ints[TERMINAL]:
        for i in range(nc):
            lam[i] = 0.0
    else:
        a, tau = vec(tbl, ints, E_A), vec(tbl, ints, E_TAU)
        for i in range(nv):
            a[i] = u[i]
        for i in range(nc):
            lam[i] = u[nv + i]
        rnea_pass(rb, ws, a, tau)  # leaves the accelerations at a in ws.oa
        if ints[N_CONTACTS]:
            cw, Jcs, c = entry_contact_workspace(tbl, ints), mat(tbl, ints, E_JCS), vec(tbl, ints, E_A0)
            gains, ref_R, ref_p = mat(tbl, ints, E_GAINS), cube(tbl, ints, E_REF_R), mat(tbl, ints, E_REF_P)
            for n in range(ints[N_CONTACTS]):
                fid, ncn, ref, row = contact_fields(ints, n)
                contact_calc(rb, ws, cw, fid, ncn, ref, gains[n, 0], gains[n, 1], ref_R[n], ref_p[n], row, Jcs, c)
            for k in range(nv):
                acc = 0.0
                for i in range(nc):
                    acc += Jcs[i, k] * lam[i]
                tau[k] -= acc
    residual_rows(tbl, ints, par, rb, ws, x, u)
    _item_rows(tbl, ints, par, iints, 0, iints[0], vec(tbl, ints, E_R), u)
    starts = ints[ints[STARTS]: ints[STARTS] + ints[N_STACK]]
    return activation_values(
        vec(tbl, ints, E_R), vec(tbl, ints, E_LB), vec(tbl, ints, E_UB), vec(tbl, ints, E_ACT_WEIGHTS), starts,
        vec(tbl, ints, E_ITEM_COSTS), vec(tbl, ints, E_ITEM_WEIGHTS),
    )


@uncounted
def _constraints(tbl, ints, par, iints, rb, ws, x, u, derivatives):
    """The constraint manager's rows: the Euler node's kinds on the constraint table, the inverse-dynamics items into
    ``cr`` (``cJx``, ``cJu``), stacked into ``g``, ``h`` (and their Jacobians, if ``derivatives``)."""
    ctbl, cints = constraint_table(tbl, ints)
    if cints.shape[0]:
        residual_rows(ctbl, cints, par, rb, ws, x, u)
        _item_rows(tbl, ints, par, iints, iints[0], iints[1], vec(tbl, ints, E_CR), u)
        if derivatives:
            residual_jacobians(ctbl, cints, par, rb, ws, x, u)
            _item_jacobians(tbl, ints, par, iints, iints[0], iints[1], ws, mat(tbl, ints, E_CJX),
                            mat(tbl, ints, E_CJU), 0)
    stack_rows(tbl, ints, derivatives)


@uncounted
def invdyn_calc(tbl, ints, par, iints, x, u):
    """``xnext`` and the constraint rows of the node at ``(x, u)``; returns its cost (``dt`` times the stack's at a
    running node).  The evaluation is stamped with ``(x, u)`` (:func:`.euler_node_kernel.remember_values`)."""
    rb, ws = entry_model(tbl, ints), entry_workspace(tbl, ints)
    stamp = vec(tbl, ints, E_STAMP)
    if stamp.shape[0]:
        stamp[0] = 0.0
    cost = _values(tbl, ints, par, iints, x, u, rb, ws)
    euler_step(tbl, ints, par, x, rb)
    if has_rows(ints):
        _constraints(tbl, ints, par, iints, rb, ws, x, u, False)
    remember_values(stamp, x, u, cost, 1.0)
    return cost if ints[TERMINAL] else par[0] * cost


@uncounted
def invdyn_rollout_step(tbl, ints, par, iints, x_ref, x, u_ref, k, K, alpha, lb, ub, u, dx, x_next, f, gap):
    """One node of the DDP family's rollout (as :func:`.euler_node_kernel.node_rollout_step`): ``dx = x ⊖ x_ref``,
    ``u = clamp(u_ref - α k - K dx, lb, ub)``, the node at ``(x, u)``, and ``x_next = xnext``, or
    ``xnext ⊕ ((α - 1) f)`` if ``gap``; returns the node's cost."""
    step_control(tbl, ints, x_ref, x, u_ref, k, K, alpha, lb, ub, u, dx)
    cost = invdyn_calc(tbl, ints, par, iints, x, u)
    step_next(tbl, ints, alpha, x_next, f, gap)
    return cost


@uncounted
def _torque_derivatives(tbl, ints, par, rb, ws):
    """``∂τ/∂(q, v)`` into ``dtau_dq``/``dtau_dv``, ``M`` into the workspace, the contacts' ``∂c/∂x`` and the forces'
    ``∂λ``, the differential ``Fx = 0``, ``Fu = (I, 0)`` (after :func:`_values` at a running node, whose kinematics,
    contacts and forces are the node's own arrays); ``τ`` again into the shared scratch (the constraint rows read it),
    by the same operations as :func:`_values`."""
    nv, nu, nc = ints[NV], ints[NU], ints[NC]
    dq, dv, a = mat(tbl, ints, E_DTAU_DQ), mat(tbl, ints, E_DTAU_DV), vec(tbl, ints, E_A)
    rnea_derivatives(rb, ws, a, dq, dv)  # the kinematics of _values at (q, v) are still in ws
    crba(rb, ws)
    tau, lam, Jcs = vec(tbl, ints, E_TAU), vec(tbl, ints, E_LAM), mat(tbl, ints, E_JCS)
    for k in range(nv):
        tau[k] = ws.tau[k]
        if nc:
            acc = 0.0
            for i in range(nc):
                acc += Jcs[i, k] * lam[i]
            tau[k] -= acc
    if ints[N_CONTACTS]:
        cw, lam, dc = entry_contact_workspace(tbl, ints), vec(tbl, ints, E_LAM), mat(tbl, ints, E_DA0_DX)
        gains, ref_R, ref_p = mat(tbl, ints, E_GAINS), cube(tbl, ints, E_REF_R), mat(tbl, ints, E_REF_P)
        for n in range(ints[N_CONTACTS]):
            fid, ncn, ref, row = contact_fields(ints, n)
            contact_force_derivatives(rb, ws, fid, ncn, ref, ref_R[n], lam, row, dq)
            contact_calc_diff(rb, ws, cw, fid, ncn, ref, gains[n, 0], gains[n, 1], ref_R[n], ref_p[n], row, dc)
    df_dx, df_du = mat(tbl, ints, E_DF_DX), mat(tbl, ints, E_DF_DU)
    for i in range(nc):
        for j in range(2 * nv):
            df_dx[i, j] = 0.0
        for j in range(nu):
            df_du[i, j] = 1.0 if j == nv + i else 0.0
    dFx, dFu = mat(tbl, ints, E_DFX), mat(tbl, ints, E_DFU)
    for i in range(nv):
        for j in range(2 * nv):
            dFx[i, j] = 0.0
        for j in range(nu):
            dFu[i, j] = 1.0 if i == j else 0.0


@uncounted
def invdyn_calc_diff(tbl, ints, par, iints, x, u):
    """Values and derivatives of the node at ``(x, u)``; returns its cost.  The values are those of the last
    :func:`invdyn_calc` when its stamp is ``(x, u)`` to the bit (:func:`.euler_node_kernel.stamp_current`), else
    evaluated here; the stamp is then spent."""
    rb, ws = entry_model(tbl, ints), entry_workspace(tbl, ints)
    stamp = vec(tbl, ints, E_STAMP)
    if stamp_current(stamp, x, u):
        cost = stamp[1]
    else:
        cost = _values(tbl, ints, par, iints, x, u, rb, ws)
        euler_step(tbl, ints, par, x, rb)
    if stamp.shape[0]:
        stamp[0] = 0.0
    terminal = ints[TERMINAL] != 0
    if not terminal:
        _torque_derivatives(tbl, ints, par, rb, ws)
    elif ints[NC]:
        df_dx = mat(tbl, ints, E_DF_DX)
        for i in range(ints[NC]):
            for j in range(df_dx.shape[1]):
                df_dx[i, j] = 0.0
    residual_jacobians(tbl, ints, par, rb, ws, x, u)
    _item_jacobians(tbl, ints, par, iints, 0, iints[0], ws, mat(tbl, ints, E_JX), mat(tbl, ints, E_JU),
                    ints[U_START])
    if has_rows(ints):
        _constraints(tbl, ints, par, iints, rb, ws, x, u, True)
    return sums_and_chain(tbl, ints, par, x, rb, cost, terminal)
