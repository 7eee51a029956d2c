"""Compiled glue of :class:`~crocopy.solvers.sqp.SolverSQP` and :class:`~crocopy.solvers.csqp.SolverCSQP`
(numba), twins of the numpy methods of :mod:`crocopy.solvers.sqp` and :mod:`crocopy.solvers.csqp`.

They read the running nodes' ``Fx, Fu, Lxx, Lxu, Luu, Lx, Lu`` by address (``daddr (T, 7)``,
:class:`.horizon.NodeDerivatives`), the solver's per-node arrays in its horizon buffer (``haddr (T+1, NQ)``,
columns of :mod:`.horizon`: gaps ``fs``, gains ``k``, ``K``, value function ``Vx``, ``Vxx``) and the steps
``dx (T+1, n)``, ``du (T+1, m)``, multipliers ``lam (T+1, n)`` as padded stacks; ``dims (T+1, 3)`` holds
each node's ``(ndx, nu, nc)`` and ``C (T+1, c, n)``, ``D (T+1, c, m)``, ``y (T+1, c)`` the QP rows
(``nc = 0`` for SolverSQP).

* :func:`linear_rollout`: ``δx_0 = f_0``, ``δu_t = -k_t - K_t δx_t``, ``δx_{t+1} = Fx δx_t + Fu δu_t +
  f_{t+1}``, then ``λ_t = Vxx_t (δx_t - f_t) + Vx_t``;
* :func:`kkt`: ``max(‖Lx_t + Fx_tᵀ λ_{t+1} - λ_t + [t >= 1] C_tᵀ y_t‖∞, ‖Lu_t + Fu_tᵀ λ_{t+1} + D_tᵀ y_t‖∞,
  ‖Lx_T - λ_T + C_Tᵀ y_T‖∞, max_t ‖f_t‖∞)``;
* :func:`gap_l1`: ``Σ_t ‖f_t‖₁`` (:func:`stack_l1` for gaps in a stack, summed in the same order); :func:`gap_linf`:
  ``max_t ‖f_t‖∞`` (the DDP family's ``ffeas``);
* :func:`all_finite`: whether the vectors at some addresses are finite (a trial's states and controls).
"""

from __future__ import annotations

import math

import numpy as np

from ..kernels import compiled, matrix_at, uncounted, vector_at
from .horizon import FS, KM, KV, VX, VXX


def readable(a: np.ndarray) -> np.ndarray:
    """``a`` as a C-contiguous float64 array, for a kernel (a copy only when it is not one)."""
    return a if a.dtype == np.float64 and a.flags.c_contiguous else np.ascontiguousarray(a, dtype=np.float64)


def _linear_rollout(dims, daddr, haddr, dx, du, lam):
    T = dims.shape[0] - 1
    n0 = dims[0, 0]
    f0 = vector_at(haddr[0, FS], n0)
    for i in range(n0):
        dx[0, i] = f0[i]
    for t in range(T):
        n, m, n1 = dims[t, 0], dims[t, 1], dims[t + 1, 0]
        Fx, Fu = matrix_at(daddr[t, 0], n1, n), matrix_at(daddr[t, 1], n1, m)
        k, K, f1 = vector_at(haddr[t, KV], m), matrix_at(haddr[t, KM], m, n), vector_at(haddr[t + 1, FS], n1)
        for i in range(m):
            acc = 0.0
            for j in range(n):
                acc += K[i, j] * dx[t, j]
            du[t, i] = -k[i] - acc
        for i in range(n1):
            acc = 0.0
            for j in range(n):
                acc += Fx[i, j] * dx[t, j]
            acc2 = 0.0
            for j in range(m):
                acc2 += Fu[i, j] * du[t, j]
            dx[t + 1, i] = acc + acc2 + f1[i]
    for t in range(T + 1):
        n = dims[t, 0]
        Vxx, Vx, f = matrix_at(haddr[t, VXX], n, n), vector_at(haddr[t, VX], n), vector_at(haddr[t, FS], n)
        for i in range(n):
            acc = 0.0
            for j in range(n):
                acc += Vxx[i, j] * (dx[t, j] - f[j])
            lam[t, i] = acc + Vx[i]


