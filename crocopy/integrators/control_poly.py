"""Polynomial control parametrizations (Crocoddyl's ``PolyZero``, ``PolyOne`` and ``PolyTwoRK``).

The parameters ``u = (u₀, …, u_{K-1})`` (``K`` blocks of size ``nw``, ``nu = K nw``) are the values
of ``w`` at ``K`` nodes ``t₀ < … < t_{K-1}`` of the normalised step, and ``w(t)`` is the polynomial
of degree ``K - 1`` through them (Lagrange form)::

    w(t) = Σₖ cₖ(t) uₖ,    cₖ(t) = Π_{j≠k} (t - tⱼ) / (tₖ - tⱼ),    dw_du = [c₀ I, …, c_{K-1} I]

* ``PolyZero``: ``K = 1``, ``w = u`` (constant over the step, ``dw_du = I``).
* ``PolyOne``: nodes ``(0, ½)``, ``w(t) = (1 - 2t) u₀ + 2t u₁`` (linear).
* ``PolyTwoRK``: nodes ``(0, ⅓, ⅔)`` for ``RKType.three`` and ``(0, ½, 1)`` for ``RKType.four``
  (quadratic), the stage times of those Runge-Kutta schemes.

The coefficients ``c = (cₖ(t))`` of the last ``calc``/``calcDiff`` are kept in ``data.c``; the
Jacobian products use them.  ``params(t, w)`` returns the constant polynomial ``uₖ = w`` (exact at
every ``t``, since the ``cₖ`` sum to one), and ``convertBounds`` repeats the bounds on ``w`` for each
block: they bound ``w`` at the nodes only (between the nodes a quadratic may leave them, and so may
the line of ``PolyOne`` on ``(½, 1]``).
"""

from __future__ import annotations

import numpy as np

from ..enums import RKType
from ..validation import as_vector
from .control_base import (
    ControlParametrizationDataAbstract,
    ControlParametrizationModelAbstract,
    as_dimension,
)


class _PolynomialControl(ControlParametrizationModelAbstract):
    """``K`` blocks of parameters, each a value of ``w``: shared ``params`` and ``convertBounds``."""

    def __init__(self, nw: int, blocks: int) -> None:
        nw = as_dimension(nw, "nw")
        super().__init__(nw, blocks * nw)
        self._blocks = blocks

    def params(self, data: ControlParametrizationDataAbstract, t: float, w: np.ndarray) -> None:
        data.u[:] = np.tile(as_vector(w, self._nw, "w"), self._blocks)

    def convertBounds(
        self, w_lb: np.ndarray, w_ub: np.ndarray, u_lb: np.ndarray | None = None, u_ub: np.ndarray | None = None
    ) -> list[np.ndarray]:
        w_lb, w_ub = self._check_bounds_args(w_lb, w_ub)
        bounds = [np.tile(w_lb, self._blocks), np.tile(w_ub, self._blocks)]
        for out, value in zip((u_lb, u_ub), bounds):
            if out is not None:
                out[:] = value
        return bounds


class ControlParametrizationModelPolyZero(_PolynomialControl):
    """Crocoddyl's ``ControlParametrizationModelPolyZero(nw)``: constant control ``w = u`` (``nu = nw``)."""

    def __init__(self, nw: int) -> None:
        super().__init__(nw, 1)

    def createData(self) -> ControlParametrizationDataAbstract:
        data = ControlParametrizationDataAbstract(self)
        np.fill_diagonal(data.dw_du, 1.0)
        return data

    def calc(self, data: ControlParametrizationDataAbstract, t: float, u: np.ndarray) -> None:
        data.w[:] = u

    def calcDiff(self, data: ControlParametrizationDataAbstract, t: float, u: np.ndarray) -> None:
        """Nothing to do: ``data.dw_du`` is the identity from ``createData``."""

    def _multiply_by_jacobian(self, data: ControlParametrizationDataAbstract, A: np.ndarray) -> np.ndarray:
        return A.copy()

    def _multiply_jacobian_transpose_by(self, data: ControlParametrizationDataAbstract, A: np.ndarray) -> np.ndarray:
        return A.copy()


