"""Hierarchical DDP: LQ recursion vs a dense lexicographic QP, strict priorities, single level = DDP."""

from __future__ import annotations

import numpy as np
import pytest
from solver_problems import DAMDoubleIntegrator

import crocopy
from crocopy import SolverHDDP
from crocopy.residuals.base import ResidualDataAbstract, ResidualModelAbstract
from crocopy.solvers.hddp_lq import LevelDerivatives, hierarchical_backward_pass
from crocopy.solvers.projection_lq import projected_backward_pass


def random_levels(rng, T, ndx, nu, ranks):
    """Low-rank PSD task costs ``½‖Cᵢ z + cᵢ‖²`` per level; the last level is a full-rank effort."""
    levels = []
    for rank in ranks:
        Lx, Lu, Lxx, Lxu, Luu = [], [], [], [], []
        for t in range(T + 1):
            Cx = rng.standard_normal((rank, ndx)) if t == T else np.zeros((rank, ndx))
            c = rng.standard_normal(rank)
            Lx.append(Cx.T @ c)
            Lxx.append(Cx.T @ Cx)
            if t < T:
                Lu.append(np.zeros(nu))
                Lxu.append(np.zeros((ndx, nu)))
                Luu.append(np.zeros((nu, nu)))
        levels.append(LevelDerivatives(Lx, Lu, Lxx, Lxu, Luu))
    eff = LevelDerivatives([np.zeros(ndx) for _ in range(T + 1)], [0.1 * rng.standard_normal(nu) for _ in range(T)],
                           [np.zeros((ndx, ndx)) for _ in range(T + 1)], [np.zeros((ndx, nu)) for _ in range(T)],
                           [np.eye(nu) for _ in range(T)])
    return [*levels, eff]


def dense_lexicographic(Fx, Fu, levels):
    """Lexicographic minimisation over the stacked controls by nested nullspaces (δx₀ = 0)."""
    T, nu, ndx = len(Fx), Fu[0].shape[1], Fx[0].shape[0]
    Sx = [np.zeros((ndx, T * nu))]
    for t in range(T):
        S = Fx[t] @ Sx[-1]
        S[:, t * nu:(t + 1) * nu] += Fu[t]
        Sx.append(S)
    z, N = np.zeros(T * nu), np.eye(T * nu)
    for lv in levels:
        H, g = np.zeros((T * nu, T * nu)), np.zeros(T * nu)
        for t in range(T + 1):
            H += Sx[t].T @ lv.Lxx[t] @ Sx[t]
            g += Sx[t].T @ lv.Lx[t]
            if t < T:
                E = np.zeros((nu, T * nu))
                E[:, t * nu:(t + 1) * nu] = np.eye(nu)
                H += E.T @ lv.Luu[t] @ E + Sx[t].T @ lv.Lxu[t] @ E + E.T @ lv.Lxu[t].T @ Sx[t]
                g += E.T @ lv.Lu[t]
        Hw, gw = N.T @ H @ N, N.T @ (H @ z + g)
        z = z - N @ np.linalg.pinv(Hw, rcond=1e-10, hermitian=True) @ gw
        w, V = np.linalg.eigh(Hw)
        N = N @ V[:, w <= 1e-10 * max(w[-1], 1e-300)]
    return [z[t * nu:(t + 1) * nu] for t in range(T)]


def test_hierarchical_lq_matches_dense_lexicographic_qp():
    rng = np.random.default_rng(0)
    T, ndx, nu = 5, 4, 3
    Fx = [np.eye(ndx) + 0.1 * rng.standard_normal((ndx, ndx)) for _ in range(T)]
    Fu = [rng.standard_normal((ndx, nu)) for _ in range(T)]
    levels = random_levels(rng, T, ndx, nu, ranks=[1, 1])
    res = hierarchical_backward_pass(Fx, Fu, levels)
    dx, us = np.zeros(ndx), []
    for t in range(T):
        du = sum(res.ff[k][t] for k in range(len(levels))) + res.K[t] @ dx
        us.append(du)
        dx = Fx[t] @ dx + Fu[t] @ du
    for a, b in zip(us, dense_lexicographic(Fx, Fu, levels)):
        np.testing.assert_allclose(a, b, atol=1e-8)
    assert res.rank[0][T - 1] == 1 and res.free[0] == 0


