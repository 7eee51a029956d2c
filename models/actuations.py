"""Actuation models of multibody systems.

- :class:`ActuationModelFull`: every joint is actuated, ``tau = u`` (``nu = nv``).
- :class:`ActuationModelFloatingBase`: the root (free-flyer) joint is unactuated,
  ``tau = (0, u)`` with ``nu = nv - 6``.
- :class:`ActuationModelFloatingBaseThrusters`: the root joint is driven by ``n`` thrusters fixed
  on the base; ``tau = W u`` for ``nu = n + nv - 6`` where the first ``n`` columns of ``W`` are
  the thrusters' wrenches in the base frame and the rest select the other joints.
- :class:`ActuationModelLinear` (crocopy's own): ``tau = S u`` for any constant ``S (nv, nu)``, for
  example the selection of the actuated joints of an under-actuated robot (acrobot, pendubot).

Control bounds ``u_lb``/``u_ub`` default to the URDF effort limits of the actuated joints (thrust
limits for thrusters; unbounded for :class:`ActuationModelLinear`).  ``dtau_du`` and ``Mtau`` are
constant and set in ``createData``.
"""

from __future__ import annotations

import enum
from collections.abc import Sequence
from typing import Any

import numpy as np
import pinocchio as pin

from crocopy.actuation_base import ActuationDataAbstract, ActuationModelAbstract

from .state_multibody import StateMultibody

_HUGE = 1e300


def _effort_limit(model: pin.Model, start: int) -> np.ndarray:
    lim = np.array(model.effortLimit[start:], dtype=float)
    lim[~np.isfinite(lim) | (lim >= _HUGE)] = np.inf
    return lim


def _check_state(state: object) -> StateMultibody:
    if not isinstance(state, StateMultibody):
        raise ValueError(f"state must be a StateMultibody, got {type(state).__name__}")
    return state


def _floating_base_nv(state: StateMultibody) -> int:
    model = state.pinocchio
    if model.njoints < 2 or model.joints[1].shortname() != "JointModelFreeFlyer":
        raise ValueError("the first joint of the Pinocchio model must be a free-flyer (JointModelFreeFlyer)")
    return model.joints[1].nv


class ActuationModelFull(ActuationModelAbstract):
    """Crocoddyl's ``ActuationModelFull(state)``: ``tau = u``, ``nu = nv``."""

    def __init__(self, state: StateMultibody) -> None:
        super().__init__(_check_state(state), state.nv)
        lim = _effort_limit(state.pinocchio, 0)
        self._u_lb, self._u_ub = -lim, lim.copy()

    def calc(self, data: ActuationDataAbstract, x: np.ndarray, u: np.ndarray | None = None) -> None:
        if u is not None:
            data.tau[:] = u

    def calcDiff(self, data: ActuationDataAbstract, x: np.ndarray, u: np.ndarray | None = None) -> None:
        """``dtau_du = I`` and ``dtau_dx = 0`` are constant (set in :meth:`createData`)."""

    def compiled_matrix(self) -> np.ndarray:
        """``S = ∂τ/∂u = I``, ``(nv, nu)``: this actuation's lowering (compiled nodes read ``τ = S u``)."""
        return np.eye(self.state.nv, self.nu)

    def commands(self, data: ActuationDataAbstract, x: np.ndarray, tau: np.ndarray) -> None:
        data.u[:] = tau

    def torqueTransform(self, data: ActuationDataAbstract, x: np.ndarray, u: np.ndarray) -> None:
        """``Mtau = I`` is constant (set in :meth:`createData`)."""

    def createData(self) -> ActuationDataAbstract:
        data = ActuationDataAbstract(self)
        np.fill_diagonal(data.dtau_du, 1.0)
        np.fill_diagonal(data.Mtau, 1.0)
        return data


