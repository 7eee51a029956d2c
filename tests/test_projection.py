"""Projection (equality-constrained) DDP: LQ recursion vs KKT, solver behaviour, error detection."""

from __future__ import annotations

import numpy as np
import pytest

import crocopy
from crocopy import SolverProjection
from crocopy.solvers.projection_lq import ConstraintRankError, linear_rollout_model_change, projected_backward_pass


def _psd(rng, n):
    A = rng.standard_normal((n, n))
    return A @ A.T + np.eye(n)


def random_lq(rng, T=6, ndx=4, nu=3, cons=None):
    """Random LQ data; ``cons`` maps node -> ("su" state-input | "x" pure-state, rows)."""
    P = {
        "Fx": [np.eye(ndx) + 0.1 * rng.standard_normal((ndx, ndx)) for _ in range(T)],
        "Fu": [rng.standard_normal((ndx, nu)) for _ in range(T)],
        "Lx": [rng.standard_normal(ndx) for _ in range(T + 1)],
        "Lu": [rng.standard_normal(nu) for _ in range(T)],
        "Lxx": [_psd(rng, ndx) for _ in range(T + 1)],
        "Lxu": [0.1 * rng.standard_normal((ndx, nu)) for _ in range(T)],
        "Luu": [_psd(rng, nu) for _ in range(T)],
        "Hx": [np.zeros((0, ndx)) for _ in range(T + 1)],
        "Hu": [np.zeros((0, nu)) for _ in range(T)],
        "h": [np.zeros(0) for _ in range(T + 1)],
    }
    for t, (kind, n) in (cons or {}).items():
        P["Hx"][t] = rng.standard_normal((n, ndx))
        P["h"][t] = rng.standard_normal(n)
        if t < T:
            P["Hu"][t] = rng.standard_normal((n, nu)) if kind == "su" else np.zeros((n, nu))
    return P


def kkt_solution(P):
    """Solve the equality-constrained LQ problem (δx₀ = 0) by one dense KKT system."""
    T, ndx, nu = len(P["Fx"]), P["Lx"][0].size, P["Lu"][0].size
    nz = (T + 1) * ndx + T * nu

    def ix(t):
        return slice(t * ndx, (t + 1) * ndx)

    def iu(t):
        return slice((T + 1) * ndx + t * nu, (T + 1) * ndx + (t + 1) * nu)

    H, g = np.zeros((nz, nz)), np.zeros(nz)
    for t in range(T + 1):
        H[ix(t), ix(t)] += P["Lxx"][t]
        g[ix(t)] += P["Lx"][t]
    for t in range(T):
        H[iu(t), iu(t)] += P["Luu"][t]
        g[iu(t)] += P["Lu"][t]
        H[ix(t), iu(t)] += P["Lxu"][t]
        H[iu(t), ix(t)] += P["Lxu"][t].T
    rows, rhs = [], []
    r = np.zeros((ndx, nz))
    r[:, ix(0)] = np.eye(ndx)
    rows.append(r)
    rhs.append(np.zeros(ndx))
    for t in range(T):
        r = np.zeros((ndx, nz))
        r[:, ix(t + 1)] = -np.eye(ndx)
        r[:, ix(t)] = P["Fx"][t]
        r[:, iu(t)] = P["Fu"][t]
        rows.append(r)
        rhs.append(np.zeros(ndx))
    for t in range(T + 1):
        n = P["h"][t].size
        if n:
            r = np.zeros((n, nz))
            r[:, ix(t)] = P["Hx"][t]
            if t < T:
                r[:, iu(t)] = P["Hu"][t]
            rows.append(r)
            rhs.append(-P["h"][t])
    A, b = np.vstack(rows), np.concatenate(rhs)
    kkt = np.block([[H, A.T], [A, np.zeros((A.shape[0], A.shape[0]))]])
    z = np.linalg.solve(kkt, np.concatenate([-g, b]))[:nz]
    return [z[iu(t)] for t in range(T)]


