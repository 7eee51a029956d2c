"""Crocoddyl's own problems, built by Crocoddyl's own code, timed with crocopy and with Crocoddyl
(the second part of ``crocopy bench --vs crocoddyl``).

A *job* is one of the crocoddyl wheel's example scripts or one of its ``utils`` gait builders, as in
:mod:`crocopy.bench.compat` (whose binding of ``sys.modules["crocoddyl"]`` to crocopy and solve
recorder are reused: the files are executed, never read).  For each job two long-lived worker
processes are started, one per library, each with one BLAS thread:

1. the worker runs the job once (its own solves, callbacks and prints; output discarded), recording
   every outermost ``solve`` call with copies of its arguments;
2. on each ``round`` request it replays each recorded call on the same solver object, without
   callbacks and with ``problem.nthreads = 1`` (full-solve wall time, iterations, final cost), then
   takes one sample of ``problem.calc``, ``problem.calcDiff`` on the solution and of the backward
   pass (``solver.computeDirection(False)``), a short phase looped to last ≥ 20 ms.

The parent asks the two workers in turn, alternating which goes first, for ``repeats`` rounds, and
reports medians: per recorded solve, ms per iteration of the full solve, calc+calcDiff and backward
ms, iterations and final cost of each library and the ratios.  A replay whose iterations or cost
differ from the job's own solve is flagged (the job changed the problem after solving it).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

from ..solvers import compiled_nodes
from . import compat
from .side_by_side import require_crocoddyl
from .timing import limit_threads, loops_for, sample_ms

SHIPPED_JOBS = ("quadruped-walk", "quadruped-trot", "quadruped-jump", "humanoid_taichi", "humanoid_manipulation",
                "quadrotor_fwddyn", "arm_manipulation_fwddyn", "quadrotor_invdyn", "arm_manipulation_invdyn")
"""Default jobs: ANYmal walk/trot/jump (the ``utils`` quadruped builder), Talos taichi and manipulation,
the quadrotor and the arm (shipped examples), with forward and with inverse dynamics (SolverIntro)."""

PHASES = ("calc", "calcDiff", "backward")
WORKER_TIMEOUT = 1800.0


# ------------------------------------------------------------------------------------- the worker
class Worker:
    """In the worker process: the job's recorded solve calls, replayed and timed on request."""

    def __init__(self, library: str, job: str) -> None:
        folder = compat.crocoddyl_folder()
        if library == "crocopy":
            compat.bind_crocopy(folder)
        limit_threads()
        import crocoddyl
        import matplotlib.pyplot as plt

        plt.show = lambda *args, **kwargs: None
        recorded: list[dict[str, Any]] = []
        calls: list[tuple] = []
        compat.record_solves(crocoddyl, recorded, calls)
        compat.execute_job(job, folder)
        self.recorded, self.calls = list(recorded), list(calls)  # the job's own (the replays are recorded too)
        self.loops: dict[tuple[int, str], int] = {}

    def solves(self) -> list[dict[str, Any]]:
        """The job's own solves: solver, iterations, cost, horizon."""
        return [{**rec, "T": int(call[0].problem.T)} for rec, call in zip(self.recorded, self.calls)]

    def round(self) -> list[dict[str, Any]]:
        """Replay every recorded solve and sample its phases: one dict per solve."""
        out = []
        for k, (solver, args, kwargs) in enumerate(self.calls):
            problem = solver.problem
            if problem.nthreads != 1:
                problem.nthreads = 1
            solver.setCallbacks([])
            args_k, kwargs_k = compat._copied(args), {n: compat._copied(v) for n, v in kwargs.items()}
            t0 = time.perf_counter()
            solver.solve(*args_k, **kwargs_k)
            seconds = time.perf_counter() - t0
            calls = phase_calls(solver)
            phases = {}
            for phase in PHASES:
                loops = self.loops.setdefault((k, phase), loops_for(calls[phase]))
                phases[phase] = sample_ms(calls[phase], loops)
            out.append({"seconds": seconds, "iter": int(solver.iter), "cost": float(solver.cost), "phases": phases})
        return out


