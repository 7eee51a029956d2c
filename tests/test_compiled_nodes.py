"""Solves with compiled nodes give the iterations, costs and datas of solves without them."""

from __future__ import annotations

import numpy as np
import pytest
from node_checks import data_values, failed_solve, make_solver

import crocopy
from crocopy.problems import registry
from crocopy.solvers import compiled_nodes

pytestmark = pytest.mark.skipif(not crocopy.kernels_enabled(), reason="compiled nodes need numba")

SOLVERS = ("SolverDDP", "SolverFDDP", "SolverBoxDDP", "SolverBoxFDDP")


def solve(name: str, solver: str, compiled: bool, maxiter: int = 40, **overrides):
    problem, xs, us = registry.build(name, **overrides)
    s = make_solver(solver, problem, compiled)
    s.solve(xs, us, maxiter)
    return s, problem


CASES = [("quad-goal", solver) for solver in SOLVERS]
CASES += [("arm", solver) for solver in SOLVERS if solver != "SolverBoxDDP"]
"""Converged solves.  Box-DDP stops within its tolerance at points whose costs are up to 3e-6 apart (round-off;
the quadrotor's pitch rate is nearly free there, ±5e-5 rad/s at the last nodes), so only its iterations and
cost are compared.  Box-DDP on the arm is left out: its first trial from the builder's infeasible guess is an
unstable rollout that DDP accepts whatever its cost, and round-off (1e-13 at node 5) grows to O(1) by node 75,
so the two evaluations take different paths from the first iteration on."""


@pytest.mark.parametrize(("name", "solver"), CASES)
def test_same_iterations_and_cost(name, solver):
    fast, _ = solve(name, solver, True, maxiter=500)
    slow, _ = solve(name, solver, False, maxiter=500)
    assert fast.iter == slow.iter
    assert fast.reason == slow.reason == "converged"
    assert fast.cost == pytest.approx(slow.cost, rel=1e-5 if solver == "SolverBoxDDP" else 1e-10)
    if solver != "SolverBoxDDP":
        for a, b in zip([*fast.xs, *fast.us], [*slow.xs, *slow.us]):
            np.testing.assert_allclose(a, b, rtol=1e-7, atol=1e-7)


def test_datas_after_the_solve_are_those_a_solve_without_compiled_nodes_leaves():
    fast, fast_problem = solve("quad-goal", "SolverBoxFDDP", True, maxiter=5)
    slow, slow_problem = solve("quad-goal", "SolverBoxFDDP", False, maxiter=5)
    fid = fast_problem.runningModels[0].differential.costs.costs["goal"].cost.residual.id
    for a, b in zip([*fast_problem.runningDatas, fast_problem.terminalData],
                    [*slow_problem.runningDatas, slow_problem.terminalData]):
        assert a.cost == pytest.approx(b.cost, rel=1e-7, abs=1e-10)
        for name in ("xnext", "Fx", "Fu", "Lx", "Lu", "Lxx", "Lxu", "Luu"):  # atol: 1e-10 of the largest entry
            want = getattr(b, name)  # (Lx reaches 2e3: its near-zero entries move by ~1e-7 with 2e-9 in xs)
            np.testing.assert_allclose(getattr(a, name), want, rtol=1e-6, atol=max(1e-7, 1e-10 * np.abs(want).max()),
                                       err_msg=name)
        da, db = a.differential, b.differential
        np.testing.assert_allclose(da.xout, db.xout, rtol=1e-6, atol=1e-7)
        np.testing.assert_allclose(da.pinocchio.oMf[fid].translation, db.pinocchio.oMf[fid].translation, atol=1e-8)
        for name in da.costs.costs:
            ca, cb = da.costs.costs[name], db.costs.costs[name]
            assert ca.cost == pytest.approx(cb.cost, rel=1e-7, abs=1e-10)
            np.testing.assert_allclose(ca.residual.r, cb.residual.r, rtol=1e-6, atol=1e-7)
            np.testing.assert_allclose(ca.residual.Rx, cb.residual.Rx, rtol=1e-6, atol=1e-7)


def test_compiled_nodes_are_selected_only_where_they_apply():
    problem, xs, us = registry.build("quad-goal")
    s = crocopy.SolverFDDP(problem)
    assert compiled_nodes.select(s) is not None
    assert all(step is not None for step in compiled_nodes.select(s).steps)

    class Subclass(crocopy.SolverFDDP):
        pass

    assert compiled_nodes.select(Subclass(problem)) is None

    class UserCallback(crocopy.CallbackAbstract):
        def __call__(self, solver):
            pass

    s.setCallbacks([crocopy.CallbackVerbose(), UserCallback()])
    assert compiled_nodes.select(s) is None
    s.setCallbacks([crocopy.CallbackVerbose()])
    assert compiled_nodes.select(s) is not None
    with crocopy.use_kernels(False):
        assert compiled_nodes.select(s) is None
    pend, _, _ = registry.build("pend", python_actuation=True)
    assert compiled_nodes.select(crocopy.SolverFDDP(pend)) is None
    pend, _, _ = registry.build("pend")
    assert compiled_nodes.select(crocopy.SolverFDDP(pend)) is not None