def policy_rollout(P, res):
    dx, us, xs = np.zeros(P["Lx"][0].size), [], []
    for t in range(len(P["Fx"])):
        xs.append(dx)
        du = -res.k[t] - res.K[t] @ dx
        us.append(du)
        dx = P["Fx"][t] @ dx + P["Fu"][t] @ du
    xs.append(dx)
    return xs, us


@pytest.mark.parametrize("cons", [
    {},
    {0: ("su", 2), 2: ("su", 1), 3: ("x", 1), 6: ("x", 2)},
    {1: ("x", 1), 2: ("su", 1), 4: ("x", 1), 5: ("su", 1), 6: ("x", 1)},
])
def test_lq_recursion_matches_kkt(cons):
    rng = np.random.default_rng(len(cons))
    P = random_lq(rng, cons=cons)
    res = projected_backward_pass(**P)
    xs, us = policy_rollout(P, res)
    for a, b in zip(us, kkt_solution(P)):
        np.testing.assert_allclose(a, b, atol=1e-9)
    for t in range(len(xs)):
        viol = P["Hx"][t] @ xs[t] + P["h"][t] + (P["Hu"][t] @ us[t] if t < len(us) else 0.0)
        assert np.all(np.abs(viol) < 1e-9)
    c1, c2 = linear_rollout_model_change(P["Fx"], P["Fu"], P["Lx"], P["Lu"], P["Lxx"], P["Lxu"], P["Luu"], res.k, res.K)
    model = sum(P["Lx"][t] @ xs[t] + 0.5 * xs[t] @ P["Lxx"][t] @ xs[t] for t in range(len(xs)))
    model += sum(P["Lu"][t] @ us[t] + 0.5 * us[t] @ P["Luu"][t] @ us[t] + xs[t] @ P["Lxu"][t] @ us[t]
                 for t in range(len(us)))
    assert c1 + 0.5 * c2 == pytest.approx(model, rel=1e-10, abs=1e-10)


def test_rank_deficient_rows_detected():
    rng = np.random.default_rng(3)
    P = random_lq(rng, cons={2: ("su", 1)})
    P["Hx"][2] = np.vstack([P["Hx"][2], P["Hx"][2]])
    P["Hu"][2] = np.vstack([P["Hu"][2], P["Hu"][2]])
    P["h"][2] = np.r_[P["h"][2], P["h"][2]]
    with pytest.raises(ConstraintRankError, match="rank-deficient") as err:
        projected_backward_pass(**P)
    assert err.value.node == 2


def test_contradictory_rows_are_reported_infeasible():
    rng = np.random.default_rng(3)
    P = random_lq(rng, cons={2: ("su", 1)})
    P["Hx"][2] = np.vstack([P["Hx"][2], 2.0 * P["Hx"][2]])
    P["Hu"][2] = np.vstack([P["Hu"][2], 2.0 * P["Hu"][2]])
    P["h"][2] = np.r_[P["h"][2], 2.0 * P["h"][2] + 0.5]
    with pytest.raises(ConstraintRankError, match="contradict") as err:
        projected_backward_pass(**P)
    assert (err.value.node, err.value.kind) == (2, "infeasible")


def test_relative_degree_violation_detected():
    rng = np.random.default_rng(4)
    P = random_lq(rng, cons={3: ("x", 1)})
    P["Fu"][2][0] = 0.0
    P["Hx"][3] = np.eye(4)[:1]
    with pytest.raises(ConstraintRankError, match="relative-degree") as err:
        projected_backward_pass(**P)
    assert err.value.node == 3


def test_over_constrained_node_detected():
    rng = np.random.default_rng(5)
    P = random_lq(rng, nu=1, cons={2: ("su", 1), 3: ("x", 1)})
    with pytest.raises(ConstraintRankError, match="over-constrained") as err:
        projected_backward_pass(**P)
    assert err.value.node == 2