def test_single_level_is_the_ddp_riccati_recursion():
    rng = np.random.default_rng(1)
    T, ndx, nu = 6, 4, 2
    Fx = [np.eye(ndx) + 0.1 * rng.standard_normal((ndx, ndx)) for _ in range(T)]
    Fu = [rng.standard_normal((ndx, nu)) for _ in range(T)]
    lv = LevelDerivatives(
        [rng.standard_normal(ndx) for _ in range(T + 1)], [rng.standard_normal(nu) for _ in range(T)],
        [np.eye(ndx) for _ in range(T + 1)], [0.1 * rng.standard_normal((ndx, nu)) for _ in range(T)],
        [2.0 * np.eye(nu) for _ in range(T)],
    )
    res = hierarchical_backward_pass(Fx, Fu, [lv])
    empty_x, empty_u = [np.zeros((0, ndx))] * (T + 1), [np.zeros((0, nu))] * T
    ref = projected_backward_pass(Fx, Fu, lv.Lx, lv.Lu, lv.Lxx, lv.Lxu, lv.Luu, empty_x, empty_u,
                                  [np.zeros(0)] * (T + 1))
    for t in range(T):
        np.testing.assert_allclose(res.ff[0][t], -ref.k[t], atol=1e-10)
        np.testing.assert_allclose(res.K[t], -ref.K[t], atol=1e-10)
        np.testing.assert_allclose(res.Vxx[0][t], ref.Vxx[t], atol=1e-9)


class ResidualPlanarEE(ResidualModelAbstract):
    """Planar 3-link arm (unit links), ``r = sel · (x_ee, y_ee, φ) - ref`` with ``φ = q₀ + q₁ + q₂``."""

    def __init__(self, state, sel, ref):
        self.sel, self.ref = np.atleast_2d(sel), np.asarray(ref, dtype=float)
        super().__init__(state, self.sel.shape[0], 3, True, False, False)

    @staticmethod
    def fk(q):
        a = np.cumsum(q)
        p = np.array([np.cos(a).sum(), np.sin(a).sum(), a[-1]])
        J = np.ones((3, 3))
        for j in range(3):
            J[0, j] = -np.sin(a[j:]).sum()
            J[1, j] = np.cos(a[j:]).sum()
        return p, J

    def calc(self, data, x, u=None):
        data.r[:] = self.sel @ self.fk(x[:3])[0] - self.ref

    def calcDiff(self, data, x, u=None):
        data.Rx[:, :3] = self.sel @ self.fk(x[:3])[1]

    def createData(self, data=None):
        return ResidualDataAbstract(self, data)


def arm_problem(tasks=("t1", "t2"), T=20, dt=0.05, effort_w=1e-3):
    state = crocopy.StateVector(6)
    specs = {
        "t1": ResidualPlanarEE(state, [[0.0, 0.0, 1.0], [0.0, 0.0, 1.0]], [0.9, 1.1]),
        "x1": ResidualPlanarEE(state, [[1.0, 0.0, 0.0], [1.0, 0.0, 0.0]], [0.9, 1.1]),
        "t2": ResidualPlanarEE(state, [[0.0, 1.0, 0.0]], [2.9]),
        "t3": ResidualPlanarEE(state, [[1.0, 1.0, 0.0]], [3.5]),
    }
    running, terminal = crocopy.CostModelSum(state, 3), crocopy.CostModelSum(state, 3)
    running.addCost("effort", crocopy.CostModelResidual(state, crocopy.ResidualModelControl(state, 3)), effort_w)
    terminal.addCost("velocity", crocopy.CostModelResidual(
        state, crocopy.ActivationModelWeightedQuad(np.r_[np.zeros(3), np.ones(3)]),
        crocopy.ResidualModelState(state, np.zeros(6), 3)), 1e-3)
    for name in tasks:
        terminal.addCost(name, crocopy.CostModelResidual(state, specs[name]), 1.0)
    rm = crocopy.IntegratedActionModelEuler(DAMDoubleIntegrator(running, 3), dt)
    tm = crocopy.IntegratedActionModelEuler(DAMDoubleIntegrator(terminal, 3), 0.0)
    return crocopy.ShootingProblem(np.array([0.3, 0.4, 0.5, 0, 0, 0]), [rm] * T, tm)


def solve_hddp(levels, tasks, maxiter=100, th_last=1e-4, **kw):
    problem = arm_problem(tasks, **kw)
    solver = SolverHDDP(problem, levels)
    solver.th_rel = ([1e-10] + [1e-4] * (len(levels) - 2))[: len(levels) - 1] + [th_last]
    solver.th_abs = [0.0] * len(levels)
    solver.solve([], [], maxiter=maxiter)
    return solver


