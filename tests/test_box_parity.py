"""Rules that make the box solvers follow Crocoddyl 3.2 (crocopy-only checks; the side-by-side runs
against Crocoddyl are ``crocopy bench --box-parity``, :mod:`crocopy.bench.box_parity`)."""

import numpy as np
import pytest

import crocopy
from crocopy import ActionModelUnicycle
from crocopy.bench.box_parity import Trace, first_divergence, meets_bar, solve_trace
from crocopy.shooting import ShootingProblem
from crocopy.solvers.box_ddp import SolverBoxDDP
from crocopy.solvers.box_fddp import SolverBoxFDDP
from crocopy.solvers.box_qp import BoxQP

# a QP on which the flipped Armijo sign cycles (Crocoddyl 3.2 returns the same non-optimal point)
A = np.array([[-0.8, 0.5, 0.3], [-1.6, 0.4, 0.4], [-1.4, 0.6, -0.2]])
H_CYCLE = A @ A.T + 0.1 * np.eye(3)
Q_CYCLE = np.array([0.9, -0.3, 0.6])
LB_CYCLE = np.array([-0.7, -0.3, -0.8])
UB_CYCLE = np.array([0.5, 0.3, 0.3])


def kkt_residual(H, q, lb, ub, x):
    g = q + H @ x
    r = np.where(x <= lb, np.minimum(g, 0.0), np.where(x >= ub, np.maximum(g, 0.0), g))
    return np.abs(r).max()


def objective(x):
    return 0.5 * x @ H_CYCLE @ x + Q_CYCLE @ x


def test_paper_armijo_converges_where_the_flipped_sign_cycles():
    paper = BoxQP(3, reg=0.0)
    x_paper = paper.solve(H_CYCLE, Q_CYCLE, LB_CYCLE, UB_CYCLE, np.zeros(3)).x.copy()
    compat = BoxQP(3, reg=0.0)
    compat.compat_crocoddyl = True
    x_compat = compat.solve(H_CYCLE, Q_CYCLE, LB_CYCLE, UB_CYCLE, np.zeros(3)).x.copy()
    assert kkt_residual(H_CYCLE, Q_CYCLE, LB_CYCLE, UB_CYCLE, x_paper) < 1e-9 and paper.iter < 10
    assert compat.iter == compat.maxiter
    assert kkt_residual(H_CYCLE, Q_CYCLE, LB_CYCLE, UB_CYCLE, x_compat) > 0.1
    assert objective(x_compat) > objective(x_paper) + 0.1


def test_flipped_sign_accepts_a_cost_increase_the_paper_rule_rejects():
    x0 = np.array([-0.7, 0.3, 0.3])  # where the cycle of the flipped rule passes
    for compat, increases in ((True, True), (False, False)):
        qp = BoxQP(3, maxiter=1, reg=0.0)
        qp.compat_crocoddyl = compat
        x1 = qp.solve(H_CYCLE, Q_CYCLE, LB_CYCLE, UB_CYCLE, x0).x
        assert not np.array_equal(x1, x0)
        assert (objective(x1) > objective(x0)) == increases


def test_gradient_test_is_the_infinity_norm_of_the_pre_step_gradient():
    # g = (0.4, 0.4) at x0: infinity norm 0.4 <= 0.5 < 2-norm 0.57: one (exact) step, then stop
    qp = BoxQP(2, th_grad=0.5, reg=0.0)
    sol = qp.solve(np.eye(2), np.zeros(2), -np.ones(2), np.ones(2), np.full(2, 0.4))
    assert qp.iter == 1 and np.allclose(sol.x, 0.0)
    qp.th_grad = 0.39
    qp.solve(np.eye(2), np.zeros(2), -np.ones(2), np.ones(2), np.full(2, 0.4))
    assert qp.iter == 2


@pytest.mark.parametrize("seed", range(6))
def test_regularized_qp_is_solved_consistently(seed):
    rng = np.random.default_rng(seed)
    n = 5
    M = rng.standard_normal((n, n))
    H = M @ M.T + 0.1 * np.eye(n)
    q = 3.0 * rng.standard_normal(n)
    lb, ub = -rng.random(n) - 0.05, rng.random(n) + 0.05
    qp = BoxQP(n, reg=0.3)
    sol = qp.solve(H, q, lb, ub, rng.standard_normal(n))
    Hr = H + 0.3 * np.eye(n)
    assert kkt_residual(Hr, q, lb, ub, sol.x) < 1e-8
    g = q + Hr @ sol.x
    clamped = [j for j in range(n) if (sol.x[j] <= lb[j] and g[j] > 0) or (sol.x[j] >= ub[j] and g[j] < 0)]
    assert sol.clamped_idx == clamped


