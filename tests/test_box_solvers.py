"""Box-DDP and Box-FDDP: equivalence with DDP/FDDP, bounds, optimality against scipy, errors."""

import numpy as np
import pytest
from scipy.optimize import minimize

import crocopy
from crocopy import ActionModelLQR, ActionModelUnicycle
from crocopy.shooting import ShootingProblem
from crocopy.solvers import SolverDDP, SolverFDDP
from crocopy.solvers.box_ddp import SolverBoxDDP
from crocopy.solvers.box_fddp import SolverBoxFDDP
from crocopy.solvers.clamping import SolverClampedDDP

PAIRS = [(SolverBoxDDP, SolverDDP), (SolverBoxFDDP, SolverFDDP)]


def unicycle_problem(T=20, lb=(-0.3, -0.2), ub=(0.3, 0.2), x0=(1.0, 2.0, 0.5)):
    model = ActionModelUnicycle()
    model.u_lb, model.u_ub = np.array(lb), np.array(ub)
    return ShootingProblem(np.array(x0), [model] * T, ActionModelUnicycle())


def lqr_problem(T=10, nx=4, nu=2, seed=3, lb=-1.5, ub=1.2):
    rng = np.random.default_rng(seed)
    A = np.eye(nx) + 0.1 * rng.standard_normal((nx, nx))
    B = rng.standard_normal((nx, nu))
    L = rng.standard_normal((nx, nx))
    Q = L @ L.T / nx + np.eye(nx)
    R = np.eye(nu) * 0.5
    N = 0.1 * rng.standard_normal((nx, nu))
    model = ActionModelLQR(A, B, Q, R, N, rng.standard_normal(nx), rng.standard_normal(nx), rng.standard_normal(nu))
    model.u_lb, model.u_ub = np.full(nu, lb), np.full(nu, ub)
    x0 = rng.standard_normal(nx) * 3.0
    return ShootingProblem(x0, [model] * T, model), model


def record(solver):
    rows = []
    solver.setCallbacks([lambda s: rows.append(([x.copy() for x in s.xs], [u.copy() for u in s.us], s.cost))])
    return rows


@pytest.mark.parametrize(("Box", "Plain"), PAIRS)
@pytest.mark.parametrize("feasible", [True, False])
def test_inactive_bounds_give_the_plain_solver_iterates(Box, Plain, feasible):
    problem = unicycle_problem(T=25, lb=(-1e3, -1e3), ub=(1e3, 1e3))
    us0 = [np.array([0.1, -0.05])] * problem.T
    xs0 = problem.rollout(us0) if feasible else None
    box, plain = Box(problem), Plain(problem)
    rows_box, rows_plain = record(box), record(plain)
    ok_box = box.solve(xs0, us0, 50, feasible)
    ok_plain = plain.solve(xs0, us0, 50, feasible)
    assert ok_box == ok_plain
    assert len(rows_box) == len(rows_plain) > 1
    for (xb, ub, cb), (xp, up, cp) in zip(rows_box, rows_plain, strict=True):
        assert np.allclose(np.array(xb), np.array(xp), rtol=0, atol=1e-10)
        assert np.allclose(np.array(ub), np.array(up), rtol=0, atol=1e-10)
        assert cb == pytest.approx(cp, rel=1e-12)


@pytest.mark.parametrize("Solver", [SolverBoxDDP, SolverBoxFDDP])
@pytest.mark.parametrize("feasible", [True, False])
def test_bounds_are_never_violated(Solver, feasible):
    problem = unicycle_problem(T=30)
    rng = np.random.default_rng(0)
    us0 = [rng.standard_normal(2) for _ in range(problem.T)]  # partly outside the box
    if feasible:  # a feasible warm start must respect the box (it is used as given, as in Crocoddyl)
        us0 = [np.clip(u, [-0.3, -0.2], [0.3, 0.2]) for u in us0]
    xs0 = problem.rollout(us0) if feasible else None
    solver = Solver(problem)
    worst = []
    solver.setCallbacks([lambda s: worst.append(max(np.max(np.array(s.us) - [0.3, 0.2]),
                                                    np.max([-0.3, -0.2] - np.array(s.us))))])
    assert solver.solve(xs0, us0, 200, feasible)
    assert max(worst) <= 0.0
    assert solver.isFeasible
    us = np.array(solver.us)
    assert np.all(us >= [-0.3, -0.2]) and np.all(us <= [0.3, 0.2])
    assert np.any(np.isclose(us, [0.3, 0.2])) or np.any(np.isclose(us, [-0.3, -0.2]))


