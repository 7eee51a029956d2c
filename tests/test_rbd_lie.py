"""The compiled Lie-group kernels equal Pinocchio (and crocopy's StateMultibody) on SO(3), SE(3) and robots.

Oracles: Pinocchio's ``log3/Jlog3/log6/Jlog6`` and its ``integrate/difference/dIntegrate/dDifference`` on a
lone free flyer, on example-robot-data models and on :func:`robots.joint_chain` (spherical, planar, translation and
helical joints: SO(3), SE(2) and vector spaces), and :class:`crocopy.StateMultibody`.  The SE(3)
exponential, its Jacobian and the adjoint are private to the kernels; they are checked through
``integrate`` and ``dintegrate`` of a free flyer (``q ⊕ ν = M(q) exp6(ν)``, ``∂/∂v = jexp6(ν)``,
``∂/∂q = Ad(exp6 ν)⁻¹``).  Pinocchio's ``Jexp6``/``Jlog6`` (and ``Jlog3``) lose up to 1e-7 for rotation
angles between about 1e-4 and 1e-2 (measured against the series below), so at those angles the kernels are
checked against an independent reference instead: power series of the matrix exponential and of the
SE(3) right Jacobian ``Σ_k (-ad ν)^k/(k+1)!`` summed in extended precision.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from robots import JOINT_CHAIN, load

import crocopy
from crocopy.kernels import compiled
from crocopy.models.rbd import configuration_kernel as conf
from crocopy.models.rbd import lie_kernel as lie
from crocopy.models.rbd.joint_types import FREEFLYER, PLANAR, REVOLUTE_UB, joint_arrays

ROBOTS = ("iris", "double_pendulum", "kinova", "panda", "anymal", "talos", JOINT_CHAIN)
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


def free_flyer():
    """``(model, jtype, idx_q, idx_v)`` of a model made of one free-flyer joint: ``q ⊕ ν = M(q) exp6(ν)``."""
    model = pin.Model()
    model.addJoint(0, pin.JointModelFreeFlyer(), pin.SE3.Identity(), "base")
    jtype, idx_q, idx_v, _ = joint_arrays(model)
    return model, jtype, idx_q, idx_v


def inverse_adjoint(R, p):
    """``Ad(R, p)⁻¹ = [[Rᵀ, -Rᵀ [p]], [0, Rᵀ]]`` (6, 6), in NumPy."""
    hat = np.array([[0.0, -p[2], p[1]], [p[2], 0.0, -p[0]], [-p[1], p[0], 0.0]])
    return np.block([[R.T, -R.T @ hat], [np.zeros((3, 3)), R.T]])


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
    w_out, J = np.empty(3), np.empty((3, 3))
    Rp = pin.exp3(w)
    lie.log3(Rp, w_out)
    close(w_out, pin.log3(Rp))
    close(w_out, w, 1e-9)  # angles below π come back (π - 1e-9 loses ~1e-7 relative in R's entries)
    lie.jlog3(Rp, J)
    close(J, pin.Jlog3(Rp))


@pytest.mark.parametrize("angle", ANGLES)
@pytest.mark.parametrize("seed", range(3))
def test_se3_maps_equal_pinocchio(angle, seed):
    nu = twist(seed, angle)
    out6, J = np.empty(6), np.empty((6, 6))
    M = pin.exp6(nu)
    lie.log6(M.rotation, M.translation, out6)
    close(out6, pin.log6(M).vector)
    lie.jlog6(M.rotation, M.translation, J)
    close(J, pin.Jlog6(M))


@pytest.mark.parametrize("angle", ANGLES)
@pytest.mark.parametrize("seed", range(3))
def test_free_flyer_exponential_and_its_jacobians_equal_pinocchio(angle, seed):
    """``integrate`` (``exp6``) and ``dintegrate`` (``Ad(exp6 ν)⁻¹``, ``jexp6``) of a lone free flyer."""
    model, jtype, idx_q, idx_v = free_flyer()
    nu = twist(seed, angle)
    q = random_q(model, np.random.default_rng(seed))
    q_out, J = np.empty(7), np.full((6, 6), np.nan)
    conf.integrate(jtype, idx_q, idx_v, q, nu, q_out)
    close(q_out, pin.integrate(model, q, nu))
    close(pin.XYZQUATToSE3(q_out).homogeneous, (pin.XYZQUATToSE3(q) * pin.exp6(nu)).homogeneous)
    for arg, pin_arg in ((0, pin.ARG0), (1, pin.ARG1)):
        conf.dintegrate(jtype, idx_q, idx_v, q, nu, arg, J)
        close(J, pin.dIntegrate(model, q, nu, pin_arg))
    close(J, pin.Jexp6(nu))


def test_zero_twist_and_identity():
    model, jtype, idx_q, idx_v = free_flyer()
    J6, out6 = np.empty((6, 6)), np.empty(6)
    q = pin.neutral(model)
    for arg in (0, 1):
        conf.dintegrate(jtype, idx_q, idx_v, q, np.zeros(6), arg, J6)
        assert np.array_equal(J6, np.eye(6))
    assert np.array_equal(J6, pin.Jexp6(np.zeros(6)))
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
    close(pin.exp3(w), R, 1e-12)
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
    model, jtype, idx_q, idx_v = free_flyer()
    q, q_out, J, back = pin.neutral(model), np.empty(7), np.full((6, 6), np.nan), np.empty(6)
    Rs, ps = series_exp6(nu)
    conf.integrate(jtype, idx_q, idx_v, q, nu, q_out)
    M = pin.XYZQUATToSE3(q_out)
    close(M.rotation, Rs, 1e-13)
    close(M.translation, ps, 1e-13)
    conf.dintegrate(jtype, idx_q, idx_v, q, nu, 0, J)
    close(J, inverse_adjoint(Rs, ps), 1e-13)
    Jr = series_jexp6(nu)
    conf.dintegrate(jtype, idx_q, idx_v, q, nu, 1, J)
    close(J, Jr, 1e-13)
    lie.log6(Rs, ps, back)
    close(back, nu, 1e-9 if angle > 3.0 else 1e-12)
    lie.jlog6(Rs, ps, J)
    close(J @ Jr, np.eye(6), 1e-12 if angle < 3.0 else 1e-9)
    J3 = np.empty((3, 3))
    lie.jlog3(Rs, J3)
    close(J3 @ Jr[3:, 3:], np.eye(3), 1e-12 if angle < 3.0 else 1e-9)


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


FULL_TURN = 1e-2
"""Pinocchio's ``dIntegrate`` w.r.t. ``v`` (``Jexp6``) loses precision when a free flyer's rotation angle is this
close to a non-zero multiple of 2π (1e-10 at 3e-3 away, 1e-7 at 1e-4, NaN at 2π, against central differences):
the Pinocchio comparisons skip those draws, :func:`test_dintegrate_near_full_turns_matches_finite_differences`
covers them."""


def near_full_turn(jtype, idx_v, v) -> bool:
    """Whether a free flyer's rotation ``v[iv+3:iv+6]`` has an angle within :data:`FULL_TURN` of ``2π k``, ``k ≥ 1``."""
    for j in range(1, jtype.shape[0]):
        if jtype[j] == FREEFLYER:
            angle = float(np.linalg.norm(v[idx_v[j] + 3: idx_v[j] + 6]))
            turns = round(angle / (2 * math.pi))
            if turns >= 1 and abs(angle - 2 * math.pi * turns) < FULL_TURN:
                return True
    return False


