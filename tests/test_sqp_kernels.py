"""The compiled SQP/CSQP paths (:mod:`crocopy.solvers.csqp_kernel`, :mod:`crocopy.solvers.sqp_kernel`) against
their numpy twins: kernels on or off give the same iterations, cost (1e-9), KKT and QP read-outs, on free and
constrained problems, with the ADMM's variants; one compiled call per QP against one call per iteration
(time limit, QP print-out); rebound or unreadable constraint arrays; pickled solvers."""

from __future__ import annotations

import contextlib
import io
import pickle

import numpy as np
import pytest
from sqp_problems import LinearModel, random_lq

import crocopy


def _unicycle() -> crocopy.ShootingProblem:
    m = crocopy.ActionModelUnicycle()
    return crocopy.ShootingProblem(np.array([-1.0, -1.0, 1.0]), [m] * 20, m)


def _boxed(seed: int = 2) -> crocopy.ShootingProblem:
    """Random LQ whose first state (after ``x0``) and both controls are boxed, with a terminal equality (``nh``)."""
    rows = lambda t: (np.r_[np.eye(3)[:1] * (t > 0), np.zeros((2, 3))], np.r_[np.zeros((1, 2)), np.eye(2)],  # noqa: E731
                      np.array([-0.3, -0.4, -np.inf]), np.array([0.3, 0.4, 0.5]))
    return random_lq(seed, T=10, rows=rows, terminal_eqs=(np.eye(3)[:2], np.zeros((2, 2)), np.array([0.1, -0.2])))


def _solve(build, cls, kernels: bool, settings: dict | None = None, maxiter: int = 100):
    with crocopy.use_kernels(kernels):
        solver = cls(build())
        for name, value in (settings or {}).items():
            setattr(solver, name, value)
        out = io.StringIO()
        with contextlib.redirect_stdout(out):
            converged = solver.solve([], [], maxiter)
        return solver, converged, out.getvalue()


def _assert_same(a, b, xs_atol: float = 1e-10) -> None:
    (sa, ca, _), (sb, cb, _) = a, b
    assert ca == cb and sa.iter == sb.iter
    assert sa.cost == pytest.approx(sb.cost, rel=1e-9)
    assert sa.KKT == pytest.approx(sb.KKT, rel=1e-6, abs=1e-12)
    assert sa.gap_norm == pytest.approx(sb.gap_norm, rel=1e-6, abs=1e-12)
    for x, y in zip(sa.xs, sb.xs):
        np.testing.assert_allclose(x, y, rtol=1e-8, atol=xs_atol)
    for x, y in zip(sa.lag_mul, sb.lag_mul):
        np.testing.assert_allclose(x, y, rtol=1e-6, atol=1e-9)


@pytest.mark.parametrize("cls", [crocopy.SolverSQP, crocopy.SolverCSQP])
def test_free_problem_kernels_on_or_off(cls):
    # Gauss-Newton converges linearly here; from a KKT of ~1e-8 on, the filter compares costs equal to the last
    # bit (round-off picks the step), so stop before that
    runs = [_solve(_unicycle, cls, k, {"termination_tolerance": 1e-7}) for k in (True, False)]
    assert runs[0][1]
    _assert_same(*runs)


VARIANTS = [{}, {"update_rho_with_heuristic": True}, {"rho_update_interval": 1}, {"equality_qp_initial_guess": False},
            {"reset_rho": True, "reset_y": True}, {"mu_dynamic": -1.0}, {"rho_sparse": 1.0}]


@pytest.mark.parametrize("settings", VARIANTS, ids=lambda s: ",".join(s) or "defaults")
def test_constrained_problem_kernels_on_or_off(settings):
    # an accurate QP: with eps_abs = 1e-4 the KKT measure stalls above the tolerance and the line search ends
    # the solve on round-off (as in mim-solvers)
    settings = {"termination_tolerance": 1e-5, "eps_abs": 1e-8, "eps_rel": 0.0, **settings}
    runs = [_solve(_boxed, crocopy.SolverCSQP, k, settings) for k in (True, False)]
    assert runs[0][1], runs[0][0].reason
    _assert_same(*runs)
    (on, _, _), (off, _, _) = runs
    assert on.qp_iters == off.qp_iters > 0
    assert on.constraint_norm == pytest.approx(off.constraint_norm, rel=1e-6, abs=1e-12)
    assert on.gfeas == pytest.approx(off.gfeas, rel=1e-6, abs=1e-12)
    assert on.rho_sparse == pytest.approx(off.rho_sparse, rel=1e-9)
    for a, b in zip(on.y, off.y):
        np.testing.assert_allclose(a, b, rtol=1e-6, atol=1e-9)
    assert max(np.abs(y).max(initial=0.0) for y in on.y) > 1e-3  # some rows are active


