"""The generalized gravity ``g(q) = RNEA(q, 0, 0)`` of a lowered model and its derivatives (numba kernels, on the
kinematics and composite inertias of :mod:`.dynamics_kernel`, whose conventions they share).

``g_d = oS_dᵀ Ic_i a_g`` for each dof ``d`` of joint ``i`` (``Ic_i`` the composite inertia of its subtree, ``a_g =
-gravity``).  A tangent of dof ``c`` of joint ``j`` (``s = oS_c``) moves the subtree of ``j``: for ``i`` in it
``∂g_d = -oS_dᵀ Ic_i (s × a_g)``; for ``j`` strictly inside the subtree of ``i``, ``∂g_d = oS_dᵀ (s ×* (Ic_j a_g) -
Ic_j (s × a_g))``; else 0.  Both write ``ws.oIc`` only, which every other user recomputes.  Tests:
``tests/test_rbd_dynamics.py`` (Pinocchio's ``computeGeneralizedGravity`` and its derivatives).
"""

from __future__ import annotations

import numpy as np

from crocopy.kernels import uncounted

from .dynamics_kernel import composite_inertias
from .lowering import RigidBodyModel, RigidBodyWorkspace
from .spatial import dot, fcross, get6, mcross


@uncounted
def _gravity_force(rb, ws, i):
    """``Ic_i a_g``: the subtree of joint ``i`` held against gravity (``a_g = -gravity``, ``ws.oIc`` current)."""
    g, I = rb.gravity, ws.oIc
    return (_row_force(I, i, 0, g), _row_force(I, i, 1, g), _row_force(I, i, 2, g), _row_force(I, i, 3, g),
            _row_force(I, i, 4, g), _row_force(I, i, 5, g))


@uncounted
def _row_force(I, i, r, g):
    """``-(I[i, r] · g)``: row ``r`` of ``I_i a_g``."""
    acc = 0.0
    for c in range(6):
        acc -= I[i, r, c] * g[c]
    return acc


@uncounted
def generalized_gravity(rb: RigidBodyModel, ws: RigidBodyWorkspace, g_out: np.ndarray) -> None:
    """``g_out (nv,) = RNEA(q, 0, 0)`` on the kinematics in ``ws`` (a :func:`forward_kinematics` at ``q``; ``v`` does
    not enter): ``g_d = oS_dᵀ Ic_i a_g`` for each dof ``d`` of joint ``i``, ``Ic_i`` the composite inertia of its
    subtree (left in ``ws.oIc``; nothing else of ``ws`` is written) and ``a_g = -gravity``."""
    composite_inertias(rb, ws)
    idx_v, nvj = rb.idx_v, rb.nvj
    for i in range(1, rb.njoints):
        F = _gravity_force(rb, ws, i)
        for d in range(nvj[i]):
            g_out[idx_v[i] + d] = dot(get6(ws.oS, idx_v[i] + d), F)


@uncounted
def gravity_derivatives(rb: RigidBodyModel, ws: RigidBodyWorkspace, dg_out: np.ndarray) -> None:
    """``dg_out[:, :nv] = ∂g/∂q`` of :func:`generalized_gravity` (tangents in each joint's frame)."""
    composite_inertias(rb, ws)
    g = rb.gravity
    a_g = (-g[0], -g[1], -g[2], -g[3], -g[4], -g[5])
    oS, oIc, dof_joint, subtree_end = ws.oS, ws.oIc, rb.dof_joint, rb.subtree_end
    nv = rb.nv
    for c in range(nv):
        j = dof_joint[c]
        s = get6(oS, c)
        w = mcross(s, a_g)
        for d in range(nv):
            i = dof_joint[d]
            if j <= i < subtree_end[j]:  # i in the subtree of j (j itself included)
                acc = 0.0
                for r in range(6):
                    x = 0.0
                    for k in range(6):
                        x += oIc[i, r, k] * w[k]
                    acc += oS[d, r] * x
                dg_out[d, c] = -acc
            elif i < j < subtree_end[i]:  # j strictly inside the subtree of i
                F = _gravity_force(rb, ws, j)
                term = fcross(s, F)
                acc = 0.0
                for r in range(6):
                    x = 0.0
                    for k in range(6):
                        x += oIc[j, r, k] * w[k]
                    acc += oS[d, r] * (term[r] - x)
                dg_out[d, c] = acc
            else:
                dg_out[d, c] = 0.0
