"""``crocopy bench --compat``: Crocoddyl's own example scripts and gait builders, run with crocopy.

The crocoddyl 3.2.1 wheel (the ``bench`` extra) ships example scripts (``crocoddyl/examples/*.py``) and
gait builders (``crocoddyl/utils/quadruped.py``, ``biped.py``).  Each is run twice, each time in its own
subprocess with a timeout, no display and ``MPLBACKEND=Agg``:

- with ``sys.modules["crocoddyl"]`` bound to crocopy (``crocoddyl.utils`` is the wheel's own folder,
  executed under that binding, as a user's script would import it);
- with Crocoddyl itself, for the reference iterations and costs.

The scripts are located with ``importlib.util.find_spec("crocoddyl")`` and only executed (never read).
Every call of a solver's ``solve`` is recorded (iterations, cost).  The gait builders are driven by
:func:`solve_gait`: build the gait's ``ShootingProblem`` with the builder, then ``SolverFDDP`` from
the quasi-static warm start.

The report is a markdown table: does the script run to its end with crocopy (or its first error),
crocopy's iterations and final cost next to Crocoddyl's, and their relative difference.
"""

from __future__ import annotations

import argparse
import dataclasses
import importlib.util
import json
import math
import os
import pathlib
import runpy
import subprocess
import sys
import tempfile
import time
import traceback
from collections.abc import Callable, Sequence
from typing import Any

from .side_by_side import BenchDependencyError, require_crocoddyl

#: gait builders: name → (utils module, robot, feet, reference configuration, builder method, arguments after x0)
GAITS: dict[str, tuple[str, str, tuple[str, ...], str, str, tuple]] = {
    "quadruped-walk": ("quadruped", "anymal", ("LF_FOOT", "RF_FOOT", "LH_FOOT", "RH_FOOT"), "standing",
                       "createWalkingProblem", (0.25, 0.15, 1e-2, 25, 2)),
    "quadruped-trot": ("quadruped", "anymal", ("LF_FOOT", "RF_FOOT", "LH_FOOT", "RH_FOOT"), "standing",
                       "createTrottingProblem", (0.15, 0.1, 1e-2, 25, 2)),
    "quadruped-pace": ("quadruped", "anymal", ("LF_FOOT", "RF_FOOT", "LH_FOOT", "RH_FOOT"), "standing",
                       "createPacingProblem", (0.15, 0.1, 1e-2, 25, 5)),
    "quadruped-bound": ("quadruped", "anymal", ("LF_FOOT", "RF_FOOT", "LH_FOOT", "RH_FOOT"), "standing",
                        "createBoundingProblem", (0.15, 0.1, 1e-2, 25, 5)),
    "quadruped-jump": ("quadruped", "anymal", ("LF_FOOT", "RF_FOOT", "LH_FOOT", "RH_FOOT"), "standing",
                       "createJumpingProblem", (0.15, [0.2, 0.0, 0.0], 1e-2, 10, 20)),
    "biped-walk": ("biped", "talos_legs", ("right_sole_link", "left_sole_link"), "half_sitting",
                   "createWalkingProblem", (0.4, 0.1, 3e-2, 20, 10)),
}
GAIT_CLASSES = {"quadruped": "SimpleQuadrupedalGaitProblem", "biped": "SimpleBipedGaitProblem"}
GAIT_MAXITER = 100
TIMEOUT = 900.0
LIBRARIES = ("crocopy", "crocoddyl")


@dataclasses.dataclass
class RunResult:
    """One run of a script or gait with one library."""

    ok: bool
    error: str | None = None
    where: str | None = None
    solves: list[dict[str, Any]] = dataclasses.field(default_factory=list)
    seconds: float = 0.0


@dataclasses.dataclass
class Row:
    """A script or gait: crocopy's run and Crocoddyl's (None when it was not run)."""

    name: str
    crocopy: RunResult
    crocoddyl: RunResult | None


# ------------------------------------------------------------------------------------------ where
def crocoddyl_folder() -> pathlib.Path:
    """The installed crocoddyl package folder (``BenchDependencyError`` without the bench extra)."""
    spec = importlib.util.find_spec("crocoddyl")
    if spec is None or not spec.submodule_search_locations:
        raise BenchDependencyError("crocopy bench --compat needs Crocoddyl 3.2.1: pip install 'crocopy[bench]'")
    return pathlib.Path(list(spec.submodule_search_locations)[0])


