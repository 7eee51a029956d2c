"""Fast versions of the Box-DDP / Box-FDDP paper experiments (small sizes, few iterations)."""

import numpy as np
import pytest

import crocopy
from crocopy.experiments.box_ddp import (
    DEMO_COSTS,
    ActionModelCar,
    box_ddp_tassa,
    car_initial_controls,
    car_problem,
    car_rules_table,
    run_car,
    saturated_arcs,
    solve_recording,
)
from crocopy.experiments.box_ddp_lq import convergence_order, lq_problem, run_lq
from crocopy.experiments.box_ddp_rules import SolverBoxDDPRules
from crocopy.experiments.box_fddp import initial_positions, run_quadrotor_ics, solve_quadrotor
from crocopy.experiments.lq_reference import BoxLQ, box_lq_optimum


@pytest.mark.parametrize("costs", [{}, DEMO_COSTS])
@pytest.mark.parametrize("u", [np.array([0.3, -1.1]), np.array([-0.45, 1.7]), None])
def test_car_derivatives_against_numdiff(u, costs):
    model = ActionModelCar(**costs)
    nd = crocopy.ActionModelNumDiff(model)
    data, ndata = model.createData(), nd.createData()
    x = np.array([0.3, -0.7, 1.2, 2.5])
    for m, d in ((model, data), (nd, ndata)):
        m.calc(d, x, u)
        m.calcDiff(d, x, u)
    assert data.cost == pytest.approx(ndata.cost)
    names = ("Lx", "Lxx") if u is None else ("Fx", "Fu", "Lx", "Lu", "Lxx", "Lxu", "Luu")
    for name in names:
        assert np.allclose(getattr(data, name), getattr(ndata, name), atol=1e-5), name


def test_lq_problem_matches_the_paper_definition():
    problem, model = lq_problem(n=5, m=2, N=7, h=0.01, c_u=3.0, seed=1)
    assert problem.T == 7 and model.state.nx == 5 and model.nu == 2
    assert np.allclose(model.Q, 0.01 * np.eye(5)) and np.allclose(model.R, 0.03 * np.eye(2))
    assert np.allclose(model.u_lb, -1.0) and np.allclose(model.u_ub, 1.0)
    n = 300
    for normalized, std in ((True, 0.01 / np.sqrt(n)), (False, 0.01)):
        _, model = lq_problem(n=n, m=2, N=3, seed=2, normalized=normalized)
        assert np.std(model.A - np.eye(n)) == pytest.approx(std, rel=0.02)
        assert np.std(model.B) == pytest.approx(0.01, rel=0.2)


def random_box_lq(seed, n=3, m=2, N=6, bound=0.3):
    rng = np.random.default_rng(seed)
    A = np.eye(n) + 0.3 * rng.standard_normal((n, n))
    B = rng.standard_normal((n, m))
    Q, Qf = np.diag(rng.uniform(0.5, 2.0, n)), np.diag(rng.uniform(0.5, 2.0, n))
    return BoxLQ(A, B, Q, 0.1 * np.eye(m), Qf, 3.0 * rng.standard_normal(n), N, -bound * np.ones(m), bound * np.ones(m))


def dense_box_qp(lq):
    """Brute-force reference: the minimiser over every face (free / lower / upper) of the box."""
    import itertools

    dim = lq.N * lq.m
    J0, g0 = lq.cost_grad(np.zeros(dim))
    H = np.column_stack([lq.cost_grad(e)[1] - g0 for e in np.eye(dim)])
    best = np.inf
    for pattern in itertools.product((0, 1, 2), repeat=dim):
        p = np.array(pattern)
        z = np.where(p == 1, lq.lb, np.where(p == 2, lq.ub, 0.0))
        f = p == 0
        if f.any():
            z[f] = np.linalg.solve(H[np.ix_(f, f)], -(g0[f] + H[np.ix_(f, ~f)] @ z[~f]))
        if np.all(z >= lq.lb - 1e-12) and np.all(z <= lq.ub + 1e-12):
            best = min(best, lq.cost_grad(np.clip(z, lq.lb, lq.ub))[0])
    return best


