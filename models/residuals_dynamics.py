"""Whole-body residuals: centre of mass, centroidal momentum, gravity compensation, joint efforts
and joint accelerations.

- ``ResidualModelCoMPosition``:   ``r = c(q) - cref`` (3), ``∂r/∂q = Jcom``.
- ``ResidualModelCentroidalMomentum``: ``r = h(q, v) - href`` (6, linear then angular),
  ``Rx = (∂h/∂q, Ag)`` from ``computeCentroidalDynamicsDerivatives``.
- ``ResidualModelControlGrav``:   ``r = τ(x, u) - g(q)`` (nv), ``Rx = ∂τ/∂x - (∂g/∂q, 0)``,
  ``Ru = ∂τ/∂u``; on terminal nodes ``r = -g(q)``.
- ``ResidualModelJointEffort``:   ``r = τ_joints - uref`` (actuation.nu) from the joint data.
- ``ResidualModelJointAcceleration``: ``r = a - aref`` (nv) from the joint data.

They read the data collector filled by the differential action model (see
:mod:`crocopy.models.free_fwd_dynamics`).  Gravity is computed in a private ``pinocchio.Data`` so
that the shared one (velocities, accelerations) is left untouched.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from crocopy.actuation_base import ActuationModelAbstract
from crocopy.data_collector import DataCollectorAbstract
from crocopy.residuals.base import ResidualDataAbstract, ResidualModelAbstract
from crocopy.state import StateAbstract
from crocopy.validation import ArgumentTypeError, as_optional_count, as_vector
from crocopy.versioning import frozen_copy

from .residuals_frame import check_same_robot, check_state, shared_pinocchio
from .state_multibody import StateMultibody

_NO_PARAMETERS = frozen_copy(np.zeros(0))
"""The (empty) parameters compiled nodes read of a residual without any."""


def _split_ref_nu(ref: np.ndarray | int | None, nu: int | None, default_size: int,
                  name: str) -> tuple[np.ndarray, int | None]:
    """Crocoddyl's overloads ``(state, ref, nu)``, ``(state, ref)``, ``(state, nu)``, ``(state)`` (``name``: the
    reference's argument name, for errors)."""
    if ref is not None and np.isscalar(ref):
        if nu is not None or not isinstance(ref, int | np.integer) or isinstance(ref, bool | np.bool_):
            raise ArgumentTypeError(f"{name} must be a vector (or, without nu, an int nu), got"
                                    f" {type(ref).__name__} {ref!r:.40}")
        return np.zeros(default_size), int(ref)
    return (np.zeros(default_size) if ref is None else ref), nu


class ResidualDataCoMPosition(ResidualDataAbstract):
    """Data of :class:`ResidualModelCoMPosition`: ``pinocchio`` (the collector's)."""


class ResidualDataControlGrav(ResidualDataAbstract):
    """Data of :class:`ResidualModelControlGrav`: ``pinocchio`` (a private one) and ``actuation`` (the collector's)."""


class ResidualModelCoMPosition(ResidualModelAbstract):
    """``ResidualModelCoMPosition(state, cref, nu=state.nv)``: ``r = com(q) - cref``."""

    _value_attributes = frozenset({"reference"})

    compiled_kind = "com"
    """The kind compiled nodes evaluate this class as (:mod:`crocopy.models.rbd.euler_node_kernel`)."""

    def compiled_parameters(self) -> np.ndarray:
        """The parameters compiled nodes read: ``cref`` (the read-only array itself)."""
        return self._cref


    def __init__(self, state: StateMultibody, cref: np.ndarray, nu: int | None = None) -> None:
        super().__init__(check_state(state), 3, nu, True, False, False)
        self.reference = cref

    @property
    def reference(self) -> np.ndarray:
        """Reference CoM position ``cref``, shape ``(3,)`` (a read-only copy: assign a new array to change it)."""
        return self._cref

    @reference.setter
    def reference(self, value: np.ndarray) -> None:
        self._cref = frozen_copy(as_vector(value, 3, "cref"))

    def createData(self, data: DataCollectorAbstract | None = None) -> ResidualDataCoMPosition:
        d = ResidualDataCoMPosition(self, data)
        d.pinocchio = shared_pinocchio(data, self.state, type(self).__name__)
        return d

    def calc(self, data: ResidualDataAbstract, x: np.ndarray, u: np.ndarray | None = None) -> None:
        com = pin.centerOfMass(self.state.pinocchio, data.pinocchio, pin.POSITION, False)
        np.subtract(com, self._cref, out=data.r)

    def calcDiff(self, data: ResidualDataAbstract, x: np.ndarray, u: np.ndarray | None = None) -> None:
        data.Rx[:, : self.state.nv] = pin.jacobianCenterOfMass(self.state.pinocchio, data.pinocchio, False)


