"""SolverIntro's fully pivoted LU in one compiled call: ``P A Q = L U``, the largest remaining entry first.

The factor is written in place into ``U`` (a copy of ``A``, ``(m, n)``), the permutations into ``rows`` (``m``)
and ``cols`` (``n``): ``A[rows][:, cols] = L U`` with ``L``'s multipliers below ``U``'s diagonal.  The
elimination stops at the first pivot below ``rtol`` times the first one (or zero); the number of pivots taken
is returned.  Each step is the numpy twin's (:func:`crocopy.solvers.intro.full_pivot_lu`): the same pivot
(the first largest ``|U[i, j]|`` in column-major order, the first NaN if there is one) and the same operations
in the same order, so both give the same numbers.
"""

from __future__ import annotations

from ..kernels import uncounted


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
