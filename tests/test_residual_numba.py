"""A user's residual written as numba functions (``ResidualModelNumba``): compiled nodes keep it compiled.

Every residual below crosses free (arm) and contact (quadruped) nodes, running and terminal: the compiled node
equals the Python node and central differences; ``check_residual_derivatives`` accepts right derivatives and names
a wrong entry; a solve with the user's translation residual equals a solve with the built-in one, kernels on
and off.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from node_checks import assert_same_solves, check_finite_differences, compare_with_python_node

import crocopy
from crocopy.problems import arm, quadruped
from crocopy.problems.user_residual import NumbaFrameTranslation as Translation
from crocopy.problems.user_residual import build_user_reach


class UpAxis(crocopy.ResidualModelNumba):
    """``r = R e_z - e_z``: keep the frame's z axis vertical (world Jacobian: ``∂(R e_z) = -[R e_z]× J_ω``)."""

    def __init__(self, state, frame, nu=None):
        super().__init__(state, 3, nu, frame=frame, frame_reference=pin.WORLD, kinematics=("jacobian",),
                         v_dependent=False)

    @staticmethod
    def compute_residual(r, x, u, p, kin):
        r[0], r[1], r[2] = kin.R[0, 2], kin.R[1, 2], kin.R[2, 2] - 1.0

    @staticmethod
    def compute_jacobians(Rx, Ru, x, u, p, kin):
        z = kin.R[:, 2]
        for j in range(kin.J.shape[1]):
            w = kin.J[3:, j]
            Rx[0, j] = w[1] * z[2] - w[2] * z[1]
            Rx[1, j] = w[2] * z[0] - w[0] * z[2]
            Rx[2, j] = w[0] * z[1] - w[1] * z[0]


class CoMHeight(crocopy.ResidualModelNumba):
    """``r = com_z - h`` (one row)."""

    def __init__(self, state, height, nu=None):
        super().__init__(state, 1, nu, kinematics=("com",), v_dependent=False)
        self.height = float(height)

    def parameters(self):
        return np.array([self.height])

    @staticmethod
    def compute_residual(r, x, u, p, kin):
        r[0] = kin.com[2] - p[0]

    @staticmethod
    def compute_jacobians(Rx, Ru, x, u, p, kin):
        Rx[0, : kin.Jcom.shape[1]] = kin.Jcom[2]


class VelocityControl(crocopy.ResidualModelNumba):
    """``r = v + u_scale u`` (depends on ``v`` and ``u``; no kinematics): the ``Ru`` path."""

    def __init__(self, state, nu):
        super().__init__(state, nu, nu, v_dependent=True, u_dependent=True)

    @staticmethod
    def compute_residual(r, x, u, p, kin):
        nv = kin.J.shape[1]
        for i in range(r.shape[0]):
            r[i] = x[x.shape[0] - nv + (nv - r.shape[0]) + i] + (0.5 * u[i] if u.shape[0] else 0.0)

    @staticmethod
    def compute_jacobians(Rx, Ru, x, u, p, kin):
        nv = kin.J.shape[1]
        for i in range(Rx.shape[0]):
            Rx[i, nv + (nv - Rx.shape[0]) + i] = 1.0
            if Ru.shape[1]:
                Ru[i, i] = 0.5


def user_residuals(state, frame, nu):
    return {
        "translation": Translation(state, frame, [0.3, 0.2, 0.4], nu),
        "up axis": UpAxis(state, frame, nu),
        "com height": CoMHeight(state, 0.3, nu),
        "velocity and control": VelocityControl(state, nu),
    }


def arm_node(name, terminal):
    problem, _, _ = arm.build_arm_reaching(crocopy, nodes=4)
    iam = problem.terminalModel if terminal else problem.runningModels[0]
    dam = iam.differential
    frame = dam.state.pinocchio.nframes - 1
    dam.costs.addCost("user", crocopy.CostModelResidual(dam.state, user_residuals(dam.state, frame, dam.nu)[name]),
                      3.0)
    return iam


def quadruped_node(name, terminal):
    problem, _, _ = quadruped.build_gait(crocopy, "walk", step_knots=2, support_knots=1, cycles=1)
    iam = problem.terminalModel if terminal else problem.runningModels[0]
    dam = iam.differential
    frame = dam.state.pinocchio.getFrameId("LF_FOOT")
    dam.costs.addCost("user", crocopy.CostModelResidual(dam.state, user_residuals(dam.state, frame, dam.nu)[name]),
                      3.0)
    return iam