def test_nonlinear_constrained_problem_kernels_on_or_off():
    pytest.importorskip("pinocchio")
    from crocopy.bench.mim import build_problem

    def build():
        return build_problem(crocopy, "ur5_ee_eq")

    runs = [_solve(build, crocopy.SolverCSQP, k, {"termination_tolerance": 1e-6}, 50) for k in (True, False)]
    assert runs[0][1]
    _assert_same(*runs)
    assert runs[0][0].qp_iters == runs[1][0].qp_iters


def test_one_call_per_qp_or_per_iteration():
    """A time limit or the QP print-out runs the compiled ADMM one iteration per call: same answer, and the print-out
    is the numpy twin's."""
    one = _solve(_boxed, crocopy.SolverCSQP, True)
    stepwise = _solve(_boxed, crocopy.SolverCSQP, True, {"max_solve_time": 1e6})
    _assert_same(one, stepwise)
    assert one[0].qp_iters == stepwise[0].qp_iters
    printed = [_solve(_boxed, crocopy.SolverCSQP, k, {"with_qp_callbacks": True}, 3)[2] for k in (True, False)]
    assert printed[0].count("QP iter") == printed[1].count("QP iter") > 0
    assert [line.split()[2] for line in printed[0].splitlines() if "QP iter" in line] == [
        line.split()[2] for line in printed[1].splitlines() if "QP iter" in line]


class _FortranGxData(crocopy.ActionDataAbstract):
    """A data class keeping ``Gx`` in Fortran order behind a property of its own (the kernel cannot read it in
    place)."""

    @property
    def Gx(self) -> np.ndarray:
        return self._gx

    @Gx.setter
    def Gx(self, value) -> None:
        self._gx = np.asfortranarray(value, dtype=float)


class _FortranGxModel(LinearModel):
    def createData(self):
        return _FortranGxData(self)


def test_unreadable_constraint_arrays_take_the_numpy_twin():
    """Rows whose ``Gx`` a kernel cannot read in place are read by the numpy twin: the same solve."""
    results = []
    for model_class in (LinearModel, _FortranGxModel):
        boxed = _boxed()
        problem = crocopy.ShootingProblem(boxed.x0, [_as(model_class, m) for m in boxed.runningModels],
                                          boxed.terminalModel)
        solver = crocopy.SolverCSQP(problem)
        solver.eps_abs, solver.eps_rel, solver.termination_tolerance = 1e-8, 0.0, 1e-5
        assert solver.solve([], [], 100)
        assert (solver._row_addresses() is None) == (model_class is _FortranGxModel)
        results.append((solver.iter, solver.cost))
    assert results[1][0] == results[0][0]
    assert results[1][1] == pytest.approx(results[0][1], rel=1e-12)


def _as(cls, m: LinearModel) -> LinearModel:
    return cls(m.A, m.B, m.c, m.Q, m.q, m.R, m.rows, m.eqs, m.terminal)


@pytest.mark.parametrize("cls", [crocopy.SolverSQP, crocopy.SolverCSQP])
def test_pickled_solver_keeps_its_stacks(cls):
    solver = cls(_boxed())
    solver.solve([], [], 2)
    copy = pickle.loads(pickle.dumps(solver))
    for s in (solver, copy):
        s.solve([], [], 100)
    assert copy.iter == solver.iter and copy.cost == pytest.approx(solver.cost, rel=1e-12)
    for a, b in zip(copy.dx, solver.dx):
        np.testing.assert_array_equal(a, b)
    copy.dx[1][0] = 123.0
    assert copy._steps[0][1, 0] == 123.0  # the read-outs are still views of the stacks the kernels write