class ResidualModelCentroidalMomentum(ResidualModelAbstract):
    """``ResidualModelCentroidalMomentum(state, href, nu=state.nv)``: ``r = h_G(q, v) - href``.

    Data fields ``dh_dq (6, nv)``, ``dhd_dq``, ``dhd_dv (6, nv)`` hold Pinocchio's centroidal
    derivatives (at zero acceleration).
    """

    compiled_kind = "centroidal"
    """The kind compiled forward-dynamics nodes evaluate this class as (:mod:`crocopy.models.rbd.residual_kernel`)."""

    def compiled_parameters(self) -> np.ndarray:
        """The parameters compiled nodes read: ``href``."""
        return self._href

    def __init__(self, state: StateMultibody, href: np.ndarray, nu: int | None = None) -> None:
        super().__init__(check_state(state), 6, as_optional_count(nu, "nu"), True, True, False)
        self.reference = href

    @property
    def reference(self) -> np.ndarray:
        """Reference momentum ``href = (linear, angular)``, shape ``(6,)``."""
        return self._href

    @reference.setter
    def reference(self, value: np.ndarray) -> None:
        self._href = as_vector(value, 6, "href").copy()

    def createData(self, data: DataCollectorAbstract | None = None) -> "ResidualDataCentroidalMomentum":
        return ResidualDataCentroidalMomentum(self, data)

    def calc(self, data: "ResidualDataCentroidalMomentum", x: np.ndarray, u: np.ndarray | None = None) -> None:
        h = pin.computeCentroidalMomentum(self.state.pinocchio, data.pinocchio)
        np.subtract(h.vector, self._href, out=data.r)

    def calcDiff(self, data: "ResidualDataCentroidalMomentum", x: np.ndarray, u: np.ndarray | None = None) -> None:
        nq, nv = self.state.nq, self.state.nv
        dh_dq, dhd_dq, dhd_dv, Ag = pin.computeCentroidalDynamicsDerivatives(
            self.state.pinocchio, data.pinocchio_own, x[:nq], x[nq:], data.zero_a
        )
        data.dh_dq[:] = dh_dq
        data.dhd_dq[:] = dhd_dq
        data.dhd_dv[:] = dhd_dv
        data.Rx[:, :nv] = dh_dq
        data.Rx[:, nv:] = Ag


class ResidualDataCentroidalMomentum(ResidualDataAbstract):
    """Data of :class:`ResidualModelCentroidalMomentum` (Crocoddyl's fields ``pinocchio``, ``dhd_dq``,
    ``dhd_dv``, plus ``dh_dq``, all ``(6, nv)``, and a private Pinocchio data for the derivatives)."""

    def __init__(self, model: ResidualModelCentroidalMomentum, data: DataCollectorAbstract | None) -> None:
        super().__init__(model, data)
        nv = model.state.nv
        self.pinocchio = shared_pinocchio(data, model.state, type(model).__name__)
        self.pinocchio_own = model.state.pinocchio.createData()
        self.dh_dq = np.zeros((6, nv))
        self.dhd_dq = np.zeros((6, nv))
        self.dhd_dv = np.zeros((6, nv))
        self.zero_a = np.zeros(nv)


