"""The compiled rigid-body kernels (models/rbd/dynamics_kernel.py) give Pinocchio's numbers, the oracle.

Robots: iris (free flyer, one body), double_pendulum, kinova (unbounded RUBZ joints), talos_arm (armature),
panda (aligned and unaligned prismatic), anymal, solo12, talos (free flyer + 32 revolute, armature), and
``joint_chain`` (:func:`robots.joint_chain`: spherical, planar, translation and helical joints on a free flyer).
Random states come from Hypothesis seeds; errors are compared with ``tol · max(1, max |reference|)``.
"""

from __future__ import annotations

import functools

import numba
import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from robots import JOINT_CHAIN, load

from crocopy.models.rbd import dynamics_kernel as K
from crocopy.models.rbd import gravity_kernel as G
from crocopy.models.rbd.joint_types import NotLowerable
from crocopy.models.rbd.lowering import lower_model, make_workspace

ROBOTS = ("iris", "double_pendulum", "kinova", "talos_arm", "panda", "anymal", "solo12", "talos", JOINT_CHAIN)
REFERENCES = (pin.WORLD, pin.LOCAL, pin.LOCAL_WORLD_ALIGNED)
SEEDS = st.integers(0, 2**32 - 1)


def per_robot(test):
    """``test(robot, seed)`` on every robot, for a few Hypothesis seeds."""
    return pytest.mark.parametrize("robot", ROBOTS)(settings(max_examples=3, deadline=None)(given(seed=SEEDS)(test)))


@functools.cache
def lowered(name):
    """``(model, data, rb, ws)`` of robot ``name``, built once per test session."""
    model = load(name)
    rb = lower_model(model)
    return model, model.createData(), rb, make_workspace(rb)


def state(model, seed):
    """A random ``(q, v, a, tau)``: ``q = neutral ⊕ δ`` covers every joint type (free-flyer rotation,
    unbounded joints' ``[cos, sin]``, prismatic offsets)."""
    rng = np.random.default_rng(seed)
    q = pin.integrate(model, pin.neutral(model), rng.uniform(-np.pi, np.pi, model.nv))
    v, a, tau = (rng.standard_normal(model.nv) for _ in range(3))
    return q, v, a, tau


def close(x, ref, tol=1e-9):
    """Assert ``max |x - ref| <= tol · max(1, max |ref|)``."""
    ref = np.asarray(ref)
    scale = max(1.0, float(np.abs(ref).max(initial=0.0)))
    err = float(np.abs(np.asarray(x) - ref).max(initial=0.0))
    assert err <= tol * scale, f"error {err:.3e} > {tol:.0e} x {scale:.3e}"


def symmetric(upper):
    """The full matrix of a Pinocchio result whose upper triangle only is filled."""
    return np.triu(upper) + np.triu(upper, 1).T


def test_lowered_model_matches_pinocchio():
    model, _, rb, ws = lowered("talos")
    assert (rb.nq, rb.nv, rb.njoints, rb.nframes) == (model.nq, model.nv, model.njoints, model.nframes)
    assert list(rb.parent) == list(model.parents)
    assert list(rb.frame_joint) == [f.parentJoint for f in model.frames]
    for i in range(1, model.njoints):
        assert list(range(i, rb.subtree_end[i])) == sorted([i, *model.subtrees[i][1:]])
        assert all(rb.dof_joint[k] == i for k in range(model.idx_vs[i], model.idx_vs[i] + model.nvs[i]))
    close(rb.armature, model.armature, 0)
    close(rb.gravity, model.gravity.vector, 0)
    assert ws.M.shape == (model.nv, model.nv) and ws.oR.shape == (model.njoints, 3, 3)


def test_lower_model_refuses_unsupported_joints():
    model = pin.Model()
    model.addJoint(0, pin.JointModelSphericalZYX(), pin.SE3.Identity(), "ball")
    with pytest.raises(NotLowerable, match="'ball' is a JointModelSphericalZYX"):
        lower_model(model)


@per_robot
def test_forward_kinematics(robot, seed):
    model, data, rb, ws = lowered(robot)
    q, v, _, _ = state(model, seed)
    K.forward_kinematics(rb, ws, q, v)
    pin.forwardKinematics(model, data, q, v)
    J = pin.computeJointJacobians(model, data, q)
    close(ws.oS, J.T)
    for i in range(1, model.njoints):
        close(ws.oR[i], data.oMi[i].rotation)
        close(ws.op[i], data.oMi[i].translation)
        close(ws.ov[i], data.oMi[i].act(data.v[i]).vector)


