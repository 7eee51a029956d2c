"""``crocopy bench --first-solve``: a whole first ``crocopy solve``, as after installing, and the same run again.

Each round runs ``crocopy solve PROBLEM --solver S --html FILE`` to its end in a subprocess (stdout and
stderr merged and unbuffered, as on a terminal), twice:

* **fresh**: numba's kernel cache (``NUMBA_CACHE_DIR``) and crocopy's user cache (``CROCOPY_CACHE_DIR``:
  parsed robot models) point to new empty folders, as after installing;
* **warm**: the same folders again, filled by the fresh run.

From the launch, it times the compile notice (if any), the first line of the verbose table (iteration 0),
the summary line (the solve's end) and the ``meshcat animation written`` line; ``html`` is the time
between the last two (loading the robot's meshes and writing the page), ``end`` the process's exit.
``CPU`` is the user + system seconds of the whole process.  Each run also tells whether it printed the
compile notice.  The medians and every sample are reported with the machine's load average, which moves
the wall times on a shared machine (the CPU seconds move less).
"""

from __future__ import annotations

import dataclasses
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Mapping, Sequence

from .latency import ITERATION_LINE, NOTICE, crocopy_command

HTML_LINE = "meshcat animation written to"


@dataclasses.dataclass
class Run:
    """Seconds from the launch to each milestone of one ``crocopy solve`` (None: never seen), its CPU seconds,
    exit status and output lines."""

    notice: float | None = None
    first_iteration: float | None = None
    solved: float | None = None
    html_written: float | None = None
    end: float | None = None
    cpu: float | None = None
    returncode: int | None = None
    output: list[str] = dataclasses.field(default_factory=list)

    @property
    def html(self) -> float | None:
        """Seconds writing the animation (from the summary line to the ``written`` line)."""
        if self.solved is None or self.html_written is None:
            return None
        return self.html_written - self.solved


def time_run(argv: Sequence[str], env: Mapping[str, str], problem: str, timeout: float = 1800.0) -> Run:
    """Run ``argv`` (a ``crocopy solve problem ...``) to its end and time its milestones (see :class:`Run`)."""
    with tempfile.TemporaryDirectory(prefix="crocopy-first-solve-") as cwd:
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        t0 = time.perf_counter()
        proc = subprocess.Popen(list(argv), stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                                env={**env, "PYTHONUNBUFFERED": "1"}, cwd=cwd)
        run = Run()
        summary = f"{problem}: "
        try:
            for line in proc.stdout:
                elapsed = time.perf_counter() - t0
                run.output.append(line.rstrip("\n"))
                if run.notice is None and NOTICE in line:
                    run.notice = elapsed
                if run.first_iteration is None and ITERATION_LINE.match(line):
                    run.first_iteration = elapsed
                if run.solved is None and line.startswith(summary) and "converge" in line:
                    run.solved = elapsed
                if HTML_LINE in line:
                    run.html_written = elapsed
                if elapsed > timeout:
                    proc.kill()
                    break
            run.returncode = proc.wait()
            run.end = time.perf_counter() - t0
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.wait()
            proc.stdout.close()
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        run.cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return run


KINDS = ("notice", "first iteration", "solved", "html", "end", "CPU")
"""The measures of a run, in the report's order (``notice``: whether the compile notice was printed)."""


def _values(run: Run) -> dict[str, float | None]:
    return {"first iteration": run.first_iteration, "solved": run.solved, "html": run.html, "end": run.end,
            "CPU": run.cpu}


def measure(problem: str = "jump", solver: str = "boxfddp", repeats: int = 2, env: Mapping[str, str] | None = None,
            progress: Callable[[str], None] | None = None,
            command: Sequence[str] | None = None) -> dict[str, dict[str, list]]:
    """``repeats`` rounds of (fresh run, warm run): the samples by run kind (``fresh``/``warm``) and measure.
    ``command``: the ``crocopy`` command to run (default: this environment's)."""
    base = {**(os.environ if env is None else env), "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1"}
    samples: dict[str, dict[str, list]] = {kind: {k: [] for k in KINDS} for kind in ("fresh", "warm")}
    for r in range(repeats):
        with tempfile.TemporaryDirectory(prefix="crocopy-first-solve-cache-") as cache:
            env_r = {**base, "NUMBA_CACHE_DIR": os.path.join(cache, "numba"),
                     "CROCOPY_CACHE_DIR": os.path.join(cache, "crocopy")}
            argv = [*(command or crocopy_command()), "solve", problem, "--solver", solver,
                    "--html", os.path.join(cache, "a.html")]
            for kind in ("fresh", "warm"):
                run = time_run(argv, env_r, problem)
                if run.returncode not in (0, 1) or run.first_iteration is None:
                    tail = "\n".join(run.output[-5:])
                    raise RuntimeError(f"{' '.join(argv)} failed (exit {run.returncode}); its output ended:\n{tail}")
                samples[kind]["notice"].append(run.notice is not None)
                for key, value in _values(run).items():
                    samples[kind][key].append(value)
        if progress is not None:
            progress(f"round {r + 1}: " + "; ".join(
                f"{kind} " + ", ".join(f"{k} {_s(v[-1])}" for k, v in by.items()) for kind, by in samples.items()))
    return samples


def _s(value: float | bool | None) -> str:
    if isinstance(value, bool):
        return "yes" if value else "no"
    return "-" if value is None else f"{value:.2f}"


def format_report(samples: Mapping[str, Mapping[str, Sequence]], problem: str, solver: str,
                  title: str | None = None) -> str:
    """Markdown table: per run kind and measure, the median and every sample (seconds).  ``title``: a heading
    and paragraph in place of the default heading (the command is then named before the table's description)."""
    load = os.getloadavg()
    command = f"`crocopy solve {problem} --solver {solver} --html FILE`"
    lines = [f"## A whole first solve: {command}", ""] if title is None else [title, "", f"{command}:"]
    lines += ["Seconds from the launch, fresh (empty caches) and warm (the same caches again); `html` is the"
              " animation's export, `CPU` the process's user + system seconds; `notice` whether the compile notice"
              f" was printed. Medians of the rounds (load average {load[0]:.2f} at the end, {os.cpu_count()} CPUs).",
              "", "| run | measure | median | samples |", "|---|---|---|---|"]
    for kind, by in samples.items():
        for measure_name, values in by.items():
            if measure_name == "notice":
                median = _s(any(values)) if values else "-"
            else:
                seen = [v for v in values if v is not None]
                median = _s(statistics.median(seen)) if seen else "never"
            lines.append(f"| {kind} | {measure_name} | {median} | {', '.join(_s(v) for v in values)} |")
    return "\n".join(lines) + "\n"


def run_first_solve_bench(problem: str = "jump", solver: str = "boxfddp", repeats: int = 2) -> str:
    """The ``crocopy bench --first-solve`` report (progress lines on stderr)."""
    samples = measure(problem, solver, repeats, progress=lambda line: print(line, file=sys.stderr, flush=True))
    return format_report(samples, problem, solver)
