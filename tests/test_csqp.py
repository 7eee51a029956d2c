"""SolverCSQP (mim-solvers' API): closed-form equality-constrained LQ, box constraints against
Box-FDDP, Crocoddyl's equalities (nh > 0) equal to lb == ub rows, a terminal constraint present but
inactive, the ADMM's read-outs and the verbose/logger format."""

from __future__ import annotations

import contextlib
import io

import numpy as np
import pytest
from sqp_problems import LinearModel, random_lq

import crocopy
import crocopy.mim_solvers as mim_solvers


def _integrator(T: int, a: float, b: float, as_rows: bool) -> crocopy.ShootingProblem:
    """``x⁺ = x + u``, cost ``½ Σ u²``, ``x_T = b`` as a row ``b <= x_T <= b`` or as an equality ``x_T - b = 0``."""
    one, zero = np.ones((1, 1)), np.zeros((1, 1))
    run = LinearModel(one, one, np.zeros(1), zero, np.zeros(1), one)
    if as_rows:
        term = LinearModel(one, one, np.zeros(1), zero, np.zeros(1), one, rows=(one, zero, [b], [b]), terminal=True)
    else:
        term = LinearModel(one, one, np.zeros(1), zero, np.zeros(1), one, eqs=(one, zero, np.array([b])),
                           terminal=True)
    return crocopy.ShootingProblem(np.array([a]), [run] * T, term)


@pytest.mark.parametrize("as_rows", [True, False], ids=["lb==ub", "nh"])
def test_terminal_equality_closed_form(as_rows):
    T, a, b = 10, 0.0, 1.0
    solver = crocopy.SolverCSQP(_integrator(T, a, b, as_rows))
    solver.eps_abs, solver.eps_rel = 1e-8, 0.0
    assert solver.solve([], [], 50)
    np.testing.assert_allclose(np.array(solver.us)[:, 0], (b - a) / T, atol=1e-7)
    assert solver.cost == pytest.approx((b - a) ** 2 / (2 * T), rel=1e-6)
    assert solver.y[-1][0] == pytest.approx(-(b - a) / T, rel=1e-5)
    np.testing.assert_allclose(np.array(solver.lag_mul)[:, 0], -(b - a) / T, atol=1e-6)
    assert solver.rho_vec[-1][0] == pytest.approx(1e3 * solver.rho_sparse)
    assert solver.constraint_norm < 1e-7


def _box_lq(seed: int, bound: float):
    """A random LQ problem whose controls are bounded, written as rows (for CSQP) and as control limits
    (for Box-FDDP)."""
    nu = 2
    rows = lambda t: (np.zeros((nu, 3)), np.eye(nu), -bound * np.ones(nu), bound * np.ones(nu))  # noqa: E731
    with_rows = random_lq(seed, rows=rows)
    plain = random_lq(seed)
    for m in plain.runningModels:
        m.u_lb, m.u_ub = -bound * np.ones(nu), bound * np.ones(nu)
    return with_rows, plain


@pytest.mark.parametrize("seed", [0, 3])
def test_control_box_rows_match_box_fddp(seed):
    rows, box = _box_lq(seed, 0.3)
    csqp = crocopy.SolverCSQP(rows)
    csqp.eps_abs, csqp.eps_rel, csqp.max_qp_iters = 1e-9, 0.0, 20000
    csqp.termination_tolerance = 1e-8
    assert csqp.solve([], [], 50)
    fddp = crocopy.SolverBoxFDDP(box)
    fddp.th_stop = 1e-14
    fddp.solve([], [], 200)
    assert np.abs(np.array(csqp.us)).max() <= 0.3 + 1e-7
    assert np.abs(np.array(csqp.us)).max() >= 0.3 - 1e-6  # the bounds are active
    assert csqp.cost == pytest.approx(fddp.cost, rel=1e-7)
    np.testing.assert_allclose(np.array(csqp.us), np.array(fddp.us), atol=1e-5)
    for y, u in zip(csqp.y[:-1], csqp.us):  # y > 0 on an active upper bound, < 0 on an active lower one
        active = np.abs(np.abs(u) - 0.3) < 1e-6
        assert np.all(np.sign(y[active]) == np.sign(u[active]))
        assert np.all(np.abs(y[~active]) < 1e-6)