def lqr_problem(rng, T=10, nx=4, nu=3, nh=1, terminal=True):
    A = np.eye(nx) + 0.1 * rng.standard_normal((nx, nx))
    B = rng.standard_normal((nx, nu))
    Q, R = _psd(rng, nx), _psd(rng, nu)
    N = 0.1 * rng.standard_normal((nx, nu))
    f, q, r = rng.standard_normal(nx), rng.standard_normal(nx), rng.standard_normal(nu)
    G, g = np.zeros((0, nx + nu)), np.zeros(0)
    H, h = rng.standard_normal((nh, nx + nu)), rng.standard_normal(nh)
    running = crocopy.ActionModelLQR(A, B, Q, R, N, G, H, f, q, r, g, h)
    Ht = H if terminal else np.zeros((0, nx + nu))
    term = crocopy.ActionModelLQR(A, B, Q, R, N, G, Ht, f, q, r, g, h[: Ht.shape[0]])
    return crocopy.ShootingProblem(rng.standard_normal(nx), [running] * T, term)


def test_linear_constraints_hold_after_one_iteration():
    rng = np.random.default_rng(10)
    problem = lqr_problem(rng)
    solver = SolverProjection(problem)
    solver.solve([], [], maxiter=1)
    assert solver.stepLength == 1.0
    problem.calc(solver.xs, solver.us)
    for m, d in zip(problem.runningModels, problem.runningDatas):
        assert np.max(np.abs(d.h[: m.nh])) < 1e-9
    assert np.max(np.abs(problem.terminalData.h)) < 1e-9
    assert solver.hfeas < 1e-9
    assert solver.solve(solver.xs, solver.us, maxiter=3, is_feasible=True)
    assert solver.iter <= 1


def test_without_constraints_equals_ddp_iterate_for_iterate():
    x0 = np.array([-1.0, 0.6, 0.4])
    iterates = []
    for cls in (crocopy.SolverDDP, SolverProjection):
        problem = crocopy.ShootingProblem(x0, [crocopy.ActionModelUnicycle()] * 20, crocopy.ActionModelUnicycle())
        solver = cls(problem)
        log = []
        solver.setCallbacks([lambda s, log=log: log.append((s.cost, [u.copy() for u in s.us], s.stepLength))])
        assert solver.solve([], [], maxiter=50)
        iterates.append(log)
    ddp, proj = iterates
    assert len(ddp) == len(proj) > 2
    for (c0, u0, a0), (c1, u1, a1) in zip(ddp, proj):
        assert a0 == a1
        assert c1 == pytest.approx(c0, rel=1e-10)
        np.testing.assert_allclose(np.array(u1), np.array(u0), atol=1e-9)



CURV = 1.0


def heading(px):
    """Constrained heading ``θ = 0.3 sin(CURV x) / CURV`` of :class:`UnicycleHeading`."""
    return 0.3 * np.sin(px * CURV) / CURV


class UnicycleHeading(crocopy.ActionModelAbstract):
    """Unicycle with the pure-state equality ``θ = heading(x)`` on every node (terminal too)."""

    def __init__(self, state_input=False):
        self.inner = crocopy.ActionModelUnicycle()
        nh = 2 if state_input else 1
        super().__init__(self.inner.state, 2, 5, 0, nh, 0, 1)
        self.state_input = state_input

    def createData(self):
        data = crocopy.ActionDataAbstract(self)
        data.inner = self.inner.createData()
        return data

    def calc(self, data, x, u=None):
        self.inner.calc(data.inner, x, u)
        data.xnext[:], data.cost, data.r[:] = data.inner.xnext, data.inner.cost, data.inner.r
        data.h[0] = x[2] - heading(x[0])
        if self.state_input and u is not None:
            data.h[1] = u[0] + 0.2 * x[1] - 0.5

    def calcDiff(self, data, x, u=None):
        self.inner.calcDiff(data.inner, x, u)
        for name in ("Fx", "Fu", "Lx", "Lu", "Lxx", "Lxu", "Luu"):
            getattr(data, name)[:] = getattr(data.inner, name)
        data.Hx[:] = 0.0
        data.Hu[:] = 0.0
        data.Hx[0] = [-0.3 * np.cos(x[0] * CURV), 0.0, 1.0]
        if self.state_input and u is not None:
            data.Hx[1, 1] = 0.2
            data.Hu[1, 0] = 1.0


