"""Compiled centre of mass of a lowered model and its Jacobian (Pinocchio's ``centerOfMass`` and
``jacobianCenterOfMass``).

With ``m_i`` the body masses (joints ``1 .. njoints - 1``), ``c_i = p_i + R_i com_i`` their world centres of
mass and ``m = Σ m_i``::

    com = Σ m_i c_i / m,     Jcom_k = (m_j s_v + s_ω × h_j) / m

for a dof ``k`` of joint ``j`` with world column ``s = oS_k = [s_v; s_ω]`` (the velocity of a point ``c`` moved by
``s`` is ``s_v + s_ω × c``), ``m_j = Σ m_i`` and ``h_j = Σ m_i c_i`` over the subtree of ``j``.  The subtree
sums are taken per joint (``O(njoints²)`` flops, no scratch).  Shapes: ``com_out (3,)``, ``Jcom_out (3, nv)``.
"""

from __future__ import annotations

import math

import numpy as np

from crocopy.kernels import uncounted

from .lowering import RigidBodyModel, RigidBodyWorkspace


@uncounted
def _subtree_moment(rb, ws, j):
    """``(m_j, h_j)``: mass and first moment ``Σ m_i c_i`` (world) of the subtree of joint ``j``."""
    oR, op, com, mass = ws.oR, ws.op, rb.com, rb.mass
    m = hx = hy = hz = 0.0
    for i in range(j, rb.subtree_end[j]):
        if i == 0:
            continue
        mi = mass[i]
        m += mi
        hx += mi * (op[i, 0] + oR[i, 0, 0] * com[i, 0] + oR[i, 0, 1] * com[i, 1] + oR[i, 0, 2] * com[i, 2])
        hy += mi * (op[i, 1] + oR[i, 1, 0] * com[i, 0] + oR[i, 1, 1] * com[i, 1] + oR[i, 1, 2] * com[i, 2])
        hz += mi * (op[i, 2] + oR[i, 2, 0] * com[i, 0] + oR[i, 2, 1] * com[i, 1] + oR[i, 2, 2] * com[i, 2])
    return m, hx, hy, hz


@uncounted
def center_of_mass(rb: RigidBodyModel, ws: RigidBodyWorkspace, com_out: np.ndarray, Jcom_out: np.ndarray) -> None:
    """``com_out (3,)``: the world centre of mass; ``Jcom_out (3, nv)``: its Jacobian (after
    :func:`~.dynamics_kernel.forward_kinematics`)."""
    m, hx, hy, hz = _subtree_moment(rb, ws, 0)
    inv = 1.0 / m if m > 0.0 else math.nan  # a massless robot: NaN, as Pinocchio's centerOfMass
    com_out[0], com_out[1], com_out[2] = hx * inv, hy * inv, hz * inv
    oS = ws.oS
    for j in range(1, rb.njoints):
        mj, hx, hy, hz = _subtree_moment(rb, ws, j)
        for k in range(rb.idx_v[j], rb.idx_v[j] + rb.nvj[j]):
            Jcom_out[0, k] = (mj * oS[k, 0] + oS[k, 4] * hz - oS[k, 5] * hy) * inv
            Jcom_out[1, k] = (mj * oS[k, 1] + oS[k, 5] * hx - oS[k, 3] * hz) * inv
            Jcom_out[2, k] = (mj * oS[k, 2] + oS[k, 3] * hy - oS[k, 4] * hx) * inv
