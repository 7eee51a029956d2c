"""Property tests of the multibody models (issue 14): StateMultibody, actuations, free and contact forward
dynamics, contacts and frame residuals answer every drawn argument with a clear error or a finite,
shape-correct result, and the dynamics derivatives still match numerical differentiation."""

from __future__ import annotations

import functools
import re

import example_robot_data
import numpy as np
import pinocchio as pin
import pytest
from fuzz_inputs import (
    CONTROL_KINDS,
    FUZZ,
    assert_finite,
    assert_matches_numdiff,
    calls_in_drawn_order,
    outcome,
    vector_arg,
)
from hypothesis import given
from hypothesis import strategies as st

import crocopy

GOOD_KINDS = ("ok", "list", "column", "row")
"""Valid forms for multibody points (integer rounding would break a free flyer's unit quaternion)."""
KINDS = GOOD_KINDS + ("short", "long", "matrix", "nan", "inf", "string", "complex", "bool", "none", "scalar")


@functools.cache
def _robot(name: str) -> example_robot_data.robots_loader.RobotWrapper:
    return example_robot_data.load(name)


def _state(name: str) -> crocopy.StateMultibody:
    return crocopy.StateMultibody(_robot(name).model)


def _point(state: crocopy.StateMultibody, data: st.DataObject) -> np.ndarray:
    """A valid state near the robot's reference configuration (standing, for solo12: not singular)."""
    dx = np.array(data.draw(st.lists(st.floats(-0.3, 0.3), min_size=state.ndx, max_size=state.ndx)))
    name = "solo12" if state.pinocchio.name.startswith("solo") else "talos_arm"
    return state.integrate(np.concatenate([_robot(name).q0, np.zeros(state.nv)]), dx)


def _costs(state: crocopy.StateMultibody, nu: int, frame: str) -> crocopy.CostModelSum:
    costs = crocopy.CostModelSum(state, nu)
    costs.addCost("x", crocopy.CostModelResidual(state, crocopy.ResidualModelState(state, state.zero(), nu)), 1.0)
    costs.addCost("u", crocopy.CostModelResidual(state, crocopy.ResidualModelControl(state, nu)), 1e-2)
    fid = state.pinocchio.getFrameId(frame)
    costs.addCost("p", crocopy.CostModelResidual(
        state, crocopy.ResidualModelFrameTranslation(state, fid, np.array([0.1, 0.2, 0.3]), nu)), 1.0)
    return costs


def free_arm() -> crocopy.DifferentialActionModelFreeFwdDynamics:
    state = _state("talos_arm")
    actuation = crocopy.ActuationModelFull(state)
    return crocopy.DifferentialActionModelFreeFwdDynamics(
        state, actuation, _costs(state, actuation.nu, "gripper_left_joint"))


def solo_in_contact() -> crocopy.DifferentialActionModelContactFwdDynamics:
    state = _state("solo12")
    actuation = crocopy.ActuationModelFloatingBase(state)
    contacts = crocopy.ContactModelMultiple(state, actuation.nu)
    for foot, frame in (("FL_FOOT", pin.LOCAL_WORLD_ALIGNED), ("FR_FOOT", pin.LOCAL), ("HL_FOOT", pin.LOCAL)):
        fid = state.pinocchio.getFrameId(foot)
        contacts.addContact(foot, crocopy.ContactModel3D(
            state, fid, np.zeros(3), frame, actuation.nu, np.array([0.0, 50.0])))
    return crocopy.DifferentialActionModelContactFwdDynamics(
        state, actuation, contacts, _costs(state, actuation.nu, "FL_FOOT"))


DYNAMICS = {
    "free-arm": free_arm,
    "contact-solo": solo_in_contact,
    "euler-free-arm": lambda: crocopy.IntegratedActionModelEuler(free_arm(), 0.01),
}
MODELS = {name: functools.cache(make) for name, make in DYNAMICS.items()}