class ResidualModelControlGrav(ResidualModelAbstract):
    """``ResidualModelControlGrav(state, nu=state.nv)``: ``r = τ(x, u) - g(q)`` (shape ``(nv,)``).

    Needs an actuated data collector (``shared.actuation`` holds ``tau``, ``dtau_dx``, ``dtau_du``).
    """

    compiled_kind = "control_grav"
    """The kind compiled forward-dynamics nodes evaluate this class as (:mod:`crocopy.models.rbd.residual_kernel`)."""

    def compiled_parameters(self) -> np.ndarray:
        """The parameters compiled nodes read: none."""
        return _NO_PARAMETERS

    def __init__(self, state: StateMultibody, nu: int | None = None) -> None:
        super().__init__(check_state(state), state.nv, nu, True, False, True)

    def createData(self, data: DataCollectorAbstract | None = None) -> ResidualDataControlGrav:
        d = ResidualDataControlGrav(self, data)
        shared_pinocchio(data, self.state, type(self).__name__)
        act = getattr(data, "actuation", None)
        if act is None or act.tau.shape != (self.state.nv,) or act.dtau_du.shape != (self.state.nv, self.nu):
            raise ValueError(
                f"ResidualModelControlGrav needs an actuation data collector with tau ({self.state.nv},) and "
                f"dtau_du ({self.state.nv}, {self.nu})"
            )
        d.actuation = act
        d.pinocchio = self.state.pinocchio.createData()
        return d

    def calc(self, data: ResidualDataAbstract, x: np.ndarray, u: np.ndarray | None = None) -> None:
        g = pin.computeGeneralizedGravity(self.state.pinocchio, data.pinocchio, x[: self.state.nq])
        if u is None:
            np.negative(g, out=data.r)
        else:
            np.subtract(data.actuation.tau, g, out=data.r)

    def calcDiff(self, data: ResidualDataAbstract, x: np.ndarray, u: np.ndarray | None = None) -> None:
        nq, nv = self.state.nq, self.state.nv
        dg_dq = pin.computeGeneralizedGravityDerivatives(self.state.pinocchio, data.pinocchio, x[:nq])
        if u is None:
            data.Rx[:, :nv] = -dg_dq
            data.Rx[:, nv:] = 0.0
            return
        data.Rx[:] = data.actuation.dtau_dx
        data.Rx[:, :nv] -= dg_dq
        data.Ru[:] = data.actuation.dtau_du


class ResidualModelJointEffort(ResidualModelAbstract):
    """``ResidualModelJointEffort(state, actuation, uref, nu=state.nv, fwddyn=False)``: ``r = τ_joints - uref``.

    Also ``(state, actuation, nu)`` and ``(state, actuation)`` with ``uref = 0``.  The joint efforts
    (``actuation.nu`` of them) come from the joint data collector (``shared.joint``); with
    ``fwddyn=True`` they are the controls themselves and the residual does not depend on ``x``.
    """

    compiled_kind = "effort"
    """The kind compiled forward-dynamics nodes evaluate this class as (their joint efforts are the controls:
    :mod:`crocopy.models.rbd.residual_kernel`; an inverse-dynamics node has an item kind of its own for it)."""
    rows_only = True
    """Its ``calc`` writes the rows ``r`` and nothing else (:meth:`.CostStack.calc_residual_datas`)."""

    def compiled_parameters(self) -> np.ndarray:
        """The parameters compiled nodes read: ``uref``."""
        return self._uref

    def __init__(
        self,
        state: StateAbstract,
        actuation: ActuationModelAbstract,
        uref: np.ndarray | int | None = None,
        nu: int | None = None,
        fwddyn: bool = False,
    ) -> None:
        if not isinstance(actuation, ActuationModelAbstract):
            raise ValueError(f"actuation must be an ActuationModelAbstract, got {type(actuation).__name__}")
        if isinstance(state, StateMultibody):
            check_same_robot(state, actuation, "actuation")
        uref, nu = _split_ref_nu(uref, nu, actuation.nu, "uref")
        super().__init__(state, actuation.nu, nu, not fwddyn, not fwddyn, True)
        self.actuation = actuation
        self.fwddyn = bool(fwddyn)
        self.reference = uref

    @property
    def reference(self) -> np.ndarray:
        """Reference joint efforts ``uref``, shape ``(actuation.nu,)``."""
        return self._uref

    @reference.setter
    def reference(self, value: np.ndarray) -> None:
        self._uref = as_vector(value, self.nr, "uref").copy()

    def createData(self, data: DataCollectorAbstract | None = None) -> ResidualDataAbstract:
        d = ResidualDataAbstract(self, data)
        joint = getattr(data, "joint", None)
        if joint is None or joint.tau.shape != (self.nr,) or joint.dtau_du.shape != (self.nr, self.nu):
            raise ValueError(
                f"ResidualModelJointEffort needs a joint data collector with tau ({self.nr},) and "
                f"dtau_du ({self.nr}, {self.nu})"
            )
        d.joint = joint
        return d

    def calc(self, data: ResidualDataAbstract, x: np.ndarray, u: np.ndarray | None = None) -> None:
        if u is None:
            data.r[:] = 0.0
        else:
            np.subtract(data.joint.tau, self._uref, out=data.r)

    def calcDiff(self, data: ResidualDataAbstract, x: np.ndarray, u: np.ndarray | None = None) -> None:
        if u is None:
            return
        if not self.fwddyn:
            data.Rx[:] = data.joint.dtau_dx
        data.Ru[:] = data.joint.dtau_du


