"""Actuation models: map the control ``u`` (shape ``(nu,)``) to generalized torques ``tau``.

``calc`` fills ``tau = a(x, u)`` (shape ``(nv,)``); ``calcDiff`` fills ``dtau_dx (nv, ndx)`` and
``dtau_du (nv, nu)``.  ``commands`` inverts the map (``u`` from ``tau``) and ``torqueTransform``
gives ``Mtau (nu, nv)``, the matrix that maps generalized torques to controls.  ``tau_set``
flags the generalized-velocity rows that the actuation can drive.
"""

from __future__ import annotations

import numpy as np

from .action_common import ControlBounds, check_state_and_nu
from .array_views import KeepsViews, tolerate_python_model
from .guards import Guard, Guarded, point_control_guards
from .state import StateAbstract
from .validation import as_vector, control_arg, state_arg
from .versioning import Parametrized


class ActuationModelAbstract(Parametrized, ControlBounds, Guarded):
    """Abstract actuation model (Crocoddyl's ``ActuationModelAbstract(state, nu)``).

    Parameters
    ----------
    state : StateAbstract
        State manifold (``state.nv`` gives the dimension of ``tau``).
    nu : int
        Control dimension.

    Attributes
    ----------
    u_lb, u_ub : numpy.ndarray
        Control bounds, shape ``(nu,)``, default unbounded.

    Notes
    -----
    A user's ``calc``, ``calcDiff``, ``commands`` and ``torqueTransform`` are checked (``x (nx,)``,
    ``u (nu,)``, ``tau (nv,)``, finite).
    """

    _read_only = frozenset({"state"})

    _guards = point_control_guards(
        commands=Guard((("data", None), ("x", state_arg), ("tau", lambda m, v, n: as_vector(v, m.state.nv, n)))),
        torqueTransform=Guard((("data", None), ("x", state_arg), ("u", control_arg))),
    )

    def __init__(self, state: StateAbstract, nu: int) -> None:
        self.nu = check_state_and_nu(state, nu)
        self.state = state
        self._init_control_limits()

    def createData(self) -> "ActuationDataAbstract":
        """Allocate the actuation data."""
        return ActuationDataAbstract(self)

    def calc(self, data: "ActuationDataAbstract", x: np.ndarray, u: np.ndarray | None = None) -> None:
        raise NotImplementedError(f"{type(self).__name__}.calc is not implemented")

    def calcDiff(self, data: "ActuationDataAbstract", x: np.ndarray, u: np.ndarray | None = None) -> None:
        raise NotImplementedError(f"{type(self).__name__}.calcDiff is not implemented")

    def commands(self, data: "ActuationDataAbstract", x: np.ndarray, tau: np.ndarray) -> None:
        """Controls ``u`` that produce the generalized torques ``tau``, written to ``data.u``."""
        raise NotImplementedError(f"{type(self).__name__}.commands is not implemented")

    def torqueTransform(self, data: "ActuationDataAbstract", x: np.ndarray, u: np.ndarray) -> None:
        """Torque-to-control map ``Mtau (nu, nv)`` (pseudo-inverse of ``dtau_du`` by default)."""
        self.calc(data, x, u)
        self.calcDiff(data, x, u)
        data.Mtau[:] = np.linalg.pinv(data.dtau_du)

    def __repr__(self) -> str:
        return f"{type(self).__name__}(nu={self.nu})"


class ActuationDataAbstract(KeepsViews):
    """Actuation data: ``tau (nv,)``, ``u (nu,)``, ``dtau_dx (nv, ndx)``, ``dtau_du (nv, nu)``,
    ``Mtau (nu, nv)`` and ``tau_set`` (bool ``(nv,)``, rows reachable by the actuation)."""

    def __init__(self, model: ActuationModelAbstract) -> None:
        nv, ndx, nu = model.state.nv, model.state.ndx, model.nu
        self.tau = np.zeros(nv)
        self.u = np.zeros(nu)
        self.dtau_dx = np.zeros((nv, ndx))
        self.dtau_du = np.zeros((nv, nu))
        self.Mtau = np.zeros((nu, nv))
        self.tau_set = np.ones(nv, dtype=bool)
        tolerate_python_model(model, self, ("tau", "u", "dtau_dx", "dtau_du", "Mtau"))


class JointDataAbstract:
    """Joint efforts and accelerations of a node (Crocoddyl's ``JointDataAbstract(state, actuation, nu)``).

    Fields: ``tau (actuation.nu,)``, ``a (nv,)``, ``dtau_dx (actuation.nu, ndx)``,
    ``dtau_du (actuation.nu, nu)``, ``da_dx (nv, ndx)``, ``da_du (nv, nu)``.
    """

    def __init__(self, state: StateAbstract, actuation: ActuationModelAbstract, nu: int) -> None:
        nv, ndx, na = state.nv, state.ndx, actuation.nu
        self.tau = np.zeros(na)
        self.a = np.zeros(nv)
        self.dtau_dx = np.zeros((na, ndx))
        self.dtau_du = np.zeros((na, nu))
        self.da_dx = np.zeros((nv, ndx))
        self.da_du = np.zeros((nv, nu))
