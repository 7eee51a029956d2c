"""SolverSQP (mim-solvers' API): one exact step on LQ problems, the filter line search, read-outs,
callbacks, the ``crocopy.mim_solvers`` alias and "one answer" with kernels on or off."""

from __future__ import annotations

import contextlib
import io
import sys

import numpy as np
import pytest
from sqp_problems import dense_lq_solution, random_lq

import crocopy
import crocopy.mim_solvers as mim_solvers


def _unicycle() -> crocopy.ShootingProblem:
    m = crocopy.ActionModelUnicycle()
    return crocopy.ShootingProblem(np.array([-1.0, -1.0, 1.0]), [m] * 20, m)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_lq_one_step_is_the_dense_kkt_solution(seed):
    problem = random_lq(seed)
    rng = np.random.default_rng(seed + 10)
    xs0 = [rng.normal(size=problem.nx) for _ in range(problem.T + 1)]
    us0 = [rng.normal(size=2) for _ in range(problem.T)]
    xs_ref, us_ref, lam_ref = dense_lq_solution(problem)
    solver = crocopy.SolverSQP(problem)
    solver.termination_tolerance = 1e-8
    assert solver.solve(xs0, us0, 10, regInit=0.0)  # no regularisation: the first step is exact
    assert solver.iter == 1 and solver.KKT <= 1e-8
    np.testing.assert_allclose(np.array(solver.xs), xs_ref, atol=1e-8)
    np.testing.assert_allclose(np.array(solver.us), us_ref, atol=1e-8)
    np.testing.assert_allclose(np.array(solver.lag_mul), lam_ref, atol=1e-7)
    assert max(np.abs(f).max() for f in solver.fs) < 1e-12


def test_trial_gaps_contract_by_one_minus_alpha_on_linear_dynamics():
    problem = random_lq(4)
    rng = np.random.default_rng(3)
    solver = crocopy.SolverSQP(problem)
    solver.solve([rng.normal(size=3) for _ in range(problem.T + 1)], [rng.normal(size=2) for _ in range(problem.T)], 0)
    solver.xs[0] = problem.x0.copy()
    solver.computeDirection()
    solver._linear_rollout()
    gaps = [f.copy() for f in solver.fs]
    for alpha in (0.5, 0.25):
        solver.tryStep(alpha)
        for f_try, f in zip(solver.fs_try[1:], gaps[1:]):
            np.testing.assert_allclose(f_try, (1 - alpha) * f, atol=1e-12)
        assert solver.gap_norm_try == pytest.approx((1 - alpha) * sum(np.abs(f).sum() for f in gaps))


def test_defaults_and_readouts():
    solver = crocopy.SolverSQP(_unicycle())
    assert solver.KKT == np.inf
    expected = {"termination_tolerance": 1e-6, "use_filter_line_search": True, "filter_size": 1, "mu_dynamic": 1.0,
                "extra_iteration_for_last_kkt": False, "reg_min": 1e-9, "reg_max": 1e9, "th_stepDec": 0.5,
                "th_stepInc": 0.01, "reg_incFactor": 10.0, "reg_decFactor": 10.0}
    for name, value in expected.items():
        assert getattr(solver, name) == value, name
    assert solver.alphas == [2.0 ** -n for n in range(10)]
    assert solver.solve(init_xs=[], init_us=[], maxiter=100, isFeasible=True, regInit=1e-6)
    assert solver.iter > 1 and solver.KKT <= 1e-6 and solver.reason == "converged"
    assert len(solver.lag_mul) == 21 and len(solver.dx) == 21 and len(solver.du) == 20
    assert solver.merit == pytest.approx(solver.cost + solver.mu_dynamic * solver.gap_norm, rel=1e-3)
    with pytest.raises(ValueError, match="maxiter"):
        solver.solve([], [], -1)


@pytest.mark.parametrize("filter_search", [True, False])
def test_merit_and_filter_line_searches_converge(filter_search):
    solver = crocopy.SolverSQP(_unicycle())
    solver.use_filter_line_search = filter_search
    solver.filter_size = 5
    solver.mu_dynamic = 100.0  # the ℓ1 merit needs a weight above the multipliers (1 stalls, as in mim-solvers)
    assert solver.solve([], [], 100)
    assert solver.KKT <= 1e-6


