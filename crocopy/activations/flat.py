"""Quadratic-flat activations: quadratic near ``r = 0``, flat far from it (width ``alpha > 0``).

With ``n = ‖r‖²``:

* QuadFlatExp: ``a = 1 - exp(-n/α)``, ``Ar = (2/α) e r`` with ``e = exp(-n/α)``,
  Hessian ``(2/α) e (I - (2/α) r rᵀ)``;
* QuadFlatLog: ``a = log(1 + n/α)``, ``Ar = 2 r / (α + n)``,
  Hessian ``2 I / (α + n) - 4 r rᵀ / (α + n)²``.

As in Crocoddyl (whose activation data stores ``Arr`` as a diagonal matrix), ``Arr`` is the
diagonal of that Hessian by default; ``true_hessian=True`` (a crocopy extension) gives the full
Hessian.  Both Hessians are indefinite far from the basin.
"""

from __future__ import annotations

import numpy as np

from ..validation import as_bool, as_number
from .base import ActivationDataAbstract, ActivationModelAbstract


class _QuadFlat(ActivationModelAbstract):
    """Shared parameters of the quadratic-flat activations.

    Parameters
    ----------
    nr : int
        Residual dimension.
    alpha : float
        Width of the quadratic basin (positive).
    true_hessian : bool
        Full Hessian in ``Arr`` instead of its diagonal (crocopy extension).
    """

    def __init__(self, nr: int, alpha: float = 1.0, true_hessian: bool = False) -> None:
        super().__init__(nr)
        self.alpha = alpha
        self._true_hessian = as_bool(true_hessian, "true_hessian")
        self.diagonal = not self._true_hessian

    @property
    def alpha(self) -> float:
        """Width of the quadratic basin (positive)."""
        return self._alpha

    @alpha.setter
    def alpha(self, value: float) -> None:
        self._alpha = as_number(value, "alpha", 0.0, strict=True)

    @property
    def true_hessian(self) -> bool:
        """True when ``Arr`` is the full Hessian, False for its diagonal (Crocoddyl's choice)."""
        return self._true_hessian

    def _write_hessian(self, data: ActivationDataAbstract, r: np.ndarray, c: float, k: float) -> None:
        """Hessian ``c I - k r rᵀ`` (full or its diagonal)."""
        if self._true_hessian:
            data.Arr = c * np.eye(self.nr) - k * np.outer(r, r)
        else:
            np.multiply(r, r, out=data.Arr_diag)
            data.Arr_diag *= -k
            data.Arr_diag += c

    def __repr__(self) -> str:
        return f"{type(self).__name__}(nr={self.nr}, alpha={self._alpha})"


class ActivationModelQuadFlatExp(_QuadFlat):
    """Crocoddyl's ``ActivationModelQuadFlatExp(nr, alpha)``: ``a = 1 - exp(-‖r‖²/alpha)``.

    Parameters ``(nr, alpha=1.0, true_hessian=False)`` (see the base class ``_QuadFlat``).
    """

    def item_form(self) -> tuple[str, float]:
        return ("flat_exp_true" if self._true_hessian else "flat_exp"), self._alpha

    def calc(self, data: ActivationDataAbstract, r: np.ndarray) -> None:
        data.a_value = 1.0 - np.exp(-float(r @ r) / self._alpha)

    def calcDiff(self, data: ActivationDataAbstract, r: np.ndarray) -> None:
        alpha = self._alpha
        c = 2.0 / alpha * np.exp(-float(r @ r) / alpha)
        np.multiply(r, c, out=data.Ar)
        self._write_hessian(data, r, c, 2.0 / alpha * c)


class ActivationModelQuadFlatLog(_QuadFlat):
    """Crocoddyl's ``ActivationModelQuadFlatLog(nr, alpha)``: ``a = log(1 + ‖r‖²/alpha)``.

    Parameters ``(nr, alpha=1.0, true_hessian=False)`` (see the base class ``_QuadFlat``).
    """

    def item_form(self) -> tuple[str, float]:
        return ("flat_log_true" if self._true_hessian else "flat_log"), self._alpha

    def calc(self, data: ActivationDataAbstract, r: np.ndarray) -> None:
        data.a_value = float(np.log1p(float(r @ r) / self._alpha))

    def calcDiff(self, data: ActivationDataAbstract, r: np.ndarray) -> None:
        c = 2.0 / (self._alpha + float(r @ r))
        np.multiply(r, c, out=data.Ar)
        self._write_hessian(data, r, c, c * c)