def condensed_lq_optimum(problem, model):
    """Optimal controls of the box-constrained LQ problem from scipy (cost as a function of U)."""
    T, nu = problem.T, model.nu

    def cost(U):
        return problem.calc(problem.rollout(list(U.reshape(T, nu))), list(U.reshape(T, nu)))

    n = T * nu
    g0 = np.zeros(n)
    H = np.zeros((n, n))
    e = np.eye(n)
    c0 = cost(np.zeros(n))
    for i in range(n):  # the cost is exactly quadratic in U: differences are exact up to roundoff
        g0[i] = (cost(e[i]) - cost(-e[i])) / 2.0
        for j in range(i, n):
            H[i, j] = H[j, i] = (cost(e[i] + e[j]) - cost(e[i]) - cost(e[j]) + c0)
    bounds = [(model.u_lb[i % nu], model.u_ub[i % nu]) for i in range(n)]
    res = minimize(lambda U: 0.5 * U @ H @ U + g0 @ U, np.zeros(n), jac=lambda U: H @ U + g0, bounds=bounds,
                   method="L-BFGS-B", options={"ftol": 1e-16, "gtol": 1e-12, "maxiter": 10000})
    return res.x.reshape(T, nu), res.fun + c0


@pytest.mark.parametrize("Solver", [SolverBoxDDP, SolverBoxFDDP])
@pytest.mark.parametrize("seed", [3, 4, 5])
def test_box_lq_optimum_matches_scipy(Solver, seed):
    problem, model = lqr_problem(seed=seed)
    U_ref, J_ref = condensed_lq_optimum(problem, model)
    solver = Solver(problem)
    solver.general_value_update = True  # Tassa's exact update; the Crocoddyl variant may stop early
    us0 = [np.zeros(model.nu)] * problem.T
    assert solver.solve(problem.rollout(us0), us0, 100, True)
    assert solver.cost == pytest.approx(J_ref, rel=1e-7)
    assert np.allclose(np.array(solver.us), U_ref, atol=1e-4)
    active = np.isclose(np.array(solver.us), 1.2) | np.isclose(np.array(solver.us), -1.5)
    assert 0 < active.sum() < active.size


@pytest.mark.parametrize("Solver", [SolverBoxDDP, SolverBoxFDDP])
def test_crocoddyl_variant_decreases_the_cost_inside_the_box(Solver):
    problem, model = lqr_problem(seed=3)
    solver = Solver(problem)
    costs = []
    solver.setCallbacks([lambda s: costs.append(s.cost)])
    us0 = [np.zeros(model.nu)] * problem.T
    solver.solve(problem.rollout(us0), us0, 30, True)
    assert costs[-1] < problem.calc(problem.rollout(us0), us0)
    assert np.all(np.diff(costs) <= 1e-9)
    us = np.array(solver.us)
    assert np.all(us >= -1.5) and np.all(us <= 1.2)


def test_feedback_rows_vanish_for_clamped_controls():
    problem = unicycle_problem(T=30)
    solver = SolverBoxDDP(problem)
    assert solver.solve(None, None, 100)
    solver.computeDirection(True)
    n_clamped = 0
    for t in range(problem.T):
        free = np.diag(solver.Quu_inv[t]) != 0.0
        assert np.all(solver.K[t][~free] == 0.0)
        n_clamped += int((~free).sum())
        u = solver.us[t]
        at_bound = np.isclose(u, [0.3, 0.2]) | np.isclose(u, [-0.3, -0.2])
        assert np.all(at_bound[~free])
    assert n_clamped > 0
    assert solver.nfactorizations > 0 and solver.nqp > 0


def test_box_fddp_closes_the_gaps_from_an_infeasible_guess():
    problem = unicycle_problem(T=20)
    xs0 = [np.array([3.0, -1.0, 0.2])] * (problem.T + 1)
    solver = SolverBoxFDDP(problem)
    gaps = []
    solver.setCallbacks([lambda s: gaps.append(s.ffeas)])
    assert solver.solve(xs0, None, 100, False)
    assert gaps[0] > 0.1 and solver.isFeasible
    assert np.allclose(problem.rollout(solver.us)[-1], solver.xs[-1], atol=1e-12)


