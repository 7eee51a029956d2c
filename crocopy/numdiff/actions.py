"""Numerical differentiation of action and differential action models.

Jacobians use central differences in the tangent space (``x ⊕ h eᵢ``) with step
``disturbance`` (default ``ε^(1/3)``, ε machine epsilon).  Cost Hessians are either the
Gauss-Newton ``Rᵀ R`` of the numerical residual Jacobian (``with_gauss_approx=True``) or the
central difference of the numerical cost gradient (step ``ε^(1/4)``).  These models are for
testing analytic derivatives: each ``calcDiff`` costs O(ndx + nu) (or O((ndx + nu)²)) ``calc``
calls.
"""

from __future__ import annotations

import numpy as np

from ..action_base import ActionDataAbstract, ActionModelAbstract
from ..diff_action_base import DifferentialActionDataAbstract, DifferentialActionModelAbstract

_EPS = np.finfo(float).eps


class _NumDiffMixin:
    """Finite-difference machinery shared by the two numdiff models."""

    model: ActionModelAbstract | DifferentialActionModelAbstract
    disturbance: float

    def __init__(self, model, with_gauss_approx: bool = False) -> None:
        super().__init__(model.state, model.nu, model.nr, model.ng, model.nh, model.ng_T, model.nh_T)
        self.model = model
        self.with_gauss_approx = bool(with_gauss_approx)
        self.disturbance = _EPS ** (1.0 / 3.0)
        self.disturbance_hessian = _EPS ** (1.0 / 4.0)
        if model.nu:
            self._set_control_limits(model.u_lb, model.u_ub)

    def calc(self, data, x: np.ndarray, u: np.ndarray | None = None) -> None:
        """Evaluate the differentiated model and copy its outputs."""
        inner = data.data_0
        self.model.calc(inner, x, u)
        data.cost = inner.cost
        self._dynamics_output(data)[:] = self._dynamics_output(inner)
        data.r[:] = inner.r
        data.g[:] = inner.g
        data.h[:] = inner.h

    def calcDiff(self, data, x: np.ndarray, u: np.ndarray | None = None) -> None:
        """Fill every derivative by finite differences."""
        self._fill(data, x, u)

    def _perturbed(self, x: np.ndarray, u: np.ndarray | None, i: int, h: float):
        ndx = self.model.state.ndx
        if i < ndx:
            dx = np.zeros(ndx)
            dx[i] = h
            return self.model.state.integrate(x, dx), u
        du = u.copy()
        du[i - ndx] += h
        return x, du

    def _outputs(self, data, x: np.ndarray, u: np.ndarray | None):
        self.model.calc(data, x, u)
        return data.cost, self._dynamics_output(data).copy(), data.r.copy(), data.g.copy(), data.h.copy()

    def _dynamics_output(self, data) -> np.ndarray:
        raise NotImplementedError

    def _dynamics_diff(self, out_plus: np.ndarray, out_minus: np.ndarray) -> np.ndarray:
        raise NotImplementedError

    def _gradient(self, data, x: np.ndarray, u: np.ndarray | None, h: float) -> np.ndarray:
        n = self.model.state.ndx + (0 if u is None else self.model.nu)
        grad = np.zeros(n)
        for i in range(n):
            xp, up = self._perturbed(x, u, i, h)
            xm, um = self._perturbed(x, u, i, -h)
            self.model.calc(data, xp, up)
            cp = data.cost
            self.model.calc(data, xm, um)
            grad[i] = (cp - data.cost) / (2 * h)
        return grad

    def _fill(self, data, x: np.ndarray, u: np.ndarray | None) -> None:
        model = self.model
        ndx = model.state.ndx
        nu = 0 if u is None else model.nu
        h = self.disturbance
        inner = data.data_0
        n = ndx + nu
        nout = data.Fx.shape[0]
        J_dyn = np.zeros((nout, n))
        grad = np.zeros(n)
        Jr = np.zeros((model.nr, n))
        Jg = np.zeros((inner.g.size, n))
        Jh = np.zeros((inner.h.size, n))
        for i in range(n):
            xp, up = self._perturbed(x, u, i, h)
            xm, um = self._perturbed(x, u, i, -h)
            cp, op, rp, gp, hp = self._outputs(inner, xp, up)
            cm, om, rm, gm, hm = self._outputs(inner, xm, um)
            J_dyn[:, i] = self._dynamics_diff(op, om) / (2 * h)
            grad[i] = (cp - cm) / (2 * h)
            Jr[:, i] = (rp - rm) / (2 * h)
            Jg[:, i] = (gp - gm) / (2 * h)
            Jh[:, i] = (hp - hm) / (2 * h)
        if self.with_gauss_approx:
            hess = Jr.T @ Jr
        else:
            hh = self.disturbance_hessian
            hess = np.zeros((n, n))
            for i in range(n):
                xp, up = self._perturbed(x, u, i, hh)
                xm, um = self._perturbed(x, u, i, -hh)
                hess[:, i] = (self._gradient(inner, xp, up, hh) - self._gradient(inner, xm, um, hh)) / (2 * hh)
            hess = 0.5 * (hess + hess.T)
        self._outputs(inner, x, u)
        data.Fx[:] = J_dyn[:, :ndx]
        data.Lx[:] = grad[:ndx]
        data.Lxx[:] = hess[:ndx, :ndx]
        data.Gx[:] = Jg[:, :ndx]
        data.Hx[:] = Jh[:, :ndx]
        if u is not None:
            data.Fu[:] = J_dyn[:, ndx:]
            data.Lu[:] = grad[ndx:]
            data.Lxu[:] = hess[:ndx, ndx:]
            data.Luu[:] = hess[ndx:, ndx:]
            data.Gu[:] = Jg[:, ndx:]
            data.Hu[:] = Jh[:, ndx:]
        data.Rx = Jr[:, :ndx]
        data.Ru = Jr[:, ndx:]


