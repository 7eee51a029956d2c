"""SolverIntro and SolverKKT on equality-constrained and unconstrained problems (crocopy alone)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from intro_problems import arm_problem, lq_equality_problem, nonlinear_equality_problem

import crocopy

EQ_SOLVERS = (crocopy.EqualitySolverType.LuNull, crocopy.EqualitySolverType.QrNull, crocopy.EqualitySolverType.Schur)


def _solve_intro(problem, eq_solver, xs=(), us=(), maxiter=100):
    solver = crocopy.SolverIntro(problem)
    solver.eq_solver = eq_solver
    converged = solver.solve(list(xs), list(us), maxiter)
    return solver, converged


def _running_h(problem):
    us = [np.zeros(m.nu) for m in problem.runningModels]
    problem.calc(problem.rollout(us), us)
    return np.concatenate([d.h for d in problem.runningDatas])


@pytest.mark.parametrize("eq_solver", EQ_SOLVERS)
def test_intro_solves_lq_equality_problem_in_one_iteration(eq_solver):
    problem = lq_equality_problem(crocopy)
    assert np.abs(_running_h(problem)).max() > 0.1
    solver, converged = _solve_intro(problem, eq_solver)
    assert converged and solver.iter == 1
    problem.calc(solver.xs, solver.us)
    assert np.abs(np.concatenate([d.h for d in problem.runningDatas])).max() < 1e-10
    assert solver.hfeas < 1e-10 and solver.stop < solver.th_stop


def test_three_equality_solvers_give_the_same_solution():
    sols = [_solve_intro(nonlinear_equality_problem(crocopy, T=10, seed=3, a=0.3, b=0.1)[0], s,
                         *nonlinear_equality_problem(crocopy, T=10, seed=3, a=0.3, b=0.1)[1:])[0] for s in EQ_SOLVERS]
    for s in sols[1:]:
        assert s.iter == sols[0].iter
        assert s.cost == pytest.approx(sols[0].cost, rel=1e-9)
        for u, u0 in zip(s.us, sols[0].us):
            np.testing.assert_allclose(u, u0, atol=1e-7)


def test_lq_solution_is_the_kkt_point_of_the_constrained_qp():
    """Intro's one-step answer equals the minimiser of the stacked equality-constrained QP."""
    problem = lq_equality_problem(crocopy, T=4)
    solver, _ = _solve_intro(problem, crocopy.EqualitySolverType.QrNull)
    m = problem.runningModels[0]
    T, nx, nu = problem.T, m.state.nx, m.nu
    nw = (T + 1) * nx + T * nu
    H = np.zeros((nw, nw))
    g = np.zeros(nw)
    rows, rhs = [], []

    def x_i(t):
        return slice(t * nx, (t + 1) * nx)

    def u_i(t):
        return slice((T + 1) * nx + t * nu, (T + 1) * nx + (t + 1) * nu)

    d = m.createData()
    xz, uz = np.zeros(nx), np.zeros(nu)
    m.calc(d, xz, uz)
    m.calcDiff(d, xz, uz)
    for t in range(T):
        H[x_i(t), x_i(t)] = d.Lxx
        H[u_i(t), u_i(t)] = d.Luu
        H[x_i(t), u_i(t)] = d.Lxu
        H[u_i(t), x_i(t)] = d.Lxu.T
        g[x_i(t)], g[u_i(t)] = d.Lx, d.Lu
        dyn = np.zeros((nx, nw))
        dyn[:, x_i(t + 1)] = np.eye(nx)
        dyn[:, x_i(t)], dyn[:, u_i(t)] = -d.Fx, -d.Fu
        rows.append(dyn)
        rhs.append(d.xnext)
        eq = np.zeros((m.nh, nw))
        eq[:, x_i(t)], eq[:, u_i(t)] = d.Hx, d.Hu
        rows.append(eq)
        rhs.append(-d.h)
    td = problem.terminalModel.createData()
    problem.terminalModel.calc(td, xz)
    problem.terminalModel.calcDiff(td, xz)
    H[x_i(T), x_i(T)], g[x_i(T)] = td.Lxx, td.Lx
    init = np.zeros((nx, nw))
    init[:, x_i(0)] = np.eye(nx)
    rows.append(init)
    rhs.append(problem.x0)
    J = np.vstack(rows)
    kkt = np.block([[H, J.T], [J, np.zeros((J.shape[0], J.shape[0]))]])
    w = np.linalg.solve(kkt, np.concatenate([-g, np.concatenate(rhs)]))[:nw]
    for t in range(T):
        np.testing.assert_allclose(solver.us[t], w[u_i(t)], atol=1e-9)
        np.testing.assert_allclose(solver.xs[t + 1], w[x_i(t + 1)], atol=1e-9)


