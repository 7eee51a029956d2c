"""``copy``, ``deepcopy`` and ``pickle`` of every public model and its data.

Every public model class gets a case: the model inside a host (an action or differential action
model that evaluates it) and a locator of its data inside the host's data.  The host and its data
are evaluated at a first point, copied (``copy.copy`` of the host, ``deepcopy`` or a pickle round
trip of the host with its data), and then the original and the copy are evaluated at a second
point: every output, and every array of the component's data, must agree.  Data share memory
(cost sums stack their residuals; squashing keeps a view of a Jacobian's diagonal), so a copy that
lost a view would keep stale values here.  The list of cases is checked against crocopy's public
classes so that a new model cannot be left out.
"""

from __future__ import annotations

import copy
import pickle
import re
from collections.abc import Callable

import numpy as np
import pinocchio as pin
import pytest
from robots import load
from test_batch import _dlqr, _limited_unicycle

import crocopy
from crocopy.problems.user_residual import NumbaFrameTranslation

OUTPUTS = ("cost", "xnext", "xout", "Fx", "Fu", "Lx", "Lu", "Lxx", "Lxu", "Luu", "g", "Gx", "Gu", "h", "Hx", "Hu")
PART_ARRAYS = ("r", "Rx", "Ru", "Ar", "Arr", "a_value", "tau", "dtau_dx", "dtau_du", "u", "du_ds", "Jc", "a0",
               "da0_dx", "f", "g", "Gx", "Gu", "h", "Hx", "Hu", "cost", "Lx", "Lxx", "dv0_dq")


# ---------------------------------------------------------------------------------------------- hosts
def _pendulum():
    return crocopy.StateMultibody(load("double_pendulum"))


def _free(state=None, cost=None, actuation=None, constraints=None, activation=None):
    """Free dynamics with a state cost (optionally the given cost, activation or constraints)."""
    state = state or _pendulum()
    actuation = actuation or crocopy.ActuationModelFull(state)
    nu = actuation.nu
    costs = crocopy.CostModelSum(state, nu)
    costs.addCost("u", crocopy.CostModelResidual(state, crocopy.ResidualModelControl(state, nu)), 0.1)
    residual = crocopy.ResidualModelState(state, state.zero(), nu)
    if activation is not None:
        costs.addCost("act", crocopy.CostModelResidual(state, activation, residual), 1.0)
    if cost is not None:
        costs.addCost("cost", cost(state, nu), 1.0)
    return crocopy.DifferentialActionModelFreeFwdDynamics(state, actuation, costs, constraints)


def _residual_case(make: Callable) -> Callable:
    """A residual ``make(state, nu)`` as a cost of free dynamics; locator: its residual data."""

    def build():
        dam = _free(cost=lambda st, nu: crocopy.CostModelResidual(st, make(st, nu)))
        return dam, dam.costs.costs["cost"].cost.residual, lambda d: d.costs.costs["cost"].residual

    return build


def _activation_case(make: Callable) -> Callable:
    def build():
        activation = make(4)
        dam = _free(activation=activation)
        return dam, activation, lambda d: d.costs.costs["act"].activation

    return build


_ROT = pin.rpy.rpyToMatrix(0.3, -0.2, 0.5)
_BOX = np.array([0.2, 0.1])


def _contact_dam(extra: Callable | None = None, nc: int = 6):
    """Talos legs on one 6D (or anymal on one 3D, 2D or 1D) contact with contact residual costs."""
    robot, foot = ("talos_legs", "left_sole_link") if nc == 6 else ("anymal", "LF_FOOT")
    model = load(robot)
    state = crocopy.StateMultibody(model)
    act = crocopy.ActuationModelFloatingBase(state)
    fid = model.getFrameId(foot)
    contacts = crocopy.ContactModelMultiple(state, act.nu)
    if nc == 6:
        contact = crocopy.ContactModel6D(state, fid, pin.SE3.Identity(), pin.LOCAL, act.nu, np.array([0.0, 2.0]))
    elif nc == 2:
        contact = crocopy.ContactModel2D(state, fid, np.zeros(2), act.nu, np.array([1.0, 2.0]))
    elif nc == 1:
        contact = crocopy.ContactModel1D(state, fid, 0.1, pin.WORLD, _ROT, act.nu, np.array([1.0, 2.0]))
    else:
        contact = crocopy.ContactModel3D(state, fid, np.zeros(3), pin.LOCAL_WORLD_ALIGNED, act.nu, np.array([1.0, 2.0]))
    contacts.addContact("foot", contact)
    costs = crocopy.CostModelSum(state, act.nu)
    costs.addCost("x", crocopy.CostModelResidual(state, crocopy.ResidualModelState(state, state.zero(), act.nu)), 1.0)
    if extra is not None:
        costs.addCost("extra", crocopy.CostModelResidual(state, extra(state, fid, act.nu)), 1.0)
    return crocopy.DifferentialActionModelContactFwdDynamics(state, act, contacts, costs, 0.0, True)


