"""The compiled-kernel switch (crocopy.kernels): it switches every consumer, the kernels give their
numpy twins' numbers, the library works without numba, and a subclass that loses a kernel is logged."""

from __future__ import annotations

import logging
import subprocess
import sys
import textwrap

import numpy as np
import pytest
from robots import load

import crocopy
from crocopy import kernels
from crocopy.costs import stack_kernel
from crocopy.integrators import euler_kernel
from crocopy.models import state_multibody
from crocopy.solvers import box_kernel, riccati_kernel
from crocopy.solvers.ddp import SolverDDP


def _lqr_problem(T: int = 15, nx: int = 6, nu: int = 3, seed: int = 0) -> crocopy.ShootingProblem:
    rng = np.random.default_rng(seed)
    A = np.eye(nx) + 0.1 * rng.standard_normal((nx, nx))
    B = rng.standard_normal((nx, nu))
    model = crocopy.ActionModelLQR(A, B, np.eye(nx), np.eye(nu), np.zeros((nx, nu)), 0.1 * rng.standard_normal(nx),
                                   rng.standard_normal(nx), rng.standard_normal(nu))
    return crocopy.ShootingProblem(rng.standard_normal(nx), [model] * T, model)


def _unicycle_problem(T: int = 20) -> crocopy.ShootingProblem:
    model = crocopy.ActionModelUnicycle()
    model.u_lb, model.u_ub = np.array([-0.3, -0.2]), np.array([0.3, 0.2])
    return crocopy.ShootingProblem(np.array([1.0, 2.0, 0.5]), [model] * T, crocopy.ActionModelUnicycle())


def _cost_sum(state, nu: int) -> crocopy.CostModelSum:
    costs = crocopy.CostModelSum(state, nu)
    costs.addCost("x", crocopy.CostModelResidual(state, crocopy.ResidualModelState(state, nu)), 1.0)
    bounds = crocopy.ActivationBounds(-0.1 * np.ones(nu), 0.1 * np.ones(nu))
    costs.addCost("u", crocopy.CostModelResidual(
        state, crocopy.ActivationModelQuadraticBarrier(bounds), crocopy.ResidualModelControl(state, nu)), 0.5)
    return costs


def _euler_problem(T: int = 10) -> crocopy.ShootingProblem:
    """An LQR differential model on a StateVector, integrated by Euler (the same one at every call)."""
    rng = np.random.default_rng(7)
    Aq, Av, B = rng.standard_normal((2, 2)), rng.standard_normal((2, 2)), rng.standard_normal((2, 2))
    dam = crocopy.DifferentialActionModelLQR(Aq, Av, B, np.eye(4), np.eye(2), np.zeros((4, 2)),
                                             rng.standard_normal(2), rng.standard_normal(4), rng.standard_normal(2))
    model = crocopy.IntegratedActionModelEuler(dam, 1e-2)
    return crocopy.ShootingProblem(np.ones(4), [model] * T, model)


def _arm_problem(T: int = 10) -> crocopy.ShootingProblem:
    state = crocopy.StateMultibody(load("talos_arm"))
    actuation = crocopy.ActuationModelFull(state)
    dam = crocopy.DifferentialActionModelFreeFwdDynamics(state, actuation, _cost_sum(state, actuation.nu))
    model = crocopy.IntegratedActionModelEuler(dam, 1e-2)
    x0 = state.zero()
    x0[0] = 0.5
    return crocopy.ShootingProblem(x0, [model] * T, model)


# ---------------------------------------------------------------------------------------------- the switch
def test_switch_is_global_and_the_context_manager_restores_it():
    assert kernels.available and crocopy.kernels_enabled()
    with crocopy.use_kernels(False):
        assert not crocopy.kernels_enabled()
        with crocopy.use_kernels(True):
            assert crocopy.kernels_enabled()
        assert not crocopy.kernels_enabled()
    assert crocopy.kernels_enabled()
    crocopy.set_kernels(False)
    try:
        assert not crocopy.kernels_enabled()
    finally:
        crocopy.set_kernels(True)
    assert crocopy.kernels_enabled()
    with pytest.raises(RuntimeError), crocopy.use_kernels(False):
        raise RuntimeError("the block failed")
    assert crocopy.kernels_enabled()


