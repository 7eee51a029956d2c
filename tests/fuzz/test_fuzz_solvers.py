"""Property tests of every solver on random, ill-scaled and diverging problems (issue 14).

Whatever the problem, ``solve`` either raises a clear ValueError (a guess whose cost is not finite)
or returns a bool and leaves a finite, shape-correct iterate whose ``cost`` is the cost of
``(xs, us)``; a NaN written into a derivative is reported with its node and quantity.  Each
property runs a bounded number of examples by default and the ``slow`` Hypothesis profile's number
under ``pytest -m slow``.
"""

from __future__ import annotations

import concurrent.futures

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from solver_problems import SOLVERS, check_outcome, integrator_problem, poison

import crocopy

settings.register_profile("slow", max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
QUICK = settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
PROFILES = [pytest.param(QUICK, id="quick"), pytest.param(settings.get_profile("slow"), id="slow",
                                                             marks=pytest.mark.slow)]
BOXED = ("BoxDDP", "BoxFDDP", "ClampedForward", "ClampedBackward")
KERNELS = st.sampled_from([True, False] if crocopy.kernels.available else [False])


def scale(lo: int, hi: int) -> st.SearchStrategy[float]:
    """``±10^e`` for an integer ``e`` in ``[lo, hi]``."""
    return st.builds(lambda s, e: s * 10.0**e, st.sampled_from([1.0, -1.0]), st.integers(lo, hi))


def vector(n: int) -> st.SearchStrategy[np.ndarray]:
    return st.builds(lambda c, v: c * np.array(v), scale(-3, 120), st.lists(st.floats(-1, 1), min_size=n, max_size=n))


@st.composite
def integrator_case(draw):
    name = draw(st.sampled_from(sorted(SOLVERS)))
    nq, T = draw(st.integers(1, 2)), draw(st.integers(1, 6))
    kw = {
        "T": T, "nq": nq, "dt": abs(draw(scale(-3, 160))),
        "w_state": draw(st.sampled_from([0.0, 1.0])) * abs(draw(scale(-12, 200))),
        "w_control": abs(draw(scale(-12, 200))), "w_goal": abs(draw(scale(-12, 200))),
        "x0": draw(vector(2 * nq)), "goal": draw(vector(2 * nq)),
        "u_bound": abs(draw(scale(-3, 3))) if name in BOXED else np.inf,
    }
    return name, kw


def solve_and_check(solver, problem, maxiter: int, kernels: bool) -> None:
    with crocopy.use_kernels(kernels):
        try:
            result = solver.solve(maxiter=maxiter)
        except ValueError as exc:
            assert "initial guess is not finite" in str(exc)
            return
    assert isinstance(result, bool)
    check_outcome(solver, problem)
    assert solver.reason.startswith("converged") if result else solver.reason


@pytest.mark.parametrize("profile", PROFILES)
def test_every_solver_leaves_a_finite_iterate_on_ill_scaled_problems(profile):
    @profile
    @given(integrator_case(), st.integers(1, 15), KERNELS)
    def check(case, maxiter, kernels):
        name, kw = case
        problem = integrator_problem(**kw)
        solve_and_check(SOLVERS[name](problem), problem, maxiter, kernels)

    check()


@st.composite
def lqr_case(draw):
    nx, nu, T = draw(st.integers(1, 3)), draw(st.integers(1, 2)), draw(st.integers(1, 5))
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    A = np.eye(nx) + abs(draw(scale(-3, 2))) * rng.standard_normal((nx, nx))
    B = abs(draw(scale(-3, 150))) * rng.standard_normal((nx, nu))
    M = rng.standard_normal((nx, nx))
    Q = draw(st.sampled_from([1.0, -1.0])) * abs(draw(scale(-6, 150))) * (M @ M.T)
    R = abs(draw(scale(-6, 150))) * np.eye(nu)
    x0 = draw(vector(nx))
    return nx, nu, T, A, B, Q, R, x0


@pytest.mark.parametrize("profile", PROFILES)
def test_every_solver_leaves_a_finite_iterate_on_diverging_lqr(profile):
    """Indefinite ``Q`` makes the cost unbounded below: the solvers must still stop finitely."""
    names = sorted(n for n in SOLVERS if n != "HDDP")

    @profile
    @given(lqr_case(), st.sampled_from(names), st.integers(1, 30), KERNELS)
    def check(case, name, maxiter, kernels):
        nx, nu, T, A, B, Q, R, x0 = case
        try:
            model = crocopy.ActionModelLQR(A, B, Q, R, np.zeros((nx, nu)))
            problem = crocopy.ShootingProblem(x0, [model] * T, model)
        except ValueError:
            return  # a model rejected at construction (e.g. an indefinite Q) is a clear error
        if name in BOXED:
            model.u_lb, model.u_ub = -np.ones(nu), np.ones(nu)
        solve_and_check(SOLVERS[name](problem), problem, maxiter, kernels)

    check()


DERIVATIVES = ("Fx", "Fu", "Lx", "Lu", "Lxx", "Lxu", "Luu")


@pytest.mark.parametrize("profile", PROFILES)
def test_a_nan_derivative_is_named_with_its_node(profile):
    @profile
    @given(st.sampled_from(sorted(SOLVERS)), st.integers(2, 6), st.data(), KERNELS)
    def check(name, T, data, kernels):
        node = data.draw(st.integers(0, T))
        quantities = ("Lx", "Lxx") if node == T else DERIVATIVES
        if name == "HDDP":  # HDDP reads the cost derivatives from the cost items, not the node's data
            quantities = ("Fx", "Fu") if node < T else ()
        if not quantities:
            return
        quantity = data.draw(st.sampled_from(quantities))
        problem = integrator_problem(T=T, u_bound=0.5 if name in BOXED else np.inf)
        poison(problem, node, quantity, after=data.draw(st.integers(0, 1)))
        solver = SOLVERS[name](problem)
        with crocopy.use_kernels(kernels):
            assert solver.solve(maxiter=30) is False
        assert solver.reason.startswith(f"non-finite {quantity} at node {node} in the derivatives")
        check_outcome(solver, problem)

    check()


def _diverging_lqr(scale_q: float, scale_b: float) -> crocopy.ShootingProblem:
    B, Q = scale_b * np.ones((2, 1)), -scale_q * np.eye(2)
    model = crocopy.ActionModelLQR(np.eye(2), B, Q, np.eye(1), np.zeros((2, 1)))
    return crocopy.ShootingProblem(np.ones(2), [model] * 4, model)


@pytest.mark.parametrize("profile", PROFILES)
def test_solve_many_results_are_finite(profile):
    """The ``solve_many`` path (in-process executor): every result finite and consistent."""

    @profile
    @given(st.lists(st.tuples(scale(-3, 150), scale(-3, 150)), min_size=1, max_size=3), st.integers(1, 20))
    def check(scales, maxiter):
        params = [{"scale_q": abs(a), "scale_b": abs(b)} for a, b in scales]
        try:
            _diverging_lqr(1.0, 1.0)
        except ValueError:
            return  # indefinite Q rejected at construction
        with concurrent.futures.ThreadPoolExecutor(1) as pool:
            results = crocopy.solve_many(_diverging_lqr, params, pool, solver=crocopy.SolverFDDP, maxiter=maxiter,
                                         return_exceptions=True)
        for p, r in zip(params, results):
            if isinstance(r, BaseException):
                assert "initial guess is not finite" in str(r)
                continue
            problem = _diverging_lqr(**p)
            assert all(np.isfinite(x).all() for x in r.xs) and all(np.isfinite(u).all() for u in r.us)
            assert np.isfinite(r.cost)
            assert r.cost == pytest.approx(problem.calc(r.xs, r.us), rel=1e-9, abs=1e-12)
            assert r.reason

    check()
