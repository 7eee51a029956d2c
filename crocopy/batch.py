"""Many solves at once on any :class:`concurrent.futures.Executor`.

:func:`solve_many` builds and solves one problem per entry of ``params`` and returns one
:class:`SolveResult` per entry, in the order of ``params``::

    import crocopy
    from crocopy.problems import registry

    builder = registry.get("quad-goal").build  # build(**overrides) -> (problem, xs, us)
    starts = [{"x0_position": (x, 0.0, 0.0)} for x in (-0.9, -0.3, 0.3)]
    results = crocopy.solve_many(builder, starts, maxiter=300)
    best = min(results, key=lambda r: r.cost)

Each task runs ``builder(**p)`` in a worker, which returns either a :class:`ShootingProblem` (the
solver then starts from its default guess) or ``(problem, xs, us)`` (Crocoddyl's examples and
:mod:`crocopy.problems` builders: the guess is ``xs, us``).  Instead of a builder, an already built
:class:`ShootingProblem` can be given: it is pickled to the workers (its datas are not: each copy
allocates its own) and each ``params`` entry may set ``x0``, ``init_xs`` and ``init_us``.

Executors.  By default a local :class:`~concurrent.futures.ProcessPoolExecutor` with one worker
per available core (at most one per task) is created and shut down; Pinocchio holds the GIL, so
threads give no speed-up on multibody problems.  Any executor with the ``submit`` interface plugs
in: a ``ThreadPoolExecutor``, ``dask.distributed.Client.get_executor()``, Ray's
``ray.util.concurrent.futures`` executor, ...  A process pool pickles the builder, so it must be a
module-level function or a :func:`functools.partial` of one (no lambda or local function, and no
module among its arguments: a registry entry's ``ProblemSpec.build`` is picklable);
:func:`solve_many` checks this first and raises ``ValueError`` otherwise.  Set
``OMP_NUM_THREADS=1`` so that the workers' BLAS threads do not compete for the cores.

Errors.  If a task raises, :func:`solve_many` cancels the tasks not yet started and raises
:class:`SolveManyError` naming the task index and its ``params``, chained to the worker's
exception; with ``return_exceptions=True`` the exception takes the task's place in the list.

A worker that dies (a segfault, an out-of-memory kill, ``os._exit``) breaks a process pool and every
task still in it.  :func:`solve_many` then keeps the results already returned and reruns each
unfinished task in a process of its own (as many at once as the pool had workers): the task whose
process dies again is the one that killed the pool, and it alone fails, with a
:class:`WorkerDiedError` giving its exit code or signal; the others complete.
"""

from __future__ import annotations

import multiprocessing
import os
import pickle
import signal
import time
from collections.abc import Callable, Iterable, Mapping
from concurrent.futures import Executor, Future, ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass, field

import numpy as np

from .shooting import ShootingProblem
from .solvers.box_fddp import SolverBoxFDDP

__all__ = ["SolveManyError", "SolveResult", "WorkerDiedError", "solve_many", "solve_one"]

_PROBLEM_KEYS = frozenset({"x0", "init_xs", "init_us"})


class SolveManyError(RuntimeError):
    """A task of :func:`solve_many` failed; ``index`` and ``params`` identify it, ``__cause__`` is
    the worker's exception."""

    def __init__(self, index: int, params: Mapping, error: BaseException) -> None:
        super().__init__(f"solve {index} with params {dict(params)!r} failed: {type(error).__name__}: {error}")
        self.index = index
        self.params = params


class WorkerDiedError(RuntimeError):
    """The process running a task died before returning (``exitcode``: its exit status, or minus the
    signal number that killed it, as :attr:`multiprocessing.Process.exitcode`)."""

    def __init__(self, exitcode: int | None) -> None:
        if exitcode is not None and exitcode < 0:
            try:
                how = f"killed by signal {signal.Signals(-exitcode).name}"
            except ValueError:
                how = f"killed by signal {-exitcode}"
        else:
            how = f"exit code {exitcode}"
        super().__init__(f"the worker process died ({how})")
        self.exitcode = exitcode


