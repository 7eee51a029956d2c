"""Smooth norm activations.

* Smooth1Norm: ``a = Σ sqrt(ε + rᵢ²)``.
* Smooth2Norm: ``a = sqrt(ε + ‖r‖²)`` (dense Hessian ``I/a - r rᵀ/a³``).
* 2NormBarrier: ``a = ½ (‖r‖ - α)²`` if ``‖r‖ < α`` else 0; Gauss-Newton Hessian
  ``r rᵀ/‖r‖²`` unless ``true_hessian``.
"""

from __future__ import annotations

import numpy as np

from .base import ActivationDataAbstract, ActivationModelAbstract


class ActivationModelSmooth1Norm(ActivationModelAbstract):
    """``a(r) = Σ sqrt(eps + rᵢ²)``."""

    diagonal = True

    def __init__(self, nr: int, eps: float = 1.0) -> None:
        if eps < 0:
            raise ValueError(f"eps must be non-negative, got {eps}")
        super().__init__(nr)
        self.eps = float(eps)

    def calc(self, data: ActivationDataAbstract, r: np.ndarray) -> None:
        data.a_value = float(np.sum(np.sqrt(self.eps + r * r)))

    def calcDiff(self, data: ActivationDataAbstract, r: np.ndarray) -> None:
        s = np.sqrt(self.eps + r * r)
        data.Ar[:] = r / s
        data.Arr_diag[:] = self.eps / (s * s * s)


class ActivationModelSmooth2Norm(ActivationModelAbstract):
    """``a(r) = sqrt(eps + ‖r‖²)``."""

    def __init__(self, nr: int, eps: float = 1.0) -> None:
        if eps < 0:
            raise ValueError(f"eps must be non-negative, got {eps}")
        super().__init__(nr)
        self.eps = float(eps)

    def calc(self, data: ActivationDataAbstract, r: np.ndarray) -> None:
        data.a_value = float(np.sqrt(self.eps + r @ r))

    def calcDiff(self, data: ActivationDataAbstract, r: np.ndarray) -> None:
        a = np.sqrt(self.eps + r @ r)
        data.Ar[:] = r / a
        data.Arr = np.eye(self.nr) / a - np.outer(r, r) / a**3


class ActivationModel2NormBarrier(ActivationModelAbstract):
    """``a(r) = ½ (‖r‖ - alpha)²`` inside the ball of radius ``alpha``, zero outside."""

    def __init__(self, nr: int, alpha: float = 0.1, true_hessian: bool = False) -> None:
        if alpha < 0:
            raise ValueError(f"alpha must be non-negative, got {alpha}")
        super().__init__(nr)
        self.alpha = float(alpha)
        self.true_hessian = bool(true_hessian)

    def calc(self, data: ActivationDataAbstract, r: np.ndarray) -> None:
        n = np.linalg.norm(r)
        data.a_value = 0.5 * (n - self.alpha) ** 2 if n < self.alpha else 0.0

    def calcDiff(self, data: ActivationDataAbstract, r: np.ndarray) -> None:
        n = np.linalg.norm(r)
        if n >= self.alpha or n == 0.0:
            data.Ar[:] = 0.0
            data.Arr = np.zeros((self.nr, self.nr))
            return
        data.Ar[:] = (n - self.alpha) / n * r
        rr = np.outer(r, r) / (n * n)
        if self.true_hessian:
            data.Arr = rr + (n - self.alpha) / n * (np.eye(self.nr) - rr)
        else:
            data.Arr = rr
