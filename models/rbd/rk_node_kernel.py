"""The compiled calc and calcDiff of a Runge-Kutta node of free or contact forward dynamics (see :mod:`.rk_node`).

A node of ``ni`` stages (RK2, RK3, RK4: ``c``, ``b`` the tableau of :mod:`crocopy.integrators.rk`) holds one table
per stage (:mod:`.node_table`, rows of ``tbls``; they share ``ints`` and ``par``), each over that stage's
differential data.  Stage ``i`` evaluates the differential model at ``yᵢ = x ⊕ (cᵢ dt kᵢ₋₁)`` (``y₀ = x``) and the
control ``u`` (:func:`.euler_node_kernel.differential_calc`): ``kᵢ = (vᵢ, aᵢ)``, ``lᵢ`` its cost stack's value; then
``dx = dt Σ bᵢ kᵢ``, ``xnext = x ⊕ dx`` and ``cost = dt Σ bᵢ lᵢ``.  The derivatives propagate ``∂yᵢ/∂(x, u)``:

    ∂yᵢ/∂x = Jx + cᵢ dt Jd ∂kᵢ₋₁/∂x,   ∂yᵢ/∂u = cᵢ dt Jd ∂kᵢ₋₁/∂u     (Jx, Jd of x ⊕ cᵢ dt kᵢ₋₁),
    ∂kᵢ/∂(x, u) = (∂yᵢ/∂(x, u)[nv:], ∂aᵢ/∂y ∂yᵢ/∂(x, u) + (0, ∂aᵢ/∂u)),

with Gauss-Newton sums of the stages' cost derivatives (``w = bᵢ dt``: ``Lx += w ∂yᵢ/∂xᵀ lᵢ,y``, ``Lxx += w
∂yᵢ/∂xᵀ lᵢ,yy ∂yᵢ/∂x``, ...) and ``Fx = Jx + Jd Σ w ∂kᵢ/∂x``, ``Fu = Jd Σ w ∂kᵢ/∂u`` (``Jx``, ``Jd`` of
``x ⊕ dx``), as :class:`~crocopy.integrators.rk.IntegratedActionModelRK` computes them.  ``Jx``, ``Jd`` are block
diagonal: the joints' ``∂(q ⊕ v)/∂q`` and ``∂(q ⊕ v)/∂v`` blocks (:func:`.configuration_kernel.dintegrate_blocks`),
then the identity, and are applied block by block.

``stamp[0]`` is 1 after a compiled evaluation of the node; the Python path spends it (``data.compiled_stamp``), and a
``calcDiff`` that finds it spent spends the stages' own stamps before evaluating them (their values may be stale).
"""

from __future__ import annotations

import math

from crocopy.kernels import uncounted

from . import node_table as table
from .configuration_kernel import dintegrate_blocks, state_integrate
from .control_map_kernel import map_controls, map_rows, stage_control
from .euler_node_kernel import (
    differential_calc,
    differential_calc_diff,
    node_calc,
    node_calc_diff,
    step_control,
    step_next,
)


@uncounted
def _stage_state(tbl, ints, x, dt, c, i, k, dy, y):
    """``yᵢ = x ⊕ (cᵢ dt kᵢ₋₁)`` into ``y[i]`` (``dy[i]`` the step; ``y₀ = x``)."""
    nq, nv = ints[table.NQ], ints[table.NV]
    if i == 0:
        for j in range(nq + nv):
            y[0, j] = x[j]
        return
    h = c[i] * dt
    for j in range(2 * nv):
        dy[i, j] = k[i - 1, j] * h
    rb = table.entry_model(tbl, ints)
    state_integrate(rb.jtype, rb.idx_q, rb.idx_v, nq, nv, x, dy[i], y[i])


@uncounted
def _stage_point(tbl, ints, x, u, dt, c, cw, i, k, dy, y, w):
    """Stage ``i``'s state ``yᵢ`` (:func:`_stage_state`) and control ``wᵢ`` (into ``w[i]``)."""
    _stage_state(tbl, ints, x, dt, c, i, k, dy, y)
    stage_control(cw, i, u, w)


@uncounted
def _begin(ints, stamp, dx):
    """The start of a pass: the stamp spent, ``dx`` zero; returns ``ndx``."""
    stamp[0] = 0.0
    n = 2 * ints[table.NV]
    for j in range(n):
        dx[j] = 0.0
    return n


