"""The compiled Lie-group kernels equal Pinocchio (and crocopy's StateMultibody) on SO(3), SE(3) and robots.

Oracles: Pinocchio's ``exp3/log3/Jexp3/Jlog3/exp6/log6/Jexp6/Jlog6``, ``SE3`` and ``Quaternion``, its
``integrate/difference/dIntegrate/dDifference/dIntegrateTransport`` on example-robot-data models, and
:class:`crocopy.StateMultibody`.  Pinocchio's ``Jexp6``/``Jlog6`` (and ``Jlog3``) lose up to 1e-7 for
rotation angles between about 1e-4 and 1e-2 (measured against the series below), so at those angles the
kernels are checked against an independent reference instead: power series of the matrix exponential
and of the SE(3) right Jacobian ``Σ_k (-ad ν)^k/(k+1)!`` summed in extended precision.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from robots import load

import crocopy
from crocopy.kernels import compiled
from crocopy.models.rbd import lie_kernel as lie
from crocopy.models.rbd.joint_types import FREEFLYER, REVOLUTE_UB, joint_arrays

ROBOTS = ("iris", "double_pendulum", "kinova", "panda", "anymal", "talos")
ANGLES = (0.0, 1e-9, 1e-6, 0.3, 1.0, 2.0, 3.0, math.pi - 1e-6, math.pi - 1e-9)
"""Rotation angles where Pinocchio's maps are accurate to round-off."""
TOL = 1e-10


def close(a, b, tol=TOL):
    """``|a - b| ≤ tol max(1, |b|)`` entry-wise maximum; returns the error for the message."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    err = float(np.max(np.abs(a - b))) if a.size else 0.0
    assert err <= tol * max(1.0, float(np.max(np.abs(b))) if b.size else 0.0), err
    return err


def axis_angle(seed, angle):
    u = np.random.default_rng(seed).normal(size=3)
    return angle * u / np.linalg.norm(u)


def twist(seed, angle):
    return np.concatenate([np.random.default_rng(seed + 1).normal(size=3), axis_angle(seed, angle)])


# --- extended-precision references ----------------------------------------------------------------------

LD = np.longdouble


def _hat(x):
    return np.array([[0, -x[2], x[1]], [x[2], 0, -x[0]], [-x[1], x[0], 0]], dtype=LD)


def series_exp6(nu):
    """``exp`` of the 4x4 twist matrix by its power series, as ``(R, p)``."""
    T = np.zeros((4, 4), dtype=LD)
    T[:3, :3], T[:3, 3] = _hat(np.asarray(nu[3:], dtype=LD)), np.asarray(nu[:3], dtype=LD)
    total, term = np.eye(4, dtype=LD), np.eye(4, dtype=LD)
    for k in range(1, 80):
        term = term @ T / LD(k)
        total += term
    return total[:3, :3].astype(float), total[:3, 3].astype(float)


def series_jexp6(nu):
    """SE(3)'s right Jacobian ``Σ_k (-ad ν)^k/(k+1)!`` with ``ad [v; ω] = [[ω^, v^], [0, ω^]]``."""
    ad = np.zeros((6, 6), dtype=LD)
    W, V = _hat(np.asarray(nu[3:], dtype=LD)), _hat(np.asarray(nu[:3], dtype=LD))
    ad[:3, :3], ad[3:, 3:], ad[:3, 3:] = W, W, V
    total, term = np.eye(6, dtype=LD), np.eye(6, dtype=LD)
    for k in range(1, 80):
        term = -term @ ad / LD(k + 1)
        total += term
    return total.astype(float)


# --- SO(3) / SE(3) against Pinocchio ---------------------------------------------------------------------


@pytest.mark.parametrize("angle", ANGLES)
@pytest.mark.parametrize("seed", range(3))
def test_so3_maps_equal_pinocchio(angle, seed):
    w = axis_angle(seed, angle)
    R, w_out, J = np.empty((3, 3)), np.empty(3), np.empty((3, 3))
    lie.exp3(w, R)
    close(R, pin.exp3(w))
    Rp = pin.exp3(w)
    lie.log3(Rp, w_out)
    close(w_out, pin.log3(Rp))
    close(w_out, w, 1e-9)  # angles below π come back (π - 1e-9 loses ~1e-7 relative in R's entries)
    lie.jexp3(w, J)
    close(J, pin.Jexp3(w))
    lie.jlog3(Rp, J)
    close(J, pin.Jlog3(Rp))


