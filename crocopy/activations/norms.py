"""Smooth norm activations.

* Smooth1Norm: ``a = Σ sqrt(ε + rᵢ²)``.
* Smooth2Norm: ``a = sqrt(ε + ‖r‖²)`` (dense Hessian ``I/a - r rᵀ/a³``).
* 2NormBarrier: ``a = ½ (‖r‖ - α)²`` if ``‖r‖ < α`` else 0; Gauss-Newton Hessian
  ``r rᵀ/‖r‖²`` unless ``true_hessian``.

The smoothing ``ε`` is at least :data:`EPS_MIN`: at ``r = 0`` the Hessian is ``1/√ε`` and a smaller
``ε`` (or 0) overflows it to inf/NaN.
"""

from __future__ import annotations

import numpy as np

from ..validation import as_number
from .base import ActivationDataAbstract, ActivationModelAbstract

EPS_MIN = 1e-200
"""Smallest smoothing ``eps`` of the smooth norms (``eps^1.5`` stays a normal float)."""


class _Smoothing:
    """The smoothing ``eps`` (>= :data:`EPS_MIN`, finite) of a smooth norm, checked on assignment."""

    _eps: float

    @property
    def eps(self) -> float:
        """Smoothing factor."""
        return self._eps

    @eps.setter
    def eps(self, value: float) -> None:
        self._eps = as_number(value, "eps", EPS_MIN)


class ActivationDataSmooth1Norm(ActivationDataAbstract):
    """Data of :class:`ActivationModelSmooth1Norm` (the fields of :class:`ActivationDataAbstract`)."""


class ActivationModelSmooth1Norm(_Smoothing, ActivationModelAbstract):
    """``a(r) = Σ sqrt(eps + rᵢ²)``."""

    diagonal = True

    def __init__(self, nr: int, eps: float = 1.0) -> None:
        super().__init__(nr)
        self.eps = eps

    def createData(self) -> ActivationDataSmooth1Norm:
        return ActivationDataSmooth1Norm(self)

    def item_form(self) -> tuple[str, float]:
        return "smooth1", self._eps

    def calc(self, data: ActivationDataAbstract, r: np.ndarray) -> None:
        data.a_value = float(np.sum(np.sqrt(self.eps + r * r)))

    def calcDiff(self, data: ActivationDataAbstract, r: np.ndarray) -> None:
        s = np.sqrt(self.eps + r * r)
        data.Ar[:] = r / s
        data.Arr_diag[:] = self.eps / (s * s * s)


class ActivationModelSmooth2Norm(_Smoothing, ActivationModelAbstract):
    """``a(r) = sqrt(eps + ‖r‖²)``."""

    def __init__(self, nr: int, eps: float = 1.0) -> None:
        super().__init__(nr)
        self.eps = eps

    def item_form(self) -> tuple[str, float]:
        return "smooth2", self._eps

    def calc(self, data: ActivationDataAbstract, r: np.ndarray) -> None:
        data.a_value = float(np.sqrt(self.eps + r @ r))

    def calcDiff(self, data: ActivationDataAbstract, r: np.ndarray) -> None:
        a = np.sqrt(self.eps + r @ r)
        data.Ar[:] = r / a
        data.Arr = np.eye(self.nr) / a - np.outer(r, r) / a**3


class ActivationModel2NormBarrier(ActivationModelAbstract):
    """``a(r) = ½ (‖r‖ - alpha)²`` inside the ball of radius ``alpha``, zero outside."""

    def __init__(self, nr: int, alpha: float = 0.1, true_hessian: bool = False) -> None:
        super().__init__(nr)
        self.alpha = as_number(alpha, "alpha", 0.0)
        self.true_hessian = bool(true_hessian)

    def item_form(self) -> tuple[str, float]:
        return ("norm_barrier_true" if self.true_hessian else "norm_barrier"), self.alpha

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