def _ur5_terminal_equality() -> crocopy.ShootingProblem:
    """UR5 reaching a point held by a terminal equality; the running nodes have no constraint manager."""
    from crocopy.problems.common import load_model

    model = load_model("ur5")
    x0 = np.r_[0.0, -1.0, 1.5, -0.5, 1.0, 0.0, np.zeros(6)]
    state = crocopy.StateMultibody(model)
    actuation = crocopy.ActuationModelFull(state)
    target = np.array([0.4, 0.2, 0.5])

    def node(terminal: bool):
        costs = crocopy.CostModelSum(state, 6)
        costs.addCost("x", crocopy.CostModelResidual(state, crocopy.ResidualModelState(state, x0, 6)), 0.1)
        manager = None
        if terminal:
            manager = crocopy.ConstraintModelManager(state, 6)
            ee = crocopy.ResidualModelFrameTranslation(state, model.getFrameId("tool0"), target, 6)
            manager.addConstraint("ee", crocopy.ConstraintModelResidual(state, ee, np.zeros(3), np.zeros(3)))
        else:
            costs.addCost("u", crocopy.CostModelResidual(state, crocopy.ResidualModelControl(state, 6)), 1e-3)
        dam = crocopy.DifferentialActionModelFreeFwdDynamics(state, actuation, costs, manager)
        return crocopy.IntegratedActionModelEuler(dam, 0.0 if terminal else 0.02)

    return crocopy.ShootingProblem(x0, [node(False) for _ in range(20)], node(True))


def test_csqp_with_compiled_nodes():
    """Nodes without constraints run compiled inside CSQP (the node with rows keeps its Python path)."""
    pytest.importorskip("pinocchio")
    from crocopy.solvers import compiled_nodes

    runs = []
    for enabled in (True, False):
        solver, converged, _ = _solve(_ur5_terminal_equality, crocopy.SolverCSQP, enabled)
        with crocopy.use_kernels(enabled):
            assert (compiled_nodes.select(solver) is not None) == enabled
        assert converged and solver.constraint_norm < 1e-8
        runs.append((solver, converged, ""))
    _assert_same(*runs)


def _quadrotor(python_nodes: tuple = (), nthreads: int = 1):
    """quad-goal with ``python_nodes`` on the Python path (a subclass of the integrator), on ``nthreads``."""
    from crocopy.problems import registry

    problem, xs, us = registry.build("quad-goal")
    models = list(problem.runningModels)

    class Euler(crocopy.IntegratedActionModelEuler):
        pass

    for t in python_nodes:
        models[t] = Euler(models[t].differential, models[t].dt)
    problem = crocopy.ShootingProblem(problem.x0, models, problem.terminalModel)
    problem.nthreads = nthreads
    return problem, xs, us


def _user_reach():
    """A Kinova reach whose nodes have a Python residual (compiled nodes run it in Python around their call)."""
    from crocopy.problems.user_residual import build_user_reach

    return build_user_reach(crocopy, "python", robot="kinova", nodes=12)


TRIALS = {"ranges": (lambda: _quadrotor((3, 17)), {0: 3, 4: 17, 18: 50}),
          "first node in Python": (lambda: _quadrotor((0, 9)), {1: 9, 10: 50}),
          "threads": (lambda: _quadrotor((5,), nthreads=2), {0: 5, 6: 50}),
          "Python residuals": (_user_reach, {0: 12})}