def test_lower_priority_task_never_changes_the_top_task():
    """Top task: end-effector angle (its optimal set is flat); lower tasks: end-effector position."""
    base = solve_hddp([["t1"], ["velocity", "effort"]], ("t1",))
    full = solve_hddp([["t1"], ["t2"], ["velocity", "effort"]], ("t1", "t2"))
    three = solve_hddp([["t1"], ["t2"], ["t3"], ["velocity", "effort"]], ("t1", "t2", "t3"))
    g1 = base.level_costs[0]
    assert g1 == pytest.approx(0.01, rel=1e-8)
    for s in (full, three):
        assert s.reason.startswith("converged")
        assert abs(s.level_costs[0] - g1) <= 1e-8 * g1
    p = arm_problem(("t1", "t2"))
    p.calc(base.xs, base.us)
    t2_unserved = p.terminalData.differential.costs.costs["t2"].cost
    assert full.level_costs[1] < 1e-2 * t2_unserved
    assert three.level_costs[1] == pytest.approx(full.level_costs[1], rel=1e-2)


def test_curved_top_task_is_never_traded_for_a_lower_one():
    """Top task: end-effector x (curved optimal set); the line search keeps it at its optimum."""
    base = solve_hddp([["x1"], ["velocity", "effort"]], ("x1",), maxiter=30)
    full = solve_hddp([["x1"], ["t2"], ["velocity", "effort"]], ("x1", "t2"), maxiter=30)
    g1 = base.level_costs[0]
    assert g1 == pytest.approx(0.01, rel=1e-8)
    assert abs(full.level_costs[0] - g1) <= 1e-8 * g1


def test_single_level_hierarchy_equals_ddp():
    names = ["t1", "t2", "velocity", "effort"]
    hddp = solve_hddp([names], ("t1", "t2"), th_last=1e-12)
    assert hddp.reason.startswith("converged")
    ddp = crocopy.SolverDDP(arm_problem(("t1", "t2")))
    assert ddp.solve([], [], maxiter=300)
    assert hddp.cost == pytest.approx(ddp.cost, rel=1e-6)
    np.testing.assert_allclose(np.array(hddp.us), np.array(ddp.us), atol=1e-3)


def test_lq_hierarchy_converges_in_one_step():
    problem = arm_problem(("t1",), T=5)
    solver = SolverHDDP(problem, [["t1", "velocity", "effort"]])
    solver.solve([], [], maxiter=1)
    assert solver.level_steps[0] == 1.0


def test_per_level_costs_are_reported_per_iteration(capsys):
    problem = arm_problem(("t1", "t2"))
    solver = SolverHDDP(problem, [["t1"], ["t2"], ["velocity", "effort"]])
    log = crocopy.CallbackHDDPLogger()
    solver.setCallbacks([crocopy.CallbackHDDPVerbose(), log])
    solver.solve([], [], maxiter=30)
    rows = [line.split() for line in capsys.readouterr().out.splitlines()[1:]]
    assert len(rows) == len(log.level_costs) == len(log.iters) > 2
    for row, G in zip(rows, log.level_costs):
        assert G.shape == (3,)
        np.testing.assert_allclose([float(v) for v in row[1:4]], G, rtol=1e-3)
    G1 = [G[0] for G in log.level_costs]
    assert all(b <= a * (1 + 1e-9) for a, b in zip(G1, G1[1:])) and G1[-1] == pytest.approx(0.01, rel=1e-8)
    assert log.level_costs[-1][1] < 0.1 * log.level_costs[0][1]
    problem.calc(solver.xs, solver.us)
    items = problem.terminalData.differential.costs.costs
    assert log.level_costs[-1][0] == pytest.approx(items["t1"].cost, rel=1e-12)
    assert log.level_costs[-1][1] == pytest.approx(items["t2"].cost, rel=1e-12)
    assert log.costs[-1] == pytest.approx(problem.calc(solver.xs, solver.us), rel=1e-12)


def test_bad_levels_are_rejected():
    problem = arm_problem(("t1", "t2"))
    with pytest.raises(KeyError, match="nope"):
        SolverHDDP(problem, [["t1", "t2", "velocity", "effort", "nope"]])
    with pytest.raises(ValueError, match="in no level"):
        SolverHDDP(problem, [["t1"], ["velocity", "effort"]])
    with pytest.raises(ValueError, match="levels 0 and 1"):
        SolverHDDP(problem, [["t1", "t2"], ["t2", "velocity", "effort"]])
    with pytest.raises(ValueError, match="non-empty"):
        SolverHDDP(problem, [])


