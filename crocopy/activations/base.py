"""Base activation model/data.

``calc`` sets ``a_value = a(r)``; ``calcDiff`` sets ``Ar = ∂a/∂r`` (``(nr,)``) and
``Arr = ∂²a/∂r²`` (``(nr, nr)``).  Diagonal activations also keep ``Arr_diag`` (``(nr,)``) so cost
models can form ``Rᵀ Arr R`` without a dense product; ``Arr`` is then a view refreshed on demand.
"""

from __future__ import annotations

import numpy as np


class ActivationModelAbstract:
    """Abstract activation of a residual of dimension ``nr``."""

    #: True when ``Arr`` is diagonal (stored in ``data.Arr_diag``).
    diagonal = True

    def __init__(self, nr: int) -> None:
        if nr < 0:
            raise ValueError(f"nr must be non-negative, got {nr}")
        self.nr = int(nr)

    def createData(self) -> "ActivationDataAbstract":
        return ActivationDataAbstract(self)

    def calc(self, data: "ActivationDataAbstract", r: np.ndarray) -> None:
        raise NotImplementedError

    def calcDiff(self, data: "ActivationDataAbstract", r: np.ndarray) -> None:
        raise NotImplementedError

    def __repr__(self) -> str:
        return f"{type(self).__name__}(nr={self.nr})"


class ActivationDataAbstract:
    """Activation value ``a_value``, gradient ``Ar`` and Hessian ``Arr`` (dense or diagonal)."""

    def __init__(self, model: ActivationModelAbstract) -> None:
        self.a_value = 0.0
        self.Ar = np.zeros(model.nr)
        self.Arr_diag = np.zeros(model.nr)
        self._Arr = np.zeros((model.nr, model.nr))
        self._diagonal = model.diagonal

    @property
    def Arr(self) -> np.ndarray:
        """Hessian of the activation, shape ``(nr, nr)``."""
        if self._diagonal:
            self._Arr[:] = 0.0
            np.fill_diagonal(self._Arr, self.Arr_diag)
        return self._Arr

    @Arr.setter
    def Arr(self, value: np.ndarray) -> None:
        self._Arr[:] = value
        if self._diagonal:
            self.Arr_diag[:] = np.diag(self._Arr)