def _contact_residual_case(make: Callable, nc: int = 6) -> Callable:
    def build():
        dam = _contact_dam(make, nc)
        return dam, dam.costs.costs["extra"].cost.residual, lambda d: d.costs.costs["extra"].residual

    return build


def _impulse(kind: str = "6D"):
    model = load("talos_legs")
    state = crocopy.StateMultibody(model)
    impulses = crocopy.ImpulseModelMultiple(state)
    cls = crocopy.ImpulseModel6D if kind == "6D" else crocopy.ImpulseModel3D
    impulses.addImpulse("foot", cls(state, model.getFrameId("left_sole_link"), pin.LOCAL_WORLD_ALIGNED))
    costs = crocopy.CostModelSum(state, 0)
    costs.addCost("x", crocopy.CostModelResidual(state, crocopy.ResidualModelState(state, state.zero(), 0)), 1.0)
    costs.addCost("com", crocopy.CostModelResidual(state, crocopy.ResidualModelImpulseCoM(state)), 1.0)
    return crocopy.ActionModelImpulseFwdDynamics(state, impulses, costs, 0.3, 0.0, True)


def _itself(make: Callable) -> Callable:
    def build():
        model = make()
        return model, model, None

    return build


def _thrusters():
    state = crocopy.StateMultibody(load("talos_legs"))
    thrusters = [
        crocopy.Thruster(pin.SE3(np.eye(3), np.array(p)), 0.1, t)
        for p, t in (([0.2, 0.0, 0.0], crocopy.ThrusterType.CW), ([0.0, 0.2, 0.0], crocopy.ThrusterType.CCW))
    ]
    return crocopy.ActuationModelFloatingBaseThrusters(state, thrusters)


def _actuation_case(make: Callable) -> Callable:
    def build():
        actuation = make()
        dam = _free(state=actuation.state, actuation=actuation)
        return dam, actuation, lambda d: d.multibody.actuation

    return build


def _squashed(state):
    full = crocopy.ActuationModelFull(state)
    squashing = crocopy.SquashingModelSmoothSat(-np.ones(full.nu), 2.0 * np.ones(full.nu), full.nu)
    return crocopy.ActuationSquashingModel(full, squashing, full.nu)


def _constraint_dam():
    state = _pendulum()
    manager = crocopy.ConstraintModelManager(state, state.nv)
    residual = crocopy.ResidualModelState(state, state.zero(), state.nv)
    manager.addConstraint("ineq", crocopy.ConstraintModelResidual(state, residual, -np.ones(4), np.ones(4)))
    manager.addConstraint("eq", crocopy.ConstraintModelResidual(state, crocopy.ResidualModelControl(state, 2)))
    return _free(state=state, constraints=manager)


def _invdyn(contact: bool):
    """ANYmal under free inverse dynamics, or on two 3D feet under contact inverse dynamics."""
    model = load("anymal")
    state = crocopy.StateMultibody(model)
    act = crocopy.ActuationModelFloatingBase(state)
    nu = state.nv + (6 if contact else 0)
    costs = crocopy.CostModelSum(state, nu)
    costs.addCost("x", crocopy.CostModelResidual(state, crocopy.ResidualModelState(state, state.zero(), nu)), 1.0)
    costs.addCost("tau", crocopy.CostModelResidual(state, crocopy.ResidualModelJointEffort(state, act, nu)), 1.0)
    if not contact:
        return crocopy.DifferentialActionModelFreeInvDynamics(state, act, costs)
    contacts = crocopy.ContactModelMultiple(state, nu)
    for foot in ("LF_FOOT", "RH_FOOT"):
        contact = crocopy.ContactModel3D(state, foot, np.zeros(3), pin.LOCAL_WORLD_ALIGNED, nu, np.array([1.0, 2.0]))
        contacts.addContact(foot, contact)
    return crocopy.DifferentialActionModelContactInvDynamics(state, act, contacts, costs)