def example_scripts(folder: pathlib.Path | None = None) -> list[pathlib.Path]:
    """The example scripts shipped in the wheel, by name."""
    folder = (folder or crocoddyl_folder()) / "examples"
    return sorted(p for p in folder.glob("*.py") if p.name != "__init__.py")


def jobs(names: Sequence[str] | None = None) -> list[str]:
    """Job names: the example scripts' stems, then the gaits (``names`` selects among them)."""
    every = [p.stem for p in example_scripts()] + list(GAITS)
    if not names:
        return every
    unknown = [n for n in names if n not in every]
    if unknown:
        raise KeyError(f"unknown compat job(s) {unknown}; known: {', '.join(every)}")
    return list(names)


# ----------------------------------------------------------------------------------- in the child
def bind_crocopy(folder: pathlib.Path) -> None:
    """``import crocoddyl`` gives crocopy; ``crocoddyl.utils`` is the wheel's folder, executed on crocopy."""
    import crocopy

    sys.modules["crocoddyl"] = crocopy
    utils = folder / "utils"
    spec = importlib.util.spec_from_file_location("crocoddyl.utils", utils / "__init__.py",
                                                  submodule_search_locations=[str(utils)])
    module = importlib.util.module_from_spec(spec)
    sys.modules["crocoddyl.utils"] = module
    crocopy.utils = module
    spec.loader.exec_module(module)


def record_solves(lib: Any, sink: list[dict[str, Any]], calls: list[tuple] | None = None) -> None:
    """Wrap every solver class's ``solve`` to append ``{solver, iter, cost, converged}`` to ``sink``
    (outermost calls only, so a solver calling its base class's ``solve`` is counted once).

    With ``calls``, also append ``(solver, args, kwargs)`` of each outermost call, the arrays among
    the arguments (and in lists of them) copied as they were passed, so that the call can be replayed."""
    depth = [0]

    def wrap(original: Callable) -> Callable:
        def solve(self, *args, **kwargs):
            if depth[0] == 0 and calls is not None:
                calls.append((self, _copied(args), {k: _copied(v) for k, v in kwargs.items()}))
            depth[0] += 1
            try:
                converged = original(self, *args, **kwargs)
            finally:
                depth[0] -= 1
            if depth[0] == 0:
                sink.append({"solver": type(self).__name__, "iter": int(self.iter), "cost": float(self.cost),
                             "converged": bool(converged)})
            return converged

        return solve

    for name in dir(lib):
        cls = getattr(lib, name, None)
        if name.startswith("Solver") and isinstance(cls, type) and "solve" in cls.__dict__:
            cls.solve = wrap(cls.__dict__["solve"])


def _copied(value: Any) -> Any:
    """``value`` with its numpy arrays copied (also inside lists and tuples)."""
    if isinstance(value, (list, tuple)):
        return type(value)(_copied(v) for v in value)
    return value.copy() if hasattr(value, "copy") and hasattr(value, "shape") else value


def solve_gait(name: str) -> None:
    """Build gait ``name`` with the wheel's builder (``crocoddyl.utils``) and solve it with FDDP."""
    import crocoddyl
    import example_robot_data
    import numpy as np

    module, robot_name, feet, reference, method, arguments = GAITS[name]
    builder_module = __import__(f"crocoddyl.utils.{module}", fromlist=[GAIT_CLASSES[module]])
    model = example_robot_data.load(robot_name).model
    q0 = model.referenceConfigurations[reference].copy()
    x0 = np.concatenate([q0, np.zeros(model.nv)])
    builder = getattr(builder_module, GAIT_CLASSES[module])(model, *feet)
    problem = getattr(builder, method)(x0, *arguments)
    solver = crocoddyl.SolverFDDP(problem)
    xs = [x0] * (problem.T + 1)
    us = problem.quasiStatic([x0] * problem.T)
    solver.solve(xs, us, GAIT_MAXITER, False)


def _where(exc: BaseException, inside: pathlib.Path) -> str | None:
    """``file:line`` of the innermost frame of the traceback in the crocoddyl wheel (the script's line),
    then ``raised in file:line`` of the innermost crocopy frame below it, if any."""
    frames = traceback.extract_tb(exc.__traceback__)
    script = [f for f in frames if f.filename.startswith(str(inside))]
    if not script:
        return None
    where = f"{pathlib.Path(script[-1].filename).name}:{script[-1].lineno}"
    below = [f for f in frames[frames.index(script[-1]) + 1:] if "crocopy" in pathlib.Path(f.filename).parts
             or pathlib.Path(f.filename).parent.name == "models"]
    if below:
        raised = pathlib.Path(below[-1].filename)
        where += f"; raised in {raised.parent.name}/{raised.name}:{below[-1].lineno}"
    return where


