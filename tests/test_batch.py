"""Pickling of models and problems, and :func:`crocopy.solve_many` on thread and process pools."""

import pickle
from concurrent.futures import ProcessPoolExecutor, ThreadPoolExecutor

import numpy as np
import pytest
from robots import load

import crocopy
from crocopy.batch import solve_one
from crocopy.bench.batch import makespan, run_batch_bench
from crocopy.bench.scaling import fit_exponent, hop_memory, run_scaling_bench
from crocopy.cli import build_parser
from crocopy.problems import registry
from crocopy.problems.common import load_model

FIELDS = ("cost", "xnext", "r", "Fx", "Fu", "Lx", "Lu", "Lxx", "Lxu", "Luu", "g", "Gx", "Gu", "h", "Hx", "Hu")


def assert_same_node(model, other, x, u) -> None:
    """``model`` and ``other`` give bitwise-equal calc/calcDiff results at ``(x, u)``."""
    d, e = model.createData(), other.createData()
    for m, data in ((model, d), (other, e)):
        m.calc(data, x, u)
        m.calcDiff(data, x, u)
    for f in FIELDS:
        a, b = getattr(d, f, None), getattr(e, f, None)
        if a is not None:
            np.testing.assert_array_equal(a, b, err_msg=f)


def roundtrip(obj):
    return pickle.loads(pickle.dumps(obj))


def _dlqr():
    return crocopy.DifferentialActionModelLQR.Random(3, 2, 1, 1)


def _limited_unicycle():
    model = crocopy.ActionModelUnicycle()
    model.u_lb, model.u_ub = np.array([-1.0, -0.5]), np.array([2.0, 0.5])
    return model


CORE_MODELS = {
    "lqr": lambda: crocopy.ActionModelLQR.Random(5, 3, 2, 1),
    "unicycle": crocopy.ActionModelUnicycle,
    "numdiff": lambda: crocopy.ActionModelNumDiff(crocopy.ActionModelUnicycle(), True),
    "euler-dlqr": lambda: crocopy.IntegratedActionModelEuler(_dlqr(), 1e-2),
    "rk4-numdiff-dlqr": lambda: crocopy.IntegratedActionModelRK(
        crocopy.DifferentialActionModelNumDiff(_dlqr()), crocopy.RKType.four, 1e-2
    ),
    "squashed": lambda: crocopy.ActionModelSquashed(_limited_unicycle(), "tanh"),
    "penalty": lambda: crocopy.ActionModelControlPenalty(_limited_unicycle(), 1e2),
}


@pytest.mark.parametrize("name", sorted(CORE_MODELS))
@pytest.mark.parametrize("terminal", [False, True])
def test_core_models_pickle(name, terminal):
    model = CORE_MODELS[name]()
    copy = roundtrip(model)
    assert type(copy) is type(model) and copy is not model
    np.testing.assert_array_equal(copy.u_lb, model.u_lb)
    rng = np.random.default_rng(3)
    x = model.state.rand()
    assert_same_node(model, copy, x, None if terminal else rng.standard_normal(model.nu))


def test_pinocchio_model_without_name_and_with_infinite_limits():
    """Pinocchio's own archive cannot read back Talos legs (empty name, infinite effort limits)."""
    model = load("talos_legs")
    assert model.name == "" and not np.all(np.isfinite(model.effortLimit))
    copy = roundtrip(model)
    assert copy == model and copy.name == ""
    np.testing.assert_array_equal(copy.effortLimit, model.effortLimit)
    anymal = load_model("anymal")
    named = roundtrip(anymal)
    assert named == anymal and named.name == "anymal"