@pytest.mark.parametrize("angle", ANGLES)
@pytest.mark.parametrize("seed", range(3))
def test_se3_maps_equal_pinocchio(angle, seed):
    nu = twist(seed, angle)
    R, p, out6, J = np.empty((3, 3)), np.empty(3), np.empty(6), np.empty((6, 6))
    lie.exp6(nu, R, p)
    M = pin.exp6(nu)
    close(R, M.rotation)
    close(p, M.translation)
    lie.log6(M.rotation, M.translation, out6)
    close(out6, pin.log6(M).vector)
    lie.jexp6(nu, J)
    close(J, pin.Jexp6(nu))
    lie.jlog6(M.rotation, M.translation, J)
    close(J, pin.Jlog6(M))
    lie.adjoint(M.rotation, M.translation, J)
    close(J, M.action)


def test_zero_twist_and_identity():
    R, p, J6, J3, out6 = np.empty((3, 3)), np.empty(3), np.empty((6, 6)), np.empty((3, 3)), np.empty(6)
    lie.exp6(np.zeros(6), R, p)
    assert np.array_equal(R, np.eye(3)) and np.array_equal(p, np.zeros(3))
    lie.jexp6(np.zeros(6), J6)
    assert np.array_equal(J6, np.eye(6)) and np.array_equal(J6, pin.Jexp6(np.zeros(6)))
    lie.jexp3(np.zeros(3), J3)
    assert np.array_equal(J3, np.eye(3))
    lie.log6(np.eye(3), np.zeros(3), out6)
    assert np.array_equal(out6, np.zeros(6))
    lie.jlog6(np.eye(3), np.zeros(3), J6)
    assert np.array_equal(J6, np.eye(6))


@pytest.mark.parametrize("axis", range(3))
def test_log_at_exactly_pi(axis):
    R = -np.eye(3)
    R[axis, axis] = 1.0  # rotation by π about a coordinate axis: ±π e_axis are both logarithms
    w = np.empty(3)
    lie.log3(R, w)
    assert np.allclose(np.abs(w), np.abs(pin.log3(R)), atol=1e-12) and abs(abs(w[axis]) - math.pi) < 1e-12
    back = np.empty((3, 3))
    lie.exp3(w, back)
    close(back, R, 1e-12)
    J, out6 = np.empty((3, 3)), np.empty(6)
    lie.jlog3(R, J)
    close(J, pin.Jlog3(R))
    p = np.array([0.3, -0.2, 0.5])
    lie.log6(R, p, out6)
    close(np.abs(out6), np.abs(pin.log6(pin.SE3(R, p)).vector))


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**31), angle=st.one_of(st.floats(0.0, math.pi - 1e-6), st.floats(1e-5, 2e-2)))
def test_se3_maps_equal_series_references(seed, angle):
    """At every angle, including those where Pinocchio's Jacobians lose digits."""
    nu = twist(seed, angle)
    R, p, J, back = np.empty((3, 3)), np.empty(3), np.empty((6, 6)), np.empty(6)
    lie.exp6(nu, R, p)
    Rs, ps = series_exp6(nu)
    close(R, Rs, 1e-13)
    close(p, ps, 1e-13)
    lie.log6(Rs, ps, back)
    close(back, nu, 1e-9 if angle > 3.0 else 1e-12)
    Jr = series_jexp6(nu)
    lie.jexp6(nu, J)
    close(J, Jr, 1e-13)
    lie.jlog6(R, p, J)
    close(J @ Jr, np.eye(6), 1e-12 if angle < 3.0 else 1e-9)
    J3 = np.empty((3, 3))
    lie.jexp3(nu[3:], J3)
    close(J3, Jr[3:, 3:], 1e-13)
    lie.jlog3(R, J3)
    close(J3 @ Jr[3:, 3:], np.eye(3), 1e-12 if angle < 3.0 else 1e-9)


