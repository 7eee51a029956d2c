"""Discrete-time action models: the model/data pair every node of a shooting problem holds.

An action model maps ``(x, u)`` (shapes ``(nx,)``, ``(nu,)``) to the next state
``xnext = f(x, u)`` and a cost ``l(x, u)``.  ``calcDiff`` fills the first derivatives
``Fx (ndx, ndx)``, ``Fu (ndx, nu)``, ``Lx (ndx,)``, ``Lu (nu,)`` and the (Gauss-Newton)
Hessians ``Lxx (ndx, ndx)``, ``Lxu (ndx, nu)``, ``Luu (nu, nu)``.  Inequality constraints
``g_lb <= g(x, u) <= g_ub`` (``ng``) and equalities ``h(x, u) = 0`` (``nh``) come with their
Jacobians ``Gx, Gu, Hx, Hu``.  A call without ``u`` evaluates the terminal model.  What it shares
with differential models lives in :mod:`crocopy.action_common`.
"""

from __future__ import annotations

import numpy as np

from .action_common import ActionDataBase, ActionModelBase
from .stored import Stored


class ActionModelAbstract(ActionModelBase):
    """Abstract discrete-time action model (Crocoddyl's ``ActionModelAbstract(state, nu, nr=1, ng=0, nh=0,
    ng_T=0, nh_T=0)``).

    Parameters
    ----------
    state : StateAbstract
        State manifold.
    nu : int
        Control dimension (0 for autonomous systems).
    nr : int, optional
        Cost-residual dimension (default 1).
    ng, nh : int, optional
        Number of inequality / equality constraints of running nodes (default 0).
    ng_T, nh_T : int, optional
        Number of inequality / equality constraints when used as terminal node (default 0).
    """

    def createData(self) -> "ActionDataAbstract":
        """Allocate the data this model writes into."""
        return ActionDataAbstract(self)

    def _rest_error(self, data: "ActionDataAbstract", x: np.ndarray) -> np.ndarray:
        return self.state.diff(x, data.xnext)

    def checkData(self, data: object) -> bool:
        """True if ``data`` was created by this kind of model."""
        return isinstance(data, ActionDataAbstract)


class ActionDataAbstract(ActionDataBase):
    """Data of an action model: cost, next state ``xnext (nx,)``, residual, derivatives (``Fx (ndx, ndx)``,
    ``Fu (ndx, nu)``) and constraints."""

    xnext = Stored()

    def __init__(self, model: ActionModelAbstract) -> None:
        super().__init__(model, model.state.ndx)
        self.xnext = np.zeros(model.state.nx)