@pytest.mark.parametrize("seed", [0, 1])
def test_box_lq_optimum_matches_a_brute_force_qp(seed):
    lq = random_box_lq(seed, N=4)
    ref = box_lq_optimum(lq)
    assert ref.gap <= 1e-11 * abs(ref.J)
    assert np.any(np.abs(ref.us) >= 0.3 - 1e-7)  # the bounds are active
    assert ref.J == pytest.approx(dense_box_qp(lq), rel=1e-10)


def test_box_lq_certificate_bounds_every_feasible_point():
    lq = random_box_lq(3)
    ref = box_lq_optimum(lq)
    rng = np.random.default_rng(0)
    for _ in range(50):
        z = rng.uniform(lq.lb, lq.ub)
        J, gap = lq.gap(z)
        assert J >= ref.J - ref.gap and J - gap <= ref.J + 1e-12
    J, g = lq.cost_grad(ref.us.ravel())
    e = 1e-6 * rng.standard_normal(g.size)
    assert lq.cost_grad(ref.us.ravel() + e)[0] - J == pytest.approx(g @ e, rel=1e-4, abs=1e-12)


def test_box_lq_optimum_without_active_bounds_is_the_riccati_solution():
    problem, model = lq_problem(n=6, m=3, N=30, c_u=1.0, seed=4)
    model.u_lb, model.u_ub = -1e3 * np.ones(3), 1e3 * np.ones(3)
    ref = box_lq_optimum(BoxLQ.from_lqr_model(model, problem.x0, problem.T))
    ddp = crocopy.SolverDDP(problem)
    ddp.solve([], [], 2)
    assert ddp.cost == pytest.approx(ref.J, rel=1e-10)
    with pytest.raises(ValueError, match="lb < ub"):
        BoxLQ(model.A, model.B, model.Q, model.R, model.Q, problem.x0, 3, np.ones(3), np.ones(3))


def test_convergence_order_of_model_sequences():
    assert convergence_order([1e-1, 1e-2, 1e-4, 1e-8, 0.0]) == pytest.approx([2.0, 2.0])
    assert convergence_order([1.0, 0.5, 0.25, 0.125]) == pytest.approx([1.0, 1.0])
    assert convergence_order([1e-3, 1e-14]) == []


def test_run_lq_small(tmp_path, capsys):
    res = run_lq(str(tmp_path), maxiter=20, n_random=2, sizes=(6, 3, 40), n_range=(4, 8))
    out = capsys.readouterr().out
    assert "factorisations per QP solve" in out
    assert (tmp_path / "boxddp_lq.png").stat().st_size > 10_000
    for r in (res["showcase"], *res["random"]):
        assert r["gap"] <= 1e-11 * abs(r["J*"]) and r["active"] > 0.0
        for err in r["errors"].values():
            assert err.min() >= -1e-10  # no method goes below the certified optimum
        assert r["iterations"]["Box-DDP"] is not None and r["iterations"]["Box-DDP"] <= 20
    assert res["summary"]["methods"]["Box-DDP"]["within_20"] == 3


def test_box_ddp_showcase_reaches_the_certified_optimum_within_20_iterations():
    from crocopy.experiments.box_ddp import box_ddp_tassa

    problem, model = lq_problem()
    ref = box_lq_optimum(BoxLQ.from_lqr_model(model, problem.x0, problem.T))
    assert 0.02 < np.mean(np.abs(ref.us) >= 1.0 - 1e-6) < 0.5
    solver = box_ddp_tassa(problem)
    costs = []
    solver.setCallbacks([lambda s: costs.append(s.cost)])
    us0 = [np.zeros(model.nu)] * problem.T
    solver.solve(problem.rollout(us0), us0, 20, True)
    err0 = (problem.calc(problem.rollout(us0), us0) - ref.J) / ref.J
    err = np.r_[err0, (np.array(costs) - ref.J) / ref.J]
    assert err.min() >= -1e-10 and 0 < np.flatnonzero(err < 1e-8)[0] <= 20
    assert convergence_order(err)[0] > 1.2  # superlinear before the exact final step