def test_intro_without_constraints_is_fddp():
    model = crocopy.ActionModelUnicycle()
    problem = crocopy.ShootingProblem(np.array([-1.0, -1.0, 1.0]), [model] * 20, model)
    intro, fddp = crocopy.SolverIntro(problem), crocopy.SolverFDDP(problem)
    assert intro.solve([], [], 50) and fddp.solve([], [], 50)
    assert intro.iter == fddp.iter
    assert intro.cost == pytest.approx(fddp.cost, rel=1e-12)
    assert intro.upsilon == 0.0


def test_intro_attributes_and_defaults():
    solver = crocopy.SolverIntro(lq_equality_problem(crocopy, T=3))
    assert solver.eq_solver == crocopy.LuNull
    assert (solver.th_feas, solver.rho, solver.upsilon, solver.zero_upsilon) == (1e-4, 0.3, 0.0, False)
    solver.solve([], [], 5)
    assert solver.Hu_rank == [2, 2, 2]
    assert solver.YZ[0].shape == (3, 3)
    assert solver.Hy[0].shape == (2, 2)
    assert solver.Qzz[0].shape == (1, 1) and solver.Qz[0].shape == (1,)
    np.testing.assert_allclose(solver.Hy[0], solver.Hy[0].T, atol=1e-12)  # LU: Y = Huᵀ
    with pytest.raises(AttributeError):
        solver.upsilon = 1.0
    with pytest.raises(ValueError, match="eq_solver"):
        solver.eq_solver = 7


def test_zero_upsilon_resets_the_penalty():
    problem, xs, us = nonlinear_equality_problem(crocopy, T=10, seed=3, a=0.3, b=0.1)
    solver = crocopy.SolverIntro(problem)
    solver.solve(xs, us, 5)
    assert solver.upsilon > 0.0
    kept = solver.upsilon
    solver.solve(xs, us, 0)
    assert solver.upsilon == kept
    solver.solve(xs, us, 1)
    assert solver.upsilon >= kept
    solver.zero_upsilon = True
    solver.solve(xs, us, 0)
    assert solver.upsilon == 0.0


@pytest.mark.parametrize("kernels", [True, False], ids=["kernels", "python"])
def test_a_reused_solver_with_zero_upsilon_solves_as_a_fresh_one(kernels):
    """A solver that converged (its ``hfeas`` tiny) solves again from the same guess with ``zero_upsilon``: the first
    iteration of the new solve leaves ``upsilon`` alone (as a fresh solver's does), so both solves are the same."""
    problem, xs, us = nonlinear_equality_problem(crocopy, T=12, seed=3, a=0.5, b=0.1)
    with crocopy.use_kernels(kernels):
        reused = crocopy.SolverIntro(problem)
        assert reused.solve(list(xs), list(us), 100)
        assert 0.0 < reused.hfeas < 1e-6
        reused.zero_upsilon = True
        reused.solve(list(xs), list(us), 100)
        fresh = crocopy.SolverIntro(problem)
        fresh.solve(list(xs), list(us), 100)
    assert (reused.iter, reused.cost, reused.upsilon) == (fresh.iter, fresh.cost, fresh.upsilon)


