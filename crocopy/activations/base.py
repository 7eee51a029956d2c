"""Base activation model/data.

``calc`` sets ``a_value = a(r)``; ``calcDiff`` sets ``Ar = ∂a/∂r`` (``(nr,)``) and
``Arr = ∂²a/∂r²`` (``(nr, nr)``).  Diagonal activations also keep ``Arr_diag`` (``(nr,)``) so cost
models can form ``Rᵀ Arr R`` without a dense product; ``Arr`` is then a view refreshed on demand.
"""

from __future__ import annotations

import numpy as np

from ..array_views import KeepsViews, tolerate_python_model
from ..guards import Guard, Guarded
from ..validation import as_count, residual_arg, warn_after
from ..versioning import Parametrized

_R_PARAMS = (("data", None), ("r", residual_arg))


class ActivationModelAbstract(Parametrized, Guarded):
    """Abstract activation of a residual of dimension ``nr`` (Crocoddyl's ``ActivationModelAbstract(nr)``).

    A subclass written from Python fills ``data.a_value``, ``data.Ar`` and ``data.Arr`` (dense).
    """

    #: True when ``Arr`` is diagonal and stored in ``data.Arr_diag`` (``data.Arr`` is then rebuilt
    #: from it on each read); False for a dense ``data.Arr``.
    diagonal = False

    #: A user's ``calc(data, r)``/``calcDiff(data, r)`` is checked: ``r`` of shape ``(nr,)``, finite.
    _guards = {name: Guard(_R_PARAMS, after=after) for name, after in warn_after("a_value", diff=("Ar", "Arr")).items()}

    def __init__(self, nr: int) -> None:
        self.nr = as_count(nr, "nr")

    def createData(self) -> "ActivationDataAbstract":
        return ActivationDataAbstract(self)

    def barrier_form(self) -> tuple | None:
        """``(lb, ub, w)`` if ``a(r) = ½ Σ wᵢ (rᵢ - clip(rᵢ, lbᵢ, ubᵢ))²`` with
        ``Arr = diag(w ∘ [r ≤ lb or r ≥ ub])`` exactly, else ``None``.

        The quadratic activations are the case ``lb = ub = 0``.  Cost sums evaluate such activations
        for all their items at once; a subclass that overrides ``calc``/``calcDiff`` of the class
        declaring the form is called item by item instead (logged once at DEBUG level on the
        ``"crocopy"`` logger), unless it declares its own ``barrier_form``.
        """
        return None

    def item_form(self) -> tuple[str, float] | None:
        """``(kind, parameter)`` of an activation that compiled nodes evaluate item by item
        (:func:`crocopy.costs.stack_kernel.item_activations`: ``"smooth1"`` and ``"smooth2"`` with their ``eps``,
        ``"flat_exp"``, ``"flat_log"`` and their full-Hessian ``"flat_exp_true"``, ``"flat_log_true"`` with their
        ``alpha``, ``"norm_barrier"`` and ``"norm_barrier_true"`` with theirs), else ``None``; a subclass that
        overrides ``calc``/``calcDiff`` of the class declaring it is not evaluated so.  The ``*_true`` kinds and the
        smooth 2-norm have a dense Hessian (a diagonal plus a rank-one term, which the cost stack adds)."""
        return None

    def calc(self, data: "ActivationDataAbstract", r: np.ndarray) -> None:
        raise NotImplementedError

    def calcDiff(self, data: "ActivationDataAbstract", r: np.ndarray) -> None:
        raise NotImplementedError

    def __repr__(self) -> str:
        return f"{type(self).__name__}(nr={self.nr})"


class ActivationDataAbstract(KeepsViews):
    """Activation value ``a_value``, gradient ``Ar`` and Hessian ``Arr`` (dense or diagonal)."""

    def __init__(self, model: ActivationModelAbstract) -> None:
        self._a_store = np.zeros(1)
        self.Ar = np.zeros(model.nr)
        self.Arr_diag = np.zeros(model.nr)
        self._Arr = np.zeros((model.nr, model.nr))
        self._diagonal = model.diagonal
        tolerate_python_model(model, self, ("Ar", "_Arr"))

    @property
    def a_value(self) -> float:
        """Activation value ``a(r)``."""
        return float(self._a_store[0])

    @a_value.setter
    def a_value(self, value: float) -> None:
        self._a_store[0] = value

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
