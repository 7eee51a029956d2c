"""Compiled stagewise ADMM of :class:`~crocopy.solvers.csqp.SolverCSQP` (numba), twin of :mod:`.csqp_admm`.

:func:`admm_run` runs ADMM iterations ``j0 <= j < j1`` of one QP (:mod:`.csqp_admm` states the maths:
the Riccati x-update with ``σ``, ``μ`` and the rows' ``ρ``, ``η = y - ρ z``; the rollout; the
over-relaxed projection and dual ascent; every ``rho_update_interval`` iterations the residuals, the
``ρ̄`` update and the stopping test) in one call, and, when asked, first the equality-QP pass that sets
the anchor ``w̄``.  It works on the stacked arrays of :class:`~crocopy.solvers.csqp_admm.StagewiseADMM`
(node ``t`` in row ``t``, padded to the largest node: ``C (N+1, c, n)``, ``P (N+1, n, n)`` ...; ``dims``
``(N+1, 3)`` gives each node's ``(ndx, nu, nc)``) and reads the running nodes' derivatives ``Fx, Fu,
Lxx, Lxu, Luu, Lx, Lu`` where the datas keep them (``daddr (N, 7)``, :class:`.horizon.NodeDerivatives`)
and the gaps in the solver's horizon buffer (``haddr[:, FS]``, :class:`.horizon.Horizon`).

Settings ``par``: ``(σ, μ, α, rho_min, rho_max, adaptive_rho_tolerance, eps_abs, eps_rel, ρ̄)``;
The rows' products (``C δx``, ``Cᵀ η`` ...) run over each row's span of nonzero entries (:func:`row_spans`, found
once per call: a selection row or a constraint on the state alone costs its nonzeros only; the same numbers).
``ipar``: ``(j0, j1, rho_update_interval, update_rho_with_heuristic, equality pass first, factorised)``.  A
scheduled refactorisation (every ``rho_update_interval`` iterations) is skipped while ``factorised``: the factors
are those of the current ``ρ`` (the same numbers), i.e. since the last one no ``ρ̄`` update (nor equality pass) came.
It writes the residuals of its last check, ``ρ̄`` and ``factorised`` into ``out = (r_p, r_d, s_p, s_d, ρ̄,
factorised)`` and returns the
iteration whose stopping test passed, 0 when none did before ``j1``, or ``-(t + 1)`` when ``Quu`` of
node ``t`` is not positive definite (nor finite).  :func:`multipliers` gives ``λ_t = p_t + P_t δx_t``.
Row kinds (``kind``): :data:`INEQUALITY`, :data:`EQUALITY`, :data:`FREE`.
"""

from __future__ import annotations

import numpy as np

from ..kernels import compiled, matrix_at, vector_at
from .riccati_kernel import cholesky_lower

INEQUALITY, EQUALITY, FREE = 0, 1, 2


def _assign_rho(dims, kind, rho, rho_bar, rho_min):
    """Per-row ``ρ``: ``rho_min`` (free), ``1e3 ρ̄`` (equality), ``ρ̄`` (the others)."""
    for t in range(dims.shape[0]):
        for i in range(dims[t, 2]):
            rho[t, i] = rho_min if kind[t, i] == FREE else (1e3 * rho_bar if kind[t, i] == EQUALITY else rho_bar)


assign_rho = compiled(_assign_rho)


