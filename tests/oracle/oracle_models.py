"""Factories of the oracle suite: the same model built through the same API in crocopy and Crocoddyl.

Every builder takes the library module (``crocopy`` or ``crocoddyl``) as its first argument and
calls only names the two share, so one function describes the model for both.  The suite then
evaluates both models at the same random states and controls and compares every number.

- :data:`RESIDUALS`: residual name → ``builder(lib, ctx)`` and the dynamics kinds it applies to.
- :data:`ACTIVATIONS`: activation name → ``builder(lib, nr)``.
- :data:`DYNAMICS`: dynamics kind → robot, contact/impulse set-up and model builder.
- :data:`INTEGRATORS`: integrator name → ``builder(lib, dam)``: Euler and RK2/3/4, and the same with
  the control parametrizations of :data:`CONTROLS` (``lib.IntegratedActionModelEuler(dam,
  lib.ControlParametrizationModelPolyOne(dam.nu), DT)``); a new entry is crossed with every residual
  (with :data:`CONTROLLED_RESIDUALS` when its name holds a ``-``, to keep the suite fast).

A builder whose class crocopy does not export yet is left out of the crossing (see
:func:`implemented`); :mod:`test_oracle_coverage` asserts the converse, that every residual,
activation, cost and constraint crocopy exports has a builder here.
"""

from __future__ import annotations

import dataclasses
import functools
from collections.abc import Callable
from types import ModuleType
from typing import Any

import example_robot_data
import numpy as np
import pinocchio as pin

DT = 1e-2
SEED = 20240613


@functools.cache
def robot(name: str) -> pin.Model:
    """Pinocchio model of an example-robot-data robot (cached, shared by both libraries)."""
    return example_robot_data.load(name).model


@dataclasses.dataclass
class Context:
    """What a residual builder needs: the library's state and actuation, ``nu`` and the frames."""

    lib: ModuleType
    state: Any
    actuation: Any
    nu: int
    frame: int
    contact_frame: int
    nc: int


def _rng(tag: str) -> np.random.Generator:
    """A generator seeded by ``tag`` so both libraries draw the same references."""
    return np.random.default_rng([SEED, *tag.encode()])


def _cone_rotation() -> np.ndarray:
    return pin.rpy.rpyToMatrix(0.2, -0.1, 0.3)


# ----------------------------------------------------------------------------------------- residuals
def _state(lib, c: Context):
    r = _rng("state")
    m = c.state.pinocchio
    q = pin.integrate(m, pin.neutral(m), 0.2 * r.normal(size=m.nv))
    return lib.ResidualModelState(c.state, np.concatenate([q, r.normal(size=m.nv)]), c.nu)


def _control(lib, c: Context):
    return lib.ResidualModelControl(c.state, _rng("control").normal(size=c.nu))


def _com(lib, c: Context):
    return lib.ResidualModelCoMPosition(c.state, _rng("com").normal(size=3), c.nu)


def _centroidal(lib, c: Context):
    return lib.ResidualModelCentroidalMomentum(c.state, _rng("centroidal").normal(size=6), c.nu)


def _control_grav(lib, c: Context):
    return lib.ResidualModelControlGrav(c.state, c.nu)


def _joint_effort(lib, c: Context):
    return lib.ResidualModelJointEffort(c.state, c.actuation, _rng("effort").normal(size=c.actuation.nu), c.nu)


def _joint_effort_fwddyn(lib, c: Context):
    uref = _rng("effort").normal(size=c.actuation.nu)
    return lib.ResidualModelJointEffort(c.state, c.actuation, uref, c.nu, True)


def _joint_acceleration(lib, c: Context):
    return lib.ResidualModelJointAcceleration(c.state, _rng("acc").normal(size=c.state.nv), c.nu)


def _placement(lib, c: Context):
    r = _rng("placement")
    return lib.ResidualModelFramePlacement(c.state, c.frame, pin.SE3(pin.exp3(r.normal(size=3)), r.normal(size=3)),
                                           c.nu)


def _rotation(lib, c: Context):
    return lib.ResidualModelFrameRotation(c.state, c.frame, pin.exp3(_rng("rotation").normal(size=3)), c.nu)


