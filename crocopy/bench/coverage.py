"""``crocopy bench --coverage``: nodes compiled / nodes per problem, and why the others are not.

Two sources of problems:

- crocopy's builders (:mod:`crocopy.problems`), built in this process;
- Crocoddyl's shipped example scripts and ``utils`` gait builders (the jobs of :mod:`crocopy.bench.compat`, bench
  extra), each run to its end in its own subprocess with ``crocoddyl`` bound to crocopy; every problem one of its
  solves was called on counts once (a problem solved twice, by two solvers, counts once).

Each problem's nodes are asked for their compiled evaluators as a solve does (:func:`crocopy.compiled_coverage`);
the table gives per problem (per job: over its problems) the nodes compiled, the nodes, and the reasons of the others
with their counts, then every reason with its node count.  The full ``crocopy bench --vs crocoddyl`` run appends the
same section to its report (BENCHMARKS.md).
"""

from __future__ import annotations

import argparse
import dataclasses
import functools
import json
import os
import pathlib
import subprocess
import sys
import tempfile
from collections import Counter
from collections.abc import Callable, Sequence

from ..not_compiled import USER
from ..solvers.coverage import compiled_coverage
from . import compat
from .side_by_side import BenchDependencyError


@dataclasses.dataclass
class Row:
    """The nodes of one builder's problem or one job's problems."""

    name: str
    source: str
    reasons: list[str | None] = dataclasses.field(default_factory=list)
    """Per node, None (compiled) or why it is not compiled."""
    problems: int = 0
    solvers: list[str] = dataclasses.field(default_factory=list)
    error: str | None = None

    @property
    def compiled(self) -> int:
        return sum(r is None for r in self.reasons)

    def why(self) -> Counter:
        """Reason → nodes, most frequent first."""
        return Counter(r for r in self.reasons if r is not None)


def builder_row(name: str) -> Row:
    """The coverage of the registered problem ``name`` (:mod:`crocopy.problems`)."""
    from crocopy.problems import registry

    problem = registry.build(name)[0]
    return Row(name, "crocopy builder", [c.reason for c in compiled_coverage(problem)], 1)


# ----------------------------------------------------------------------------------- in the child
def problems_of(calls: Sequence[tuple]) -> tuple[list, list[str]]:
    """The distinct problems of recorded solve calls ``(solver, args, kwargs)``, and the solvers' class names."""
    problems, seen, solvers = [], set(), []
    for solver, _, _ in calls:
        name = type(solver).__name__
        if name not in solvers:
            solvers.append(name)
        if id(solver.problem) not in seen:
            seen.add(id(solver.problem))
            problems.append(solver.problem)
    return problems, solvers


def run_child(job: str, result_file: str) -> int:
    """Run ``job`` with crocopy in this process and write its :class:`Row` as JSON (with the coverage of what it
    solved before failing, if it fails)."""
    folder = compat.crocoddyl_folder()
    compat.bind_crocopy(folder)
    import crocoddyl
    import matplotlib.pyplot as plt

    plt.show = lambda *args, **kwargs: None
    recorded: list[dict] = []
    calls: list[tuple] = []
    compat.record_solves(crocoddyl, recorded, calls)
    row = Row(job, "Crocoddyl gait" if job in compat.GAITS else "Crocoddyl example")
    try:
        compat.execute_job(job, folder)
    except SystemExit as exc:
        if exc.code not in (None, 0):
            row.error = f"SystemExit: {exc.code}"
    except BaseException as exc:  # noqa: BLE001 - the job's failure is reported with its coverage so far
        row.error = compat.first_error_line(exc)
    problems, row.solvers = problems_of(calls)
    row.problems = len(problems)
    row.reasons = [c.reason for problem in problems for c in compiled_coverage(problem)]
    pathlib.Path(result_file).write_text(json.dumps(dataclasses.asdict(row)), encoding="utf-8")
    return 0