def _factorise(n, m, c, n1, Fx, Fu, Lxx, Lxu, Luu, C, D, rho, with_rows, sigma, mu, P1, P, K, L, Qxx, Qxu, Quu, W,
               Wu, idx):
    """``Quu`` factor ``L`` (its diagonal inverted, so that the solves multiply), gains ``K`` and ``P`` of a node
    from the next ``P1`` (node rows ``C, D, rho``, which enter ``Qxx``/``Qxu`` only when ``with_rows == 2``, i.e. not
    on node 0); False when ``Quu`` is not positive definite or not finite.  Stack rows (padded) and loops whose inner
    index is contiguous (vectorised); the products skip zero entries (selection rows, the identity blocks of
    ``Fx``)."""
    for i in range(n):
        for j in range(n1):
            W[i, j] = 0.0
    for i in range(m):
        for j in range(n1):
            Wu[i, j] = 0.0
    for q in range(n1):
        for i in range(n):
            a = Fx[q, i]
            if a == 0.0:
                continue
            for j in range(n1):
                W[i, j] += a * P1[q, j]
        for i in range(m):
            a = Fu[q, i]
            if a == 0.0:
                continue
            for j in range(n1):
                Wu[i, j] += a * P1[q, j]
    for i in range(n):
        for j in range(n):
            Qxx[i, j] = 0.0
        for j in range(m):
            Qxu[i, j] = 0.0
        for q in range(n1):
            a = W[i, q]
            if a == 0.0:
                continue
            for j in range(n):
                Qxx[i, j] += a * Fx[q, j]
            for j in range(m):
                Qxu[i, j] += a * Fu[q, j]
        for j in range(n):
            Qxx[i, j] = Lxx[i, j] + Qxx[i, j]
        for j in range(m):
            Qxu[i, j] = Lxu[i, j] + Qxu[i, j]
        Qxx[i, i] += sigma
    if with_rows == 2:
        for r in range(c):
            for i in range(n):
                a = rho[r] * C[r, i]
                if a == 0.0:
                    continue
                for j in range(n):
                    Qxx[i, j] += a * C[r, j]
    if m == 0:
        symmetrise(n, Qxx, P, mu)
        return True
    for i in range(m):
        for j in range(m):
            Quu[i, j] = 0.0
        for q in range(n1):
            a = Wu[i, q]
            if a == 0.0:
                continue
            for j in range(m):
                Quu[i, j] += a * Fu[q, j]
        for j in range(m):
            Quu[i, j] = Luu[i, j] + Quu[i, j]
        Quu[i, i] += sigma + mu
    if with_rows:
        for r in range(c):
            for i in range(m):
                a = rho[r] * D[r, i]
                if a == 0.0:
                    continue
                for j in range(m):
                    Quu[i, j] += a * D[r, j]
            if with_rows == 2:
                for i in range(n):
                    a = rho[r] * C[r, i]
                    if a == 0.0:
                        continue
                    for j in range(m):
                        Qxu[i, j] += a * D[r, j]
    if not cholesky_lower(Quu, idx, m, L):
        return False
    for i in range(m):  # the diagonal inverted: the solves multiply
        L[i, i] = 1.0 / L[i, i]
    for i in range(m):  # K = Quu⁻¹ Qxuᵀ: L⁻¹ then L⁻ᵀ, row by row
        for j in range(n):
            K[i, j] = Qxu[j, i]
        for q in range(i):
            a = L[i, q]
            if a == 0.0:
                continue
            for j in range(n):
                K[i, j] -= a * K[q, j]
        d = L[i, i]
        for j in range(n):
            K[i, j] *= d
    for i in range(m - 1, -1, -1):
        for q in range(i + 1, m):
            a = L[q, i]
            if a == 0.0:
                continue
            for j in range(n):
                K[i, j] -= a * K[q, j]
        d = L[i, i]
        for j in range(n):
            K[i, j] *= d
    for i in range(n):
        for q in range(m):
            a = Qxu[i, q]
            if a == 0.0:
                continue
            for j in range(n):
                Qxx[i, j] -= a * K[q, j]
    symmetrise(n, Qxx, P, mu)
    return True


def _symmetrise(n, Q, P, mu):
    """``P = (Q + Qᵀ)/2 + mu I`` on the leading ``n × n`` block."""
    for i in range(n):
        for j in range(n):
            P[i, j] = 0.5 * (Q[i, j] + Q[j, i])
        P[i, i] += mu


symmetrise = compiled(_symmetrise)
factorise = compiled(_factorise)




def _row_spans(dims, C, D, spans):
    """Where each row's nonzero entries are: ``C[t, r, spans[t, r, 0]:spans[t, r, 1]]`` and ``D[t, r, spans[t, r, 2]:
    spans[t, r, 3]]`` (``(0, 0)`` for a zero row); the products of the ADMM iterations skip the rest (a selection row,
    a constraint on the state alone)."""
    N = dims.shape[0] - 1
    for t in range(N + 1):
        n, m, c = dims[t, 0], dims[t, 1], dims[t, 2]
        for r in range(c):
            first, last = 0, 0
            for i in range(n):
                if C[t, r, i] != 0.0:
                    if last == 0:
                        first = i
                    last = i + 1
            spans[t, r, 0], spans[t, r, 1] = first, last
            first, last = 0, 0
            for i in range(m if t < N else 0):
                if D[t, r, i] != 0.0:
                    if last == 0:
                        first = i
                    last = i + 1
            spans[t, r, 2], spans[t, r, 3] = first, last


row_spans = compiled(_row_spans)


