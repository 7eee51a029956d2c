"""SolverIntro's compiled constrained backward pass (:mod:`crocopy.solvers.intro_riccati_kernel`) against its Python
steps: the same gains, value function and read-outs on the same iterate, the same iterations and cost over whole
solves, the same failures (regularisation raised, then False with a reason, never an exception)."""

from __future__ import annotations

import copy
import pickle

import numpy as np
import pytest
from intro_problems import arm_problem, lq_equality_problem, nonlinear_equality_model, nonlinear_equality_problem

import crocopy
from crocopy.solvers.base import BackwardPassError

pytestmark = pytest.mark.skipif(not crocopy.kernels_enabled(), reason="the compiled pass needs numba")

EQ_SOLVERS = (crocopy.LuNull, crocopy.QrNull, crocopy.Schur)
READOUTS = ("k", "K", "Vx", "Vxx", "Qx", "Qu", "Qxx", "Qxu", "Quu", "YZ", "Hy", "ks", "Ks", "kz", "Kz", "Qz", "Qzz",
            "Qxz", "Quz")


def _lq(H, h=None, nu=3, nx=4, seed=0):
    """LQR nodes whose equality rows are ``H [x; u] + h = 0`` (so ``Hu`` may be rank deficient or zero)."""
    r = np.random.RandomState(seed)
    A, B = np.eye(nx) + 0.1 * r.randn(nx, nx), r.randn(nx, nu)
    H = np.asarray(H, dtype=float)
    h = r.randn(H.shape[0]) if h is None else h
    return crocopy.ActionModelLQR(A, B, np.eye(nx), 0.1 * np.eye(nu), np.zeros((nx, nu)), np.zeros((0, nx + nu)), H,
                                  r.randn(nx), r.randn(nx), r.randn(nu), np.zeros(0), h)


def _rank_deficient_problem(T=6):
    """Three consistent rows of which the third is the sum of the first two (``Hu`` of rank 2), between nodes
    without rows."""
    r = np.random.RandomState(4)
    H, h = r.randn(2, 7), r.randn(2)
    dependent = _lq(np.vstack([H, H[0] + H[1]]), np.append(h, h[0] + h[1]))
    free = _lq(np.zeros((0, 7)))
    models = [dependent if t % 3 else free for t in range(T)]
    return crocopy.ShootingProblem(r.randn(4), models, crocopy.ActionModelLQR(4, 3)), [], []


def _mixed_problem(T=6):
    """Two rows (``Hu`` of full rank) on two nodes of three, none on the others."""
    r = np.random.RandomState(5)
    models = [_lq(r.randn(2, 7)) if t % 3 else _lq(np.zeros((0, 7))) for t in range(T)]
    return crocopy.ShootingProblem(r.randn(4), models, crocopy.ActionModelLQR(4, 3)), [], []


def _more_rows_than_controls():
    """Five rows on three controls (``Hy`` has more rows than columns: least squares)."""
    r = np.random.RandomState(8)
    model = _lq(r.randn(5, 7))
    return crocopy.ShootingProblem(r.randn(4), [model] * 5, crocopy.ActionModelLQR(4, 3)), [], []


def _state_rows():
    """A pure-state row (``Hu = 0``: rank 0, the whole control space is free)."""
    model = _lq(np.array([[1.0, 0.5, 0.0, 0.0, 0.0, 0.0, 0.0]]))
    return crocopy.ShootingProblem(np.ones(4), [model] * 4, crocopy.ActionModelLQR(4, 3)), [], []


PROBLEMS = {
    "lq": lambda: (lq_equality_problem(crocopy), [], []),
    "nonlinear": lambda: nonlinear_equality_problem(crocopy, T=10, seed=3, a=0.3, b=0.1),
    "rank-deficient": _rank_deficient_problem,
    "mixed": _mixed_problem,
    "least-squares": _more_rows_than_controls,
    "state-rows": _state_rows,
    "arm": lambda: (arm_problem(crocopy, T=8), [], []),
}


def _direction(problem, xs, us, eq_solver, kernels, preg=1e-6):
    """One backward pass on the iterate ``(xs, us)`` (gaps open) with kernels on or off."""
    solver = crocopy.SolverIntro(problem)
    solver.eq_solver = eq_solver
    with crocopy.use_kernels(kernels):
        solver.setCandidate(xs, us, False)
        solver.preg = preg
        solver.calcDiff()
        solver.backwardPass()
    return solver


def _direction_or_error(problem, xs, us, eq_solver, kernels):
    try:
        return _direction(problem, xs, us, eq_solver, kernels)
    except BackwardPassError as error:
        return str(error)


def _assert_same_readouts(a, b, rtol=1e-9):
    assert a.Hu_rank == b.Hu_rank
    for name in READOUTS:
        for t, (x, y) in enumerate(zip(getattr(a, name), getattr(b, name))):
            assert x.shape == y.shape, (name, t)
            scale = max(1.0, float(np.abs(y).max())) if y.size else 1.0
            np.testing.assert_allclose(x, y, rtol=0, atol=rtol * scale, err_msg=f"{name}[{t}]")


