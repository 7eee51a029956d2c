"""Squashing functions and squashed actuation (Box-FDDP paper, squashing comparison).

A squashing model maps an unbounded input ``s`` (shape ``(ns,)``) to a bounded output
``u = sq(s)`` inside ``(s_lb, s_ub)``; ``calcDiff`` fills the diagonal Jacobian
``du_ds (ns, ns)``.  The smooth saturation is, per component,

    sq(s) = ½ (s_lb + √(β² + (s - s_lb)²)) + ½ (s_ub - √(β² + (s - s_ub)²)),
    β = smooth · (s_ub - s_lb),

which tends to ``s_lb``/``s_ub`` as ``s → ∓∞`` (``smooth = 0.1`` by default).
:class:`ActuationSquashingModel` composes a squashing with an actuation model:
``tau = a(x, sq(u))``, ``dtau_du = (∂a/∂u) du_ds``.
"""

from __future__ import annotations

import numpy as np

from crocopy.actuation_base import ActuationDataAbstract, ActuationModelAbstract
from crocopy.array_views import KeepsViews, tolerate_python_model
from crocopy.guards import Guard, Guarded
from crocopy.validation import as_count, as_number, as_vector, check_bounds


class SquashingModelAbstract(Guarded):
    """Abstract squashing (Crocoddyl's ``SquashingModelAbstract(ns)``) with bounds ``s_lb``/``s_ub``.

    A squashing written from Python fills ``data.u`` in ``calc`` and ``data.du_ds`` in ``calcDiff``.
    """

    _guards = {
        "calc": Guard((("data", None), ("s", lambda m, v, n: as_vector(v, m.ns, n)))),
        "calcDiff": Guard((("data", None), ("s", lambda m, v, n: as_vector(v, m.ns, n)))),
    }

    def __init__(self, ns: int) -> None:
        self.ns = as_count(ns, "ns", 1)
        self._s_lb = np.full(self.ns, -np.inf)
        self._s_ub = np.full(self.ns, np.inf)

    @property
    def s_lb(self) -> np.ndarray:
        """Lower output bound, shape ``(ns,)``."""
        return self._s_lb

    @s_lb.setter
    def s_lb(self, value: np.ndarray) -> None:
        lb = as_vector(value, self.ns, "s_lb", allow_nonfinite=True)
        check_bounds(lb, self._s_ub, "s_lb", "s_ub")
        self._s_lb = lb
        self._update()

    @property
    def s_ub(self) -> np.ndarray:
        """Upper output bound, shape ``(ns,)``."""
        return self._s_ub

    @s_ub.setter
    def s_ub(self, value: np.ndarray) -> None:
        ub = as_vector(value, self.ns, "s_ub", allow_nonfinite=True)
        check_bounds(self._s_lb, ub, "s_lb", "s_ub")
        self._s_ub = ub
        self._update()

    def _update(self) -> None:
        """Refresh cached quantities after a bound change."""

    def createData(self) -> "SquashingDataAbstract":
        return SquashingDataAbstract(self)

    def calc(self, data: "SquashingDataAbstract", s: np.ndarray) -> None:
        raise NotImplementedError(f"{type(self).__name__}.calc is not implemented")

    def calcDiff(self, data: "SquashingDataAbstract", s: np.ndarray) -> None:
        raise NotImplementedError(f"{type(self).__name__}.calcDiff is not implemented")

    def __repr__(self) -> str:
        return f"{type(self).__name__}(ns={self.ns})"


class SquashingDataAbstract(KeepsViews):
    """Squashing output ``u (ns,)`` and its Jacobian ``du_ds (ns, ns)``."""

    def __init__(self, model: SquashingModelAbstract) -> None:
        self.u = np.zeros(model.ns)
        self.du_ds = np.zeros((model.ns, model.ns))
        tolerate_python_model(model, self, ("u", "du_ds"))