@pytest.mark.parametrize("case", TRIALS)
def test_sqp_trial_over_compiled_ranges_equals_the_node_loop(case):
    """SQP's trial point (``x ⊕ α δx``, the nodes, the gaps) over compiled ranges equals the node loop's."""
    pytest.importorskip("pinocchio")
    from crocopy.solvers import compiled_nodes

    build, segments = TRIALS[case]
    problem, xs, us = build()
    solver = crocopy.SolverSQP(problem)
    state = problem.runningModels[0].state
    solver.setCandidate([state.integrate(xs[0], np.full(state.ndx, 0.01)), *xs[1:]], us, False)  # a gap at node 0
    nodes = compiled_nodes.attach(solver)
    assert nodes.segments == segments
    solver.computeDirection()
    assert max(np.abs(d).max() for d in solver.dx) > 1e-3  # a step that moves every part of the trial
    for alpha in (1.0, 0.25):
        solver._nodes = nodes
        merit = solver.tryStep(alpha)
        fast = [[v.copy() for v in vs] for vs in (solver.xs_try, solver.us_try, solver.fs_try)]
        fast_norms = solver.cost_try, solver.gap_norm_try
        solver._nodes = None
        assert solver.tryStep(alpha) == pytest.approx(merit, rel=1e-9)
        assert fast_norms == pytest.approx((solver.cost_try, solver.gap_norm_try), rel=1e-9)
        for a_list, b_list in zip(fast, (solver.xs_try, solver.us_try, solver.fs_try)):
            for a, b in zip(a_list, b_list):
                np.testing.assert_allclose(a, b, rtol=1e-9, atol=1e-11)


@pytest.mark.parametrize("name", ["SolverCSQP", "SolverFDDP", "SolverBoxFDDP"])
@pytest.mark.parametrize("kernels", [True, False], ids=["kernels", "python"])
def test_solver_prepares_its_compiled_nodes_when_made(kernels, name):
    """The node tables and the addresses the kernels read are made with the solver (with kernels on; every solver of
    the DDP family, as Crocoddyl's allocate their workspace), and the solve uses those evaluators."""
    pytest.importorskip("pinocchio")
    from crocopy.models.rbd import euler_node
    from crocopy.solvers import compiled_nodes

    problem = _ur5_terminal_equality()
    datas = problem.runningDatas
    assert all(euler_node._NODES.get(d) is None for d in datas)
    with crocopy.use_kernels(kernels):
        solver = getattr(crocopy, name)(problem)
        made = [euler_node._NODES.get(d) for d in datas]
        assert all(node is not None for node in made) == kernels and (kernels or not any(made))
        assert (solver._trajectory_addresses is not None) == kernels
        assert solver._derivatives.addr.shape[0] == (problem.T if kernels else 0)
        if kernels:
            assert [calc.__self__ for calc in compiled_nodes.select(solver).calcs[:-1]] == made
        if name == "SolverCSQP":
            assert solver.solve([], [], 50) and solver.constraint_norm < 1e-8
        else:  # the terminal equality is not theirs to meet: a finite solve on the same evaluators
            solver.solve([], [], 5)
            assert np.isfinite(solver.cost)
            if kernels:
                assert [calc.__self__ for calc in compiled_nodes.select(solver).calcs[:-1]] == made


@pytest.mark.parametrize("interval", [1, 3])
def test_admm_skips_a_refactorisation_only_when_rho_is_unchanged(interval):
    """The compiled ADMM refactorises on schedule only when ``ρ̄`` changed since the last factorisation: its iterates
    equal, to the last bit, those of the schedule run one iteration per call with every factorisation made."""
    solver = crocopy.SolverCSQP(_boxed())
    solver.eps_abs, solver.eps_rel, solver.rho_update_interval, solver.max_qp_iters = 1e-10, 0.0, interval, 60
    solver.solve([], [], 1)  # a QP at the initial point
    solver.calc(True)
    qp = solver._qp
    start = {name: getattr(qp, name).copy() for name in ("y", "z", "rho")}
    args = (solver._derivative_addresses(), solver._horizon.addr, solver.problem.terminalData, solver, 1e-6)
    runs = []
    for per_call in (False, True):
        for name, value in start.items():
            getattr(qp, name)[...] = value
        qp.rho_bar, qp.factorised = 0.1, False
        qp.run(*args, 1, 1, True)
        done = 0
        if per_call:
            for j in range(1, 61):
                qp.factorised = False  # every scheduled factorisation made
                done = qp.run(*args, j, j + 1, False)
                if done:
                    break
        else:
            done = qp.run(*args, 1, 61, False)
        runs.append((done, qp.rho_bar, *(a.copy() for a in (qp.y, qp.z, qp.rho, qp.dx_s, qp.du_s, qp.P_s, qp.K_s))))
    assert runs[0][1] != 0.1  # ρ̄ moved at least once
    assert runs[0][0] == runs[1][0] and runs[0][1] == runs[1][1]
    for a, b in zip(runs[0][2:], runs[1][2:]):
        np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("where", ["state", "control"])