NODES = {"arm": arm_node, "quadruped": quadruped_node}
NAMES = ("translation", "up axis", "com height", "velocity and control")


@pytest.mark.parametrize("terminal", [False, True], ids=["running", "terminal"])
@pytest.mark.parametrize("robot", sorted(NODES))
@pytest.mark.parametrize("name", NAMES)
def test_compiled_node_with_a_user_residual(name, robot, terminal):
    iam = NODES[robot](name, terminal)
    state = iam.state
    rng = np.random.default_rng(3)
    x = state.integrate(iam.differential.costs.costs["state"].cost.residual.reference, 0.05 * rng.standard_normal(
        state.ndx))
    u = 0.1 * rng.standard_normal(iam.nu)
    compare_with_python_node(iam, x, u, terminal, rtol=1e-9, atol=1e-10, cost_rel=1e-10)
    if not terminal:
        check_finite_differences(iam, state, x, u, h=1e-4, atol=1e-5, roundoff=1e-7)


@pytest.mark.parametrize("name", NAMES)
def test_check_residual_derivatives_accepts_each_residual(name):
    state = crocopy.StateMultibody(pin.buildSampleModelManipulator())
    residual = user_residuals(state, state.pinocchio.nframes - 1, state.nv)[name]
    crocopy.check_residual_derivatives(residual)


class WrongTranslation(Translation):
    """The translation residual with one Jacobian entry off."""

    @staticmethod
    def compute_jacobians(Rx, Ru, x, u, p, kin):
        for i in range(3):
            for j in range(kin.J.shape[1]):
                Rx[i, j] = kin.J[i, j]
        Rx[1, 2] += 0.5


def test_check_residual_derivatives_names_the_wrong_entry():
    state = crocopy.StateMultibody(pin.buildSampleModelManipulator())
    residual = WrongTranslation(state, state.pinocchio.nframes - 1, np.zeros(3))
    with pytest.raises(AssertionError, match=r"Rx\[1, 2\]"):
        crocopy.check_residual_derivatives(residual)


def reach(user: bool):
    return build_user_reach(crocopy, "numba" if user else "builtin", robot="kinova", nodes=20)


@pytest.mark.parametrize("kernels", [True, False], ids=["kernels", "python"])
def test_user_residual_solves_as_the_built_in(kernels):
    with crocopy.use_kernels(kernels):
        assert_same_solves([reach(False), reach(True)])


def test_user_parameters_changed_between_solves():
    """Assigning the residual's attribute that ``parameters()`` reads is seen by the next solve (fresh answer)."""
    problem, xs, us = reach(True)
    solver = crocopy.SolverFDDP(problem)
    solver.solve(xs, us, 5)
    for m in [*problem.runningModels, problem.terminalModel]:
        m.differential.costs.costs["goal"].cost.residual.reference = np.array([0.3, 0.1, 0.5])
    solver.solve(xs, us, 10)
    fresh, _, _ = reach(True)
    for m in [*fresh.runningModels, fresh.terminalModel]:
        m.differential.costs.costs["goal"].cost.residual.reference = np.array([0.3, 0.1, 0.5])
    other = crocopy.SolverFDDP(fresh)
    other.solve(xs, us, 10)
    assert solver.iter == other.iter
    assert solver.cost == pytest.approx(other.cost, rel=1e-9)


def test_bad_declarations_are_refused():
    state = crocopy.StateMultibody(pin.buildSampleModelManipulator())
    for kinematics in ("placement", ("velocity",)):
        with pytest.raises(ValueError, match="kinematics"):
            crocopy.ResidualModelNumba.__init__(Translation.__new__(Translation), state, 3, kinematics=kinematics)

    class Incomplete(crocopy.ResidualModelNumba):
        @staticmethod
        def compute_residual(r, x, u, p, kin):
            r[0] = 0.0

    with pytest.raises(TypeError, match="compute_jacobians"):
        Incomplete(state, 1)
    with pytest.raises((KeyError, ValueError)):
        Translation(state, "no such frame", np.zeros(3))


def test_non_finite_parameters_are_refused():
    state = crocopy.StateMultibody(pin.buildSampleModelManipulator())
    residual = Translation(state, state.pinocchio.nframes - 1, np.array([np.nan, 0.0, 0.0]))
    with pytest.raises(ValueError, match="non-finite"):
        crocopy.check_residual_derivatives(residual)
