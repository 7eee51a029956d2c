"""Continuous-time (differential) action models.

A differential action model maps ``(x, u)`` to the acceleration ``xout = a(x, u)`` (shape
``(nv,)``) and a cost rate ``l(x, u)``.  ``calcDiff`` fills ``Fx (nv, ndx)``, ``Fu (nv, nu)``
and the cost derivatives ``Lx, Lu, Lxx, Lxu, Luu``.  Integrators
(:mod:`crocopy.integrators.euler`, :mod:`crocopy.integrators.rk`) turn it into an action model.
What it shares with discrete action models lives in :mod:`crocopy.action_common`.
"""

from __future__ import annotations

import numpy as np

from .action_common import ActionDataBase, ActionModelBase
from .stored import Stored


class DifferentialActionModelAbstract(ActionModelBase):
    """Abstract differential action model (Crocoddyl's ``DifferentialActionModelAbstract(state, nu, nr=1,
    ng=0, nh=0, ng_T=0, nh_T=0)``).

    Parameters
    ----------
    state : StateAbstract
        State manifold (``nv`` gives the acceleration dimension).
    nu : int
        Control dimension.
    nr, ng, nh, ng_T, nh_T : int, optional
        Residual and constraint dimensions, as for :class:`~crocopy.action_base.ActionModelAbstract`
        (defaults 1, 0, 0, 0, 0).
    """

    def createData(self) -> "DifferentialActionDataAbstract":
        """Allocate the data this model writes into."""
        return DifferentialActionDataAbstract(self)

    def _rest_error(self, data: "DifferentialActionDataAbstract", x: np.ndarray) -> np.ndarray:
        return data.xout

    def checkData(self, data: object) -> bool:
        """True if ``data`` was created by this kind of model."""
        return isinstance(data, DifferentialActionDataAbstract)


class DifferentialActionDataAbstract(ActionDataBase):
    """Data of a differential action model: cost, acceleration ``xout (nv,)``, residual, derivatives
    (``Fx (nv, ndx)``, ``Fu (nv, nu)``) and constraints."""

    xout = Stored()

    def __init__(self, model: DifferentialActionModelAbstract) -> None:
        super().__init__(model, model.state.nv)
        self.xout = np.zeros(model.state.nv)
