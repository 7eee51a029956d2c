"""Shared pieces of the legged-robot builders (quadrupeds and humanoids).

Every function takes the optimal-control library as its ``lib`` argument (``crocopy`` or
``crocoddyl``) and only uses Crocoddyl's public API through it, so the very same builder
produces the same problem with either library.

A node of a legged problem is one of:

* a **contact node** (:meth:`LeggedSetup.contact_node`): contact forward dynamics with a set of
  supporting frames (3D point contacts for feet, 6D contacts for soles and hands), integrated
  with explicit Euler over ``dt``;
* an **impulse node** (:meth:`LeggedSetup.impulse_node`): impulse dynamics for the frames that
  touch down (perfectly inelastic, restitution 0), duration zero.

Costs of a contact node (weights are the ``weights`` mapping entries, each multiplying a
squared-residual activation ``0.5 * ||r||^2_W``):

* ``state``: state regularisation towards the reference posture ``x0`` with the per-component
  weights of :meth:`LeggedSetup.state_weights` (base x/y free);
* ``control``: control regularisation ``||u||^2``;
* ``limits``: quadratic barrier on joint position limits and (possibly reduced) velocity limits;
* ``friction``: quadratic barrier keeping each contact force in its linearised friction cone
  (4 facets, outer approximation) or, for 6D contacts, its wrench cone;
* ``swing``: translation (3D) or placement (6D) tracking of a swinging frame;
* ``com``: centre-of-mass position tracking;
* ``apex`` and ``foot_xy``: the jump's base apex target and feet kept under the body in flight
  (:func:`crocopy.problems.quadruped.build_jump`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from functools import cache
from types import ModuleType

import numpy as np
import pinocchio as pin

from .model_cache import load_model_cached

DEFAULT_WEIGHTS: dict[str, float] = {
    "state": 1e1,
    "control": 1e-1,
    "limits": 1e3,
    "friction": 1e1,
    "swing": 1e6,
    "com": 1e5,
    "apex": 1e6,
    "foot_xy": 1e5,
    "impulse_state": 1e1,
    "impulse_foot": 1e7,
    "terminal_state": 1e3,
}


@cache
def _load(name: str) -> pin.Model:
    return load_model_cached(name)


def load_model(name: str) -> pin.Model:
    """A fresh copy of example-robot-data's model ``name`` (read once per process, from
    :mod:`.model_cache`'s file when there is one)."""
    return pin.Model(_load(name))


def set_control_bounds(model: object, lb: np.ndarray, ub: np.ndarray) -> None:
    """Set ``u_lb``/``u_ub`` on an action model (used by the box solvers)."""
    model.u_lb = np.asarray(lb, dtype=float).copy()
    model.u_ub = np.asarray(ub, dtype=float).copy()


