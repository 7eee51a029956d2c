"""Householder reflections for the compiled passes: LAPACK's steps, written as loops on small dense arrays.

:func:`householder_column` is ``dlarfg`` (the reflector ``H = I - τ v vᵀ`` with ``v[0] = 1`` that maps a column to
``β e₀``, ``v`` stored below ``β``), :func:`apply_householder` applies it to columns of another array,
:func:`pivoted_qr` is the column-pivoted QR of ``dgeqp3`` (unblocked ``dlaqp2``) with ``Q`` formed as ``dorgqr``
does, and :func:`least_squares` solves a full-column-rank system in the least-squares sense by the same reflectors.
Every function works in place on the caller's scratch and allocates nothing.
"""

from __future__ import annotations

import numpy as np

from ..kernels import uncounted


def _householder_column(A, j, lo):
    """LAPACK's ``dlarfg`` on ``A[lo:, j]``: ``A[lo, j] ← β``, ``A[lo+1:, j] ← v[1:]`` (``v[0] = 1``); returns ``τ``
    (``H = I - τ v vᵀ``, ``H A[lo:, j] = β e₀``)."""
    m = A.shape[0]
    alpha = A[lo, j]
    s = 0.0
    for i in range(lo + 1, m):
        s += A[i, j] * A[i, j]
    if s == 0.0:
        return 0.0
    beta = -np.copysign(np.hypot(alpha, np.sqrt(s)), alpha)
    scale = 1.0 / (alpha - beta)
    for i in range(lo + 1, m):
        A[i, j] *= scale
    A[lo, j] = beta
    return (beta - alpha) / beta


def _apply_householder(A, j, lo, tau, C, c0, c1):
    """``C[lo:, c0:c1] ← H C[lo:, c0:c1]`` with the reflector of :func:`householder_column` stored in ``A[lo:, j]``."""
    if tau == 0.0:
        return
    m = A.shape[0]
    for c in range(c0, c1):
        w = C[lo, c]
        for i in range(lo + 1, m):
            w += A[i, j] * C[i, c]
        w *= tau
        C[lo, c] -= w
        for i in range(lo + 1, m):
            C[i, c] -= w * A[i, j]


householder_column = uncounted(_householder_column)
apply_householder = uncounted(_apply_householder)


def _column_norm(A, j, lo):
    s = 0.0
    for i in range(lo, A.shape[0]):
        s += A[i, j] * A[i, j]
    return np.sqrt(s)


column_norm = uncounted(_column_norm)


def _pivoted_qr(A, Q, tau, vn1, vn2):
    """Column-pivoted Householder QR of ``A`` (``(m, n)``, in place: ``R`` on and above the diagonal, the
    reflectors below), as LAPACK's ``dgeqp3`` (unblocked, ``dlaqp2``: the largest partial column norm first,
    norms downdated and recomputed on cancellation), and ``Q = H₀ H₁ ⋯ H_{k-1}`` (``(m, m)``, ``k = min(m, n)``)
    as ``dorgqr``."""
    m, n = A.shape
    kmax = min(m, n)
    tol3z = np.sqrt(np.finfo(np.float64).eps)
    for j in range(n):
        vn1[j] = column_norm(A, j, 0)
        vn2[j] = vn1[j]
    for i in range(kmax):
        pvt = i
        for j in range(i + 1, n):
            if vn1[j] > vn1[pvt]:
                pvt = j
        if pvt != i:
            for r in range(m):
                A[r, i], A[r, pvt] = A[r, pvt], A[r, i]
            vn1[pvt] = vn1[i]
            vn2[pvt] = vn2[i]
        tau[i] = householder_column(A, i, i)
        apply_householder(A, i, i, tau[i], A, i + 1, n)
        for j in range(i + 1, n):
            if vn1[j] != 0.0:
                temp = abs(A[i, j]) / vn1[j]
                temp = max(1.0 - temp * temp, 0.0)
                ratio = vn1[j] / vn2[j]
                if temp * ratio * ratio <= tol3z:
                    if i < m - 1:
                        vn1[j] = column_norm(A, j, i + 1)
                        vn2[j] = vn1[j]
                    else:
                        vn1[j] = 0.0
                        vn2[j] = 0.0
                else:
                    vn1[j] *= np.sqrt(temp)
    for i in range(m):
        for j in range(m):
            Q[i, j] = 1.0 if i == j else 0.0
    for i in range(kmax - 1, -1, -1):
        apply_householder(A, i, i, tau[i], Q, i, m)


pivoted_qr = uncounted(_pivoted_qr)


def _least_squares(Hy, h, Hx, A, B, ks, Ks):
    """``ks = Hy⁺ h``, ``Ks = Hy⁺ Hx`` (``Hy`` of full column rank) by Householder QR (scratch ``A`` of ``Hy``'s
    shape, ``B (p, 1 + ndx)``)."""
    p, r = Hy.shape
    n = Hx.shape[1]
    for i in range(p):
        for j in range(r):
            A[i, j] = Hy[i, j]
        B[i, 0] = h[i]
        for j in range(n):
            B[i, 1 + j] = Hx[i, j]
    for j in range(r):
        tau = householder_column(A, j, j)
        apply_householder(A, j, j, tau, A, j + 1, r)
        apply_householder(A, j, j, tau, B, 0, n + 1)
    for c in range(n + 1):
        for i in range(r - 1, -1, -1):
            acc = B[i, c]
            for j in range(i + 1, r):
                acc -= A[i, j] * B[j, c]
            B[i, c] = acc / A[i, i]
    for i in range(r):
        ks[i] = B[i, 0]
        for j in range(n):
            Ks[i, j] = B[i, 1 + j]


least_squares = uncounted(_least_squares)
