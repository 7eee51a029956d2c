"""Compiled Euler nodes with 1D and 2D contacts (alone and mixed with 3D and 6D ones, in LOCAL, LOCAL_WORLD_ALIGNED
and WORLD coordinates, with and without Baumgarte gains) against the Python node, finite differences and solves.

The nodes are those of ``test_contacts_1d2d.py`` (ANYmal, one contact per foot).  The compiled contacts take a 1D or
2D contact as rows of its point contact (:mod:`crocopy.models.rbd.contact_kernel`); force residuals on such a
contact keep the node on the Python path.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from node_checks import check_finite_differences, check_new_evaluator, compare_with_python_node, make_solver
from test_contacts_1d2d import CASES, IDS, make_dam

import crocopy
from crocopy.solvers import compiled_nodes

pytestmark = pytest.mark.skipif(not crocopy.kernels_enabled(), reason="compiled nodes need numba")


def euler(case, seed: int = 0):
    dam = make_dam(*case, seed=seed)
    return crocopy.IntegratedActionModelEuler(dam, 0.01), dam.state


def point(state, nu: int, seed: int):
    rng = np.random.default_rng(50 + seed)
    np.random.seed(50 + seed)
    x = state.rand()
    x[state.nq:] = 0.5 * rng.standard_normal(state.nv)
    return x, 0.5 * rng.standard_normal(nu)


@pytest.mark.parametrize("case", CASES, ids=IDS)
@pytest.mark.parametrize("terminal", [False, True])
def test_projected_contacts_compile_and_match_the_python_node(case, terminal):
    iam, state = euler(case)
    problem = crocopy.ShootingProblem(state.zero(), [iam], iam)
    assert all(entry.compiled for entry in crocopy.compiled_coverage(problem))
    x, u = point(state, iam.nu, 0)
    compare_with_python_node(iam, x, u, terminal, rtol=1e-7, atol=1e-7, cost_rel=1e-9)


@pytest.mark.parametrize("case", [CASES[1], CASES[3], CASES[4]], ids=[IDS[1], IDS[3], IDS[4]])
def test_projected_contact_derivatives_match_finite_differences(case):
    iam, state = euler(case, seed=1)
    x, u = point(state, iam.nu, 1)
    check_finite_differences(iam, state, x, u, h=1e-6, atol=1e-5, roundoff=1e-10)


@pytest.mark.parametrize("case", [CASES[1], CASES[3]], ids=[IDS[1], IDS[3]])
def test_solves_with_projected_contacts_match_the_python_nodes(case):
    outcomes = []
    for compiled in (True, False):
        iam, state = euler(case, seed=2)
        x0, _ = point(state, iam.nu, 2)
        problem = crocopy.ShootingProblem(x0, [iam] * 8, iam)
        solver = make_solver("SolverFDDP", problem, compiled)
        if compiled:
            assert compiled_nodes.select(solver).horizon is not None
        solver.solve([], [], 6)
        outcomes.append((solver.iter, solver.cost))
    assert outcomes[0][0] == outcomes[1][0] and outcomes[0][0] > 1
    assert outcomes[0][1] == pytest.approx(outcomes[1][1], rel=1e-9)


def force(state, fid, nu):
    return crocopy.ResidualModelContactForce(state, fid, pin.Force(np.array([0.3, -0.2, 5.0, 0.1, 0.2, 0.3])), 1, nu)


def cone(state, fid, nu):
    return crocopy.ResidualModelContactFrictionCone(
        state, fid, crocopy.FrictionCone(pin.rpy.rpyToMatrix(0.1, -0.2, 0.3), 0.7, 4, False), nu)


FORCE_CASES = [(CASES[0], force), (CASES[1], force), (CASES[4], force), (CASES[2], cone), (CASES[3], cone)]
FORCE_IDS = ["1D-local-force", "1D-gains-force", "1D-lwa-force", "2D-cone", "2D-gains-cone"]


@pytest.mark.parametrize("case, residual", FORCE_CASES, ids=FORCE_IDS)
def test_force_residuals_on_1d_and_2d_contacts_compile_and_match_the_python_node(case, residual):
    """A contact-force residual on a 1D contact (``nc = 1``: the force along its axis) and a friction cone on a 2D
    contact read the contact's own rows (``A E``, :func:`crocopy.models.rbd.contact_lowering.force_parameters`)."""
    dam = make_dam(*case, residual, seed=4)
    iam = crocopy.IntegratedActionModelEuler(dam, 0.01)
    problem = crocopy.ShootingProblem(dam.state.zero(), [iam], iam)
    assert all(entry.compiled for entry in crocopy.compiled_coverage(problem))
    x, u = point(dam.state, iam.nu, 4)
    compare_with_python_node(iam, x, u, False, rtol=1e-7, atol=1e-7, cost_rel=1e-9)
    check_finite_differences(iam, dam.state, x, u, h=1e-6, atol=1e-5, roundoff=1e-10)


@pytest.mark.parametrize("case, residual", [(CASES[0], force), (CASES[2], cone), (CASES[3], cone)],
                         ids=["1D-force", "2D-cone", "2D-gains-cone"])
def test_force_constraints_on_1d_and_2d_contacts_match_the_python_node(case, residual):
    """The force of a 1D contact as an equality, a friction cone on a 2D contact as an inequality: the node's rows."""
    dam = make_dam(*case, seed=5)
    state, nu = dam.state, dam.nu
    constraint = residual(state, state.pinocchio.getFrameId("LF_FOOT"), nu)
    bounds = np.full(constraint.nr, np.inf)
    manager = crocopy.ConstraintModelManager(state, nu)
    manager.addConstraint("c", crocopy.ConstraintModelResidual(state, constraint, False) if residual is force
                          else crocopy.ConstraintModelResidual(state, constraint, -bounds, np.zeros(constraint.nr)))
    constrained = crocopy.DifferentialActionModelContactFwdDynamics(state, dam.actuation, dam.contacts, dam.costs,
                                                                    manager, 0.0, True)
    constrained.use_pinocchio_constraints = False
    iam = crocopy.IntegratedActionModelEuler(constrained, 0.01)
    x, u = point(state, nu, 5)
    fast, slow = iam.createData(), iam.createData()
    iam._compiled_node(fast, False, {}).calcDiff(x, u, False)
    iam.calc(slow, x, u)
    iam.calcDiff(slow, x, u)
    assert iam.ng + iam.nh == constraint.nr
    for name in ("g", "Gx", "Gu", "h", "Hx", "Hu"):
        a, b = getattr(fast, name), getattr(slow, name)
        np.testing.assert_allclose(a, b, rtol=1e-8, atol=1e-8 * max(1.0, np.abs(b).max(initial=0.0)), err_msg=name)


def test_projected_contact_parameters_are_read_again():
    """A 1D contact's ``reference`` and ``Raxis`` and a 2D contact's ``reference`` and gains assigned after an
    evaluator was made: the next one evaluates the new contacts (as the Python node)."""
    iam, state = euler(("1A23W6W", (3.0, 1.0)), seed=3)
    data = iam.createData()
    x, u = point(state, iam.nu, 3)
    iam._compiled_node(data, False, {})
    contacts = iam.differential.contacts.contacts
    one, two = contacts["LF_FOOT"].contact, contacts["RF_FOOT"].contact
    one.reference = 0.3
    one.Raxis = pin.rpy.rpyToMatrix(-0.2, 0.5, 0.1)
    two.reference = np.array([0.2, -0.1])
    two.gains = np.array([6.0, 2.0])
    check_new_evaluator(iam, data, x, u)