class ActuationModelFloatingBase(ActuationModelAbstract):
    """Crocoddyl's ``ActuationModelFloatingBase(state)``: ``tau = (0_6, u)``, ``nu = nv - 6``.

    Raises ``ValueError`` if the model's first joint is not a free flyer.
    """

    def __init__(self, state: StateMultibody) -> None:
        nfb = _floating_base_nv(_check_state(state))
        super().__init__(state, state.nv - nfb)
        self._nfb = nfb
        lim = _effort_limit(state.pinocchio, nfb)
        self._u_lb, self._u_ub = -lim, lim.copy()

    def calc(self, data: ActuationDataAbstract, x: np.ndarray, u: np.ndarray | None = None) -> None:
        if u is not None:
            data.tau[self._nfb :] = u

    def calcDiff(self, data: ActuationDataAbstract, x: np.ndarray, u: np.ndarray | None = None) -> None:
        """``dtau_du = (0; I)`` and ``dtau_dx = 0`` are constant (set in :meth:`createData`)."""

    def compiled_matrix(self) -> np.ndarray:
        """``S = ∂τ/∂u = (0; I)``, ``(nv, nu)``: this actuation's lowering (compiled nodes read ``τ = S u``)."""
        S = np.zeros((self.state.nv, self.nu))
        np.fill_diagonal(S[self._nfb:], 1.0)
        return S

    def commands(self, data: ActuationDataAbstract, x: np.ndarray, tau: np.ndarray) -> None:
        data.u[:] = tau[self._nfb :]

    def torqueTransform(self, data: ActuationDataAbstract, x: np.ndarray, u: np.ndarray) -> None:
        """``Mtau = (0 I)`` is constant (set in :meth:`createData`)."""

    def createData(self) -> ActuationDataAbstract:
        data = ActuationDataAbstract(self)
        nfb = self._nfb
        np.fill_diagonal(data.dtau_du[nfb:], 1.0)
        np.fill_diagonal(data.Mtau[:, nfb:], 1.0)
        data.tau_set[:nfb] = False
        return data


class ActuationModelLinear(ActuationModelAbstract):
    """crocopy's ``ActuationModelLinear(state, S)``: ``tau = S u`` with a constant ``S``, shape ``(nv, nu)``.

    Crocoddyl has no such class (its examples write the under-actuated pendulum's actuation in Python);
    crocopy's compiled nodes take this one.  ``Mtau = S⁺`` (pseudo-inverse), ``commands`` gives
    ``u = S⁺ tau``; ``tau_set`` flags the rows of ``S`` that are not zero.  ``S`` is read-only (build a
    new model to change it); ``u_lb``/``u_ub`` default to unbounded.

    Raises ``ValueError`` if ``S`` is not a finite ``(nv, nu)`` matrix with ``nu >= 1``.
    """

    def __init__(self, state: StateMultibody, S: np.ndarray) -> None:
        nv = _check_state(state).nv
        S = np.array(S, dtype=float, copy=True)
        if S.ndim == 1 and S.shape[0] == nv:
            S = S.reshape(nv, 1)
        if S.ndim != 2 or S.shape[0] != nv or S.shape[1] < 1:
            raise ValueError(f"S must have shape (nv, nu) = ({nv}, nu) with nu >= 1, got {S.shape}")
        if not np.isfinite(S).all():
            raise ValueError("S must be finite")
        S.flags.writeable = False
        self._S = S
        self._Mtau = np.linalg.pinv(S)
        self._Mtau.flags.writeable = False
        super().__init__(state, S.shape[1])

    @property
    def S(self) -> np.ndarray:
        """The constant torque map ``tau = S u``, shape ``(nv, nu)`` (read-only)."""
        return self._S

    def calc(self, data: ActuationDataAbstract, x: np.ndarray, u: np.ndarray | None = None) -> None:
        if u is not None:
            np.dot(self._S, u, out=data.tau)

    def calcDiff(self, data: ActuationDataAbstract, x: np.ndarray, u: np.ndarray | None = None) -> None:
        """``dtau_du = S`` and ``dtau_dx = 0`` are constant (set in :meth:`createData`)."""

    def compiled_matrix(self) -> np.ndarray:
        """``S``, ``(nv, nu)``: this actuation's lowering (compiled nodes read ``τ = S u``)."""
        return self._S

    def commands(self, data: ActuationDataAbstract, x: np.ndarray, tau: np.ndarray) -> None:
        np.dot(self._Mtau, tau, out=data.u)

    def torqueTransform(self, data: ActuationDataAbstract, x: np.ndarray, u: np.ndarray) -> None:
        """``Mtau = S⁺`` is constant (set in :meth:`createData`)."""

    def createData(self) -> ActuationDataAbstract:
        data = ActuationDataAbstract(self)
        data.dtau_du[:] = self._S
        data.Mtau[:] = self._Mtau
        data.tau_set[:] = np.abs(self._S).sum(axis=1) > 0.0
        return data

    def __setstate__(self, state: dict) -> None:
        self.__dict__.update(state)
        self._S.flags.writeable = self._Mtau.flags.writeable = False