def test_a_user_callback_reads_nested_datas_of_the_current_iterate():
    problem, xs, us = registry.build("quad-goal")
    s = crocopy.SolverFDDP(problem)
    seen = []

    class Reader(crocopy.CallbackAbstract):
        def __call__(self, solver):
            d = solver.problem.runningDatas[0]
            seen.append(d.differential.costs.cost * problem.runningModels[0].dt - d.cost)

    s.setCallbacks([Reader()])
    s.solve(xs, us, 5)
    assert seen and max(abs(v) for v in seen) < 1e-12


def test_mixed_problem_compiles_the_nodes_it_can():
    problem, xs, us = registry.build("quad-goal")
    models = list(problem.runningModels)
    dam = models[3].differential

    class Euler(crocopy.IntegratedActionModelEuler):
        pass

    models[3] = Euler(dam, models[3].dt)
    mixed = crocopy.ShootingProblem(problem.x0, models, problem.terminalModel)
    nodes = compiled_nodes.select(crocopy.SolverFDDP(mixed))
    assert nodes.steps[3] is None and nodes.steps[2] is not None
    assert nodes.horizon is not None and nodes.segments == {0: 3, 4: problem.T} and nodes.python_nodes == [3]
    fast = crocopy.SolverFDDP(mixed)
    fast.solve(xs, us, 30)
    reference, _ = solve("quad-goal", "SolverFDDP", False, maxiter=30)
    assert fast.iter == reference.iter
    assert fast.cost == pytest.approx(reference.cost, rel=1e-9)


def test_a_diverging_solve_stops_as_without_compiled_nodes():
    """Overflowing rollouts (a far too long time step) are rejected and the solve keeps a finite iterate."""
    outcomes = []
    for compiled in (True, False):
        problem, xs, us = registry.build("quad-goal")
        for m in problem.runningModels:
            m.dt = 50.0
        outcomes.append(failed_solve(problem, xs, us, compiled, 20))
    assert outcomes[0] == outcomes[1]
    assert outcomes[0][0] is False and "non-finite" in outcomes[0][2]


def test_the_compiled_rollout_writes_its_arrays_in_place():
    problem, xs, us = registry.build("quad-goal")
    solver = crocopy.SolverFDDP(problem)
    solver.solve(xs, us, 3)
    assert compiled_nodes.attach(solver).horizon is not None
    solver.computeDirection()
    solver._trial_rollout(0.5, gaps=True)
    ids = [id(a) for a in solver.xs_try + solver.us_try]
    solver._trial_rollout(0.25, gaps=True)
    assert [id(a) for a in solver.xs_try + solver.us_try] == ids
    values = solver.xs_try[4].copy(), solver.us_try[4].copy()
    solver._trial_rollout(1.0)
    assert [id(a) for a in solver.xs_try + solver.us_try] == ids
    assert not np.array_equal(solver.xs_try[4], values[0]) and not np.array_equal(solver.us_try[4], values[1])
    reference = [x.copy() for x in solver.xs_try]
    solver._nodes = None
    solver._trial_rollout(1.0)
    for a, b in zip(solver.xs_try, reference):
        np.testing.assert_allclose(a, b, rtol=1e-10, atol=1e-10)


def test_expected_improvement_over_the_compiled_horizon_equals_the_node_loop():
    problem, xs, us = registry.build("quad-goal")
    solver = crocopy.SolverFDDP(problem)
    solver.setCandidate(xs, us, False)
    assert compiled_nodes.attach(solver).horizon is not None
    solver.computeDirection()
    assert not solver.isFeasible and solver._Vxx_f is solver._Vxx_f_views
    for alpha in (0.25, 0.1, 0.01):
        solver.tryStep(alpha)
        fast = solver.expectedImprovement().copy()
        nodes, solver._nodes = solver._nodes, None
        slow = solver.expectedImprovement().copy()
        solver._nodes = nodes
        assert abs(fast[1] - solver._dq) > 1e-6  # the gap term is not zero here
        np.testing.assert_allclose(fast, slow, rtol=1e-12, atol=1e-14)