@FUZZ
@given(robot=st.sampled_from(["talos_arm", "solo12"]), data=st.data())
def test_state_multibody_operations(robot, data):
    state = _state(robot)
    x0 = data.draw(vector_arg("x0", state.nx, _point(state, data), KINDS))
    x1 = data.draw(vector_arg("x1", state.nx, _point(state, data), KINDS))
    out = {}

    def diff_then_integrate():
        out["dx"] = state.diff(x0.value, x1.value)
        out["x"] = state.integrate(x0.value, out["dx"])
        out["J"] = state.Jdiff(x0.value, x1.value)

    def check():
        assert out["dx"].shape == (state.ndx,) and np.all(np.isfinite(out["dx"]))
        np.testing.assert_allclose(state.diff(out["x"], x1.array), 0.0, atol=1e-9)
        assert all(J.shape == (state.ndx, state.ndx) and np.all(np.isfinite(J)) for J in out["J"])

    outcome(diff_then_integrate, [x0, x1], check)


@FUZZ
@given(robot=st.sampled_from(["talos_arm", "solo12"]), data=st.data())
def test_actuations(robot, data):
    state = _state(robot)
    actuation = crocopy.ActuationModelFull(state) if robot == "talos_arm" else crocopy.ActuationModelFloatingBase(state)
    ad = actuation.createData()
    x = data.draw(vector_arg("x", state.nx, _point(state, data), KINDS))
    u = data.draw(vector_arg("u", actuation.nu, kinds=CONTROL_KINDS))
    shapes = {"tau": (state.nv,), "dtau_dx": (state.nv, state.ndx), "dtau_du": (state.nv, actuation.nu)}
    outcome(lambda: (actuation.calc(ad, x.value, u.value), actuation.calcDiff(ad, x.value, u.value)), [x, u],
            lambda: assert_finite(ad, shapes))


@FUZZ
@given(name=st.sampled_from(sorted(MODELS)), data=st.data())
def test_dynamics_give_a_clear_error_or_a_finite_result(name, data):
    model = MODELS[name]()
    md = model.createData()
    x = data.draw(vector_arg("x", model.state.nx, _point(model.state, data), KINDS))
    terminal = data.draw(st.booleans())
    u = None if terminal else data.draw(vector_arg("u", model.nu, kinds=CONTROL_KINDS))
    args = [x] if terminal else [x, u]
    ndx, nu = model.state.ndx, model.nu
    calls_in_drawn_order(data, model, md, args,
                         lambda m: {"cost": ()} if m == "calc" else {"Lx": (ndx,), "Lu": (nu,), "Lxx": (ndx, ndx)})


@FUZZ
@given(name=st.sampled_from(sorted(MODELS)), data=st.data())
def test_dynamics_derivatives_match_numdiff(name, data):
    model = MODELS[name]()
    x = _point(model.state, data)
    u = np.array(data.draw(st.lists(st.floats(-1.0, 1.0), min_size=model.nu, max_size=model.nu)))
    assert_matches_numdiff(model, x, u, 1e-4)


@FUZZ
@given(data=st.data())
def test_contacts_and_frame_residuals(data):
    state = _state("solo12")
    fid = state.pinocchio.getFrameId("FL_FOOT")
    pdata = pin.Data(state.pinocchio)
    x = data.draw(vector_arg("x", state.nx, _point(state, data), KINDS))
    xv = x.array if x.valid else state.zero()
    pin.forwardKinematics(state.pinocchio, pdata, xv[: state.nq], xv[state.nq:])
    pin.computeJointJacobians(state.pinocchio, pdata)
    pin.updateFramePlacements(state.pinocchio, pdata)
    contact = crocopy.ContactModel3D(state, fid, np.zeros(3), pin.LOCAL, 12)
    cd = contact.createData(pdata)
    outcome(lambda: (contact.calc(cd, x.value), contact.calcDiff(cd, x.value)), [x],
            lambda: assert_finite(cd, {"a0": (3,), "Jc": (3, state.nv), "da0_dx": (3, state.ndx)}))
    xref = data.draw(vector_arg("xref", 3))

    def set_contact_reference():
        contact.reference = xref.value

    outcome(set_contact_reference, [xref], lambda: np.testing.assert_array_equal(contact.reference, xref.array))
    residual = crocopy.ResidualModelFrameTranslation(state, fid, np.zeros(3), 12)
    rd = residual.createData(crocopy.DataCollectorMultibody(pdata))
    u = data.draw(vector_arg("u", 12, kinds=CONTROL_KINDS))
    outcome(lambda: (residual.calc(rd, x.value, u.value), residual.calcDiff(rd, x.value, u.value)), [x, u],
            lambda: assert_finite(rd, {"r": (3,), "Rx": (3, state.ndx)}))

    def set_residual_reference():
        residual.reference = xref.value

    outcome(set_residual_reference, [xref], lambda: np.testing.assert_array_equal(residual.reference, xref.array))
    placement = crocopy.ResidualModelFramePlacement(state, fid, pin.SE3.Identity(), 12)
    bad = data.draw(st.sampled_from([np.nan, np.inf, 0.5]))
    M = pin.SE3.Identity()
    M.translation = np.array([0.0, bad, 0.0])
    if np.isfinite(bad):
        placement.reference = M
        np.testing.assert_array_equal(placement.reference.translation, M.translation)
    else:
        with pytest.raises(ValueError, match="pref contains NaN or inf"):
            placement.reference = M