@pytest.mark.parametrize("value", [np.nan, np.inf, -np.inf])
def test_a_non_finite_trial_is_seen_with_kernels_on_or_off(where, value):
    """The line search's check of a trial's states and controls (compiled, by address; numpy twin)."""
    for enabled in (True, False):
        with crocopy.use_kernels(enabled):
            solver = crocopy.SolverSQP(_unicycle())
            assert solver._trial_finite()
            (solver.xs_try[7] if where == "state" else solver.us_try[19])[1] = value
            assert not solver._trial_finite()


def test_sqp_on_a_gait_kernels_on_or_off():
    """SQP over contact nodes (compiled ranges) and impulse nodes (their own compiled calls, between the ranges)."""
    pytest.importorskip("pinocchio")
    from crocopy.problems import quadruped
    from crocopy.solvers import compiled_nodes

    runs = []
    for enabled in (True, False):
        with crocopy.use_kernels(enabled):
            problem, xs, us = quadruped.build_gait(crocopy, "walk", step_knots=2, support_knots=1, cycles=1)
            solver = crocopy.SolverSQP(problem)
            if enabled:
                assert compiled_nodes.select(solver).segments == {0: 3, 4: 7, 8: 11, 12: 15, 16: 17}
            converged = solver.solve(xs, us, 8)
            runs.append((solver, converged, ""))
    _assert_same(*runs, xs_atol=1e-9)  # contact dynamics: 4e-10 apart on an AMD EPYC (the host CPU's FMAs)


def test_row_spans_cover_every_nonzero_entry():
    """The ADMM's products run over each row's span of nonzero entries: first to last nonzero, ``(0, 0)`` for a zero
    row, no ``D`` span on the terminal node."""
    from crocopy.solvers.csqp_kernel import row_spans

    dims = np.array([[4, 3, 3], [4, 3, 2], [4, 0, 1]], dtype=np.int64)
    C, D = np.zeros((3, 3, 4)), np.zeros((3, 3, 3))
    C[0, 0, 1], C[0, 0, 2], C[0, 1, 3], D[0, 1, 0], D[0, 2, 2] = 1.0, -2.0, 3.0, 4.0, 5.0
    C[1, 1, 0], C[1, 1, 3], D[1, 0, 1] = 1.0, 1.0, -1.0
    C[2, 0, 0], D[2, 0, 1] = 2.0, 9.0  # D of the terminal node is never read
    spans = np.full((3, 3, 4), -1, dtype=np.int64)
    row_spans(dims, C, D, spans)
    assert spans[0, :3].tolist() == [[1, 3, 0, 0], [3, 4, 0, 1], [0, 0, 2, 3]]
    assert spans[1, :2].tolist() == [[0, 0, 1, 2], [0, 4, 0, 0]]
    assert spans[2, 0].tolist() == [0, 1, 0, 0]


@pytest.mark.parametrize("bad", [None, np.inf, -np.inf, np.nan], ids=["finite", "inf", "-inf", "nan"])
def test_ffeas_infinity_norm_compiled_equals_numpy(bad):
    """The DDP family's ``ffeas`` (∞-norm of the gaps): one compiled call on the horizon buffer with kernels on, numpy's
    ``max`` of the stacked gaps with them off, NaN/inf included."""
    solver = crocopy.SolverFDDP(_unicycle())
    rng = np.random.default_rng(3)
    for f in solver.fs:
        f[:] = rng.normal(size=f.shape)
    if bad is not None:
        solver.fs[4][1] = bad
    expected = float(np.abs(np.concatenate(solver.fs)).max())
    with crocopy.use_kernels(True):
        compiled = solver._gaps_norm()
    with crocopy.use_kernels(False):
        plain = solver._gaps_norm()
    assert compiled == plain == expected or (np.isnan(expected) and np.isnan(compiled) and np.isnan(plain))