class SquashingModelSmoothSat(SquashingModelAbstract):
    """Smooth saturation ``SquashingModelSmoothSat(u_lb, u_ub, ns)`` (see the module docstring).

    Parameters
    ----------
    u_lb, u_ub : numpy.ndarray
        Finite output bounds, shape ``(ns,)`` (stored as ``s_lb``/``s_ub``).
    ns : int
        Input dimension.
    """

    def __init__(self, u_lb: np.ndarray, u_ub: np.ndarray, ns: int) -> None:
        super().__init__(ns)
        lb = as_vector(u_lb, self.ns, "u_lb")
        ub = as_vector(u_ub, self.ns, "u_ub")
        check_bounds(lb, ub, "u_lb", "u_ub")
        self._s_lb, self._s_ub = lb, ub
        self._smooth = 0.1
        self._update()

    @property
    def smooth(self) -> float:
        """Smoothing factor: ``β = smooth · (s_ub - s_lb)``."""
        return self._smooth

    @smooth.setter
    def smooth(self, value: float) -> None:
        self._smooth = as_number(value, "smooth", 0.0, strict=True)
        self._update()

    def _update(self) -> None:
        beta = self._smooth * (self._s_ub - self._s_lb)
        self._beta2 = beta * beta
        self._mid = 0.5 * (self._s_lb + self._s_ub)

    def createData(self) -> "SquashingDataAbstract":
        data = SquashingDataAbstract(self)
        data.a = np.zeros(self.ns)  # s - s_lb
        data.b = np.zeros(self.ns)  # s - s_ub
        data.ra = np.zeros(self.ns)  # √(β² + a²)
        data.rb = np.zeros(self.ns)  # √(β² + b²)
        data.diag = np.einsum("ii->i", data.du_ds)  # writable view of the diagonal of du_ds
        return data

    def _roots(self, data: SquashingDataAbstract, s: np.ndarray) -> None:
        """``a = s - s_lb``, ``b = s - s_ub``, ``ra = √(β² + a²)``, ``rb = √(β² + b²)`` into ``data``."""
        np.subtract(s, self._s_lb, out=data.a)
        np.subtract(s, self._s_ub, out=data.b)
        np.multiply(data.a, data.a, out=data.ra)
        data.ra += self._beta2
        np.sqrt(data.ra, out=data.ra)
        np.multiply(data.b, data.b, out=data.rb)
        data.rb += self._beta2
        np.sqrt(data.rb, out=data.rb)

    def calc(self, data: SquashingDataAbstract, s: np.ndarray) -> None:
        self._roots(data, s)
        np.subtract(data.ra, data.rb, out=data.u)
        data.u *= 0.5
        data.u += self._mid

    def calcDiff(self, data: SquashingDataAbstract, s: np.ndarray) -> None:
        """``du_ds = diag(½ (a/√(β²+a²) - b/√(β²+b²)))`` (no prior :meth:`calc` needed)."""
        self._roots(data, s)
        d = data.diag
        np.divide(data.a, data.ra, out=d)
        d -= data.b / data.rb
        d *= 0.5


class ActuationSquashingData(ActuationDataAbstract):
    """Data of :class:`ActuationSquashingModel`: the actuation fields plus ``squashing`` and ``actuation``
    (the data of the squashing and of the inner actuation)."""


class ActuationSquashingModel(ActuationModelAbstract):
    """Crocoddyl's ``ActuationSquashingModel(actuation, squashing, nu)``: ``tau = actuation(x, squashing(u))``.

    Parameters
    ----------
    actuation : ActuationModelAbstract
        Actuation driven by the squashed controls (``actuation.nu == squashing.ns``).
    squashing : SquashingModelAbstract
        Squashing function.
    nu : int
        Dimension of the raw control ``u`` (equal to ``squashing.ns``).
    """

    def __init__(self, actuation: ActuationModelAbstract, squashing: SquashingModelAbstract, nu: int) -> None:
        if not isinstance(actuation, ActuationModelAbstract):
            raise ValueError(f"actuation must be an ActuationModelAbstract, got {type(actuation).__name__}")
        if not isinstance(squashing, SquashingModelAbstract):
            raise ValueError(f"squashing must be a SquashingModelAbstract, got {type(squashing).__name__}")
        if squashing.ns != actuation.nu or nu != squashing.ns:
            raise ValueError(
                f"nu = {nu}, squashing.ns = {squashing.ns} and actuation.nu = {actuation.nu} must be equal"
            )
        super().__init__(actuation.state, nu)
        self.actuation = actuation
        self.squashing = squashing

    def createData(self) -> ActuationSquashingData:
        data = ActuationSquashingData(self)
        data.squashing = self.squashing.createData()
        data.actuation = self.actuation.createData()
        data.tau_set[:] = data.actuation.tau_set
        return data

    def calc(self, data: ActuationDataAbstract, x: np.ndarray, u: np.ndarray | None = None) -> None:
        if u is None:
            return
        self.squashing.calc(data.squashing, u)
        self.actuation.calc(data.actuation, x, data.squashing.u)
        data.tau[:] = data.actuation.tau

    def calcDiff(self, data: ActuationDataAbstract, x: np.ndarray, u: np.ndarray | None = None) -> None:
        if u is None:
            return
        self.squashing.calcDiff(data.squashing, u)
        self.actuation.calcDiff(data.actuation, x, data.squashing.u)
        data.dtau_dx[:] = data.actuation.dtau_dx
        np.dot(data.actuation.dtau_du, data.squashing.du_ds, out=data.dtau_du)

    def commands(self, data: ActuationDataAbstract, x: np.ndarray, tau: np.ndarray) -> None:
        """Raw controls whose squashed value best reproduces ``tau`` (Newton on the monotone squashing)."""
        self.actuation.commands(data.actuation, x, tau)
        lb, ub = self.squashing.s_lb, self.squashing.s_ub
        margin = 1e-9 * np.maximum(ub - lb, 1.0)
        target = np.clip(data.actuation.u, lb + margin, ub - margin)
        s = target.copy()
        sdata = data.squashing
        for _ in range(50):
            self.squashing.calc(sdata, s)
            self.squashing.calcDiff(sdata, s)
            step = (target - sdata.u) / np.diag(sdata.du_ds)
            s += step
            if np.max(np.abs(step)) < 1e-12:
                break
        data.u[:] = s