PLANAR_CLAMPED = 1e-9
"""Where a planar joint's relative cosine ``c0 c1 + s0 s1`` rounds above 1 (angles below about 1.5e-8), Pinocchio's
``difference`` takes the angle as 0 (so do the kernels) but its ``dDifference`` puts the angle ``θ`` where ``jlog2``
has ``θ/2`` (the kernels' ``jlog2`` is exact at ``θ``): the comparisons of those Jacobians allow this much there."""


def planar_clamped(jtype, idx_q, q0, q1) -> bool:
    """Whether a planar joint's relative cosine rounds above 1 (:data:`PLANAR_CLAMPED`)."""
    return any(jtype[j] == PLANAR and q0[idx_q[j] + 2] * q1[idx_q[j] + 2] + q0[idx_q[j] + 3] * q1[idx_q[j] + 3] > 1.0
               for j in range(1, jtype.shape[0]))


@settings(max_examples=15, deadline=None)
@given(seed=st.integers(0, 2**31), near=st.booleans())
def test_configuration_space_equals_pinocchio(robot, seed, near):
    """``integrate``, ``dintegrate`` and the Jacobians of the difference equal Pinocchio's; ``difference`` equals
    ``StateMultibody.diff``: Pinocchio's, except on continuous joints near zero (see
    :func:`test_unbounded_joint_difference_is_exact_where_pinocchio_rounds`)."""
    model, jtype, idx_q, idx_v, state = robot
    rng, q0, q1, v = draws(model, seed)
    assume(not near_full_turn(jtype, idx_v, v))
    if near:  # q1 a round-off away from q0, or equal
        q1 = pin.integrate(model, q0, rng.normal(size=model.nv) * rng.choice([0.0, 1e-9]))
    nq, nv = model.nq, model.nv
    q_out, v_out, J = np.empty(nq), np.empty(nv), np.full((nv, nv), np.nan)
    conf.integrate(jtype, idx_q, idx_v, q0, v, q_out)
    close(q_out, pin.integrate(model, q0, v))
    x0, x1, Jx = np.r_[q0, np.zeros(nv)], np.r_[q1, np.zeros(nv)], np.full((2 * nv, 2 * nv), np.nan)
    conf.difference(jtype, idx_q, idx_v, q0, q1, v_out)
    close(v_out, state.diff(x0, x1)[:nv])
    blocks = np.zeros((nv, nv), dtype=bool)
    for j in range(1, len(jtype)):
        first, last = idx_v[j], idx_v[j] + model.joints[j].nv
        blocks[first:last, first:last] = True
    for arg, pin_arg in ((0, pin.ARG0), (1, pin.ARG1)):
        conf.dintegrate(jtype, idx_q, idx_v, q0, v, arg, J)
        close(J, pin.dIntegrate(model, q0, v, pin_arg))
        Jb = np.full((nv, nv), 7.0)
        conf.dintegrate_blocks(jtype, idx_q, idx_v, v, arg, Jb)  # the joints' diagonal blocks only
        np.testing.assert_array_equal(Jb[blocks], J[blocks])
        assert np.all(Jb[~blocks] == 7.0)
        conf.state_jdiff(jtype, idx_q, idx_v, nq, nv, x0, x1, arg == 0, Jx)  # its q block is dDifference
        close(Jx[:nv, :nv], pin.dDifference(model, q0, q1, pin_arg),
              PLANAR_CLAMPED if planar_clamped(jtype, idx_q, q0, q1) else TOL)