@pytest.mark.parametrize("seed", range(5))
def test_placements_and_quaternions_equal_pinocchio(seed):
    rng = np.random.default_rng(seed)
    Ma, Mb = (pin.SE3(pin.exp3(rng.normal(size=3)), rng.normal(size=3)) for _ in range(2))
    R, p, x = np.empty((3, 3)), np.empty(3), rng.normal(size=3)
    lie.se3_compose(Ma.rotation, Ma.translation, Mb.rotation, Mb.translation, R, p)
    close(np.c_[R, p], (Ma * Mb).homogeneous[:3])
    lie.relative_placement(Ma.rotation, Ma.translation, Mb.rotation, Mb.translation, R, p)
    close(np.c_[R, p], (Ma.inverse() * Mb).homogeneous[:3])
    lie.se3_act(Ma.rotation, Ma.translation, x, p)
    close(p, Ma.act(x))
    quat = np.empty(4)
    for rot in (Ma.rotation, pin.exp3(axis_angle(seed, math.pi - 1e-3)), np.diag([1.0, -1.0, -1.0]),
                np.diag([-1.0, 1.0, -1.0]), np.diag([-1.0, -1.0, 1.0])):
        lie.rot_to_quat(rot, quat)
        ref = pin.Quaternion(rot).coeffs()
        close(quat * np.sign(quat @ ref), ref)
        lie.quat_to_rot(quat, R)
        close(R, rot)
        lie.quat_to_rot(ref, R)
        close(R, pin.Quaternion(ref).toRotationMatrix())


# --- configuration space and the multibody state ----------------------------------------------------------


@pytest.fixture(scope="module", params=ROBOTS)
def robot(request):
    model = load(request.param)
    jtype, idx_q, idx_v, _ = joint_arrays(model)
    return model, jtype, idx_q, idx_v, crocopy.StateMultibody(model)


def random_q(model, rng):
    """A normalised configuration (joint limits do not matter to the Lie-group operations)."""
    return pin.normalize(model, rng.uniform(-3.0, 3.0, model.nq))


def draws(model, seed):
    rng = np.random.default_rng(seed)
    q0, q1 = random_q(model, rng), random_q(model, rng)
    v = rng.normal(size=model.nv) * rng.choice([1e-7, 0.3, 3.0])
    return rng, q0, q1, v


@settings(max_examples=15, deadline=None)
@given(seed=st.integers(0, 2**31), near=st.booleans())
def test_configuration_space_equals_pinocchio(robot, seed, near):
    model, jtype, idx_q, idx_v, _ = robot
    rng, q0, q1, v = draws(model, seed)
    if near:  # q1 a round-off away from q0, or equal
        q1 = pin.integrate(model, q0, rng.normal(size=model.nv) * rng.choice([0.0, 1e-9]))
    nq, nv = model.nq, model.nv
    q_out, v_out, J = np.empty(nq), np.empty(nv), np.full((nv, nv), np.nan)
    lie.integrate(jtype, idx_q, idx_v, q0, v, q_out)
    close(q_out, pin.integrate(model, q0, v))
    lie.difference(jtype, idx_q, idx_v, q0, q1, v_out)
    close(v_out, pin.difference(model, q0, q1))
    J_in = rng.normal(size=(nv, 4))
    for arg, pin_arg in ((0, pin.ARG0), (1, pin.ARG1)):
        lie.dintegrate(jtype, idx_q, idx_v, q0, v, arg, J)
        close(J, pin.dIntegrate(model, q0, v, pin_arg))
        lie.ddifference(jtype, idx_q, idx_v, q0, q1, arg, J)
        close(J, pin.dDifference(model, q0, q1, pin_arg))
        out = np.empty_like(J_in)
        lie.dintegrate_transport(jtype, idx_q, idx_v, q0, v, J_in, arg, out)
        close(out, pin.dIntegrateTransport(model, q0, v, J_in, pin_arg))
        in_place = J_in.copy()
        lie.dintegrate_transport(jtype, idx_q, idx_v, q0, v, in_place, arg, in_place)
        assert np.array_equal(in_place, out)