@st.composite
def rotation_like(draw) -> tuple[np.ndarray, bool]:
    """A 3x3 matrix near a random rotation: itself, a reflection of it, or it perturbed or scaled; and
    whether it is a rotation (orthonormal within 1e-6, determinant +1)."""
    q = np.array(draw(st.lists(st.floats(-1.0, 1.0), min_size=4, max_size=4)))
    R = pin.Quaternion(*(q / np.linalg.norm(q))).toRotationMatrix() if np.linalg.norm(q) > 1e-3 else np.eye(3)
    kind = draw(st.sampled_from(["rotation", "reflection", "noise", "scaled"]))
    if kind == "reflection":
        return R @ np.diag([1.0, 1.0, -1.0]), False
    if kind == "noise":
        eps = draw(st.sampled_from([1e-9, 1e-4, 1e-2]))
        E = R + eps * np.array(draw(st.lists(st.floats(-1.0, 1.0), min_size=9, max_size=9))).reshape(3, 3)
        return E, bool(np.abs(E.T @ E - np.eye(3)).max() <= 1e-6)
    if kind == "scaled":
        return 1.5 * R, False
    return R, True


@FUZZ
@given(data=rotation_like())
def test_rotation_references_must_be_rotations(data):
    R, is_rotation = data
    state = _state("solo12")
    fid = state.pinocchio.getFrameId("FL_FOOT")
    makers = (
        ("Rref", lambda: crocopy.ResidualModelFrameRotation(state, fid, R, 12)),
        ("pref.rotation", lambda: crocopy.ResidualModelFramePlacement(state, fid, pin.SE3(R, np.zeros(3)), 12)),
        ("pref.rotation", lambda: crocopy.ContactModel6D(state, fid, pin.SE3(R, np.zeros(3)), pin.LOCAL, 12)),
        ("rotation", lambda: crocopy.ContactModel1D(state, fid, 0.0, pin.LOCAL, R, 12)),
        ("R", lambda: crocopy.FrictionCone(R, 0.7)),
    )
    for name, make in makers:
        if is_rotation:
            make()
        else:
            with pytest.raises(ValueError, match=rf"{re.escape(name)} must be a rotation matrix"):
                make()


@FUZZ
@given(id=st.one_of(st.integers(-3, 40), st.booleans(), st.floats(0.0, 5.0), st.sampled_from(["FL_FOOT", "nope"]),
                    st.none()))
def test_frame_ids_are_ints_or_names(id):
    state = _state("solo12")
    model = state.pinocchio
    valid = (isinstance(id, int) and not isinstance(id, bool) and 0 <= id < model.nframes) or (
        isinstance(id, str) and model.existFrame(id))
    for make in (lambda: crocopy.ContactModel3D(state, id, np.zeros(3), pin.LOCAL, 12),
                 lambda: crocopy.ResidualModelFrameTranslation(state, id, np.zeros(3), 12),
                 lambda: crocopy.ImpulseModel3D(state, id, pin.LOCAL)):
        if valid:
            make()
        else:
            with pytest.raises((TypeError, ValueError, KeyError)) as err:
                make()
            assert re.search(r"\b(id|frame)\b", str(err.value)), str(err.value)
