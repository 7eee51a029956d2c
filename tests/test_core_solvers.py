"""DDP/FDDP: LQR in one iteration against an independent Riccati solution, gaps, agreement, errors."""

import contextlib
import io

import numpy as np
import pytest

import crocopy


def _lqr_problem(nx=6, nu=3, T=20, seed=0):
    rng = np.random.default_rng(seed)
    A = np.eye(nx) + 0.1 * rng.standard_normal((nx, nx))
    B = rng.standard_normal((nx, nu))
    Q = np.diag(rng.uniform(0.5, 2.0, nx))
    R = np.diag(rng.uniform(0.5, 2.0, nu))
    N = 0.05 * rng.standard_normal((nx, nu))
    f, q, r = 0.1 * rng.standard_normal(nx), rng.standard_normal(nx), rng.standard_normal(nu)
    model = crocopy.ActionModelLQR(A, B, Q, R, N, f, q, r)
    x0 = rng.standard_normal(nx)
    return crocopy.ShootingProblem(x0, [model] * T, model), (A, B, Q, R, N, f, q, r, x0)


def _riccati(A, B, Q, R, N, f, q, r, x0, T):
    """Independent affine-LQR solution by backward Riccati recursion on V(x) = ½xᵀPx + pᵀx."""
    P, p = Q.copy(), q.copy()
    gains = []
    for _ in range(T):
        H = R + B.T @ P @ B
        G = N.T + B.T @ P @ A
        h = r + B.T @ (P @ f + p)
        K = -np.linalg.solve(H, G)
        k = -np.linalg.solve(H, h)
        gains.append((K, k))
        P_new = Q + A.T @ P @ A + G.T @ K
        p = q + A.T @ (P @ f + p) + G.T @ k
        P = 0.5 * (P_new + P_new.T)
    gains.reverse()
    xs, us = [x0], []
    for K, k in gains:
        us.append(K @ xs[-1] + k)
        xs.append(A @ xs[-1] + B @ us[-1] + f)
    return xs, us


@pytest.mark.parametrize("solver_cls", [crocopy.SolverDDP, crocopy.SolverFDDP])
def test_lqr_converges_in_one_iteration_to_riccati_solution(solver_cls):
    problem, args = _lqr_problem()
    xs_ref, us_ref = _riccati(*args, problem.T)
    solver = solver_cls(problem)
    logger = crocopy.CallbackLogger()
    solver.setCallbacks([logger])
    assert solver.solve([problem.x0] * (problem.T + 1), [np.zeros(3)] * problem.T, 10, False)
    np.testing.assert_allclose(np.array(solver.us), np.array(us_ref), atol=1e-9)
    np.testing.assert_allclose(np.array(solver.xs), np.array(xs_ref), atol=1e-9)
    assert logger.iters[0] == 0 and logger.steps[0] == 1.0
    assert solver.stop < 1e-12 and len(logger.iters) <= 2


def test_fddp_closes_gaps_from_infeasible_warm_start():
    problem, _ = _lqr_problem()
    rng = np.random.default_rng(5)
    xs0 = [rng.standard_normal(6) for _ in range(problem.T + 1)]
    solver = crocopy.SolverFDDP(problem)
    logger = crocopy.CallbackLogger()
    solver.setCallbacks([logger])
    assert solver.solve(xs0, [np.zeros(3)] * problem.T)
    assert logger.ffeass[0] > 0.1
    assert solver.isFeasible
    rolled = problem.rollout(solver.us)
    np.testing.assert_allclose(np.array(rolled), np.array(solver.xs), atol=1e-10)


def _unicycle(T=30):
    m = crocopy.ActionModelUnicycle()
    return crocopy.ShootingProblem(np.array([-1.0, -1.0, 1.0]), [m] * T, m)


def test_ddp_and_fddp_agree_on_unicycle():
    sols = []
    for cls in (crocopy.SolverDDP, crocopy.SolverFDDP):
        s = cls(_unicycle())
        assert s.solve()
        sols.append(s)
    np.testing.assert_allclose(np.array(sols[0].xs), np.array(sols[1].xs), atol=1e-6)
    assert sols[0].cost == pytest.approx(sols[1].cost, rel=1e-9)


def test_solve_is_deterministic():
    runs = []
    for _ in range(2):
        s = crocopy.SolverFDDP(_unicycle())
        s.solve([np.array([0.1, 0.2, 0.3])] * 31, [np.array([0.5, 0.1])] * 30, 50)
        runs.append((s.iter, s.cost, np.array(s.us)))
    assert runs[0][0] == runs[1][0] and runs[0][1] == runs[1][1]
    np.testing.assert_array_equal(runs[0][2], runs[1][2])