@dataclass
class SolveResult:
    """Outcome of one solve (the solver's attributes of the same names at return).

    Attributes
    ----------
    xs, us : list of numpy.ndarray
        Final state (T+1) and control (T) trajectories.
    cost : float
        Final total cost.
    iter : int
        Iterations performed (``solver.iter``).
    converged : bool
        Return value of ``solver.solve``.
    reason : str
        Why the solver stopped (``solver.reason``: ``"converged"`` or the failure).
    params : dict
        The task's ``params`` entry.
    time : float
        Wall time of build and solve in the worker (s).
    cpu_time : float
        CPU time of the worker's process during build and solve (s).
    """

    xs: list[np.ndarray]
    us: list[np.ndarray]
    cost: float
    iter: int
    converged: bool
    reason: str
    params: dict = field(default_factory=dict)
    time: float = 0.0
    cpu_time: float = 0.0


def solve_one(
    builder: Callable[..., object] | ShootingProblem,
    params: Mapping | None = None,
    solver: Callable[[ShootingProblem], object] = SolverBoxFDDP,
    maxiter: int = 100,
    isFeasible: bool = False,
    solver_options: Mapping | None = None,
) -> SolveResult:
    """Build (or take) one problem, solve it and return its :class:`SolveResult`.

    This is what a :func:`solve_many` worker runs; the arguments are those of :func:`solve_many`
    with one ``params`` entry.
    """
    t0, c0 = time.perf_counter(), time.process_time()
    params = dict(params or {})
    init_xs = init_us = None
    if isinstance(builder, ShootingProblem):
        unknown = params.keys() - _PROBLEM_KEYS
        if unknown:
            raise KeyError(f"params for a built problem may set {sorted(_PROBLEM_KEYS)}, got {sorted(unknown)}")
        problem = pickle.loads(pickle.dumps(builder))  # a private copy, also under threads
        if "x0" in params:
            problem.x0 = params["x0"]
        init_xs, init_us = params.get("init_xs"), params.get("init_us")
    else:
        built = builder(**params)
        if isinstance(built, ShootingProblem):
            problem = built
        elif isinstance(built, tuple) and len(built) == 3 and isinstance(built[0], ShootingProblem):
            problem, init_xs, init_us = built
        else:
            raise ValueError(f"builder must return a ShootingProblem or (problem, xs, us), got {type(built).__name__}")
    s = solver(problem)
    for name, value in (solver_options or {}).items():
        if not hasattr(s, name):
            raise KeyError(f"solver_options: {type(s).__name__} has no attribute {name!r}")
        setattr(s, name, value)
    converged = bool(s.solve(init_xs, init_us, maxiter, isFeasible))
    return SolveResult(
        xs=[np.array(x) for x in s.xs],
        us=[np.array(u) for u in s.us],
        cost=float(s.cost),
        iter=int(s.iter),
        converged=converged,
        reason=str(getattr(s, "reason", "")),
        params=params,
        time=time.perf_counter() - t0,
        cpu_time=time.process_time() - c0,
    )