@per_robot
def test_forward_dynamics_and_mass_inverse(robot, seed):
    model, data, rb, ws = lowered(robot)
    q, v, _, tau = state(model, seed)
    acc, Minv = np.zeros(model.nv), np.zeros((model.nv, model.nv))
    K.forward_dynamics(rb, ws, q, v, tau, acc)
    K.mass_inverse(rb.dof_parent, ws.L, ws.dinv, Minv)
    M = symmetric(pin.crba(model, data, q))  # includes the armature
    close(ws.M, M)
    close(ws.L.T @ ws.L, M)
    close(np.triu(ws.L, 1), 0 * M, 0)
    close(acc, pin.aba(model, data, q, v, tau))
    close(acc, np.linalg.solve(M, tau - pin.nonLinearEffects(model, data, q, v)))
    close(Minv, np.linalg.inv(M))
    close(Minv, Minv.T, 0)


def test_forward_dynamics_with_armature_is_cholesky_of_crba_plus_armature():
    model, data, rb, ws = lowered("talos_arm")
    assert model.armature.max() > 0
    q, v, _, tau = state(model, 7)
    acc = np.zeros(model.nv)
    K.forward_dynamics(rb, ws, q, v, tau, acc)
    pin.computeAllTerms(model, data, q, v)
    no_armature = symmetric(data.M) - np.diag(model.armature)
    L = np.linalg.cholesky(no_armature + np.diag(model.armature))
    close(acc, np.linalg.solve(L @ L.T, tau - data.nle))
    assert np.abs(acc - np.linalg.solve(no_armature, tau - data.nle)).max() > 1e-3  # the armature matters


@per_robot
def test_rnea_derivatives(robot, seed):
    model, data, rb, ws = lowered(robot)
    q, v, a, _ = state(model, seed)
    dq, dv = np.zeros((model.nv, model.nv)), np.zeros((model.nv, model.nv))
    K.dynamics_derivatives(rb, ws, q, v, a, dq, dv)
    pin.computeRNEADerivatives(model, data, q, v, a)
    close(dq, data.dtau_dq)
    close(dv, data.dtau_dv)
    close(ws.tau, pin.rnea(model, data, q, v, a))


@per_robot
def test_free_dynamics_derivatives_from_rnea_derivatives(robot, seed):
    """``∂a/∂(q, v) = -M⁻¹ ∂RNEA/∂(q, v)`` at ``a = FD(q, v, τ)``: Pinocchio's ABA derivatives."""
    model, data, rb, ws = lowered(robot)
    q, v, _, tau = state(model, seed)
    n = model.nv
    acc, Minv, dq, dv = np.zeros(n), np.zeros((n, n)), np.zeros((n, n)), np.zeros((n, n))
    K.forward_dynamics(rb, ws, q, v, tau, acc)
    K.mass_inverse(rb.dof_parent, ws.L, ws.dinv, Minv)
    K.dynamics_derivatives(rb, ws, q, v, acc, dq, dv)
    pin.computeABADerivatives(model, data, q, v, tau)
    close(-Minv @ dq, data.ddq_dq, 1e-8)
    close(-Minv @ dv, data.ddq_dv, 1e-8)
    close(Minv, symmetric(data.Minv), 1e-8)


@per_robot
def test_frames(robot, seed):
    """Placement, Jacobian, velocity and velocity derivatives of every frame, in the three references."""
    model, data, rb, ws = lowered(robot)
    q, v, a, _ = state(model, seed)
    K.forward_kinematics(rb, ws, q, v)
    pin.computeForwardKinematicsDerivatives(model, data, q, v, a)
    pin.computeJointJacobians(model, data, q)
    pin.updateFramePlacements(model, data)
    R, p, out = np.zeros((3, 3)), np.zeros(3), np.zeros(6)
    J, dq, dv = (np.zeros((6, model.nv)) for _ in range(3))
    for f in range(model.nframes):
        K.frame_placement(rb, ws, f, R, p)
        close(R, data.oMf[f].rotation)
        close(p, data.oMf[f].translation)
        for reference in REFERENCES:
            K.frame_jacobian(rb, ws, f, int(reference), J)
            close(J, pin.getFrameJacobian(model, data, f, reference))
            K.frame_velocity(rb, ws, f, int(reference), out)
            close(out, pin.getFrameVelocity(model, data, f, reference).vector)
            K.frame_velocity_derivatives(rb, ws, f, int(reference), dq, dv)
            ref_dq, ref_dv = pin.getFrameVelocityDerivatives(model, data, f, reference)
            close(dq, ref_dq)
            close(dv, ref_dv)


def test_reference_codes_are_pinocchios():
    assert (K.WORLD, K.LOCAL, K.LOCAL_WORLD_ALIGNED) == tuple(
        int(r) for r in (pin.WORLD, pin.LOCAL, pin.LOCAL_WORLD_ALIGNED)
    )


