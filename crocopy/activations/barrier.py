"""Quadratic barrier activations: zero inside ``[lb, ub]``, quadratic outside.

``a = ½‖r - clip(r, lb, ub)‖²`` (weighted: ``½ Σ wᵢ (rᵢ - clip(rᵢ))²``).
"""

from __future__ import annotations

import numpy as np

from ..validation import as_vector, check_bounds
from .base import ActivationDataAbstract, ActivationModelAbstract


class ActivationBounds:
    """Bounds ``lb <= r <= ub`` (shape ``(nr,)``), shrunk around their middle by ``beta`` in (0, 1]."""

    def __init__(self, lb: np.ndarray, ub: np.ndarray, beta: float = 1.0) -> None:
        lb = np.asarray(lb, dtype=float).reshape(-1)
        ub = as_vector(ub, lb.size, "ub", allow_nonfinite=True)
        lb = as_vector(lb, lb.size, "lb", allow_nonfinite=True)
        check_bounds(lb, ub, "lb", "ub")
        if not 0.0 < beta <= 1.0:
            raise ValueError(f"beta must be in (0, 1], got {beta}")
        if beta < 1.0:
            finite = np.isfinite(lb) & np.isfinite(ub)
            mid, half = 0.5 * (lb[finite] + ub[finite]), 0.5 * (ub[finite] - lb[finite])
            lb, ub = lb.copy(), ub.copy()
            lb[finite], ub[finite] = mid - beta * half, mid + beta * half
        self.lb, self.ub, self.beta = lb, ub, float(beta)

    def __repr__(self) -> str:
        return f"ActivationBounds(lb={self.lb}, ub={self.ub}, beta={self.beta})"


class ActivationModelQuadraticBarrier(ActivationModelAbstract):
    """``a = ½‖r - clip(r, lb, ub)‖²``."""

    def __init__(self, bounds: ActivationBounds) -> None:
        super().__init__(bounds.lb.size)
        self.bounds = bounds

    def _excess(self, r: np.ndarray) -> np.ndarray:
        return r - np.clip(r, self.bounds.lb, self.bounds.ub)

    def calc(self, data: ActivationDataAbstract, r: np.ndarray) -> None:
        e = self._excess(r)
        data.a_value = 0.5 * float(e @ e)

    def calcDiff(self, data: ActivationDataAbstract, r: np.ndarray) -> None:
        data.Ar[:] = self._excess(r)
        data.Arr_diag[:] = (r < self.bounds.lb) | (r > self.bounds.ub)


class ActivationModelWeightedQuadraticBarrier(ActivationModelQuadraticBarrier):
    """``a = ½ Σ wᵢ (rᵢ - clip(rᵢ, lbᵢ, ubᵢ))²``."""

    def __init__(self, bounds: ActivationBounds, weights: np.ndarray) -> None:
        super().__init__(bounds)
        self.weights = as_vector(weights, self.nr, "weights")

    def calc(self, data: ActivationDataAbstract, r: np.ndarray) -> None:
        e = self._excess(r)
        data.a_value = 0.5 * float(e @ (self.weights * e))

    def calcDiff(self, data: ActivationDataAbstract, r: np.ndarray) -> None:
        data.Ar[:] = self.weights * self._excess(r)
        data.Arr_diag[:] = self.weights * ((r < self.bounds.lb) | (r > self.bounds.ub))
