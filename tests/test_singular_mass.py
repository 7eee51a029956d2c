"""A mass matrix that is singular at every configuration (a moving joint whose subtree has no mass or inertia: the
bravo7 gripper's fingers; an arm with every inertia zero) gives NaN dynamics on both paths, never an exception, and
a solve returns False naming the joints, with kernels on and off alike."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from node_checks import failed_solve, make_solver
from robots import load, reaching_node

import crocopy
from crocopy.models.dynamics_options import massless_joints
from crocopy.models.rbd import dynamics_kernel as K
from crocopy.models.rbd.lowering import lower_model, make_workspace

FINGERS = ["bravo_finger1_joint", "bravo_finger2_joint"]


def weightless_arm() -> pin.Model:
    """ur5 with every body inertia zero."""
    model = pin.Model(load("ur5"))
    for i in range(model.njoints):
        model.inertias[i] = pin.Inertia.Zero()
    return model


def reaching(model: pin.Model, armature: float = 0.0, T: int = 5) -> crocopy.ShootingProblem:
    """A fully actuated reaching problem on ``model`` (the tip frame to a point), from the neutral posture."""
    state = crocopy.StateMultibody(model)
    tip, target = model.nframes - 1, (0.2, 0.2, 0.4)
    running, terminal = (reaching_node(state, tip, target, 1.0, end, armature) for end in (False, True))
    return crocopy.ShootingProblem(state.zero(), [running] * T, terminal)


def test_massless_joints_are_named():
    assert massless_joints(load("bravo7_gripper"), np.zeros(8)) == FINGERS
    assert massless_joints(load("bravo7_gripper"), np.r_[np.zeros(6), 1e-3, 1e-3]) == []
    assert massless_joints(weightless_arm(), np.zeros(6)) == list(load("ur5").names[1:])
    for robot in ("ur5", "anymal", "kinova"):
        model = load(robot)
        assert massless_joints(model, np.zeros(model.nv)) == []


@pytest.mark.parametrize("make", [lambda: load("bravo7_gripper"), weightless_arm], ids=["bravo7-fingers", "no-inertia"])
def test_forward_dynamics_kernel_gives_nan_not_an_exception(make):
    model = make()
    rb = lower_model(model)
    ws = make_workspace(rb)
    a = np.zeros(model.nv)
    K.forward_dynamics(rb, ws, pin.neutral(model), np.zeros(model.nv), np.ones(model.nv), a)
    assert np.isnan(a).any()
    assert np.isnan(pin.aba(model, model.createData(), pin.neutral(model), np.zeros(model.nv), np.ones(model.nv))).any()


@pytest.mark.skipif(not crocopy.kernels_enabled(), reason="compiled nodes need numba")
@pytest.mark.parametrize("make", [lambda: load("bravo7_gripper"), weightless_arm], ids=["bravo7-fingers", "no-inertia"])
def test_a_solve_returns_false_naming_the_joints_with_and_without_kernels(make):
    model = make()
    problem = reaching(model)
    xs, us = [problem.x0] * (problem.T + 1), [np.zeros(problem.nu_max)] * problem.T
    fast = failed_solve(problem, xs, us, True, 5)
    slow = failed_solve(problem, xs, us, False, 5)
    assert fast == slow
    assert fast[0] is False
    assert fast[2].startswith("non-finite Fx at node 0 in the derivatives: the mass matrix is singular: joint(s) ")
    assert all(repr(name) in fast[2] for name in massless_joints(model, np.zeros(model.nv))[:6])


@pytest.mark.skipif(not crocopy.kernels_enabled(), reason="compiled nodes need numba")
def test_an_armature_makes_the_fingers_solvable_on_both_paths():
    problem = reaching(load("bravo7_gripper"), armature=1e-3)
    results = []
    for compiled in (True, False):
        s = make_solver("SolverFDDP", problem, compiled)
        s.solve([], [], 10)
        results.append((s.iter, s.cost, s.reason))
    assert results[0][0] == results[1][0] and results[0][2] == results[1][2]
    assert np.isfinite(results[0][1]) and results[0][1] == pytest.approx(results[1][1], rel=1e-9)
