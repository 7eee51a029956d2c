"""The one-call compiled backward pass (crocopy.solvers.horizon) equals its numpy twin, and follows the problem.

Nodes of mixed sizes (impulse nodes with nu = 0, LQR nodes with and without controls), feasible and
infeasible iterates, bounds inactive and active; a model that rebinds its derivative arrays; a problem
changed by updateModel/circularAppend after the solver was built.
"""

from __future__ import annotations

import numpy as np
import pytest

import crocopy
from crocopy.problems import registry
from crocopy.solvers.horizon import stores

SOLVERS = [crocopy.SolverDDP, crocopy.SolverFDDP, crocopy.SolverBoxDDP, crocopy.SolverBoxFDDP]
FIELDS = ("Vxx", "Vx", "Qxx", "Qxu", "Quu", "Qx", "Qu", "K", "k")


def _lqr(rng, nu: int) -> crocopy.ActionModelLQR:
    """A stable, well-conditioned LQR node with 4 states and ``nu`` controls."""
    A = np.eye(4) + 0.1 * rng.standard_normal((4, 4))
    B = rng.standard_normal((4, nu))
    return crocopy.ActionModelLQR(A, B, 2.0 * np.eye(4), np.eye(nu), np.zeros((4, nu)), np.zeros(4),
                                  rng.standard_normal(4), rng.standard_normal(nu))


def _lqr_mixed(bounded: bool) -> crocopy.ShootingProblem:
    """LQR nodes with 3, 0 and 1 controls (same state), bounded if asked."""
    rng = np.random.default_rng(3)
    models = []
    for t in range(12):
        nu = (3, 0, 1)[t % 3]
        m = _lqr(rng, nu)
        if nu and bounded:
            m.u_lb, m.u_ub = -0.05 * np.ones(nu), 0.05 * np.ones(nu)
        models.append(m)
    return crocopy.ShootingProblem(rng.standard_normal(4), models, _lqr(rng, 0))


def _trot(bounded: bool) -> crocopy.ShootingProblem:
    """ANYmal trot, one short cycle: contact nodes (nu = 12) and impulse nodes (nu = 0)."""
    problem = registry.get("trot-short").build()[0]
    if not bounded:
        for m in problem.runningModels:
            if m.nu:
                m.u_lb, m.u_ub = np.full(m.nu, -np.inf), np.full(m.nu, np.inf)
    return problem


def _iterate(problem, feasible: bool, seed: int):
    """A rollout of small random controls (feasible), or random states around it (gaps)."""
    rng = np.random.default_rng(seed)
    us = [0.1 * rng.standard_normal(m.nu) for m in problem.runningModels]
    for u, m in zip(us, problem.runningModels):
        if m.nu and np.isfinite(m.u_lb).all():
            np.clip(u, m.u_lb, m.u_ub, out=u)
    xs = problem.rollout(us)
    if not feasible:
        models = [*problem.runningModels, problem.terminalModel]
        xs = [m.state.integrate(x, 0.05 * rng.standard_normal(m.state.ndx)) for m, x in zip(models, xs)]
    return xs, us


def _direction(solver, kernels_on: bool, k0: list) -> dict:
    for k, k_init in zip(solver.k, k0):
        k[:] = k_init  # the box QP's warm start
    with crocopy.use_kernels(kernels_on):
        solver.computeDirection(False)
    out = {name: [a.copy() for a in getattr(solver, name)] for name in FIELDS}
    if isinstance(solver, crocopy.SolverFDDP):
        out["dg_dq"] = [np.array([solver._dg, solver._dq])]
    if hasattr(solver, "Quu_inv"):
        out["Quu_inv"] = [a.copy() for a in solver.Quu_inv]
        out["clamped"] = [np.array(solver._clamped, dtype=float)]
    return out


def _assert_same(a: dict, b: dict) -> None:
    """Equal to 1e-12 relative to the largest value-function entry (the scale of the recursion's round-off)."""
    assert a.keys() == b.keys()
    scale = max(1.0, *(np.abs(V).max() for V in b["Vxx"]))
    for name in a:
        assert len(a[name]) == len(b[name])
        for x, y in zip(a[name], b[name], strict=True):
            assert x.shape == y.shape
            assert np.max(np.abs(x - y), initial=0.0) <= 1e-12 * scale, name


@pytest.mark.parametrize("Solver", SOLVERS, ids=lambda S: S.__name__)
@pytest.mark.parametrize("feasible", [True, False], ids=["feasible", "gaps"])
@pytest.mark.parametrize("bounded", [False, True], ids=["free", "bounded"])
@pytest.mark.parametrize("build", [_lqr_mixed, _trot], ids=["lqr-mixed", "trot-impulses"])
def test_compiled_pass_equals_numpy_twin(build, bounded, feasible, Solver):
    problem = build(bounded)
    solver = Solver(problem)
    xs, us = _iterate(problem, feasible, seed=7)
    solver.setCandidate(xs, us, feasible)
    solver.preg = solver.dreg = 1e-6
    solver.calcDiff()
    rng = np.random.default_rng(1)
    k0 = [0.01 * rng.standard_normal(k.shape) for k in solver.k]
    compiled = _direction(solver, True, k0)
    twin = _direction(solver, False, k0)
    _assert_same(compiled, twin)
    assert any(np.abs(K).sum() > 0 for K in compiled["K"])
    if "clamped" in compiled and bounded and feasible:
        assert compiled["clamped"][0].any()  # the bounds are active somewhere