def _translation(lib, c: Context):
    return lib.ResidualModelFrameTranslation(c.state, c.frame, _rng("translation").normal(size=3), c.nu)


def _velocity(reference_frame: pin.ReferenceFrame) -> Callable:
    def build(lib, c: Context):
        vref = pin.Motion(_rng("velocity").normal(size=6))
        return lib.ResidualModelFrameVelocity(c.state, c.frame, vref, reference_frame, c.nu)

    return build


def _contact_force(lib, c: Context):
    return lib.ResidualModelContactForce(c.state, c.contact_frame, pin.Force(_rng("force").normal(size=6)), c.nc, c.nu)


def _friction_cone(lib, c: Context):
    cone = lib.FrictionCone(_cone_rotation(), 0.7, 4, False, 0.0, 100.0)
    return lib.ResidualModelContactFrictionCone(c.state, c.contact_frame, cone, c.nu)


def _wrench_cone(lib, c: Context):
    cone = lib.WrenchCone(_cone_rotation(), 0.6, np.array([0.1, 0.05]), 4, False, 0.0, 100.0)
    return lib.ResidualModelContactWrenchCone(c.state, c.contact_frame, cone, c.nu)


def _cop(lib, c: Context):
    support = lib.CoPSupport(_cone_rotation(), np.array([0.1, 0.05]))
    return lib.ResidualModelContactCoPPosition(c.state, c.contact_frame, support, c.nu)


def _contact_control_grav(lib, c: Context):
    return lib.ResidualModelContactControlGrav(c.state, c.nu)


def _impulse_com(lib, c: Context):
    return lib.ResidualModelImpulseCoM(c.state)


FREE, CONTACT3, CONTACT6, IMPULSE3, IMPULSE6 = "free", "contact3d", "contact6d", "impulse3d", "impulse6d"
CONTACT1, CONTACT2, CONTACT_WORLD, IMPULSE_WORLD = "contact1d", "contact2d", "contact-world", "impulse-world"
FREE_INV, CONTACT3_INV, CONTACT6_INV = "free_invdyn", "contact3d_invdyn", "contact6d_invdyn"
INVDYN = (FREE_INV, CONTACT3_INV, CONTACT6_INV)
ALL = (FREE, CONTACT3, CONTACT6, IMPULSE3, IMPULSE6, CONTACT1, CONTACT2, CONTACT_WORLD, IMPULSE_WORLD, *INVDYN)
ACTUATED = (FREE, CONTACT3, CONTACT6, CONTACT1, CONTACT2, CONTACT_WORLD)
CONTACTS = (CONTACT3, CONTACT6, CONTACT1, CONTACT2, CONTACT_WORLD)
#: a force residual needs a 3D or 6D force on its frame (or, for contact_force, a 1D contact; Crocoddyl
#: refuses the 2D contact there), the friction cone a 2D contact or more, the wrench cone and CoP a 6D one
CONTACT_AND_IMPULSE = (CONTACT3, CONTACT6, IMPULSE3, IMPULSE6, CONTACT_WORLD, IMPULSE_WORLD)
SIX_D = (CONTACT6, IMPULSE6, CONTACT_WORLD, IMPULSE_WORLD)
IMPULSES = (IMPULSE3, IMPULSE6, IMPULSE_WORLD)


@dataclasses.dataclass(frozen=True)
class ResidualSpec:
    """A residual builder, the class it builds and the dynamics kinds whose data collector serves it."""

    cls: str
    build: Callable
    kinds: tuple[str, ...]