CASES: dict[str, Callable] = {
    # action and differential action models (host = the model)
    "ActionModelLQR": _itself(lambda: crocopy.ActionModelLQR.Random(4, 2, 1, 1)),
    "ActionModelUnicycle": _itself(crocopy.ActionModelUnicycle),
    "ActionModelControlPenalty": _itself(lambda: crocopy.ActionModelControlPenalty(_limited_unicycle(), 1e2)),
    "ActionModelSquashed": _itself(lambda: crocopy.ActionModelSquashed(_limited_unicycle(), "smooth-sat")),
    "ActionModelNumDiff": _itself(lambda: crocopy.ActionModelNumDiff(crocopy.ActionModelUnicycle())),
    "ActionModelImpulseFwdDynamics": _itself(_impulse),
    "IntegratedActionModelEuler": _itself(lambda: crocopy.IntegratedActionModelEuler(_free(), 1e-2)),
    "IntegratedActionModelRK": _itself(lambda: crocopy.IntegratedActionModelRK(_dlqr(), crocopy.RKType.four, 1e-2)),
    "DifferentialActionModelLQR": _itself(_dlqr),
    "DifferentialActionModelNumDiff": _itself(lambda: crocopy.DifferentialActionModelNumDiff(_dlqr())),
    "DifferentialActionModelFreeFwdDynamics": _itself(_constraint_dam),
    "DifferentialActionModelContactFwdDynamics": _itself(_contact_dam),
    "DifferentialActionModelFreeInvDynamics": _itself(lambda: _invdyn(False)),
    "DifferentialActionModelContactInvDynamics": _itself(lambda: _invdyn(True)),
    # activations
    "ActivationModelQuad": _activation_case(crocopy.ActivationModelQuad),
    "ActivationModelWeightedQuad": _activation_case(
        lambda n: crocopy.ActivationModelWeightedQuad(np.arange(1.0, n + 1))
    ),
    "ActivationModelQuadraticBarrier": _activation_case(
        lambda n: crocopy.ActivationModelQuadraticBarrier(crocopy.ActivationBounds(-0.1 * np.ones(n), 0.1 * np.ones(n)))
    ),
    "ActivationModelWeightedQuadraticBarrier": _activation_case(
        lambda n: crocopy.ActivationModelWeightedQuadraticBarrier(
            crocopy.ActivationBounds(-0.1 * np.ones(n), 0.1 * np.ones(n)), np.arange(1.0, n + 1)
        )
    ),
    "ActivationModelSmooth1Norm": _activation_case(lambda n: crocopy.ActivationModelSmooth1Norm(n, 0.1)),
    "ActivationModelSmooth2Norm": _activation_case(lambda n: crocopy.ActivationModelSmooth2Norm(n, 0.1)),
    "ActivationModel2NormBarrier": _activation_case(lambda n: crocopy.ActivationModel2NormBarrier(n, 5.0)),
    "ActivationModelQuadFlatExp": _activation_case(lambda n: crocopy.ActivationModelQuadFlatExp(n, 0.5)),
    "ActivationModelQuadFlatLog": _activation_case(lambda n: crocopy.ActivationModelQuadFlatLog(n, 0.5, True)),
    "ActivationModelNumDiff": _activation_case(
        lambda n: crocopy.ActivationModelNumDiff(crocopy.ActivationModelQuad(n))
    ),
    # residuals on free dynamics
    "ResidualModelState": _residual_case(lambda st, nu: crocopy.ResidualModelState(st, st.rand(), nu)),
    "ResidualModelControl": _residual_case(lambda st, nu: crocopy.ResidualModelControl(st, np.ones(nu))),
    "ResidualModelFramePlacement": _residual_case(
        lambda st, nu: crocopy.ResidualModelFramePlacement(st, st.pinocchio.nframes - 1, pin.SE3.Random(), nu)
    ),
    "ResidualModelNumba": _residual_case(
        lambda st, nu: NumbaFrameTranslation(st, st.pinocchio.nframes - 1, np.ones(3), nu)
    ),
    "ResidualModelFrameTranslation": _residual_case(
        lambda st, nu: crocopy.ResidualModelFrameTranslation(st, st.pinocchio.nframes - 1, np.ones(3), nu)
    ),
    "ResidualModelFrameRotation": _residual_case(
        lambda st, nu: crocopy.ResidualModelFrameRotation(st, st.pinocchio.nframes - 1, _ROT, nu)
    ),
    "ResidualModelFrameVelocity": _residual_case(
        lambda st, nu: crocopy.ResidualModelFrameVelocity(
            st, st.pinocchio.nframes - 1, pin.Motion(np.ones(6)), pin.LOCAL_WORLD_ALIGNED, nu
        )
    ),
    "ResidualModelCoMPosition": _residual_case(lambda st, nu: crocopy.ResidualModelCoMPosition(st, np.ones(3), nu)),
    "ResidualModelCentroidalMomentum": _residual_case(
        lambda st, nu: crocopy.ResidualModelCentroidalMomentum(st, np.ones(6), nu)
    ),
    "ResidualModelControlGrav": _residual_case(lambda st, nu: crocopy.ResidualModelControlGrav(st, nu)),
    "ResidualModelJointEffort": _residual_case(
        lambda st, nu: crocopy.ResidualModelJointEffort(st, crocopy.ActuationModelFull(st), np.ones(nu), nu, True)
    ),
    "ResidualModelJointAcceleration": _residual_case(
        lambda st, nu: crocopy.ResidualModelJointAcceleration(st, np.ones(st.nv), nu)
    ),
    # residuals on contact and impulse dynamics
    "ResidualModelContactForce": _contact_residual_case(
        lambda st, fid, nu: crocopy.ResidualModelContactForce(st, fid, pin.Force(np.arange(1.0, 7.0)), 6, nu)
    ),
    "ResidualModelContactFrictionCone": _contact_residual_case(
        lambda st, fid, nu: crocopy.ResidualModelContactFrictionCone(st, fid, crocopy.FrictionCone(_ROT, 0.7, 4), nu),
        nc=3,
    ),
    "ResidualModelContactWrenchCone": _contact_residual_case(
        lambda st, fid, nu: crocopy.ResidualModelContactWrenchCone(st, fid, crocopy.WrenchCone(_ROT, 0.6, _BOX), nu)
    ),
    "ResidualModelContactCoPPosition": _contact_residual_case(
        lambda st, fid, nu: crocopy.ResidualModelContactCoPPosition(st, fid, crocopy.CoPSupport(_ROT, _BOX), nu)
    ),
    "ResidualModelContactControlGrav": _contact_residual_case(
        lambda st, fid, nu: crocopy.ResidualModelContactControlGrav(st, nu)
    ),
    "ResidualModelImpulseCoM": lambda: (
        (m := _impulse()), m.costs.costs["com"].cost.residual, lambda d: d.costs.costs["com"].residual
    ),
    # costs and constraints
    "CostModelResidual": lambda: (
        (dam := _free()), dam.costs.costs["u"].cost, lambda d: d.costs.costs["u"]
    ),
    "CostModelSum": lambda: ((dam := _free()), dam.costs, lambda d: d.costs),
    "ConstraintModelResidual": lambda: (
        (dam := _constraint_dam()), dam.constraints.constraints["ineq"].constraint,
        lambda d: d.constraints.constraints["ineq"],
    ),
    "ConstraintModelManager": lambda: ((dam := _constraint_dam()), dam.constraints, lambda d: d.constraints),
    # actuations and squashing
    "ActuationModelFull": _actuation_case(lambda: crocopy.ActuationModelFull(_pendulum())),
    "ActuationModelFloatingBase": _actuation_case(
        lambda: crocopy.ActuationModelFloatingBase(crocopy.StateMultibody(load("talos_legs")))
    ),
    "ActuationModelFloatingBaseThrusters": _actuation_case(_thrusters),
    "ActuationModelLinear": _actuation_case(lambda: crocopy.ActuationModelLinear(_pendulum(), [[0.0], [1.0]])),
    "ActuationSquashingModel": _actuation_case(lambda: _squashed(_pendulum())),
    "SquashingModelSmoothSat": lambda: (
        (dam := _free(actuation=_squashed(_pendulum()))), dam.actuation.squashing,
        lambda d: d.multibody.actuation.squashing,
    ),
    # contacts and impulses
    "ContactModel6D": lambda: (
        (dam := _contact_dam()), dam.contacts.contacts["foot"].contact, lambda d: d.multibody.contacts.contacts["foot"]
    ),
    "ContactModel3D": lambda: (
        (dam := _contact_dam(nc=3)), dam.contacts.contacts["foot"].contact,
        lambda d: d.multibody.contacts.contacts["foot"],
    ),
    "ContactModel2D": lambda: (
        (dam := _contact_dam(nc=2)), dam.contacts.contacts["foot"].contact,
        lambda d: d.multibody.contacts.contacts["foot"],
    ),
    "ContactModel1D": lambda: (
        (dam := _contact_dam(nc=1)), dam.contacts.contacts["foot"].contact,
        lambda d: d.multibody.contacts.contacts["foot"],
    ),
    "ContactModelMultiple": lambda: ((dam := _contact_dam()), dam.contacts, lambda d: d.multibody.contacts),
    "ImpulseModel6D": lambda: (
        (m := _impulse()), m.impulses.impulses["foot"].impulse, lambda d: d.multibody.impulses.impulses["foot"]
    ),
    "ImpulseModel3D": lambda: (
        (m := _impulse("3D")), m.impulses.impulses["foot"].impulse, lambda d: d.multibody.impulses.impulses["foot"]
    ),
    "ImpulseModelMultiple": lambda: ((m := _impulse()), m.impulses, lambda d: d.multibody.impulses),
}

