"""IRIS quadrotor problems (:mod:`crocopy.problems.quadrotor`): way-point geometry, build, quick solves."""

import numpy as np
import pinocchio as pin
import pytest

import crocopy
from crocopy.problems import quadrotor, registry


@pytest.mark.parametrize("start", [(-0.3, 0.0, 0.0), (0.5, -1.0, 2.0)])
def test_loop_is_closed_at_the_start_and_thrust_points_at_the_centre(start):
    T, waypoints = quadrotor.task_waypoints("loop", start=start)
    assert T == 100 and [t for t, _, _ in waypoints] == [25, 50, 75, 100]
    centre = np.asarray(start) + [0.0, 0.0, 1.0]
    last_node, last, last_velocity = waypoints[-1]
    assert np.allclose(last.translation, start) and np.allclose(last.rotation, np.eye(3))
    assert np.allclose(last_velocity, 0.0)
    heights = []
    for _, M, _ in waypoints[:-1]:
        to_centre = centre - M.translation
        assert np.linalg.norm(to_centre) == pytest.approx(1.0)
        assert np.allclose(M.rotation[:, 2], to_centre)  # body z (thrust) towards the centre
        assert abs(M.translation[1] - start[1]) < 1e-12  # vertical x-z plane through the start
        heights.append(M.translation[2] - start[2])
    assert heights == pytest.approx([1.0, 2.0, 1.0])  # front, top (upside down), back


def test_problems_build_with_finite_first_derivatives():
    for task, T in (("goal", 50), ("loop", 100), ("narrow", 60)):
        problem, xs, us = quadrotor.build_quadrotor(crocopy, task=task)
        assert (problem.T, problem.nx, problem.ndx, problem.runningModels[0].nu) == (T, 13, 12, 4)
        assert np.allclose(problem.runningModels[0].u_lb, 0.1) and np.allclose(problem.runningModels[0].u_ub, 10.3)
        assert np.isfinite(problem.calc(xs, us))
        problem.calcDiff(xs, us)
        for d in problem.runningDatas:
            assert np.all(np.isfinite(d.Fx)) and np.all(np.isfinite(d.Lxx)) and np.all(np.isfinite(d.Luu))


def test_waypoint_costs_are_zero_on_the_targets():
    """Placing the base on a way-point's placement and velocity zeroes that node's way-point costs."""
    problem, _, _ = quadrotor.build_quadrotor(crocopy, task="loop")
    _, waypoints = quadrotor.task_waypoints("loop")
    node, M, _ = waypoints[1]
    model, data = problem.runningModels[node], problem.runningDatas[node]
    x = np.concatenate([M.translation, pin.Quaternion(M.rotation).coeffs(), np.zeros(6)])
    model.calc(data, x, np.full(4, 1.0))
    assert data.differential.costs.costs["waypoint"].cost == pytest.approx(0.0, abs=1e-20)


def test_bad_arguments_raise():
    with pytest.raises(ValueError, match="task"):
        quadrotor.build_quadrotor(crocopy, task="flip")
    with pytest.raises(ValueError, match="x0_position"):
        quadrotor.build_quadrotor(crocopy, x0_position=(0.0, 1.0))
    with pytest.raises(ValueError, match="way-point nodes"):
        quadrotor.build_quadrotor(crocopy, task="loop", T=2)


@pytest.mark.parametrize(("name", "solver"), [("quad-loop", "fddp"), ("quad-goal", "boxfddp")])
def test_quick_solves_reach_the_documented_cost(name, solver):
    spec = registry.get(name)
    problem, xs, us = spec.build(crocopy)
    s = {"fddp": crocopy.SolverFDDP, "boxfddp": crocopy.SolverBoxFDDP}[solver](problem)
    assert s.solve(xs, us, spec.maxiter, False)
    ref = spec.reference[solver]
    if ref.exact:
        assert s.cost == pytest.approx(ref.cost, rel=spec.rtol)
    else:  # crocopy's Box-FDDP follows the paper and ends no higher than Crocoddyl's
        assert s.cost <= ref.cost * (1.0 + spec.rtol)
    if solver == "boxfddp":
        thrusts = np.array(s.us)
        assert thrusts.min() >= 0.1 - 1e-9 and thrusts.max() <= 10.3 + 1e-9
