"""Quadratic barrier activations: zero inside ``[lb, ub]``, quadratic outside.

``a = ½‖r - clip(r, lb, ub)‖²`` (weighted: ``½ Σ (wᵢ (rᵢ - clip(rᵢ)))²``, the weights applied to the
excess before squaring, which is the value Crocoddyl computes; its ``Arr = w`` is not the Hessian
of that value, crocopy's ``Arr = w²`` is, see docs/crocoddyl_deviations.md).
"""

from __future__ import annotations

import numpy as np

from ..validation import as_bound, as_number, as_vector, check_bounds
from ..versioning import frozen_copy, touch
from .base import ActivationDataAbstract, ActivationModelAbstract
from .quad import ActivationWeights


class ActivationBounds:
    """Bounds ``lb <= r <= ub`` (shape ``(nr,)``), shrunk around their middle by ``beta`` in (0, 1].

    ``lb`` and ``ub`` are read-only arrays; assigning new ones re-checks them.
    """

    def __init__(self, lb: np.ndarray, ub: np.ndarray, beta: float = 1.0) -> None:
        lb, ub = as_bound(lb, None, "lb", upper=False), as_bound(ub, None, "ub", upper=True)
        if lb.shape != ub.shape:
            raise ValueError(f"lb and ub must have the same shape, got {lb.shape} and {ub.shape}")
        check_bounds(lb, ub, "lb", "ub")
        beta = as_number(beta, "beta")
        if not 0.0 < beta <= 1.0:
            raise ValueError(f"beta must be in (0, 1], got {beta}")
        if beta < 1.0:
            finite = np.isfinite(lb) & np.isfinite(ub)
            mid, half = 0.5 * (lb[finite] + ub[finite]), 0.5 * (ub[finite] - lb[finite])
            lb, ub = lb.copy(), ub.copy()
            lb[finite], ub[finite] = mid - beta * half, mid + beta * half
        self._lb, self._ub, self.beta = frozen_copy(lb), frozen_copy(ub), float(beta)

    @property
    def lb(self) -> np.ndarray:
        """Lower bound, shape ``(nr,)``."""
        return self._lb

    @lb.setter
    def lb(self, value: np.ndarray) -> None:
        value = as_bound(value, self._lb.size, "lb", upper=False)
        check_bounds(value, self._ub, "lb", "ub")
        self._lb = frozen_copy(value)
        touch(self)

    @property
    def ub(self) -> np.ndarray:
        """Upper bound, shape ``(nr,)``."""
        return self._ub

    @ub.setter
    def ub(self, value: np.ndarray) -> None:
        value = as_bound(value, self._ub.size, "ub", upper=True)
        check_bounds(self._lb, value, "lb", "ub")
        self._ub = frozen_copy(value)
        touch(self)

    def __repr__(self) -> str:
        return f"ActivationBounds(lb={self.lb}, ub={self.ub}, beta={self.beta})"


class ActivationModelQuadraticBarrier(ActivationModelAbstract):
    """``a = ½‖r - clip(r, lb, ub)‖²``."""

    diagonal = True

    def __init__(self, bounds: ActivationBounds) -> None:
        super().__init__(bounds.lb.size)
        self._bounds = bounds

    @property
    def bounds(self) -> ActivationBounds:
        """The bounds ``lb``/``ub``."""
        return self._bounds

    @bounds.setter
    def bounds(self, value: ActivationBounds) -> None:
        if value.lb.size != self.nr:
            raise ValueError(f"bounds have size {value.lb.size}, expected nr = {self.nr}")
        self._bounds = value
        touch(self)

    def barrier_form(self) -> tuple:
        return self._bounds.lb, self._bounds.ub, 1.0

    def createData(self) -> "ActivationDataQuadraticBarrier":
        return ActivationDataQuadraticBarrier(self)

    def _excess(self, data: "ActivationDataQuadraticBarrier", r: np.ndarray) -> np.ndarray:
        """``r - clip(r, lb, ub)`` into ``data.excess`` (and ``data.outside = excess != 0``)."""
        e = data.excess
        np.minimum(r, self.bounds.ub, out=e)
        np.maximum(e, self.bounds.lb, out=e)
        np.subtract(r, e, out=e)
        return e

    def _active_rows(self, data: "ActivationDataQuadraticBarrier", r: np.ndarray) -> None:
        """``Arr_diag = [r ≤ lb or r ≥ ub]`` (curvature on the bounds too, as Crocoddyl)."""
        np.less_equal(r, self.bounds.lb, out=data.below)
        np.greater_equal(r, self.bounds.ub, out=data.above)
        np.logical_or(data.below, data.above, out=data.below)
        data.Arr_diag[:] = data.below

    def calc(self, data: "ActivationDataQuadraticBarrier", r: np.ndarray) -> None:
        e = self._excess(data, r)
        data.a_value = 0.5 * float(e @ e)

    def calcDiff(self, data: "ActivationDataQuadraticBarrier", r: np.ndarray) -> None:
        e = self._excess(data, r)
        data.Ar[:] = e
        self._active_rows(data, r)


class ActivationDataQuadraticBarrier(ActivationDataAbstract):
    """Activation data with an ``excess`` work vector ``r - clip(r, lb, ub)``, shape ``(nr,)``."""

    def __init__(self, model: ActivationModelQuadraticBarrier) -> None:
        super().__init__(model)
        self.excess = np.zeros(model.nr)
        self.below = np.zeros(model.nr, dtype=bool)
        self.above = np.zeros(model.nr, dtype=bool)


class ActivationModelWeightedQuadraticBarrier(ActivationWeights, ActivationModelQuadraticBarrier):
    """``a = ½ Σ (wᵢ (rᵢ - clip(rᵢ, lbᵢ, ubᵢ)))²``; ``Ar = w² ∘ e``, ``Arr = diag(w²)`` outside the bounds."""

    def __init__(self, bounds: ActivationBounds, weights: np.ndarray) -> None:
        super().__init__(bounds)
        self._weights = frozen_copy(as_vector(weights, self.nr, "weights"))

    def barrier_form(self) -> tuple:
        return self._bounds.lb, self._bounds.ub, self._weights * self._weights

    def calc(self, data: ActivationDataQuadraticBarrier, r: np.ndarray) -> None:
        e = self._excess(data, r) * self._weights
        data.a_value = 0.5 * float(e @ e)

    def calcDiff(self, data: ActivationDataQuadraticBarrier, r: np.ndarray) -> None:
        e = self._excess(data, r)
        w2 = self._weights * self._weights
        np.multiply(w2, e, out=data.Ar)
        self._active_rows(data, r)
        data.Arr_diag *= w2