def _gradient(A, g, base, rows, cols, out):
    """``out[:cols] = base + Aᵀ g`` (``A (rows, cols)``): columns four at a time, each sum in row order."""
    i = 0
    while i + 4 <= cols:
        a0, a1, a2, a3 = base[i], base[i + 1], base[i + 2], base[i + 3]
        for q in range(rows):
            x = g[q]
            a0 += A[q, i] * x
            a1 += A[q, i + 1] * x
            a2 += A[q, i + 2] * x
            a3 += A[q, i + 3] * x
        out[i], out[i + 1], out[i + 2], out[i + 3] = a0, a1, a2, a3
        i += 4
    while i < cols:
        a0 = base[i]
        for q in range(rows):
            a0 += A[q, i] * g[q]
        out[i] = a0
        i += 1


gradient = compiled(_gradient)


def _riccati(dims, daddr, haddr, fs_col, LxT, LxxT, sigma, mu, rows, full, C, D, rho, eta, dx_bar, du_bar, P, p, Pd,
             K, k, L, S, Sv, idx, spans):
    """The backward pass of :meth:`.csqp_admm.StagewiseADMM.riccati`; -1, or the node whose ``Quu`` failed.
    The stacks are indexed in place (a row view per node costs a reference count); the rows' products run over their
    nonzero spans (:func:`row_spans`)."""
    N = dims.shape[0] - 1
    Qxx, Qxu, Quu, W, Wu = S[0], S[1], S[2], S[3], S[4]
    Qx, Qu, g = Sv[0], Sv[1], Sv[2]
    n, c = dims[N, 0], dims[N, 2]
    terminal_rows = rows and c > 0
    for i in range(n):
        p[N, i] = LxT[i]
        if sigma != 0.0:
            p[N, i] -= sigma * dx_bar[N, i]
    if terminal_rows:
        for r in range(c):
            a_ = eta[N, r]
            for i in range(spans[N, r, 0], spans[N, r, 1]):
                p[N, i] += C[N, r, i] * a_
    if full:
        for i in range(n):
            for j in range(n):
                P[N, i, j] = LxxT[i, j]
        if terminal_rows:
            for r in range(c):
                for i in range(n):
                    a_ = rho[N, r] * C[N, r, i]
                    for j in range(n):
                        P[N, i, j] += C[N, r, j] * a_
        for i in range(n):
            P[N, i, i] += sigma + mu
    for t in range(N - 1, -1, -1):
        n, m, c, n1 = dims[t, 0], dims[t, 1], dims[t, 2], dims[t + 1, 0]
        Fx, Fu = matrix_at(daddr[t, 0], n1, n), matrix_at(daddr[t, 1], n1, m)
        Lx, Lu = vector_at(daddr[t, 5], n), vector_at(daddr[t, 6], m)
        with_rows = 0 if not rows or c == 0 else (1 if t == 0 else 2)
        if full:
            d1 = vector_at(haddr[t + 1, fs_col], n1)
            for i in range(n1):
                acc = 0.0
                for j in range(n1):
                    acc += P[t + 1, i, j] * d1[j]
                Pd[t + 1, i] = acc
        for i in range(n1):
            g[i] = p[t + 1, i] + Pd[t + 1, i]
        gradient(Fx, g, Lx, n1, n, Qx)
        gradient(Fu, g, Lu, n1, m, Qu)
        if sigma != 0.0:
            for i in range(n):
                Qx[i] -= sigma * dx_bar[t, i]
            for i in range(m):
                Qu[i] -= sigma * du_bar[t, i]
        for r in range(c if with_rows else 0):
            a_ = eta[t, r]
            if with_rows == 2:
                for i in range(spans[t, r, 0], spans[t, r, 1]):
                    Qx[i] += C[t, r, i] * a_
            for i in range(spans[t, r, 2], spans[t, r, 3]):
                Qu[i] += D[t, r, i] * a_
        if full and not factorise(n, m, c, n1, Fx, Fu, matrix_at(daddr[t, 2], n, n), matrix_at(daddr[t, 3], n, m),
                                  matrix_at(daddr[t, 4], m, m), C[t], D[t], rho[t], with_rows, sigma, mu,
                                  P[t + 1], P[t], K[t], L[t], Qxx, Qxu, Quu, W, Wu, idx):
            return t
        if m > 0:
            for i in range(m):  # k = Quu⁻¹ Qu with the factor L (L then Lᵀ; its diagonal inverted)
                acc = Qu[i]
                for q in range(i):
                    acc -= L[t, i, q] * k[t, q]
                k[t, i] = acc * L[t, i, i]
            for i in range(m - 1, -1, -1):
                acc = k[t, i]
                for q in range(i + 1, m):
                    acc -= L[t, q, i] * k[t, q]
                k[t, i] = acc * L[t, i, i]
            i = 0
            while i + 4 <= n:
                a0, a1, a2, a3 = Qx[i], Qx[i + 1], Qx[i + 2], Qx[i + 3]
                for q in range(m):
                    a_ = -Qu[q]
                    a0 += K[t, q, i] * a_
                    a1 += K[t, q, i + 1] * a_
                    a2 += K[t, q, i + 2] * a_
                    a3 += K[t, q, i + 3] * a_
                Qx[i], Qx[i + 1], Qx[i + 2], Qx[i + 3] = a0, a1, a2, a3
                i += 4
            while i < n:
                a0 = Qx[i]
                for q in range(m):
                    a0 += K[t, q, i] * -Qu[q]
                Qx[i] = a0
                i += 1
        for i in range(n):
            p[t, i] = Qx[i]
    return -1


