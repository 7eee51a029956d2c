"""Crocoddyl names crocopy provides for scripts: data classes under their names, containers, helpers."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st
from robots import load

import crocopy


def _collector():
    model = load("anymal")
    state = crocopy.StateMultibody(model)
    act = crocopy.ActuationModelFloatingBase(state)
    pd = model.createData()
    contacts = crocopy.ContactModelMultiple(state, act.nu)
    contacts.addContact("lf", crocopy.ContactModel3D(state, "LF_FOOT", np.zeros(3), pin.LOCAL, act.nu))
    joint = crocopy.JointDataAbstract(state, act, act.nu)
    shared = crocopy.DataCollectorJointActMultibodyInContact(pd, act.createData(), joint, contacts.createData(pd))
    return state, act, shared


def test_data_classes_under_crocoddyl_names():
    state, act, shared = _collector()
    nu, fid = act.nu, state.pinocchio.getFrameId("LF_FOOT")
    cone = crocopy.FrictionCone(np.eye(3), 0.7)
    wrench = crocopy.WrenchCone(np.eye(3), 0.7, np.array([0.1, 0.1]))
    cases = [
        (crocopy.ResidualModelFramePlacement(state, fid, pin.SE3.Identity(), nu), crocopy.ResidualDataFramePlacement),
        (crocopy.ResidualModelFrameRotation(state, fid, np.eye(3), nu), crocopy.ResidualDataFrameRotation),
        (crocopy.ResidualModelFrameTranslation(state, fid, np.zeros(3), nu), crocopy.ResidualDataFrameTranslation),
        (crocopy.ResidualModelFrameVelocity(state, fid, pin.Motion.Zero(), pin.LOCAL, nu),
         crocopy.ResidualDataFrameVelocity),
        (crocopy.ResidualModelCoMPosition(state, np.zeros(3), nu), crocopy.ResidualDataCoMPosition),
        (crocopy.ResidualModelControlGrav(state, nu), crocopy.ResidualDataControlGrav),
        (crocopy.ResidualModelContactFrictionCone(state, fid, cone, nu), crocopy.ResidualDataContactFrictionCone),
    ]
    for model, cls in cases:
        data = model.createData(shared)
        assert type(data) is cls and isinstance(data, crocopy.ResidualDataAbstract)
    six = load("talos_legs")
    s6 = crocopy.StateMultibody(six)
    a6 = crocopy.ActuationModelFloatingBase(s6)
    contacts = crocopy.ContactModelMultiple(s6, a6.nu)
    contacts.addContact("l", crocopy.ContactModel6D(s6, "left_sole_link", pin.SE3.Identity(), pin.LOCAL, a6.nu))
    pd = six.createData()
    sh6 = crocopy.DataCollectorMultibodyInContact(pd, contacts.createData(pd))
    wrench_res = crocopy.ResidualModelContactWrenchCone(s6, "left_sole_link", wrench, a6.nu)
    assert type(wrench_res.createData(sh6)) is crocopy.ResidualDataContactWrenchCone
    assert type(crocopy.ImpulseModel3D(state, fid).createData(state.pinocchio.createData())) is crocopy.ImpulseData3D
    assert type(crocopy.ImpulseModel6D(state, fid).createData(state.pinocchio.createData())) is crocopy.ImpulseData6D
    res = crocopy.ConstraintModelResidual(state, crocopy.ResidualModelControl(state, nu))
    assert type(res.createData(shared)) is crocopy.ConstraintDataResidual
    assert type(crocopy.ActivationModelSmooth1Norm(3).createData()) is crocopy.ActivationDataSmooth1Norm
    assert type(crocopy.ActionModelLQR(2, 2).createData()) is crocopy.ActionDataLQR
    assert type(crocopy.ActionModelUnicycle().createData()) is crocopy.ActionDataUnicycle
    dlqr = crocopy.DifferentialActionModelLQR(2, 2)
    assert type(dlqr.createData()) is crocopy.DifferentialActionDataLQR
    for iam in (crocopy.IntegratedActionModelEuler(dlqr, 0.1),
                crocopy.IntegratedActionModelRK(dlqr, crocopy.four, 0.1)):
        assert isinstance(iam.createData(), crocopy.IntegratedActionDataAbstract)
    squash = crocopy.ActuationSquashingModel(act, crocopy.SquashingModelSmoothSat(-np.ones(nu), np.ones(nu), nu), nu)
    assert type(squash.createData()) is crocopy.ActuationSquashingData


def test_containers_are_python_containers():
    models = crocopy.StdVec_ActionModel()
    models.append(crocopy.ActionModelUnicycle())
    assert len(models) == 1
    xs = crocopy.StdVec_MatrixXs([np.eye(2)])
    copies = xs.tolist()
    assert np.array_equal(copies[0], np.eye(2)) and copies[0] is not xs[0]
    costs = crocopy.CostModelSum(crocopy.StateVector(3), 2)
    assert isinstance(costs.costs, crocopy.StdMap_CostItem)
    assert isinstance(costs.active_set, crocopy.StdSet_String)


def _direction(v: np.ndarray) -> np.ndarray:
    v = v / np.abs(v).max()
    return v / np.linalg.norm(v)


ADVERSARIAL_PAIRS = [
    ([1.0, 0.0, 2.2e-158], [-1.0, 0.0, 0.0]),  # issue 27: NaN (the old s² underflowed)
    ([1.0, 0.0, 0.0], [-1.0, 0.0, 0.0]),  # exactly opposite along each axis
    ([0.0, 2.0, 0.0], [0.0, -1e-300, 0.0]),
    ([0.0, 0.0, 3e300], [0.0, 0.0, -5e-324]),
    ([0.6, 0.8, 0.0], [-0.6, -0.8, 1e-17]),  # nearly opposite off the axes: u × w is round-off
    ([0.6, 0.8, 1e-300], [-0.6, -0.8, 0.0]),
    ([1.0, 1e-320, 0.0], [-1.0, 0.0, 0.0]),  # subnormal components
    ([5e-324, 0.0, 0.0], [0.0, 5e-324, 5e-324]),
    ([1e-300, 2e-300, -1e-300], [3e-310, 0.0, 1e-310]),  # tiny
    ([1.7e308, -1.7e308, 1.7e308], [-1.7e308, 1.7e308, -1.6e308]),  # huge: |a| overflows
    ([1.0, 1e-200, 0.0], [1.0, 0.0, 1e-200]),  # nearly parallel
    ([2.0, 2.0, 2.0], [1.0, 1.0, 1.0]),  # parallel
]
COMPONENT = st.one_of(st.floats(-10, 10), st.floats(allow_nan=False, allow_infinity=False))


def _with_examples(pairs):
    def decorate(test):
        for a, b in reversed(pairs):
            test = example(a, b)(test)
        return test
    return decorate


@settings(max_examples=60, deadline=None)
@given(st.lists(COMPONENT, min_size=3, max_size=3), st.lists(COMPONENT, min_size=3, max_size=3))
@_with_examples(ADVERSARIAL_PAIRS)
def test_rotation_from_two_vectors(a, b):
    a, b = np.array(a), np.array(b)
    R = crocopy.rotationMatrixFromTwoVectors(a, b)
    assert np.all(np.isfinite(R))
    np.testing.assert_allclose(R @ R.T, np.eye(3), atol=1e-12)
    assert np.linalg.det(R) == pytest.approx(1.0, abs=1e-12)
    if not a.any() or not b.any():
        np.testing.assert_array_equal(R, np.eye(3))
        return
    u, w = _direction(a), _direction(b)
    np.testing.assert_allclose(R @ u, w, atol=1e-12)  # every pair of non-zero vectors, at every scale
    axis = np.cross(u, w)
    if np.linalg.norm(axis) > 1e-6:
        np.testing.assert_allclose(R @ axis, axis, atol=1e-12)  # about u × w: the smallest angle


def test_rotation_from_two_vectors_degenerate_and_bad_input():
    ez = np.array([0.0, 0.0, 1.0])
    for b in (ez, 2 * ez, np.zeros(3)):
        np.testing.assert_array_equal(crocopy.rotationMatrixFromTwoVectors(ez, b), np.eye(3))
    for e in np.eye(3):  # opposite: a half-turn about an axis perpendicular to a
        R = crocopy.rotationMatrixFromTwoVectors(e, -3 * e)
        np.testing.assert_allclose(R @ e, -e, atol=1e-15)
        assert np.trace(R) == pytest.approx(-1.0, abs=1e-15)
    np.testing.assert_allclose(crocopy.rotationMatrixFromTwoVectors([0, 0, 2], [0, 3, 0]),
                               [[1, 0, 0], [0, 0, 1], [0, -1, 0]], atol=1e-15)
    with pytest.raises(ValueError, match=r"a has shape \(2,\), expected \(3,\)"):
        crocopy.rotationMatrixFromTwoVectors(np.ones(2), ez)


def test_seed_shared_memory_and_exception():
    state = crocopy.StateMultibody(load("anymal"))
    crocopy.seed(7)
    x1 = state.rand()
    crocopy.seed(7)
    np.testing.assert_array_equal(state.rand(), x1)
    with pytest.raises(ValueError, match="seed_value"):
        crocopy.seed(-1)
    assert crocopy.sharedMemory() is True
    crocopy.sharedMemory(True)
    with pytest.raises(ValueError, match="always share"):
        crocopy.sharedMemory(False)
    with pytest.raises(crocopy.Exception):
        crocopy.ContactModel1D(state, "LF_FOOT", np.zeros(3), pin.LOCAL)


def test_star_import_gives_the_core_and_the_models():
    namespace: dict = {}
    exec("from crocopy import *", namespace)
    for name in ("ActionModelUnicycle", "SolverFDDP", "SolverIntro", "ShootingProblem", "ContactModel3D",
                 "StateMultibody", "LuNull"):
        assert name in namespace, name
    assert not any(name.startswith("_") for name in crocopy.__all__)
    with pytest.raises(AttributeError, match="has no attribute '__wrapped__'"):
        crocopy.__wrapped__  # noqa: B018  (dunders are not forwarded to crocopy.models)
