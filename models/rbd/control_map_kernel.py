"""A node's control parametrization in compiled nodes (:mod:`.rk_node`): the differential model reads ``w``, the
node's controls are the parameters ``u = (u₀, …, u_{K-1})`` (``K`` blocks of ``nw``), and at a stage of normalised
time ``τ`` (:mod:`crocopy.integrators.control_poly`)

    w = Σₖ cₖ(τ) uₖ,   ∂w/∂u = [c₀ I, …, c_{K-1} I],

so that a stage's derivatives map as ``Fu = Fw ∂w/∂u``, ``Lu = ∂w/∂uᵀ Lw``, ``Lxu = Lxw ∂w/∂u``,
``Luu = ∂w/∂uᵀ Lww ∂w/∂u``, ``Gu = Gw ∂w/∂u``, ``Hu = Hw ∂w/∂u``: blocks of ``Fw``, ``Lw``, ``Lxw``, ``Gw``, ``Hw``
scaled by ``cₖ``, of ``Lww`` by ``cₖ cₗ``.  The
identity parametrization is ``K = 1``, ``c₀ = 1``.
"""

from __future__ import annotations

from crocopy.kernels import uncounted


@uncounted
def stage_control(cw, i, u, w):
    """``w[i] = Σₖ cw[i, k] uₖ`` (the blocks ``uₖ`` of ``u``, each of ``w``'s size)."""
    nw = w.shape[1]
    for j in range(nw):
        acc = 0.0
        for blk in range(cw.shape[1]):
            acc += cw[i, blk] * u[blk * nw + j]
        w[i, j] = acc


@uncounted
def map_controls(Fw, Lw, Lxw, Lww, c, Fu, Lu, Lxu, Luu):
    """``Fu``, ``Lu``, ``Lxu``, ``Luu`` from a stage's ``Fw (nv, nw)``, ``Lw``, ``Lxw (ndx, nw)``, ``Lww`` and the
    coefficients ``c`` of its ``∂w/∂u`` (module docstring)."""
    nw = Lw.shape[0]
    for blk in range(c.shape[0]):
        s = c[blk]
        first = blk * nw
        for r in range(Fw.shape[0]):
            for j in range(nw):
                Fu[r, first + j] = s * Fw[r, j]
        for r in range(Lxw.shape[0]):
            for j in range(nw):
                Lxu[r, first + j] = s * Lxw[r, j]
        for j in range(nw):
            Lu[first + j] = s * Lw[j]
        for other in range(c.shape[0]):
            t = c[other]
            second = other * nw
            for r in range(nw):
                for j in range(nw):
                    Luu[first + r, second + j] = s * (t * Lww[r, j])


@uncounted
def map_rows(Gw, c, Gu):
    """``Gu = Gw ∂w/∂u``: a constraint Jacobian's blocks ``cₖ Gw`` (nothing for zero rows)."""
    nw = Gw.shape[1]
    for blk in range(c.shape[0]):
        s = c[blk]
        for r in range(Gw.shape[0]):
            for j in range(nw):
                Gu[r, blk * nw + j] = s * Gw[r, j]