# ---------------------------------------------------------------------------------- in the parent
def job_row(job: str, timeout: float = compat.TIMEOUT) -> Row:
    """The coverage of Crocoddyl's job ``job`` (a subprocess, as :func:`crocopy.bench.compat.run_job` runs it)."""
    env = dict(os.environ, MPLBACKEND="Agg", OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1", MKL_NUM_THREADS="1")
    for flag in ("DISPLAY", "CROCODDYL_DISPLAY", "CROCODDYL_PLOT"):
        env.pop(flag, None)
    source = "Crocoddyl gait" if job in compat.GAITS else "Crocoddyl example"
    with tempfile.TemporaryDirectory(prefix="crocopy-coverage-") as work:
        result_file = os.path.join(work, "result.json")
        command = [sys.executable, "-m", "crocopy.bench.coverage", job, result_file]
        try:
            done = subprocess.run(command, cwd=work, env=env, capture_output=True, text=True, timeout=timeout)
        except subprocess.TimeoutExpired:
            return Row(job, source, error=f"timeout after {timeout:.0f} s")
        if os.path.exists(result_file):
            return Row(**json.loads(pathlib.Path(result_file).read_text(encoding="utf-8")))
        tail = [line for line in done.stderr.strip().splitlines() if line.strip()]
        return Row(job, source, error=f"exit code {done.returncode}: {tail[-1] if tail else 'no output'}")


def run_coverage(problems: Sequence[str] | None = None, jobs: Sequence[str] | None = None,
                 progress: Callable[[str], None] | None = None) -> str:
    """The markdown section for builders ``problems`` and Crocoddyl's ``jobs`` (None: none of them; an empty
    sequence: every one)."""
    from crocopy.problems import registry

    rows = []
    names = [] if problems is None else list(problems) or registry.names()
    job_names = [] if jobs is None else compat.jobs(list(jobs))
    for name in names:
        rows.append(builder_row(name))
        if progress is not None:
            progress(format_row(rows[-1]))
    for job in job_names:
        rows.append(job_row(job))
        if progress is not None:
            progress(format_row(rows[-1]))
    return format_section(rows)


# ------------------------------------------------------------------------------------------ table
def _reasons(counts: Counter) -> str:
    return ", ".join(f"{n} {reason}" for reason, n in counts.most_common()) or "—"


def format_row(row: Row) -> str:
    """``| problem | source | problems | solvers | compiled / nodes | not compiled |``."""
    ratio = f"{row.compiled}/{len(row.reasons)}"
    why = _reasons(row.why())
    if row.error:
        why += f"; the job stopped: {row.error}"
    cells = [row.name, row.source, str(row.problems), ", ".join(row.solvers) or "—", ratio, why]
    return "| " + " | ".join(cell.replace("|", "\\|") for cell in cells) + " |"


def format_section(rows: Sequence[Row]) -> str:
    """The markdown section: one row per builder or job, totals per source, then every reason with its nodes."""
    header = "| problem | source | problems | solvers | nodes compiled / nodes | not compiled: nodes, why |"
    lines = ["## Compiled nodes (`crocopy bench --coverage`)", "",
             "The nodes a solve evaluates as one compiled call (with kernels on: the DDP family, SQP, CSQP, Intro "
             "and the projection solver take compiled nodes), per problem, and why the others keep the Python "
             "path (`crocopy.compiled_coverage`: the solver's own decision, node by node). Crocoddyl's jobs run "
             "with `crocoddyl` bound to crocopy; each problem one of their solves was called on counts once, "
             "whichever solver it used. A reason is the first test a node fails.", "",
             header, "|---" * header.count(" | ") + "|---|", *(format_row(r) for r in rows), ""]
    by_source: dict[str, list[Row]] = {}
    for row in rows:
        by_source.setdefault(row.source, []).append(row)
    lines += ["| source | nodes compiled / nodes | not compiled, besides a user's Python subclass |", "|---|---|---|"]
    for source, group in by_source.items():
        reasons = [r for row in group for r in row.reasons]
        others = sum(r is not None and not r.startswith(USER) for r in reasons)
        lines.append(f"| {source} ({len(group)}) | {reasons.count(None)}/{len(reasons)} | {others} |")
    total = Counter(r for row in rows for r in row.reasons if r is not None)
    if total:
        names = Counter(row.name for row in rows)
        lines += ["", "| why not compiled | nodes | problems |", "|---|---|---|"]
        for reason, n in total.most_common():
            where = [row.name if names[row.name] == 1 else f"{row.name} ({row.source})"
                     for row in rows if reason in row.reasons]
            lines.append(f"| {reason} | {n} | {', '.join(where)} |")
    return "\n".join(lines) + "\n"


def run_coverage_cli(args: argparse.Namespace) -> int:
    """``crocopy bench --coverage [--problems ...] [--shipped [JOB ...]] [--out FILE]``: builders (all without
    names) and Crocoddyl's jobs (all without names; only with ``--shipped`` when ``--problems`` is given; none without
    the bench extra unless ``--shipped`` asks for them)."""
    builders = args.problems if args.problems is not None else [] if args.shipped is None else None
    jobs = args.shipped if args.shipped is not None else [] if args.problems is None else None
    progress = functools.partial(print, file=sys.stderr, flush=True)
    try:
        if jobs is not None:
            compat.jobs(list(jobs))  # the bench extra and the names, checked before any work
    except BenchDependencyError as exc:
        if args.shipped is not None:
            print(exc.args[0], file=sys.stderr)
            return 2
        progress(f"builders only: {exc.args[0]}")
        jobs = None
    except KeyError as exc:
        print(exc.args[0], file=sys.stderr)
        return 2
    section = run_coverage(builders, jobs, progress)
    print(section)
    if args.out:
        pathlib.Path(args.out).write_text(section, encoding="utf-8")
        print(f"report written to {args.out}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(run_child(*sys.argv[1:3]))