def unicycle(T=15):
    model = ActionModelUnicycle()
    model.u_lb, model.u_ub = np.array([-0.3, -0.2]), np.array([0.3, 0.2])
    return ShootingProblem(np.array([1.0, 2.0, 0.5]), [model] * T, ActionModelUnicycle())


@pytest.mark.parametrize("compat", [False, True])
def test_qp_warm_start_is_the_previous_step(compat):
    problem = unicycle()
    solver = SolverBoxFDDP(problem)
    solver.compat_crocoddyl = compat
    with crocopy.use_kernels(False):
        solver.solve(None, None, 3, True)
        previous = [k.copy() for k in solver.k]
        qp = solver._qps[2]
        starts = []
        solve = qp._solve
        qp._solve = lambda H, q, lb, ub, xinit: starts.append(xinit.copy()) or solve(H, q, lb, ub, xinit)
        solver.computeDirection(True)
    assert len(starts) == problem.T
    for t, xinit in enumerate(reversed(starts)):
        assert np.array_equal(xinit, previous[t] if compat else -previous[t])


@pytest.mark.parametrize("compat", [False, True])
def test_box_ddp_rollout_from_an_infeasible_iterate(compat):
    problem = unicycle()
    solver = SolverBoxDDP(problem)
    solver.compat_crocoddyl = compat
    xs = [np.array([1.0, 2.0, 0.5]) + 0.1 * t for t in range(problem.T + 1)]
    solver.setCandidate(xs, [np.zeros(2)] * problem.T, False)
    solver.preg = solver.dreg = 1e-9
    solver.computeDirection(True)
    gaps = [f.copy() for f in solver.fs]
    assert np.abs(gaps[-1]).max() > 0.05
    solver.forwardPass(0.5)
    model = problem.runningModels[0]
    for t in range(problem.T):
        data = model.createData()
        model.calc(data, solver.xs_try[t], solver.us_try[t])
        gap = model.state.diff(solver.xs_try[t + 1], data.xnext)
        expected = 0.5 * gaps[-1] if (compat and t == problem.T - 1) else np.zeros(3)
        assert np.allclose(gap, expected, atol=1e-12)
    assert np.array_equal(solver.xs_try[0], problem.x0)


def test_compat_flag_reaches_every_box_qp_and_reports_gaps_of_feasible_iterates():
    problem = unicycle()
    solver = SolverBoxDDP(problem)
    assert solver.compat_crocoddyl is False and not any(qp.compat_crocoddyl for qp in solver._qps.values())
    solver.compat_crocoddyl = True
    assert all(qp.compat_crocoddyl for qp in solver._qps.values())
    xs = [np.array([1.0, 2.0, 0.5])] * (problem.T + 1)
    solver.setCandidate(xs, [np.full(2, 0.1)] * problem.T, True)
    solver.calcDiff()
    assert solver.ffeas > 0.0 and all(not f.any() for f in solver.fs)


def test_parity_helpers():
    ref = Trace(3, 1.0, True, 0.0, [(3.0, 1.0, 1.0), (2.0, 0.5, 0.5), (1.0, 1e-6, 1.0)])
    same = Trace(3, 1.0 + 1e-9, True, 0.0, [(3.0, 1.0, 1.0), (2.0, 0.5, 0.5), (1.0, 1e-6 * (1 + 1e-8), 1.0)])
    assert first_divergence(ref, same) is None and meets_bar(ref, same)
    other = Trace(3, 1.1, True, 0.0, [(3.0, 1.0, 1.0), (2.0, 0.5, 0.25), (1.1, 1e-6, 1.0)])
    assert first_divergence(ref, other) == 1 and not meets_bar(ref, other)
    shorter = Trace(2, 1.0, True, 0.0, ref.log[:2])
    assert first_divergence(ref, shorter) == 2 and not meets_bar(ref, shorter)


def test_solve_trace_logs_every_iteration():
    import crocopy

    trace = solve_trace(crocopy, "quad-goal", "boxfddp", maxiter=4, compat=True)
    assert trace.iters == 4 and len(trace.log) == 4 and not trace.converged
    assert all(np.isfinite(row[0]) for row in trace.log)
    with pytest.raises(ValueError, match="solver_name"):
        solve_trace(crocopy, "quad-goal", "fddp")