def test_unconstrained_csqp_equals_sqp():
    runs = []
    for cls in (crocopy.SolverSQP, crocopy.SolverCSQP):
        solver = cls(random_lq(5, T=12))
        rng = np.random.default_rng(0)
        solver.solve([rng.normal(size=3) for _ in range(13)], [rng.normal(size=2) for _ in range(12)], 10)
        runs.append((solver.iter, solver.cost))
    assert runs[0][0] == runs[1][0] == 1
    assert runs[0][1] == pytest.approx(runs[1][1], rel=1e-9)


def test_qp_iterations_are_multiples_of_the_interval():
    rows, _ = _box_lq(1, 0.3)
    solver = crocopy.SolverCSQP(rows)
    logger = mim_solvers.CallbackLogger()
    solver.setCallbacks([logger])
    solver.solve([], [], 30)
    qp = logger.convergence_data["qp_iter"]
    assert all(q >= 25 and q % 25 == 0 for q in qp)
    solver.max_qp_iters = 30
    solver.reset_y = True
    solver.solve([], [], 1)
    assert solver.qp_iters in (25.0, 31.0)


def test_defaults_and_readouts():
    solver = crocopy.SolverCSQP(_box_lq(0, 0.3)[0])
    expected = {"termination_tolerance": 1e-6, "use_filter_line_search": True, "filter_size": 1, "mu_dynamic": 10.0,
                "mu_constraint": 10.0, "lag_mul_inf_norm_coef": 10.0, "max_qp_iters": 1000, "eps_abs": 1e-4,
                "eps_rel": 1e-4, "sigma": 1e-6, "alpha": 1.6, "rho_sparse": 0.1, "rho_update_interval": 25,
                "adaptive_rho_tolerance": 5, "equality_qp_initial_guess": True, "reset_y": False,
                "reset_rho": False, "update_rho_with_heuristic": False, "remove_reg": False,
                "with_qp_callbacks": False, "max_solve_time": np.inf, "extra_iteration_for_last_kkt": False}
    for name, value in expected.items():
        assert getattr(solver, name) == value, name
    assert solver.solve()
    for name in ("KKT", "merit", "gap_norm", "constraint_norm", "qp_iters", "norm_primal", "norm_dual",
                 "norm_primal_rel", "norm_dual_rel"):
        assert np.isfinite(getattr(solver, name)), name
    assert len(solver.y) == len(solver.z) == len(solver.rho_vec) == solver.problem.T + 1
    assert [len(v) for v in solver.y] == [2] * 8 + [0]
    solver.rho_sparse = 0.5
    assert solver.rho_sparse == 0.5 and solver.rho_vec[0][0] == 0.5


def test_variants_converge():
    for setting in ({"update_rho_with_heuristic": True}, {"equality_qp_initial_guess": False},
                    {"reset_rho": True, "reset_y": True}, {"mu_dynamic": -1.0}, {"remove_reg": True},
                    {"use_filter_line_search": False, "mu_dynamic": 1e3, "mu_constraint": 1e3}):
        solver = crocopy.SolverCSQP(_box_lq(2, 0.3)[0])
        solver.eps_abs, solver.eps_rel = 1e-8, 0.0  # KKT stalls at the QP's accuracy (as in mim-solvers)
        solver.termination_tolerance = 1e-5
        for name, value in setting.items():
            setattr(solver, name, value)
        assert solver.solve([], [], 100), setting
        assert solver.constraint_norm < 1e-4


def test_step_length_is_the_step_taken():
    problem = random_lq(6)
    solver = crocopy.SolverCSQP(problem)
    logger = mim_solvers.CallbackLogger()
    solver.setCallbacks([logger])
    solver.alphas = [0.5, 0.25]
    solver.solve([], [], 3)
    assert solver.stepLength == 0.5  # mim-solvers 0.3.0 reports 1.0 whatever the step
    assert logger.convergence_data["step"][1:] == [0.5, 0.5]
    gaps = logger.convergence_data["gap_norm"]
    assert gaps[0] > 0 and gaps[1:] == pytest.approx([0.5 * g for g in gaps[:-1]], rel=1e-9)  # linear dynamics