@uncounted
def _rate(tbl, ints, y, k, i):
    """``kᵢ = (vᵢ, aᵢ)`` from the stage's state and its table's acceleration."""
    nq, nv = ints[table.NQ], ints[table.NV]
    a = table.vec(tbl, ints, table.E_A)
    for j in range(nv):
        k[i, j] = y[i, nq + j]
        k[i, nv + j] = a[j]


@uncounted
def _spend(tbls, ints):
    """Spend every stage's stamp (their tables' values are evaluated again)."""
    for i in range(tbls.shape[0]):
        stamp = table.vec(tbls[i], ints, table.E_STAMP)
        if stamp.shape[0]:
            stamp[0] = 0.0


@uncounted
def rk_calc(tbls, ints, par, c, b, dts, stamp, cw, w, x, u, y, dy, k, dx, xnext):
    """``dx``, ``xnext`` of the node at ``(x, u)``; returns its cost, NaN where a stage's acceleration is not finite
    (the caller evaluates the node on the Python path).  ``dts = [dt]``; stage ``i`` reads the control
    ``wᵢ = Σₖ cw[i, k] uₖ`` (:func:`.control_map_kernel.stage_control`, into ``w[i]``)."""
    dt = dts[0]
    n = _begin(ints, stamp, dx)
    cost = 0.0
    for i in range(tbls.shape[0]):
        tbl = tbls[i]
        _stage_point(tbl, ints, x, u, dt, c, cw, i, k, dy, y, w)
        value = differential_calc(tbl, ints, par, y[i], w[i])
        if math.isnan(value):
            return value
        _rate(tbl, ints, y, k, i)
        if b[i] != 0.0:
            h = b[i] * dt
            for j in range(n):
                dx[j] += h * k[i, j]
            cost += b[i] * value
    rb = table.entry_model(tbls[0], ints)
    state_integrate(rb.jtype, rb.idx_q, rb.idx_v, ints[table.NQ], ints[table.NV], x, dx, xnext)
    stamp[0] = 1.0
    return dt * cost


@uncounted
def _integrate_jacobian(tbl, ints, Jq, Jv, h, M, with_x, out):
    """``out = Jx + h Jd M`` (``with_x``) or ``h Jd M`` (a control Jacobian), ``Jx``, ``Jd`` of ``x ⊕ step`` (the
    joints' blocks of ``Jq``, ``Jv``, :func:`_blocks`, then the identity).  Only the blocks are read, one joint's
    rows at a time, the rows of ``M`` added whole."""
    nv = ints[table.NV]
    rb = table.entry_model(tbl, ints)
    n = 2 * nv
    cols = M.shape[1]
    for r in range(n):
        for col in range(cols):
            out[r, col] = 0.0
    for joint in range(1, rb.jtype.shape[0]):
        first, last = rb.idx_v[joint], rb.idx_v[joint] + rb.nvj[joint]
        for r in range(first, last):
            if with_x:
                for m in range(first, last):
                    out[r, m] = Jq[r, m]
            for m in range(first, last):
                s = h * Jv[r, m]
                for col in range(cols):
                    out[r, col] += s * M[m, col]
    for r in range(nv, n):
        if with_x:
            out[r, r] = 1.0
        for col in range(cols):
            out[r, col] += h * M[r, col]


@uncounted
def _blocks(tbl, ints, step, Jq, Jv):
    """The joints' blocks of ``∂(q ⊕ step_q)/∂q`` and ``/∂step_q`` into ``Jq``, ``Jv``."""
    rb = table.entry_model(tbl, ints)
    nv = ints[table.NV]
    dintegrate_blocks(rb.jtype, rb.idx_q, rb.idx_v, step[:nv], 0, Jq)
    dintegrate_blocks(rb.jtype, rb.idx_q, rb.idx_v, step[:nv], 1, Jv)