RESIDUALS: dict[str, ResidualSpec] = {
    "state": ResidualSpec("ResidualModelState", _state, ALL),
    "control": ResidualSpec("ResidualModelControl", _control, (*ACTUATED, *INVDYN)),
    "com": ResidualSpec("ResidualModelCoMPosition", _com, ALL),
    "centroidal": ResidualSpec("ResidualModelCentroidalMomentum", _centroidal, ALL),
    # Crocoddyl rejects the contact dynamics' data collector for this residual (crocopy accepts it)
    "control_grav": ResidualSpec("ResidualModelControlGrav", _control_grav, (FREE,)),
    "joint_effort": ResidualSpec("ResidualModelJointEffort", _joint_effort, (*ACTUATED, *INVDYN)),
    "joint_effort_fwddyn": ResidualSpec("ResidualModelJointEffort", _joint_effort_fwddyn, ACTUATED),
    "joint_acceleration": ResidualSpec("ResidualModelJointAcceleration", _joint_acceleration, (*ACTUATED, *INVDYN)),
    "frame_placement": ResidualSpec("ResidualModelFramePlacement", _placement, ALL),
    "frame_rotation": ResidualSpec("ResidualModelFrameRotation", _rotation, ALL),
    "frame_translation": ResidualSpec("ResidualModelFrameTranslation", _translation, ALL),
    "frame_velocity_local": ResidualSpec("ResidualModelFrameVelocity", _velocity(pin.LOCAL), ALL),
    "frame_velocity_world": ResidualSpec("ResidualModelFrameVelocity", _velocity(pin.WORLD), ALL),
    "frame_velocity_lwa": ResidualSpec("ResidualModelFrameVelocity", _velocity(pin.LOCAL_WORLD_ALIGNED), ALL),
    "contact_force": ResidualSpec("ResidualModelContactForce", _contact_force,
                                  (*CONTACT_AND_IMPULSE, CONTACT1, CONTACT3_INV, CONTACT6_INV)),
    "friction_cone": ResidualSpec("ResidualModelContactFrictionCone", _friction_cone,
                                  (*CONTACT_AND_IMPULSE, CONTACT2, CONTACT3_INV, CONTACT6_INV)),
    "wrench_cone": ResidualSpec("ResidualModelContactWrenchCone", _wrench_cone, (*SIX_D, CONTACT6_INV)),
    "cop_position": ResidualSpec("ResidualModelContactCoPPosition", _cop, (*SIX_D, CONTACT6_INV)),
    "contact_control_grav": ResidualSpec("ResidualModelContactControlGrav", _contact_control_grav, CONTACTS),
    "impulse_com": ResidualSpec("ResidualModelImpulseCoM", _impulse_com, IMPULSES),
}


# --------------------------------------------------------------------------------------- activations
def _bounds(lib, nr: int):
    r = _rng(f"bounds{nr}")
    return lib.ActivationBounds(-np.abs(r.normal(size=nr)), np.abs(r.normal(size=nr)), 1.0)


def _weights(nr: int) -> np.ndarray:
    return 0.5 + _rng(f"weights{nr}").random(nr)


ACTIVATIONS: dict[str, tuple[str, Callable]] = {
    "quad": ("ActivationModelQuad", lambda lib, nr: lib.ActivationModelQuad(nr)),
    "weighted_quad": ("ActivationModelWeightedQuad", lambda lib, nr: lib.ActivationModelWeightedQuad(_weights(nr))),
    "quad_barrier": ("ActivationModelQuadraticBarrier",
                     lambda lib, nr: lib.ActivationModelQuadraticBarrier(_bounds(lib, nr))),
    "weighted_quad_barrier": ("ActivationModelWeightedQuadraticBarrier",
                              lambda lib, nr: lib.ActivationModelWeightedQuadraticBarrier(_bounds(lib, nr),
                                                                                          _weights(nr))),
    "smooth1": ("ActivationModelSmooth1Norm", lambda lib, nr: lib.ActivationModelSmooth1Norm(nr, 0.5)),
    "smooth2": ("ActivationModelSmooth2Norm", lambda lib, nr: lib.ActivationModelSmooth2Norm(nr, 0.5)),
    "norm_barrier": ("ActivationModel2NormBarrier", lambda lib, nr: lib.ActivationModel2NormBarrier(nr, 2.0, False)),
    "norm_barrier_true_hessian": ("ActivationModel2NormBarrier",
                                  lambda lib, nr: lib.ActivationModel2NormBarrier(nr, 2.0, True)),
    "quad_flat_exp": ("ActivationModelQuadFlatExp", lambda lib, nr: lib.ActivationModelQuadFlatExp(nr, 1.5)),
    "quad_flat_log": ("ActivationModelQuadFlatLog", lambda lib, nr: lib.ActivationModelQuadFlatLog(nr, 1.5)),
}