class ResidualModelJointAcceleration(ResidualModelAbstract):
    """``ResidualModelJointAcceleration(state, aref, nu=state.nv)``: ``r = a - aref`` (shape ``(nv,)``).

    Also ``(state, nu)`` and ``(state)`` with ``aref = 0``.  Reads ``shared.joint`` (``a``,
    ``da_dx``, ``da_du``); on terminal nodes (no acceleration) ``r = 0`` with zero Jacobians.
    """

    compiled_kind = "acceleration"
    """The kind compiled forward-dynamics nodes evaluate this class as (:mod:`crocopy.models.rbd.residual_kernel`; an
    inverse-dynamics node has an item kind of its own for it)."""
    rows_only = True
    """Its ``calc`` writes the rows ``r`` and nothing else (:meth:`.CostStack.calc_residual_datas`)."""

    def compiled_parameters(self) -> np.ndarray:
        """The parameters compiled nodes read: ``aref``."""
        return self._aref

    def __init__(self, state: StateAbstract, aref: np.ndarray | int | None = None, nu: int | None = None) -> None:
        aref, nu = _split_ref_nu(aref, nu, state.nv, "aref")
        super().__init__(state, state.nv, nu, True, True, True)
        self.reference = aref

    @property
    def reference(self) -> np.ndarray:
        """Reference acceleration ``aref``, shape ``(nv,)``."""
        return self._aref

    @reference.setter
    def reference(self, value: np.ndarray) -> None:
        self._aref = as_vector(value, self.nr, "aref").copy()

    def createData(self, data: DataCollectorAbstract | None = None) -> ResidualDataAbstract:
        d = ResidualDataAbstract(self, data)
        joint = getattr(data, "joint", None)
        if joint is None or joint.a.shape != (self.nr,) or joint.da_du.shape != (self.nr, self.nu):
            raise ValueError(
                f"ResidualModelJointAcceleration needs a joint data collector with a ({self.nr},) and "
                f"da_du ({self.nr}, {self.nu})"
            )
        d.joint = joint
        return d

    def calc(self, data: ResidualDataAbstract, x: np.ndarray, u: np.ndarray | None = None) -> None:
        if u is None:
            data.r[:] = 0.0
        else:
            np.subtract(data.joint.a, self._aref, out=data.r)

    def calcDiff(self, data: ResidualDataAbstract, x: np.ndarray, u: np.ndarray | None = None) -> None:
        if u is None:
            data.Rx[:] = 0.0
            return
        data.Rx[:] = data.joint.da_dx
        data.Ru[:] = data.joint.da_du