@pytest.mark.parametrize("state_input", [False, True])
def test_nonlinear_equality_constraints_converge(state_input):
    x0 = np.array([-1.0, 0.6, heading(-1.0)])
    problem = crocopy.ShootingProblem(x0, [UnicycleHeading(state_input)] * 15, UnicycleHeading(state_input))
    solver = SolverProjection(problem)
    hfeas = []
    solver.setCallbacks([lambda s: hfeas.append(s.hfeas)])
    assert solver.solve([], [], maxiter=200), solver.reason
    assert hfeas[-1] < 1e-9
    problem.calc(solver.xs, solver.us)
    for x in solver.xs:
        assert abs(x[2] - heading(x[0])) < 1e-8
    if state_input:
        for x, u in zip(solver.xs, solver.us):
            assert abs(u[0] + 0.2 * x[1] - 0.5) < 1e-8
    assert all(np.isfinite(u).all() for u in solver.us)


def test_equality_feasibility_is_reported_per_iteration(capsys):
    x0 = np.array([-1.0, 0.6, heading(-1.0)])
    problem = crocopy.ShootingProblem(x0, [UnicycleHeading(True)] * 15, UnicycleHeading(True))
    solver = SolverProjection(problem)
    log = crocopy.CallbackLogger()
    solver.setCallbacks([crocopy.CallbackVerbose(), log])
    assert solver.solve([], [], maxiter=50)
    lines = capsys.readouterr().out.splitlines()
    header = next(line for line in lines if line.startswith("iter"))
    assert "||hfeas||" in header
    rows = [line.split() for line in lines if line[:4].strip().isdigit()]
    column = header.split().index("||hfeas||")
    assert len(rows) == len(log.hfeass) == solver.iter + 1
    for row, hfeas in zip(rows, log.hfeass):
        assert float(row[column]) == pytest.approx(hfeas, rel=1e-3, abs=1e-300)
    assert log.hfeass[0] > 1e-2 and log.hfeass[-1] < 1e-9
    problem.calc(solver.xs, solver.us)
    worst = max(np.abs(d.h).max() for d in [*problem.runningDatas, problem.terminalData])
    assert log.hfeass[-1] == pytest.approx(worst, rel=1e-9, abs=1e-15)


def test_solver_reports_infeasible_x0_and_over_constrained_nodes():
    x0 = np.array([-1.0, 0.6, 0.5])
    problem = crocopy.ShootingProblem(x0, [UnicycleHeading()] * 5, UnicycleHeading())
    with pytest.raises(ConstraintRankError, match="x0 violates") as err:
        SolverProjection(problem).solve([], [], maxiter=5)
    assert err.value.kind == "infeasible"
    rng = np.random.default_rng(2)
    problem = lqr_problem(rng, nu=1, nh=1)
    with pytest.raises(ConstraintRankError, match="over-constrained"):
        SolverProjection(problem).solve([], [], maxiter=5)


def _double_integrator(H, h, H_T, h_T, dt=0.1):
    """``p' = p + dt v``, ``v' = v + dt u`` (explicit Euler) with equality rows ``H [x; u] + h = 0``."""
    A, B = np.array([[1.0, dt], [0.0, 1.0]]), np.array([[0.0], [dt]])
    Q, R, N, f = 1e-2 * np.eye(2), np.eye(1), np.zeros((2, 1)), np.zeros(2)
    q, r, G, g = np.zeros(2), np.zeros(1), np.zeros((0, 3)), np.zeros(0)
    running = crocopy.ActionModelLQR(A, B, Q, R, N, G, np.atleast_2d(H), f, q, r, g, np.atleast_1d(h))
    terminal = crocopy.ActionModelLQR(A, B, Q, R, N, G, np.atleast_2d(H_T), f, q, r, g, np.atleast_1d(h_T))
    return crocopy.ShootingProblem(np.zeros(2), [running] * 8, terminal)