def test_kkt_solves_lqr_in_one_iteration_like_fddp():
    problem = lq_equality_problem(crocopy, nh=0)
    kkt, fddp = crocopy.SolverKKT(problem), crocopy.SolverFDDP(problem)
    assert kkt.solve([], [], 10) and kkt.iter == 1
    assert fddp.solve([], [], 10)
    assert kkt.cost == pytest.approx(fddp.cost, rel=1e-10)
    for x, y in zip(kkt.xs, fddp.xs):
        np.testing.assert_allclose(x, y, atol=1e-9)
    n = (problem.T + 1) * 4 * 2 + problem.T * 3
    assert kkt.kkt.shape == (n, n) and kkt.kktref.shape == (n,) and kkt.primaldual.shape == (n,)
    assert len(kkt.dxs) == len(kkt.lambdas) == problem.T + 1 and len(kkt.dus) == problem.T


def test_kkt_nonlinear_matches_fddp():
    model = crocopy.ActionModelUnicycle()
    problem = crocopy.ShootingProblem(np.array([-1.0, -1.0, 1.0]), [model] * 20, model)
    kkt, fddp = crocopy.SolverKKT(problem), crocopy.SolverFDDP(problem)
    assert kkt.solve([], [], 50) and fddp.solve([], [], 50)
    assert kkt.cost == pytest.approx(fddp.cost, rel=1e-9)


class _Exploding(crocopy.ActionModelAbstract):
    """One control, one equality row ``u - 3 = 0``; the cost overflows to inf for ``u > 1``."""

    def __init__(self):
        crocopy.ActionModelAbstract.__init__(self, crocopy.StateVector(1), 1, 0, 0, 1, 0, 0)

    def calc(self, data, x, u=None):
        if u is None:
            data.cost = float(x @ x)
            return
        data.xnext[:] = x + u
        with np.errstate(over="ignore"):
            data.cost = float(np.exp(800.0 * (u[0] - 1.0)) + x @ x)
        data.h[:] = u - 3.0

    def calcDiff(self, data, x, u=None):
        data.Lx[:] = 2 * x
        data.Lxx[:] = 2.0
        if u is None:
            return
        data.Fx[:] = 1.0
        data.Fu[:] = 1.0
        with np.errstate(over="ignore"):
            e = np.exp(800.0 * (u[0] - 1.0))
        data.Lu[:] = 800.0 * e
        data.Luu[:] = 640000.0 * e + 1.0
        data.Hx[:] = 0.0
        data.Hu[:] = 1.0


class _NanBeyond(crocopy.ActionModelAbstract):
    """One control pulled to 5 by ``(u - 5)²``; the cost is NaN for ``|u| > 2`` (no equality rows)."""

    def __init__(self):
        crocopy.ActionModelAbstract.__init__(self, crocopy.StateVector(1), 1, 0)

    def calc(self, data, x, u=None):
        data.cost = 0.0
        if u is not None:
            data.xnext[:] = x + u
            data.cost = float((u[0] - 5.0) ** 2) if abs(u[0]) <= 2.0 else np.nan

    def calcDiff(self, data, x, u=None):
        if u is not None:
            data.Fx[:] = 1.0
            data.Fu[:] = 1.0
            data.Lu[:] = 2.0 * (u - 5.0)
            data.Luu[:] = 2.0


@pytest.mark.parametrize(("make", "model_class"), [
    (crocopy.SolverIntro, _Exploding), (crocopy.SolverIntro, _NanBeyond), (crocopy.SolverKKT, _NanBeyond),
])
def test_a_diverging_solve_returns_false_without_nan(make, model_class):
    model = model_class()
    problem = crocopy.ShootingProblem(np.array([0.5]), [model] * 3, model)
    solver = make(problem)
    assert solver.solve([], [], 20) is False
    assert all(np.isfinite(x).all() for x in solver.xs)
    assert all(np.isfinite(u).all() for u in solver.us)
    assert np.isfinite(solver.cost)


def test_registered_and_exported():
    from crocopy.solvers import SOLVERS

    assert SOLVERS["intro"] == "SolverIntro" and SOLVERS["kkt"] == "SolverKKT"
    assert (crocopy.LuNull, crocopy.QrNull, crocopy.Schur) == EQ_SOLVERS


