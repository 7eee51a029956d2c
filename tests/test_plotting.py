"""Solution, convergence and feasibility plots saved as PNG with the Agg backend."""

from __future__ import annotations

import subprocess
import sys
import warnings
from types import SimpleNamespace

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
from PIL import Image  # noqa: E402

import crocopy  # noqa: E402
from crocopy.callbacks.plotting import (  # noqa: E402
    gap_norms,
    plot_convergence_from_logger,
    plot_feasibility,
    plotConvergence,
    plotFeasibility,
    plotOCSolution,
)


@pytest.fixture(autouse=True)
def _close_figures():
    yield
    plt.close("all")


@pytest.fixture(scope="module")
def solved():
    model = crocopy.ActionModelUnicycle()
    problem = crocopy.ShootingProblem(np.array([1.0, -0.5, 0.4]), [model] * 20, model)
    solver = crocopy.SolverFDDP(problem)
    logger = crocopy.CallbackLogger()
    solver.setCallbacks([logger])
    xs0 = [np.array([1.0, -0.5, 0.4]) + 0.1 * i for i in range(21)]  # infeasible guess: open gaps
    solver.solve(xs0, [np.zeros(2)] * 20, 50)
    return solver, logger


def _png_ok(path) -> np.ndarray:
    img = np.asarray(Image.open(path).convert("RGB"), dtype=int)
    assert img.shape[0] > 100 and img.shape[1] > 100
    assert (img.std(axis=(0, 1)) > 5).all()  # not a blank canvas
    return img


def test_plotting_does_not_load_matplotlib_with_crocopy(tmp_path):
    code = "import sys, crocopy, crocopy.callbacks.plotting; print('matplotlib' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=tmp_path)
    assert out.stdout.strip() == "False"
    assert crocopy.plotOCSolution is plotOCSolution and crocopy.plotConvergence is plotConvergence


def test_solution_plot_with_limits(solved, tmp_path):
    solver, _ = solved
    lb, ub = np.array([-0.5, -np.inf]), np.array([0.5, 2.0])
    path = tmp_path / "solution.png"
    fig = plotOCSolution(solver.xs, solver.us, figIndex=3, show=False, figTitle="unicycle", u_lb=lb, u_ub=ub,
                         dts=[0.1] * 20, path=path)
    _png_ok(path)
    state_ax, control_ax = fig.axes
    assert len(state_ax.lines) == 3
    np.testing.assert_allclose(state_ax.lines[0].get_xdata(), 0.1 * np.arange(21))
    np.testing.assert_allclose(state_ax.lines[2].get_ydata(), [x[2] for x in solver.xs])
    limits = sorted(line.get_ydata()[0] for line in control_ax.lines[2:])
    assert limits == [-0.5, 0.5, 2.0]  # infinite bound skipped
    assert fig._suptitle.get_text() == "unicycle"
    assert [ax.get_title() for ax in fig.axes] == ["state trajectory", "control trajectory"]
    only_u = plotOCSolution(us=solver.us, show=False)
    assert len(only_u.axes) == 1
    assert only_u._suptitle.get_text() == "State and control trajectories"  # a title even without figTitle


def test_solution_plot_bad_input():
    with pytest.raises(ValueError, match="xs or us"):
        plotOCSolution(show=False)
    with pytest.raises(ValueError, match="u_ub"):
        plotOCSolution(us=[np.zeros(2)] * 3, u_ub=np.ones(3), show=False)
    with pytest.raises(ValueError, match="xs must hold vectors of one size"):
        plotOCSolution([np.zeros(2), np.zeros(3)], show=False)
    with pytest.raises(ValueError, match="dts"):
        plotOCSolution([np.zeros(2)] * 4, dts=[0.1], show=False)


