"""Cost models: an activation of a residual, and weighted sums of named costs.

For ``l = a(r(x, u))``: ``Lx = Rxᵀ Ar``, ``Lu = Ruᵀ Ar``, and the Gauss-Newton Hessians
``Lxx = Rxᵀ Arr Rx``, ``Lxu = Rxᵀ Arr Ru``, ``Luu = Ruᵀ Arr Ru``.  A cost sum adds
``weight * l`` over its active items.
"""

from __future__ import annotations

import numpy as np

from ..activations import ActivationModelAbstract, ActivationModelQuad
from ..array_views import tolerate_python_model
from ..data_collector import DataCollectorAbstract
from ..guards import Guarded, point_control_guards
from ..residuals.base import ResidualModelAbstract
from ..state import StateAbstract
from ..validation import warn_after
from ..versioning import Parametrized


def _is_int(value: object) -> bool:
    return isinstance(value, (int, np.integer)) and not isinstance(value, bool)


class CostModelAbstract(Parametrized, Guarded):
    """Abstract cost ``l(x, u)`` of an activation and a residual (Crocoddyl's ``CostModelAbstract``).

    Crocoddyl's constructor forms, positional or with keywords:

    - ``CostModelAbstract(state, activation, residual)``;
    - ``CostModelAbstract(state, residual)`` (quadratic activation of ``residual.nr`` rows);
    - ``CostModelAbstract(state, activation, nu=state.nv)`` and ``CostModelAbstract(state, nr,
      nu=state.nv)`` (quadratic activation): for costs written from Python, whose ``residual`` is
      then an abstract residual of ``nr = activation.nr`` rows that only sizes the data.

    Parameters
    ----------
    state : StateAbstract
        State manifold.
    activation : ActivationModelAbstract, ResidualModelAbstract or int
        Activation, or the residual (form 2), or the residual dimension ``nr``.
    residual : ResidualModelAbstract or int, optional
        Residual, or the control dimension ``nu`` given positionally.
    nu : int, optional
        Control dimension when there is no residual (default ``state.nv``).
    nr : int, optional
        Residual dimension when there is neither activation nor residual.

    Notes
    -----
    A user's ``calc``/``calcDiff`` is checked (``x (nx,)``, ``u (nu,)`` or ``None``, finite).
    """

    _read_only = frozenset({"state", "activation", "residual"})

    _guards = point_control_guards(warn_after("cost", diff=("Lx", "Lu", "Lxx", "Lxu", "Luu")))

    def __init__(
        self,
        state: StateAbstract,
        activation: ActivationModelAbstract | ResidualModelAbstract | int | None = None,
        residual: ResidualModelAbstract | int | None = None,
        nu: int | None = None,
        nr: int | None = None,
    ) -> None:
        if not isinstance(state, StateAbstract):
            raise ValueError(f"state must be a StateAbstract, got {type(state).__name__}")
        if isinstance(activation, ResidualModelAbstract):
            activation, residual = None, activation
        elif _is_int(activation):
            activation, nr = None, activation
        if _is_int(residual):
            residual, nu = None, residual
        if residual is None:
            residual = self._sizing_residual(state, activation, nr, nu)
        elif nu is not None and int(nu) != residual.nu:
            raise ValueError(f"nu = {nu} does not match residual.nu = {residual.nu}")
        if not isinstance(residual, ResidualModelAbstract):
            raise ValueError(f"residual must be a ResidualModelAbstract, got {type(residual).__name__}")
        if activation is None:
            activation = ActivationModelQuad(residual.nr)
        if not isinstance(activation, ActivationModelAbstract):
            raise ValueError(f"activation must be an ActivationModelAbstract, got {type(activation).__name__}")
        if activation.nr != residual.nr:
            raise ValueError(
                f"activation.nr = {activation.nr} does not match residual.nr = {residual.nr}"
            )
        if residual.state.nx != state.nx or residual.state.ndx != state.ndx:
            raise ValueError("residual was built on a different state than the cost")
        self.state = state
        self.activation = activation
        self.residual = residual
        self.nu = residual.nu

    @staticmethod
    def _sizing_residual(state: StateAbstract, activation, nr: int | None, nu: int | None) -> ResidualModelAbstract:
        """The abstract residual of a cost built without one (``nr`` rows from the activation or ``nr``)."""
        if activation is not None:
            if not isinstance(activation, ActivationModelAbstract):
                raise ValueError(f"activation must be an ActivationModelAbstract, got {type(activation).__name__}")
            if nr is not None and int(nr) != activation.nr:
                raise ValueError(f"nr = {nr} does not match activation.nr = {activation.nr}")
            nr = activation.nr
        if nr is None:
            raise ValueError("CostModelAbstract needs an activation, a residual or nr")
        return ResidualModelAbstract(state, int(nr), nu)

    def createData(self, data: DataCollectorAbstract | None = None) -> "CostDataAbstract":
        return CostDataAbstract(self, data)

    def calc(self, data: "CostDataAbstract", x: np.ndarray, u: np.ndarray | None = None) -> None:
        raise NotImplementedError

    def calcDiff(self, data: "CostDataAbstract", x: np.ndarray, u: np.ndarray | None = None) -> None:
        raise NotImplementedError

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.residual!r}, {self.activation!r})"