# ---------------------------------------------------------------------------------------- dynamics
@dataclasses.dataclass(frozen=True)
class DynamicsSpec:
    """Robot, frames and contact set-up of a dynamics kind (``supports``: ``(frame, type, gains)``).

    ``nc`` is the dimension of every support unless ``dims`` gives one per support (the residuals read
    the first); ``integrators`` restricts the integrators crossed with the kind (None: all).
    """

    robot: str
    frame: str
    supports: tuple[tuple[str, Any, tuple[float, float]], ...]
    nc: int
    impulse: bool
    inv_damping: float = 0.0
    r_coeff: float = 0.0
    invdyn: bool = False
    dims: tuple[int, ...] = ()
    integrators: tuple[str, ...] | None = None


_LOCAL, _LWA, _WORLD = pin.LOCAL, pin.LOCAL_WORLD_ALIGNED, pin.WORLD
_FEW = ("euler", "rk4")
_FEET = ("LF_FOOT", "RF_FOOT", "LH_FOOT", "RH_FOOT")
_SOLES = ("left_sole_link", "right_sole_link")
DYNAMICS: dict[str, DynamicsSpec] = {
    FREE: DynamicsSpec("anymal", "LF_FOOT", (), 0, False),
    CONTACT3: DynamicsSpec("anymal", "RF_KFE",
                           tuple((f, t, g) for f, t, g in zip(_FEET, (_LOCAL, _LWA, _LWA, _LOCAL),
                                                              ((0.0, 40.0), (10.0, 5.0), (0.0, 0.0), (3.0, 0.0)))),
                           3, False),
    CONTACT6: DynamicsSpec("talos_legs", "right_sole_link",
                           ((_SOLES[0], _LOCAL, (5.0, 10.0)), (_SOLES[1], _LWA, (0.0, 30.0))), 6, False),
    IMPULSE3: DynamicsSpec("anymal", "RF_KFE", tuple((f, t, (0.0, 0.0)) for f, t in zip(_FEET[:3],
                                                                                         (_LOCAL, _LWA, _LWA))),
                           3, True),
    IMPULSE6: DynamicsSpec("talos_legs", "right_sole_link", ((_SOLES[0], _LOCAL, (0.0, 0.0)),), 6, True, r_coeff=0.3),
    CONTACT1: DynamicsSpec("anymal", "RF_KFE",
                           tuple((f, t, g) for f, t, g in zip(_FEET, (_LOCAL, _LWA, _WORLD, _LOCAL),
                                                              ((5.0, 3.0), (0.0, 10.0), (2.0, 0.0), (0.0, 0.0)))),
                           1, False, dims=(1, 1, 1, 3), integrators=_FEW),
    CONTACT2: DynamicsSpec("anymal", "RF_KFE",
                           tuple((f, _LOCAL, g) for f, g in zip(_FEET, ((5.0, 3.0), (0.0, 10.0), (2.0, 0.0),
                                                                        (0.0, 0.0)))),
                           2, False, integrators=_FEW),
    CONTACT_WORLD: DynamicsSpec("talos_legs", "right_sole_link",
                                ((_SOLES[0], _WORLD, (5.0, 10.0)), (_SOLES[1], _WORLD, (3.0, 30.0))), 6, False,
                                dims=(6, 3), integrators=_FEW),
    IMPULSE_WORLD: DynamicsSpec("talos_legs", "right_sole_link", ((_SOLES[0], _WORLD, (0.0, 0.0)),
                                                                   (_SOLES[1], _WORLD, (0.0, 0.0))), 6, True,
                                dims=(6, 3)),
}
#: the inverse-dynamics kinds are crossed with these integrators only (their differential model is what
#: is new; the Runge-Kutta cases are the slow ones, their Jacobians being proven against numdiff)
INVDYN_INTEGRATORS = ("euler", "rk4", "euler-poly1", "rk3-poly2rk3")
DYNAMICS[FREE_INV] = dataclasses.replace(DYNAMICS[FREE], invdyn=True, integrators=INVDYN_INTEGRATORS)
DYNAMICS[CONTACT3_INV] = dataclasses.replace(DYNAMICS[CONTACT3], invdyn=True, integrators=INVDYN_INTEGRATORS)
DYNAMICS[CONTACT6_INV] = dataclasses.replace(DYNAMICS[CONTACT6], invdyn=True, integrators=INVDYN_INTEGRATORS)