riccati = compiled(_riccati)


def _rollout(dims, daddr, haddr, fs_col, K, k, dx, du):
    """``δx_0 = d_0``, ``δu_t = -k_t - K_t δx_t``, ``δx_{t+1} = Fu δu_t + Fx δx_t + d_{t+1}``: rows four at a time
    (independent sums, each in the order of one row's), the last ones one by one."""
    N = dims.shape[0] - 1
    d0 = vector_at(haddr[0, fs_col], dims[0, 0])
    for i in range(dims[0, 0]):
        dx[0, i] = d0[i]
    for t in range(N):
        n, m, n1 = dims[t, 0], dims[t, 1], dims[t + 1, 0]
        Fx, Fu = matrix_at(daddr[t, 0], n1, n), matrix_at(daddr[t, 1], n1, m)
        d1 = vector_at(haddr[t + 1, fs_col], n1)
        i = 0
        while i + 4 <= m:
            a0, a1, a2, a3 = -k[t, i], -k[t, i + 1], -k[t, i + 2], -k[t, i + 3]
            for j in range(n):
                x = dx[t, j]
                a0 -= K[t, i, j] * x
                a1 -= K[t, i + 1, j] * x
                a2 -= K[t, i + 2, j] * x
                a3 -= K[t, i + 3, j] * x
            du[t, i], du[t, i + 1], du[t, i + 2], du[t, i + 3] = a0, a1, a2, a3
            i += 4
        while i < m:
            acc = -k[t, i]
            for j in range(n):
                acc -= K[t, i, j] * dx[t, j]
            du[t, i] = acc
            i += 1
        i = 0
        while i + 4 <= n1:
            a0 = a1 = a2 = a3 = b0 = b1 = b2 = b3 = 0.0
            for j in range(m):
                x = du[t, j]
                a0 += Fu[i, j] * x
                a1 += Fu[i + 1, j] * x
                a2 += Fu[i + 2, j] * x
                a3 += Fu[i + 3, j] * x
            for j in range(n):
                x = dx[t, j]
                b0 += Fx[i, j] * x
                b1 += Fx[i + 1, j] * x
                b2 += Fx[i + 2, j] * x
                b3 += Fx[i + 3, j] * x
            dx[t + 1, i], dx[t + 1, i + 1] = a0 + b0 + d1[i], a1 + b1 + d1[i + 1]
            dx[t + 1, i + 2], dx[t + 1, i + 3] = a2 + b2 + d1[i + 2], a3 + b3 + d1[i + 3]
            i += 4
        while i < n1:
            acc = 0.0
            for j in range(m):
                acc += Fu[i, j] * du[t, j]
            acc2 = 0.0
            for j in range(n):
                acc2 += Fx[i, j] * dx[t, j]
            dx[t + 1, i] = acc + acc2 + d1[i]
            i += 1


rollout = compiled(_rollout)


def _transpose_max(C, D, t, rows, n, m, v, w, best, spans):
    """``max(best, ‖C_tᵀ v‖∞, ‖D_tᵀ v‖∞)`` over ``rows`` rows (``D`` skipped when ``m = 0``; ``w``: scratch)."""
    for i in range(n):
        w[i] = 0.0
    for r in range(rows):
        a = v[r]
        for i in range(spans[t, r, 0], spans[t, r, 1]):
            w[i] += C[t, r, i] * a
    for i in range(n):
        best = max(best, abs(w[i]))
    if m > 0:
        for i in range(m):
            w[i] = 0.0
        for r in range(rows):
            a = v[r]
            for i in range(spans[t, r, 2], spans[t, r, 3]):
                w[i] += D[t, r, i] * a
        for i in range(m):
            best = max(best, abs(w[i]))
    return best