@settings(max_examples=15, deadline=None)
@given(seed=st.integers(0, 2**31))
def test_state_operations_equal_state_multibody(robot, seed):
    model, jtype, idx_q, idx_v, state = robot
    rng, q0, q1, v = draws(model, seed)
    assume(not near_full_turn(jtype, idx_v, v))
    nq, nv = model.nq, model.nv
    x0, x1 = np.r_[q0, rng.normal(size=nv)], np.r_[q1, rng.normal(size=nv)]
    dx = np.r_[v, rng.normal(size=nv)]
    out_x, out_dx, J = np.empty(state.nx), np.empty(state.ndx), np.full((state.ndx, state.ndx), np.nan)
    conf.state_diff(jtype, idx_q, idx_v, nq, nv, x0, x1, out_dx)
    close(out_dx, state.diff(x0, x1))
    conf.state_integrate(jtype, idx_q, idx_v, nq, nv, x0, dx, out_x)
    close(out_x, state.integrate(x0, dx))
    Jq = np.full((nv, nv), np.nan)
    for k, first in enumerate((True, False)):
        conf.state_jdiff(jtype, idx_q, idx_v, nq, nv, x0, x1, first, J)
        close(J, state.Jdiff(x0, x1)[k])
        conf.dintegrate(jtype, idx_q, idx_v, x0, dx, k, Jq)  # a whole state x and tangent dx as q and v
        close(Jq, state.Jintegrate(x0, dx)[k][:nv, :nv])


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
        conf.integrate(jtype, idx_q, idx_v, q, v, out)
        close(out, pin.integrate(model, q, v), 1e-12)