@pytest.mark.parametrize("eq_solver", EQ_SOLVERS, ids=str)
@pytest.mark.parametrize("name", PROBLEMS)
def test_compiled_pass_equals_the_python_steps(name, eq_solver):
    problem, xs, us = PROBLEMS[name]()
    r = np.random.RandomState(11)
    xs = xs or [m.state.rand() for m in (*problem.runningModels, problem.terminalModel)]
    us = us or [r.randn(m.nu) for m in problem.runningModels]
    assert any(m.nh for m in problem.runningModels)
    compiled = _direction_or_error(problem, xs, us, eq_solver, True)
    python = _direction_or_error(problem, xs, us, eq_solver, False)
    if isinstance(python, str):  # Schur with more rows than rank: Hu Quu⁻¹ Huᵀ is singular, both paths say so
        assert eq_solver == crocopy.Schur and compiled == python and "singular" in python
        return
    _assert_same_readouts(compiled, python)
    assert not compiled.isFeasible and np.abs(np.concatenate(compiled.fs)).max() > 0  # the gaps were deflected


def test_ranks_are_read_back():
    problem, _, _ = _rank_deficient_problem()
    for eq in (crocopy.LuNull, crocopy.QrNull):
        solver = _direction(problem, [], [], eq, True)
        assert solver.Hu_rank == [0 if t % 3 == 0 else 2 for t in range(problem.T)]
        assert solver.YZ[1].shape == (3, 3) and solver.Hy[1].shape == (3, 2) and solver.Ks[1].shape == (2, 4)
        assert solver.Qzz[1].shape == (1, 1) and solver.Qxz[1].shape == (4, 1) and solver.Quz[1].shape == (3, 1)
    schur = _direction(*_mixed_problem()[:1], [], [], crocopy.Schur, True)
    assert schur.Hu_rank == [0 if t % 3 == 0 else 2 for t in range(6)]
    assert schur.Qzz[1].shape == (2, 2) and schur.Hy[1].shape == (2, 2) and not schur.YZ[1].any()


SOLVES = [(name, eq) for name in ("lq", "nonlinear", "mixed", "arm") for eq in EQ_SOLVERS] + [
    ("rank-deficient", crocopy.LuNull), ("rank-deficient", crocopy.QrNull)]


@pytest.mark.parametrize(("name", "eq_solver"), SOLVES, ids=[f"{n}-{e}" for n, e in SOLVES])
def test_kernels_on_or_off_solve_alike(name, eq_solver):
    results = []
    for kernels in (True, False):
        problem, xs, us = PROBLEMS[name]()
        solver = crocopy.SolverIntro(problem)
        solver.eq_solver = eq_solver
        trace = []
        solver.setCallbacks([lambda s, rows=trace: rows.append((s.cost, s.stop, s.preg, s.stepLength, s.hfeas))])
        with crocopy.use_kernels(kernels):
            converged = solver.solve(xs, us, 60)
        results.append((converged, solver, trace))
    assert results[0][0] and solver.hfeas < 1e-8
    (ok_c, compiled, trace_c), (ok_p, python, trace_p) = results
    assert ok_c == ok_p and compiled.iter == python.iter
    assert compiled.cost == pytest.approx(python.cost, rel=1e-9)
    assert [row[2:4] for row in trace_c] == [row[2:4] for row in trace_p]  # preg and step lengths
    np.testing.assert_allclose([row[0] for row in trace_c], [row[0] for row in trace_p], rtol=1e-9)
    _assert_same_readouts(compiled, python, rtol=1e-7)


def test_switching_kernels_and_methods_on_one_solver_keeps_the_readouts_right():
    """The lists show views of the compiled pass's buffer; a Python pass or another method in between must not
    leave them stale or wrongly shaped."""
    problem, _, _ = _mixed_problem()
    r = np.random.RandomState(2)
    xs = [m.state.rand() for m in (*problem.runningModels, problem.terminalModel)]
    us = [r.randn(m.nu) for m in problem.runningModels]
    solver = crocopy.SolverIntro(problem)
    solver.setCandidate(xs, us, False)
    solver.preg = 1e-6
    solver.calcDiff()
    for eq, kernels in [(crocopy.LuNull, True), (crocopy.Schur, True), (crocopy.LuNull, False), (crocopy.QrNull, True),
                        (crocopy.LuNull, True)]:
        solver.eq_solver = eq
        with crocopy.use_kernels(kernels):
            solver.backwardPass()
        reference = _direction(problem, xs, us, eq, False)
        _assert_same_readouts(solver, reference)


def test_a_pickled_or_copied_solver_has_readouts_of_its_own():
    problem, xs, us = PROBLEMS["mixed"]()
    solver = crocopy.SolverIntro(problem)
    assert solver.solve(xs, us, 50)
    for other in (pickle.loads(pickle.dumps(solver)), copy.deepcopy(solver)):
        _assert_same_readouts(other, solver, rtol=0.0)
        assert all(not np.shares_memory(a, b) for a, b in zip(other.YZ, solver.YZ))
        assert other.solve(xs, us, 50) and solver.solve(xs, us, 50)
        assert other.iter == solver.iter
        _assert_same_readouts(other, solver, rtol=1e-12)