@pytest.mark.parametrize("Solver", [SolverBoxDDP, SolverBoxFDDP])
def test_defaults_and_attributes(Solver):
    problem = unicycle_problem(T=5)
    solver = Solver(problem)
    assert solver.th_stop == 5e-5
    assert solver.alphas == [2.0**-n for n in range(10)]
    assert (solver.reg_min, solver.reg_max, solver.reg_incFactor) == (1e-9, 1e9, 10.0)
    assert len(solver.Quu_inv) == 5 and solver.Quu_inv[0].shape == (2, 2)
    assert solver.general_value_update is False


def test_inverted_or_nan_bounds_raise():
    model = ActionModelUnicycle()
    model.u_lb = np.array([1.0, 5.0])
    model.u_ub = np.array([2.0, 1.0])  # below u_lb[1]: the pair is checked where it is used
    with pytest.raises(ValueError, match="NaN"):
        model.u_lb = np.array([np.nan, 0.0])
    problem = unicycle_problem(T=3)
    problem.runningModels[0].u_lb = np.array([0.5, 0.0])
    for Solver in (SolverBoxDDP, SolverBoxFDDP):
        with pytest.raises(ValueError, match="u_lb"):
            Solver(problem).solve()
    problem.runningModels[0]._u_lb = np.array([np.nan, 0.0])
    with pytest.raises(ValueError, match="NaN"):
        SolverBoxDDP(problem)


@pytest.mark.parametrize("Solver", [SolverBoxDDP, SolverBoxFDDP])
def test_bounds_changed_between_solves_are_read_again(Solver):
    """A solve takes the bounds it read at the last one only while they are the same arrays holding the same values:
    bounds written in place (not through the setter), set anew or made NaN are read again, as a new solver reads
    them."""
    problem, model = lqr_problem()
    solver = Solver(problem)
    solver.solve()

    def same_as_a_new_solver():
        solver.solve()
        new = Solver(problem)
        new.solve()
        assert solver.iter == new.iter and solver.cost == new.cost
        for a, b in zip([*solver.xs, *solver.us], [*new.xs, *new.us], strict=True):
            np.testing.assert_array_equal(a, b)

    model.u_lb[:] = -0.4
    same_as_a_new_solver()
    assert min(u.min() for u in solver.us) >= -0.4 and min(u.min() for u in solver.us) < -0.35
    model.u_ub = np.full(model.nu, 0.3)
    same_as_a_new_solver()
    assert max(u.max() for u in solver.us) <= 0.3
    model.u_lb[0] = np.nan
    with pytest.raises(ValueError, match="NaN"):
        solver.solve()


@pytest.mark.parametrize("clamping", ["forward", "backward"])
def test_clamping_baselines_stay_in_the_box(clamping):
    problem = unicycle_problem(T=20)
    solver = SolverClampedDDP(problem, clamping)
    us0 = [np.zeros(2)] * problem.T
    solver.solve(problem.rollout(us0), us0, 30, True)
    us = np.array(solver.us)
    assert np.all(us >= [-0.3, -0.2]) and np.all(us <= [0.3, 0.2])
    assert solver.cost < problem.calc(problem.rollout(us0), us0)
    if clamping == "backward":
        solver.computeDirection(True)
        for t in range(problem.T):
            target = solver.us[t] - solver.k[t]
            assert np.all(target >= np.array([-0.3, -0.2]) - 1e-12) and np.all(target <= np.array([0.3, 0.2]) + 1e-12)
    with pytest.raises(ValueError, match="clamping"):
        SolverClampedDDP(problem, "sideways")


@pytest.mark.parametrize("Solver", [SolverBoxDDP, SolverBoxFDDP])
@pytest.mark.parametrize(("general", "compat"), [(False, False), (True, False), (False, True)])
def test_compiled_and_numpy_backward_passes_agree(Solver, general, compat):
    runs = []
    for kernel in (False, True):
        problem = unicycle_problem(T=30)
        solver = Solver(problem)
        solver.general_value_update = general
        solver.compat_crocoddyl = compat
        rows = record(solver)
        with crocopy.use_kernels(kernel):
            assert solver.solve(None, None, 100)
        runs.append((rows, solver.nfactorizations, solver.nqp))
    (rows_np, f_np, q_np), (rows_k, f_k, q_k) = runs
    assert len(rows_np) == len(rows_k) and (f_np, q_np) == (f_k, q_k)
    for (_, u1, c1), (_, u2, c2) in zip(rows_np, rows_k, strict=True):
        assert np.allclose(np.array(u1), np.array(u2), rtol=0, atol=1e-10)
        assert c1 == pytest.approx(c2, rel=1e-12)
