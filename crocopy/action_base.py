"""Discrete-time action models: the model/data pair every node of a shooting problem holds.

An action model maps ``(x, u)`` (shapes ``(nx,)``, ``(nu,)``) to the next state
``xnext = f(x, u)`` and a cost ``l(x, u)``.  ``calcDiff`` fills the first derivatives
``Fx (ndx, ndx)``, ``Fu (ndx, nu)``, ``Lx (ndx,)``, ``Lu (nu,)`` and the (Gauss-Newton)
Hessians ``Lxx (ndx, ndx)``, ``Lxu (ndx, nu)``, ``Luu (nu, nu)``.  Inequality constraints
``g_lb <= g(x, u) <= g_ub`` (``ng``) and equalities ``h(x, u) = 0`` (``nh``) come with their
Jacobians ``Gx, Gu, Hx, Hu``.  A call without ``u`` evaluates the terminal model.
"""

from __future__ import annotations

import numpy as np

from .state import StateAbstract
from .validation import as_vector, check_bounds


class ControlLimitsMixin:
    """Control bounds ``u_lb``/``u_ub`` (shape ``(nu,)``) shared by action and differential models."""

    nu: int

    def _init_control_limits(self) -> None:
        self._u_lb = np.full(self.nu, -np.inf)
        self._u_ub = np.full(self.nu, np.inf)
        self.has_control_limits = False

    @property
    def u_lb(self) -> np.ndarray:
        """Lower control bound, shape ``(nu,)``."""
        return self._u_lb

    @u_lb.setter
    def u_lb(self, value: np.ndarray) -> None:
        self._set_control_limits(as_vector(value, self.nu, "u_lb", allow_nonfinite=True), self._u_ub)

    @property
    def u_ub(self) -> np.ndarray:
        """Upper control bound, shape ``(nu,)``."""
        return self._u_ub

    @u_ub.setter
    def u_ub(self, value: np.ndarray) -> None:
        self._set_control_limits(self._u_lb, as_vector(value, self.nu, "u_ub", allow_nonfinite=True))

    def _set_control_limits(self, lb: np.ndarray, ub: np.ndarray) -> None:
        check_bounds(lb, ub, "u_lb", "u_ub")
        self._u_lb = lb
        self._u_ub = ub
        self.has_control_limits = bool(np.all(np.isfinite(lb)) and np.all(np.isfinite(ub)) and self.nu > 0)


class ActionModelAbstract(ControlLimitsMixin):
    """Abstract discrete-time action model (Crocoddyl's ``ActionModelAbstract``).

    Parameters
    ----------
    state : StateAbstract
        State manifold.
    nu : int
        Control dimension (0 for autonomous systems).
    nr : int
        Cost-residual dimension.
    ng, nh : int
        Number of inequality / equality constraints of running nodes.
    ng_T, nh_T : int
        Number of inequality / equality constraints when used as terminal node.
    """

    def __init__(
        self, state: StateAbstract, nu: int, nr: int = 1, ng: int = 0, nh: int = 0, ng_T: int = 0, nh_T: int = 0
    ) -> None:
        if not isinstance(state, StateAbstract):
            raise ValueError(f"state must be a StateAbstract, got {type(state).__name__}")
        if nu < 0:
            raise ValueError(f"nu must be non-negative, got {nu}")
        self.state = state
        self.nu = int(nu)
        self.nr = int(nr)
        self.ng = int(ng)
        self.nh = int(nh)
        self.ng_T = int(ng_T)
        self.nh_T = int(nh_T)
        self.g_lb = np.full(self.ng, -np.inf)
        self.g_ub = np.full(self.ng, np.inf)
        self._init_control_limits()

    def createData(self) -> "ActionDataAbstract":
        """Allocate the data this model writes into."""
        return ActionDataAbstract(self)

    def calc(self, data: "ActionDataAbstract", x: np.ndarray, u: np.ndarray | None = None) -> None:
        raise NotImplementedError(f"{type(self).__name__}.calc is not implemented")

    def calcDiff(self, data: "ActionDataAbstract", x: np.ndarray, u: np.ndarray | None = None) -> None:
        raise NotImplementedError(f"{type(self).__name__}.calcDiff is not implemented")

    def quasiStatic(
        self, data: "ActionDataAbstract", x: np.ndarray, maxiter: int = 100, tol: float = 1e-9
    ) -> np.ndarray:
        """Control that keeps the system at rest at ``x`` (Newton iterations on ``xnext ⊖ x = 0``).

        Returns
        -------
        numpy.ndarray
            Quasi-static control, shape ``(nu,)``.
        """
        x = as_vector(x, self.state.nx, "x")
        u = np.zeros(self.nu)
        if self.nu == 0:
            return u
        for _ in range(maxiter):
            self.calc(data, x, u)
            self.calcDiff(data, x, u)
            drift = self.state.diff(x, data.xnext)
            du = np.linalg.lstsq(data.Fu, -drift, rcond=None)[0]
            u += du
            if np.linalg.norm(du, np.inf) <= tol:
                break
        return u

    def checkData(self, data: object) -> bool:
        """True if ``data`` was created by this kind of model."""
        return isinstance(data, ActionDataAbstract)

    def __repr__(self) -> str:
        return f"{type(self).__name__}(nx={self.state.nx}, nu={self.nu})"


class ActionDataAbstract:
    """Data of an action model: cost, next state, residual, derivatives and constraints."""

    def __init__(self, model: ActionModelAbstract) -> None:
        ndx, nu = model.state.ndx, model.nu
        ng, nh = max(model.ng, model.ng_T), max(model.nh, model.nh_T)
        self.cost = np.nan
        self.xnext = np.zeros(model.state.nx)
        self.r = np.zeros(model.nr)
        self.Fx = np.zeros((ndx, ndx))
        self.Fu = np.zeros((ndx, nu))
        self.Lx = np.zeros(ndx)
        self.Lu = np.zeros(nu)
        self.Lxx = np.zeros((ndx, ndx))
        self.Lxu = np.zeros((ndx, nu))
        self.Luu = np.zeros((nu, nu))
        self.g = np.zeros(ng)
        self.Gx = np.zeros((ng, ndx))
        self.Gu = np.zeros((ng, nu))
        self.h = np.zeros(nh)
        self.Hx = np.zeros((nh, ndx))
        self.Hu = np.zeros((nh, nu))