def test_multibody_models_with_squashing_actuation_pickle():
    state = crocopy.StateMultibody(load("talos_arm"))
    base = crocopy.ActuationModelFull(state)
    squash = crocopy.SquashingModelSmoothSat(-np.full(base.nu, 2.0), np.full(base.nu, 2.5), base.nu)
    actuation = crocopy.ActuationSquashingModel(base, squash, base.nu)
    costs = crocopy.CostModelSum(state, actuation.nu)
    costs.addCost("x", crocopy.CostModelResidual(state, crocopy.ResidualModelState(state, actuation.nu)), 1.0)
    costs.addCost("u", crocopy.CostModelResidual(state, crocopy.ResidualModelControl(state, actuation.nu)), 1e-2)
    dam = crocopy.DifferentialActionModelFreeFwdDynamics(state, actuation, costs)
    model = crocopy.IntegratedActionModelEuler(dam, 1e-2)
    copy = roundtrip(model)
    assert copy.differential.state.pinocchio == state.pinocchio
    assert_same_node(model, copy, state.rand(), np.random.default_rng(0).standard_normal(model.nu))


@pytest.mark.parametrize("name", ["pend", "trot-short", "quad-goal"])
def test_registry_problem_pickles_without_datas_and_evaluates_the_same(name):
    problem, xs, us = registry.build(name)
    copy = roundtrip(problem)
    assert copy.T == problem.T
    np.testing.assert_array_equal(copy.x0, problem.x0)
    assert all(a is not b for a, b in zip(copy.runningDatas, problem.runningDatas, strict=True))
    rng = np.random.default_rng(1)
    models = [*problem.runningModels, problem.terminalModel]
    xs = [m.state.integrate(x, 1e-2 * rng.standard_normal(m.state.ndx)) for m, x in zip(models, xs, strict=True)]
    us = [u + 0.1 * rng.standard_normal(u.shape) for u in us]
    for p in (problem, copy):
        p.calc(xs, us)
        p.calcDiff(xs, us)
    assert copy.cost == problem.cost
    for d, e in zip(
        [*problem.runningDatas, problem.terminalData], [*copy.runningDatas, copy.terminalData], strict=True
    ):
        for f in ("cost", "xnext", "Fx", "Fu", "Lx", "Lu", "Lxx", "Lxu", "Luu"):
            np.testing.assert_array_equal(getattr(d, f), getattr(e, f), err_msg=f)
    models_only = len(pickle.dumps(models))
    # the problem's own fields shift pickle's memo indices (2- or 5-byte references): a few kB at most;
    # one node's data would be tens of kB (77 kB for the pendulum's)
    assert len(pickle.dumps(problem)) < models_only + 5000


def unicycle(x0=(1.0, 0.5, 0.2), T=20):
    """A unicycle problem from ``x0``: (problem, xs, us) with a zero guess."""
    x0 = np.asarray(x0, dtype=float)
    model = _limited_unicycle()
    problem = crocopy.ShootingProblem(x0, [model] * T, crocopy.ActionModelUnicycle())
    return problem, [x0] * (T + 1), [np.zeros(2)] * T


def failing_unicycle(x0, fail=False):
    """:func:`unicycle`, or ValueError when ``fail``."""
    if fail:
        raise ValueError("this start is refused")
    return unicycle(x0)[0]


STARTS = [{"x0": (1.0, 0.5, 0.2)}, {"x0": (-1.0, 2.0, 1.0)}, {"x0": (0.3, -0.7, -2.0)}]


def assert_same_results(results, expected):
    assert len(results) == len(expected)
    for r, e in zip(results, expected, strict=True):
        assert (r.cost, r.iter, r.converged, r.reason, r.params) == (e.cost, e.iter, e.converged, e.reason, e.params)
        np.testing.assert_array_equal(np.array(r.xs), np.array(e.xs))
        np.testing.assert_array_equal(np.array(r.us), np.array(e.us))


