"""``crocopy compile``'s warm-up solves: together they call every kernel with the argument types the bundled
problems give them, so that a later solve finds them all in the cache."""

from __future__ import annotations

from collections.abc import Callable
from types import ModuleType

COMPILE_RUNS = (("jump", ("boxfddp", "fddp", "ddp", "boxddp")), ("pend", ("fddp", "boxfddp")), ("arm", ("fddp",)))
"""Bundled problem → the keys of the solvers run on it."""


def terminal_equality_reach(lib: ModuleType) -> tuple:
    """mim-solvers' UR5 reach with a terminal equality row (CSQP's kernel that reads the rows)."""
    from .mim import build_problem

    return build_problem(lib, "ur5_ee_eq"), [], []


def threaded_python_reach(lib: ModuleType) -> tuple:
    """A short reach whose goal is a Python residual, on two threads: the kernels that re-cost Python residuals'
    nodes and add the ranges' costs."""
    from ..problems.user_residual import build_user_reach

    problem, xs, us = build_user_reach(lib, "python", nodes=10)
    problem.nthreads = 2
    return problem, xs, us


def equality_lq(lib: ModuleType) -> tuple:
    """LQR nodes with two equality rows each (SolverIntro's compiled constrained pass, its LU and ``hfeas``)."""
    import numpy as np

    r = np.random.RandomState(0)
    nx, nu, nh = 4, 3, 2
    running = lib.ActionModelLQR(np.eye(nx), r.randn(nx, nu), np.eye(nx), np.eye(nu), np.zeros((nx, nu)),
                                 np.zeros((0, nx + nu)), r.randn(nh, nx + nu), np.zeros(nx), np.zeros(nx), np.zeros(nu),
                                 np.zeros(0), r.randn(nh))
    return lib.ShootingProblem(np.ones(nx), [running] * 5, lib.ActionModelLQR(nx, nu)), [], []


def warm_up_runs(crocopy: ModuleType, solvers: dict[str, str]) -> list[tuple[Callable, list[type]]]:
    """``(builder, solver classes)`` pairs: :data:`COMPILE_RUNS` (``solvers`` maps a key to a class name), SQP and
    CSQP on the arm (their QP and glue kernels), the threaded Python-residual reach (FDDP, SQP), the terminal
    equality reach (CSQP) and LQR nodes with equality rows (SolverIntro)."""
    from ..problems import registry

    runs = [(registry.get(name).build, [getattr(crocopy, solvers[k]) for k in keys]) for name, keys in COMPILE_RUNS]
    runs.append((registry.get("arm").build, [crocopy.SolverSQP, crocopy.SolverCSQP]))
    runs.append((threaded_python_reach, [crocopy.SolverFDDP, crocopy.SolverSQP]))
    runs.append((terminal_equality_reach, [crocopy.SolverCSQP]))
    runs.append((equality_lq, [crocopy.SolverIntro]))
    return runs
