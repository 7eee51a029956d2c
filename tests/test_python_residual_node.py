"""A Crocoddyl-style Python residual in a free-dynamics node: the node stays compiled, only that residual runs in
Python (``models/rbd/python_residuals.py``); the node equals the Python node and finite differences, a solve equals
the built-in residual's; contact nodes with such a residual keep the Python path."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from node_checks import assert_same_solves, check_finite_differences, compare_with_python_node

import crocopy
from crocopy.problems import quadruped
from crocopy.problems.user_residual import build_user_reach, python_frame_translation


class UserVelocity(crocopy.ResidualModelFrameVelocity):
    """A user's subclass of a built-in residual (not compiled: its node runs it in Python), depending on ``v``."""


def arm_node(kind: str, terminal: bool):
    problem, _, _ = build_user_reach(crocopy, "python", robot="kinova", nodes=4)
    iam = problem.terminalModel if terminal else problem.runningModels[1]
    dam = iam.differential
    if kind == "velocity":
        fid = dam.state.pinocchio.nframes - 1
        residual = UserVelocity(dam.state, fid, pin.Motion(np.full(6, 0.2)), pin.LOCAL_WORLD_ALIGNED, dam.nu)
        dam.costs.addCost("velocity", crocopy.CostModelResidual(dam.state, residual), 2.0)
    return iam


@pytest.mark.parametrize("terminal", [False, True], ids=["running", "terminal"])
@pytest.mark.parametrize("kind", ["translation", "velocity"])
def test_node_with_a_python_residual_stays_compiled(kind, terminal):
    iam = arm_node(kind, terminal)
    data = iam.createData()
    evaluator = iam._compiled_node(data, terminal, {})
    assert evaluator is not None and evaluator.python.items
    state = iam.state
    rng = np.random.default_rng(7)
    x = state.integrate(state.zero(), 0.3 * rng.standard_normal(state.ndx))
    u = rng.standard_normal(iam.nu)
    compare_with_python_node(iam, x, u, terminal, rtol=1e-9, atol=1e-10, cost_rel=1e-10)
    if not terminal:
        check_finite_differences(iam, state, x, u, h=1e-4, atol=1e-5, roundoff=1e-7)


@pytest.mark.parametrize("kernels", [True, False], ids=["kernels", "python"])
def test_python_residual_solves_as_the_built_in(kernels):
    with crocopy.use_kernels(kernels):
        assert_same_solves([build_user_reach(crocopy, v, robot="kinova", nodes=20) for v in ("builtin", "python")])


def test_contact_node_with_a_python_residual_keeps_the_python_path():
    problem, _, _ = quadruped.build_gait(crocopy, "walk", step_knots=2, support_knots=1, cycles=1)
    iam = problem.runningModels[0]
    dam = iam.differential
    cls = python_frame_translation(crocopy)
    fid = dam.state.pinocchio.getFrameId("LF_FOOT")
    dam.costs.addCost("user", crocopy.CostModelResidual(dam.state, cls(dam.state, fid, np.zeros(3), dam.nu)), 1.0)
    assert iam._compiled_node(iam.createData(), False, {}) is None