@settings(max_examples=15, deadline=None)
@given(seed=st.integers(0, 2**31))
def test_state_operations_equal_state_multibody(robot, seed):
    model, jtype, idx_q, idx_v, state = robot
    rng, q0, q1, v = draws(model, seed)
    nq, nv = model.nq, model.nv
    x0, x1 = np.r_[q0, rng.normal(size=nv)], np.r_[q1, rng.normal(size=nv)]
    dx = np.r_[v, rng.normal(size=nv)]
    out_x, out_dx, J = np.empty(state.nx), np.empty(state.ndx), np.full((state.ndx, state.ndx), np.nan)
    lie.state_diff(jtype, idx_q, idx_v, nq, nv, x0, x1, out_dx)
    close(out_dx, state.diff(x0, x1))
    lie.state_integrate(jtype, idx_q, idx_v, nq, nv, x0, dx, out_x)
    close(out_x, state.integrate(x0, dx))
    for k, first in enumerate((True, False)):
        lie.state_jdiff(jtype, idx_q, idx_v, nq, nv, x0, x1, first, J)
        close(J, state.Jdiff(x0, x1)[k])
        lie.state_jintegrate(jtype, idx_q, idx_v, nq, nv, x0, dx, first, J)
        close(J, state.Jintegrate(x0, dx)[k])
        J_in = rng.normal(size=(state.ndx, 3))
        transported = J_in.copy()
        state.JintegrateTransport(x0, dx, transported, crocopy.Jcomponent.first if first else crocopy.Jcomponent.second)
        lie.dintegrate_transport(jtype, idx_q, idx_v, x0, dx, J_in, 1 - int(first), J_in)
        close(J_in, transported)


def test_non_unit_joint_configurations_are_handled_as_pinocchio_does():
    """A quaternion or an unbounded joint's (cos, sin) off the unit sphere by round-off-sized drift."""
    for name in ("iris", "kinova"):
        model = load(name)
        jtype, idx_q, idx_v, _ = joint_arrays(model)
        rng = np.random.default_rng(7)
        q = random_q(model, rng)
        for j in range(1, model.njoints):
            if jtype[j] == FREEFLYER:
                q[idx_q[j] + 3: idx_q[j] + 7] *= 1.0 + 1e-6
            elif jtype[j] == REVOLUTE_UB:
                q[idx_q[j]: idx_q[j] + 2] *= 1.0 - 1e-6
        v = rng.normal(size=model.nv)
        out = np.empty(model.nq)
        lie.integrate(jtype, idx_q, idx_v, q, v, out)
        close(out, pin.integrate(model, q, v), 1e-12)


def test_unbounded_joint_difference_rounds_like_pinocchio():
    """Two (cos, sin) a few 1e-9 rad apart: Pinocchio returns 0 when their rounded dot product exceeds 1."""
    model = pin.Model()
    model.addJoint(0, pin.JointModelRUBZ(), pin.SE3.Identity(), "hinge")
    jtype, idx_q, idx_v, _ = joint_arrays(model)
    rng, out, above_one = np.random.default_rng(11), np.empty(1), 0
    for _ in range(400):
        q0 = pin.normalize(model, rng.normal(size=2))
        q1 = pin.integrate(model, q0, rng.normal(size=1) * 1e-9)
        above_one += q0 @ q1 > 1.0
        lie.difference(jtype, idx_q, idx_v, q0, q1, out)
        assert out[0] == pytest.approx(pin.difference(model, q0, q1)[0], abs=1e-15)
    assert above_one > 0  # the rule was exercised


# --- called from compiled code ------------------------------------------------------------------------------


@compiled
def _round_trip(jtype, idx_q, idx_v, nq, nv, x, dx, nu, x_out, dx_out, J, R, p, out6):
    """``x ⊕ dx ⊖ x`` and ``log6(exp6(nu))`` inside one compiled call."""
    lie.state_integrate(jtype, idx_q, idx_v, nq, nv, x, dx, x_out)
    lie.state_diff(jtype, idx_q, idx_v, nq, nv, x, x_out, dx_out)
    lie.state_jintegrate(jtype, idx_q, idx_v, nq, nv, x, dx, False, J)
    lie.exp6(nu, R, p)
    lie.log6(R, p, out6)


@pytest.mark.parametrize("name", ["iris", "kinova"])
def test_kernels_run_inside_a_compiled_function(name):
    model = load(name)
    jtype, idx_q, idx_v, _ = joint_arrays(model)
    state = crocopy.StateMultibody(model)
    rng = np.random.default_rng(3)
    x = np.r_[random_q(model, rng), rng.normal(size=model.nv)]
    dx, nu = rng.normal(size=state.ndx) * 0.5, twist(4, 1.2)
    x_out, dx_out, J = np.empty(state.nx), np.empty(state.ndx), np.empty((state.ndx, state.ndx))
    R, p, out6 = np.empty((3, 3)), np.empty(3), np.empty(6)
    _round_trip(jtype, idx_q, idx_v, model.nq, model.nv, x, dx, nu, x_out, dx_out, J, R, p, out6)
    close(x_out, state.integrate(x, dx))
    close(dx_out, dx)
    close(J, state.Jintegrate(x, dx)[1])
    close(out6, nu)
