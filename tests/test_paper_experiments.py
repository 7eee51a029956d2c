"""Fast versions of the Box-DDP / Box-FDDP paper experiments (small sizes, few iterations)."""

import numpy as np
import pytest

import crocopy
from crocopy.experiments.box_ddp import ActionModelCar, lq_problem, run_car, run_lq
from crocopy.experiments.box_fddp import initial_positions, run_quadrotor_ics, solve_quadrotor


@pytest.mark.parametrize("u", [np.array([0.3, -1.1]), np.array([-0.45, 1.7]), None])
def test_car_derivatives_against_numdiff(u):
    model = ActionModelCar()
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
    assert np.abs(model.A - np.eye(5)).max() < 0.1


def test_run_lq_small(tmp_path, capsys):
    res = run_lq(str(tmp_path), maxiter=20, n_random=2, sizes=(6, 3, 40), n_range=(4, 8))
    out = capsys.readouterr().out
    assert "factorizations per QP solve" in out
    assert (tmp_path / "boxddp_lq.png").stat().st_size > 10_000
    costs = res["showcase"]
    best = min(c.min() for c in costs.values())
    assert costs["Box-DDP"][-1] == pytest.approx(best, rel=1e-8)
    assert costs["clamping (rollout)"][-1] >= best
    assert 0.0 < res["factorizations_per_qp"] < 3.0


def test_run_car_small(tmp_path):
    res = run_car(str(tmp_path), maxiter=40, N=60)
    assert (tmp_path / "boxddp_car.png").stat().st_size > 10_000
    us = res["us"]["Box-DDP"]
    assert np.all(np.abs(us[:, 0]) <= 0.5) and np.all(np.abs(us[:, 1]) <= 2.0)
    assert np.all(np.abs(res["us"]["squashing"][:, 0]) < 0.5)
    assert res["clamped_nodes_with_zero_K_rows"] == res["clamped_nodes"]
    assert res["costs"]["Box-DDP"][-1] < res["costs"]["Box-DDP"][0]


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