#: Public model-like classes evaluated by themselves (no data): states, cones and bounds.
STANDALONE: dict[str, tuple[Callable, Callable]] = {
    "StateVector": (lambda: crocopy.StateVector(5), lambda s: s.Jintegrate(np.ones(5), np.arange(5.0))),
    "StateMultibody": (
        lambda: crocopy.StateMultibody(load("anymal")),
        lambda s: s.Jdiff(s.zero(), s.integrate(s.zero(), np.linspace(-1.0, 1.0, s.ndx))),
    ),
    "StateNumDiff": (
        lambda: crocopy.StateNumDiff(crocopy.StateMultibody(load("double_pendulum"))),
        lambda s: s.Jintegrate(s.zero(), np.arange(4.0)),
    ),
    "FrictionCone": (lambda: crocopy.FrictionCone(_ROT, 0.6, 6), lambda c: [c.A, c.lb, c.ub]),
    "WrenchCone": (lambda: crocopy.WrenchCone(_ROT, 0.6, _BOX), lambda c: [c.A, c.lb, c.ub]),
    "CoPSupport": (lambda: crocopy.CoPSupport(_ROT, _BOX), lambda c: [c.A, c.lb, c.ub]),
    "ActivationBounds": (lambda: crocopy.ActivationBounds(-np.ones(3), np.ones(3), 0.9), lambda b: [b.lb, b.ub]),
    "Thruster": (lambda: crocopy.Thruster(pin.SE3(_ROT, np.ones(3)), 0.1), lambda t: [t.pose.homogeneous, t.ctorque]),
    "ControlParametrizationModelPolyZero": (
        lambda: crocopy.ControlParametrizationModelPolyZero(3), lambda c: _control_output(c, 0.3)
    ),
    "ControlParametrizationModelPolyOne": (
        lambda: crocopy.ControlParametrizationModelPolyOne(3), lambda c: _control_output(c, 0.3)
    ),
    "ControlParametrizationModelPolyTwoRK": (
        lambda: crocopy.ControlParametrizationModelPolyTwoRK(3, crocopy.RKType.four), lambda c: _control_output(c, 0.7)
    ),
}