def test_icub_upper_body_scenario_reaches_compatible_targets():
    from crocopy.experiments.hddp import HDDPScenario, _hddp_solve, run_hddp

    scn = HDDPScenario(T=10)
    assert (scn.model.nq, scn.model.nv) == (11, 11)
    solver, errors, iters, _ = _hddp_solve(scn, scn.targets(3), [["left"], ["right"], ["effort"]], 60)
    assert solver.reason.startswith("converged")
    assert errors["left"] < 1e-8 and errors["right"] < 1e-8
    assert np.all(np.isfinite(np.array(solver.us)))
    with pytest.raises(ValueError, match="trials"):
        run_hddp(trials=0)


def reach_lq(T=6, dt=2e-3, minv=(1.0, 0.05, 20.0), weight=1.0):
    """``q, v ∈ R³`` under symplectic Euler with a spread inverse inertia; level 1 a terminal 2-D reach."""
    Minv = np.diag(minv)
    A = np.block([[np.eye(3), dt * np.eye(3)], [np.zeros((3, 3)), np.eye(3)]])
    B = np.vstack([dt**2 * Minv, dt * Minv])
    C = np.hstack([np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 1.0]]), np.zeros((2, 3))])
    c = np.array([0.3, -0.2])
    zx, zu = [np.zeros(6) for _ in range(T)], [np.zeros(3) for _ in range(T)]
    Lxx = [np.zeros((6, 6)) for _ in range(T)] + [weight * C.T @ C]
    Lx = zx + [weight * C.T @ c]
    reach = LevelDerivatives(Lx, zu, Lxx, [np.zeros((6, 3))] * T, [np.zeros((3, 3))] * T)
    effort = LevelDerivatives([np.zeros(6)] * (T + 1), zu, [np.zeros((6, 6))] * (T + 1), [np.zeros((6, 3))] * T,
                              [1e-6 * np.eye(3)] * T)
    return [A] * T, [B] * T, reach, effort, C, c


def test_rank_threshold_keeps_the_reach_directions_of_the_last_node():
    """Curvature ``dt⁴ M⁻²`` spread over 4e5 at the last node: all reach directions stay in level 1."""
    Fx, Fu, reach, effort, C, c = reach_lq()
    res = hierarchical_backward_pass(Fx, Fu, [reach, effort], rank_scale="peak")
    T = len(Fx)
    assert res.rank[0][T - 1] == 2 and res.rank[1][T - 1] == 1
    assert all(res.rank[0][t] == 0 for t in range(T - 1))  # V⁽¹⁾ is round-off before the last node
    dx = np.zeros(6)
    for t in range(T):
        dx = Fx[t] @ dx + Fu[t] @ (res.ff[0][t] + res.ff[1][t] + res.K[t] @ dx)
    np.testing.assert_allclose(C @ dx + c, 0.0, atol=1e-10)


def test_rank_scale_task_leaves_a_small_running_part_to_the_lower_levels():
    """A running reach weighted 1e-5: its curvature is ~1e-10 of the task scale and ~1e-5 of the peak."""
    Fx, Fu, reach, effort, C, c = reach_lq()
    T = len(Fx)
    running = LevelDerivatives([1e-5 * C.T @ c] * T + [reach.Lx[T]], reach.Lu, [1e-5 * C.T @ C] * T + [reach.Lxx[T]],
                               reach.Lxu, reach.Luu)
    task = hierarchical_backward_pass(Fx, Fu, [running, effort])
    peak = hierarchical_backward_pass(Fx, Fu, [running, effort], rank_scale="peak")
    assert task.rank[0] == [0] * (T - 1) + [2] and task.rank[1][: T - 1] == [3] * (T - 1)
    assert all(r == 2 for r in peak.rank[0]) and all(r == 1 for r in peak.rank[1])
    with pytest.raises(ValueError, match="rank_scale"):
        hierarchical_backward_pass(Fx, Fu, [running, effort], rank_scale="max")


