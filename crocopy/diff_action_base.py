"""Continuous-time (differential) action models.

A differential action model maps ``(x, u)`` to the acceleration ``xout = a(x, u)`` (shape
``(nv,)``) and a cost rate ``l(x, u)``.  ``calcDiff`` fills ``Fx (nv, ndx)``, ``Fu (nv, nu)``
and the cost derivatives ``Lx, Lu, Lxx, Lxu, Luu``.  Integrators
(:mod:`crocopy.integrators.euler`, :mod:`crocopy.integrators.rk`) turn it into an action model.
"""

from __future__ import annotations

import numpy as np

from .action_base import ControlLimitsMixin
from .state import StateAbstract
from .validation import as_vector


class DifferentialActionModelAbstract(ControlLimitsMixin):
    """Abstract differential action model (Crocoddyl's ``DifferentialActionModelAbstract``).

    Parameters
    ----------
    state : StateAbstract
        State manifold (``nv`` gives the acceleration dimension).
    nu : int
        Control dimension.
    nr, ng, nh, ng_T, nh_T : int
        Residual and constraint dimensions, as for :class:`ActionModelAbstract`.
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

    def createData(self) -> "DifferentialActionDataAbstract":
        """Allocate the data this model writes into."""
        return DifferentialActionDataAbstract(self)

    def calc(self, data: "DifferentialActionDataAbstract", x: np.ndarray, u: np.ndarray | None = None) -> None:
        raise NotImplementedError(f"{type(self).__name__}.calc is not implemented")

    def calcDiff(self, data: "DifferentialActionDataAbstract", x: np.ndarray, u: np.ndarray | None = None) -> None:
        raise NotImplementedError(f"{type(self).__name__}.calcDiff is not implemented")

    def quasiStatic(
        self, data: "DifferentialActionDataAbstract", x: np.ndarray, maxiter: int = 100, tol: float = 1e-9
    ) -> np.ndarray:
        """Control that gives zero acceleration at ``x`` (Newton iterations on ``a(x, u) = 0``)."""
        x = as_vector(x, self.state.nx, "x")
        u = np.zeros(self.nu)
        if self.nu == 0:
            return u
        for _ in range(maxiter):
            self.calc(data, x, u)
            self.calcDiff(data, x, u)
            du = np.linalg.lstsq(data.Fu, -data.xout, rcond=None)[0]
            u += du
            if np.linalg.norm(du, np.inf) <= tol:
                break
        return u

    def checkData(self, data: object) -> bool:
        """True if ``data`` was created by this kind of model."""
        return isinstance(data, DifferentialActionDataAbstract)

    def __repr__(self) -> str:
        return f"{type(self).__name__}(nx={self.state.nx}, nu={self.nu})"


class DifferentialActionDataAbstract:
    """Data of a differential action model: cost, acceleration, residual, derivatives, constraints."""

    def __init__(self, model: DifferentialActionModelAbstract) -> None:
        ndx, nv, nu = model.state.ndx, model.state.nv, model.nu
        ng, nh = max(model.ng, model.ng_T), max(model.nh, model.nh_T)
        self.cost = np.nan
        self.xout = np.zeros(nv)
        self.r = np.zeros(model.nr)
        self.Fx = np.zeros((nv, ndx))
        self.Fu = np.zeros((nv, nu))
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