@uncounted
def _rate_jacobians(tbl, ints, i, dydx, dydu, dkdx, dkdu, dFu):
    """``∂kᵢ/∂x = (∂yᵢ/∂x[nv:], ∂aᵢ/∂y ∂yᵢ/∂x)``, ``∂kᵢ/∂u = (∂yᵢ/∂u[nv:], ∂aᵢ/∂y ∂yᵢ/∂u + ∂aᵢ/∂u)`` (``dFu``:
    ``∂aᵢ/∂u``, the stage's ``∂aᵢ/∂wᵢ`` mapped to ``u``)."""
    nv, nu = ints[table.NV], dFu.shape[1]
    n = 2 * nv
    dFx = table.mat(tbl, ints, table.E_DFX)
    for r in range(nv):
        for col in range(n):
            dkdx[i, r, col] = dydx[i, nv + r, col]
            dkdx[i, nv + r, col] = 0.0
        for col in range(nu):
            dkdu[i, r, col] = dydu[i, nv + r, col]
            dkdu[i, nv + r, col] = dFu[r, col]
        for m in range(n):
            s = dFx[r, m]
            for col in range(n):
                dkdx[i, nv + r, col] += s * dydx[i, m, col]
            for col in range(nu):
                dkdu[i, nv + r, col] += s * dydu[i, m, col]


@uncounted
def _first_stage(tbl, ints, w, dkdx, dkdu, mapped, sums):
    """Stage 0 (``∂y₀/∂x = I``, ``∂y₀/∂u = 0``): its ``∂k₀`` and the sums started from its terms times ``w``
    (``mapped``: the stage's control derivatives mapped to ``u``)."""
    dFu, dLu, dLxu, dLuu = mapped
    nv, nu = ints[table.NV], dFu.shape[1]
    n = 2 * nv
    dFx = table.mat(tbl, ints, table.E_DFX)
    for r in range(nv):
        for col in range(n):
            dkdx[0, r, col] = 1.0 if col == nv + r else 0.0
            dkdx[0, nv + r, col] = dFx[r, col]
        for col in range(nu):
            dkdu[0, r, col] = 0.0
            dkdu[0, nv + r, col] = dFu[r, col]
    kx_sum, ku_sum, Lx, Lu, Lxx, Lxu, Luu = sums
    dLx, dLxx = table.vec(tbl, ints, table.E_DLX), table.mat(tbl, ints, table.E_DLXX)
    for r in range(n):
        Lx[r] = w * dLx[r]
        for col in range(n):
            kx_sum[r, col] = w * dkdx[0, r, col]
            Lxx[r, col] = w * dLxx[r, col]
        for col in range(nu):
            ku_sum[r, col] = w * dkdu[0, r, col]
            Lxu[r, col] = w * dLxu[r, col]
    for r in range(nu):
        Lu[r] = w * dLu[r]
        for col in range(nu):
            Luu[r, col] = w * dLuu[r, col]


@uncounted
def _add_stage(tbl, ints, i, w, dydx, dydu, dkdx, dkdu, LxxJ, T, mapped, sums):
    """Add stage ``i``'s terms times ``w = bᵢ dt`` to the sums (scratch: ``LxxJ`` ``ndx × nu``, ``T`` ``ndx × ndx``):
    ``T = lyy ∂y/∂x``, ``LxxJ = lyy ∂y/∂u``, then each sum row by row, adding whole rows (contiguous loops)."""
    _, dLu, dLxu, dLuu = mapped
    n, nu = 2 * ints[table.NV], dLu.shape[0]
    kx_sum, ku_sum, Lx, Lu, Lxx, Lxu, Luu = sums
    dLx, dLxx = table.vec(tbl, ints, table.E_DLX), table.mat(tbl, ints, table.E_DLXX)
    for r in range(n):
        for col in range(n):
            kx_sum[r, col] += w * dkdx[i, r, col]
            T[r, col] = 0.0
        for col in range(nu):
            ku_sum[r, col] += w * dkdu[i, r, col]
            LxxJ[r, col] = 0.0
        for m in range(n):
            s = dLxx[r, m]
            for col in range(n):
                T[r, col] += s * dydx[i, m, col]
            for col in range(nu):
                LxxJ[r, col] += s * dydu[i, m, col]
    for m in range(n):
        s = w * dLx[m]
        for col in range(n):
            Lx[col] += s * dydx[i, m, col]
        for col in range(nu):
            Lu[col] += s * dydu[i, m, col]
    for r in range(nu):
        Lu[r] += w * dLu[r]
    for r in range(n):
        for m in range(n):
            s = w * dydx[i, m, r]
            for col in range(n):
                Lxx[r, col] += s * T[m, col]
            for col in range(nu):
                Lxu[r, col] += s * (LxxJ[m, col] + dLxu[m, col])
    for r in range(nu):
        for m in range(n):
            s = w * dydu[i, m, r]
            for col in range(nu):
                Luu[r, col] += s * (LxxJ[m, col] + dLxu[m, col]) + w * dydu[i, m, col] * dLxu[m, r]
        for col in range(nu):
            Luu[r, col] += w * dLuu[r, col]


