"""Small problems and solver factories shared by the solver NaN/inf tests and the solver fuzz.

``integrator_problem`` is ``q̈ = u`` (Euler, ``nq`` joints) with a :class:`crocopy.CostModelSum` of
named items ``"state"``/``"control"``/``"goal"``, so every solver runs on it, HDDP included
(levels ``[["goal"], ["state", "control"]]``).  :func:`poison` makes one node write NaN into one
derivative from its ``after``-th ``calcDiff`` on.
"""

from __future__ import annotations

import numpy as np

import crocopy


class DAMDoubleIntegrator(crocopy.DifferentialActionModelAbstract):
    """``q̈ = u`` with a cost stack; ``x = (q, v)``, ``nu = nq``."""

    def __init__(self, costs: crocopy.CostModelSum, nq: int) -> None:
        super().__init__(costs.state, nq, 1)
        self.costs = costs

    def createData(self):
        data = crocopy.DifferentialActionDataAbstract(self)
        data.costs = self.costs.createData(crocopy.DataCollectorAbstract())
        return data

    def calc(self, data, x, u=None):
        data.xout[:] = 0.0 if u is None else u
        self.costs.calc(data.costs, x, u)
        data.cost = data.costs.cost

    def calcDiff(self, data, x, u=None):
        data.Fx[:] = 0.0
        data.Fu[:] = np.eye(self.nu)
        self.costs.calcDiff(data.costs, x, u)
        for name in ("Lx", "Lxx") if u is None else ("Lx", "Lu", "Lxx", "Lxu", "Luu"):
            getattr(data, name)[:] = getattr(data.costs, name)


def integrator_problem(T: int = 8, nq: int = 2, dt: float = 0.1, w_state: float = 1e-2, w_control: float = 1e-2,
                       w_goal: float = 10.0, x0=None, goal=None, u_bound: float = np.inf) -> crocopy.ShootingProblem:
    """``q̈ = u`` over ``T`` Euler steps of ``dt``, from ``x0`` (default ones) to ``goal`` (default zeros)."""
    state = crocopy.StateVector(2 * nq)
    x0 = np.ones(2 * nq) if x0 is None else np.asarray(x0, dtype=float)
    goal = np.zeros(2 * nq) if goal is None else np.asarray(goal, dtype=float)
    running, terminal = crocopy.CostModelSum(state, nq), crocopy.CostModelSum(state, nq)
    running.addCost("state", crocopy.CostModelResidual(state, crocopy.ResidualModelState(state, goal, nq)), w_state)
    running.addCost("control", crocopy.CostModelResidual(state, crocopy.ResidualModelControl(state, nq)), w_control)
    terminal.addCost("goal", crocopy.CostModelResidual(state, crocopy.ResidualModelState(state, goal, nq)), w_goal)
    rm = crocopy.IntegratedActionModelEuler(DAMDoubleIntegrator(running, nq), dt)
    if np.isfinite(u_bound):
        rm.u_lb, rm.u_ub = -u_bound * np.ones(nq), u_bound * np.ones(nq)
    tm = crocopy.IntegratedActionModelEuler(DAMDoubleIntegrator(terminal, nq), 0.0)
    return crocopy.ShootingProblem(x0, [rm] * T, tm)


class DAMPoisoned(DAMDoubleIntegrator):
    """:class:`DAMDoubleIntegrator` writing NaN into ``data.<quantity>`` from its ``after``-th ``calcDiff`` on."""

    def __init__(self, costs: crocopy.CostModelSum, nq: int, quantity: str, after: int) -> None:
        super().__init__(costs, nq)
        self.quantity, self.after, self.calls = quantity, after, 0

    def calcDiff(self, data, x, u=None):
        super().calcDiff(data, x, u)
        if self.calls >= self.after:
            getattr(data, self.quantity).flat[0] = np.nan
        self.calls += 1


def poison(problem: crocopy.ShootingProblem, node: int, quantity: str, after: int = 0) -> DAMPoisoned:
    """Replace node ``node`` (T: the terminal one) of an :func:`integrator_problem` by a copy whose
    differential model writes NaN into ``quantity`` (``"Fx"``, ``"Fu"``, ``"Lx"``, ...) from its
    ``after``-th ``calcDiff`` on; the integrated node's same quantity is then NaN."""
    model = problem.terminalModel if node == problem.T else problem.runningModels[node]
    dam = DAMPoisoned(model.differential.costs, model.nu, quantity, after)
    bad = crocopy.IntegratedActionModelEuler(dam, model.dt)
    bad.u_lb, bad.u_ub = model.u_lb, model.u_ub
    problem.updateModel(node, bad)
    return dam


def _clamped(kind: str):
    return lambda p: crocopy.SolverClampedDDP(p, kind)


#: Every solver of crocopy, as a factory of a problem built by :func:`integrator_problem`.
SOLVERS = {
    "DDP": crocopy.SolverDDP,
    "FDDP": crocopy.SolverFDDP,
    "BoxDDP": crocopy.SolverBoxDDP,
    "BoxFDDP": crocopy.SolverBoxFDDP,
    "ClampedForward": _clamped("forward"),
    "ClampedBackward": _clamped("backward"),
    "Projection": crocopy.SolverProjection,
    "HDDP": lambda p: crocopy.SolverHDDP(p, [["goal"], ["state", "control"]]),
}


def check_outcome(solver, problem: crocopy.ShootingProblem) -> None:
    """The iterate a solve left: shapes, finiteness, and ``cost`` equal to the cost of ``(xs, us)``."""
    assert len(solver.xs) == problem.T + 1 and len(solver.us) == problem.T
    models = [*problem.runningModels, problem.terminalModel]
    for x, m in zip(solver.xs, models):
        assert x.shape == (m.state.nx,) and np.isfinite(x).all()
    for u, m in zip(solver.us, problem.runningModels):
        assert u.shape == (m.nu,) and np.isfinite(u).all()
    assert np.isfinite(solver.cost)
    recomputed = problem.calc(list(solver.xs), list(solver.us))
    assert np.isclose(solver.cost, recomputed, rtol=1e-9, atol=1e-12), (solver.cost, recomputed)