transpose_max = compiled(_transpose_max)


def _update(dims, C, D, lo, hi, z, y, rho, dx, du, alpha, check, heuristic, v, w, out, spans):
    """Projection and dual ascent of every row (``z``, ``y``); if ``check``, ``out[:4] = (r_p, r_d, s_p, s_d)``
    (``v``, ``w``: scratch; the rows' products over their nonzero ``spans``)."""
    N = dims.shape[0] - 1
    r_p = r_d = s_p = s_d = -np.inf
    for t in range(N + 1):
        n, m, c = dims[t, 0], dims[t, 1], dims[t, 2]
        if c == 0:
            continue
        for r in range(c):
            acc = 0.0
            for j in range(spans[t, r, 0], spans[t, r, 1]):
                acc += C[t, r, j] * dx[t, j]
            if t < N:
                for j in range(spans[t, r, 2], spans[t, r, 3]):
                    acc += D[t, r, j] * du[t, j]
            v[r] = acc
        for r in range(c):
            z_hat = alpha * v[r] + (1.0 - alpha) * z[t, r]
            z_new = min(max(z_hat + y[t, r] / rho[t, r], lo[t, r]), hi[t, r])
            y[t, r] += rho[t, r] * (z_hat - z_new)
            dz = rho[t, r] * (z_new - z[t, r])
            z[t, r] = z_new
            if check:
                r_p = max(r_p, abs(v[r] - z_new))
                s_p = max(s_p, abs(v[r]), abs(z_new))
                if heuristic:
                    r_d = max(r_d, abs(dz))
                    s_d = max(s_d, abs(y[t, r]))
            v[r] = dz
        if check and not heuristic:
            r_d = transpose_max(C, D, t, c, n, m if t < N else 0, v, w, r_d, spans)
            s_d = transpose_max(C, D, t, c, n, m if t < N else 0, y[t], w, s_d, spans)
    if check:
        out[0], out[1], out[2], out[3] = r_p, r_d, s_p, s_d


update = compiled(_update)


def _rho_estimate(rho_bar, r_p, r_d, s_p, s_d):
    """``ρ̄ √(r_p s_d / (r_d s_p))`` with numpy's rules for a zero divisor (NaN when undefined)."""
    num, den = r_p * s_d, r_d * s_p
    if den == 0.0:
        q = np.nan if num == 0.0 or num != num else (np.inf if num > 0.0 else -np.inf)
    else:
        q = num / den
    if q != q or q < 0.0:
        return np.nan
    return rho_bar * np.sqrt(q)


rho_estimate = compiled(_rho_estimate)


