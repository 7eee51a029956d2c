"""Linearised contact cones: ``lb <= A f <= ub``.

- :class:`FrictionCone`: ``nf`` facets ``(cos θᵢ, sin θᵢ, -μ')`` and ``-(cos θᵢ, sin θᵢ, μ')``
  (``θᵢ = 2π i / nf``, ``i < nf/2``) with upper bound 0, then the normal-force row ``(0, 0, 1)``
  bounded by ``[min_nforce, max_nforce]``.  ``μ' = μ cos(π/nf)`` for the inner approximation, ``μ``
  otherwise.  ``A = A_local Rᵀ`` (``R`` orients the cone: its z axis is the contact normal).
- :class:`CoPSupport`: the centre of pressure of a wrench stays in the ``box = (length, width)``
  rectangle: ``±τx <= (width/2) fz``, ``±τy <= (length/2) fz`` (4 rows, upper bound 0).
- :class:`WrenchCone`: the friction facets, the normal-force row, the 4 CoP rows and 8 yaw-torque
  rows (``nf + 13`` rows) on the 6D wrench ``(f, τ)``; ``A = A_local diag(Rᵀ, Rᵀ)``.
"""

from __future__ import annotations

import numpy as np

from crocopy.validation import as_bool, as_count, as_number, as_rotation, as_vector


def _check_rotation(R: np.ndarray) -> np.ndarray:
    return as_rotation(R, "R")


def _check_box(box: np.ndarray, allow_inf: bool = False) -> np.ndarray:
    box = as_vector(box, 2, "box (length, width)", allow_nonfinite=allow_inf)
    if np.any(np.isnan(box)) or np.any(box < 0.0):
        raise ValueError(f"box (length, width) must be non-negative, got {box}")
    return box


def _check_facet_parameters(cone: "FrictionCone | WrenchCone") -> None:
    """Check and convert ``cone.mu``, ``cone.nf`` and ``cone.inner_appr`` in place."""
    cone.mu, cone.nf = as_number(cone.mu, "mu"), as_count(cone.nf, "nf")
    cone.inner_appr = as_bool(cone.inner_appr, "inner_appr")