def test_arm_acceleration_rows_three_solvers_agree():
    """Talos' arm with its joint accelerations held by equality rows (``Hu = M⁻¹``, nonlinear in q)."""
    results = []
    for eq in EQ_SOLVERS:
        solver, converged = _solve_intro(arm_problem(crocopy, T=10), eq)
        assert converged and solver.hfeas < 1e-9
        results.append(solver)
    for s in results[1:]:
        assert s.iter == results[0].iter
        assert s.cost == pytest.approx(results[0].cost, rel=1e-9)


def test_rows_the_controls_cannot_reach_are_left_to_hfeas():
    """Pure-state rows (``Hu = 0``): the nullspace solvers keep the whole control space (rank 0) and
    the rows only count in ``hfeas``; the Schur complement is singular and the solve returns False."""
    model = crocopy.ActionModelLQR(np.eye(2), np.eye(2), np.eye(2), np.eye(2), np.zeros((2, 2)),
                                   np.zeros((0, 4)), np.array([[1.0, 0.0, 0.0, 0.0]]), np.zeros(2), np.zeros(2),
                                   np.zeros(2), np.zeros(0), np.array([-1.0]))
    problem = crocopy.ShootingProblem(np.zeros(2), [model] * 3, crocopy.ActionModelLQR(2, 2))
    lu, _ = _solve_intro(problem, crocopy.LuNull, maxiter=5)
    assert lu.Hu_rank == [0, 0, 0]
    assert lu.hfeas > 0.5
    assert all(np.isfinite(u).all() for u in lu.us)
    schur, converged = _solve_intro(problem, crocopy.Schur, maxiter=5)
    assert converged is False
    assert "reg_max" in schur.reason


@settings(max_examples=80, deadline=None)
@given(st.integers(1, 5), st.integers(1, 7), st.integers(0, 2**32 - 1), st.sampled_from(["random", "dependent", "zeros",
                                                                                       "ties", "nan"]))
def test_compiled_full_pivot_lu_equals_its_numpy_twin(m, n, seed, kind):
    """The compiled fully pivoted LU (:mod:`crocopy.solvers.intro_kernel`) against its numpy steps, to the bit: the
    same pivots (first largest in column-major order, ties and NaN included), factor, permutations and rank."""
    from crocopy.solvers.intro import full_pivot_lu

    rng = np.random.default_rng(seed)
    A = rng.standard_normal((m, n))
    if kind == "dependent" and m > 1:
        A[-1] = 2.0 * A[0] - A[m // 2]
    elif kind == "zeros":
        A[:, rng.integers(0, n)] = 0.0
        A[rng.integers(0, m)] = 0.0
    elif kind == "ties":
        A = np.round(A)
    elif kind == "nan":
        A[rng.integers(0, m), rng.integers(0, n)] = np.nan
    with crocopy.use_kernels(True):
        compiled = full_pivot_lu(A, 1e-12)
    with crocopy.use_kernels(False):
        twin = full_pivot_lu(A, 1e-12)
    assert compiled[3] == twin[3]
    for a, b in zip(compiled[:3], twin[:3]):
        np.testing.assert_array_equal(a, b)


def test_non_finite_equality_rows_fail_the_backward_pass_quietly(capfd):
    """NaN in a node's equality rows: BackwardPassError from the least squares (nothing printed by LAPACK)."""
    from crocopy.solvers.base import BackwardPassError
    from crocopy.solvers.intro import _least_squares

    A = np.array([[np.nan, 1.0], [2.0, 3.0], [1.0, 1.0]])
    with pytest.raises(BackwardPassError, match="non-finite equality rows"):
        _least_squares(A, np.ones(3), np.ones((3, 2)))
    with pytest.raises(BackwardPassError, match="non-finite equality rows"):
        _least_squares(np.eye(2), np.array([np.inf, 0.0]), np.ones((2, 2)))
    big = np.full((2, 2), 1e308)
    with np.errstate(over="ignore"):  # finite rows whose sum overflows: checked entry by entry, then solved
        sol, _ = _least_squares(big + np.diag([1e308, 0.0]) * 0.5, np.ones(2), np.ones((2, 1)))
    assert np.isfinite(sol).all()
    assert capfd.readouterr().err == ""
