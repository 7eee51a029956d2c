"""Common part of the integrated action models (a differential model, a control parametrization, a time step).

The integrated model's state is the differential model's.  Its control ``u`` is the parameter vector
of a control parametrization (:mod:`~crocopy.integrators.control_base`) that gives the differential
model's control ``w(t, u)`` along the step; its ``nu`` is the parametrization's and its control
limits are the differential model's, converted by ``convertBounds`` at construction.  The default,
``ControlParametrizationModelPolyZero``, is ``w = u``: the integrators then pass ``u`` straight to the
differential model and skip the Jacobian products (``data.control`` is left untouched).  Otherwise
every derivative with respect to ``w`` goes through ``dw_du``::

    Fu = Fw dw_du,  Lu = dw_duᵀ Lw,  Lxu = Lxw dw_du,  Luu = dw_duᵀ Lww dw_du,  Gu = Gw dw_du,  Hu = Hw dw_du

Terminal nodes (``u`` omitted) keep ``xnext = x`` and the differential model's terminal cost, not
scaled by ``dt``.

Both of Crocoddyl's constructor overloads are accepted, positionally or by keyword (``stepTime`` is
Crocoddyl's keyword for ``timeStep``)::

    Model(diffModel, [rktype,] timeStep=1e-3, withCostResidual=True)
    Model(diffModel, control, [rktype,] timeStep=1e-3, withCostResidual=True)
"""

from __future__ import annotations

import numpy as np

from ..action_base import ActionDataAbstract, ActionModelAbstract
from ..diff_action_base import DifferentialActionModelAbstract
from ..not_compiled import class_reason, decline
from ..state import StateVector
from ..validation import as_number
from .control_base import ControlParametrizationDataAbstract, ControlParametrizationModelAbstract
from .control_poly import ControlParametrizationModelPolyZero

_DEFAULTS = {"control": None, "timeStep": 1e-3, "withCostResidual": True}


def bind_arguments(owner: str, args: tuple, kwargs: dict, names: tuple[str, ...]) -> dict:
    """Bind an integrator's constructor arguments to ``names`` (which start with ``"control"``).

    The overload without a control is chosen when the first positional argument is neither a
    :class:`ControlParametrizationModelAbstract` nor ``None`` (the default control) and ``control``
    is not given by keyword.  Missing arguments take :data:`_DEFAULTS`; a missing one without
    default raises ``TypeError``.
    """
    first_is_control = bool(args) and (args[0] is None or isinstance(args[0], ControlParametrizationModelAbstract))
    if not (first_is_control or "control" in kwargs):
        names = names[1:]
    if len(args) > len(names):
        raise TypeError(f"{owner}() takes at most {len(names) + 1} positional arguments ({', '.join(names)} "
                        f"after diffModel), got {len(args) + 1}")
    bound = dict(zip(names, args))
    for key, value in kwargs.items():
        key = "timeStep" if key == "stepTime" else key
        if key not in names:
            raise TypeError(f"{owner}() got an unexpected keyword argument {key!r}")
        if key in bound:
            raise TypeError(f"{owner}() got multiple values for argument {key!r}")
        bound[key] = value
    missing = [name for name in names if name not in bound and name not in _DEFAULTS]
    if missing:
        raise TypeError(f"{owner}() missing required argument {missing[0]!r}")
    return {**_DEFAULTS, **bound}