def first_error_line(exc: BaseException) -> str:
    """``Type: first line of the message``."""
    message = str(exc).strip().splitlines()
    return f"{type(exc).__name__}: {message[0]}" if message else type(exc).__name__


def execute_job(job: str, folder: pathlib.Path) -> None:
    """Run ``job`` in this process: a gait of :data:`GAITS` (:func:`solve_gait`), else the wheel's example
    script ``job`` as ``__main__``."""
    if job in GAITS:
        solve_gait(job)
    else:
        script = folder / "examples" / f"{job}.py"
        sys.argv = [str(script)]
        runpy.run_path(str(script), run_name="__main__")


def run_child(library: str, job: str, result_file: str) -> int:
    """Run one job with one library in this process and write its :class:`RunResult` as JSON."""
    folder = crocoddyl_folder()
    if library == "crocopy":
        bind_crocopy(folder)
    import crocoddyl
    import matplotlib.pyplot as plt

    plt.show = lambda *args, **kwargs: None
    result = RunResult(ok=False)
    record_solves(crocoddyl, result.solves)
    start = time.perf_counter()
    try:
        execute_job(job, folder)
        result.ok = True
    except SystemExit as exc:
        result.ok = exc.code in (None, 0)
        if not result.ok:
            result.error = f"SystemExit: {exc.code}"
    except BaseException as exc:  # noqa: BLE001 - any failure of the script is the measurement
        result.error, result.where = first_error_line(exc), _where(exc, folder)
    result.seconds = time.perf_counter() - start
    pathlib.Path(result_file).write_text(json.dumps(dataclasses.asdict(result)), encoding="utf-8")
    return 0