def test_max_solve_time():
    solver = crocopy.SolverCSQP(_box_lq(0, 0.3)[0])
    solver.max_solve_time = 0.0
    assert not solver.solve([], [], 10)
    assert solver.max_solve_time_reached and "max_solve_time" in solver.reason


def test_verbose_and_logger_format():
    solver = mim_solvers.SolverCSQP(_box_lq(0, 0.3)[0])
    logger = mim_solvers.CallbackLogger()
    solver.setCallbacks([mim_solvers.CallbackVerbose(), logger])
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        assert solver.solve([], [], 50)
    lines = out.getvalue().splitlines()
    assert lines[0] == ("iter    merit      cost     ||gaps||   ||Constraint||   ||(dx,du)||    step     "
                        "KKT criteria   QP iters ")
    assert lines[1].split()[1] == "0.000e+00"  # the merit is computed after the callbacks
    assert lines[-1].split()[5:7] == ["----", "----"] and lines[-1].split()[-1] == "-----"
    assert list(logger.convergence_data) == ["us", "xs", "fs", "iter", "cost", "merit", "preg", "dreg", "step",
                                             "gap_norm", "constraint_norm", "qp_iter", "KKT"]


def _arm_with_terminal_inactive_constraint():
    """Kinova (T = 5) with a control box on every node, registered as not active on the terminal node."""
    from robots import load

    model = load("kinova")
    state = crocopy.StateMultibody(model)
    act = crocopy.ActuationModelFull(state)
    nu = act.nu

    def node(terminal):
        costs = crocopy.CostModelSum(state, nu)
        costs.addCost("x", crocopy.CostModelResidual(state, crocopy.ResidualModelState(state, state.zero(), nu)), 1.0)
        costs.addCost("u", crocopy.CostModelResidual(state, crocopy.ResidualModelControl(state, nu)), 1e-2)
        manager = crocopy.ConstraintModelManager(state, nu)
        res = crocopy.ResidualModelControl(state, nu)
        manager.addConstraint("u", crocopy.ConstraintModelResidual(state, res, -5 * np.ones(nu), 5 * np.ones(nu),
                                                                   T_constraint=False))
        dam = crocopy.DifferentialActionModelFreeFwdDynamics(state, act, costs, manager)
        return crocopy.IntegratedActionModelEuler(dam, 0.0 if terminal else 0.02)

    x0 = np.r_[model.referenceConfigurations["arm_up"], np.zeros(model.nv)]
    return crocopy.ShootingProblem(x0, [node(False) for _ in range(5)], node(True))


def test_terminal_constraint_present_but_inactive():
    problem = _arm_with_terminal_inactive_constraint()
    assert problem.terminalModel.ng == nu_ng(problem) and problem.terminalModel.ng_T == 0
    solver = crocopy.SolverCSQP(problem)
    solver.termination_tolerance = 1e-5
    assert len(solver.y[-1]) == 0
    assert solver.solve([], [], 50)
    assert np.abs(np.array(solver.us)).max() <= 5 + 1e-4


def nu_ng(problem) -> int:
    return problem.runningModels[0].ng


def _kinova_ubound(change):
    from crocopy.bench import mim

    problem = mim.build_problem(crocopy, "kinova_ubound")
    change(problem)
    return problem


def _solve_from_rest(solver):
    problem = solver.problem
    solver.solve([problem.x0] * (problem.T + 1), [np.zeros(m.nu) for m in problem.runningModels], 4)
    return solver.iter, solver.cost, np.concatenate(solver.us).tobytes()