linear_rollout = compiled(_linear_rollout)


def _worst(worst, v, n):
    for i in range(n):
        if abs(v[i]) > worst:
            worst = abs(v[i])
    return worst


worst_abs = compiled(_worst)


def _kkt(dims, daddr, haddr, LxT, lam, C, D, y, g):
    """The KKT measure (module docstring); ``g``: scratch of the largest node's size."""
    T = dims.shape[0] - 1
    worst = 0.0
    for t in range(T):
        n, m, c, n1 = dims[t, 0], dims[t, 1], dims[t, 2], dims[t + 1, 0]
        Fx, Fu = matrix_at(daddr[t, 0], n1, n), matrix_at(daddr[t, 1], n1, m)
        Lx, Lu = vector_at(daddr[t, 5], n), vector_at(daddr[t, 6], m)
        for i in range(n):
            g[i] = Lx[i] - lam[t, i]
        for q in range(n1):
            a = lam[t + 1, q]
            for i in range(n):
                g[i] += Fx[q, i] * a
        if t > 0:
            for r in range(c):
                a = y[t, r]
                for i in range(n):
                    g[i] += C[t, r, i] * a
        worst = worst_abs(worst, g, n)
        for i in range(m):
            g[i] = Lu[i]
        for q in range(n1):
            a = lam[t + 1, q]
            for i in range(m):
                g[i] += Fu[q, i] * a
        for r in range(c):
            a = y[t, r]
            for i in range(m):
                g[i] += D[t, r, i] * a
        worst = worst_abs(worst, g, m)
    n, c = dims[T, 0], dims[T, 2]
    for i in range(n):
        g[i] = LxT[i] - lam[T, i]
    for r in range(c):
        a = y[T, r]
        for i in range(n):
            g[i] += C[T, r, i] * a
    worst = worst_abs(worst, g, n)
    for t in range(T + 1):
        worst = worst_abs(worst, vector_at(haddr[t, FS], dims[t, 0]), dims[t, 0])
    return worst


kkt = compiled(_kkt)


def _gap_l1(dims, haddr):
    total = 0.0
    for t in range(dims.shape[0]):
        f = vector_at(haddr[t, FS], dims[t, 0])
        for i in range(dims[t, 0]):
            total += abs(f[i])
    return total


def _stack_l1(dims, f):
    """:func:`gap_l1` of the gaps in a stack ``f (T+1, n)`` (same order of summation)."""
    total = 0.0
    for t in range(dims.shape[0]):
        for i in range(dims[t, 0]):
            total += abs(f[t, i])
    return total


def _gap_linf(dims, haddr):
    """``max_t ‖f_t‖∞``: NaN as soon as an entry is NaN (as numpy's ``max``), 0 without entries."""
    worst = 0.0
    for t in range(dims.shape[0]):
        f = vector_at(haddr[t, FS], dims[t, 0])
        for i in range(dims[t, 0]):
            a = abs(f[i])
            if a != a:
                return a
            if a > worst:
                worst = a
    return worst


def _zero_gaps(dims, haddr):
    """``f_t = 0`` for every node."""
    for t in range(dims.shape[0]):
        f = vector_at(haddr[t, FS], dims[t, 0])
        for i in range(dims[t, 0]):
            f[i] = 0.0


gap_l1 = compiled(_gap_l1)
gap_linf = compiled(_gap_linf)
zero_gaps = uncounted(_zero_gaps)
stack_l1 = compiled(_stack_l1)


def _all_finite(addresses, sizes):
    """True when the ``sizes[t]`` floats at ``addresses[t]`` are finite, for every t."""
    for t in range(addresses.shape[0]):
        n = sizes[t]
        if n:
            v = vector_at(addresses[t], n)
            for i in range(n):
                if not math.isfinite(v[i]):
                    return False
    return True


all_finite = compiled(_all_finite)