def test_levenberg_regularisation_is_relative_to_the_task_curvature():
    Fx, Fu, reach, effort, _, _ = reach_lq(T=4)
    scaled = reach_lq(T=4, weight=1e12)[2]
    a = hierarchical_backward_pass(Fx, Fu, [reach], lambdas=[1e-3])
    b = hierarchical_backward_pass(Fx, Fu, [scaled], lambdas=[1e-3])
    plain = hierarchical_backward_pass(Fx, Fu, [reach])
    for t in range(4):
        np.testing.assert_allclose(a.ff[0][t], b.ff[0][t], rtol=1e-8, atol=1e-12)
        np.testing.assert_allclose(a.K[t], b.K[t], rtol=1e-8, atol=1e-12)
    assert np.linalg.norm(a.ff[0][3]) < 0.99 * np.linalg.norm(plain.ff[0][3])  # λ damps the step


def test_icub_scenario_conflicts_only_where_it_should():
    from crocopy.experiments.hddp import HDDPScenario, static_optimum

    scn = HDDPScenario(T=10)
    conflict = static_optimum(scn, scn.targets(1), starts=3)
    compatible = static_optimum(scn, scn.targets(3), starts=1)
    alone = static_optimum(scn, {"right": scn.targets(1)["right"]}, starts=3)["right"]
    assert conflict["left"] < 1e-12 and conflict["right"] > 1e-3 and alone < 0.1 * conflict["right"]
    assert compatible["left"] < 1e-12 and compatible["right"] < 1e-12


def test_icub_conflicting_test_meets_the_top_task():
    from crocopy.experiments.hddp import HDDPScenario, _hddp_solve

    scn = HDDPScenario()
    solver, errors, _, _ = _hddp_solve(scn, scn.targets(1, np.random.default_rng(0)), [["left"], ["right"], ["effort"]],
                                       60)
    assert errors["left"] <= 1e-7 and errors["right"] > 1e-5
    assert np.all(np.isfinite(np.array(solver.us)))


@pytest.mark.slow
def test_table1_bars_on_ten_trials():
    from crocopy.experiments.hddp import run_hddp

    res = run_hddp(trials=10, verbose=False, reference_trials=0)
    for test in (1, 2):
        assert res[test]["met"]["left"] >= 10 * 0.95
    assert res[3]["errors"]["left"] <= 1e-7 and res[3]["errors"]["right"] <= 1e-7
    assert res[3]["met"]["left"] == res[3]["met"]["right"] == 10
    assert res["priority"]["relative"] <= 1e-8
    assert res[1]["bar"] and res[2]["bar"] and res[3]["bar"]


def test_table1_bar_counts_trials_and_test3_means():
    from crocopy.experiments.hddp import table1_bar

    errors = np.full((20, 2), 1e-9)
    errors[:1, 0] = 1e-3
    assert table1_bar(1, errors)[0] and "19/20" in table1_bar(1, errors)[1]
    errors[:2, 0] = 1e-3
    assert not table1_bar(2, errors)[0]  # 18/20 = 90 % < 95 %
    assert not table1_bar(3, errors)[0]  # the mean of task 1 is 1e-4
    assert table1_bar(3, np.full((5, 2), 5e-8))[0]
    assert not table1_bar(3, np.array([[1e-9, 2e-7]]))[0]


@pytest.mark.slow
def test_table2_weighted_runs_do_not_stop_at_no_level_improves():
    from crocopy.experiments.hddp import run_hddp_weighted

    rows = run_hddp_weighted(weights=(1e3, 1e4, 1e5), verbose=False)
    for r in rows:
        if r["solver"] == "Weighted HDDP":
            assert "no level improves" not in r["reason"] and r["errors"][0] < 1e-6


def test_linear_prediction_of_a_trial_is_exact_on_linear_dynamics():
    """``q̈ = u`` under Euler is linear: the blow-up guard's prediction matches every trial exactly."""
    problem = arm_problem(("t1", "t2"))
    solver = SolverHDDP(problem, [["t1"], ["t2"], ["velocity", "effort"]])
    solver.us = [np.full(3, 0.2) for _ in range(problem.T)]
    solver.xs = problem.rollout(solver.us)
    problem.calc(solver.xs, solver.us)
    problem.calcDiff(solver.xs, solver.us)
    solver._backward(solver._reader.derivatives(solver.xs, solver.us))
    for steps in ([1.0, 0.0, 0.0], [0.5, 1.0, 0.25]):
        solver._rollout(np.array(steps))
        dx = problem.runningModels[0].state.diff(solver.xs[-1], solver.xs_try[-1])
        assert np.abs(dx).max() > 1e-3
        assert solver._deviation_ratio() == pytest.approx(1.0, rel=1e-9)