def _control_output(control, t: float) -> list:
    """The control's value and Jacobian at normalised time ``t``, from a data that went through a pickle."""
    data = pickle.loads(pickle.dumps(control.createData()))
    control.calc(data, t, np.linspace(-1.0, 1.0, control.nu))
    control.calcDiff(data, t, np.linspace(-1.0, 1.0, control.nu))
    return [data.w, data.dw_du]

_MODEL_CLASS = re.compile(r"(Model|^State|Cone$|^CoPSupport$|^ActivationBounds$|^Thruster$)")


def test_every_public_model_class_has_a_case():
    public = {
        name for name in dir(crocopy)
        if isinstance(getattr(crocopy, name), type) and _MODEL_CLASS.search(name) and not name.endswith("Abstract")
        and getattr(crocopy, name).__module__.startswith("crocopy")  # not the container names (list, dict)
        and not name.startswith("Std")
        and "Data" not in name
    }
    assert public - set(CASES) - set(STANDALONE) == set()


def _roundtrip(how: str, obj):
    if how == "deepcopy":
        return copy.deepcopy(obj)
    return pickle.loads(pickle.dumps(obj))


def _point(model, seed: int):
    rng = np.random.default_rng(seed)
    np.random.seed(seed)
    x = model.state.rand()
    return x, rng.uniform(-0.5, 0.5, model.nu)


