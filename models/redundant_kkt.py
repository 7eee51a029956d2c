"""KKT solve of contact and impulse dynamics whose stacked Jacobian is rank-deficient (redundant contacts).

The contact dynamics (``r = τ - b``, ``c = a0``) and the impulse dynamics (``r = M v⁻``,
``c = e Jc v⁻``) solve, with ``M`` (nv, nv) positive definite and ``J`` (nc, nv)::

    [M  Jᵀ] [ y ]   [ r ]
    [J  0 ] [-λ ] = [-c ],       S = J M⁻¹ Jᵀ  (nc, nc).

When ``J`` has dependent rows (the same contact twice, a 3D and a 6D contact on one frame, three
point contacts on one body, a kinematic singularity) ``S`` is singular and the KKT matrix has no
inverse.  The rows stay consistent (``c`` lies in the range of ``J``), so ``y`` is still unique
(Gauss' principle: the closest acceleration to the free one that meets the constraints) while ``λ``
is not; this module returns the minimum-norm ``λ``, which shares a redundant force equally::

    λ = -S⁺ (J M⁻¹ r + c),    y = M⁻¹ (r + Jᵀ λ),

with ``S⁺`` the pseudo-inverse from the eigen-decomposition of ``S`` (eigenvalues below
``rtol · max eigenvalue`` dropped).  The same blocks, written into ``Kinv``,

    Kinv = [[M⁻¹ - M⁻¹Jᵀ S⁺ J M⁻¹,  M⁻¹Jᵀ S⁺], [S⁺ J M⁻¹,  -S⁺]],

map any consistent right-hand side to a solution of the KKT system, so the derivatives of ``y``
(and of ``λ``, whose redundant directions are constant) follow from ``Kinv`` exactly as from the
inverse of a regular KKT matrix.  With independent rows ``S⁺ = S⁻¹`` and all of this is the usual
KKT inverse.  Rows that are dependent *and* contradict each other (a 6D and a 3D contact on one
frame while it moves: the 6D drift is a spatial acceleration, the 3D one a classical acceleration)
get the minimum-norm least-squares multipliers of ``S λ = -(J M⁻¹ r + c)`` (a compromise).
Cost: one Cholesky of ``M`` and one ``nc × nc`` eigen-decomposition.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg

RTOL = 1e-9
"""Eigenvalues of ``S`` below ``RTOL`` times its largest are treated as zero (redundant directions)."""


def solve_redundant_kkt(M: np.ndarray, r: np.ndarray, J: np.ndarray, c: np.ndarray, Kinv: np.ndarray,
                        rtol: float = RTOL) -> tuple[np.ndarray, np.ndarray]:
    """Minimum-norm-multiplier solution of the KKT system above; writes ``Kinv`` (nv+nc, nv+nc).

    Parameters
    ----------
    M : ndarray (nv, nv)
        Inertia matrix (only its upper triangle is read, as Pinocchio fills it).
    r : ndarray (nv,)
        First block of the right-hand side.
    J : ndarray (nc, nv)
        Stacked contact Jacobian (rank-deficient or not).
    c : ndarray (nc,)
        Constraint drift (the second block is ``-c``).
    Kinv : ndarray (nv+nc, nv+nc)
        Output: the solution operator described in the module docstring.

    Returns
    -------
    y, lam : ndarray (nv,), ndarray (nc,)
        The unique ``y`` and the minimum-norm multipliers.
    """
    nv = M.shape[0]
    chol = scipy.linalg.cho_factor(np.triu(M), lower=False, check_finite=False)
    MinvJt = scipy.linalg.cho_solve(chol, J.T, check_finite=False)
    Minv_r = scipy.linalg.cho_solve(chol, r, check_finite=False)
    S = J @ MinvJt
    w, V = np.linalg.eigh(0.5 * (S + S.T))
    keep = w > rtol * max(float(w[-1]) if w.size else 0.0, np.finfo(float).tiny)
    Vk = V[:, keep]
    S_pinv = (Vk / w[keep]) @ Vk.T
    lam = -S_pinv @ (J @ Minv_r + c)
    y = Minv_r + MinvJt @ lam
    B = MinvJt @ S_pinv
    Kinv[:nv, :nv] = scipy.linalg.cho_solve(chol, np.eye(nv), check_finite=False) - B @ MinvJt.T
    Kinv[:nv, nv:] = B
    Kinv[nv:, :nv] = B.T
    Kinv[nv:, nv:] = -S_pinv
    return y, lam