# ---------------------------------------------------------------------------------- in the parent
def run_in_subprocess(module: str, args: Sequence[str], timeout: float = TIMEOUT) -> RunResult:
    """``python -m module --child *args RESULT`` in a subprocess (own working folder, no display, one BLAS thread);
    the child writes its :class:`RunResult` as JSON to ``RESULT``."""
    env = dict(os.environ, MPLBACKEND="Agg", OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1", MKL_NUM_THREADS="1")
    for flag in ("DISPLAY", "CROCODDYL_DISPLAY", "CROCODDYL_PLOT"):
        env.pop(flag, None)
    with tempfile.TemporaryDirectory(prefix="crocopy-child-") as work:
        result_file = os.path.join(work, "result.json")
        command = [sys.executable, "-m", module, "--child", *args, result_file]
        start = time.perf_counter()
        try:
            done = subprocess.run(command, cwd=work, env=env, capture_output=True, text=True, timeout=timeout)
        except subprocess.TimeoutExpired:
            return RunResult(ok=False, error=f"timeout after {timeout:.0f} s", seconds=timeout)
        if os.path.exists(result_file):
            return RunResult(**json.loads(pathlib.Path(result_file).read_text(encoding="utf-8")))
        tail = [line for line in done.stderr.strip().splitlines() if line.strip()]
        return RunResult(ok=False, error=f"exit code {done.returncode}: {tail[-1] if tail else 'no output'}",
                         seconds=time.perf_counter() - start)


def run_job(library: str, job: str, timeout: float = TIMEOUT) -> RunResult:
    """Run ``job`` with ``library`` in a subprocess (:func:`run_in_subprocess`)."""
    return run_in_subprocess("crocopy.bench.compat", (library, job), timeout)


def run_compat(names: Sequence[str] | None = None, timeout: float = TIMEOUT,
               progress: Callable[[str], None] | None = None) -> list[Row]:
    """Every job (or ``names``) with crocopy and with Crocoddyl."""
    require_crocoddyl()
    rows = []
    for job in jobs(names):
        mine = run_job("crocopy", job, timeout)
        theirs = run_job("crocoddyl", job, timeout)
        rows.append(Row(job, mine, theirs))
        if progress:
            progress(format_row(rows[-1]))
    return rows


# ------------------------------------------------------------------------------------------ table
HEADER = ("| script | runs to its end with crocopy | crocopy iterations | crocopy final cost | Crocoddyl iterations "
          "| Crocoddyl final cost | relative difference |")


def _iterations(result: RunResult | None) -> str:
    if result is None or not result.solves:
        return "-"
    iters = [s["iter"] for s in result.solves]
    return ", ".join(map(str, iters)) if len(iters) <= 4 else f"{sum(iters)} in {len(iters)} solves"


def _cost(result: RunResult | None) -> str:
    return f"{result.solves[-1]['cost']:.6g}" if result is not None and result.solves else "-"


def relative_difference(mine: RunResult, theirs: RunResult | None) -> float | None:
    """Largest ``|c - c_ref| / |c_ref|`` over the solves both runs made, in order (a run that stopped
    early is compared on the solves it finished)."""
    if theirs is None or not mine.solves or not theirs.solves:
        return None
    diffs = [abs(a["cost"] - b["cost"]) / max(abs(b["cost"]), 1e-300) for a, b in zip(mine.solves, theirs.solves)]
    return max(diffs) if all(math.isfinite(d) for d in diffs) else math.inf


def _status(result: RunResult) -> str:
    if result.ok:
        return "yes"
    where = f" ({result.where})" if result.where else ""
    return f"no: {result.error}{where}"


def format_row(row: Row) -> str:
    diff = relative_difference(row.crocopy, row.crocoddyl)
    counts = (len(row.crocopy.solves), len(row.crocoddyl.solves) if row.crocoddyl is not None else 0)
    solves = f" ({counts[0]} vs {counts[1]} solves)" if diff is not None and counts[0] != counts[1] else ""
    cells = [row.name, _status(row.crocopy), _iterations(row.crocopy), _cost(row.crocopy),
             _iterations(row.crocoddyl), _cost(row.crocoddyl), ("-" if diff is None else f"{diff:.2e}") + solves]
    return "| " + " | ".join(cell.replace("|", "\\|") for cell in cells) + " |"


def format_table(rows: Sequence[Row]) -> str:
    """The markdown report: a summary line, then one row per script or gait."""
    scripts = [r for r in rows if r.name not in GAITS]
    gaits = [r for r in rows if r.name in GAITS]
    summary = [f"{sum(r.crocopy.ok for r in scripts)} of {len(scripts)} example scripts"] if scripts else []
    if gaits:
        summary.append(f"{sum(r.crocopy.ok for r in gaits)} of {len(gaits)} gaits")
    lines = [
        "## Crocoddyl's own scripts with crocopy (`crocopy bench --compat`)",
        "",
        " and ".join(summary) + " run to their end with `sys.modules[\"crocoddyl\"]` bound to crocopy.",
        "",
        HEADER,
        "|" + "---|" * HEADER.count(" | ") + "---|",
        *(format_row(r) for r in rows),
    ]
    return "\n".join(lines) + "\n"


def report_cli(run: Callable[..., list[Row]], table: Callable[[Sequence[Row]], str], names: Sequence[str] | None,
               out: str | None, refused: tuple[type[Exception], ...] = ()) -> int:
    """A bench command over script runs: ``run(names, progress=...)`` with progress lines on stderr, its ``table``
    printed and written to ``out``; exit status 2 with the message of a missing dependency, an unknown name or
    one of ``refused``."""
    try:
        rows = run(names, progress=lambda line: print(line, file=sys.stderr, flush=True))
    except (BenchDependencyError, KeyError, *refused) as exc:
        print(exc.args[0], file=sys.stderr)
        return 2
    report = table(rows)
    print(report)
    if out:
        pathlib.Path(out).write_text(report, encoding="utf-8")
        print(f"report written to {out}", file=sys.stderr)
    return 0


def run_compat_cli(names: Sequence[str] | None, out: str | None) -> int:
    """The ``crocopy bench --compat`` command: run, print the table, write it to ``out``."""
    return report_cli(run_compat, format_table, names, out)


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m crocopy.bench.compat")
    parser.add_argument("--child", nargs=3, metavar=("LIBRARY", "JOB", "RESULT"), required=True)
    args = parser.parse_args(argv)
    library, job, result_file = args.child
    if library not in LIBRARIES:
        parser.error(f"LIBRARY must be one of {LIBRARIES}")
    return run_child(library, job, result_file)


if __name__ == "__main__":
    sys.exit(main())