def test_bounds_are_read_again_only_after_a_constraint_changed(monkeypatch):
    """Between two solves, an assignment elsewhere (every goal's reference) leaves the QP's bounds as they were read;
    ``updateBounds`` on one constraint has them read again.  Each solve equals that of a solver with the same history
    made to read its bounds before every solve."""
    from crocopy.solvers import csqp

    reads = []
    bounds = csqp._bounds
    monkeypatch.setattr(csqp, "_bounds", lambda model, terminal: reads.append(model) or bounds(model, terminal))

    def move_goals(problem):
        for m in [*problem.runningModels, problem.terminalModel]:
            goal = m.differential.costs.costs["goal"].cost.residual
            goal.reference = goal.reference + np.array([0.05, -0.05, 0.0])

    def tighten(problem):
        problem.runningModels[5].differential.constraints.constraints["u"].constraint.updateBounds(
            -np.full(6, 2.0), np.full(6, 2.0))

    solvers = [crocopy.SolverCSQP(_kinova_ubound(lambda p: None)) for _ in range(2)]
    outcomes = []
    for change in (None, move_goals, tighten):
        step = []
        for k, solver in enumerate(solvers):
            if change is not None:
                change(solver.problem)
            if k == 1:
                solver._bounds_seen = (-1, -1)  # read them again whatever changed
            reads.clear()
            step.append(_solve_from_rest(solver))
            step.append(len(reads))
        outcomes.append(step)
    T = solvers[0].problem.T
    assert [reads_kept for _, reads_kept, _, _ in outcomes[1:]] == [0, T + 1]
    assert all(kept == read for kept, _, read, _ in outcomes)
    assert outcomes[2][0][1] != outcomes[1][0][1]  # the tightened bound is active


def test_constraint_bounds_are_read_only():
    """A constraint's bounds change through ``updateBounds``/``removeBounds`` only (an in-place write would go
    unseen by a solver that read them)."""
    state = crocopy.StateVector(2)
    constraint = crocopy.ConstraintModelResidual(state, crocopy.ResidualModelControl(state, 2), -np.ones(2),
                                                 np.ones(2))
    for bound in (constraint.lb, constraint.ub):
        with pytest.raises(ValueError, match="read-only"):
            bound[0] = 0.5
    constraint.updateBounds(-np.full(2, 3.0), np.full(2, 3.0))
    assert constraint.lb.tolist() == [-3.0, -3.0] and not constraint.ub.flags.writeable


def _rows_and_equalities() -> crocopy.ShootingProblem:
    """Random LQ whose states and controls are boxed, with a terminal equality given as ``nh`` rows."""
    rows = lambda t: (np.r_[np.eye(3)[:1] * (t > 0), np.zeros((1, 3))], np.r_[np.zeros((1, 2)), np.eye(2)[:1]],  # noqa: E731
                      np.array([-0.2, -0.3]), np.array([0.2, 0.3]))
    return random_lq(4, T=8, rows=rows, terminal_eqs=(np.eye(3)[:2], np.zeros((2, 2)), np.array([0.1, -0.2])))


class _Recorder(crocopy.CallbackAbstract):
    def __init__(self) -> None:
        super().__init__()
        self.seen = []

    def __call__(self, solver) -> None:
        self.seen.append((solver.gfeas, solver.hfeas, solver.constraint_norm, solver.cost))


class _OwnCalcDiff(crocopy.SolverCSQP):
    calls = 0

    def calcDiff(self):
        type(self).calls += 1
        return super().calcDiff()


def test_calc_gives_the_constraint_norms_of_calc_diff():
    # SolverCSQP.calc differentiates the nodes without calcDiff's own constraint norms (its QP rows give gfeas);
    # a subclass's calcDiff is still the one called, and both give the same norms at every iteration
    runs = []
    for cls in (crocopy.SolverCSQP, _OwnCalcDiff):
        solver = cls(_rows_and_equalities())
        recorder = _Recorder()
        solver.setCallbacks([recorder])
        solver.solve([], [], 20)
        runs.append((solver, recorder.seen))
    (plain, seen), (own, seen_own) = runs
    assert _OwnCalcDiff.calls >= own.iter > 0
    assert plain.iter == own.iter and seen == seen_own
    assert any(h > 0.0 for _, h, _, _ in seen) and any(g > 0.0 for g, _, _, _ in seen)