class ThrusterType(enum.IntEnum):
    """Spin direction of a thruster: its reaction torque is ``+ctorque * thrust`` (CW) or ``-`` (CCW) about its axis."""

    CW = 0
    CCW = 1


class Thruster:
    """Crocoddyl's ``Thruster(M, ctorque, type=ThrusterType.CW, min_thrust=0., max_thrust=inf)``.

    A thruster at pose ``M`` (``pinocchio.SE3``, relative to the root joint) pushes along its local
    z axis; ``Thruster(ctorque, ...)`` places it at the root joint's origin.

    Parameters
    ----------
    M : pinocchio.SE3, optional
        Pose of the thruster in the root-joint frame (stored as ``pose``).
    ctorque : float
        Torque produced about the thrust axis per unit thrust.
    type : ThrusterType
        Spin direction (default ``CW``).
    min_thrust, max_thrust : float
        Thrust bounds (defaults ``0`` and ``inf``).
    """

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        names = ("M", "ctorque", "type", "min_thrust", "max_thrust")
        if args and not isinstance(args[0], pin.SE3):
            args = (pin.SE3.Identity(), *args)
        if len(args) > len(names):
            raise TypeError(f"Thruster takes at most {len(names)} arguments, got {len(args)}")
        params = dict(zip(names, args, strict=False))
        for key, value in kwargs.items():
            if key not in names or key in params:
                raise TypeError(f"Thruster got an unexpected or repeated argument {key!r}")
            params[key] = value
        if "ctorque" not in params:
            raise ValueError("Thruster requires ctorque")
        M = params.get("M", pin.SE3.Identity())
        if not isinstance(M, pin.SE3):
            raise ValueError(f"M must be a pinocchio.SE3, got {type(M).__name__}")
        min_thrust, max_thrust = float(params.get("min_thrust", 0.0)), float(params.get("max_thrust", np.inf))
        if min_thrust > max_thrust:
            raise ValueError(f"min_thrust = {min_thrust} is above max_thrust = {max_thrust}")
        self.pose = M
        self.ctorque = float(params["ctorque"])
        self.type = ThrusterType(params.get("type", ThrusterType.CW))
        self.min_thrust = min_thrust
        self.max_thrust = max_thrust

    def __repr__(self) -> str:
        return (
            f"Thruster(pose={self.pose.translation.tolist()}, ctorque={self.ctorque}, type={self.type.name}, "
            f"min_thrust={self.min_thrust}, max_thrust={self.max_thrust})"
        )


