"""``crocopy bench --latency``: how long ``crocopy solve`` takes to print its first iteration line.

Each round launches ``crocopy solve PROBLEM --no-html`` twice in a subprocess (stdout and stderr
merged and unbuffered, as on a terminal) and times, from the launch, the compile notice (if any)
and the first line of the verbose table (iteration 0):

* **fresh**: numba's kernel cache (``NUMBA_CACHE_DIR``) and crocopy's user cache
  (``CROCOPY_CACHE_DIR``: parsed robot models) point to new empty folders, as after installing;
* **warm**: the same folders again, filled by the fresh run.

Besides the wall time, the CPU seconds the process had used when the line came (read from
``/proc``) are reported: on a shared machine they move less with the load.

The process is stopped once the line is seen.  A third subprocess per round times
``python -c "import crocopy"``.  The rounds interleave the three, and the report gives their
medians and every sample (the machine's load moves them; the load average is printed).
"""

from __future__ import annotations

import dataclasses
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path

ITERATION_LINE = re.compile(r"^\s*0\s+[-+0-9.]+e[-+]\d+\s")
"""The verbose table's first row (iteration 0)."""

NOTICE = "compiling kernels"


@dataclasses.dataclass
class Launch:
    """Seconds from a launch to the first iteration line (None if it never came) and to the compile notice;
    the CPU seconds the process had used when the line came (None where ``/proc`` does not tell)."""

    first_iteration: float | None
    notice: float | None
    output: list[str]
    cpu: float | None = None


def cpu_seconds(pid: int) -> float | None:
    """User + system CPU seconds used so far by process ``pid`` (Linux ``/proc``; None elsewhere)."""
    try:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    except OSError:
        return None
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def crocopy_command() -> list[str]:
    """The ``crocopy`` console script of this Python's environment (``python -m crocopy.cli`` without one)."""
    script = Path(sys.executable).with_name("crocopy")
    return [str(script)] if script.is_file() else [sys.executable, "-m", "crocopy.cli"]


def time_first_iteration(argv: Sequence[str], env: Mapping[str, str], timeout: float = 600.0) -> Launch:
    """Run ``argv`` and time its output lines until the first :data:`ITERATION_LINE` (then stop it)."""
    with tempfile.TemporaryDirectory(prefix="crocopy-latency-") as cwd:
        t0 = time.perf_counter()
        proc = subprocess.Popen(list(argv), stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                                env={**env, "PYTHONUNBUFFERED": "1"}, cwd=cwd)
        launch = Launch(None, None, [])
        try:
            for line in proc.stdout:
                elapsed = time.perf_counter() - t0
                launch.output.append(line.rstrip("\n"))
                if launch.notice is None and NOTICE in line:
                    launch.notice = elapsed
                if ITERATION_LINE.match(line):
                    launch.first_iteration = elapsed
                    launch.cpu = cpu_seconds(proc.pid)
                    break
                if elapsed > timeout:
                    break
        finally:
            proc.kill()
            proc.wait()
            proc.stdout.close()
    return launch


def time_import(env: Mapping[str, str]) -> float:
    """Wall seconds of ``python -c "import crocopy"`` in a subprocess (interpreter start included)."""
    with tempfile.TemporaryDirectory(prefix="crocopy-latency-") as cwd:
        t0 = time.perf_counter()
        subprocess.run([sys.executable, "-c", "import crocopy"], env=dict(env), cwd=cwd, check=True)
        return time.perf_counter() - t0


def measure(problem: str = "jump", solver: str = "boxfddp", repeats: int = 3,
            env: Mapping[str, str] | None = None,
            progress: Callable[[str], None] | None = None) -> dict[str, list[float | None]]:
    """``repeats`` rounds of (fresh launch, warm launch, import): the samples in seconds, by kind."""
    base = {**(os.environ if env is None else env), "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1"}
    argv = [*crocopy_command(), "solve", problem, "--solver", solver, "--no-html"]
    samples: dict[str, list[float | None]] = {"fresh": [], "fresh notice": [], "fresh CPU": [], "warm": [],
                                              "warm notice": [], "warm CPU": [], "import crocopy": []}
    for r in range(repeats):
        with tempfile.TemporaryDirectory(prefix="crocopy-latency-cache-") as cache:
            env_r = {**base, "NUMBA_CACHE_DIR": os.path.join(cache, "numba"),
                     "CROCOPY_CACHE_DIR": os.path.join(cache, "crocopy")}
            for kind in ("fresh", "warm"):
                launch = time_first_iteration(argv, env_r)
                if launch.first_iteration is None:
                    tail = "\n".join(launch.output[-5:])
                    raise RuntimeError(f"{' '.join(argv)} printed no iteration line; its output ended with:\n{tail}")
                samples[kind].append(launch.first_iteration)
                samples[f"{kind} notice"].append(launch.notice)
                samples[f"{kind} CPU"].append(launch.cpu)
        samples["import crocopy"].append(time_import(base))
        if progress is not None:
            progress(f"round {r + 1}: " + ", ".join(f"{k} {_s(v[-1])}" for k, v in samples.items()))
    return samples


def _s(value: float | None) -> str:
    return "-" if value is None else f"{value:.2f}"


def format_report(samples: Mapping[str, Sequence[float | None]], problem: str, solver: str) -> str:
    """Markdown table: median and samples (seconds) of each kind."""
    load = os.getloadavg()
    lines = [f"## Launch to first iteration line: `crocopy solve {problem} --solver {solver} --no-html`", "",
             f"Seconds from the launch (CPU: seconds of CPU the process had used by then); medians of "
             f"interleaved rounds (load average {load[0]:.2f} at the end).", "",
             "| measure | median s | samples s |", "|---|---|---|"]
    for kind, values in samples.items():
        seen = [v for v in values if v is not None]
        median = _s(statistics.median(seen)) if seen else "never"
        lines.append(f"| {kind} | {median} | {', '.join(_s(v) for v in values)} |")
    return "\n".join(lines) + "\n"


def run_latency_bench(problem: str = "jump", solver: str = "boxfddp", repeats: int = 3) -> str:
    """The ``crocopy bench --latency`` report (progress lines on stderr)."""
    samples = measure(problem, solver, repeats, progress=lambda line: print(line, file=sys.stderr, flush=True))
    return format_report(samples, problem, solver)