def test_extra_iteration_describes_the_final_iterate():
    solver = crocopy.SolverSQP(_unicycle())
    solver.extra_iteration_for_last_kkt = True
    assert not solver.solve([], [], 3)
    assert solver.iter == 3
    first = solver.KKT
    solver.extra_iteration_for_last_kkt = False
    solver.solve([], [], 3)
    assert solver.KKT > first  # without it, KKT describes the iterate before the last step


def test_kernels_on_or_off_give_one_answer():
    runs = []
    for enabled in (True, False):
        with crocopy.use_kernels(enabled):
            solver = crocopy.SolverSQP(_unicycle())
            # Gauss-Newton converges linearly here; below a KKT of ~3e-9 the filter compares costs equal to the
            # last bit and gaps of 1e-16, so round-off (kernels or BLAS) picks the step: stop before that.
            solver.termination_tolerance = 1e-8
            assert solver.solve([], [], 100)
            runs.append((solver.iter, solver.cost))
    assert runs[0][0] == runs[1][0]
    assert runs[0][1] == pytest.approx(runs[1][1], rel=1e-12)


def test_mim_solvers_alias_callbacks():
    solver = mim_solvers.SolverSQP(_unicycle())
    logger = mim_solvers.CallbackLogger()
    solver.setCallbacks([mim_solvers.CallbackVerbose(), logger])
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        assert solver.solve([], [], 100)
    lines = out.getvalue().splitlines()
    assert lines[0] == "iter    merit      cost     ||gaps||     step     KKT criteria   "
    assert lines[1].startswith("   0  ") and lines[-1].split()[4] == "----"
    data = logger.convergence_data
    assert list(data) == ["us", "xs", "fs", "iter", "cost", "merit", "preg", "dreg", "step", "KKT"]
    assert data["iter"] == list(range(solver.iter + 1)) and data["KKT"][-1] == solver.KKT
    assert mim_solvers.SolverSQP is crocopy.SolverSQP and mim_solvers.SolverCSQP is crocopy.SolverCSQP


def test_plot_convergence():
    pytest.importorskip("matplotlib")
    import matplotlib

    matplotlib.use("Agg")
    solver = crocopy.SolverSQP(_unicycle())
    logger = mim_solvers.CallbackLogger()
    solver.setCallbacks([logger])
    solver.solve([], [], 100)
    fig = mim_solvers.plotConvergence(logger.convergence_data, show=False)
    assert [ax.get_ylabel() for ax in fig.axes] == ["iter", "cost", "merit", "step", "KKT"]
    assert fig.axes[-1].get_yscale() == "log"


def test_bench_vs_mim_without_the_bench_extra(monkeypatch):
    monkeypatch.setitem(sys.modules, "mim_solvers", None)  # not importable, whether installed or not
    from crocopy.cli import main

    err = io.StringIO()
    with contextlib.redirect_stderr(err):
        assert main(["bench", "--vs", "mim"]) == 2
    assert "mim-solvers" in err.getvalue()


def test_compiled_nodes_give_one_answer():
    from crocopy.problems import registry
    from crocopy.solvers import compiled_nodes

    runs = []
    for enabled in (True, False):
        with crocopy.use_kernels(enabled):
            problem, xs, us = registry.get("arm").build()
            solver = crocopy.SolverSQP(problem)
            assert (compiled_nodes.select(solver) is not None) == enabled
            assert solver.solve(xs, us, 100)
            runs.append((solver.iter, solver.cost, problem.runningDatas[3].cost))
    assert runs[0][0] == runs[1][0]
    assert runs[0][1] == pytest.approx(runs[1][1], rel=1e-12)
    assert runs[0][2] == pytest.approx(runs[1][2], rel=1e-12)  # the datas are left at the final iterate


def test_direction_and_trial_from_outside_solve():
    solver = crocopy.SolverSQP(_unicycle())
    solver.setCandidate([], [], False)
    solver.computeDirection()
    assert solver.gap_norm == pytest.approx(sum(np.abs(f).sum() for f in solver.fs))
    assert max(np.abs(d).max() for d in solver.dx) > 0  # the linear rollout ran
    merit = solver.tryStep(1.0)
    assert merit == pytest.approx(solver.cost_try + solver.mu_dynamic * solver.gap_norm_try)
    solver.checkKKTConditions()
    assert solver.stoppingCriteria() == solver.KKT > 0
