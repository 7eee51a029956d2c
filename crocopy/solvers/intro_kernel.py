"""SolverIntro's bases ``[Y Z]`` of ``Hu``'s row space and nullspace, compiled: by fully pivoted LU or by the
column-pivoted QR of ``Huᵀ`` (:func:`~.householder_kernel.pivoted_qr`).

:func:`full_pivot_lu_kernel` is ``P A Q = L U``, the largest remaining entry first.

The factor is written in place into ``U`` (a copy of ``A``, ``(m, n)``), the permutations into ``rows`` (``m``)
and ``cols`` (``n``): ``A[rows][:, cols] = L U`` with ``L``'s multipliers below ``U``'s diagonal.  The
elimination stops at the first pivot below ``rtol`` times the first one (or zero); the number of pivots taken
is returned.  Each step is the numpy twin's (:func:`crocopy.solvers.intro.full_pivot_lu`): the same pivot
(the first largest ``|U[i, j]|`` in column-major order, the first NaN if there is one) and the same operations
in the same order, so both give the same numbers.  :func:`lu_basis` and :func:`qr_basis` write ``[Y Z]``
(``(nu, nu)``: ``Y`` the first ``r`` columns, spanning ``Hu``'s row space, ``Z`` the nullspace) and return the rank
``r``, as the twin's ``lu_range_kernel``/``qr_range_kernel`` of :mod:`.intro`.
"""

from __future__ import annotations

from ..kernels import uncounted
from .householder_kernel import pivoted_qr


@uncounted
def full_pivot_lu_kernel(U, rows, cols, rtol):
    """Factor ``U`` in place (see the module docstring); returns the rank."""
    m, n = U.shape
    rank = 0
    first = 0.0
    for k in range(min(m, n)):
        pivot, pi, pj = -1.0, k, k
        found_nan = False
        for j in range(k, n):
            for i in range(k, m):
                a = abs(U[i, j])
                if a != a:
                    pivot, pi, pj, found_nan = a, i, j, True
                    break
                if a > pivot:
                    pivot, pi, pj = a, i, j
            if found_nan:
                break
        if k == 0:
            first = pivot
        if pivot <= rtol * first or pivot == 0.0:
            break
        if pi != k:
            for c in range(n):
                U[k, c], U[pi, c] = U[pi, c], U[k, c]
            rows[k], rows[pi] = rows[pi], rows[k]
        if pj != k:
            for r in range(m):
                U[r, k], U[r, pj] = U[r, pj], U[r, k]
            cols[k], cols[pj] = cols[pj], cols[k]
        d = U[k, k]
        for i in range(k + 1, m):
            f = U[i, k] / d
            for c in range(k, n):
                U[i, c] -= f * U[k, c]
            U[i, k] = f
        rank += 1
    return rank


def _lu_basis(Hu, U, rows, cols, rtol, basis):
    """``[Y Z]`` of ``Hu`` by fully pivoted LU (``U``: scratch of ``Hu``'s shape); returns the rank ``r``."""
    p, m = Hu.shape
    for i in range(p):
        rows[i] = i
        for j in range(m):
            U[i, j] = Hu[i, j]
    for j in range(m):
        cols[j] = j
    r = full_pivot_lu_kernel(U, rows, cols, rtol)
    for i in range(m):
        for j in range(r):
            basis[i, j] = Hu[rows[j], i]
        for j in range(r, m):
            basis[i, j] = 0.0
    for c in range(m - r):
        for i in range(r - 1, -1, -1):  # x = U[:r, :r]⁻¹ U[:r, r + c], the column's free part is -x
            acc = U[i, r + c]
            for j in range(i + 1, r):
                acc += U[i, j] * basis[cols[j], r + c]
            basis[cols[i], r + c] = -(acc / U[i, i])
        basis[cols[r + c], r + c] = 1.0
    return r


def _qr_basis(Hu, A, tau, vn1, vn2, rtol, basis):
    """``[Y Z]`` of ``Hu`` by column-pivoted QR of ``Huᵀ`` (``A``: scratch of its shape); returns the rank."""
    p, m = Hu.shape
    for i in range(m):
        for j in range(p):
            A[i, j] = Hu[j, i]
    pivoted_qr(A, basis, tau, vn1, vn2)
    first = abs(A[0, 0])
    r = 0
    if first > 0.0:
        for i in range(min(m, p)):
            if abs(A[i, i]) > rtol * first:
                r += 1
    return r


lu_basis = uncounted(_lu_basis)
qr_basis = uncounted(_qr_basis)
