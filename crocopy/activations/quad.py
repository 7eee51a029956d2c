"""Quadratic activations: ``a = ½ rᵀr`` and ``a = ½ rᵀ diag(w) r``."""

from __future__ import annotations

import numpy as np

from ..validation import as_vector
from ..versioning import frozen_copy, touch
from .base import ActivationDataAbstract, ActivationModelAbstract


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


class ActivationWeights:
    """The weights ``w`` (shape ``(nr,)``) of a weighted activation: a read-only array; assigning new
    ones re-checks them and touches the activation (:mod:`crocopy.versioning`)."""

    nr: int
    _weights: np.ndarray
    _value_attributes = frozenset({"weights"})
    """Assigning new weights (of the same length) changes values only (:mod:`crocopy.versioning`)."""

    @property
    def weights(self) -> np.ndarray:
        """Weights ``w``, shape ``(nr,)`` (read-only; assign a new array to change them)."""
        return self._weights

    @weights.setter
    def weights(self, value: np.ndarray) -> None:
        self._weights = frozen_copy(as_vector(value, self.nr, "weights"))
        touch(self, layout=False)


class ActivationModelWeightedQuad(ActivationWeights, ActivationModelAbstract):
    """``a(r) = ½ Σ wᵢ rᵢ²`` with ``weights`` of shape ``(nr,)``."""

    diagonal = True

    def __init__(self, weights: np.ndarray) -> None:
        weights = as_vector(weights, None, "weights")
        super().__init__(weights.size)
        self._weights = frozen_copy(weights)

    def barrier_form(self) -> tuple:
        return 0.0, 0.0, self._weights

    def calc(self, data: ActivationDataAbstract, r: np.ndarray) -> None:
        data.a_value = 0.5 * float(r @ (self._weights * r))

    def calcDiff(self, data: ActivationDataAbstract, r: np.ndarray) -> None:
        np.multiply(self._weights, r, out=data.Ar)
        data.Arr_diag[:] = self._weights