def test_unbounded_joint_difference_is_exact_where_pinocchio_rounds():
    """Two (cos, sin) a few 1e-9 rad apart: Pinocchio returns 0 when their rounded dot product exceeds 1; the kernel
    returns ``atan2(c0 s1 - s0 c1, c0 c1 + s0 s1)`` there too (issue 27), elsewhere Pinocchio's value."""
    model = pin.Model()
    model.addJoint(0, pin.JointModelRUBZ(), pin.SE3.Identity(), "hinge")
    jtype, idx_q, idx_v, _ = joint_arrays(model)
    rng, out, above_one = np.random.default_rng(11), np.empty(1), 0
    for _ in range(400):
        q0 = pin.normalize(model, rng.normal(size=2))
        q1 = pin.integrate(model, q0, rng.normal(size=1) * 1e-9)
        conf.difference(jtype, idx_q, idx_v, q0, q1, out)
        (c0, s0), (c1, s1) = q0, q1
        assert out[0] == math.atan2(c0 * s1 - s0 * c1, c0 * c1 + s0 * s1)
        reference = pin.difference(model, q0, q1)[0]
        if reference == 0.0 and out[0] != 0.0:
            above_one += 1
        else:
            assert out[0] == pytest.approx(reference, abs=1e-15)
    assert above_one > 0  # the rule was exercised


# --- called from compiled code ------------------------------------------------------------------------------


@compiled
def _round_trip(jtype, idx_q, idx_v, nq, nv, x, dx, x_out, dx_out, J, Jq, R, p, out6, J6):
    """``x ⊕ dx ⊖ x``, its Jacobians and ``log6``/``jlog6`` of ``(R, p)`` inside one compiled call."""
    conf.state_integrate(jtype, idx_q, idx_v, nq, nv, x, dx, x_out)
    conf.state_diff(jtype, idx_q, idx_v, nq, nv, x, x_out, dx_out)
    conf.state_jdiff(jtype, idx_q, idx_v, nq, nv, x, x_out, False, J)
    conf.dintegrate(jtype, idx_q, idx_v, x, dx, 1, Jq)
    lie.log6(R, p, out6)
    lie.jlog6(R, p, J6)


@pytest.mark.parametrize("name", ["iris", "kinova"])
def test_kernels_run_inside_a_compiled_function(name):
    model = load(name)
    jtype, idx_q, idx_v, _ = joint_arrays(model)
    state = crocopy.StateMultibody(model)
    rng = np.random.default_rng(3)
    x = np.r_[random_q(model, rng), rng.normal(size=model.nv)]
    dx, nu = rng.normal(size=state.ndx) * 0.5, twist(4, 1.2)
    x_out, dx_out, J = np.empty(state.nx), np.empty(state.ndx), np.empty((state.ndx, state.ndx))
    Jq, M, out6, J6 = np.empty((model.nv, model.nv)), pin.exp6(nu), np.empty(6), np.empty((6, 6))
    _round_trip(jtype, idx_q, idx_v, model.nq, model.nv, x, dx, x_out, dx_out, J, Jq, M.rotation, M.translation,
                out6, J6)
    close(x_out, state.integrate(x, dx))
    close(dx_out, dx)
    close(J, state.Jdiff(x, x_out)[1])
    close(Jq, state.Jintegrate(x, dx)[1][:model.nv, :model.nv])
    close(out6, nu)
    close(J6, pin.Jlog6(M))


@pytest.mark.parametrize("turns", [1, 2])
@pytest.mark.parametrize("gap", [FULL_TURN, 1e-4, 0.0])
def test_dintegrate_near_full_turns_matches_finite_differences(turns, gap):
    """Where Pinocchio's ``Jexp6`` is inaccurate (a rotation angle near ``2π k``), ``dintegrate`` w.r.t. ``v``
    against central differences of ``integrate``/``difference``."""
    model = load("iris")
    jtype, idx_q, idx_v, _ = joint_arrays(model)
    u = np.array([0.3, -0.8, 0.5]) / np.linalg.norm([0.3, -0.8, 0.5])
    v = np.r_[0.4, -1.0, 2.0, (2 * math.pi * turns - gap) * u, np.zeros(model.nv - 6)]
    q0 = pin.neutral(model)
    J = np.empty((model.nv, model.nv))
    conf.dintegrate(jtype, idx_q, idx_v, q0, v, 1, J)
    x = pin.integrate(model, q0, v)
    h = 1e-5
    for j in range(6):
        e = np.zeros(model.nv)
        e[j] = h
        column = (pin.difference(model, x, pin.integrate(model, q0, v + e))
                  - pin.difference(model, x, pin.integrate(model, q0, v - e))) / (2 * h)
        close(J[:6, j], column[:6], tol=1e-9)