def context(lib, kind: str) -> Context:
    """The state, actuation and frames of dynamics ``kind`` in ``lib``."""
    spec = DYNAMICS[kind]
    model = robot(spec.robot)
    state = lib.StateMultibody(model)
    actuation = lib.ActuationModelFloatingBase(state)
    nu = 0 if spec.impulse else actuation.nu
    if spec.invdyn:  # the control is (a, f): accelerations, then every contact's force
        nu = model.nv + spec.nc * len(spec.supports)
    contact_frame = model.getFrameId(spec.supports[0][0]) if spec.supports else model.getFrameId(spec.frame)
    return Context(lib, state, actuation, nu, model.getFrameId(spec.frame), contact_frame, spec.nc)


def _contact(lib, c: Context, fid: int, typ, gains: np.ndarray, dim: int, r: np.random.Generator):
    if dim == 1:
        return lib.ContactModel1D(c.state, fid, float(r.normal()), typ, pin.exp3(r.normal(size=3)), c.nu, gains)
    if dim == 2:
        return lib.ContactModel2D(c.state, fid, r.normal(size=2), c.nu, gains)
    if dim == 3:
        return lib.ContactModel3D(c.state, fid, r.normal(size=3), typ, c.nu, gains)
    ref = pin.SE3(pin.exp3(0.3 * r.normal(size=3)), r.normal(size=3))
    return lib.ContactModel6D(c.state, fid, ref, typ, c.nu, gains)


def _supports(lib, c: Context, spec: DynamicsSpec):
    model = c.state.pinocchio
    dims = spec.dims or (spec.nc,) * len(spec.supports)
    if spec.impulse:
        stack = lib.ImpulseModelMultiple(c.state)
        for (name, typ, _), dim in zip(spec.supports, dims):
            cls = lib.ImpulseModel3D if dim == 3 else lib.ImpulseModel6D
            stack.addImpulse(name, cls(c.state, model.getFrameId(name), typ))
        return stack
    stack = lib.ContactModelMultiple(c.state, c.nu)
    r = _rng("supports")
    for (name, typ, gains), dim in zip(spec.supports, dims):
        stack.addContact(name, _contact(lib, c, model.getFrameId(name), typ, np.array(gains), dim, r))
    return stack


def dynamics(lib, kind: str, c: Context, costs, constraints):
    """The differential action model (free, contact) or the impulse action model of ``kind``."""
    spec = DYNAMICS[kind]
    with_constraints = () if constraints is None else (constraints,)  # Crocoddyl crashes on None
    if kind == FREE:
        return lib.DifferentialActionModelFreeFwdDynamics(c.state, c.actuation, costs, *with_constraints)
    if kind == FREE_INV:
        return lib.DifferentialActionModelFreeInvDynamics(c.state, c.actuation, costs, *with_constraints)
    supports = _supports(lib, c, spec)
    if spec.invdyn:
        return lib.DifferentialActionModelContactInvDynamics(c.state, c.actuation, supports, costs, *with_constraints)
    if spec.impulse:
        return lib.ActionModelImpulseFwdDynamics(c.state, supports, costs, *with_constraints, spec.r_coeff,
                                                 spec.inv_damping, True)
    return lib.DifferentialActionModelContactFwdDynamics(c.state, c.actuation, supports, costs, *with_constraints,
                                                         spec.inv_damping, True)


# ------------------------------------------------------------------------------------- integrators
def _rk(rk: str) -> Callable:
    return lambda lib, dam: lib.IntegratedActionModelRK(dam, getattr(lib.RKType, rk), DT)


def _controlled(rk: str | None, control: Callable) -> Callable:
    """An integrator taking a control parametrization (``rk``: None for Euler, else the RKType name)."""
    def build(lib, dam):
        if rk is None:
            return lib.IntegratedActionModelEuler(dam, control(lib, dam.nu), DT)
        return lib.IntegratedActionModelRK(dam, control(lib, dam.nu), getattr(lib.RKType, rk), DT)

    return build


