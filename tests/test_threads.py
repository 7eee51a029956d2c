"""A solve in one thread never changes what a call in another thread checks or accepts (issue 24, item 4).

One thread solves a problem in a loop; a residual of the problem's terminal node pauses the solve (in the
middle of an iteration, on the solve's trusted path) while the other thread calls ``calc``/``calcDiff`` of
action models, differential models, states, actuations, cost sums, costs, residuals and activations with
lists, column vectors and NaN, and ``calcDiff`` before ``calc``.  Each call's outcome (the data it filled,
or the error it raised) must equal the same call made alone, and every solve of the loop must equal the
solve made alone.  Two problems: a free-dynamics arm solved on the Python path, and a contact quadruped
whose running nodes are compiled.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager

import numpy as np
import pytest
from node_checks import make_solver

import crocopy
from crocopy import guards
from crocopy.problems import arm, quadruped
from crocopy.solvers import compiled_nodes

WAIT_S = 120.0
"""Longest wait for the other thread (a first solve may compile kernels)."""

FIELDS = ("cost", "xnext", "xout", "Fx", "Fu", "Lx", "Lu", "Lxx", "Lxu", "Luu", "r", "Rx", "Ru", "a_value", "Ar",
          "Arr", "tau", "dtau_dx", "dtau_du")
"""Data fields compared besides the data's own attributes (some are descriptors)."""


class Gate:
    """Pauses the solving thread once per :meth:`overlap`, inside the solve, while the other thread calls."""

    def __init__(self) -> None:
        self._armed: tuple[threading.Event, threading.Event] | None = None
        self.checked_inside: list[bool] = []
        """``guards.checking()`` of the solving thread at each pause (False: on a solve's trusted path)."""

    def pause_here(self) -> None:
        """Called by the solving thread: wait here if an overlap was asked for."""
        armed, self._armed = self._armed, None
        if armed is None:
            return
        inside, release = armed
        self.checked_inside.append(guards.checking())
        inside.set()
        release.wait(WAIT_S)

    @contextmanager
    def overlap(self) -> Iterator[None]:
        """Run the body while the solving thread is paused inside a solve."""
        inside, release = threading.Event(), threading.Event()
        self._armed = (inside, release)
        try:
            assert inside.wait(WAIT_S), "the solve never reached the pause"
            yield
        finally:
            release.set()


class PausingResidual(crocopy.ResidualModelAbstract):
    """A zero residual (exact zero derivatives) whose ``calc`` calls ``gate.pause_here()``."""

    def __init__(self, state: crocopy.StateAbstract, nu: int, gate: Gate) -> None:
        super().__init__(state, 1, nu)
        self.gate = gate

    def calc(self, data, x, u=None):
        data.r[:] = 0.0
        self.gate.pause_here()

    def calcDiff(self, data, x, u=None):
        data.Rx[:] = 0.0
        data.Ru[:] = 0.0


def with_pause(problem: crocopy.ShootingProblem, gate: Gate) -> crocopy.ShootingProblem:
    """``problem`` with a pausing cost in its terminal node (new datas)."""
    dam = problem.terminalModel.differential
    pause = crocopy.CostModelResidual(dam.state, PausingResidual(dam.state, dam.costs.nu, gate))
    dam.costs.addCost("pause", pause, 1.0)
    return crocopy.ShootingProblem(problem.x0, problem.runningModels, problem.terminalModel)


def snapshot(data: object) -> dict:
    """Copies of ``data``'s arrays and numbers."""
    names = set(vars(data)) | set(FIELDS)
    out = {}
    for name in sorted(names):
        value = getattr(data, name, None)
        if isinstance(value, (np.ndarray, float, int)) and not isinstance(value, bool):
            out[name] = np.array(value, copy=True)
    return out


def outcome(call: Callable[[], object]) -> tuple:
    """``("ok", result)`` or ``("raised", error type, message)``."""
    try:
        return ("ok", call())
    except Exception as e:  # noqa: BLE001 (the error itself is the outcome compared)
        return ("raised", type(e), str(e))


def same(alone: object, during: object) -> bool:
    """Whether two outcomes are equal: the same structure, arrays equal entry by entry (NaN equal to NaN)."""
    if isinstance(alone, dict):
        return isinstance(during, dict) and alone.keys() == during.keys() and all(same(alone[k], during[k])
                                                                                 for k in alone)
    if isinstance(alone, (tuple, list)):
        return (isinstance(during, (tuple, list)) and len(alone) == len(during)
                and all(same(a, b) for a, b in zip(alone, during)))
    if isinstance(alone, np.ndarray):
        return (isinstance(during, np.ndarray) and alone.shape == during.shape
                and bool(np.array_equal(alone, during, equal_nan=True)))
    return alone == during