def phase_calls(solver: Any) -> dict[str, Callable[[], object]]:
    """The timed phases on the solver's solution (evaluated once here, so the backward pass has its data);
    crocopy's as its solve runs them (on compiled nodes where they apply)."""
    problem, xs, us = solver.problem, list(solver.xs), list(solver.us)
    problem.calc(xs, us)
    problem.calcDiff(xs, us)
    calls = {"calc": lambda: problem.calc(xs, us), "calcDiff": lambda: problem.calcDiff(xs, us),
             "backward": lambda: solver.computeDirection(False)}
    nodes = compiled_nodes.attach(solver) if type(solver).__module__.startswith("crocopy.") else None
    if nodes is not None:
        at = solver._addresses()  # the solver's own arrays: their addresses, read once as a solve reads them
        calls["calc"] = lambda: nodes.calc(problem, xs, us, at)
        calls["calcDiff"] = lambda: nodes.calcDiff(problem, xs, us, True, None, at)
    return calls


def serve(library: str, job: str) -> int:
    """The worker's loop: JSON lines in on stdin, out on the original stdout (the job's prints go to stderr)."""
    channel = os.fdopen(os.dup(1), "w", buffering=1)
    os.dup2(2, 1)
    sys.stdout = sys.stderr

    def reply(message: dict) -> None:
        channel.write(json.dumps(message) + "\n")

    try:
        worker = Worker(library, job)
    except BaseException as exc:  # noqa: BLE001 - the job's failure is the answer
        reply({"error": compat.first_error_line(exc)})
        return 0
    reply({"solves": worker.solves()})
    for line in sys.stdin:
        if line.strip() != "round":
            break
        reply({"round": worker.round()})
    return 0


# ------------------------------------------------------------------------------------- the parent
class WorkerError(RuntimeError):
    """A worker failed to run its job or died."""


