"""Oracle: SolverIntro and SolverKKT against Crocoddyl's on the same problems (bench extra).

The problems (:mod:`intro_problems`) are built through the same public API in both libraries, and
Crocoddyl runs as a black box.  Compared: convergence, iterations and final cost (1e-6 relative,
the issue's bar), the per-iteration figures the verbose callback prints, the nullspace factors
(``Hu_rank``, ``YZ``, ``Hy``) and the KKT system.  Known difference, not compared here: Crocoddyl's
SolverIntro schedules ``preg`` differently from FDDP (it depends on ``th_feas``); crocopy keeps
FDDP's schedule, which only shows once the regularisation leaves ``reg_min`` (see the docstring of
:mod:`crocopy.solvers.intro`).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

crocoddyl = pytest.importorskip("crocoddyl")

import crocopy  # noqa: E402

pytestmark = pytest.mark.usefixtures("bench_crocoddyl")

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
import intro_problems as ip  # noqa: E402

EQ = ("LuNull", "QrNull", "Schur")
NONLINEAR = [dict(T=10, seed=3, a=0.3, b=0.1), dict(T=12, seed=3, a=0.5, b=0.1), dict(T=10, seed=6, a=0.3, b=0.1),
             dict(T=10, seed=1, a=0.3, b=0.1), dict(T=12, seed=6, a=0.5, b=0.1), dict(T=12, seed=5, a=0.5, b=0.1),
             dict(T=12, seed=3, a=0.5, b=0.1, th_feas=1e-2, init_reg=1e-3),
             dict(T=12, seed=7, a=0.5, b=0.1, th_feas=1e4, init_reg=1e-9),
             dict(T=12, seed=1, a=0.5, b=0.1, th_feas=1.0, init_reg=1e-1)]
FIGURES = ("cost", "merit", "upsilon", "stop", "stepLength", "hfeas", "ffeas", "dV", "dVexp", "dPhi", "dPhiexp", "preg")
KKT_FIGURES = ("cost", "stop", "stepLength", "dV", "dVexp", "ffeas")
#: upsilon divides by hfeas, which tends to 0: round-off differences grow as it does.
REL = {"upsilon": 1e-4, "preg": 1e-9}


def _trace(lib, solver, xs, us, maxiter, figures=FIGURES, init_reg=None):
    rows = []

    def record(s):
        rows.append({k: float(getattr(s, k)) for k in figures})

    if lib is crocoddyl:
        class Recorder(crocoddyl.CallbackAbstract):
            def __init__(self):
                crocoddyl.CallbackAbstract.__init__(self)

            def __call__(self, s):
                record(s)

        solver.setCallbacks([Recorder()])
    else:
        solver.setCallbacks([record])
    if init_reg is None:
        converged = solver.solve(list(xs), list(us), maxiter)
    else:
        converged = solver.solve(list(xs), list(us), maxiter, False, init_reg)
    return converged, rows


def _intro(lib, problem, eq):
    solver = lib.SolverIntro(problem)
    solver.eq_solver = getattr(lib.EqualitySolverType, eq)
    return solver


@pytest.mark.parametrize("eq", EQ)
def test_lq_equality_problem_same_as_crocoddyl(eq):
    out = {}
    for lib in (crocoddyl, crocopy):
        s = _intro(lib, ip.lq_equality_problem(lib), eq)
        ok, rows = _trace(lib, s, [], [], 10)
        out[lib] = (ok, s.iter, s.cost, [np.array(u) for u in s.us], rows)
    (ok_c, it_c, cost_c, us_c, rows_c), (ok_m, it_m, cost_m, us_m, rows_m) = out[crocoddyl], out[crocopy]
    assert ok_c and ok_m and it_c == it_m == 1
    assert cost_m == pytest.approx(cost_c, rel=1e-12)
    for k in ("cost", "merit", "stepLength", "dV", "dVexp"):
        assert [r[k] for r in rows_m] == pytest.approx([r[k] for r in rows_c], rel=1e-9, abs=1e-9)
    for a, b in zip(us_m, us_c):
        np.testing.assert_allclose(a, b, atol=1e-10)


@pytest.mark.parametrize("eq", EQ)
def test_backward_pass_attributes_same_as_crocoddyl(eq):
    """Every per-node attribute after one computeDirection from the same infeasible candidate."""
    names = ("Hu_rank", "YZ", "Hy", "Qz", "Qzz", "Qxz", "Quz", "kz", "Kz", "ks", "Ks", "k", "K", "Vx", "Vxx")
    got = {}
    for lib in (crocoddyl, crocopy):
        problem, xs, us = ip.nonlinear_equality_problem(lib, T=10, seed=3, a=0.3, b=0.1)
        s = _intro(lib, problem, eq)
        s.setCandidate(xs, us, False)
        s.computeDirection(True)
        got[lib] = {k: [np.array(v) for v in getattr(s, k)] for k in names}
    for k in names:
        for a, b in zip(got[crocopy][k], got[crocoddyl][k]):
            np.testing.assert_allclose(a.reshape(b.shape), b, rtol=1e-8, atol=1e-9, err_msg=k)


@pytest.mark.parametrize("case", NONLINEAR, ids=lambda c: "-".join(f"{k}{v}" for k, v in c.items()))
def test_nonlinear_equality_problem_same_iterations_and_cost(case):
    out = {}
    case = dict(case)
    th_feas, init_reg = case.pop("th_feas", 1e-4), case.pop("init_reg", None)
    for lib in (crocoddyl, crocopy):
        problem, xs, us = ip.nonlinear_equality_problem(lib, **case)
        s = lib.SolverIntro(problem)
        s.th_feas = th_feas
        ok, rows = _trace(lib, s, xs, us, 100, init_reg=init_reg)
        out[lib] = (ok, s.iter, s.cost, rows)
    ok_c, it_c, cost_c, rows_c = out[crocoddyl]
    ok_m, it_m, cost_m, rows_m = out[crocopy]
    assert ok_c and ok_m
    assert it_m == it_c
    assert cost_m == pytest.approx(cost_c, rel=1e-6)
    for i, (rc, rm) in enumerate(zip(rows_c, rows_m)):
        for k in FIGURES:
            assert rm[k] == pytest.approx(rc[k], rel=REL.get(k, 1e-6), abs=1e-9), f"iteration {i}: {k}"


def test_a_reused_solver_solves_again_as_crocoddyls():
    """One solver solving the same problem again (as a script calling ``solve()`` twice): ``upsilon`` persists, the
    first iteration of each solve does not update it (its held ``hfeas`` is the last solve's), so the second solve
    (not the first's again: ``upsilon`` counts from its first iteration) traces as Crocoddyl's; a solve with
    ``maxiter = 0`` leaves the figures as they were."""
    out = {}
    case = dict(NONLINEAR[1])
    for lib in (crocoddyl, crocopy):
        problem, xs, us = ip.nonlinear_equality_problem(lib, **case)
        s = lib.SolverIntro(problem)
        first = _trace(lib, s, xs, us, 100)
        s.solve(list(xs), list(us), 0)
        idle = (float(s.hfeas), float(s.merit), float(s.upsilon))
        second = _trace(lib, s, xs, us, 100)
        out[lib] = (first, idle, second, s.iter, s.cost)
    (first_c, idle_c, (ok_c, rows_c), it_c, cost_c) = out[crocoddyl]
    (first_m, idle_m, (ok_m, rows_m), it_m, cost_m) = out[crocopy]
    assert first_c[0] and first_m[0]
    assert ok_c and ok_m and it_m == it_c and len(rows_c) > 2
    assert cost_m == pytest.approx(cost_c, rel=1e-6)
    assert idle_m == pytest.approx(idle_c, rel=1e-4, abs=1e-9)
    for i, (rc, rm) in enumerate(zip(rows_c, rows_m)):
        for k in FIGURES:
            assert rm[k] == pytest.approx(rc[k], rel=REL.get(k, 1e-6), abs=1e-9), f"iteration {i}: {k}"


@pytest.mark.parametrize("eq", EQ)
def test_arm_acceleration_rows_same_as_crocoddyl(eq):
    """Talos' arm, free forward dynamics, joint accelerations as equality rows on every running node."""
    out = {}
    for lib in (crocoddyl, crocopy):
        s = _intro(lib, ip.arm_problem(lib), eq)
        ok, rows = _trace(lib, s, [], [], 100)
        out[lib] = (ok, s.iter, s.cost, rows)
    assert out[crocoddyl][:2] == out[crocopy][:2] == (True, 4)
    assert out[crocopy][2] == pytest.approx(out[crocoddyl][2], rel=1e-9)
    for rc, rm in zip(out[crocoddyl][3], out[crocopy][3]):
        for k in ("cost", "merit", "stepLength", "ffeas"):
            assert rm[k] == pytest.approx(rc[k], rel=1e-6, abs=1e-9)


def test_verbose_header_and_rows_as_crocoddyl(capfd):
    for lib in (crocoddyl, crocopy):
        s = _intro(lib, ip.lq_equality_problem(lib), "LuNull")
        s.setCallbacks([lib.CallbackVerbose()])
        s.solve([], [], 10)
    lines = capfd.readouterr().out.strip().splitlines()
    assert len(lines) == 6
    croc, mine = lines[:3], lines[3:]
    assert mine[0] == croc[0]
    for a, b in zip(croc[1:], mine[1:]):
        assert len(a.split()) == len(b.split()) == 15
        assert a.split()[:2] == b.split()[:2]


def test_kkt_same_as_crocoddyl():
    for build, iters in ((lambda lib: ip.lq_equality_problem(lib, nh=0), 1), (_unicycle, 8)):
        out = {}
        for lib in (crocoddyl, crocopy):
            s = lib.SolverKKT(build(lib))
            ok, rows = _trace(lib, s, [], [], 50, KKT_FIGURES)
            out[lib] = (ok, s.iter, s.cost, rows)
        assert out[crocoddyl][:2] == out[crocopy][:2] == (True, iters)
        assert out[crocopy][2] == pytest.approx(out[crocoddyl][2], rel=1e-9)
        for rc, rm in zip(out[crocoddyl][3], out[crocopy][3]):
            # At an iterate that already meets th_stop, the line search compares a cost change and a prediction that
            # are both round-off (dV 0 or 1e-13, dVexp 1e-17 or 1e-13), so the step it keeps is round-off too.
            figures = KKT_FIGURES if rc["stop"] >= 1e-9 else ("cost", "stop", "dV", "dVexp", "ffeas")
            for k in figures:
                assert rm[k] == pytest.approx(rc[k], rel=1e-6, abs=1e-9)


def test_kkt_system_same_as_crocoddyl():
    r = np.random.RandomState(4)
    xs, us = [r.randn(3) for _ in range(6)], [r.randn(2) for _ in range(5)]
    got = {}
    for lib in (crocoddyl, crocopy):
        m = lib.ActionModelUnicycle()
        s = lib.SolverKKT(lib.ShootingProblem(np.array([-1.0, -1.0, 1.0]), [m] * 5, m))
        s.setCandidate(xs, us, False)
        s.computeDirection(True)
        got[lib] = (np.array(s.kkt), np.array(s.kktref), np.array(s.primaldual), s.expectedImprovement().copy(),
                    s.stoppingCriteria())
    for a, b in zip(got[crocopy], got[crocoddyl]):
        np.testing.assert_allclose(a, b, rtol=1e-10, atol=1e-10)


def _unicycle(lib):
    m = lib.ActionModelUnicycle()
    return lib.ShootingProblem(np.array([-1.0, -1.0, 1.0]), [m] * 20, m)