class IntegratedActionModelAbstract(ActionModelAbstract):
    """Base of Euler and Runge-Kutta integrated models.

    Parameters
    ----------
    diffModel : DifferentialActionModelAbstract
        Continuous-time model.
    control : ControlParametrizationModelAbstract, optional
        Parametrization of the differential model's control over the step (``control.nw`` must
        equal ``diffModel.nu``); default ``ControlParametrizationModelPolyZero(diffModel.nu)``.
    timeStep : float
        Integration step ``dt`` (>= 0), default 1e-3.
    withCostResidual : bool
        Expose the differential model's residual as the node's residual ``r`` (default True).
    """

    _value_attributes = frozenset({"dt"})

    def __init__(self, diffModel: DifferentialActionModelAbstract, *args: object, **kwargs: object) -> None:
        bound = bind_arguments(type(self).__name__, args, kwargs, ("control", "timeStep", "withCostResidual"))
        self._init_integrated(diffModel, bound["control"], bound["timeStep"], bound["withCostResidual"])

    def _init_integrated(
        self,
        diffModel: DifferentialActionModelAbstract,
        control: ControlParametrizationModelAbstract | None,
        timeStep: float,
        withCostResidual: bool,
    ) -> None:
        if not isinstance(diffModel, DifferentialActionModelAbstract):
            raise ValueError(f"diffModel must be a DifferentialActionModelAbstract, got {type(diffModel).__name__}")
        if control is None:
            control = ControlParametrizationModelPolyZero(diffModel.nu)
        elif not isinstance(control, ControlParametrizationModelAbstract):
            raise TypeError(f"control must be a ControlParametrizationModelAbstract, got {type(control).__name__}")
        if control.nw != diffModel.nu:
            raise ValueError(f"control.nw ({control.nw}) must equal diffModel.nu ({diffModel.nu})")
        timeStep = as_number(timeStep, "timeStep", 0.0)
        super().__init__(
            diffModel.state, control.nu, diffModel.nr if withCostResidual else 0,
            diffModel.ng, diffModel.nh, diffModel.ng_T, diffModel.nh_T,
        )
        self.differential = diffModel
        self._control = control
        self._identity_control = type(control) is ControlParametrizationModelPolyZero
        self.dt = timeStep
        self.withCostResidual = bool(withCostResidual)
        self._follow_constraints(diffModel)
        if diffModel.nu:
            self._set_control_limits(*control.convertBounds(diffModel.u_lb, diffModel.u_ub))
        self._euclidean = type(diffModel.state) is StateVector

    def _offer_compiled(self, exact: type, hook: str, data, terminal: bool, memo: dict,
                        controls: tuple = ()) -> object | None:
        """This node's compiled evaluator for a solve (:mod:`crocopy.solvers.compiled_nodes`), made by the
        differential model's method ``hook`` when it has one; None (the reason recorded in ``memo``) for a subclass
        of the integrator class ``exact`` (its overrides run) or a control parametrization other than the identity
        and the classes ``controls`` (exact)."""
        if type(self) is not exact:
            return decline(memo, class_reason(self, "integrator"))
        if not self._identity_control and type(self.control) not in controls:
            return decline(memo, f"control parametrization {type(self.control).__name__}")
        make = getattr(self.differential, hook, None)
        if make is None:
            return decline(memo, class_reason(self.differential, "differential model"))
        return make(self, data, terminal, memo)

    @property
    def control(self) -> ControlParametrizationModelAbstract:
        """Control parametrization (read-only)."""
        return self._control

    @property
    def dt(self) -> float:
        """Integration step."""
        return self._dt

    @dt.setter
    def dt(self, value: float) -> None:
        self._dt = as_number(value, "dt (timeStep)", 0.0)

    def quasiStatic(self, data: ActionDataAbstract, x: np.ndarray, maxiter: int = 100, tol: float = 1e-9) -> np.ndarray:
        """The differential model's quasi-static control (zero acceleration at ``x``) as parameters.

        Returns
        -------
        numpy.ndarray
            Shape ``(nu,)``: ``params(t=0, w)`` of the differential model's answer ``w``.
        """
        w = self.differential.quasiStatic(self._differential_data(data), x, maxiter, tol)
        if self._identity_control:
            return w
        cdata = self._control_data(data)
        self._control.params(cdata, 0.0, w)
        return cdata.u.copy()

    def _differential_data(self, data: ActionDataAbstract):
        return data.differential

    def _control_data(self, data: ActionDataAbstract) -> ControlParametrizationDataAbstract:
        return data.control

    def _control_input(self, cdata: ControlParametrizationDataAbstract, t: float, u: np.ndarray) -> np.ndarray:
        """The differential model's control ``w(t, u)`` (``u`` itself for PolyZero)."""
        if self._identity_control:
            return u
        self._control._raw_calc(cdata, t, u)
        return cdata.w

    def _control_derivatives(
        self, cdata: ControlParametrizationDataAbstract, ddata, t: float, u: np.ndarray, chain: "ControlChainData"
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``(Fu, Lu, Lxu, Luu)`` of the differential model with respect to the parameters ``u``."""
        if self._identity_control:
            return ddata.Fu, ddata.Lu, ddata.Lxu, ddata.Luu
        return chain.map(self._control, cdata, ddata, t, u)

    def _control_jacobian(
        self, cdata: ControlParametrizationDataAbstract | None, A: np.ndarray, out: np.ndarray
    ) -> None:
        """``out = A dw_du`` (``A`` itself for PolyZero, zero on a terminal node, ``cdata is None``)."""
        if self._identity_control:
            out[:] = A
        elif cdata is None:
            out[:] = 0.0
        else:
            out[:] = self._control.multiplyByJacobian(cdata, A)

    def _copy_constraints(
        self, data: ActionDataAbstract, ddata, diff: bool, cdata: ControlParametrizationDataAbstract | None = None
    ) -> None:
        if data.g.size:
            data.g[:] = ddata.g
        if data.h.size:
            data.h[:] = ddata.h
        if diff:
            if data.g.size:
                data.Gx[:] = ddata.Gx
                self._control_jacobian(cdata, ddata.Gu, data.Gu)
            if data.h.size:
                data.Hx[:] = ddata.Hx
                self._control_jacobian(cdata, ddata.Hu, data.Hu)

    def _terminal_calc(self, data: ActionDataAbstract, ddata, x: np.ndarray) -> None:
        self.differential._raw_calc(ddata, x)
        data.xnext[:] = x
        data.cost = ddata.cost
        if self.withCostResidual:
            data.r[:] = ddata.r
        self._copy_constraints(data, ddata, diff=False)

    def _terminal_calcDiff(self, data: ActionDataAbstract, ddata, x: np.ndarray) -> None:
        self.differential._raw_calcDiff(ddata, x)
        if self._euclidean:
            data.Fx[:] = np.eye(self.state.ndx)
        else:
            data.Fx[:] = self.state._raw_Jintegrate(x, np.zeros(self.state.ndx))[0]
        data.Lx[:] = ddata.Lx
        data.Lxx[:] = ddata.Lxx
        self._copy_constraints(data, ddata, diff=True)


class IntegratedActionDataAbstract(ActionDataAbstract):
    """Crocoddyl's base of the integrated action data (Euler, Runge-Kutta): the fields of
    :class:`~crocopy.action_base.ActionDataAbstract`."""


class ControlChainData:
    """Buffers of the differential model's derivatives mapped from ``w`` to the parameters ``u``.

    Shapes: ``Fu (nv, nu)``, ``Lu (nu,)``, ``Lxu (ndx, nu)``, ``Lwu (nw, nu)`` (``Lww dw_du``), ``Luu (nu, nu)``.
    """

    def __init__(self, model: IntegratedActionModelAbstract) -> None:
        nv, ndx, nu, nw = model.state.nv, model.state.ndx, model.nu, model.control.nw
        self.Fu = np.zeros((nv, nu))
        self.Lu = np.zeros(nu)
        self.Lxu = np.zeros((ndx, nu))
        self.Lwu = np.zeros((nw, nu))
        self.Luu = np.zeros((nu, nu))

    def map(
        self, control: ControlParametrizationModelAbstract, cdata: ControlParametrizationDataAbstract, ddata,
        t: float, u: np.ndarray,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Fill and return ``(Fw dw_du, dw_duᵀ Lw, Lxw dw_du, dw_duᵀ Lww dw_du)`` (``calc`` ran at ``t``)."""
        control._raw_calcDiff(cdata, t, u)
        self.Fu[:] = control.multiplyByJacobian(cdata, ddata.Fu)
        self.Lu[:] = control.multiplyJacobianTransposeBy(cdata, ddata.Lu[:, None])[:, 0]
        self.Lxu[:] = control.multiplyByJacobian(cdata, ddata.Lxu)
        self.Lwu[:] = control.multiplyByJacobian(cdata, ddata.Luu)
        self.Luu[:] = control.multiplyJacobianTransposeBy(cdata, self.Lwu)
        return self.Fu, self.Lu, self.Lxu, self.Luu