class ActuationModelFloatingBaseThrusters(ActuationModelAbstract):
    """Crocoddyl's ``ActuationModelFloatingBaseThrusters(state, thrusters)``.

    ``tau = Wthrust u`` with ``u = (thrusts, joint torques)``: the column of thruster ``i`` is the
    base-frame wrench ``(f_i, M_i.translation × f_i + s_i ctorque_i z_i)`` with ``f_i = R_i z`` and
    ``s_i = +1`` for CW, ``-1`` for CCW.  ``Mtau = Wthrust⁺`` (pseudo-inverse).
    """

    def __init__(self, state: StateMultibody, thrusters: Sequence[Thruster]) -> None:
        nfb = _floating_base_nv(_check_state(state))
        thrusters = list(thrusters)
        for i, t in enumerate(thrusters):
            if not isinstance(t, Thruster):
                raise ValueError(f"thrusters[{i}] must be a Thruster, got {type(t).__name__}")
        self._nfb = nfb
        self._thrusters = thrusters
        super().__init__(state, len(thrusters) + state.nv - nfb)
        self._update()

    @property
    def nthrusters(self) -> int:
        """Number of thrusters."""
        return len(self._thrusters)

    @property
    def thrusters(self) -> list[Thruster]:
        """The thrusters (assigning a new list of the same length rebuilds ``Wthrust``)."""
        return self._thrusters

    @thrusters.setter
    def thrusters(self, value: Sequence[Thruster]) -> None:
        value = list(value)
        if len(value) != len(self._thrusters):
            raise ValueError(f"thrusters must hold {len(self._thrusters)} thrusters, got {len(value)}")
        self._thrusters = value
        self._update()

    @property
    def Wthrust(self) -> np.ndarray:
        """Torque map ``tau = Wthrust u``, shape ``(nv, nu)``."""
        return self._W

    @property
    def S(self) -> np.ndarray:
        """Projector ``Wthrust Wthrust⁺`` on the generalized torques the actuation can produce, ``(nv, nv)``."""
        return self._S

    def _update(self) -> None:
        nv, nfb, n = self.state.nv, self._nfb, len(self._thrusters)
        W = np.zeros((nv, self.nu))
        for i, t in enumerate(self._thrusters):
            z = t.pose.rotation[:, 2]
            sign = 1.0 if t.type == ThrusterType.CW else -1.0
            W[:3, i] = z
            W[3:6, i] = np.cross(t.pose.translation, z) + sign * t.ctorque * z
        np.fill_diagonal(W[nfb:, n:], 1.0)
        self._W = W
        self._Mtau = np.linalg.pinv(W)
        self._S = W @ self._Mtau
        lim = _effort_limit(self.state.pinocchio, nfb)
        self._u_lb = np.concatenate([[t.min_thrust for t in self._thrusters], -lim])
        self._u_ub = np.concatenate([[t.max_thrust for t in self._thrusters], lim])

    def calc(self, data: ActuationDataAbstract, x: np.ndarray, u: np.ndarray | None = None) -> None:
        if u is not None:
            np.dot(self._W, u, out=data.tau)

    def calcDiff(self, data: ActuationDataAbstract, x: np.ndarray, u: np.ndarray | None = None) -> None:
        """``dtau_du = Wthrust`` (copied when the thrusters changed since ``data`` last got it)."""
        if data._W_source is not self._W:
            data.dtau_du[:] = self._W
            data._W_source = self._W

    def compiled_matrix(self) -> np.ndarray:
        """``Wthrust``, ``(nv, nu)``: this actuation's lowering (compiled nodes read ``τ = S u``)."""
        return self._W

    def commands(self, data: ActuationDataAbstract, x: np.ndarray, tau: np.ndarray) -> None:
        np.dot(self._Mtau, tau, out=data.u)

    def torqueTransform(self, data: ActuationDataAbstract, x: np.ndarray, u: np.ndarray) -> None:
        data.Mtau[:] = self._Mtau

    def createData(self) -> ActuationDataAbstract:
        data = ActuationDataAbstract(self)
        data.dtau_du[:] = self._W
        data._W_source = self._W
        data.Mtau[:] = self._Mtau
        data.tau_set[:] = np.abs(self._W).sum(axis=1) > 1e-12
        return data