def calls_on(problem: crocopy.ShootingProblem) -> dict[str, tuple[Callable[[], object], bool]]:
    """Calls on the models of ``problem``'s first and last nodes: name -> (call, expected to succeed alone)."""
    node, terminal = problem.runningModels[0], problem.terminalModel
    dam, state = node.differential, node.state
    costs = dam.costs
    x = state.integrate(problem.x0, np.linspace(-0.1, 0.1, state.ndx))
    u = np.linspace(0.5, 1.5, node.nu)
    x_list, x_column, u_column = x.tolist(), x.reshape(-1, 1), u.reshape(-1, 1)
    dx_column = np.linspace(0.2, -0.2, state.ndx).reshape(-1, 1)
    x_nan = x.copy()
    x_nan[1] = np.nan

    def action(model, method: str, x_arg, u_arg=None) -> Callable[[], dict]:
        def call():
            data = model.createData()  # never evaluated: calcDiff runs calc first
            getattr(model, method)(data, x_arg) if u_arg is None else getattr(model, method)(data, x_arg, u_arg)
            return snapshot(data)
        return call

    def part(model, method: str, data_of: Callable, *args) -> Callable[[], dict]:
        def call():
            data = data_of(dam.createData())
            getattr(model, method)(data, *args)
            return snapshot(data)
        return call

    calls = {}
    for label, model in (("node", node), ("differential", dam)):
        calls[f"{label}.calc(list, column)"] = (action(model, "calc", x_list, u_column), True)
        calls[f"{label}.calcDiff before calc"] = (action(model, "calcDiff", x_column, u.tolist()), True)
        calls[f"{label}.calc(NaN)"] = (action(model, "calc", x_nan, u), False)
        calls[f"{label}.calcDiff(u of wrong size)"] = (action(model, "calcDiff", x, np.ones(node.nu + 1)), False)
    calls["terminal.calc(column)"] = (action(terminal, "calc", x_column), True)
    calls["terminal.calcDiff before calc"] = (action(terminal, "calcDiff", x_list), True)
    calls["state.diff(list, column)"] = (lambda: state.diff(x_list, x_column), True)
    calls["state.integrate(list, column)"] = (lambda: state.integrate(x_list, dx_column), True)
    calls["state.Jdiff(list, column)"] = (lambda: state.Jdiff(x_list, x_column), True)
    calls["state.Jintegrate(column, list)"] = (lambda: state.Jintegrate(x_column, dx_column.ravel().tolist()), True)
    calls["state.diff(NaN)"] = (lambda: state.diff(x, x_nan), False)
    actuation = dam.actuation
    for method in ("calc", "calcDiff"):
        calls[f"actuation.{method}(list, column)"] = (
            part(actuation, method, lambda d: d.multibody.actuation, x_list, u_column), True)
        calls[f"costs.{method}(list, column)"] = (part(costs, method, lambda d: d.costs, x_list, u_column), True)
    calls["costs.calc(NaN)"] = (part(costs, "calc", lambda d: d.costs, x_nan, u), False)
    for name, item in costs.costs.items():
        cost, residual, activation = item.cost, item.cost.residual, item.cost.activation
        r = np.linspace(-1.0, 1.0, residual.nr)
        calls[f"cost {name}.calc(list, column)"] = (
            part(cost, "calc", lambda d, n=name: d.costs.costs[n], x_list, u_column), True)
        calls[f"residual {name}.calc(column, list)"] = (
            part(residual, "calc", lambda d, n=name: d.costs.costs[n].residual, x_column, u.tolist()), True)
        calls[f"residual {name}.calcDiff(NaN)"] = (
            part(residual, "calcDiff", lambda d, n=name: d.costs.costs[n].residual, x_nan, u), False)
        calls[f"activation {name}.calcDiff(list)"] = (
            part(activation, "calcDiff", lambda d, n=name: d.costs.costs[n].activation, r.tolist()), True)
        calls[f"activation {name}.calc(column)"] = (
            part(activation, "calc", lambda d, n=name: d.costs.costs[n].activation, r.reshape(-1, 1)), True)
    return calls