def test_verbose_table_format():
    s = crocopy.SolverFDDP(_unicycle())
    s.setCallbacks([crocopy.CallbackVerbose()])
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        s.solve([np.array([0.1, 0.2, 0.3])] * 31, [np.array([0.5, 0.1])] * 30, 12, False)
    lines = buf.getvalue().splitlines()
    header = (
        "iter    cost       merit      stop      |grad|      preg       dreg      step   ||ffeas||  ||gfeas||"
        "  ||hfeas||   dV-exp       dV      dPhi-exp     dPhi"
    )
    assert lines[0] == header
    assert lines[0] == crocopy.CallbackVerbose().header()
    rows = [line for line in lines if not line.startswith("iter")]
    assert len(rows) == s.iter + 1
    assert lines.count(header) == (len(rows) + 9) // 10
    assert rows[0].startswith("   0  2.864e+02  0.000e+00")
    assert all(len(r.split()) == 15 for r in rows)
    lvl0 = crocopy.CallbackVerbose(crocopy.VerboseLevel._0, 6)
    expected = "iter      cost          stop         |grad|         preg       step      dV-exp          dV"
    assert lvl0.header() == expected


def test_bad_inputs_raise_value_errors():
    problem = _unicycle(5)
    s = crocopy.SolverDDP(problem)
    with pytest.raises(ValueError, match=r"init_xs has 3 items, expected T \+ 1 = 6"):
        s.solve([np.zeros(3)] * 3, [np.zeros(2)] * 5)
    with pytest.raises(ValueError, match=r"init_us\[2\] has shape \(3,\), expected \(2,\)"):
        s.solve([np.zeros(3)] * 6, [np.zeros(2)] * 2 + [np.zeros(3)] + [np.zeros(2)] * 2)
    with pytest.raises(ValueError, match=r"init_xs\[1\] contains NaN"):
        s.solve([np.zeros(3), np.full(3, np.nan)] + [np.zeros(3)] * 4, [np.zeros(2)] * 5)
    with pytest.raises(ValueError, match=r"x0 has shape \(2,\), expected \(3,\)"):
        crocopy.ShootingProblem(np.zeros(2), [crocopy.ActionModelUnicycle()], crocopy.ActionModelUnicycle())
    with pytest.raises(ValueError, match="x0 contains NaN"):
        problem.x0 = np.array([0.0, np.nan, 0.0])
    with pytest.raises(ValueError, match="node 0 has state"):
        crocopy.ShootingProblem(np.zeros(3), [crocopy.ActionModelUnicycle()], crocopy.ActionModelLQR(4, 2))
    m = crocopy.ActionModelUnicycle()
    m.u_lb = np.array([0.0, 2.0])  # the pair is checked at use: its setters may come in any order
    m.u_ub = np.array([1.0, 1.0])
    with pytest.raises(ValueError, match=r"u_lb\[1\] = 2.0 is above runningModels\[0\].u_ub\[1\]"):
        crocopy.SolverFDDP(crocopy.ShootingProblem(np.zeros(3), [m], m)).solve()
    with pytest.raises(ValueError, match="u_lb contains NaN"):
        m.u_lb = np.array([np.nan, 0.0])


class _Exploding(crocopy.ActionModelUnicycle):
    """Unicycle whose cost becomes NaN for large controls: the line search must reject those steps."""

    def calc(self, data, x, u=None):
        super().calc(data, x, u)
        if u is not None and np.abs(u).max() > 0.05:
            data.cost = np.nan


def test_divergence_returns_false_keeps_last_good_iterate():
    m = _Exploding()
    problem = crocopy.ShootingProblem(np.array([-1.0, -1.0, 1.0]), [m] * 10, crocopy.ActionModelUnicycle())
    s = crocopy.SolverFDDP(problem)
    us0 = [np.zeros(2)] * 10
    ok = s.solve(problem.rollout(us0), us0, 100, True)
    assert not ok
    assert s.reason
    assert all(np.isfinite(x).all() for x in s.xs) and all(np.isfinite(u).all() for u in s.us)
    assert np.isfinite(s.cost)
    assert max(np.abs(u).max() for u in s.us) <= 0.05