class LeggedSetup:
    """Robot, state, actuation, limits and contact frames shared by the nodes of a legged problem.

    Parameters
    ----------
    lib : module
        ``crocopy`` or ``crocoddyl``.
    model : pinocchio.Model
        Floating-base robot model (its ``effortLimit``/``velocityLimit`` give the bounds).
    x0 : numpy.ndarray
        Reference state ``(nq + nv,)``: posture used for regularisation and quasi-static torques.
    contact_frames : sequence of str
        Names of the frames that can make contact (feet, soles, hands).  The floating base's
        ``root_joint`` frame is registered too (for base tasks).
    contact_dim : int
        3 for point contacts, 6 for surface (sole/hand) contacts.
    torque_limit, velocity_limit : numpy.ndarray, optional
        Actuated-joint bounds ``(nu,)``; default from the URDF.
    mu : float
        Friction coefficient of the cones.
    foot_size : tuple of float
        Length and width of a sole (m) for the 6D wrench cone.
    weights : mapping, optional
        Overrides of :data:`DEFAULT_WEIGHTS`.
    state_weights : numpy.ndarray, optional
        Squared per-component weights ``(2 nv,)`` of the state regularisation (default
        :meth:`state_weights`).
    """

    def __init__(
        self,
        lib: ModuleType,
        model: pin.Model,
        x0: np.ndarray,
        contact_frames: Sequence[str],
        contact_dim: int = 3,
        torque_limit: np.ndarray | None = None,
        velocity_limit: np.ndarray | None = None,
        mu: float = 0.7,
        foot_size: tuple[float, float] = (0.2, 0.1),
        weights: Mapping[str, float] | None = None,
        state_weights: np.ndarray | None = None,
    ) -> None:
        if contact_dim not in (3, 6):
            raise ValueError(f"contact_dim must be 3 or 6, got {contact_dim}")
        self.lib = lib
        self.model = model
        self.data = model.createData()
        self.state = lib.StateMultibody(model)
        self.actuation = lib.ActuationModelFloatingBase(self.state)
        self.nu = self.actuation.nu
        self.x0 = np.asarray(x0, dtype=float).copy()
        if self.x0.shape != (model.nq + model.nv,):
            raise ValueError(f"x0 must have shape ({model.nq + model.nv},), got {self.x0.shape}")
        self.contact_dim = contact_dim
        self._state_w = None if state_weights is None else np.asarray(state_weights, float).copy()
        if self._state_w is not None and self._state_w.shape != (2 * model.nv,):
            raise ValueError(f"state_weights must have shape ({2 * model.nv},), got {self._state_w.shape}")
        self.mu = mu
        self.foot_size = foot_size
        self.weights = dict(DEFAULT_WEIGHTS)
        if weights:
            unknown = set(weights) - set(DEFAULT_WEIGHTS)
            if unknown:
                raise KeyError(f"weights: unknown keys {sorted(unknown)}; expected {sorted(DEFAULT_WEIGHTS)}")
            self.weights.update(weights)
        self.ids = {}
        for name in contact_frames:
            if not model.existFrame(name):
                raise KeyError(f"contact_frames: frame {name!r} not in the model")
            self.ids[name] = model.getFrameId(name)
        nv = model.nv
        self.torque_limit = (
            model.effortLimit[6:].copy() if torque_limit is None else np.asarray(torque_limit, float).copy()
        )
        self.velocity_limit = (
            model.velocityLimit[6:].copy() if velocity_limit is None else np.asarray(velocity_limit, float).copy()
        )
        for arg, val in (("torque_limit", self.torque_limit), ("velocity_limit", self.velocity_limit)):
            if val.shape != (nv - 6,):
                raise ValueError(f"{arg} must have shape ({nv - 6},), got {val.shape}")
        if model.existFrame("root_joint"):
            self.ids.setdefault("root_joint", model.getFrameId("root_joint"))
        q0 = self.x0[: model.nq]
        pin.forwardKinematics(model, self.data, q0)
        pin.updateFramePlacements(model, self.data)
        self.placements0 = {name: self.data.oMf[fid].copy() for name, fid in self.ids.items()}
        self.com0 = pin.centerOfMass(model, self.data, q0).copy()

    # ------------------------------------------------------------------ cost pieces
    def state_weights(self) -> np.ndarray:
        """Per-component weights of the state regularisation (tangent space, ``(2 nv,)``).

        Base x/y free, base height and orientation 500, joint positions 0.01, base velocities 10,
        joint velocities 1 (squared inside :class:`ActivationModelWeightedQuad`), unless
        ``state_weights`` was given.
        """
        if self._state_w is not None:
            return self._state_w
        nv = self.model.nv
        w = np.concatenate([[0.0, 0.0, 500.0], [500.0] * 3, [0.01] * (nv - 6), [10.0] * 6, [1.0] * (nv - 6)])
        return w**2

    def _state_cost(self, nu: int, xref: np.ndarray | None = None, weights: np.ndarray | None = None) -> object:
        lib = self.lib
        xref = self.x0 if xref is None else xref
        weights = self.state_weights() if weights is None else weights
        res = lib.ResidualModelState(self.state, xref, nu)
        return lib.CostModelResidual(self.state, lib.ActivationModelWeightedQuad(weights), res)

    def _limit_cost(self, nu: int) -> object:
        """Quadratic barrier on joint position limits and velocity limits (base unbounded)."""
        lib, m = self.lib, self.model
        inf6 = np.full(6, np.inf)
        lb = np.concatenate([-inf6, m.lowerPositionLimit[7:], -inf6, -self.velocity_limit])
        ub = np.concatenate([inf6, m.upperPositionLimit[7:], inf6, self.velocity_limit])
        res = lib.ResidualModelState(self.state, self.state.zero(), nu)
        act = lib.ActivationModelQuadraticBarrier(lib.ActivationBounds(lb, ub))
        return lib.CostModelResidual(self.state, act, res)

    def _frame_cost(self, name: str, target: np.ndarray | pin.SE3, nu: int) -> object:
        lib, fid = self.lib, self.ids[name]
        if isinstance(target, pin.SE3):
            res = lib.ResidualModelFramePlacement(self.state, fid, target, nu)
        else:
            res = lib.ResidualModelFrameTranslation(self.state, fid, np.asarray(target, float), nu)
        return lib.CostModelResidual(self.state, res)

    def _cone_cost(self, name: str) -> object:
        lib, fid = self.lib, self.ids[name]
        if self.contact_dim == 3:
            cone = lib.FrictionCone(np.eye(3), self.mu, 4, False)
            res = lib.ResidualModelContactFrictionCone(self.state, fid, cone, self.nu)
        else:
            cone = lib.WrenchCone(np.eye(3), self.mu, np.array(self.foot_size), 4, False)
            res = lib.ResidualModelContactWrenchCone(self.state, fid, cone, self.nu)
        act = lib.ActivationModelQuadraticBarrier(lib.ActivationBounds(cone.lb, cone.ub))
        return lib.CostModelResidual(self.state, act, res)

    def _contact(self, name: str, ref: np.ndarray | pin.SE3 | None) -> object:
        lib, fid = self.lib, self.ids[name]
        gains = np.array([0.0, 50.0])
        if self.contact_dim == 3:
            pos = self.placements0[name].translation if ref is None else np.asarray(ref, float)
            return lib.ContactModel3D(self.state, fid, pos, pin.LOCAL_WORLD_ALIGNED, self.nu, gains)
        pl = self.placements0[name] if ref is None else ref
        return lib.ContactModel6D(self.state, fid, pl, pin.LOCAL, self.nu, gains)

    # ------------------------------------------------------------------ nodes
    def contact_node(
        self,
        dt: float,
        support: Mapping[str, np.ndarray | pin.SE3 | None],
        swing: Mapping[str, np.ndarray | pin.SE3] | None = None,
        com_ref: np.ndarray | None = None,
        friction: Sequence[str] | None = None,
        torque_limit: np.ndarray | None = None,
        extra: Mapping[str, tuple[object, float]] | None = None,
        terminal: bool = False,
        xref: np.ndarray | None = None,
        state_weights: np.ndarray | None = None,
    ) -> object:
        """Integrated contact-dynamics node.

        Parameters
        ----------
        dt : float
            Time step (0 for a terminal node).
        support : mapping
            Frame name → contact reference (position for 3D, SE3 for 6D; ``None`` = initial one).
            Empty: free (flight) dynamics.
        swing : mapping, optional
            Frame name → tracking target (position or SE3), weight ``weights['swing']``.
        com_ref : numpy.ndarray, optional
            CoM target ``(3,)``, weight ``weights['com']``.
        friction : sequence of str, optional
            Support frames with a friction/wrench-cone penalty (default: all of ``support``).
        torque_limit : numpy.ndarray, optional
            Control bounds for the box solvers (default: the setup's).
        extra : mapping, optional
            Name → ``(cost model, weight)`` added to the cost sum.
        terminal : bool
            Terminal node: state weight ``weights['terminal_state']`` and no control cost.
        xref : numpy.ndarray, optional
            Reference of the state regularisation (default ``x0``).
        state_weights : numpy.ndarray, optional
            Squared per-component weights ``(2 nv,)`` of the state regularisation (default
            :meth:`state_weights`).
        """
        lib, w, nu = self.lib, self.weights, self.nu
        contacts = lib.ContactModelMultiple(self.state, nu)
        for name, ref in support.items():
            contacts.addContact(name + "_contact", self._contact(name, ref))
        costs = lib.CostModelSum(self.state, nu)
        state_weight = w["terminal_state"] if terminal else w["state"]
        costs.addCost("state", self._state_cost(nu, xref, state_weights), state_weight)
        costs.addCost("limits", self._limit_cost(nu), w["limits"])
        if not terminal:
            costs.addCost("control", lib.CostModelResidual(self.state, lib.ResidualModelControl(self.state, nu)),
                          w["control"])
        for name in support if friction is None else friction:
            costs.addCost(name + "_cone", self._cone_cost(name), w["friction"])
        for name, target in (swing or {}).items():
            costs.addCost(name + "_swing", self._frame_cost(name, target, nu), w["swing"])
        if com_ref is not None:
            res = lib.ResidualModelCoMPosition(self.state, np.asarray(com_ref, float), nu)
            costs.addCost("com", lib.CostModelResidual(self.state, res), w["com"])
        for name, (cost, weight) in (extra or {}).items():
            costs.addCost(name, cost, weight)
        if support:
            dam = lib.DifferentialActionModelContactFwdDynamics(self.state, self.actuation, contacts, costs, 0.0, True)
        else:
            dam = lib.DifferentialActionModelFreeFwdDynamics(self.state, self.actuation, costs)
        lim = self.torque_limit if torque_limit is None else torque_limit
        set_control_bounds(dam, -lim, lim)
        model = lib.IntegratedActionModelEuler(dam, dt)
        set_control_bounds(model, -lim, lim)
        return model

    def impulse_node(
        self,
        landing: Mapping[str, np.ndarray | pin.SE3 | None],
        support: Sequence[str] = (),
        extra: Mapping[str, tuple[object, float]] | None = None,
    ) -> object:
        """Impulse node for the frames in ``landing`` (name → target position/placement).

        The frames in ``support`` (already in contact) take part in the impact too, without a
        target.  Costs: state regularisation (``weights['impulse_state']``), joint limits and the
        landing targets (``weights['impulse_foot']``).
        """
        lib, w = self.lib, self.weights
        impulses = lib.ImpulseModelMultiple(self.state)
        costs = lib.CostModelSum(self.state, 0)
        for name, target in {**{s: None for s in support}, **landing}.items():
            fid = self.ids[name]
            if self.contact_dim == 3:
                imp = lib.ImpulseModel3D(self.state, fid, pin.LOCAL_WORLD_ALIGNED)
            else:
                imp = lib.ImpulseModel6D(self.state, fid, pin.LOCAL)
            impulses.addImpulse(name + "_impulse", imp)
            if target is not None:
                costs.addCost(name + "_landing", self._frame_cost(name, target, 0), w["impulse_foot"])
        costs.addCost("state", self._state_cost(0), w["impulse_state"])
        costs.addCost("limits", self._limit_cost(0), w["limits"])
        for name, (cost, weight) in (extra or {}).items():
            costs.addCost(name, cost, weight)
        return lib.ActionModelImpulseFwdDynamics(self.state, impulses, costs, 0.0, 0.0, True)

    def problem(self, running: Sequence[object], terminal: object) -> tuple[object, list, list]:
        """``ShootingProblem`` from ``x0`` with the warm start of the papers.

        The guess is the reference posture with zero velocity at every node and the quasi-static
        (gravity-compensating) controls computed at it, clipped to the control bounds.
        """
        problem = self.lib.ShootingProblem(self.x0, list(running), terminal)
        xs = [self.x0.copy() for _ in range(len(running) + 1)]
        us = [
            np.clip(u, m.u_lb, m.u_ub) if m.nu else u
            for u, m in zip(problem.quasiStatic(xs[:-1]), running, strict=True)
        ]
        return problem, xs, us


def swing_point(start: np.ndarray, end: np.ndarray, height: float, s: float) -> np.ndarray:
    """Foot reference at phase ``s`` in [0, 1]: linear in x/y/z, plus a parabolic lift ``4 h s (1 - s)``."""
    p = (1.0 - s) * np.asarray(start, float) + s * np.asarray(end, float)
    p[2] += 4.0 * height * s * (1.0 - s)
    return p
