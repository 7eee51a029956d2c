"""Crocoddyl's profiler: a shared stop-watch that times named tasks while it is enabled.

``enable_profiler()`` / ``disable_profiler()`` switch it (off by default).  While it is on, the
solvers' ``solve``, ``computeDirection``, ``calcDiff``, ``backwardPass``, ``tryStep`` and
``forwardPass`` are timed under ``"ClassName::method"`` names (the class that defines the method,
e.g. ``"SolverDDP::backwardPass"``); :func:`profiled` times any other function.
``stop_watch_report(precision)`` prints, per task, the minimum, average, maximum, last and total
wall-clock times in milliseconds and the number of samples; ``stop_watch_get_*_time(name)``
return seconds (``KeyError`` for a task never timed); ``stop_watch_reset_all()`` forgets them.
"""

from __future__ import annotations

import functools
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

__all__ = [
    "disable_profiler",
    "enable_profiler",
    "profiled",
    "stop_watch_get_average_time",
    "stop_watch_get_max_time",
    "stop_watch_get_min_time",
    "stop_watch_get_total_time",
    "stop_watch_report",
    "stop_watch_reset_all",
]


@dataclass
class _Task:
    """Samples of one task, in seconds."""

    count: int = 0
    total: float = 0.0
    min: float = float("inf")
    max: float = 0.0
    last: float = 0.0

    def add(self, seconds: float) -> None:
        self.count += 1
        self.total += seconds
        self.min = min(self.min, seconds)
        self.max = max(self.max, seconds)
        self.last = seconds


class _StopWatch:
    enabled = False
    tasks: dict[str, _Task] = {}


def enable_profiler() -> None:
    """Start timing the profiled functions."""
    _StopWatch.enabled = True


def disable_profiler() -> None:
    """Stop timing (the samples taken so far are kept)."""
    _StopWatch.enabled = False


def profiling() -> bool:
    """Whether the profiler is enabled (what it times must then run as the timed methods)."""
    return _StopWatch.enabled


def profiled(name: str, func: Callable) -> Callable:
    """``func`` timed under ``name`` whenever the profiler is enabled (a plain call otherwise)."""

    @functools.wraps(func)
    def timed(*args: Any, **kwargs: Any) -> Any:
        if not _StopWatch.enabled:
            return func(*args, **kwargs)
        start = time.perf_counter()
        try:
            return func(*args, **kwargs)
        finally:
            _StopWatch.tasks.setdefault(name, _Task()).add(time.perf_counter() - start)

    return timed


def _task(name: str) -> _Task:
    try:
        return _StopWatch.tasks[name]
    except KeyError:
        known = ", ".join(sorted(_StopWatch.tasks)) or "none (is the profiler enabled?)"
        raise KeyError(f"the stop-watch has no task {name!r}; timed tasks: {known}") from None


def stop_watch_get_average_time(name: str) -> float:
    """Average time of task ``name``, in seconds."""
    task = _task(name)
    return task.total / task.count


def stop_watch_get_max_time(name: str) -> float:
    """Longest time of task ``name``, in seconds."""
    return _task(name).max


def stop_watch_get_min_time(name: str) -> float:
    """Shortest time of task ``name``, in seconds."""
    return _task(name).min


def stop_watch_get_total_time(name: str) -> float:
    """Total time spent in task ``name``, in seconds."""
    return _task(name).total


def stop_watch_reset_all() -> None:
    """Forget every sample."""
    _StopWatch.tasks.clear()


def stop_watch_report(precision: int = 3) -> None:
    """Print the timed tasks (milliseconds, ``precision`` decimals), sorted by name."""
    columns = ("min", "avg", "max", "lastTime", "nSamples", "totalTime")
    width = max([len(name) for name in _StopWatch.tasks] + [40]) + 2
    print("*** PROFILING RESULTS [ms]".ljust(width) + "".join(c.rjust(12) for c in columns) + "  ***")
    for name in sorted(_StopWatch.tasks):
        task = _StopWatch.tasks[name]
        times = (task.min, task.total / task.count, task.max, task.last)
        cells = [f"{1e3 * t:.{precision}f}" for t in times] + [str(task.count), f"{1e3 * task.total:.{precision}f}"]
        print(name.ljust(width) + "".join(c.rjust(12) for c in cells))
