"""Numerical differentiation of an activation (Crocoddyl's ``ActivationModelNumDiff(model)``).

Central differences with step ``h = disturbance`` (default ``ε^(1/3)``, ε machine epsilon):

    Ar_i  = (a(r + h eᵢ) - a(r - h eᵢ)) / 2h
    Arr_ij = (a(r + h₂eᵢ + h₂eⱼ) - a(r + h₂eᵢ - h₂eⱼ) - a(r - h₂eᵢ + h₂eⱼ) + a(r - h₂eᵢ - h₂eⱼ)) / 4h₂²

with ``h₂ = disturbance_hessian`` (default ``ε^(1/4)``).  ``Arr`` is the full (symmetric) Hessian.
For testing analytic activation derivatives: a ``calcDiff`` costs O(nr²) ``calc`` calls.
"""

from __future__ import annotations

import numpy as np

from .base import ActivationDataAbstract, ActivationModelAbstract

_EPS = np.finfo(float).eps


class ActivationModelNumDiff(ActivationModelAbstract):
    """Activation whose ``Ar``/``Arr`` are finite differences of ``model``'s value.

    Parameters
    ----------
    model : ActivationModelAbstract
        Activation to differentiate (stored as ``model``).
    """

    def __init__(self, model: ActivationModelAbstract) -> None:
        if not isinstance(model, ActivationModelAbstract):
            raise ValueError(f"model must be an ActivationModelAbstract, got {type(model).__name__}")
        super().__init__(model.nr)
        self.model = model
        self.disturbance = _EPS ** (1.0 / 3.0)
        self.disturbance_hessian = _EPS ** (1.0 / 4.0)

    def createData(self) -> "ActivationDataNumDiff":
        return ActivationDataNumDiff(self)

    def calc(self, data: "ActivationDataNumDiff", r: np.ndarray) -> None:
        """Value of ``model`` at ``r`` (also kept in ``data.data_0``)."""
        self.model.calc(data.data_0, r)
        data.a_value = data.data_0.a_value

    def _value(self, data: "ActivationDataNumDiff", r: np.ndarray) -> float:
        self.model.calc(data.data_rp, r)
        return data.data_rp.a_value

    def calcDiff(self, data: "ActivationDataNumDiff", r: np.ndarray) -> None:
        """Gradient and Hessian by central differences (see the module docstring)."""
        nr = self.nr
        h, h2 = self.disturbance, self.disturbance_hessian
        rp, dr = data.rp, data.dr
        for i in range(nr):
            dr[:] = 0.0
            dr[i] = h
            np.add(r, dr, out=rp)
            plus = self._value(data, rp)
            np.subtract(r, dr, out=rp)
            data.Ar[i] = (plus - self._value(data, rp)) / (2.0 * h)
        hessian = np.zeros((nr, nr))
        for i in range(nr):
            for j in range(i, nr):
                total = 0.0
                for si, sj, sign in ((1, 1, 1), (1, -1, -1), (-1, 1, -1), (-1, -1, 1)):
                    dr[:] = 0.0
                    dr[i] += si * h2
                    dr[j] += sj * h2
                    np.add(r, dr, out=rp)
                    self.model.calc(data.data_r2p, rp)
                    total += sign * data.data_r2p.a_value
                hessian[i, j] = hessian[j, i] = total / (4.0 * h2 * h2)
        data.Arr = hessian
        self.calc(data, r)

    def __repr__(self) -> str:
        return f"ActivationModelNumDiff({self.model!r})"


class ActivationDataNumDiff(ActivationDataAbstract):
    """Data of :class:`ActivationModelNumDiff`: ``data_0`` (the model's data at ``r``), work data
    ``data_rp``/``data_r2p`` for the perturbed inputs, ``dr (nr,)`` the last disturbance and
    ``rp (nr,)`` the last perturbed input."""

    def __init__(self, model: ActivationModelNumDiff) -> None:
        super().__init__(model)
        self.data_0 = model.model.createData()
        self.data_rp = model.model.createData()
        self.data_r2p = model.model.createData()
        self.dr = np.zeros(model.nr)
        self.rp = np.zeros(model.nr)