def test_box_solvers_report_the_gaps_of_a_feasible_iterate_from_the_compiled_derivatives():
    reports = []
    for compiled in (True, False):
        problem, xs, us = registry.build("quad-goal")
        solver = crocopy.SolverBoxFDDP(problem)
        solver.compat_crocoddyl = True
        xs = problem.rollout(us)
        xs[7] = xs[7].copy()
        xs[7][[0, 1, 2, 7, 12]] += 0.01  # a feasible iterate (declared so) with one gap
        solver.setCandidate(xs, us, True)
        if compiled:
            assert compiled_nodes.attach(solver).horizon is not None
        solver.calcDiff()
        assert all(not f.any() for f in solver.fs)
        reports.append(solver.ffeas)
    assert reports[0] == pytest.approx(reports[1], rel=1e-12) and reports[0] > 0.009


def test_rollout_bounds_are_the_bound_arrays():
    problem, xs, us = registry.build("pend")
    nodes = compiled_nodes.select(crocopy.SolverBoxFDDP(problem))
    unbounded = {1: (np.full(1, -np.inf), np.full(1, np.inf))}
    lbs = [np.array([-float(t)]) for t in range(problem.T)]
    ubs = [np.array([float(t)]) for t in range(problem.T)]
    lbs[3] = ubs[3] = None
    lb_list, ub_list = nodes.bounds(lbs, ubs, unbounded)
    assert lb_list[2] is lbs[2] and ub_list[5] is ubs[5] and lb_list[3] is unbounded[1][0]
    lb_list, ub_list = nodes.bounds(None, None, unbounded)
    assert all(lb is unbounded[1][0] for lb in lb_list) and all(ub is unbounded[1][1] for ub in ub_list)


def _mixed_quadrotor():
    """quad-goal with its nodes 3 and 17 on the Python path (a subclass of the integrator)."""
    problem, xs, us = registry.build("quad-goal")
    models = list(problem.runningModels)

    class Euler(crocopy.IntegratedActionModelEuler):
        pass

    for t in (3, 17):
        models[t] = Euler(models[t].differential, models[t].dt)
    return crocopy.ShootingProblem(problem.x0, models, problem.terminalModel), xs, us


def test_trial_steps_over_compiled_ranges_equal_the_node_loop():
    """Rollouts, gaps and expected improvements of a problem whose compiled nodes form three ranges."""
    problem, xs, us = _mixed_quadrotor()
    solver = crocopy.SolverFDDP(problem)
    solver.setCandidate(xs, us, False)
    assert compiled_nodes.attach(solver).segments == {0: 3, 4: 17, 18: problem.T}
    solver.computeDirection()
    fs = [f.copy() for f in solver.fs]
    nodes, solver._nodes = solver._nodes, None
    solver._synced = False  # the Python nodes need their own calc (compiled nodes skip their intermediates)
    solver.computeDirection()
    for a, b in zip(fs, solver.fs):
        np.testing.assert_allclose(a, b, rtol=1e-8, atol=1e-9)
    for alpha in (0.25, 0.1):
        solver._nodes = nodes
        fast = solver.tryStep(alpha), solver.expectedImprovement().copy(), [x.copy() for x in solver.xs_try]
        solver._nodes = None
        slow = solver.tryStep(alpha), solver.expectedImprovement().copy(), solver.xs_try
        assert fast[0] == pytest.approx(slow[0], rel=1e-8)
        np.testing.assert_allclose(fast[1], slow[1], rtol=1e-8, atol=1e-12)
        for a, b in zip(fast[2], slow[2]):
            np.testing.assert_allclose(a, b, rtol=1e-8, atol=1e-9)


def _with_every_free_residual(problem):
    """``problem`` with a rotation, velocity, CoM and placement cost added to every node (the arm's frame)."""
    import pinocchio as pin

    first = problem.runningModels[0].differential
    state, frame = first.state, first.costs.costs["goal"].cost.residual.id
    for t, model in enumerate([*problem.runningModels, problem.terminalModel]):
        dam, nu = model.differential, model.nu
        residuals = {"rotation": crocopy.ResidualModelFrameRotation(state, frame, np.eye(3), nu),
                     "velocity": crocopy.ResidualModelFrameVelocity(state, frame, pin.Motion.Zero(), pin.LOCAL, nu),
                     "com": crocopy.ResidualModelCoMPosition(state, np.zeros(3), nu),
                     "placement": crocopy.ResidualModelFramePlacement(state, frame, pin.SE3.Identity(), nu)}
        for name, residual in residuals.items():
            dam.costs.addCost(name, crocopy.CostModelResidual(state, residual), 1e-3 * (1 + t % 3))
    return problem


FILLED = [("quad-goal", "SolverFDDP", None), ("arm", "SolverBoxFDDP", None), ("arm", "SolverSQP", None),
          ("arm", "SolverDDP", _with_every_free_residual), ("man", "SolverFDDP", None),
          ("ur5_ee_box", "SolverCSQP", None), ("kinova_ubound", "SolverCSQP", None)]