def test_convergence_plot_crocoddyl_signature(solved, tmp_path):
    _, log = solved
    path = tmp_path / "conv.png"
    fig = plotConvergence(log.costs, log.pregs, log.dregs, log.grads, log.stops, log.steps, figIndex=2, show=False,
                          path=path)
    _png_ok(path)
    assert len(fig.axes) == 5
    np.testing.assert_allclose(fig.axes[0].lines[0].get_ydata(), log.costs)
    np.testing.assert_allclose(fig.axes[4].lines[0].get_ydata(), log.steps)
    assert [ax.get_title() for ax in fig.axes] == [
        "Cost", "Regularization", "Gradient", "Stopping criterion", "Step length"]
    assert all(ax.get_yscale() == "log" for ax in fig.axes)  # every quantity spans decades over a solve
    assert fig._suptitle.get_text() == "Solver convergence"
    assert max(log.costs) / min(log.costs) > 10  # the case the log scale is for: a linear axis would flatten it
    with pytest.raises(ValueError, match="one value per iteration"):
        plotConvergence([1.0, 2.0], [1.0], [1.0], [1.0], [1.0], [1.0], show=False)
    with pytest.raises(ValueError, match="costs must be a 1-D"):
        plotConvergence(np.zeros((2, 2)), [1.0], [1.0], [1.0], [1.0], [1.0], show=False)


def test_convergence_from_logger(solved, tmp_path):
    _, log = solved
    path = tmp_path / "logger.png"
    fig = plot_convergence_from_logger(log, path, title="FDDP")
    _png_ok(path)
    assert len(fig.axes) == 6
    gaps = fig.axes[5].lines[0].get_ydata()
    assert gaps[0] > 1e-3 and gaps[-1] == pytest.approx(1e-14)  # gaps open at first, closed (0) at the end
    titles = {ax.get_title(): ax for ax in fig.axes}
    assert set(titles) == {"Cost", "Regularization", "Gradient", "Stopping criterion", "Step length",
                           "Dynamic feasibility"}
    assert all(ax.get_yscale() == "log" for ax in fig.axes)
    assert fig._suptitle.get_text() == "FDDP"
    assert plot_convergence_from_logger(log)._suptitle.get_text() == "Solver convergence"
    with pytest.raises(ValueError, match="no iterations"):
        plot_convergence_from_logger(crocopy.CallbackLogger())


def test_feasibility_plots(solved, tmp_path):
    _, log = solved
    path = tmp_path / "feas.png"
    fig = plotFeasibility(log.ffeass, log.hfeass, show=False, path=path)
    _png_ok(path)
    np.testing.assert_allclose(fig.axes[0].lines[0].get_ydata(), np.where(np.array(log.ffeass) > 0, log.ffeass, 1e-14))
    assert fig.axes[0].get_yscale() == "log" and fig.axes[0].get_title() and fig._suptitle.get_text() == "Feasibility"
    path2 = tmp_path / "fig4.png"
    slow = [1.0 * 0.5**k for k in range(12)] + [0.0]
    fig = plot_feasibility({"FDDP": log, "slow": slow}, path2, title="gap contraction")
    _png_ok(path2)
    assert [line.get_label() for line in fig.axes[0].lines] == ["FDDP", "slow"]
    assert fig.axes[0].get_yscale() == "log"
    assert fig.axes[0].get_title() == "Gap norm per iteration" and fig._suptitle.get_text() == "gap contraction"
    np.testing.assert_allclose(fig.axes[0].lines[1].get_ydata()[-1], 1e-14)
    single = plot_feasibility(slow)
    assert len(single.axes[0].lines) == 1


def test_gap_norms_from_gaps_only():
    logger = SimpleNamespace(ffeass=[], fs=[[np.array([0.1, -0.3]), np.array([0.2])], [np.zeros(2), np.zeros(1)]])
    np.testing.assert_allclose(gap_norms(logger), [0.3, 0.0])


def test_show_with_agg_backend_does_not_fail(solved):
    _, log = solved
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        plotFeasibility(log.ffeass, log.hfeass, show=True)


def test_negative_costs_get_a_symmetric_log_axis():
    costs = [-50.0, -3.0, 0.0, 2.0, 400.0]
    grads, steps = [1.0, 0.1, 1e-2, 1e-3, 1e-4], [1.0, 0.5, 0.25, 1.0, 1.0]
    fig = plotConvergence(costs, [1e-9] * 5, [1e-9] * 5, grads, [1.0] * 5, steps, show=False)
    assert fig.axes[0].get_yscale() == "symlog"
    np.testing.assert_allclose(fig.axes[0].lines[0].get_ydata(), costs)  # drawn as they are, zero included
    assert [ax.get_yscale() for ax in fig.axes[1:]] == ["log"] * 4
