"""Oracle: crocopy's SolverSQP/SolverCSQP against mim-solvers 0.3.0 (bench extra), run as a black box.

Each problem of :mod:`crocopy.bench.mim` is built with each library and solved from ``x0`` at every
node and zero controls by the solver of the same name.  Bar (issue 26): crocopy converges when
mim-solvers does, to its cost within 1e-6 relative, with a constraint violation <= 1e-6, in at most
mim-solvers' iterations + 10 %.  A single ADMM step is also compared on the UR5 box: same QP
iterations, ρ, step, multipliers and KKT.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

crocoddyl = pytest.importorskip("crocoddyl")
mim_solvers = pytest.importorskip("mim_solvers")

import crocopy  # noqa: E402
import crocopy.mim_solvers as crocopy_mim  # noqa: E402
from crocopy.bench.mim import MIM_CASES, build_problem, run  # noqa: E402

pytestmark = pytest.mark.usefixtures("bench_crocoddyl")

#: (problem, solver, termination tolerance, solver settings).  With the default QP accuracy
#: (eps_abs = 1e-4) the KKT measure of the UR5 box stalls near 3e-6 (as mim-solvers'), and its violation
#: stays near 1e-6, so that case asks the QP for more; the Solo12 case stalls near 1e-5.
CASES = MIM_CASES


@pytest.mark.parametrize("name, solver, tolerance, settings", CASES, ids=[f"{c[0]}-{c[1]}" for c in CASES])
def test_same_solution_as_mim_solvers(name, solver, tolerance, settings):
    mim = run(crocoddyl, mim_solvers, name, solver, 200, tolerance, settings)
    mine = run(crocopy, crocopy_mim, name, solver, 200, tolerance, settings)
    assert mim["converged"], mim
    assert mine["converged"], (mine, mim)
    assert mine["iter"] <= math.ceil(1.1 * mim["iter"]), (mine, mim)
    assert mine["cost"] == pytest.approx(mim["cost"], rel=1e-6), (mine, mim)
    assert mine["violation"] <= 1e-6, mine
    assert mine["KKT"] <= tolerance


def _first_qp(lib, solvers):
    """One CSQP QP at a perturbed start of the UR5 box problem, with the KKT of that start."""
    problem = build_problem(lib, "ur5_ee_box")
    rng = np.random.default_rng(3)
    xs = [problem.x0 + 0.05 * np.r_[rng.normal(size=6), np.zeros(6)] for _ in range(problem.T + 1)]
    us = [rng.normal(size=6) for _ in range(problem.T)]
    solver = solvers.SolverCSQP(problem)
    solver.extra_iteration_for_last_kkt = True
    solver.solve(xs, us, 0)
    return {
        "qp_iters": float(solver.qp_iters), "KKT": float(solver.KKT),
        "rho": [np.array(r, copy=True) for r in solver.rho_vec], "dx": [np.array(v, copy=True) for v in solver.dx],
        "du": [np.array(v, copy=True) for v in solver.du], "y": [np.array(v, copy=True) for v in solver.y],
        "lag_mul": [np.array(v, copy=True) for v in solver.lag_mul],
    }


def test_admm_trace_matches_mim_solvers():
    mim, mine = _first_qp(crocoddyl, mim_solvers), _first_qp(crocopy, crocopy)
    assert mine["qp_iters"] == mim["qp_iters"]
    assert mine["KKT"] == pytest.approx(mim["KKT"], rel=1e-6)
    for key in ("rho", "dx", "du", "y", "lag_mul"):
        for a, b in zip(mine[key], mim[key]):
            np.testing.assert_allclose(a, b, rtol=1e-6, atol=1e-8, err_msg=key)