def _admm_run(dims, daddr, haddr, fs_col, LxT, LxxT, kind, C, D, lo, hi, z, y, rho, eta, dx, du, dx_bar, du_bar, P, p,
              Pd, K, k, L, par, ipar, out):
    sigma, mu, alpha, rho_min, rho_max, tol, eps_abs, eps_rel, rho_bar = (par[0], par[1], par[2], par[3], par[4],
                                                                        par[5], par[6], par[7], par[8])
    j0, j1, interval, heuristic, anchor = ipar[0], ipar[1], ipar[2], ipar[3] != 0, ipar[4] != 0
    current = ipar[5] != 0 and not anchor
    nmax, mmax, cmax = P.shape[1], K.shape[1], C.shape[1]
    w = max(nmax, mmax, 1)
    S = np.zeros((5, w, w))
    Sv = np.zeros((3, w))
    v = np.zeros(max(cmax, 1))
    wv = np.zeros(w)
    idx = np.arange(max(mmax, 1))
    N = dims.shape[0] - 1
    spans = np.zeros((N + 1, max(cmax, 1), 4), dtype=np.int64)
    row_spans(dims, C, D, spans)
    if anchor:
        t = riccati(dims, daddr, haddr, fs_col, LxT, LxxT, 0.0, mu, False, True, C, D, rho, eta, dx_bar, du_bar, P, p,
                    Pd, K, k, L, S, Sv, idx, spans)
        out[5] = 0.0
        if t >= 0:
            return -(t + 1)
        rollout(dims, daddr, haddr, fs_col, K, k, dx, du)
        dx_bar[:, :] = dx
        du_bar[:, :] = du
    for j in range(j0, j1):
        for t in range(N + 1):
            for r in range(dims[t, 2]):
                eta[t, r] = y[t, r] - rho[t, r] * z[t, r]
        full = (interval == 1 or j % interval == 1) and not current
        t = riccati(dims, daddr, haddr, fs_col, LxT, LxxT, sigma, mu, True, full, C, D, rho, eta, dx_bar, du_bar, P,
                    p, Pd, K, k, L, S, Sv, idx, spans)
        if t >= 0:
            out[5] = 0.0
            return -(t + 1)
        current = True
        out[5] = 1.0
        rollout(dims, daddr, haddr, fs_col, K, k, dx, du)
        check = j % interval == 0
        update(dims, C, D, lo, hi, z, y, rho, dx, du, alpha, check, heuristic, v, wv, out, spans)
        dx_bar[:, :] = dx
        du_bar[:, :] = du
        if not check:
            continue
        estimate = rho_estimate(rho_bar, out[0], out[1], out[2], out[3])
        if estimate == estimate:
            estimate = min(max(estimate, rho_min), rho_max)
            if estimate > tol * rho_bar or estimate < rho_bar / tol:
                rho_bar = estimate
                out[4] = rho_bar
                assign_rho(dims, kind, rho, rho_bar, rho_min)
                current = False
                out[5] = 0.0
        if abs(eps_rel) <= np.finfo(np.float64).eps:
            eps_p = eps_d = eps_abs
        else:
            eps_p, eps_d = eps_abs + eps_rel * out[2], eps_abs + eps_rel * out[3]
        if out[0] <= eps_p and out[1] <= eps_d:
            return j
    return 0


admm_run = compiled(_admm_run)


def _multipliers(dims, P, p, dx, lam):
    """``λ_t = p_t + P_t δx_t`` into ``lam (N+1, n)``."""
    for t in range(dims.shape[0]):
        n = dims[t, 0]
        for i in range(n):
            acc = 0.0
            for j in range(n):
                acc += P[t, i, j] * dx[t, j]
            lam[t, i] = p[t, i] + acc


multipliers = compiled(_multipliers)


def _node_rows(dims, ngh, saddr, lb, ub, load, C, D, lo, hi, out):
    """Each node's rows from its constraint arrays at ``saddr[t] = (g, h, Gx, Gu, Hx, Hu)`` (``ngh[t] = (ng, nh)``
    rows of each), ``c = (g, h)``: if ``load``, ``lo = lb - c``, ``hi = ub - c``, ``C = (Gx; Hx)``,
    ``D = (Gu; Hu)``.  ``out = (Ψ, ‖v‖∞, ‖v‖₁)`` with ``Ψ = Σ max(lb - c, 0) + max(c - ub, 0)`` over all rows and
    ``v = max(lb - g, 0, g - ub)`` over the inequality rows."""
    N = dims.shape[0] - 1
    psi = 0.0
    vinf = 0.0
    v1 = 0.0
    for t in range(N + 1):
        n, m, nc = dims[t, 0], dims[t, 1], dims[t, 2]
        if nc == 0:
            continue
        ng, nh = ngh[t, 0], ngh[t, 1]
        a = saddr[t]
        g, h = vector_at(a[0], ng), vector_at(a[1], nh)
        for r in range(nc):
            c = g[r] if r < ng else h[r - ng]
            below, above = lb[t, r] - c, c - ub[t, r]
            if load:
                lo[t, r], hi[t, r] = below, -above
            worst = max(max(below, 0.0), above)
            psi += max(below, 0.0) + max(above, 0.0)
            if r < ng:
                vinf = max(vinf, abs(worst))
                v1 += abs(worst)
        if load:
            if ng:
                copy_rows(C, t, 0, matrix_at(a[2], ng, n))
                if t < N:
                    copy_rows(D, t, 0, matrix_at(a[3], ng, m))
            if nh:
                copy_rows(C, t, ng, matrix_at(a[4], nh, n))
                if t < N:
                    copy_rows(D, t, ng, matrix_at(a[5], nh, m))
    out[0], out[1], out[2] = psi, vinf, v1


def _copy_rows(S, t, first, M):
    """``S[t, first:first + rows, :cols] = M`` in loops (no views)."""
    for r in range(M.shape[0]):
        for c in range(M.shape[1]):
            S[t, first + r, c] = M[r, c]


copy_rows = compiled(_copy_rows)
node_rows = compiled(_node_rows)
