"""``crocopy bench --batch``: many solves serially and with :func:`crocopy.solve_many`.

The workload is the Box-FDDP paper's Fig. 7 setup (:mod:`crocopy.experiments.box_fddp`): the IRIS
quadrotor goal task (:func:`crocopy.problems.quadrotor.build_quadrotor`, registry entry
``quad-goal``) from the 10 initial positions ``(-0.3 ± 0.6, 0, 0)`` m of
:func:`crocopy.experiments.box_fddp.initial_positions`, cold start, Box-FDDP, at most 300 iterations.

Each repetition times, interleaved so that load drift hits both: the 10 build+solve tasks one after
the other in this process, then the same tasks through :func:`crocopy.solve_many` on a fresh
process pool of ``workers`` processes (pool start-up and result transfer included).  One solve
runs before timing, so that the numba kernels are loaded in this process (forked workers inherit
them; otherwise each worker pays the ~1–2 s cache load on its first solve).  Reported: median
wall times, the speed-up (serial / parallel) and a check that both give the same costs and
iterations.

On a shared machine the wall-clock ratio says little: Linux groups a login session's processes
(scheduler autogroups), and under load from other sessions the group receives one share of the
cores however many processes it runs.  So the CPU time is also measured — of the serial loop, and
of each task in its worker — and the pool's schedule replayed with those CPU times (each task to
the first free worker, in order): ``serial CPU / replayed makespan`` is the speed-up on otherwise
idle cores, pool start-up and transfers excluded.  The load average is printed with the figures.
"""

from __future__ import annotations

import heapq
import os
import statistics
import time

from ..batch import available_cores, solve_many, solve_one
from ..solvers.box_fddp import SolverBoxFDDP

__all__ = ["makespan", "run_batch_bench"]


def makespan(durations: list[float], workers: int) -> float:
    """Finish time of ``durations`` run in order by ``workers`` workers, each task to the first free one."""
    if workers < 1:
        raise ValueError(f"workers must be positive, got {workers}")
    free = [0.0] * min(workers, max(len(durations), 1))
    for d in durations:
        heapq.heappush(free, heapq.heappop(free) + d)
    return max(free)


def run_batch_bench(n: int = 10, workers: int = 2, repeats: int = 3, maxiter: int = 300) -> dict:
    """Time ``n`` quadrotor goal solves serially and on ``workers`` processes; print and return the figures.

    Returns
    -------
    dict
        ``serial`` and ``parallel`` (lists of wall times, s), ``speedup`` (ratio of the medians),
        ``serial_cpu`` and ``replayed`` (CPU times, s) and ``cpu_speedup`` (ratio of their medians),
        ``results`` (the parallel :class:`crocopy.batch.SolveResult` list) and ``same`` (whether
        serial and parallel costs and iterations agree).
    """
    from ..experiments.box_fddp import initial_positions
    from ..problems import registry

    if n < 1 or workers < 1 or repeats < 1:
        raise ValueError(f"n, workers and repeats must be positive, got {n}, {workers}, {repeats}")
    builder = registry.get("quad-goal").build
    params = [{"x0_position": tuple(p)} for p in initial_positions(n)]
    solve_one(builder, params[0], SolverBoxFDDP, 1)
    print(
        f"crocopy bench --batch: quad-goal (Box-FDDP paper Fig. 7) from {n} starts, Box-FDDP, maxiter {maxiter};"
        f" serial vs solve_many on {workers} processes ({available_cores()} cores available)"
    )
    serial_t, parallel_t, serial_cpu, replayed = [], [], [], []
    for k in range(repeats):
        t0, c0 = time.perf_counter(), time.process_time()
        serial = [solve_one(builder, p, SolverBoxFDDP, maxiter) for p in params]
        serial_t.append(time.perf_counter() - t0)
        serial_cpu.append(time.process_time() - c0)
        t0 = time.perf_counter()
        parallel = solve_many(builder, params, solver=SolverBoxFDDP, maxiter=maxiter, max_workers=workers)
        parallel_t.append(time.perf_counter() - t0)
        replayed.append(makespan([r.cpu_time for r in parallel], workers))
        print(
            f"  run {k + 1}: wall serial {serial_t[-1]:.2f} s, parallel {parallel_t[-1]:.2f} s;"
            f" CPU serial {serial_cpu[-1]:.2f} s, replayed parallel makespan {replayed[-1]:.2f} s;"
            f" load average {os.getloadavg()[0]:.1f}",
            flush=True,
        )
    same = all(
        (s.cost, s.iter, s.converged) == (p.cost, p.iter, p.converged) for s, p in zip(serial, parallel, strict=True)
    )
    print(f"  {'start x':>8s} {'cost':>12s} {'iter':>5s} {'converged':>9s} {'worker s':>8s} {'CPU s':>6s}")
    for p, r in zip(params, parallel, strict=True):
        print(
            f"  {p['x0_position'][0]:8.3f} {r.cost:12.6g} {r.iter:5d} {str(r.converged):>9s} {r.time:8.2f}"
            f" {r.cpu_time:6.2f}"
        )
    ts, tp = statistics.median(serial_t), statistics.median(parallel_t)
    cs, cp = statistics.median(serial_cpu), statistics.median(replayed)
    print(
        f"  median wall time: serial {ts:.2f} s, solve_many on {workers} processes {tp:.2f} s: speed-up {ts / tp:.2f}x"
        f" (load average {os.getloadavg()[0]:.1f} on {available_cores()} cores)\n"
        f"  median CPU time: serial {cs:.2f} s, replayed {workers}-worker makespan {cp:.2f} s:"
        f" speed-up on idle cores {cs / cp:.2f}x; same costs and iterations: {'yes' if same else 'NO'}"
    )
    return {
        "serial": serial_t,
        "parallel": parallel_t,
        "speedup": ts / tp,
        "serial_cpu": serial_cpu,
        "replayed": replayed,
        "cpu_speedup": cs / cp,
        "results": parallel,
        "same": same,
    }