def _evaluate(model, data, x, u):
    model.calc(data, x, u)
    model.calcDiff(data, x, u)


def _arrays(obj, names) -> dict:
    found = {}
    for name in names:
        value = getattr(obj, name, None)
        if hasattr(value, "vector"):
            value = value.vector
        if isinstance(value, (np.ndarray, float)):
            found[name] = np.array(value, dtype=float)
    return found


def _assert_same(a: dict, b: dict, what: str):
    assert a.keys() == b.keys(), what
    for name in a:
        np.testing.assert_allclose(b[name], a[name], rtol=1e-12, atol=1e-12, err_msg=f"{what}.{name}")


@pytest.mark.parametrize("how", ["copy", "deepcopy", "pickle"])
@pytest.mark.parametrize("name", sorted(CASES))
def test_copies_compute_like_the_original(name, how):
    host, component, part = CASES[name]()
    twin = copy.copy(component) if how == "copy" else _roundtrip(how, component)
    assert type(twin) is type(component) and twin is not component
    data = host.createData()
    _evaluate(host, data, *_point(host, 1))
    if how == "copy":
        host2 = copy.copy(host)
        data2 = host2.createData()
        assert type(copy.copy(data)) is type(data)
    else:
        host2, data2 = _roundtrip(how, (host, data))
        if part is not None:
            alone = _roundtrip(how, part(data))
            assert type(alone) is type(part(data))
    x, u = _point(host, 2)
    _evaluate(host, data, x, u)
    _evaluate(host2, data2, x, u)
    _assert_same(_arrays(data, OUTPUTS), _arrays(data2, OUTPUTS), "data")
    if part is not None:
        _assert_same(_arrays(part(data), PART_ARRAYS), _arrays(part(data2), PART_ARRAYS), name)
    if how != "copy":
        before = _arrays(data2, OUTPUTS)
        _evaluate(host, data, *_point(host, 3))
        _assert_same(before, _arrays(data2, OUTPUTS), "copy after the original moved")


@pytest.mark.parametrize("how", ["copy", "deepcopy", "pickle"])
@pytest.mark.parametrize("name", sorted(STANDALONE))
def test_standalone_models_copy(name, how):
    make, output = STANDALONE[name]
    model = make()
    twin = copy.copy(model) if how == "copy" else _roundtrip(how, model)
    assert type(twin) is type(model)
    for a, b in zip(output(model), output(twin)):
        np.testing.assert_allclose(b, a, rtol=1e-12, atol=1e-12)


def test_standalone_core_datas_pickle_and_keep_their_views():
    """Residual and activation data of a cost sum are views into its stack: pickled alone, the cost-sum
    data keeps writing where its stack reads."""
    state = crocopy.StateVector(4)
    costs = crocopy.CostModelSum(state, 2)
    costs.addCost("x", crocopy.CostModelResidual(state, crocopy.ResidualModelState(state, np.ones(4), 2)), 2.0)
    costs.addCost("u", crocopy.CostModelResidual(state, crocopy.ResidualModelControl(state, 2)), 1.0)
    data = costs.createData(crocopy.DataCollectorAbstract())
    x, u = np.arange(4.0), np.array([1.0, -2.0])
    costs.calc(data, x, u)
    for twin in (pickle.loads(pickle.dumps(data)), copy.deepcopy(data)):
        assert np.shares_memory(twin.costs["x"].residual.r, twin.stack.r)
        assert not np.shares_memory(twin.costs["x"].residual.r, data.stack.r)
        costs.calc(twin, 2 * x, u)
        costs.calcDiff(twin, 2 * x, u)
        assert twin.cost == pytest.approx(2.0 * 0.5 * np.sum((2 * x - 1.0) ** 2) + 0.5 * np.sum(u**2))
        np.testing.assert_allclose(twin.Lx, 2.0 * (2 * x - 1.0))
    sq = crocopy.SquashingModelSmoothSat(-np.ones(2), np.ones(2), 2)
    sdata = pickle.loads(pickle.dumps(sq.createData()))
    sq.calcDiff(sdata, np.array([0.1, -0.3]))
    assert np.all(np.diag(sdata.du_ds) > 0.0)