def test_problem_api_rollout_quasistatic_circular_append():
    problem = _unicycle(4)
    us = [np.array([1.0, 0.5])] * 4
    xs = problem.rollout(us)
    assert len(xs) == 5 and problem.calc(xs, us) > 0
    assert problem.calcDiff(xs, us) == pytest.approx(problem.calc(xs, us))
    lqr = crocopy.ActionModelLQR(3, 3)
    p2 = crocopy.ShootingProblem(np.zeros(3), [lqr] * 3, lqr)
    uqs = p2.quasiStatic([np.array([1.0, 2.0, 3.0])] * 4)
    d = lqr.createData()
    lqr.calc(d, np.array([1.0, 2.0, 3.0]), uqs[0])
    np.testing.assert_allclose(d.xnext, [1.0, 2.0, 3.0], atol=1e-9)
    new = crocopy.ActionModelUnicycle()
    problem.circularAppend(new)
    assert problem.runningModels[-1] is new and problem.T == 4
    with pytest.raises(ValueError, match="node index"):
        problem.updateModel(9, new)


@pytest.mark.parametrize("feasible", [True, False])
def test_compiled_riccati_kernel_equals_numpy_path(feasible):
    assert crocopy.kernels.available
    problem, _ = _lqr_problem(nx=8, nu=3, T=15, seed=3)
    rng = np.random.default_rng(1)
    xs = [rng.standard_normal(8) for _ in range(16)]
    us = [rng.standard_normal(3) for _ in range(15)]
    results = []
    for use_kernel in (True, False):
        s = crocopy.SolverFDDP(problem)
        s.setCandidate(xs, us, feasible)
        s.preg = s.dreg = 1e-3
        with crocopy.use_kernels(use_kernel):
            s.computeDirection(True)
        results.append((np.array(s.K), np.array(s.k), np.array(s.Vxx), np.array(s.Vx), np.array(s.Quu)))
    for a, b in zip(*results):
        np.testing.assert_allclose(a, b, atol=1e-10, rtol=1e-10)


def test_compiled_feedback_control_equals_numpy_twin_and_clamps():
    kernel = crocopy.solvers.riccati_kernel
    rng = np.random.default_rng(4)
    u, k, K, dx = rng.standard_normal(5), rng.standard_normal(5), rng.standard_normal((5, 7)), rng.standard_normal(7)
    lb, ub = np.full(5, -0.5), np.full(5, 0.5)
    free = u - 0.3 * k - K @ dx
    for bounds in ((np.full(5, -np.inf), np.full(5, np.inf)), (lb, ub)):
        outs = [np.full(5, np.nan), np.full(5, np.nan)]
        kernel.feedback_control(u, k, K, dx, 0.3, *bounds, outs[0])
        kernel.feedback_control_numpy(u, k, K, dx, 0.3, *bounds, outs[1])
        np.testing.assert_allclose(outs[0], outs[1], rtol=1e-14, atol=1e-15)
        np.testing.assert_allclose(outs[0], np.clip(free, *bounds), rtol=1e-14, atol=1e-15)
    assert np.any(np.abs(free) > 0.5)


@pytest.mark.parametrize("gaps", [False, True])
@pytest.mark.parametrize("preg", [0.0, 1e-3])
def test_compiled_terminal_value_equals_numpy_twin(gaps, preg):
    """``V_T = (Lxx + preg I, Lx (+ Vxx f))`` on strided views, as the solvers' buffers hold them."""
    kernel = crocopy.solvers.riccati_kernel
    rng = np.random.default_rng(5)
    Lxx, Lx, f = rng.standard_normal((6, 6)), rng.standard_normal(6), rng.standard_normal(6)
    outs = []
    for value in (kernel.terminal_value, kernel.terminal_value_numpy):
        Vxx, Vx = np.full((2, 8, 8), np.nan), np.full((2, 8), np.nan)
        value(Lxx, Lx, preg, f, gaps, Vxx[1, :6, :6], Vx[1, :6])
        outs.append((Vxx[1, :6, :6], Vx[1, :6]))
    for a, b in zip(*outs):
        np.testing.assert_allclose(a, b, rtol=1e-14, atol=1e-14)
    want = Lxx + preg * np.eye(6)
    np.testing.assert_array_equal(outs[0][0], want)
    np.testing.assert_allclose(outs[0][1], Lx + (want @ f if gaps else 0.0), rtol=1e-14, atol=1e-14)


def test_fddp_rejects_blown_up_trials_on_double_pendulum():
    """A diverging trial (huge finite cost, very negative gap term in d₀) must not pass the |d₀| < th_grad test.

    Reference: Crocoddyl 3.2.1 on the same problem converges in 110 iterations to 0.111367.
    """
    from crocopy.problems import registry

    problem, xs, us = registry.build("pend")
    solver = crocopy.SolverFDDP(problem)
    assert solver.solve(xs, us, 200, False), solver.reason
    assert solver.iter == 110
    assert solver.cost == pytest.approx(0.111367, rel=1e-5)
