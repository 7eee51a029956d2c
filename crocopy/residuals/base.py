"""Residual models r(x, u) with ``r (nr,)``, ``Rx (nr, ndx)`` and ``Ru (nr, nu)``.

Residuals are the reusable pieces of cost and constraint models.  ``q_dependent``,
``v_dependent`` and ``u_dependent`` say which arguments the residual reads; a residual that
reads only ``u`` evaluates to zero on terminal nodes (called without ``u``).
"""

from __future__ import annotations

import numpy as np

from ..array_views import KeepsViews, tolerate_python_model
from ..data_collector import DataCollectorAbstract
from ..guards import Guarded, point_control_guards
from ..state import StateAbstract
from ..validation import as_count, warn_after
from ..versioning import Parametrized


class ResidualModelAbstract(Parametrized, Guarded):
    """Abstract residual (Crocoddyl's ``ResidualModelAbstract``).

    As in Crocoddyl, ``nu`` may be left out positionally:
    ``ResidualModelAbstract(state, nr, q_dependent, v_dependent, u_dependent)`` (a bool in third
    place is ``q_dependent``).

    Parameters
    ----------
    state : StateAbstract
        State manifold.
    nr : int
        Residual dimension.
    nu : int, optional
        Control dimension (default ``state.nv``).
    q_dependent, v_dependent, u_dependent : bool
        Which arguments the residual depends on.

    Notes
    -----
    A user's ``calc``/``calcDiff`` is checked (``x (nx,)``, ``u (nu,)`` or ``None``, finite).
    """

    _read_only = frozenset({"state"})

    _guards = point_control_guards(warn_after("r", diff=("Rx", "Ru")))

    def __init__(
        self,
        state: StateAbstract,
        nr: int,
        nu: int | None = None,
        q_dependent: bool = True,
        v_dependent: bool = True,
        u_dependent: bool = True,
    ) -> None:
        if not isinstance(state, StateAbstract):
            raise ValueError(f"state must be a StateAbstract, got {type(state).__name__}")
        if isinstance(nu, (bool, np.bool_)):
            nu, q_dependent, v_dependent, u_dependent = None, nu, q_dependent, v_dependent
        self.state = state
        self.nr = as_count(nr, "nr")
        self.nu = state.nv if nu is None else as_count(nu, "nu")
        self.q_dependent = bool(q_dependent)
        self.v_dependent = bool(v_dependent)
        self.u_dependent = bool(u_dependent)

    def createData(self, data: DataCollectorAbstract | None = None) -> "ResidualDataAbstract":
        return ResidualDataAbstract(self, data)

    def calc(self, data: "ResidualDataAbstract", x: np.ndarray, u: np.ndarray | None = None) -> None:
        raise NotImplementedError(f"{type(self).__name__}.calc is not implemented")

    def calcDiff(self, data: "ResidualDataAbstract", x: np.ndarray, u: np.ndarray | None = None) -> None:
        raise NotImplementedError(f"{type(self).__name__}.calcDiff is not implemented")

    def __repr__(self) -> str:
        return f"{type(self).__name__}(nr={self.nr}, nu={self.nu})"


class ResidualDataAbstract(KeepsViews):
    """Residual value ``r``, Jacobians ``Rx``/``Ru`` and the ``shared`` data collector."""

    def __init__(self, model: ResidualModelAbstract, data: DataCollectorAbstract | None) -> None:
        self.shared = data
        self.r = np.zeros(model.nr)
        self.Rx = np.zeros((model.nr, model.state.ndx))
        self.Ru = np.zeros((model.nr, model.nu))
        tolerate_python_model(model, self, ("r", "Rx", "Ru"))