"""Free nodes (quadrotor, arm, every frame residual kind), SQP's end after a calcDiff, contact nodes, and constraint
managers on every node (mim-solvers' comparison problems, :mod:`crocopy.bench.mim`)."""


def _build(name: str) -> tuple:
    """A registry problem with its guess, or a :mod:`crocopy.bench.mim` problem from ``x0`` and zero controls."""
    if name in registry.names():
        return registry.build(name)
    from crocopy.bench.mim import build_problem

    problem = build_problem(crocopy, name)
    return problem, [problem.x0.copy()] * (problem.T + 1), [np.zeros(m.nu) for m in problem.runningModels]


@pytest.mark.parametrize(("name", "solver", "extend"), FILLED)
def test_every_value_of_the_datas_after_a_solve_is_that_of_a_python_calc_at_the_last_iterate(name, solver, extend):
    """A compiled solve ends by filling the nested datas (free dynamics: the compiled values kept, the Pinocchio data,
    torques, residual and constraint datas written on top; other nodes: their Python ``calc``): every number they
    hold equals what ``problem.calc`` at the returned iterate writes, to round-off."""
    problem, xs, us = _build(name)
    if extend is not None:
        extend(problem)
    s = make_solver(solver, problem, True)
    s.solve(xs, us, 3)
    filled = data_values(problem)
    problem.calc(s.xs, s.us)
    python = data_values(problem)
    assert filled.keys() == python.keys()
    assert len(python) > 1000
    for path, want in python.items():
        got = filled[path]
        assert got.shape == want.shape, path
        scale = np.abs(want[np.isfinite(want)]).max(initial=1.0)
        np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-9 * scale, err_msg=path)


def _recorded(method, name: str, calls: list):
    """``method`` that appends ``name`` to ``calls`` first."""

    def call(*args):
        calls.append(name)
        return method(*args)

    return call


WHOLE = [("quad-goal", "SolverFDDP"), ("arm", "SolverBoxFDDP"), ("arm", "SolverSQP"), ("arm", "SolverCSQP"),
         ("quad-goal", "SolverSQP")]


@pytest.mark.parametrize(("name", "solver"), WHOLE)
def test_one_call_over_the_whole_horizon_gives_the_numbers_of_the_node_by_node_path(name, solver, monkeypatch):
    """``calcDiff`` (running nodes, gaps, terminal node) and SQP's trial point in one compiled call give the
    iterations, costs and trajectories of the range-by-range path, to the bit."""
    runs = []
    for whole in (True, False):
        if not whole:
            monkeypatch.setattr(compiled_nodes.CompiledNodes, "_calc_diff_all", lambda self, *args: None)
            monkeypatch.setattr(compiled_nodes.CompiledNodes, "_trial_all", lambda self, *args: None)
        calls = []
        problem, xs, us = registry.build(name)
        nodes = compiled_nodes.select(make_solver(solver, problem, True))
        assert nodes is not None and nodes.ranges == [(0, problem.T)]
        horizon = nodes.horizon
        for method in ("calc_diff_all", "trial_all"):
            monkeypatch.setattr(horizon, method, _recorded(getattr(horizon, method), method, calls))
        s = make_solver(solver, problem, True)
        s.solve(xs, us, 12)
        runs.append((s.iter, s.cost, [x.copy() for x in s.xs], [u.copy() for u in s.us], set(calls)))
    (it1, c1, xs1, us1, used), (it2, c2, xs2, us2, unused) = runs
    assert "calc_diff_all" in used and not unused
    if solver in ("SolverSQP", "SolverCSQP"):
        assert "trial_all" in used
    assert (it1, c1) == (it2, c2)
    for a, b in zip(xs1 + us1, xs2 + us2):
        np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("name", ["quad-goal", "arm"])
def test_the_first_gap_by_the_compiled_state_difference_equals_the_state_model(name):
    """``f₀ = x0 ⊖ x`` by node 0's compiled difference (free flyer; revolute joints) equals ``state.diff``."""
    problem, xs, us = registry.build(name)
    s = make_solver("SolverFDDP", problem, True)
    horizon = compiled_nodes.select(s).horizon
    state, rng = problem.runningModels[0].state, np.random.default_rng(3)
    for _ in range(20):
        x = state.integrate(problem.x0, rng.standard_normal(state.ndx))
        f = np.full(state.ndx, np.nan)
        assert horizon.first_gap(x, problem.x0, f)
        np.testing.assert_allclose(f, state.diff(x, problem.x0), rtol=1e-12, atol=1e-12)