def test_solve_many_on_threads_matches_serial_solves_in_order():
    serial = [solve_one(unicycle, p, crocopy.SolverFDDP, 100) for p in STARTS]
    assert all(r.converged and r.reason == "converged" for r in serial)
    assert len({r.cost for r in serial}) == 3
    with ThreadPoolExecutor(2) as pool:
        results = crocopy.solve_many(unicycle, STARTS, pool, solver=crocopy.SolverFDDP, maxiter=100)
    assert_same_results(results, serial)
    box = crocopy.solve_many(unicycle, STARTS, ThreadPoolExecutor(2), maxiter=100)
    assert all(np.all(np.abs(np.array(r.us)) <= [2.0, 0.5]) for r in box)


def test_solve_many_default_process_pool_matches_serial_solves():
    pend = registry.get("pend").build
    tasks = [(unicycle, p) for p in STARTS[:2]] + [(pend, {}), (pend, {"torque_limit": 3.0})]
    serial = [solve_one(b, p, maxiter=5) for b, p in tasks]
    assert serial[2].cost != serial[3].cost
    assert_same_results(crocopy.solve_many(unicycle, STARTS[:2], maxiter=5), serial[:2])
    assert_same_results(crocopy.solve_many(pend, [p for _, p in tasks[2:]], maxiter=5, max_workers=2), serial[2:])


def test_solve_many_ships_a_built_problem_with_new_starts():
    problem = unicycle()[0]
    results = crocopy.solve_many(problem, STARTS, ProcessPoolExecutor(2), solver=crocopy.SolverFDDP, maxiter=100)
    expected = [solve_one(unicycle, p, crocopy.SolverFDDP, 100) for p in STARTS]
    for r, e in zip(results, expected, strict=True):
        assert r.cost == pytest.approx(e.cost, rel=1e-12)
        np.testing.assert_allclose(r.xs[0], e.xs[0])
    np.testing.assert_array_equal(problem.x0, [1.0, 0.5, 0.2])
    with pytest.raises(crocopy.SolveManyError, match="init_guess"):
        crocopy.solve_many(problem, [{"init_guess": 1}], ThreadPoolExecutor(1))


@pytest.mark.parametrize("pool", ["threads", "processes"])
def test_worker_errors_name_the_params(pool):
    executor = ThreadPoolExecutor(2) if pool == "threads" else None
    params = [{"x0": (1.0, 0.0, 0.0)}, {"x0": (2.0, 0.0, 0.0), "fail": True}, {"x0": (3.0, 0.0, 0.0)}]
    message = r"solve 1 with params .*'fail': True.*this start is refused"
    with pytest.raises(crocopy.SolveManyError, match=message) as info:
        crocopy.solve_many(failing_unicycle, params, executor, maxiter=5)
    assert info.value.index == 1 and info.value.params["fail"] is True
    assert isinstance(info.value.__cause__, ValueError)
    executor = ThreadPoolExecutor(2) if pool == "threads" else None
    results = crocopy.solve_many(failing_unicycle, params, executor, maxiter=5, return_exceptions=True)
    assert isinstance(results[1], ValueError)
    assert isinstance(results[0], crocopy.SolveResult) and results[2].params == params[2]


def test_bad_arguments():
    with pytest.raises(ValueError, match="picklable"):
        crocopy.solve_many(lambda: unicycle()[0], [{}])
    with pytest.raises(ValueError, match=r"params\[1\] must be a mapping"):
        crocopy.solve_many(unicycle, [{}, (1.0, 0.0, 0.0)])
    with pytest.raises(ValueError, match="builder must be callable"):
        crocopy.solve_many(3, [{}])
    with pytest.raises(crocopy.SolveManyError, match="builder must return"):
        crocopy.solve_many(lambda: 3, [{}], ThreadPoolExecutor(1))
    with pytest.raises(crocopy.SolveManyError, match="no attribute 'th_stoop'"):
        crocopy.solve_many(unicycle, [{}], ThreadPoolExecutor(1), solver_options={"th_stoop": 1e-9})
    assert crocopy.solve_many(unicycle, []) == []