CONTROLS: dict[str, Callable] = {
    "poly0": lambda lib, nw: lib.ControlParametrizationModelPolyZero(nw),
    "poly1": lambda lib, nw: lib.ControlParametrizationModelPolyOne(nw),
    "poly2rk3": lambda lib, nw: lib.ControlParametrizationModelPolyTwoRK(nw, lib.RKType.three),
    "poly2rk4": lambda lib, nw: lib.ControlParametrizationModelPolyTwoRK(nw, lib.RKType.four),
}
INTEGRATORS: dict[str, Callable] = {
    "euler": lambda lib, dam: lib.IntegratedActionModelEuler(dam, DT),
    "rk2": _rk("two"),
    "rk3": _rk("three"),
    "rk4": _rk("four"),
    "euler-poly0": _controlled(None, CONTROLS["poly0"]),
    "euler-poly1": _controlled(None, CONTROLS["poly1"]),
    "rk2-poly1": _controlled("two", CONTROLS["poly1"]),
    "rk3-poly2rk3": _controlled("three", CONTROLS["poly2rk3"]),
    "rk4-poly2rk4": _controlled("four", CONTROLS["poly2rk4"]),
}
#: the integrators with a control parametrization are crossed with these residuals only (the
#: parametrization acts between the integrator and the differential model, whatever the cost)
CONTROLLED_RESIDUALS = ("state", "control", "joint_effort", "joint_acceleration", "com", "frame_velocity_world",
                        "contact_force", "friction_cone")


def crossed(integrator: str, residual: str, kind: str = FREE) -> bool:
    """Whether the node suite crosses ``integrator`` with ``residual`` under dynamics ``kind``."""
    chosen = DYNAMICS[kind].integrators
    if chosen is not None and integrator not in chosen:
        return False
    return "-" not in integrator or residual in CONTROLLED_RESIDUALS


# ---------------------------------------------------------------------------------------- the node
def node(lib, kind: str, residual: str, integrator: str | None, activations: tuple[str, ...]):
    """The action model of one oracle case: residual ``residual`` as a cost under every activation in
    ``activations`` (plus an inactive copy), as an equality and as an inequality constraint, in the
    dynamics of ``kind``, integrated by ``integrator`` (``None``: the differential or impulse model)."""
    c = context(lib, kind)
    spec = RESIDUALS[residual]
    costs = lib.CostModelSum(c.state, c.nu)
    nr = spec.build(lib, c).nr
    weights = 1.0 + _rng("cost-weights").random(len(activations))
    for name, weight in zip(activations, weights):
        activation = ACTIVATIONS[name][1](lib, nr)
        costs.addCost(name, lib.CostModelResidual(c.state, activation, spec.build(lib, c)), float(weight))
    costs.addCost("default", lib.CostModelResidual(c.state, spec.build(lib, c)), 0.5)
    costs.addCost("inactive", lib.CostModelResidual(c.state, spec.build(lib, c)), 7.0, False)
    constraints = lib.ConstraintModelManager(c.state, c.nu)
    constraints.addConstraint("eq", lib.ConstraintModelResidual(c.state, spec.build(lib, c)))
    constraints.addConstraint("eq_running", lib.ConstraintModelResidual(c.state, spec.build(lib, c), False))
    bounds = _rng("constraint-bounds").normal(size=(2, nr))
    constraints.addConstraint("ineq", lib.ConstraintModelResidual(c.state, spec.build(lib, c), bounds.min(0),
                                                                  bounds.max(0)))
    model = dynamics(lib, kind, c, costs, constraints)
    if integrator is None or DYNAMICS[kind].impulse:
        return model
    return INTEGRATORS[integrator](lib, model)


def implemented(lib: ModuleType, cls: str) -> bool:
    """Whether ``lib`` exports class ``cls`` (crocopy may not implement every Crocoddyl class yet)."""
    try:
        getattr(lib, cls)
    except (AttributeError, NotImplementedError):
        return False
    return True