class _LagrangeControl(_PolynomialControl):
    """Polynomial through the values ``uₖ`` at ``nodes`` (see the module docstring)."""

    def __init__(self, nw: int, nodes: tuple[float, ...]) -> None:
        super().__init__(nw, len(nodes))
        self.nodes = nodes
        nw, nu = self._nw, self._nu
        self._diagonal = ((np.arange(len(nodes)) * nw)[:, None] + np.arange(nw) * (nu + 1)).reshape(-1)

    def _basis(self, t: float, c: np.ndarray) -> None:
        for k, tk in enumerate(self.nodes):
            value = 1.0
            for j, tj in enumerate(self.nodes):
                if j != k:
                    value *= (t - tj) / (tk - tj)
            c[k] = value

    def calc(self, data: "_LagrangeControlData", t: float, u: np.ndarray) -> None:
        self._basis(t, data.c)
        np.dot(data.c, u.reshape(self._blocks, self._nw), out=data.w)

    def calcDiff(self, data: "_LagrangeControlData", t: float, u: np.ndarray) -> None:
        self._basis(t, data.c)
        data.dw_du.reshape(-1)[self._diagonal] = np.repeat(data.c, self._nw)

    def _multiply_by_jacobian(self, data: "_LagrangeControlData", A: np.ndarray) -> np.ndarray:
        return (A[:, None, :] * data.c[:, None]).reshape(A.shape[0], self._nu)

    def _multiply_jacobian_transpose_by(self, data: "_LagrangeControlData", A: np.ndarray) -> np.ndarray:
        return (data.c[:, None, None] * A).reshape(self._nu, A.shape[1])


class _LagrangeControlData(ControlParametrizationDataAbstract):
    def __init__(self, model: _LagrangeControl) -> None:
        super().__init__(model)
        self.c = np.zeros(len(model.nodes))


class ControlParametrizationModelPolyOne(_LagrangeControl):
    """Crocoddyl's ``ControlParametrizationModelPolyOne(nw)``: linear ``w``, ``u = (w(0), w(½))``."""

    def __init__(self, nw: int) -> None:
        super().__init__(nw, (0.0, 0.5))

    def createData(self) -> "ControlParametrizationDataPolyOne":
        return ControlParametrizationDataPolyOne(self)


class ControlParametrizationDataPolyOne(_LagrangeControlData):
    """Data of :class:`ControlParametrizationModelPolyOne`; ``c`` (2,) holds ``(1 - 2t, 2t)``."""


_RK_NODES = {RKType.three: (0.0, 1.0 / 3.0, 2.0 / 3.0), RKType.four: (0.0, 0.5, 1.0)}


class ControlParametrizationModelPolyTwoRK(_LagrangeControl):
    """Crocoddyl's ``ControlParametrizationModelPolyTwoRK(nw, rktype)``: quadratic ``w`` through the RK stage times.

    ``rktype`` is ``RKType.three`` (``u = (w(0), w(⅓), w(⅔))``) or ``RKType.four``
    (``u = (w(0), w(½), w(1))``); ``RKType.two`` is refused (Crocoddyl accepts it, then fails in ``calc``).
    """

    def __init__(self, nw: int, rktype: RKType) -> None:
        try:
            nodes = _RK_NODES[RKType(rktype)]
        except (ValueError, KeyError):
            raise ValueError(
                f"rktype must be RKType.three or RKType.four for ControlParametrizationModelPolyTwoRK, got {rktype!r}"
            ) from None
        super().__init__(nw, nodes)
        self.rktype = RKType(rktype)

    def createData(self) -> "ControlParametrizationDataPolyTwoRK":
        return ControlParametrizationDataPolyTwoRK(self)

    def __repr__(self) -> str:
        return f"{type(self).__name__} {{nw={self._nw}, rktype={self.rktype.name}}}"


class ControlParametrizationDataPolyTwoRK(_LagrangeControlData):
    """Data of :class:`ControlParametrizationModelPolyTwoRK`; ``c`` (3,) holds the Lagrange coefficients at ``t``."""