def _facets(nf: int, mu: float, inner_appr: bool) -> tuple[np.ndarray, float]:
    if nf < 2 or nf % 2:
        raise ValueError(f"nf must be an even number >= 2, got {nf}")
    if not mu > 0.0:
        raise ValueError(f"mu must be positive, got {mu}")
    mu_f = mu * np.cos(np.pi / nf) if inner_appr else mu
    A = np.zeros((nf, 3))
    for i in range(nf // 2):
        th = 2.0 * np.pi * i / nf
        A[2 * i] = (np.cos(th), np.sin(th), -mu_f)
        A[2 * i + 1] = (-np.cos(th), -np.sin(th), -mu_f)
    return A, mu_f


def _check_nforce(min_nforce: float, max_nforce: float) -> tuple[float, float]:
    min_nforce = as_number(min_nforce, "min_nforce", 0.0)
    max_nforce = as_number(max_nforce, "max_nforce", allow_inf=True)
    if max_nforce < min_nforce:
        raise ValueError(f"need 0 <= min_nforce <= max_nforce, got {min_nforce}, {max_nforce}")
    return min_nforce, max_nforce


class FrictionCone:
    """Crocoddyl's ``FrictionCone(R, mu, nf=4, inner_appr=True, min_nforce=0., max_nforce=inf)``.

    Attributes ``A (nf+1, 3)``, ``lb``, ``ub`` (``nf+1``); call :meth:`update` after changing
    ``R``, ``mu``, ``nf``, ``inner_appr``, ``min_nforce`` or ``max_nforce``.
    """

    def __init__(
        self,
        R: np.ndarray | None = None,
        mu: float = 0.7,
        nf: int = 4,
        inner_appr: bool = True,
        min_nforce: float = 0.0,
        max_nforce: float = np.inf,
    ) -> None:
        self.R = np.eye(3) if R is None else R
        self.mu, self.nf, self.inner_appr = mu, nf, inner_appr
        self.min_nforce, self.max_nforce = min_nforce, max_nforce
        self.update()

    def update(self) -> None:
        """Recompute ``A``, ``lb`` and ``ub`` from the cone parameters."""
        self.R = _check_rotation(self.R)
        self.min_nforce, self.max_nforce = _check_nforce(self.min_nforce, self.max_nforce)
        _check_facet_parameters(self)
        F, _ = _facets(self.nf, self.mu, self.inner_appr)
        self.A = np.vstack([F, [0.0, 0.0, 1.0]]) @ self.R.T
        self.lb = np.r_[np.full(self.nf, -np.inf), self.min_nforce]
        self.ub = np.r_[np.zeros(self.nf), self.max_nforce]

    def __repr__(self) -> str:
        return f"FrictionCone(mu={self.mu}, nf={self.nf}, inner_appr={self.inner_appr})"


def _cop_rows(box: np.ndarray) -> np.ndarray:
    X, Y = 0.5 * box[0], 0.5 * box[1]
    return np.array(
        [
            [0.0, 0.0, -Y, 1.0, 0.0, 0.0],
            [0.0, 0.0, -Y, -1.0, 0.0, 0.0],
            [0.0, 0.0, -X, 0.0, 1.0, 0.0],
            [0.0, 0.0, -X, 0.0, -1.0, 0.0],
        ]
    )


class CoPSupport:
    """Crocoddyl's ``CoPSupport(R, box)``: ``A (4, 6)``, ``lb = -inf``, ``ub = 0``; ``box = (length, width)``.

    ``CoPSupport()`` is Crocoddyl's default: ``R = I`` and an unbounded box (its force columns of
    ``A`` are then not finite).  Call :meth:`update` after changing ``R`` or ``box``.
    """

    def __init__(self, R: np.ndarray | None = None, box: np.ndarray | None = None) -> None:
        self.R = np.eye(3) if R is None else R
        self.box = np.array([np.inf, np.inf]) if box is None else box
        self.update()

    def update(self) -> None:
        """Recompute ``A``, ``lb`` and ``ub``."""
        self.R = _check_rotation(self.R)
        self.box = _check_box(self.box, allow_inf=True)  # Crocoddyl's default: unbounded
        rows = _cop_rows(self.box)
        self.A = np.zeros((4, 6))
        with np.errstate(invalid="ignore"):
            self.A[:, :3] = rows[:, :3] @ self.R.T
        self.A[:, 3:] = rows[:, 3:] @ self.R.T
        self.lb = np.full(4, -np.inf)
        self.ub = np.zeros(4)

    def __repr__(self) -> str:
        return f"CoPSupport(box={self.box})"


class WrenchCone:
    """Crocoddyl's ``WrenchCone(R, mu, box, nf=4, inner_appr=True, min_nforce=0., max_nforce=inf)``.

    ``A (nf+13, 6)``, ``lb``, ``ub``; ``box = (length, width)`` of the contact surface.
    ``WrenchCone()`` is Crocoddyl's default: ``R = I``, ``mu = 0.7`` and an unbounded box (the CoP and
    yaw rows of ``A`` are then not finite, as in Crocoddyl).  Call :meth:`update` after changing a parameter.
    """

    def __init__(
        self,
        R: np.ndarray | None = None,
        mu: float = 0.7,
        box: np.ndarray | None = None,
        nf: int = 4,
        inner_appr: bool = True,
        min_nforce: float = 0.0,
        max_nforce: float = np.inf,
    ) -> None:
        self.R = np.eye(3) if R is None else R
        self.mu, self.nf, self.inner_appr = mu, nf, inner_appr
        self.box = np.array([np.inf, np.inf]) if box is None else box
        self.min_nforce, self.max_nforce = min_nforce, max_nforce
        self.update()

    def update(self) -> None:
        """Recompute ``A``, ``lb`` and ``ub``."""
        self.R = _check_rotation(self.R)
        self.box = _check_box(self.box, allow_inf=True)  # Crocoddyl's default: unbounded
        self.min_nforce, self.max_nforce = _check_nforce(self.min_nforce, self.max_nforce)
        _check_facet_parameters(self)
        F, m = _facets(self.nf, self.mu, self.inner_appr)
        X, Y = 0.5 * self.box[0], 0.5 * self.box[1]
        s = -(X + Y) * m
        yaw = np.array(
            [
                [Y, X, s, -m, -m, -1.0],
                [Y, -X, s, -m, m, -1.0],
                [-Y, X, s, m, -m, -1.0],
                [-Y, -X, s, m, m, -1.0],
                [Y, X, s, m, m, 1.0],
                [Y, -X, s, m, -m, 1.0],
                [-Y, X, s, -m, m, 1.0],
                [-Y, -X, s, -m, -m, 1.0],
            ]
        )
        normal = [[0.0, 0.0, 1.0, 0.0, 0.0, 0.0]]
        A = np.vstack([np.hstack([F, np.zeros((self.nf, 3))]), normal, _cop_rows(self.box), yaw])
        with np.errstate(invalid="ignore"):
            self.A = A @ np.kron(np.eye(2), self.R).T
        n = self.nf + 13
        self.lb = np.full(n, -np.inf)
        self.ub = np.zeros(n)
        self.lb[self.nf] = self.min_nforce
        self.ub[self.nf] = self.max_nforce

    def __repr__(self) -> str:
        return f"WrenchCone(mu={self.mu}, box={self.box}, nf={self.nf}, inner_appr={self.inner_appr})"