class WorkerProcess:
    """A worker subprocess (``python -m crocopy.bench.shipped LIBRARY JOB``) and its JSON-line channel."""

    def __init__(self, library: str, job: str) -> None:
        env = dict(os.environ, MPLBACKEND="Agg", OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1", MKL_NUM_THREADS="1")
        for flag in ("DISPLAY", "CROCODDYL_DISPLAY", "CROCODDYL_PLOT"):
            env.pop(flag, None)
        self.library = library
        self.proc = subprocess.Popen([sys.executable, "-m", "crocopy.bench.shipped", library, job],
                                     stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
                                     text=True, env=env, cwd=os.path.dirname(os.path.abspath(os.sep)))

    def receive(self) -> dict:
        line = self.proc.stdout.readline()
        if not line:
            raise WorkerError(f"the {self.library} worker died (exit code {self.proc.wait()})")
        message = json.loads(line)
        if "error" in message:
            raise WorkerError(f"{self.library}: {message['error']}")
        return message

    def ask_round(self) -> list[dict]:
        self.proc.stdin.write("round\n")
        self.proc.stdin.flush()
        return self.receive()["round"]

    def close(self) -> None:
        if self.proc.poll() is None:
            try:
                self.proc.stdin.write("quit\n")
                self.proc.stdin.flush()
                self.proc.wait(timeout=30)
            except (OSError, subprocess.TimeoutExpired):
                self.proc.kill()
                self.proc.wait()


@dataclass
class SolveRow:
    """One recorded solve of a job, both libraries: medians over the rounds."""

    name: str
    solver: str
    T: int
    libs: dict[str, dict[str, Any]] = field(default_factory=dict)
    """library → ``iter``, ``cost``, ``ms_per_iter``, ``calc_calcDiff``, ``backward`` (ms), ``replay_ok``."""

    def ratio(self, key: str) -> float | None:
        a, b = (self.libs.get(lib, {}).get(key) for lib in compat.LIBRARIES)
        return a / b if a is not None and b else None


@dataclass
class JobResult:
    name: str
    rows: list[SolveRow] = field(default_factory=list)
    error: str | None = None


def summarize(name: str, solves: dict[str, list[dict]], rounds: dict[str, list[list[dict]]]) -> list[SolveRow]:
    """The rows of a job from each library's own solves and round replies (medians over rounds)."""
    count = min(len(s) for s in solves.values())
    rows = []
    for k in range(count):
        first = solves["crocoddyl" if "crocoddyl" in solves else next(iter(solves))][k]
        row = SolveRow(name if count == 1 else f"{name} [{k + 1}]", first["solver"], first["T"])
        for lib, own in solves.items():
            replies = [r[k] for r in rounds[lib]]
            iters = replies[0]["iter"]
            row.libs[lib] = {
                "iter": iters,
                "cost": replies[0]["cost"],
                "ms_per_iter": statistics.median(1e3 * r["seconds"] / max(r["iter"], 1) for r in replies),
                "calc_calcDiff": statistics.median(r["phases"]["calc"] + r["phases"]["calcDiff"] for r in replies),
                "backward": statistics.median(r["phases"]["backward"] for r in replies),
                "replay_ok": own[k]["iter"] == iters
                and abs(own[k]["cost"] - replies[0]["cost"]) <= 1e-9 * max(1.0, abs(own[k]["cost"])),
            }
        rows.append(row)
    return rows


def bench_job(job: str, repeats: int = 3) -> JobResult:
    """Run ``job`` in one worker per library and time ``repeats`` interleaved rounds."""
    workers = {lib: WorkerProcess(lib, job) for lib in compat.LIBRARIES}
    try:
        solves = {lib: w.receive()["solves"] for lib, w in workers.items()}
        if any(not s for s in solves.values()):
            return JobResult(job, error="no solve recorded")
        rounds: dict[str, list[list[dict]]] = {lib: [] for lib in workers}
        order = list(workers)
        for r in range(repeats):
            for lib in order if r % 2 == 0 else order[::-1]:
                rounds[lib].append(workers[lib].ask_round())
        return JobResult(job, summarize(job, solves, rounds))
    except WorkerError as exc:
        return JobResult(job, error=str(exc))
    finally:
        for w in workers.values():
            w.close()


# ------------------------------------------------------------------------------------------ table
HEADER = ("| Crocoddyl's problem | solver | T | crocopy iter / cost | Crocoddyl iter / cost | ms/iter crocopy | "
          "ms/iter Crocoddyl | ratio | calc+calcDiff ratio | backward ratio |")


def _x(value: float | None) -> str:
    return "-" if value is None else f"{value:.2f}×"


def format_row(row: SolveRow) -> str:
    mine, theirs = row.libs.get("crocopy", {}), row.libs.get("crocoddyl", {})
    same = all(lib.get("replay_ok", True) for lib in row.libs.values())
    flag = "" if same else " (replay differs from the job's solve)"
    cells = [row.name + flag, row.solver, str(row.T),
             f"{mine.get('iter', '-')} / {mine.get('cost', float('nan')):.6g}",
             f"{theirs.get('iter', '-')} / {theirs.get('cost', float('nan')):.6g}",
             f"{mine.get('ms_per_iter', float('nan')):.3g}", f"{theirs.get('ms_per_iter', float('nan')):.3g}",
             _x(row.ratio("ms_per_iter")), _x(row.ratio("calc_calcDiff")), _x(row.ratio("backward"))]
    return "| " + " | ".join(cells) + " |"


def format_table(results: Sequence[JobResult], repeats: int) -> str:
    """The markdown section: one row per recorded solve, a line per job that failed."""
    lines = ["## Crocoddyl's own problems (built by Crocoddyl's examples and `utils`, with crocopy in its place)", "",
             f"Each job runs once per library in its own worker; its solves are then replayed {repeats} times, the "
             "libraries alternating, one thread on both sides. Medians: full-solve wall time per iteration; "
             "calc+calcDiff and backward pass (`computeDirection(False)`) on the solution. "
             "Ratio = crocopy / Crocoddyl.",
             "", HEADER, "|" + "---|" * HEADER.count(" | ") + "---|"]
    lines += [format_row(row) for result in results for row in result.rows]
    failed = [f"- {r.name}: {r.error}" for r in results if r.error]
    if failed:
        lines += ["", "Not timed:", *failed]
    return "\n".join(lines) + "\n"


def run_shipped(jobs: Sequence[str] | None = None, repeats: int = 3,
                progress: Callable[[str], None] | None = None) -> str:
    """Time ``jobs`` (default :data:`SHIPPED_JOBS`) and return the markdown section."""
    require_crocoddyl()
    names = compat.jobs(list(jobs) if jobs else list(SHIPPED_JOBS))
    results = []
    for job in names:
        results.append(bench_job(job, repeats))
        if progress is not None:
            result = results[-1]
            progress("\n".join(format_row(row) for row in result.rows) if not result.error
                     else f"{job}: {result.error}")
    return format_table(results, repeats)


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m crocopy.bench.shipped", description="a worker (see the module)")
    parser.add_argument("library", choices=compat.LIBRARIES)
    parser.add_argument("job")
    args = parser.parse_args(argv)
    return serve(args.library, args.job)


if __name__ == "__main__":
    sys.exit(main())