@pytest.mark.parametrize("bad", [1, "yes", None])
def test_switch_rejects_non_bools(bad):
    with pytest.raises(TypeError, match="enabled must be a bool"):
        crocopy.set_kernels(bad)
    assert crocopy.kernels_enabled()


def _count(monkeypatch, owner, name: str) -> list:
    """Replace ``owner.name`` (a module function or a method) by a wrapper; returns its list of calls."""
    original, calls = getattr(owner, name), []

    def counted(*args):
        calls.append(name)
        return original(*args)

    monkeypatch.setattr(owner, name, counted)
    return calls


def _solve_lqr_ddp():
    crocopy.SolverFDDP(_lqr_problem()).solve(None, None, 5)


def _solve_box():
    crocopy.SolverBoxFDDP(_unicycle_problem()).solve(None, None, 10, True)


def _solve_vector_euler():
    crocopy.SolverFDDP(_euler_problem()).solve(None, None, 3)


class _NodesInPython(crocopy.SolverFDDP):
    """A subclass, so that no compiled node (:mod:`crocopy.solvers.compiled_nodes`) replaces the Python node
    path these consumers are on."""


def _solve_arm():
    _NodesInPython(_arm_problem()).solve(None, None, 3)


# (module, kernel, numpy twin or None when the twin is a chain of methods, workload)
CONSUMERS = [
    (riccati_kernel, "riccati_pass", None, _solve_lqr_ddp),
    (riccati_kernel, "feedback_control", "feedback_control_numpy", _solve_lqr_ddp),
    (riccati_kernel, "terminal_value", "terminal_value_numpy", _solve_lqr_ddp),
    (box_kernel, "box_pass", None, _solve_box),
    (stack_kernel, "activation_values", "activation_values_numpy", _solve_arm),
    (stack_kernel, "derivatives_and_sums", "derivatives_and_sums_numpy", _solve_arm),
    (euler_kernel, "euler_step", "euler_step_numpy", _solve_vector_euler),
    (euler_kernel, "euler_chain", "euler_chain_numpy", _solve_vector_euler),
    (state_multibody, "add_integrate_jacobian", "add_integrate_jacobian_numpy", _solve_arm),
]


@pytest.mark.parametrize(("module", "kernel", "twin", "workload"), CONSUMERS,
                         ids=[c[1] for c in CONSUMERS])
def test_the_switch_selects_kernel_or_twin_in_every_consumer(monkeypatch, module, kernel, twin, workload):
    compiled = _count(monkeypatch, module, kernel)
    numpy_twin = _count(monkeypatch, module, twin) if twin else _count(monkeypatch, SolverDDP, "_backward_pass_numpy")
    with crocopy.use_kernels(True):
        workload()
    assert compiled and not numpy_twin
    compiled.clear()
    with crocopy.use_kernels(False):
        workload()
    assert not compiled and numpy_twin


# ------------------------------------------------------------------------------ kernels equal their twins
def _trace(problem_factory, Solver, maxiter: int, feasible: bool = False):
    problem = problem_factory()
    solver = Solver(problem)
    rows = []
    solver.setCallbacks([lambda s: rows.append((s.cost, s.stop, s.stepLength, s.preg))])
    converged = solver.solve(None, None, maxiter, feasible)
    return converged, solver.iter, rows, np.array(solver.us), np.concatenate(solver.xs)