def available_cores() -> int:
    """Cores this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


def solve_many(
    builder: Callable[..., object] | ShootingProblem,
    params: Iterable[Mapping],
    executor: Executor | None = None,
    *,
    solver: Callable[[ShootingProblem], object] = SolverBoxFDDP,
    maxiter: int = 100,
    isFeasible: bool = False,
    solver_options: Mapping | None = None,
    max_workers: int | None = None,
    return_exceptions: bool = False,
) -> list[SolveResult | BaseException]:
    """Solve one problem per ``params`` entry on ``executor``; results in the order of ``params``.

    Parameters
    ----------
    builder : callable or ShootingProblem
        ``builder(**p)`` returns a ``ShootingProblem`` or ``(problem, xs, us)``; or a built problem
        (then each ``p`` may only set ``x0``, ``init_xs``, ``init_us``).
    params : iterable of mapping
        One keyword-argument dict per solve (``{}`` for a builder without arguments).
    executor : concurrent.futures.Executor, optional
        Where the tasks run (its ``submit`` is used).  Default: a process pool of ``max_workers``
        workers, created for this call and shut down after it.
    solver : callable
        Solver class (or factory) called with the problem; default :class:`SolverBoxFDDP`.
    maxiter : int
        Iteration limit of each solve.
    isFeasible : bool
        Passed to ``solve`` (whether the guess is a rollout).
    solver_options : mapping, optional
        Solver attributes set before solving (e.g. ``{"th_stop": 1e-10}``).
    max_workers : int, optional
        Size of the default process pool (default: the available cores, at most one per task).
    return_exceptions : bool
        Put a failed task's exception in the list instead of raising :class:`SolveManyError`.

    Returns
    -------
    list of SolveResult
        One per ``params`` entry, in order.
    """
    if not (callable(builder) or isinstance(builder, ShootingProblem)):
        raise ValueError(f"builder must be callable or a ShootingProblem, got {type(builder).__name__}")
    params = list(params)
    for i, p in enumerate(params):
        if not isinstance(p, Mapping):
            raise ValueError(f"params[{i}] must be a mapping of keyword arguments, got {type(p).__name__}")
    if maxiter < 0:
        raise ValueError(f"maxiter must be non-negative, got {maxiter}")
    if not params:
        return []
    own = executor is None
    if own:
        workers = min(max_workers or available_cores(), len(params))
        if workers < 1:
            raise ValueError(f"max_workers must be positive, got {max_workers}")
        executor = ProcessPoolExecutor(workers)
    try:
        if isinstance(executor, ProcessPoolExecutor):
            _check_picklable(builder=builder, solver=solver, solver_options=solver_options)
        task = (solver, maxiter, isFeasible, solver_options)
        futures = [executor.submit(solve_one, builder, p, *task) for p in params]
        outcomes = _collect(futures, params, return_exceptions)
        if any(isinstance(o, BrokenProcessPool) for o in outcomes):
            executor.shutdown(wait=True, cancel_futures=True)
            broken = [i for i, o in enumerate(outcomes) if isinstance(o, BrokenProcessPool)]
            workers = getattr(executor, "_max_workers", None) or available_cores()
            for i, outcome in zip(broken, _run_isolated(builder, [params[i] for i in broken], task, workers)):
                outcomes[i] = outcome
        return _results(outcomes, params, return_exceptions)
    finally:
        if own:
            executor.shutdown(wait=True, cancel_futures=True)


def _check_picklable(**objects: object) -> None:
    for name, obj in objects.items():
        try:
            pickle.dumps(obj)
        except (pickle.PicklingError, AttributeError, TypeError) as exc:
            raise ValueError(
                f"{name} must be picklable for a process pool (a module-level function or a functools.partial "
                f"of one, not a lambda or local function): {exc}"
            ) from exc


def _collect(futures: list[Future], params: list[Mapping], return_exceptions: bool) -> list:
    """Each future's result or exception, in order.  A task's own exception is raised at once (the tasks
    not yet started are cancelled) unless ``return_exceptions``; a broken pool's are kept for a rerun."""
    outcomes: list = []
    for i, (future, p) in enumerate(zip(futures, params, strict=True)):
        try:
            outcomes.append(future.result())
        except BrokenProcessPool as exc:
            outcomes.append(exc)
        except Exception as exc:
            if not return_exceptions:
                for f in futures[i + 1 :]:
                    f.cancel()
                raise SolveManyError(i, p, exc) from exc
            outcomes.append(exc)
    return outcomes


def _results(outcomes: list, params: list[Mapping], return_exceptions: bool) -> list:
    for i, (outcome, p) in enumerate(zip(outcomes, params, strict=True)):
        if isinstance(outcome, BaseException) and not return_exceptions:
            raise SolveManyError(i, p, outcome) from outcome
    return outcomes


def _isolated_task(conn, builder, params, task) -> None:
    try:
        conn.send(solve_one(builder, params, *task))
    except Exception as exc:
        conn.send(exc)
    finally:
        conn.close()


def _run_isolated(builder, params: list[Mapping], task: tuple, workers: int) -> list:
    """Run each task in a process of its own, ``workers`` at a time; a dead process is its task's failure."""
    context = multiprocessing.get_context()
    outcomes: list = [None] * len(params)
    for start in range(0, len(params), max(1, workers)):
        running = []
        for i in range(start, min(start + max(1, workers), len(params))):
            receive, send = context.Pipe(duplex=False)
            process = context.Process(target=_isolated_task, args=(send, builder, params[i], task))
            process.start()
            send.close()
            running.append((i, process, receive))
        for i, process, receive in running:
            try:
                outcomes[i] = receive.recv()
            except EOFError:
                outcomes[i] = None
            process.join()
            receive.close()
            if outcomes[i] is None:
                outcomes[i] = WorkerDiedError(process.exitcode)
    return outcomes
