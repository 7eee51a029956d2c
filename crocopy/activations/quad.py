"""Quadratic activations: ``a = ½ rᵀr`` and ``a = ½ rᵀ diag(w) r``."""

from __future__ import annotations

import numpy as np

from ..validation import as_vector
from .base import ActivationDataAbstract, ActivationModelAbstract, ParametersVersion, frozen_copy


class ActivationModelQuad(ActivationModelAbstract):
    """``a(r) = ½‖r‖²``; ``Ar = r``; ``Arr = I``."""

    diagonal = True

    def barrier_form(self) -> tuple:
        return 0.0, 0.0, 1.0

    def calc(self, data: ActivationDataAbstract, r: np.ndarray) -> None:
        data.a_value = 0.5 * float(r @ r)

    def calcDiff(self, data: ActivationDataAbstract, r: np.ndarray) -> None:
        data.Ar[:] = r
        data.Arr_diag[:] = 1.0


class ActivationModelWeightedQuad(ActivationModelAbstract):
    """``a(r) = ½ Σ wᵢ rᵢ²`` with ``weights`` of shape ``(nr,)``."""

    diagonal = True

    def __init__(self, weights: np.ndarray) -> None:
        weights = np.asarray(weights, dtype=float).reshape(-1)
        super().__init__(weights.size)
        self._weights = frozen_copy(as_vector(weights, self.nr, "weights"))

    @property
    def weights(self) -> np.ndarray:
        """Weights ``w``, shape ``(nr,)`` (read-only; assign a new array to change them)."""
        return self._weights

    @weights.setter
    def weights(self, value: np.ndarray) -> None:
        self._weights = frozen_copy(as_vector(value, self.nr, "weights"))
        ParametersVersion.bump()

    def barrier_form(self) -> tuple:
        return 0.0, 0.0, self._weights

    def calc(self, data: ActivationDataAbstract, r: np.ndarray) -> None:
        data.a_value = 0.5 * float(r @ (self._weights * r))

    def calcDiff(self, data: ActivationDataAbstract, r: np.ndarray) -> None:
        np.multiply(self._weights, r, out=data.Ar)
        data.Arr_diag[:] = self._weights