@pytest.mark.parametrize(("factory", "Solver", "maxiter", "feasible"), [
    (_lqr_problem, crocopy.SolverDDP, 10, False),
    (_unicycle_problem, crocopy.SolverBoxDDP, 100, True),
    (_unicycle_problem, crocopy.SolverBoxFDDP, 100, False),
    (_euler_problem, crocopy.SolverFDDP, 20, False),
    (_arm_problem, crocopy.SolverFDDP, 30, False),
    (_arm_problem, crocopy.SolverBoxFDDP, 30, False),
], ids=["lqr-ddp", "unicycle-boxddp", "unicycle-boxfddp", "euler-fddp", "arm-fddp", "arm-boxfddp"])
def test_solves_with_kernels_and_with_twins_agree(factory, Solver, maxiter, feasible):
    with crocopy.use_kernels(True):
        compiled = _trace(factory, Solver, maxiter, feasible)
    with crocopy.use_kernels(False):
        twin = _trace(factory, Solver, maxiter, feasible)
    assert compiled[:2] == twin[:2]
    assert len(compiled[2]) == len(twin[2]) > 0
    for a, b in zip(compiled[2], twin[2], strict=True):
        np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(compiled[3], twin[3], rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(compiled[4], twin[4], rtol=1e-10, atol=1e-12)


def test_stack_kernels_equal_their_twins_on_random_rows():
    rng = np.random.default_rng(5)
    nr, ndx, nu, u_start = 12, 7, 3, 5
    r = rng.standard_normal(nr)
    lb, ub = -np.abs(rng.standard_normal(nr)), np.abs(rng.standard_normal(nr))
    lb[:4] = ub[:4] = 0.0
    act_w = rng.uniform(0.5, 2.0, nr)
    starts = np.array([0, 4, 9], dtype=np.intp)
    weights = rng.uniform(0.0, 3.0, nr)
    Jx, Ju = rng.standard_normal((nr, ndx)), rng.standard_normal((nr - u_start, nu))
    outs = []
    for suffix in ("", "_numpy"):
        item_costs, item_weights = np.zeros(3), np.array([1.0, 0.5, 2.0])
        total = getattr(stack_kernel, "activation_values" + suffix)(r, lb, ub, act_w, starts, item_costs, item_weights)
        Ar, Arr = np.zeros(nr), np.zeros(nr)
        getattr(stack_kernel, "activation_derivatives" + suffix)(r, lb, ub, act_w, Ar, Arr)
        L = [np.zeros(ndx), np.zeros(nu), np.zeros((ndx, ndx)), np.zeros((ndx, nu)), np.zeros((nu, nu))]
        getattr(stack_kernel, "accumulate" + suffix)(
            weights, Ar, Arr, Jx, Ju, u_start, True, *L, np.zeros(ndx + nu, dtype=np.int64))
        fused = [np.zeros(nr), np.zeros(nr), np.zeros(ndx), np.zeros(nu), np.zeros((ndx, ndx)),
                 np.zeros((ndx, nu)), np.zeros((nu, nu))]
        getattr(stack_kernel, "derivatives_and_sums" + suffix)(
            r, lb, ub, act_w, weights, *fused[:2], Jx, Ju, u_start, True, *fused[2:],
            np.zeros(ndx + nu, dtype=np.int64))
        for a, b in zip([Ar, Arr, *L], fused, strict=True):
            np.testing.assert_array_equal(a, b)
        outs.append([np.array(total), item_costs, Ar, Arr, *L])
    assert np.any(outs[0][3] == 0.0) and np.any(outs[0][3] != 0.0)
    for a, b in zip(*outs):
        np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-14)



