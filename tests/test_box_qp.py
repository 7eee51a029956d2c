"""Tests of the projected-Newton box QP against an independent QP solution (scipy)."""

import numpy as np
import pytest
from scipy.optimize import minimize

from crocopy.solvers.box_qp import BoxQP, BoxQPError, BoxQPSolution


def random_qp(rng, n):
    A = rng.standard_normal((n, n))
    H = A @ A.T + 0.1 * np.eye(n)
    q = 3.0 * rng.standard_normal(n)
    lb = -rng.random(n) - 0.05
    ub = rng.random(n) + 0.05
    return H, q, lb, ub


def kkt_residual(H, q, lb, ub, x):
    g = q + H @ x
    r = np.where(x <= lb, np.minimum(g, 0.0), np.where(x >= ub, np.maximum(g, 0.0), g))
    return np.abs(r).max()


@pytest.mark.parametrize("seed", range(12))
def test_matches_scipy_bounded_qp(seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, 13))
    H, q, lb, ub = random_qp(rng, n)
    qp = BoxQP(n, reg=0.0)
    sol = qp.solve(H, q, lb, ub, rng.standard_normal(n))
    ref = minimize(
        lambda x: 0.5 * x @ H @ x + q @ x, np.zeros(n), jac=lambda x: H @ x + q,
        bounds=list(zip(lb, ub, strict=True)), method="L-BFGS-B",
        options={"ftol": 1e-15, "gtol": 1e-12, "maxiter": 10000},
    )
    assert np.all(sol.x >= lb) and np.all(sol.x <= ub)
    assert np.allclose(sol.x, ref.x, atol=1e-5)
    assert kkt_residual(H, q, lb, ub, sol.x) < 1e-8
    # index sets partition the variables and match the active bounds at the optimum
    assert sorted(sol.free_idx + sol.clamped_idx) == list(range(n))
    g = q + H @ sol.x
    for j in sol.clamped_idx:
        assert (sol.x[j] == lb[j] and g[j] > 0) or (sol.x[j] == ub[j] and g[j] < 0)
    f = sol.free_idx
    if f:
        assert np.allclose(sol.Hff_inv, np.linalg.inv(H[np.ix_(f, f)]), rtol=1e-10, atol=1e-10)


@pytest.mark.parametrize("seed", range(8))
def test_warm_start_on_optimal_active_set_takes_one_iteration(seed):
    rng = np.random.default_rng(100 + seed)
    n = 8
    H, q, lb, ub = random_qp(rng, n)
    qp = BoxQP(n, reg=0.0)
    xstar = qp.solve(H, q, lb, ub, np.zeros(n)).x.copy()
    clamped = list(qp.solution.clamped_idx)
    free = list(qp.solution.free_idx)
    xinit = xstar.copy()
    # move the free variables away from the optimum while staying strictly inside the box
    xinit[free] += 1e-3 * rng.standard_normal(len(free))
    xinit = np.clip(xinit, lb + 1e-12, ub - 1e-12)
    xinit[clamped] = xstar[clamped]
    nfact = qp.nfactorizations
    sol = qp.solve(H, q, lb, ub, xinit)
    # the first Newton step lands on the optimum; at most a second, vanishing one confirms it
    assert qp.iter <= 2
    assert qp.nfactorizations - nfact == 1
    assert np.allclose(sol.x, xstar, atol=1e-12)
    assert sol.clamped_idx == clamped
    one = BoxQP(n, maxiter=1, reg=0.0).solve(H, q, lb, ub, xinit)
    assert np.allclose(one.x, xstar, atol=1e-12)


def test_unconstrained_is_one_newton_step():
    rng = np.random.default_rng(3)
    H, q, _, _ = random_qp(rng, 5)
    qp = BoxQP(5, maxiter=1, reg=0.0)
    sol = qp.solve(H, q, np.full(5, -np.inf), np.full(5, np.inf), rng.standard_normal(5))
    assert qp.iter == 1
    assert np.allclose(sol.x, -np.linalg.solve(H, q))
    assert sol.clamped_idx == []


def test_all_clamped():
    qp = BoxQP(2)
    sol = qp.solve(np.eye(2), np.array([5.0, -5.0]), -np.ones(2), np.ones(2), np.zeros(2))
    assert np.allclose(sol.x, [-1.0, 1.0])
    assert sol.free_idx == [] and sol.clamped_idx == [0, 1]
    assert sol.Hff_inv.shape == (0, 0)


def test_regularization_enters_the_free_block():
    H = np.diag([2.0, 3.0])
    qp = BoxQP(2, reg=0.5)
    sol = qp.solve(H, np.array([1.0, 1.0]), -np.ones(2) * 10, np.ones(2) * 10, np.zeros(2))
    assert np.allclose(sol.Hff_inv, np.diag([1 / 2.5, 1 / 3.5]))
    assert np.allclose(sol.x, [-1 / 2.5, -1 / 3.5], atol=1e-12)  # the regularized QP's optimum
    # with an active bound the answer is still the optimum of the regularized QP
    sol = qp.solve(H, np.array([1.0, -2.0]), np.array([-10.0, -10.0]), np.array([10.0, 0.5]), np.zeros(2))
    assert np.allclose(sol.x, [-1 / 2.5, 0.5]) and sol.clamped_idx == [1]


def test_not_positive_definite_raises():
    qp = BoxQP(2, reg=0.0)
    with pytest.raises(BoxQPError):
        qp.solve(np.diag([1.0, -1.0]), np.ones(2), -np.ones(2), np.ones(2), np.zeros(2))


def test_bad_inputs_raise_clear_errors():
    qp = BoxQP(3)
    H, q = np.eye(3), np.ones(3)
    lb, ub = -np.ones(3), np.ones(3)
    with pytest.raises(ValueError, match="lb"):
        qp.solve(H, q, np.array([0.0, 2.0, 0.0]), ub, np.zeros(3))
    with pytest.raises(ValueError, match="NaN"):
        qp.solve(H, q, np.array([np.nan, 0.0, 0.0]), ub, np.zeros(3))
    with pytest.raises(ValueError, match="H"):
        qp.solve(np.eye(2), q, lb, ub, np.zeros(3))
    with pytest.raises(ValueError, match="xinit"):
        qp.solve(H, q, lb, ub, np.zeros(4))


def test_defaults_and_names():
    qp = BoxQP(4)
    assert (qp.maxiter, qp.th_acceptStep, qp.th_grad, qp.reg) == (100, 0.1, 1e-9, 1e-9)
    assert qp.maxIter == 100
    assert qp.alphas == [0.5**k for k in range(10)]
    assert isinstance(qp.solution, BoxQPSolution)
    assert qp.solution.copy().x.shape == (4,)