def test_batch_bench_runs_the_quadrotor_starts_serially_and_in_parallel(capsys):
    out = run_batch_bench(n=2, workers=2, repeats=1, maxiter=3)
    assert out["same"] and len(out["results"]) == 2
    assert [r.params["x0_position"][0] for r in out["results"]] == pytest.approx([-0.9, 0.3])
    assert out["speedup"] > 0 and out["cpu_speedup"] > 0
    assert "speed-up on idle cores" in capsys.readouterr().out
    assert makespan([3.0, 1.0, 1.0, 1.0], 2) == 3.0 and makespan([1.0, 1.0, 1.0], 2) == 2.0
    with pytest.raises(ValueError, match="workers"):
        makespan([1.0], 0)


def test_scaling_fit_and_short_run():
    T = np.array([50.0, 100.0, 400.0])
    a, b = fit_exponent(T, 3e-4 * T**1.5)
    assert b == pytest.approx(1.5) and a == pytest.approx(np.log(3e-4))
    with pytest.raises(ValueError, match="same length"):
        fit_exponent(T, T[:2])
    out = run_scaling_bench(repeats=1, cycles=(1, 2), memory=False)
    assert [r["T"] for r in out["rows"]] == [58, 114]
    assert all(r["iteration"] == pytest.approx(sum(r["phases"].values())) for r in out["rows"])
    assert np.isfinite(out["exponent"]) and set(out["exponents"]) == {"calc", "calcDiff", "backward", "forward"}


def test_cli_bench_flags():
    args = build_parser().parse_args(["bench", "--batch", "--scaling", "--workers", "3", "--runs", "5"])
    assert (args.batch, args.scaling, args.workers, args.runs) == (True, True, 3, 5)
    args = build_parser().parse_args(["bench"])
    assert (args.batch, args.scaling, args.workers, args.runs) == (False, False, 2, 3)


@pytest.mark.slow
def test_hop_memory_subprocess_reports_its_own_peak():
    m = hop_memory(maxiter=1)
    assert m["T"] == 592 and m["iter"] <= 1
    assert 0 < m["baseline"] < m["built"] <= m["solved"]
    assert m["solved"] - m["baseline"] < 2**30


def dying_unicycle(x0, exit_code=None, kill=False):
    """:func:`unicycle`, or the worker process ends abruptly (``os._exit`` or SIGKILL), as a segfault would."""
    import os
    import signal

    if exit_code is not None:
        os._exit(exit_code)
    if kill:
        os.kill(os.getpid(), signal.SIGKILL)
    return unicycle(x0)


DYING = [{"x0": (1.0, 0.5, 0.2)}, {"x0": (-1.0, 2.0, 1.0)}, {"x0": (0.3, -0.7, -2.0)}, {"x0": (0.5, 0.0, 0.0)}]


@pytest.mark.parametrize("how", [{"exit_code": 3}, {"kill": True}])
def test_a_dead_worker_costs_only_its_own_task_and_is_named(how):
    params = [dict(p) for p in DYING]
    params[3].update(how)
    expected = [solve_one(unicycle, {"x0": p["x0"]}, maxiter=20) for p in DYING[:3]]
    message = "exit code 3" if "exit_code" in how else "killed by signal SIGKILL"
    with pytest.raises(crocopy.SolveManyError, match=rf"solve 3 with params .*{message}") as info:
        crocopy.solve_many(dying_unicycle, params, maxiter=20, max_workers=2)
    assert info.value.index == 3 and isinstance(info.value.__cause__, crocopy.WorkerDiedError)
    results = crocopy.solve_many(dying_unicycle, params, maxiter=20, max_workers=2, return_exceptions=True)
    assert isinstance(results[3], crocopy.WorkerDiedError)
    assert results[3].exitcode == (3 if "exit_code" in how else -9)
    for r, e in zip(results[:3], expected, strict=True):
        assert isinstance(r, crocopy.SolveResult) and (r.cost, r.iter) == (e.cost, e.iter)