@uncounted
def rk_calc_diff(tbls, ints, par, c, b, dts, stamp, cw, w, x, u, work, jac, mapped, rows, out):
    """Values and derivatives of the node at ``(x, u)`` (module docstring); returns its cost, NaN where a stage's
    acceleration is not finite.  ``work = (y, dy, k, Jq, Jv, T, LxxJ)``, ``jac = (dydx, dydu, dkdx, dkdu)``
    (per stage), ``mapped = (Fu, Lu, Lxu, Luu)`` (scratch: a stage's control derivatives mapped to ``u``,
    :func:`.control_map_kernel.map_controls`), ``rows = (Gu, Hu)`` (the node's, from the first stage's),
    ``out = (dx, xnext, Fx, Fu, kx_sum, ku_sum, Lx, Lu, Lxx, Lxu, Luu)``; ``cw``, ``w`` as for :func:`rk_calc`."""
    dt = dts[0]
    y, dy, k, Jq, Jv, T, LxxJ = work
    dydx, dydu, dkdx, dkdu = jac
    dx, xnext, Fx, Fu = out[0], out[1], out[2], out[3]
    sums = out[4:]
    if stamp[0] != 1.0:
        _spend(tbls, ints)
    nv = ints[table.NV]
    n = _begin(ints, stamp, dx)
    cost = 0.0
    for i in range(tbls.shape[0]):
        tbl = tbls[i]
        _stage_point(tbl, ints, x, u, dt, c, cw, i, k, dy, y, w)
        if i:
            h = c[i] * dt
            _blocks(tbl, ints, dy[i], Jq, Jv)
            _integrate_jacobian(tbl, ints, Jq, Jv, h, dkdx[i - 1], True, dydx[i])
            _integrate_jacobian(tbl, ints, Jq, Jv, h, dkdu[i - 1], False, dydu[i])
        value = differential_calc_diff(tbl, ints, par, y[i], w[i])
        if math.isnan(value):
            return value
        _rate(tbl, ints, y, k, i)
        _map_stage(tbl, ints, table.E_DFU, table.E_DLU, table.E_DLXU, table.E_DLUU, cw[i], mapped)
        weight = b[i] * dt
        if i == 0:
            _map_rows(tbl, ints, cw[0], rows)
            _first_stage(tbl, ints, weight, dkdx, dkdu, mapped, sums)
        else:
            _rate_jacobians(tbl, ints, i, dydx, dydu, dkdx, dkdu, mapped[0])
            if b[i] != 0.0:
                _add_stage(tbl, ints, i, weight, dydx, dydu, dkdx, dkdu, LxxJ, T, mapped, sums)
        if b[i] != 0.0:
            for j in range(n):
                dx[j] += weight * k[i, j]
            cost += b[i] * value
    tbl = tbls[0]
    rb = table.entry_model(tbl, ints)
    state_integrate(rb.jtype, rb.idx_q, rb.idx_v, ints[table.NQ], nv, x, dx, xnext)
    _blocks(tbl, ints, dx, Jq, Jv)
    _integrate_jacobian(tbl, ints, Jq, Jv, 1.0, sums[0], True, Fx)
    _integrate_jacobian(tbl, ints, Jq, Jv, 1.0, sums[1], False, Fu)
    stamp[0] = 1.0
    return dt * cost