class ActionModelNumDiff(_NumDiffMixin, ActionModelAbstract):
    """Action model whose derivatives are computed by finite differences of ``model``.

    Parameters
    ----------
    model : ActionModelAbstract
        Model to differentiate.
    with_gauss_approx : bool
        Use ``Rᵀ R`` of the numerical residual Jacobian as cost Hessian.
    """

    def createData(self) -> "ActionDataNumDiff":
        return ActionDataNumDiff(self)

    def _dynamics_output(self, data: ActionDataAbstract) -> np.ndarray:
        return data.xnext

    def _dynamics_diff(self, out_plus: np.ndarray, out_minus: np.ndarray) -> np.ndarray:
        return self.model.state.diff(out_minus, out_plus)


class ActionDataNumDiff(ActionDataAbstract):
    """Data of :class:`ActionModelNumDiff`; ``data_0`` is the differentiated model's data."""

    def __init__(self, model: ActionModelNumDiff) -> None:
        super().__init__(model)
        self.data_0 = model.model.createData()
        self.Rx = np.zeros((model.nr, model.state.ndx))
        self.Ru = np.zeros((model.nr, model.nu))


class DifferentialActionModelNumDiff(_NumDiffMixin, DifferentialActionModelAbstract):
    """Differential action model whose derivatives are computed by finite differences of ``model``."""

    def createData(self) -> "DifferentialActionDataNumDiff":
        return DifferentialActionDataNumDiff(self)

    def _dynamics_output(self, data: DifferentialActionDataAbstract) -> np.ndarray:
        return data.xout

    def _dynamics_diff(self, out_plus: np.ndarray, out_minus: np.ndarray) -> np.ndarray:
        return out_plus - out_minus


class DifferentialActionDataNumDiff(DifferentialActionDataAbstract):
    """Data of :class:`DifferentialActionModelNumDiff`; ``data_0`` is the differentiated model's data."""

    def __init__(self, model: DifferentialActionModelNumDiff) -> None:
        super().__init__(model)
        self.data_0 = model.model.createData()
        self.Rx = np.zeros((model.nr, model.state.ndx))
        self.Ru = np.zeros((model.nr, model.nu))