class _RebindingLQR(crocopy.ActionModelAbstract):
    """An LQR written as a user would for Crocoddyl: calcDiff assigns new arrays to the data."""

    def __init__(self, nu: int) -> None:
        super().__init__(crocopy.StateVector(3), nu)
        rng = np.random.default_rng(nu)
        self.A = np.eye(3) + 0.1 * rng.standard_normal((3, 3))
        self.B = rng.standard_normal((3, nu))

    def calc(self, data, x, u=None):
        u = np.zeros(self.nu) if u is None else u
        data.xnext[:] = self.A @ x + self.B @ u
        data.cost = 0.5 * (x @ x + u @ u)

    def calcDiff(self, data, x, u=None):
        u = np.zeros(self.nu) if u is None else u
        data.Fx = self.A.copy()
        data.Fu = np.asfortranarray(self.B)  # not C-contiguous: copied into a staging array
        data.Lx, data.Lu = x.copy(), u.copy()
        data.Lxx, data.Luu, data.Lxu = np.eye(3), np.eye(self.nu), np.zeros((3, self.nu))


@pytest.mark.parametrize("Solver", SOLVERS, ids=lambda S: S.__name__)
def test_a_model_rebinding_its_derivatives_solves_as_the_twin(Solver):
    def solve(kernels_on: bool):
        models = [_RebindingLQR(2) if t % 2 else _RebindingLQR(1) for t in range(10)]
        problem = crocopy.ShootingProblem(np.array([1.0, -0.5, 0.3]), models, _RebindingLQR(1))
        held = [(d.Fx, d.Fu, d.Lxx) for d in problem.runningDatas]
        solver = Solver(problem)
        with crocopy.use_kernels(kernels_on):
            solver.solve(None, None, 20)
        for (Fx, Fu, Lxx), d, m in zip(held, problem.runningDatas, models, strict=True):
            assert d.Fx is Fx and d.Fu is Fu and d.Lxx is Lxx  # assigned values were copied in (Crocoddyl's way)
            np.testing.assert_array_equal(Fu, m.B)
        return solver

    compiled, twin = solve(True), solve(False)
    assert compiled.iter == twin.iter
    np.testing.assert_allclose(compiled.cost, twin.cost, rtol=1e-12)
    for a, b in zip(compiled.K, twin.K, strict=True):
        np.testing.assert_allclose(a, b, rtol=1e-10, atol=1e-12)


def test_a_rebound_derivative_is_seen_by_the_next_pass():
    problem = _lqr_mixed(False)
    solver = crocopy.SolverFDDP(problem)
    solver.solve(None, None, 3)
    data = problem.runningDatas[4]
    data.Lxx = data.Lxx + 10.0 * np.eye(4)  # rebound, not written in place: calcDiff would not see it
    with crocopy.use_kernels(True):
        solver.computeDirection(False)
    compiled = [a.copy() for a in solver.Vxx]
    with crocopy.use_kernels(False):
        solver.computeDirection(False)
    for a, b in zip(compiled, solver.Vxx, strict=True):
        np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-12)


def test_a_derivative_of_the_wrong_size_is_refused():
    problem = _lqr_mixed(False)
    solver = crocopy.SolverDDP(problem)
    solver.solve(None, None, 2)
    held = problem.runningDatas[0].Lx
    before = held.copy()
    with pytest.raises(ValueError, match=r"data\.Lx has shape \(4,\): cannot assign a value of shape \(7,\)"):
        problem.runningDatas[0].Lx = np.zeros(7)
    assert problem.runningDatas[0].Lx is held
    np.testing.assert_array_equal(held, before)
    problem.runningDatas[0].Lx = np.arange(4.0).reshape(4, 1)  # a column: copied in
    np.testing.assert_array_equal(held, np.arange(4.0))


@pytest.mark.parametrize("Solver", SOLVERS, ids=lambda S: S.__name__)
def test_update_model_and_circular_append_reallocate(Solver):
    problem = _lqr_mixed(True)
    solver = Solver(problem)
    solver.solve(None, None, 5)
    rng = np.random.default_rng(5)
    problem.updateModel(1, _lqr(rng, 5))  # node 1 had no control
    problem.circularAppend(_lqr(rng, 0))
    solver.setCandidate(problem.rollout([np.zeros(m.nu) for m in problem.runningModels]), None, True)
    solver.calcDiff()
    with crocopy.use_kernels(True):
        solver.computeDirection(False)  # re-allocates for the new layout before the pass
    compiled = [K.copy() for K in solver.K]
    assert [K.shape for K in compiled] == [(m.nu, 4) for m in problem.runningModels]
    with crocopy.use_kernels(False):
        solver.computeDirection(False)
    for a, b in zip(compiled, solver.K, strict=True):
        np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-12)
    assert solver.solve(None, None, 50)