@uncounted
def _map_stage(tbl, ints, eFu, eLu, eLxu, eLuu, c, mapped):
    """The control derivatives of a table sized by ``w`` (its entries ``eFu`` … ``eLuu``) mapped to ``u`` into
    ``mapped = (Fu, Lu, Lxu, Luu)`` (:func:`.control_map_kernel.map_controls`, coefficients ``c``)."""
    Fu, Lu, Lxu, Luu = mapped
    map_controls(table.mat(tbl, ints, eFu), table.vec(tbl, ints, eLu), table.mat(tbl, ints, eLxu),
                 table.mat(tbl, ints, eLuu), c, Fu, Lu, Lxu, Luu)


@uncounted
def _map_rows(tbl, ints, c, rows):
    """The node's ``Gu``, ``Hu`` (``rows``) from the constraint rows of a table sized by ``w``
    (:func:`.control_map_kernel.map_rows`)."""
    Gu, Hu = rows
    if Gu.shape[0]:
        map_rows(table.mat(tbl, ints, table.E_GU), c, Gu)
    if Hu.shape[0]:
        map_rows(table.mat(tbl, ints, table.E_HU), c, Hu)


@uncounted
def rk_rollout_step(tbls, ints, par, c, b, dts, stamp, cw, w, values, x_ref, x, u_ref, kff, K, alpha, lb, ub, u, dxs,
                    x_next, f, gap):
    """One node of the DDP family's rollout (as :func:`.euler_node_kernel.node_rollout_step`): ``dxs = x ⊖ x_ref``,
    ``u = clamp(u_ref - α kff - K dxs, lb, ub)``, the node at ``(x, u)`` (``values = (y, dy, k, dx, xnext)``), and
    ``x_next = xnext``, or ``xnext ⊕ ((α - 1) f)`` if ``gap`` (``step``: scratch); returns the node's cost."""
    y, dy, k, dx, xnext, step = values
    tbl = tbls[0]
    step_control(tbl, ints, x_ref, x, u_ref, kff, K, alpha, lb, ub, u, dxs)
    cost = rk_calc(tbls, ints, par, c, b, dts, stamp, cw, w, x, u, y, dy, k, dx, xnext)
    nq, nv = ints[table.NQ], ints[table.NV]
    if gap:
        for i in range(2 * nv):
            step[i] = (alpha - 1.0) * f[i]
        rb = table.entry_model(tbl, ints)
        state_integrate(rb.jtype, rb.idx_q, rb.idx_v, nq, nv, xnext, step, x_next)
    else:
        for i in range(nq + nv):
            x_next[i] = xnext[i]
    return cost



@uncounted
def controlled_euler_calc(tbl, ints, par, cw, w, x, u):
    """An Euler node with a control parametrization at ``(x, u)``: its table (sized by ``w``) at ``w = w(0, u)``
    (:func:`.euler_node_kernel.node_calc`, into ``w[0]``); returns its cost."""
    stage_control(cw, 0, u, w)
    return node_calc(tbl, ints, par, x, w[0])


@uncounted
def controlled_euler_calc_diff(tbl, ints, par, cw, w, x, u, Fu, Lu, Lxu, Luu, rows):
    """:func:`controlled_euler_calc` with the derivatives (:func:`.euler_node_kernel.node_calc_diff`), the table's
    control derivatives mapped to the node's ``Fu``, ``Lu``, ``Lxu``, ``Luu`` and ``rows = (Gu, Hu)``; returns its
    cost."""
    stage_control(cw, 0, u, w)
    cost = node_calc_diff(tbl, ints, par, x, w[0])
    if not math.isnan(cost):
        _map_stage(tbl, ints, table.E_FU, table.E_LU, table.E_LXU, table.E_LUU, cw[0], (Fu, Lu, Lxu, Luu))
        _map_rows(tbl, ints, cw[0], rows)
    return cost


@uncounted
def controlled_euler_rollout_step(tbl, ints, par, cw, w, x_ref, x, u_ref, kff, K, alpha, lb, ub, u, dxs, x_next, f,
                                  gap):
    """One node of the rollout (as :func:`.euler_node_kernel.node_rollout_step`) of an Euler node with a control
    parametrization: ``u`` from the feedback, the node at ``w = w(0, u)``."""
    step_control(tbl, ints, x_ref, x, u_ref, kff, K, alpha, lb, ub, u, dxs)
    cost = controlled_euler_calc(tbl, ints, par, cw, w, x, u)
    step_next(tbl, ints, alpha, x_next, f, gap)
    return cost