@numba.njit
def _node(rb, ws, q, v, tau, fid, out):
    """A compiled caller, as a compiled node will be: every kernel called from inside numba."""
    acc, Minv, dq, dv, J, Jq, Jv, R, p, vel = out
    K.forward_dynamics(rb, ws, q, v, tau, acc)
    K.mass_inverse(rb.dof_parent, ws.L, ws.dinv, Minv)
    K.dynamics_derivatives(rb, ws, q, v, acc, dq, dv)
    K.forward_kinematics(rb, ws, q, v)
    K.frame_jacobian(rb, ws, fid, 1, J)
    K.frame_velocity_derivatives(rb, ws, fid, 0, Jq, Jv)
    K.frame_placement(rb, ws, fid, R, p)
    K.frame_velocity(rb, ws, fid, 2, vel)


def test_kernels_run_inside_a_compiled_function():
    model, data, rb, ws = lowered("anymal")
    q, v, _, tau = state(model, 3)
    n, fid = model.nv, model.getFrameId("LF_FOOT")
    out = (np.zeros(n), *(np.zeros((n, n)) for _ in range(3)), *(np.zeros((6, n)) for _ in range(3)))
    out += (np.zeros((3, 3)), np.zeros(3), np.zeros(6))
    _node(rb, ws, q, v, tau, fid, out)
    acc, Minv, dq, dv, J, Jq, Jv, R, p, vel = out
    pin.computeABADerivatives(model, data, q, v, tau)
    close(acc, pin.aba(model, data, q, v, tau))
    close(-Minv @ dq, data.ddq_dq, 1e-8)
    close(-Minv @ dv, data.ddq_dv, 1e-8)
    pin.computeForwardKinematicsDerivatives(model, data, q, v, acc)
    pin.computeJointJacobians(model, data, q)
    pin.updateFramePlacements(model, data)
    close(J, pin.getFrameJacobian(model, data, fid, pin.LOCAL))
    close(Jq, pin.getFrameVelocityDerivatives(model, data, fid, pin.WORLD)[0])
    close(Jv, pin.getFrameJacobian(model, data, fid, pin.WORLD))
    close(R, data.oMf[fid].rotation)
    close(p, data.oMf[fid].translation)
    close(vel, pin.getFrameVelocity(model, data, fid, pin.LOCAL_WORLD_ALIGNED).vector)


@numba.njit
def _allocates(n):
    total = 0.0
    for _ in range(n):
        total += np.ones(3).sum()
    return total


@numba.njit
def _repeat(rb, ws, q, v, tau, fid, out, n):
    for _ in range(n):
        _node(rb, ws, q, v, tau, fid, out)


def test_kernels_do_not_allocate():
    """numba's allocation counters grow no more for four calls than for one (argument boxing aside)."""
    from numba.core.runtime import _nrt_python, rtsys

    model, _, rb, ws = lowered("talos")
    q, v, _, tau = state(model, 5)
    n = model.nv
    out = (np.zeros(n), *(np.zeros((n, n)) for _ in range(3)), *(np.zeros((6, n)) for _ in range(3)))
    out += (np.zeros((3, 3)), np.zeros(3), np.zeros(6))
    fid = model.getFrameId("left_sole_link")
    _repeat(rb, ws, q, v, tau, fid, out, 1)
    _allocates(1)
    _nrt_python.memsys_enable_stats()
    try:
        counts = []
        for calls in (1, 4):
            before = rtsys.get_allocation_stats().alloc
            _repeat(rb, ws, q, v, tau, fid, out, calls)
            counts.append(rtsys.get_allocation_stats().alloc - before)
        before = rtsys.get_allocation_stats().alloc
        _allocates(4)
        control = rtsys.get_allocation_stats().alloc - before
    finally:
        _nrt_python.memsys_disable_stats()
    assert control >= 4  # the counters do count
    assert counts[0] == counts[1]


@per_robot
def test_generalized_gravity_and_its_derivatives(robot, seed):
    """``g(q) = RNEA(q, 0, 0)`` and ``∂g/∂q`` on the kinematics of any ``(q, v)``: Pinocchio's."""
    model, data, rb, ws = lowered(robot)
    q, v, _, _ = state(model, seed)
    K.forward_kinematics(rb, ws, q, v)
    g, dg = np.zeros(model.nv), np.full((model.nv, model.nv), np.nan)
    G.generalized_gravity(rb, ws, g)
    G.gravity_derivatives(rb, ws, dg)
    close(g, pin.computeGeneralizedGravity(model, data, q))
    close(dg, pin.computeGeneralizedGravityDerivatives(model, data, q))