def test_solver_lists_are_views_of_one_buffer():
    solver = crocopy.SolverBoxFDDP(_lqr_mixed(True))
    h = solver._horizon
    for name in (*FIELDS, "Quu_inv", "fs"):
        for a in getattr(solver, name):
            assert a.base is h.buf and a.flags.c_contiguous
    solver.solve(None, None, 5)
    assert np.shares_memory(solver.K[0], h.buf)


@pytest.mark.parametrize(("name", "Solver"), [
    ("pend", crocopy.SolverFDDP), ("arm", crocopy.SolverFDDP), ("arm", crocopy.SolverBoxFDDP),
])
def test_registry_solves_with_kernels_and_with_twins_agree(name, Solver):
    """Whole solves agree: the same iterations and step lengths, costs to 1e-8 (problems where round-off is not
    amplified: Box-DDP on the arm or Box-FDDP on the pendulum drift apart by 1e-6..1e-2 between any two orderings of
    the same sums, before this pass too; the arm's costs differ by 4e-9 on an AMD EPYC, 1e-10 on the Intel Xeon of
    earlier runs, where numba's code for the host CPU contracts other products into FMAs)."""
    def trace(kernels_on: bool):
        problem = registry.get(name).build()[0]
        solver = Solver(problem)
        rows = []
        solver.setCallbacks([lambda s: rows.append((s.cost, s.stepLength, s.preg))])
        with crocopy.use_kernels(kernels_on):
            solver.solve(None, None, 30)
        return solver.iter, rows

    compiled, twin = trace(True), trace(False)
    assert compiled[0] == twin[0] and len(compiled[1]) == len(twin[1]) > 0
    np.testing.assert_allclose(compiled[1], twin[1], rtol=1e-8)


@pytest.mark.parametrize("Solver", SOLVERS, ids=lambda S: S.__name__)
def test_a_deep_copy_of_a_solver_has_its_own_buffer(Solver):
    import copy
    import pickle

    problem = _lqr_mixed(True)
    solver = Solver(problem)
    solver.solve(None, None, 3)
    for make in (copy.deepcopy, lambda s: pickle.loads(pickle.dumps(s))):
        twin = make(solver)
        h = twin._horizon
        assert h is not solver._horizon
        for name in ("Vxx", "K", "k", "fs"):
            for a, b in zip(getattr(twin, name), getattr(solver, name), strict=True):
                assert a.base is h.buf
                np.testing.assert_array_equal(a, b)
        assert twin.solve(None, None, 50) == solver.solve(None, None, 50)
        assert twin.iter == solver.iter
        np.testing.assert_allclose(twin.cost, solver.cost, rtol=1e-12)


def test_a_rebound_gap_list_is_read():
    problem = _lqr_mixed(False)
    solver = crocopy.SolverFDDP(problem)
    xs, us = _iterate(problem, False, seed=2)
    solver.setCandidate(xs, us, False)
    solver.calcDiff()
    solver.fs = [f.copy() for f in solver.fs]  # no longer the buffer's views
    with crocopy.use_kernels(True):
        solver.computeDirection(False)
    compiled = [V.copy() for V in solver.Vx]
    with crocopy.use_kernels(False):
        solver.computeDirection(False)
    assert any(np.abs(f).sum() > 0 for f in solver.fs)
    for a, b in zip(compiled, solver.Vx, strict=True):
        np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-12)


class _PropertyData(crocopy.ActionDataAbstract):
    """A data class whose ``Lx`` is a property (not a stored field): its node is compared at each pass."""

    @property
    def Lx(self):
        return self._lx

    @Lx.setter
    def Lx(self, value):
        self._lx = value


class _PropertyLQR(_RebindingLQR):
    def createData(self):
        return _PropertyData(self)


def test_a_data_class_that_does_not_watch_its_arrays_is_compared_at_each_pass():
    def solve(kernels_on: bool):
        models = [_PropertyLQR(1) for _ in range(6)]
        problem = crocopy.ShootingProblem(np.array([1.0, -0.5, 0.3]), models, _PropertyLQR(1))
        solver = crocopy.SolverFDDP(problem)
        with crocopy.use_kernels(kernels_on):
            solver.solve(None, None, 20)
        return solver

    assert not stores(_PropertyData, "Lx") and stores(_PropertyData, "Fx")
    compiled, twin = solve(True), solve(False)
    assert compiled.iter == twin.iter
    np.testing.assert_allclose(compiled.cost, twin.cost, rtol=1e-12)
