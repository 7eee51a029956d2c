"""A solver's trajectories and a data's arrays own their storage: assigning copies, as Crocoddyl's bindings do.

``solver.xs = ...``, ``solver.xs[t] = ...`` and ``data.Fx = M`` copy into the arrays made at construction
(:class:`crocopy.solvers.std_vector.Trajectory`, :mod:`crocopy.stored`); a wrong length or shape raises
``ValueError`` naming the attribute, and a trajectory's length is fixed.
"""

from __future__ import annotations

import copy
import pickle

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import crocopy


def _solver(Solver=crocopy.SolverFDDP, T: int = 6) -> crocopy.SolverAbstract:
    model = crocopy.ActionModelUnicycle()
    problem = crocopy.ShootingProblem(np.array([-1.0, -1.0, 1.0]), [model] * T, crocopy.ActionModelUnicycle())
    return Solver(problem)


SOLVERS = (crocopy.SolverDDP, crocopy.SolverFDDP, crocopy.SolverBoxFDDP, crocopy.SolverIntro, crocopy.SolverKKT)


@pytest.mark.parametrize("Solver", SOLVERS, ids=lambda S: S.__name__)
def test_assigning_a_trajectory_copies_into_the_solver_arrays(Solver):
    solver = _solver(Solver)
    held = list(solver.xs)
    mine = [np.full(3, float(t)) for t in range(len(held))]
    solver.xs = mine
    assert all(a is b for a, b in zip(solver.xs, held, strict=True))
    np.testing.assert_array_equal(solver.xs[4], mine[4])
    mine[4][:] = 7.0  # the caller's arrays stay the caller's
    assert solver.xs[4][0] == 4.0
    solver.xs[2] = [1.0, 2.0, 3.0]
    assert solver.xs[2] is held[2]
    np.testing.assert_array_equal(held[2], [1.0, 2.0, 3.0])
    solver.us[0] = np.array([[0.5], [0.25]])  # a column is copied in
    np.testing.assert_array_equal(solver.us[0], [0.5, 0.25])


def test_a_shifted_warm_start_of_the_solver_own_arrays_is_read_before_written():
    solver = _solver()
    for t, x in enumerate(solver.xs):
        x[:] = t
    solver.xs = solver.xs[1:] + [solver.xs[-1]]
    np.testing.assert_array_equal([x[0] for x in solver.xs], [1, 2, 3, 4, 5, 6, 6])
    solver.xs[0:3] = solver.xs[2:5]
    np.testing.assert_array_equal([x[0] for x in solver.xs], [3, 4, 5, 4, 5, 6, 6])


@pytest.mark.parametrize(("assign", "message"), [
    (lambda s: setattr(s, "xs", [np.zeros(3)] * 3), r"solver\.xs has 7 entries: cannot assign 3"),
    (lambda s: setattr(s, "us", [np.zeros(3)] * 6), r"solver\.us\[0\] has shape \(2,\): cannot assign a value of "
                                                    r"shape \(3,\)"),
    (lambda s: s.xs.__setitem__(1, np.zeros(4)), r"solver\.xs\[1\] has shape \(3,\)"),
    (lambda s: s.xs.__setitem__(slice(0, 2), [np.zeros(3)]), r"has 2 entries: cannot assign 1"),
])
def test_a_wrong_length_or_shape_is_refused_and_nothing_changes(assign, message):
    solver = _solver()
    before = [x.copy() for x in solver.xs + solver.us]
    with pytest.raises(ValueError, match=message):
        assign(solver)
    for a, b in zip(solver.xs + solver.us, before, strict=True):
        np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("change", [lambda xs: xs.append(np.zeros(3)), lambda xs: xs.pop(), lambda xs: xs.clear(),
                                    lambda xs: xs.extend([]), lambda xs: xs.__delitem__(0),
                                    lambda xs: xs.insert(0, np.zeros(3)), lambda xs: xs.sort()])
def test_a_trajectory_has_a_fixed_length(change):
    solver = _solver()
    with pytest.raises(TypeError, match="solver.xs has a fixed length"):
        change(solver.xs)
    assert len(solver.xs) == 7


def test_copies_and_lists_of_a_trajectory_are_the_caller_own():
    solver = _solver()
    mine = solver.xs.copy()
    mine.append(np.zeros(3))
    assert len(mine) == 8 and len(solver.xs) == 7
    listed = solver.xs.tolist()
    listed[0][:] = 5.0
    assert solver.xs[0][0] != 5.0


def test_a_pickled_or_copied_solver_has_arrays_of_its_own():
    solver = _solver()
    solver.solve([], [], 5)
    for other in (pickle.loads(pickle.dumps(solver)), copy.deepcopy(solver)):
        assert all(a is not b for a, b in zip(other.xs, solver.xs))
        assert other.solve([], [], 5) == solver.solve([], [], 5)
        assert other.iter == solver.iter
        np.testing.assert_allclose(other.cost, solver.cost, rtol=1e-12)


@settings(max_examples=40, deadline=None)
@given(rows=st.integers(1, 5), cols=st.integers(1, 5))
def test_a_data_field_takes_only_its_own_shape(rows, cols):
    model = crocopy.ActionModelLQR(3, 2)
    data = model.createData()
    held = data.Fx
    value = np.ones((rows, cols))
    if (rows, cols) == (3, 3):
        data.Fx = value
        assert data.Fx is held
        np.testing.assert_array_equal(held, value)
    else:
        with pytest.raises(ValueError, match=rf"data\.Fx has shape \(3, 3\): cannot assign a value of shape "
                                             rf"\({rows}, {cols}\)"):
            data.Fx = value
        assert data.Fx is held


def test_every_array_field_of_an_action_data_copies():
    model = crocopy.ActionModelLQR(3, 2)
    data = model.createData()
    for name in ("xnext", "r", "Fx", "Fu", "Lx", "Lu", "Lxx", "Lxu", "Luu"):
        held = getattr(data, name)
        setattr(data, name, np.full(held.shape, 2.5))
        assert getattr(data, name) is held and (held == 2.5).all(), name
    with pytest.raises(AttributeError, match="data.Fx cannot be deleted"):
        del data.Fx


def test_a_problem_node_lists_are_read_only_and_update_model_keeps_solvers_in_step():
    model = crocopy.ActionModelUnicycle()
    problem = crocopy.ShootingProblem(np.array([-1.0, -1.0, 1.0]), [model] * 5, model)
    solver = crocopy.SolverFDDP(problem)
    solver.solve([], [], 10)
    other = crocopy.ActionModelLQR(3, 2)
    for change in (lambda: problem.runningModels.__setitem__(2, other),
                   lambda: problem.runningDatas.__setitem__(2, other.createData()),
                   lambda: problem.runningModels.append(other), lambda: problem.runningDatas.pop()):
        with pytest.raises(TypeError, match=r"read-only: change a node with problem\.updateModel"):
            change()
    assert problem.runningModels[2] is model and len(problem.runningDatas) == 5
    mine = problem.runningModels.tolist()
    mine[2] = other
    problem.updateModel(2, other)
    assert solver.solve([], [], 20)
    fresh = crocopy.SolverFDDP(crocopy.ShootingProblem(problem.x0, mine, model))
    assert fresh.solve([], [], 20)
    assert (solver.iter, solver.cost) == (fresh.iter, pytest.approx(fresh.cost, rel=1e-12))
    assert pickle.loads(pickle.dumps(problem)).runningModels[2].nu == 2