@pytest.mark.parametrize("seed", range(3))
def test_stack_accumulate_on_rows_with_zero_ends_equals_the_dense_sums(seed):
    """Rows that are zero, zero at one end or nonzero at one entry only (control rows, Euclidean state rows): the
    kernel's per-row support gives the dense Gauss-Newton sums."""
    rng = np.random.default_rng(seed)
    nr, ndx, nu, u_start = 14, 8, 4, 6
    Jx, Ju = rng.standard_normal((nr, ndx)), rng.standard_normal((nr - u_start, nu))
    Jx[10:] = 0.0  # control rows
    Jx[0, :] = 0.0
    Jx[0, 3] = 1.5  # one entry
    Jx[1, :2] = Jx[1, 6:] = 0.0
    Jx[2, 0] = Jx[2, ndx - 1] = 0.0
    Ju[:2] = 0.0  # force rows' Ju zero, control rows with one entry
    Ju[4:] = 0.0
    Ju[4:, :] = np.eye(nu)[: nr - u_start - 4]
    Ju[3, 0] = 0.0
    Ar, Arr = rng.standard_normal(nr), rng.uniform(0.0, 2.0, nr)
    Arr[5] = 0.0
    weights = rng.uniform(0.5, 3.0, nr)
    L = [np.zeros(ndx), np.zeros(nu), np.full((ndx, ndx), 7.0), np.full((ndx, nu), 7.0), np.full((nu, nu), 7.0)]
    stack_kernel.accumulate(weights, Ar, Arr, Jx, Ju, u_start, True, *L, np.zeros(ndx + nu, dtype=np.int64))
    g, h = weights * Ar, weights * Arr
    Hx = h[:, None] * Jx
    expected = [Jx.T @ g, Ju.T @ g[u_start:], Jx.T @ Hx, Jx[u_start:].T @ (h[u_start:, None] * Ju),
                Ju.T @ (h[u_start:, None] * Ju)]
    for a, b in zip(L, expected, strict=True):
        np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-13)

@pytest.mark.parametrize("seed", range(3))
def test_stack_accumulate_equals_the_row_by_row_dense_sums_to_the_bit(seed):
    """Leaving the zero entries of the Jacobian rows out changes no bit: the kernel equals the row-by-row rank-one
    sums over every entry, in the same order (a zero term adds ``±0``)."""
    rng = np.random.default_rng(10 + seed)
    nr, ndx, nu, u_start = 16, 9, 4, 7
    Jx = rng.standard_normal((nr, ndx)) * (rng.uniform(size=(nr, ndx)) < 0.4)
    Ju = rng.standard_normal((nr - u_start, nu)) * (rng.uniform(size=(nr - u_start, nu)) < 0.5)
    Ar, Arr, weights = rng.standard_normal(nr), rng.uniform(0.0, 2.0, nr), rng.uniform(0.5, 3.0, nr)
    Arr[3] = 0.0
    L = [np.zeros(ndx), np.zeros(nu), np.zeros((ndx, ndx)), np.zeros((ndx, nu)), np.zeros((nu, nu))]
    stack_kernel.accumulate(weights, Ar, Arr, Jx, Ju, u_start, True, *L, np.zeros(ndx + nu, dtype=np.int64))
    Lx, Lu, Lxx, Lxu, Luu = (np.zeros(ndx), np.zeros(nu), np.zeros((ndx, ndx)), np.zeros((ndx, nu)),
                             np.zeros((nu, nu)))
    for i in range(nr):
        g, h = weights[i] * Ar[i], weights[i] * Arr[i]
        Lx += g * Jx[i]
        Lxx += (h * Jx[i])[:, None] * Jx[i][None, :]
        if i >= u_start:
            ju = Ju[i - u_start]
            Lu += g * ju
            Lxu += (h * Jx[i])[:, None] * ju[None, :]
            Luu += (h * ju)[:, None] * ju[None, :]
    upper_x, upper_u = np.triu_indices(ndx), np.triu_indices(nu)
    pairs = ((L[0], Lx), (L[1], Lu), (L[2][upper_x], Lxx[upper_x]), (L[3], Lxu), (L[4][upper_u], Luu[upper_u]))
    for got, want in pairs:
        np.testing.assert_array_equal(got, want)
    np.testing.assert_array_equal(L[2], L[2].T)
    np.testing.assert_array_equal(L[4], L[4].T)