def overlapping_calls(build: Callable[[], tuple], compiled: bool) -> None:
    """Solve ``build()``'s problem in a loop in one thread; make every call of :func:`calls_on` (on a second
    build) once alone and once while the solve is paused; compare."""
    gate = Gate()
    problem, xs, us = build()
    problem = with_pause(problem, gate)
    reference = make_solver("SolverFDDP", problem, compiled)
    assert (compiled_nodes.select(reference) is not None) == compiled
    reference.solve(xs, us, 30)
    expected = (reference.iter, reference.cost)
    other = build()[0]
    calls = calls_on(other)
    alone = {name: outcome(call) for name, (call, _) in calls.items()}
    for name, (_, succeeds) in calls.items():
        if succeeds:
            assert alone[name][0] == "ok", (name, alone[name])
        else:
            assert alone[name][0] == "raised" and issubclass(alone[name][1], ValueError), (name, alone[name])

    stop, solves, errors = threading.Event(), [], []

    def solving():
        try:
            while not stop.is_set():
                solver = make_solver("SolverFDDP", problem, compiled)
                solver.solve(xs, us, 30)
                solves.append((solver.iter, solver.cost))
        except BaseException as e:  # noqa: BLE001 (reported by the main thread)
            errors.append(e)

    thread = threading.Thread(target=solving, daemon=True)
    thread.start()
    during = {}
    try:
        for name, (call, _) in calls.items():
            with gate.overlap():
                during[name] = outcome(call)
    finally:
        stop.set()
        thread.join(WAIT_S)
    assert not thread.is_alive() and errors == []
    assert gate.checked_inside == [False] * len(calls)  # every call overlapped a paused solve's trusted path
    assert solves and all(s == expected for s in solves)
    assert [name for name in calls if not same(alone[name], during[name])] == []


def test_calls_during_a_python_path_solve_equal_calls_alone():
    overlapping_calls(lambda: arm.build_arm_reaching(crocopy, nodes=8), compiled=False)


def test_calls_during_a_compiled_solve_equal_calls_alone():
    overlapping_calls(
        lambda: quadruped.build_gait(crocopy, "trot", cycles=1, step_knots=4, support_knots=1), compiled=True
    )


def test_trust_belongs_to_the_thread_that_enters_the_trusted_path():
    model = crocopy.ActionModelUnicycle()
    entered, leave, seen = threading.Event(), threading.Event(), []

    def trusted():
        with guards.trusted_path():
            seen.append(guards.checking())
            entered.set()
            leave.wait(WAIT_S)
        seen.append(guards.checking())

    thread = threading.Thread(target=trusted)
    thread.start()
    try:
        assert entered.wait(WAIT_S)
        assert guards.checking()
        data = model.createData()
        model.calc(data, [1.0, 2.0, 0.5], [[0.1], [0.2]])
        with pytest.raises(ValueError, match=r"x contains NaN or inf \(x\[0\] = nan\)"):
            model.calc(data, [np.nan, 2.0, 0.5], [0.1, 0.2])
    finally:
        leave.set()
        thread.join(WAIT_S)
    assert seen == [False, True]
    alone = model.createData()
    model.calc(alone, np.array([1.0, 2.0, 0.5]), np.array([0.1, 0.2]))
    assert same(snapshot(alone), snapshot(data))


def test_two_threads_solving_at_once_equal_solves_alone():
    def problem():
        m = crocopy.ActionModelUnicycle()
        m.costWeights = np.array([10.0, 1.0])
        return crocopy.ShootingProblem(np.array([-1.0, -1.0, 1.0]), [m] * 30, m)

    def solve():
        solver = crocopy.SolverFDDP(problem())
        solver.solve([], [], 50)
        return solver.iter, solver.cost, np.concatenate([*solver.xs, *solver.us])

    alone = solve()
    results: list[list] = [[], []]
    start = threading.Barrier(2)

    def loop(out: list) -> None:
        start.wait(WAIT_S)
        for _ in range(20):
            out.append(solve())

    threads = [threading.Thread(target=loop, args=(out,)) for out in results]
    for t in threads:
        t.start()
    for t in threads:
        t.join(WAIT_S)
    assert [len(out) for out in results] == [20, 20]
    for out in results:
        for iters, cost, z in out:
            assert (iters, cost) == alone[:2]
            np.testing.assert_array_equal(z, alone[2])
