"""Squashing approach to control limits: an element-wise sigmoid in front of a model's controls.

Given any action model ``f(x, w), l(x, w)`` with controls ``w`` limited to ``[lb, ub]``,
:class:`ActionModelSquashed` exposes the *unbounded* controls ``u`` (shape ``(nu,)``) through
``w = s(u)`` and adds a small cost on the raw controls (without it the optimizer runs off onto
the sigmoid's plateau, Tassa et al. 2014 §III-B)::

    xnext = f(x, s(u)),     cost = l(x, s(u)) + 1/2 rawWeight ||u||^2.

Chain rule with ``D = diag(s'(u))`` and ``D2 = diag(s''(u))``::

    Fu  = Fu_w D,          Lu  = D Lu_w + rawWeight u,         Lxu = Lxu_w D,
    Luu = D Luu_w D + diag(Lu_w * s''(u)) + rawWeight I,        Gu = Gu_w D,   Hu = Hu_w D.

Squashing functions (element-wise, bounds ``lb < ub`` finite):

* smooth saturation (Mastalli et al., Box-FDDP paper §IV-C, with smoothness ``beta``)::

      s(u) = 1/2 (lb + sqrt(beta^2 + (u - lb)^2)) + 1/2 (ub - sqrt(beta^2 + (u - ub)^2))

  (it equals ``(lb + ub)/2`` at the centre and tends to ``lb``/``ub`` at ``-inf``/``+inf``);
* hyperbolic tangent (Tassa et al. eq. 10): ``s(u) = (ub - lb)/2 tanh(u) + (ub + lb)/2``.

The pure functions :func:`smooth_sat`, :func:`tanh_squash` and their derivatives are the maths
shared with the Crocoddyl-style squashing models of :mod:`crocopy.models`.  ``squashing`` may
also be any object following Crocoddyl's ``SquashingModelAbstract`` protocol (``ns``,
``createData()``, ``calc(data, s)`` filling ``data.u``, ``calcDiff(data, s)`` filling
``data.du_ds``); such a model provides no second derivative, so the ``s''`` term is dropped
(Gauss-Newton) in that case.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..action_base import ActionDataAbstract, ActionModelAbstract
from ..validation import as_number, as_vector, check_bounds

__all__ = [
    "ActionDataSquashed",
    "ActionModelSquashed",
    "smooth_sat",
    "smooth_sat_diff",
    "tanh_squash",
    "tanh_squash_diff",
]


def smooth_sat(u: np.ndarray, lb: np.ndarray, ub: np.ndarray, beta: float) -> np.ndarray:
    """Smooth saturation ``s(u)`` of the Box-FDDP paper (element-wise), shape of ``u``."""
    return 0.5 * (lb + ub + np.sqrt(beta**2 + (u - lb) ** 2) - np.sqrt(beta**2 + (u - ub) ** 2))


def smooth_sat_diff(u: np.ndarray, lb: np.ndarray, ub: np.ndarray, beta: float) -> tuple[np.ndarray, np.ndarray]:
    """First and second derivatives ``(s'(u), s''(u))`` of :func:`smooth_sat` (element-wise)."""
    rl = np.sqrt(beta**2 + (u - lb) ** 2)
    ru = np.sqrt(beta**2 + (u - ub) ** 2)
    d1 = 0.5 * ((u - lb) / rl - (u - ub) / ru)
    d2 = 0.5 * beta**2 * (1.0 / rl**3 - 1.0 / ru**3)
    return d1, d2


def tanh_squash(u: np.ndarray, lb: np.ndarray, ub: np.ndarray) -> np.ndarray:
    """Hyperbolic-tangent squashing ``(ub - lb)/2 tanh(u) + (ub + lb)/2`` (element-wise)."""
    return 0.5 * (ub - lb) * np.tanh(u) + 0.5 * (ub + lb)


def tanh_squash_diff(u: np.ndarray, lb: np.ndarray, ub: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """First and second derivatives ``(s'(u), s''(u))`` of :func:`tanh_squash` (element-wise)."""
    t = np.tanh(u)
    d1 = 0.5 * (ub - lb) * (1.0 - t * t)
    return d1, -2.0 * t * d1


class ActionModelSquashed(ActionModelAbstract):
    """Action model whose controls pass through an element-wise squashing function first.

    Parameters
    ----------
    model : ActionModelAbstract
        Inner model; it receives the squashed controls ``s(u)``.
    squashing : str or squashing model
        ``"smooth-sat"`` (default), ``"tanh"``, or an object following Crocoddyl's
        ``SquashingModelAbstract`` protocol.
    s_lb, s_ub : array_like, optional
        Output bounds of the squashing function, shape ``(nu,)``; default ``model.u_lb``/``model.u_ub``
        (they must then be finite).  Ignored for a squashing-model object.
    smooth : float
        Smoothness ``beta`` of the smooth saturation (default 2, the Box-FDDP paper's value).
    rawWeight : float
        Weight of the cost ``1/2 rawWeight ||u||^2`` on the raw controls (default 1e-6).
    """

    def __init__(
        self,
        model: ActionModelAbstract,
        squashing: Any = "smooth-sat",
        s_lb: np.ndarray | None = None,
        s_ub: np.ndarray | None = None,
        smooth: float = 2.0,
        rawWeight: float = 1e-6,
    ) -> None:
        if not isinstance(model, ActionModelAbstract):
            raise ValueError(f"model must be an ActionModelAbstract, got {type(model).__name__}")
        super().__init__(model.state, model.nu, model.nr, model.ng, model.nh, model.ng_T, model.nh_T)
        self._follow_constraints(model)
        self.model = model
        self.rawWeight = float(rawWeight)
        if rawWeight < 0.0:
            raise ValueError(f"rawWeight must be non-negative, got {rawWeight}")
        nu = model.nu
        if isinstance(squashing, str):
            if squashing not in ("smooth-sat", "tanh"):
                raise ValueError(f"squashing must be 'smooth-sat', 'tanh' or a squashing model, got {squashing!r}")
            lb = as_vector(model.u_lb if s_lb is None else s_lb, nu, "s_lb", allow_nonfinite=True)
            ub = as_vector(model.u_ub if s_ub is None else s_ub, nu, "s_ub", allow_nonfinite=True)
            check_bounds(lb, ub, "s_lb", "s_ub")
            if not (np.all(np.isfinite(lb)) and np.all(np.isfinite(ub))):
                raise ValueError("squashing bounds s_lb/s_ub must be finite (set model.u_lb/u_ub or pass them)")
            self.s_lb, self.s_ub, self.smooth = lb, ub, as_number(smooth, "smooth", 0.0, strict=True)
        else:
            if getattr(squashing, "ns", None) != nu:
                raise ValueError(f"squashing model must have ns == model.nu == {nu}")
            self.s_lb = np.asarray(squashing.s_lb, dtype=float)
            self.s_ub = np.asarray(squashing.s_ub, dtype=float)
            self.smooth = float(getattr(squashing, "smooth", np.nan))
        self.squashing = squashing
        self._kind = squashing if isinstance(squashing, str) else None

    def squash(self, u: np.ndarray) -> np.ndarray:
        """The controls the inner model receives, ``s(u)``, shape ``(nu,)``."""
        if self._kind == "smooth-sat":
            return smooth_sat(u, self.s_lb, self.s_ub, self.smooth)
        if self._kind == "tanh":
            return tanh_squash(u, self.s_lb, self.s_ub)
        sdata = self.squashing.createData()
        self.squashing.calc(sdata, u)
        return np.array(sdata.u, dtype=float)

    def _squash_into(self, data: "ActionDataSquashed", u: np.ndarray, diff: bool) -> None:
        if self._kind == "smooth-sat":
            data.w[:] = smooth_sat(u, self.s_lb, self.s_ub, self.smooth)
            if diff:
                data.dw_du[:], data.d2w_du2[:] = smooth_sat_diff(u, self.s_lb, self.s_ub, self.smooth)
        elif self._kind == "tanh":
            data.w[:] = tanh_squash(u, self.s_lb, self.s_ub)
            if diff:
                data.dw_du[:], data.d2w_du2[:] = tanh_squash_diff(u, self.s_lb, self.s_ub)
        else:
            self.squashing.calc(data.squashing, u)
            data.w[:] = data.squashing.u
            if diff:
                self.squashing.calcDiff(data.squashing, u)
                du_ds = np.asarray(data.squashing.du_ds)
                data.dw_du[:] = np.diag(du_ds) if du_ds.ndim == 2 else du_ds
                data.d2w_du2[:] = 0.0

    def createData(self) -> "ActionDataSquashed":
        """Allocate the wrapper data (it holds the inner model's data as ``data.inner``)."""
        return ActionDataSquashed(self)

    def calc(self, data: "ActionDataSquashed", x: np.ndarray, u: np.ndarray | None = None) -> None:
        """Next state and cost at the squashed controls."""
        inner = data.inner
        if u is None:
            self.model.calc(inner, x)
            data.cost = inner.cost
        else:
            self._squash_into(data, u, diff=False)
            self.model.calc(inner, x, data.w)
            data.cost = inner.cost + 0.5 * self.rawWeight * float(u @ u)
        data.xnext[:] = inner.xnext
        data.r[:] = inner.r
        data.g[:] = inner.g
        data.h[:] = inner.h

    def calcDiff(self, data: "ActionDataSquashed", x: np.ndarray, u: np.ndarray | None = None) -> None:
        """Chain-rule derivatives through ``s(u)`` (see the module docstring)."""
        inner = data.inner
        if u is None:
            self.model.calcDiff(inner, x)
            data.Fx[:] = inner.Fx
            data.Lx[:] = inner.Lx
            data.Lxx[:] = inner.Lxx
            data.Gx[:] = inner.Gx
            data.Hx[:] = inner.Hx
            return
        self._squash_into(data, u, diff=True)
        self.model.calcDiff(inner, x, data.w)
        d = data.dw_du
        data.Fx[:] = inner.Fx
        np.multiply(inner.Fu, d, out=data.Fu)
        data.Lx[:] = inner.Lx
        np.multiply(d, inner.Lu, out=data.Lu)
        data.Lu += self.rawWeight * u
        data.Lxx[:] = inner.Lxx
        np.multiply(inner.Lxu, d, out=data.Lxu)
        np.multiply(inner.Luu, np.multiply.outer(d, d), out=data.Luu)
        data.Luu.flat[:: self.nu + 1] += inner.Lu * data.d2w_du2 + self.rawWeight
        data.Gx[:] = inner.Gx
        np.multiply(inner.Gu, d, out=data.Gu)
        data.Hx[:] = inner.Hx
        np.multiply(inner.Hu, d, out=data.Hu)

    def __repr__(self) -> str:
        kind = self.squashing if isinstance(self.squashing, str) else type(self.squashing).__name__
        return f"ActionModelSquashed({self.model!r}, squashing={kind})"


class ActionDataSquashed(ActionDataAbstract):
    """Data of :class:`ActionModelSquashed`: inner data, squashed controls ``w`` and ``s'``, ``s''``."""

    def __init__(self, model: ActionModelSquashed) -> None:
        super().__init__(model)
        self.inner = model.model.createData()
        self.w = np.zeros(model.nu)
        self.dw_du = np.zeros(model.nu)
        self.d2w_du2 = np.zeros(model.nu)
        self.squashing = None if isinstance(model.squashing, str) else model.squashing.createData()