# ------------------------------------------------------------------------------------- numba is missing
def test_forcing_the_availability_flag_off_uses_the_twins(monkeypatch):
    with crocopy.use_kernels(True):
        reference = _trace(_unicycle_problem, crocopy.SolverBoxFDDP, 100)
    monkeypatch.setattr(kernels, "available", False)  # the flags as an import without numba sets them
    monkeypatch.setattr(kernels, "active", False)
    assert not crocopy.kernels_enabled()
    with pytest.raises(RuntimeError, match="numba is not installed"):
        crocopy.set_kernels(True)
    with crocopy.use_kernels(False):
        assert not crocopy.kernels_enabled()
    box = _count(monkeypatch, box_kernel, "box_pass")
    feedback = _count(monkeypatch, riccati_kernel, "feedback_control")
    without = _trace(_unicycle_problem, crocopy.SolverBoxFDDP, 100)
    assert not box and not feedback
    assert without[:2] == reference[:2]
    np.testing.assert_allclose(without[3], reference[3], rtol=1e-10, atol=1e-12)


def test_the_library_imports_and_solves_without_numba():
    script = textwrap.dedent("""
        import sys
        sys.modules["numba"] = None  # `import numba` raises ImportError
        import numpy as np
        import crocopy
        from crocopy.solvers import riccati_kernel
        assert not crocopy.kernels.available and not crocopy.kernels_enabled()
        assert type(riccati_kernel.riccati_step).__name__ == "function"  # plain Python, not a dispatcher
        try:
            crocopy.set_kernels(True)
        except RuntimeError:
            pass
        else:
            raise AssertionError("set_kernels(True) must fail without numba")
        model = crocopy.ActionModelUnicycle()
        model.u_lb, model.u_ub = np.array([-0.3, -0.2]), np.array([0.3, 0.2])
        problem = crocopy.ShootingProblem(np.array([1.0, 2.0, 0.5]), [model] * 20, crocopy.ActionModelUnicycle())
        solver = crocopy.SolverBoxFDDP(problem)
        assert solver.solve(None, None, 100)
        dam = crocopy.DifferentialActionModelLQR.Random(2, 2)
        iam = crocopy.IntegratedActionModelEuler(dam, 1e-2)
        assert crocopy.SolverFDDP(crocopy.ShootingProblem(np.ones(4), [iam] * 10, iam)).solve(None, None, 20)
        print("ok", solver.iter)
    """)
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=300, cwd="/")
    assert done.returncode == 0, done.stderr
    assert done.stdout.startswith("ok")


# -------------------------------------------------------------------------------- fallbacks are logged
def _debug_records(caplog) -> list[str]:
    return [r.getMessage() for r in caplog.records if r.name == "crocopy" and r.levelno == logging.DEBUG]


def test_solver_overriding_a_node_step_is_logged_once(caplog):
    class DampedGains(crocopy.SolverDDP):
        def computeGains(self, t):
            super().computeGains(t)
            self.k[t] *= 0.5

    calls = []

    class CountedBox(crocopy.SolverBoxFDDP):
        def computeValueFunction(self, t, model):
            calls.append(t)
            super().computeValueFunction(t, model)

    caplog.set_level(logging.DEBUG, logger="crocopy")
    problem = _lqr_problem()
    for _ in range(2):
        DampedGains(problem).solve(None, None, 3)
    CountedBox(_unicycle_problem()).solve(None, None, 5, True)
    messages = _debug_records(caplog)
    damped = [m for m in messages if ".DampedGains " in m]
    assert len(damped) == 1 and "computeGains" in damped[0] and "Riccati" in damped[0]
    box = [m for m in messages if ".CountedBox " in m]
    assert len(box) == 1 and "computeValueFunction" in box[0] and "box-QP" in box[0]
    assert calls, "the override must run"


def test_solver_without_overrides_logs_nothing(caplog):
    caplog.set_level(logging.DEBUG, logger="crocopy")
    crocopy.SolverBoxFDDP(_unicycle_problem()).solve(None, None, 5, True)
    crocopy.SolverFDDP(_lqr_problem()).solve(None, None, 5)
    assert _debug_records(caplog) == []