def sample(kind: str, nu: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """A random state (configuration near the neutral one, any velocity) and control of ``kind``."""
    model = robot(DYNAMICS[kind].robot)
    rng = np.random.default_rng([SEED, seed])
    q = pin.integrate(model, pin.neutral(model), 0.4 * rng.normal(size=model.nv))
    return np.concatenate([q, rng.normal(size=model.nv)]), 5.0 * rng.normal(size=nu)


# ------------------------------------------------------------------------------------ the numbers
ACTION_FIELDS = ("xnext", "cost", "Fx", "Fu", "Lx", "Lu", "Lxx", "Lxu", "Luu", "g", "Gx", "Gu", "h", "Hx", "Hu")
DIFF_FIELDS = ("xout", "cost", "Fx", "Fu", "Lx", "Lu", "Lxx", "Lxu", "Luu", "g", "Gx", "Gu", "h", "Hx", "Hu")
COST_FIELDS = ("cost", "Lx", "Lu", "Lxx", "Lxu", "Luu")
RESIDUAL_FIELDS = ("r", "Rx", "Ru")
ACTIVATION_FIELDS = ("a_value", "Ar", "Arr")
CONSTRAINT_FIELDS = ("g", "Gx", "Gu", "h", "Hx", "Hu")


def _grab(obj, names, prefix: str, out: dict[str, np.ndarray]) -> None:
    for name in names:
        value = getattr(obj, name, None)
        if value is not None:
            out[prefix + name] = np.array(value, dtype=float, copy=True)


def _stack_items(data, prefix: str, costs, constraints, out: dict[str, np.ndarray]) -> None:
    for name in costs:
        item = data.costs.costs[name]
        _grab(item, COST_FIELDS, f"{prefix}cost[{name}].", out)
        _grab(item.residual, RESIDUAL_FIELDS, f"{prefix}cost[{name}].residual.", out)
        _grab(item.activation, ACTIVATION_FIELDS, f"{prefix}cost[{name}].activation.", out)
    for name in constraints if getattr(data, "constraints", None) is not None else ():
        item = data.constraints.constraints[name]
        _grab(item, CONSTRAINT_FIELDS, f"{prefix}constraint[{name}].", out)
        _grab(item.residual, RESIDUAL_FIELDS, f"{prefix}constraint[{name}].residual.", out)


def active_constraints(model) -> tuple[str, ...]:
    """Names of the active constraint items of a node's (differential) model: the node's ``eq``,
    ``eq_running`` and ``ineq``, plus those an inverse-dynamics model adds (``tau``, ``<contact>_acc``)."""
    dam = getattr(model, "differential", model)
    manager = getattr(dam, "constraints", None)
    if manager is None:
        return ()
    items = manager.constraints
    names = items.todict() if hasattr(items, "todict") else items
    return tuple(name for name in names if manager.getConstraintStatus(name))


def numbers(model, data, costs: tuple[str, ...], constraints=None) -> dict[str, np.ndarray]:
    """Every number of an evaluated node: the action data, each differential (stage) data and every
    active cost and constraint item's data (cost, residual, activation), keyed by a readable path
    (``constraints``: the item names, default :func:`active_constraints`)."""
    if constraints is None:
        constraints = active_constraints(model)
    out: dict[str, np.ndarray] = {}
    differential = getattr(data, "differential", None)
    if differential is None:  # an impulse model or a bare differential model
        _grab(data, ACTION_FIELDS if hasattr(data, "xnext") else DIFF_FIELDS, "", out)
        _stack_items(data, "", costs, constraints, out)
        return out
    _grab(data, ACTION_FIELDS, "", out)
    stages = differential if isinstance(differential, (list, tuple)) or hasattr(differential, "__len__") else [
        differential]
    for i, stage in enumerate(stages):
        _grab(stage, DIFF_FIELDS, f"differential[{i}].", out)
        _stack_items(stage, f"differential[{i}].", costs, constraints, out)
    return out


def evaluate(model, x: np.ndarray, u: np.ndarray | None, costs: tuple[str, ...]) -> dict[str, np.ndarray]:
    """``calc`` then ``calcDiff`` at ``(x, u)`` (``u=None``: the terminal node); :func:`numbers`."""
    data = model.createData()
    if u is None:
        model.calc(data, x)
        model.calcDiff(data, x)
    else:
        model.calc(data, x, u)
        model.calcDiff(data, x, u)
    return numbers(model, data, costs)


def differences(mine: dict[str, np.ndarray], theirs: dict[str, np.ndarray]) -> dict[str, float]:
    """Relative difference ``max|a - b| / max(1, max|b|)`` of every number both libraries hold."""
    out = {}
    for key, b in theirs.items():
        if key not in mine:
            out[key] = float("inf")
            continue
        a = mine[key]
        if a.shape != b.shape:
            out[key] = float("inf") if a.size or b.size else 0.0
            continue
        out[key] = float(np.abs(a - b).max() / max(1.0, np.abs(b).max())) if b.size else 0.0
    return out


# ------------------------------------------------------------------- each library against itself
#: value → its Jacobians with respect to ``x`` and ``u``
JACOBIANS = {"r": ("Rx", "Ru"), "xnext": ("Fx", "Fu"), "xout": ("Fx", "Fu"), "g": ("Gx", "Gu"), "h": ("Hx", "Hu"),
             "cost": ("Lx", "Lu")}


def split_key(key: str) -> tuple[str, str]:
    """``"differential[0].cost[quad].residual.Rx"`` → ``("differential[0].cost[quad].residual.", "Rx")``."""
    head, _, last = key.rpartition(".")
    return (head + "." if head else ""), last


def value_key(key: str) -> str | None:
    """The value whose Jacobian ``key`` is (``...Rx`` → ``...r``), or None for a value or a Hessian."""
    head, last = split_key(key)
    if last in JACOBIANS["xout"]:  # a stage's dynamics (differential data) or the node's (action data)
        return head + ("xout" if head.startswith("differential[") else "xnext")
    for value, jacobians in JACOBIANS.items():
        if last in jacobians:
            return head + value
    return None


def numeric_jacobians(model, x: np.ndarray, u: np.ndarray | None, keys, costs: tuple[str, ...],
                      step: float = 1e-6) -> dict[str, np.ndarray]:
    """Central differences of the values ``keys`` (computed by ``calc`` alone) along the tangent of
    ``x`` and along ``u``, each of shape ``(size, ndx + nu)`` (``xnext`` through ``state.diff``); one
    sweep of ``2 (ndx + nu)`` evaluations serves every key."""
    state = model.state
    data = model.createData()
    nu = 0 if u is None else u.size
    keys = tuple(keys)

    def values(dx: np.ndarray, du: np.ndarray) -> list[np.ndarray]:
        if u is None:
            model.calc(data, state.integrate(x, dx))
        else:
            model.calc(data, state.integrate(x, dx), u + du)
        found = numbers(model, data, costs)
        return [found[key].reshape(-1) for key in keys]

    base = values(np.zeros(state.ndx), np.zeros(nu))
    columns: list[list[np.ndarray]] = [[] for _ in keys]
    for i in range(state.ndx + nu):
        e = np.zeros(state.ndx + nu)
        e[i] = step
        plus, minus = values(e[: state.ndx], e[state.ndx :]), values(-e[: state.ndx], -e[state.ndx :])
        for k, key in enumerate(keys):
            p, m = plus[k], minus[k]
            if key.endswith("xnext"):
                p, m = state.diff(base[k], p), state.diff(base[k], m)
            columns[k].append((p - m) / (2 * step))
    return {key: np.array(cols).T for key, cols in zip(keys, columns)}


def analytic_jacobian(found: dict[str, np.ndarray], key: str) -> np.ndarray:
    """``[Kx, Ku]`` of value ``key`` from an evaluated node's numbers (``Ku`` absent on terminal nodes)."""
    head, last = split_key(key)
    jx, ju = JACOBIANS[last]
    blocks = [found[head + jx].reshape(-1, found[head + jx].shape[-1])]
    if head + ju in found and found[head + ju].size:
        blocks.append(found[head + ju].reshape(blocks[0].shape[0], -1))
    return np.hstack(blocks)