class CostDataAbstract:
    """Cost value and derivatives, with the residual and activation data."""

    def __init__(self, model: CostModelAbstract, data: DataCollectorAbstract | None) -> None:
        ndx, nu = model.state.ndx, model.nu
        self.shared = data
        self.cost = 0.0
        self.Lx = np.zeros(ndx)
        self.Lu = np.zeros(nu)
        self.Lxx = np.zeros((ndx, ndx))
        self.Lxu = np.zeros((ndx, nu))
        self.Luu = np.zeros((nu, nu))
        self.residual = model.residual.createData(data)
        self.activation = model.activation.createData()
        tolerate_python_model(model, self, ("Lx", "Lu", "Lxx", "Lxu", "Luu"))
        tolerate_python_model(model, self.residual, ("r", "Rx", "Ru"))

    @property
    def r(self) -> np.ndarray:
        """Residual vector of this cost, shape ``(nr,)`` (Crocoddyl's deprecated alias of ``residual.r``)."""
        return self.residual.r

    @property
    def Rx(self) -> np.ndarray:
        """Residual Jacobian in ``x``, shape ``(nr, ndx)`` (alias of ``residual.Rx``)."""
        return self.residual.Rx

    @property
    def Ru(self) -> np.ndarray:
        """Residual Jacobian in ``u``, shape ``(nr, nu)`` (alias of ``residual.Ru``)."""
        return self.residual.Ru


class CostModelResidual(CostModelAbstract):
    """``CostModelResidual(state, activation, residual)`` or ``(state, residual)`` (quadratic activation)."""

    def __init__(self, state: StateAbstract, activation, residual: ResidualModelAbstract | None = None) -> None:
        if residual is None:
            residual, activation = activation, ActivationModelQuad(activation.nr)
        super().__init__(state, activation, residual)
        self._terminal_zero = not (residual.q_dependent or residual.v_dependent)

    def createData(self, data: DataCollectorAbstract | None = None) -> "CostDataResidual":
        return CostDataResidual(self, data)

    def calc(self, data: "CostDataResidual", x: np.ndarray, u: np.ndarray | None = None) -> None:
        data.zero = u is None and self._terminal_zero
        if data.zero:
            data.residual.r[:] = 0.0
            return
        self.residual._raw_calc(data.residual, x, u)
        self.activation._raw_calc(data.activation, data.residual.r)

    def calcDiff(self, data: "CostDataResidual", x: np.ndarray, u: np.ndarray | None = None) -> None:
        """Residual and activation derivatives; ``data.Lx`` ... ``data.Luu`` are formed from them when read."""
        data.with_u = u is not None and self.residual.u_dependent
        data.zero = u is None and self._terminal_zero
        if data.zero:
            return
        self.residual._raw_calcDiff(data.residual, x, u)
        self.activation._raw_calcDiff(data.activation, data.residual.r)


class CostDataResidual(CostDataAbstract):
    """Data of :class:`CostModelResidual`.

    ``cost`` is the activation value (zero for a control-only residual at a terminal node).
    ``Lx``, ``Lu``, ``Lxx``, ``Lxu`` and ``Luu`` are read-only products of the residual Jacobians
    and the activation derivatives of the last ``calcDiff`` (formed on each read; a cost sum never
    reads them, it stacks the residual Jacobians instead).
    """

    def __init__(self, model: CostModelResidual, data: DataCollectorAbstract | None) -> None:
        self.shared = data
        self.residual = model.residual.createData(data)
        self.activation = model.activation.createData()
        self.with_u = False
        self.zero = True
        self._ndx, self._nu = model.state.ndx, model.nu

    @property
    def cost(self) -> float:
        """Cost value ``a(r(x, u))``."""
        return 0.0 if self.zero else self.activation.a_value

    def _hessian_times(self, J: np.ndarray) -> np.ndarray:
        adata = self.activation
        if adata._diagonal:
            return adata.Arr_diag[:, None] * J
        return adata.Arr @ J

    def _active(self, with_u: bool = False) -> bool:
        return not self.zero and (self.with_u or not with_u)

    @property
    def Lx(self) -> np.ndarray:
        """Gradient in ``x``, shape ``(ndx,)``."""
        return self.residual.Rx.T @ self.activation.Ar if self._active() else np.zeros(self._ndx)

    @property
    def Lu(self) -> np.ndarray:
        """Gradient in ``u``, shape ``(nu,)``."""
        return self.residual.Ru.T @ self.activation.Ar if self._active(True) else np.zeros(self._nu)

    @property
    def Lxx(self) -> np.ndarray:
        """Gauss-Newton Hessian in ``x``, shape ``(ndx, ndx)``."""
        if not self._active():
            return np.zeros((self._ndx, self._ndx))
        return self.residual.Rx.T @ self._hessian_times(self.residual.Rx)

    @property
    def Lxu(self) -> np.ndarray:
        """Gauss-Newton cross Hessian, shape ``(ndx, nu)``."""
        if not self._active(True):
            return np.zeros((self._ndx, self._nu))
        return self.residual.Rx.T @ self._hessian_times(self.residual.Ru)

    @property
    def Luu(self) -> np.ndarray:
        """Gauss-Newton Hessian in ``u``, shape ``(nu, nu)``."""
        if not self._active(True):
            return np.zeros((self._nu, self._nu))
        return self.residual.Ru.T @ self._hessian_times(self.residual.Ru)