def test_multibody_state_overriding_an_operation_is_logged_and_honoured(caplog):
    class DoubledJacobian(crocopy.StateMultibody):
        def Jintegrate(self, x, dx, firstsecond=crocopy.Jcomponent.both):
            return [2.0 * J for J in super().Jintegrate(x, dx, firstsecond)]

    caplog.set_level(logging.DEBUG, logger="crocopy")
    state = DoubledJacobian(load("anymal"))
    messages = [m for m in _debug_records(caplog) if "DoubledJacobian" in m]
    assert len(messages) == 1 and "Jintegrate" in messages[0] and "Euler chain rule" in messages[0]
    np.random.seed(2)
    x, dx = state.rand(), np.random.rand(state.ndx)
    Fx, Fu = np.random.rand(state.ndx, state.ndx), np.random.rand(state.ndx, 3)
    expected_x = state.Jintegrate(x, dx, crocopy.Jcomponent.first)[0] + crocopy.StateMultibody.Jintegrate(
        state, x, dx, crocopy.Jcomponent.second)[0] @ Fx
    state._integrate_chain_rule(x, dx, Fx, Fu)
    np.testing.assert_allclose(Fx, expected_x, atol=1e-12)
    out = np.zeros(state.nx)
    state._integrate_into(x, dx, out)  # integrate is not overridden: the direct form stays
    np.testing.assert_allclose(out, crocopy.StateMultibody.integrate(state, x, dx), atol=1e-14)
    DoubledJacobian(load("anymal"))
    assert len([m for m in _debug_records(caplog) if "DoubledJacobian" in m]) == 1


def test_activation_overriding_calc_is_logged_and_honoured(caplog):
    class HalfQuad(crocopy.ActivationModelQuad):
        def calc(self, data, r):
            data.a_value = 0.25 * float(r @ r)

        def calcDiff(self, data, r):
            data.Ar[:] = 0.5 * r
            data.Arr_diag[:] = 0.5

    caplog.set_level(logging.DEBUG, logger="crocopy")
    state = crocopy.StateVector(4)
    costs = crocopy.CostModelSum(state, 2)
    residual = crocopy.ResidualModelState(state, 2)
    costs.addCost("half", crocopy.CostModelResidual(state, HalfQuad(state.ndx), residual), 2.0)
    data = costs.createData(crocopy.DataCollectorAbstract())
    x, u = np.array([1.0, -2.0, 0.5, 3.0]), np.zeros(2)
    costs.calc(data, x, u)
    costs.calcDiff(data, x, u)
    assert data.cost == pytest.approx(2.0 * 0.25 * x @ x, rel=1e-14)
    np.testing.assert_allclose(data.Lx, x, rtol=1e-14)
    np.testing.assert_allclose(data.Lxx, np.eye(4), rtol=1e-14)
    messages = [m for m in _debug_records(caplog) if "HalfQuad" in m]
    assert len(messages) == 1 and "calc, calcDiff" in messages[0]


def test_euler_on_a_state_without_transport_is_logged(caplog):
    class PlainLie(crocopy.StateVector):
        """A vector space treated as a general manifold that does not implement JintegrateTransport."""

        JintegrateTransport = crocopy.StateAbstract.JintegrateTransport

    caplog.set_level(logging.DEBUG, logger="crocopy")
    dam = crocopy.DifferentialActionModelLQR.Random(2, 2)
    object.__setattr__(dam, "state", PlainLie(4))  # state is read-only; the LQR model has no state argument
    iam = crocopy.IntegratedActionModelEuler(dam, 1e-2)
    if iam._euclidean:
        pytest.fail("the test state must not be treated as Euclidean")
    messages = [m for m in _debug_records(caplog) if "PlainLie" in m]
    assert len(messages) == 1 and "does not implement JintegrateTransport" in messages[0]