@pytest.mark.slow
def test_box_ddp_lq_bar_on_the_20_random_problems(tmp_path):
    res = run_lq(str(tmp_path), plot=False, verbose=False)
    box = res["summary"]["methods"]["Box-DDP"]
    assert res["showcase"]["iterations"]["Box-DDP"] <= 20
    assert box["within_20"] - (res["showcase"]["iterations"]["Box-DDP"] <= 20) >= 18
    assert res["summary"]["bar"]
    for r in res["random"]:
        assert r["gap"] <= 1e-11 * abs(r["J*"])


def test_run_car_small(tmp_path):
    res = run_car(str(tmp_path), maxiter=40, N=60, rules=False)
    assert (tmp_path / "boxddp_car.png").stat().st_size > 10_000
    us = res["us"]["Box-DDP"]
    assert np.all(np.abs(us[:, 0]) <= 0.5) and np.all(np.abs(us[:, 1]) <= 2.0)
    assert np.all(np.abs(res["us"]["squashing"][:, 0]) < 0.5)
    assert res["clamped_nodes_with_zero_K_rows"] == res["clamped_nodes"]
    assert res["costs"]["Box-DDP"][-1] < res["costs"]["Box-DDP"][0]


def test_box_ddp_rules_crocoddyl_reproduces_the_solver_and_tassa_rules_differ():
    us0 = car_initial_controls(60)
    ref = solve_recording(box_ddp_tassa(car_problem(60)), us0, 30)
    same = solve_recording(SolverBoxDDPRules(car_problem(60), "crocoddyl", "crocoddyl", "crocoddyl"), us0, 30)
    assert same["iter"] == ref["iter"]
    np.testing.assert_allclose(same["costs"], ref["costs"], rtol=1e-12)
    tassa = SolverBoxDDPRules(car_problem(60))
    lams, costs = [], []
    tassa.setCallbacks([lambda s: (lams.append(s.preg), costs.append(s.cost))])
    tassa.solve(tassa.problem.rollout(us0), us0, 30)
    assert costs[-1] < ref["costs"][0] and np.all(np.diff(costs) <= 0.0)
    assert lams[0] == pytest.approx(1.0 / 1.6) and lams[1] == pytest.approx(lams[0] / 1.6**2)
    assert tassa.alphas[-1] == pytest.approx(1e-3) and len(tassa.alphas) == 11
    with pytest.raises(ValueError, match="line_search"):
        SolverBoxDDPRules(car_problem(5), line_search="armijo")


def test_saturated_arcs_counts_runs_on_either_bound():
    us = np.zeros((9, 2))
    us[[0, 1, 4, 7, 8], 0] = [0.5, 0.5, -0.5, 0.5, -0.5]
    assert saturated_arcs(us) == 3


@pytest.mark.slow
def test_car_iterations_against_the_paper():
    """Box-DDP's 64 iterations in the paper match a loose stop; tight stops need ~200 on this optimum."""
    table = car_rules_table(verbose=False)
    assert table["Tassa's rules, tolFun 1e-4"]["iter"] <= 96
    assert table["Crocoddyl's rules (crocopy default)"]["to_1e-2"] <= 64
    for label in ("Crocoddyl's rules (crocopy default)", "Tassa's rules, tolFun 1e-7"):
        assert table[label]["iter"] > 96 and table[label]["to_1e-3"] > 96


def test_quadrotor_box_solvers_short_horizon():
    for method in ("Box-FDDP", "Box-DDP"):
        r = solve_quadrotor(method, "goal", (-0.3, 0.0, 0.0), maxiter=100, T=15)
        assert r["solved"] and r["max_violation"] == 0.0
        assert r["us"].min() >= 0.1 and r["us"].max() <= 10.3
        assert r["cost"] < r["costs"][0]
    with pytest.raises(ValueError, match="method"):
        solve_quadrotor("clamping")


def test_run_quadrotor_ics_small(tmp_path):
    assert np.allclose(initial_positions(10)[[0, -1], 0], [-0.9, 0.3])
    res = run_quadrotor_ics(str(tmp_path), n=2, maxiter=20, T=10)
    assert (tmp_path / "boxfddp_quadrotor.png").stat().st_size > 10_000
    assert set(res["summary"]) == {"Box-FDDP", "Box-DDP", "squashing"}
    assert all(r["max_violation"] == 0.0 for rs in res["results"].values() for r in rs)