def test_solver_reports_contradictory_rows_and_relative_degree():
    no_rows = (np.zeros((0, 3)), np.zeros(0))
    problem = _double_integrator([[0.0, 1.0, 1.0], [0.0, 2.0, 2.0]], [0.0, -1.0], *no_rows)
    with pytest.raises(ConstraintRankError, match="contradict") as err:
        SolverProjection(problem).solve([], [], maxiter=5)
    assert (err.value.kind, err.value.node) == ("infeasible", 7)
    problem = _double_integrator(*no_rows, [[1.0, 0.0, 0.0]], [-1.0])
    with pytest.raises(ConstraintRankError, match="relative degree above one") as err:
        SolverProjection(problem).solve([], [], maxiter=5)
    assert (err.value.kind, err.value.node) == ("relative-degree", 8)
    problem = _double_integrator(*no_rows, [[0.0, 1.0, 0.0]], [-1.0])
    solver = SolverProjection(problem)
    assert solver.solve([], [], maxiter=5)
    assert abs(solver.xs[-1][1] - 1.0) < 1e-9


@pytest.mark.parametrize("tau", [0.0, 0.05])
def test_arm_path_residual_derivatives(tau):
    from crocopy.experiments.projection import build_arm_problem

    problem, us0, _ = build_arm_problem(dt=0.05, horizon=0.5, tau=tau)
    rng = np.random.default_rng(0)
    x = problem.x0 + 0.1 * rng.standard_normal(problem.x0.size)
    u = us0[0] + rng.standard_normal(6)
    dam, ddata = problem.runningModels[3].differential, problem.runningDatas[3].differential[0]
    cdata = ddata.constraints.constraints["ee_path"]
    assert dam.constraints.constraints["ee_path"].constraint.nh == 2
    dam.calc(ddata, x, u)
    dam.calcDiff(ddata, x, u)
    Hx, h0 = cdata.Hx.copy(), cdata.h.copy()
    eps = 1e-7
    for i in range(12):
        dx = np.zeros(12)
        dx[i] = eps
        dam.calc(ddata, problem.runningModels[3].state.integrate(x, dx), u)
        np.testing.assert_allclose((cdata.h - h0) / eps, Hx[:, i], atol=1e-5)
    assert (np.abs(Hx[:, 6:]).max() > 1e-3) == (tau > 0.0)


@pytest.mark.parametrize("integrator, tau", [("rk4", 0.1), ("euler", 0.0)])
def test_arm_experiment_removes_the_path_violation(integrator, tau):
    from crocopy.experiments.projection import build_arm_problem, path_ise

    problem, us0, info = build_arm_problem(dt=0.05, horizon=2.0, integrator=integrator, tau=tau)
    assert info["N"] == 40
    xs0 = problem.rollout(us0)
    ise0 = path_ise(xs0, info)
    assert ise0 > 1e-3
    solver = SolverProjection(problem)
    log = crocopy.CallbackLogger()
    solver.setCallbacks([log])
    assert solver.solve(xs0, us0, maxiter=20, is_feasible=True), solver.reason
    assert path_ise(solver.xs, info) < (1e-7 if tau else 1e-12)
    assert log.hfeass[-1] < 1e-9 < log.hfeass[0]
    assert solver.cost < 10.0


def test_arm_policy_check_finds_the_sampling_zero():
    from crocopy.experiments.projection import policy_check

    rows = dict(policy_check(dt=0.05, horizon=0.5))
    assert "most negative -1.0000" in rows["RK4, e = 0"]
    assert "-1.0000" not in rows["Euler, e = 0"] and "-1.0000" not in rows["RK4, e + 0.05 ė = 0"]