def test_a_subclass_overriding_a_node_step_gets_the_python_steps():
    calls = []

    class Traced(crocopy.SolverIntro):
        def _constrained_value_function(self, t):
            calls.append(t)
            super()._constrained_value_function(t)

    problem, xs, us = PROBLEMS["lq"]()
    traced, plain = Traced(problem), crocopy.SolverIntro(problem)
    assert traced.solve(xs, us, 5) and plain.solve(xs, us, 5)
    assert calls and traced.iter == plain.iter
    assert traced.cost == pytest.approx(plain.cost, rel=1e-12)


# ---------------------------------------------------------------------------------------------------- failures
class _Concave(nonlinear_equality_model(crocopy)):
    """The nonlinear node with a control cost curving down by ``-1e12`` (no regularisation up to ``reg_max``
    makes the reduced Hessian, or ``Quu``, positive definite)."""

    def calcDiff(self, data, x, u=None):
        super().calcDiff(data, x, u)
        if u is not None:
            data.Luu[:] = -1e12 * np.eye(u.size)


class _NanRows(nonlinear_equality_model(crocopy)):
    """The nonlinear node whose ``Hu`` is NaN."""

    def calcDiff(self, data, x, u=None):
        super().calcDiff(data, x, u)
        if u is not None:
            data.Hu[:] = np.nan


def _failing_problem(cls):
    models = [cls(4, 3, 2, 1, 0.3, 0.1) for _ in range(4)]
    return crocopy.ShootingProblem(np.ones(4), models, models[0])


@pytest.mark.parametrize("eq_solver", EQ_SOLVERS, ids=str)
@pytest.mark.parametrize("cls", [_Concave, _NanRows], ids=["not-positive-definite", "nan-rows"])
def test_a_failing_backward_pass_returns_false_with_the_same_reason(cls, eq_solver):
    outcomes = []
    for kernels in (True, False):
        solver = crocopy.SolverIntro(_failing_problem(cls))
        solver.eq_solver = eq_solver
        with crocopy.use_kernels(kernels):
            converged = solver.solve([], [], 10)
        assert converged is False
        assert all(np.isfinite(u).all() for u in solver.us)
        outcomes.append((solver.iter, solver.reason, solver.preg))
    assert outcomes[0] == outcomes[1]
    assert "reg_max" in outcomes[0][1] and "backward pass" in outcomes[0][1]


@pytest.mark.parametrize(("cls", "eq_solver", "message"), [
    (_Concave, crocopy.LuNull, "the reduced Hessian Qzz is not positive definite at node 3"),
    (_Concave, crocopy.QrNull, "the reduced Hessian Qzz is not positive definite at node 3"),
    (_Concave, crocopy.Schur, "Quu is not positive definite at node 3"),
    (_NanRows, crocopy.LuNull, "non-finite equality rows"),
    (_NanRows, crocopy.QrNull, "non-finite equality rows"),
    (_NanRows, crocopy.Schur, "the Schur complement Hu Quu⁻¹ Huᵀ is singular at node 3"),
])
def test_both_paths_raise_the_same_backward_pass_error(cls, eq_solver, message):
    problem = _failing_problem(cls)
    for kernels in (True, False):
        solver = crocopy.SolverIntro(problem)
        solver.eq_solver = eq_solver
        with crocopy.use_kernels(kernels):
            solver.setCandidate([], [], False)
            solver.calcDiff()
            with pytest.raises(BackwardPassError) as error:
                solver.backwardPass()
        assert str(error.value) == message


@pytest.mark.parametrize("norm", [crocopy.FeasibilityNorm.LInf, crocopy.FeasibilityNorm.L1], ids=str)
@pytest.mark.parametrize("name", ["lq", "mixed", "arm"])
def test_equality_norm_in_one_call_equals_the_python_norm(name, norm):
    """``hfeas`` (every node's ``h``, terminal included) from the compiled call and from numpy; NaN stays NaN."""
    problem, _, _ = PROBLEMS[name]()
    r = np.random.RandomState(3)
    xs = [m.state.rand() for m in (*problem.runningModels, problem.terminalModel)]
    us = [r.randn(m.nu) for m in problem.runningModels]
    problem.calc(xs, us)
    solver = crocopy.SolverIntro(problem)
    solver.feasNorm = norm
    values = {}
    for kernels in (True, False):
        with crocopy.use_kernels(kernels):
            values[kernels] = solver._equality_norm()
    assert values[True] > 0 and values[True] == pytest.approx(values[False], rel=1e-14)
    problem.runningDatas[1].h[0] = np.nan
    for kernels in (True, False):
        with crocopy.use_kernels(kernels):
            assert np.isnan(solver._equality_norm())


def test_equality_norm_without_rows_is_zero():
    problem = crocopy.ShootingProblem(np.zeros(4), [crocopy.ActionModelLQR(4, 3)] * 3, crocopy.ActionModelLQR(4, 3))
    for kernels in (True, False):
        with crocopy.use_kernels(kernels):
            assert crocopy.SolverIntro(problem)._equality_norm() == 0.0
