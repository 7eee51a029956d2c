"""The ``crocopy`` command.

* ``crocopy --version``
* ``crocopy bench``: solver timings on LQR problems (and Crocoddyl's, when installed)
* ``crocopy bench --vs crocoddyl [--problems ...] [--shipped [JOB ...]] [--repeats N] [--out BENCHMARKS.md]``:
  crocopy and Crocoddyl side by side on the bundled problems (:mod:`crocopy.bench.side_by_side`) and on
  Crocoddyl's own problems built by its example scripts and gait builders (:mod:`crocopy.bench.shipped`);
  both by default, only the part named when ``--problems`` or ``--shipped`` is given
* ``crocopy bench --vs mim [--problems ...] [--out FILE]``: SolverSQP/SolverCSQP against mim-solvers 0.3.0
  (:mod:`crocopy.bench.mim`): iterations, cost, KKT, violation and time per iteration
* ``crocopy bench --box-parity [--problems ...] [--maxiter N]``: Box-DDP/Box-FDDP iterations and
  final costs next to Crocoddyl's, each library's self-sensitivity to a perturbed guess, a one-step
  replay of Crocoddyl's iterations and a verdict per row, and the box-QP backward-pass overhead
  (:mod:`crocopy.bench.box_parity`)
* ``crocopy bench --compat [--problems ...] [--out FILE]``: Crocoddyl's shipped example scripts and gait
  builders run with ``crocoddyl`` bound to crocopy, next to Crocoddyl's own runs (:mod:`crocopy.bench.compat`)
* ``crocopy bench --mim-examples [--problems ...] [--out FILE]``: mim-solvers' example scripts (downloaded once
  from its sdist on PyPI) run with ``crocoddyl`` and ``mim_solvers`` bound to crocopy, next to mim-solvers' own
  runs (:mod:`crocopy.bench.mim_examples`)
* ``crocopy bench --coverage [--problems ...] [--shipped [JOB ...]] [--out FILE]``: nodes compiled / nodes per
  bundled problem and per Crocoddyl script and gait, with why the others are not (:mod:`crocopy.bench.coverage`)
* ``crocopy bench --models [--problems ...]``: calc + calcDiff time and per-model-kind differences of
  every node against Crocoddyl (:mod:`crocopy.bench.node_eval`)
* ``crocopy bench --batch`` / ``--scaling``: :func:`crocopy.solve_many` speed-up on the quadrotor
  starts; time per iteration vs horizon and peak memory (:mod:`crocopy.bench.batch`,
  :mod:`crocopy.bench.scaling`)
* ``crocopy bench --latency [--problems P] [--solver S] [--repeats N]``: seconds from launching
  ``crocopy solve`` to its first iteration line, fresh (empty caches) and warm (:mod:`crocopy.bench.latency`)
* ``crocopy bench --threads [--problems ...]``: node evaluation with ``problem.nthreads`` 1 and 2
  (:mod:`crocopy.bench.threads`)
* ``crocopy bench --mpc [--problems ...]``: a model-predictive cycle (new state references, one warm-started FDDP
  iteration), next to Crocoddyl's when installed (:mod:`crocopy.bench.mpc`)
* ``crocopy bench --first-solve [--problems P] [--solver S] [--repeats N]``: a whole ``crocopy solve`` with its
  HTML, fresh and warm: first iteration, end of the solve, HTML export, exit, CPU, whether the compile notice
  was printed (:mod:`crocopy.bench.first_solve`)
* ``crocopy bench --user-residual [--repeats N]``: the Talos-arm reach with its goal as the built-in residual, a
  ``ResidualModelNumba`` and a Python subclass, next to Crocoddyl's when installed (:mod:`crocopy.bench.user_residual`)
* ``crocopy list``: the bundled problems
* ``crocopy compile``: compile the numba kernels into numba's on-disk cache now (once after
  installing), so that the first ``solve`` starts at once; exit status 1 if a kernel is left uncached
* ``crocopy solve [PROBLEM] [--solver ...] [--maxiter N] [--html FILE] [--plot FILE]``: build a
  problem, solve it with the verbose table, print a summary and write the meshcat animation.
  With no problem it solves the ANYmal jump with Box-FDDP and writes ``jump.html``.
* ``crocopy table1``: Box-FDDP paper Table I next to the paper's figures
* ``crocopy paper box-ddp lq|car``, ``paper box-fddp quadrotor``, ``paper projection arm``,
  ``paper hddp table1|table2``: the papers' experiments

Arguments are checked before any work: unknown problem or experiment names, non-positive counts
(``--maxiter 0``) and output files that cannot be written (``--html``, ``--plot``, ``--out``) are
usage errors, reported with the subcommand's usage line and the valid choices.

Exit status: ``0`` success (``solve``: the solver converged), ``1`` ``solve`` ran but did not
converge, ``2`` usage error (also a missing optional extra, e.g. ``bench --vs`` without Crocoddyl).

Before ``solve`` times the solve, one iteration of the same solver on the same problem loads the
compiled (numba) kernels; on the first run after installation (unless ``crocopy compile`` ran) the kernels
this problem and solver need are compiled (the jump with Box-FDDP: 145 kernels, about 60 s of CPU time in a
fresh cache; the wall time grows with the machine's load), announced by
``compiling kernels (first run only): done/total`` as soon as numba starts compiling
(:class:`crocopy.kernel_warmup.CompileProgress`); a run that compiles nothing prints no notice.  The
reported solve time excludes that warm-up.  With ``--html``, the robot's meshes load on a background
thread while kernels compile (after the solve when nothing compiles, so that they do not slow it).
"""

from __future__ import annotations

import argparse
import os
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import TypeVar

from . import __version__
from .kernel_warmup import CompileProgress, compile_kernels, warm_up_kernels
from .solvers import SOLVERS

EXIT_CONVERGED, EXIT_NOT_CONVERGED, EXIT_USAGE = 0, 1, 2
T = TypeVar("T")
EXIT_STATUS_HELP = (
    "exit status: 0 success (solve: converged), 1 solve did not converge, "
    "2 usage error (bad flag or value, unknown name, unwritable output, missing extra)"
)


def _bench(args: argparse.Namespace) -> int:
    from .bench.command import run_bench

    return run_bench(args)


ROBOT_OF_MODEL = {"2dof_planar": ("double_pendulum",), "": ("talos_legs",), "talos": ("talos", "talos_arm")}
"""example-robot-data names of a Pinocchio model, where they differ from the model's own name (the first of the
same size is the one)."""


def _display_robot(problem):
    """The example-robot-data robot (with meshes) whose model matches the problem's, or None."""
    import example_robot_data

    model = getattr(problem.terminalModel.state, "pinocchio", None)
    if model is None:
        return None
    for name in ROBOT_OF_MODEL.get(model.name, (model.name,)):
        try:
            robot = example_robot_data.load(name)
        except Exception:
            continue
        if robot.model.nq == model.nq and robot.model.nv == model.nv:
            return robot
    return None


def _display_ready(problem) -> tuple:
    """:func:`_display_robot` and a meshcat server spawned for its export (``(None, None)`` without a robot)."""
    from .models.display.server import spawn_meshcat_server

    robot = _display_robot(problem)
    return (robot, spawn_meshcat_server()) if robot is not None else (None, None)


def in_background(function: Callable[..., T], *args: object) -> Callable[[], T]:
    """Start ``function(*args)`` on a daemon thread; the returned callable waits for it and returns its result
    (or raises its exception).  For work that releases the GIL (Pinocchio parsing a robot's meshes)."""
    outcome: dict[str, object] = {}

    def run() -> None:
        try:
            outcome["value"] = function(*args)
        except BaseException as exc:  # noqa: BLE001 - raised again by the caller's wait
            outcome["error"] = exc

    thread = threading.Thread(target=run, name=f"crocopy-{function.__name__}", daemon=True)
    thread.start()

    def wait() -> T:
        thread.join()
        if "error" in outcome:
            raise outcome["error"]
        return outcome["value"]

    return wait


class Deferred:
    """``function(*args)``, started in the background (:func:`in_background`) by :meth:`start`, or run when
    :meth:`result` is asked for it first."""

    def __init__(self, function: Callable[..., T], *args: object) -> None:
        self.function, self.args = function, args
        self.wait: Callable[[], T] | None = None

    def start(self) -> None:
        if self.wait is None:
            self.wait = in_background(self.function, *self.args)

    def result(self) -> T:
        if self.wait is None:
            return self.function(*self.args)
        return self.wait()


class AfterFirstIteration:
    """A solver callback calling ``action()`` once, at the end of the first iteration (after the verbose line)."""

    def __init__(self, action: Callable[[], object]) -> None:
        self.action: Callable[[], object] | None = action

    def __call__(self, solver: object) -> None:
        if self.action is not None:
            action, self.action = self.action, None
            action()


def _list(args: argparse.Namespace) -> int:
    from .problems import registry

    for name in registry.names():
        spec = registry.get(name)
        T, nx, nu = spec.dims
        print(f"{name:12s} T={T:<4d} nx={nx:<3d} nu={nu:<3d} {spec.description}")
    return 0


def one_iteration_each_way(solver_class: type, problem: object, xs: list, us: list) -> None:
    """``crocopy solve``'s warm-up: one iteration from the guess (gaps open), one from its result flagged feasible
    (box steps): every kernel the solve calls, with its argument types."""
    first = solver_class(problem)
    first.solve(xs, us, 1, False)
    solver_class(problem).solve(first.xs, first.us, 1, True)


def _solve(args: argparse.Namespace) -> int:
    import crocopy

    from .problems import registry

    spec = registry.get(args.problem)
    problem, xs, us = spec.build(crocopy)
    solver_class = getattr(crocopy, SOLVERS[args.solver])
    html = None if args.no_html else args.html
    display_robot = Deferred(_display_ready, problem)  # loads while kernels compile, or from the first iteration
    warm_up_kernels(lambda: one_iteration_each_way(solver_class, problem, xs, us),
                    CompileProgress(on_compile=display_robot.start if html else None))
    solver = solver_class(problem)
    if not args.quiet:
        solver.setCallbacks([crocopy.CallbackVerbose()])
    logger = crocopy.CallbackLogger()
    # The robot's meshes load (Pinocchio parsing them, GIL released) and its server starts once the first line is out.
    later = [AfterFirstIteration(display_robot.start)] if html else []
    solver.setCallbacks([*solver.getCallbacks(), logger, *later])
    t0 = time.perf_counter()
    converged = solver.solve(xs, us, args.maxiter or spec.maxiter, False)
    elapsed = time.perf_counter() - t0
    iters = max(solver.iter, 1)
    why = "" if converged else f" ({solver.reason})"
    print(
        f"{args.problem}: {SOLVERS[args.solver]} {'converged' if converged else 'did not converge'}"
        f"{why} after {solver.iter} iterations, cost {solver.cost:.6g},"
        f" {elapsed:.2f} s ({1e3 * elapsed / iters:.1f} ms/iteration)"
    )
    for line in _motion_notes(problem, solver, logger):
        print(f"{args.problem}: {line}")
    # The display's thread (it imports meshcat, hence IPython) ends before pyplot is imported here: pyplot reads a
    # half-imported IPython module otherwise.
    robot, spawned = display_robot.result() if html else (None, None)
    if args.plot:
        from .callbacks.plotting import plot_convergence_from_logger

        plot_convergence_from_logger(logger, args.plot)
        print(f"convergence plot written to {args.plot}")
    if html:
        if robot is None:
            print(f"no meshcat model for {args.problem}; animation not written", file=sys.stderr)
        else:
            from .models.display.html import export_html_on_server

            print(f"meshcat animation written to {export_html_on_server(robot, solver, html, spawned)}")
    return EXIT_CONVERGED if converged else EXIT_NOT_CONVERGED


def cost_climb_note(costs: list[float], gaps: list[float]) -> str | None:
    """Why the verbose table's cost rose above its first value, or ``None`` if it never did.

    ``costs`` and ``gaps`` (``ffeas``) are the logger's per-iteration lists (index = the verbose table's
    ``iter``).  A multiple-shooting
    solver (FDDP, Box-FDDP) starting from an infeasible guess reports the cost of its iterate with
    the gaps still open; the cost climbs while the gaps close, and only then measures a motion the
    dynamics allow.  A climb anywhere else is reported as unexpected.
    """
    if not costs or max(costs) <= costs[0]:
        return None
    peak = int(max(range(len(costs)), key=costs.__getitem__))
    open_gaps = gaps[0] > 0 and min(gaps[: peak + 1]) < gaps[0]
    if open_gaps:
        return (f"the cost rose from {costs[0]:.4g} to {costs[peak]:.4g} (iteration {peak}) while the guess's gaps"
                f" closed ({gaps[0]:.2g} -> {gaps[peak]:.2g}): expected from an infeasible start of multiple"
                f" shooting (the first costs are those of a guess the dynamics do not allow); then down to"
                f" {costs[-1]:.4g}")
    return f"the cost rose from {costs[0]:.4g} to {costs[peak]:.4g} at iteration {peak} (unexpected)"


def _motion_notes(problem, solver, logger) -> list[str]:
    """Summary lines after a solve: flight time and apex of a legged jump, and the cost's climb, if any."""
    from .problems.flight import flight_report

    notes = []
    report = flight_report(problem, solver.xs)
    if report is not None:
        notes.append(
            f"flight {report.flight_time:.2f} s, base apex {100 * report.apex:.1f} cm above its start,"
            f" feet within {report.spread_ratio:.2f}x their standing spread"
            f" and {100 * report.feet_below_base:.0f} cm below the base in flight,"
            f" {'landed on every foot' if report.landed else 'did not land on every foot'}"
        )
    climb = cost_climb_note(logger.costs, logger.ffeass)
    if climb:
        notes.append(climb)
    return notes


def _compile(args: argparse.Namespace) -> int:
    import crocopy

    from .problems import registry

    if args.solve is not None:  # what `crocopy solve PROBLEM --solver S` calls, only (the wheel build's warm-up)
        problem, xs, us = registry.get(args.solve).build(crocopy)
        solver_class = getattr(crocopy, SOLVERS[args.solver])
        warm_up_kernels(lambda: one_iteration_each_way(solver_class, problem, xs, us))
        missing = [k.py_func.__qualname__ for k in crocopy.kernels.KERNELS
                   if k.signatures and not crocopy.kernels.is_cached(k)]
        print(f"kernels of `crocopy solve {args.solve} --solver {args.solver}` ready"
              + (f"; not cached: {', '.join(missing)}" if missing else ""))
        return 1 if missing else 0
    from .bench.compile_runs import warm_up_runs

    return compile_kernels(lambda builder: builder(crocopy), warm_up_runs(crocopy, SOLVERS))


def _table1(args: argparse.Namespace) -> int:
    import crocopy

    from .experiments.table1 import RowResult, format_trend, trend_checks
    from .problems import registry

    results: dict[str, dict[str, RowResult]] = {}
    rows = [
        "| problem | Box-DDP iter | Box-DDP cost | sol | Box-FDDP iter | Box-FDDP cost | sol"
        " | paper Box-DDP | paper Box-FDDP |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for name in args.problems or registry.TABLE1:
        spec = registry.get(name)
        cells = [name]
        for key, solver_name in (("boxddp", "SolverBoxDDP"), ("boxfddp", "SolverBoxFDDP")):
            problem, xs, us = spec.build(crocopy)
            solver = getattr(crocopy, solver_name)(problem)
            ok = solver.solve(xs, us, spec.maxiter, False)
            result = RowResult(solver.iter, solver.cost, spec.solved(ok, solver.cost))
            results.setdefault(name, {})[key] = result
            cells += [str(solver.iter), f"{solver.cost:.6g}", "✓" if result.solved else "✗"]
        paper = registry.PAPER_TABLE1.get(name, {})
        for key in ("boxddp", "boxfddp"):
            it, cost, ok = paper.get(key, (0, float("nan"), False))
            cells.append(f"{it} / {cost:.5g} / {'✓' if ok else '✗'}")
        rows.append("| " + " | ".join(cells) + " |")
        print(rows[-1], flush=True)
    print("\n".join(rows))
    print(format_trend(trend_checks(results)))
    return 0


def _paper(args: argparse.Namespace) -> int:
    key = (args.paper, args.experiment)
    if key == ("box-ddp", "lq"):
        from .experiments.box_ddp_lq import run_lq

        run_lq(out_dir=args.out)
    elif key == ("box-ddp", "car"):
        from .experiments.box_ddp import run_car

        run_car(out_dir=args.out)
    elif key == ("box-fddp", "quadrotor"):
        from .experiments.box_fddp import run_quadrotor_ics

        run_quadrotor_ics(out_dir=args.out)
    elif key == ("projection", "arm"):
        from .experiments.projection import run_projection_arm

        run_projection_arm()
    elif key == ("hddp", "table1"):
        from .experiments.hddp import run_hddp

        run_hddp(trials=args.trials or 100, jobs=args.jobs or 1)
    else:
        from .experiments.hddp import run_hddp_weighted

        run_hddp_weighted()
    return 0


PAPER_EXPERIMENTS = (
    ("box-ddp", "lq"), ("box-ddp", "car"), ("box-fddp", "quadrotor"),
    ("projection", "arm"), ("hddp", "table1"), ("hddp", "table2"),
)


def _positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be a positive integer (1 or more), got {value}")
    return value


def _positive_float(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a positive number, got {text!r}") from None
    if not value > 0:
        raise argparse.ArgumentTypeError(f"must be positive, got {value}")
    return value


def _unwritable(path: str, what: str) -> str | None:
    """Why ``path`` cannot be written (``None`` if it can): tried by opening it for appending."""
    target = Path(path)
    if target.is_dir():
        return f"{what} {path} is a folder, not a file"
    if not target.parent.is_dir():
        return f"{what} {path}: folder {str(target.parent)!r} does not exist"
    existed = target.exists()
    try:
        with open(target, "ab"):
            pass
    except OSError as exc:
        return f"{what} {path} cannot be written: {exc.strerror}"
    if not existed:
        target.unlink()
    return None


def _unwritable_folder(path: str, what: str) -> str | None:
    folder = Path(path)
    if not folder.is_dir():
        return f"{what} {path} is not an existing folder"
    if not os.access(folder, os.W_OK | os.X_OK):
        return f"{what} {path} cannot be written"
    return None


def _unknown_problems(names: list[str] | None) -> str | None:
    from .problems import registry

    unknown = [n for n in names or () if n not in registry.PROBLEMS]
    if unknown:
        return f"unknown problem {unknown[0]!r}; known problems: {', '.join(registry.names())}"
    return None


def _plot_file(path: str) -> tuple[str, str | None]:
    """``path`` with ``.png`` added when it has no suffix, or an error for a format matplotlib cannot write."""
    suffix = Path(path).suffix.lower().lstrip(".")
    if not suffix:
        return f"{path}.png", None
    from matplotlib.backend_bases import FigureCanvasBase

    formats = FigureCanvasBase.get_supported_filetypes()
    if suffix not in formats:
        return path, f"--plot {path}: unknown image format {suffix!r}; use one of {', '.join(sorted(formats))}"
    return path, None


def check_args(args: argparse.Namespace) -> str | None:
    """What is wrong with the parsed ``args`` of a subcommand (``None`` if nothing): names and output paths.

    Also fills in the output names that depend on other arguments: ``solve``'s default
    ``--html <problem>.html`` and a ``.png`` suffix for a ``--plot`` file without one.
    """
    if args.command == "solve":
        error = _unknown_problems([args.problem])
        if error is None and not args.no_html:
            args.html = args.html or f"{args.problem}.html"
            error = _unwritable(args.html, "--html")
        if error is None and args.plot:
            args.plot, error = _plot_file(args.plot)
            error = error or _unwritable(args.plot, "--plot")
        return error
    if args.command == "compile" and args.solve is not None:
        return _unknown_problems([args.solve])
    if args.command in ("table1", "bench"):
        # with --compat (--mim-examples), --problems names Crocoddyl's (mim-solvers') scripts, checked there
        scripts = getattr(args, "compat", False) or getattr(args, "mim_examples", False)
        error = None if scripts else _unknown_problems(args.problems)
        if error is None and args.command == "bench" and args.out:
            error = _unwritable(args.out, "--out")
        return error
    if args.command == "paper":
        known = [e for p, e in PAPER_EXPERIMENTS if p == args.paper]
        if args.experiment not in known:
            return f"unknown experiment {args.paper} {args.experiment!r}; known: {', '.join(known)}"
        return _unwritable_folder(args.out, "--out")
    return None


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="crocopy", description="Optimal control for robots, Crocoddyl-compatible.",
                                     epilog=EXIT_STATUS_HELP)
    parser.add_argument("--version", action="version", version=f"crocopy {__version__}")
    sub = parser.add_subparsers(dest="command")

    def command(name: str, func: Callable[[argparse.Namespace], int], text: str) -> argparse.ArgumentParser:
        p = sub.add_parser(name, help=text, description=text[:1].upper() + text[1:] + ".", epilog=EXIT_STATUS_HELP)
        p.set_defaults(func=func, subparser=p)
        return p

    bench = command("bench", _bench, "time the solvers (and Crocoddyl, if installed) on benchmark problems")
    bench.add_argument("--repeats", type=_positive_int, default=None,
                       help="runs per measurement, median reported (default 20; 5 with --vs)")
    bench.add_argument("--T", type=_positive_int, default=100, help="horizon of the LQR problems")
    bench.add_argument("--vs", choices=["crocoddyl", "mim"], default=None,
                       help="side-by-side run on the bundled problems against Crocoddyl, or SolverSQP/SolverCSQP "
                            "against mim-solvers (crocopy.bench.mim) (needs the bench extra)")
    bench.add_argument("--problems", nargs="+", default=None, help="with --vs: problems (default: Table I, walk, arm)")
    bench.add_argument("--shipped", nargs="*", default=None, metavar="JOB",
                       help="with --vs: Crocoddyl's own problems, built by its example scripts and utils gaits with "
                            "crocopy in its place (crocopy.bench.shipped; default jobs without names). Without "
                            "--problems and --shipped both parts run; with one of them, only that part")
    bench.add_argument("--solver", choices=sorted(SOLVERS), default="boxfddp", help="with --vs: the solver")
    bench.add_argument("--maxiter", type=_positive_int, default=None,
                       help="with --vs: iteration limit (default: the problem's)")
    bench.add_argument("--solve-budget", type=_positive_float, default=30.0,
                       help="with --vs: no further full-solve round starts after this many seconds per problem")
    bench.add_argument("--no-memory", action="store_true", help="with --vs: skip the peak-memory subprocesses")
    bench.add_argument("--out", default=None,
                       help="with --vs, --coverage, --compat or --mim-examples: also write the markdown report "
                            "to this file")
    bench.add_argument("--batch", action="store_true",
                       help="10 quadrotor solves serially and with crocopy.solve_many (crocopy.bench.batch)")
    bench.add_argument("--scaling", action="store_true",
                       help="time per iteration vs horizon (ANYmal trot), peak memory of the hop (bench_scaling)")
    bench.add_argument("--box-parity", action="store_true",
                       help="Box-DDP/Box-FDDP iterations and costs vs Crocoddyl's (bench.box_parity; bench extra)")
    bench.add_argument("--models", action="store_true",
                       help="calc+calcDiff time and per-node differences vs Crocoddyl (crocopy.bench.node_eval)")
    bench.add_argument("--floor", action="store_true",
                       help="calc+calcDiff time inside Pinocchio's bindings vs Crocoddyl (crocopy.bench.floor)")
    bench.add_argument("--compat", action="store_true",
                       help="Crocoddyl's shipped example scripts and gait builders run with crocopy as crocoddyl, "
                            "next to Crocoddyl's own runs (crocopy.bench.compat; bench extra; --problems selects)")
    bench.add_argument("--mim-examples", action="store_true",
                       help="mim-solvers' example scripts (from its sdist on PyPI) run with crocopy as crocoddyl and "
                            "mim_solvers, next to mim-solvers' own runs (crocopy.bench.mim_examples; bench extra; "
                            "--problems selects)")
    bench.add_argument("--coverage", action="store_true",
                       help="nodes compiled / nodes per builder (--problems) and per Crocoddyl script and gait "
                            "(--shipped; bench extra), and why the others are not (crocopy.bench.coverage)")
    bench.add_argument("--latency", action="store_true",
                       help="seconds from launching `crocopy solve` to its first iteration line, with empty and "
                            "with filled caches, and of `import crocopy` (crocopy.bench.latency; first --problems)")
    bench.add_argument("--first-solve", action="store_true",
                       help="a whole `crocopy solve` with its HTML, with empty and with filled caches: first "
                            "iteration, solve, HTML export, CPU (crocopy.bench.first_solve; first --problems)")
    bench.add_argument("--fresh-install", action="store_true",
                       help="with --first-solve or --vs crocoddyl: first install --source into a new venv (pip install"
                            " .), then time its first solve (crocopy.bench.fresh_install)")
    bench.add_argument("--source", default=".", help="with --fresh-install: the crocopy checkout to install (.)")
    bench.add_argument("--user-residual", action="store_true",
                       help="the Talos-arm reach with its goal as the built-in residual, a ResidualModelNumba and a "
                            "Python subclass, ms per iteration and ratios (crocopy.bench.user_residual)")
    bench.add_argument("--threads", action="store_true",
                       help="the compiled nodes' calc+calcDiff with problem.nthreads = 1 and 2, and solves checked "
                            "bit-identical (crocopy.bench.threads; --problems selects)")
    bench.add_argument("--mpc", action="store_true",
                       help="a model-predictive cycle: new state references, then one warm-started FDDP iteration, "
                            "next to Crocoddyl's when installed (crocopy.bench.mpc; --problems selects)")
    bench.add_argument("--workers", type=_positive_int, default=2, help="with --batch: worker processes")
    bench.add_argument("--runs", type=_positive_int, default=3,
                       help="with --batch/--scaling: repetitions (median reported)")
    command("list", _list, "list the bundled problems")
    compile_ = command("compile", _compile,
                       "compile the numba kernels ahead (once after installing; solves then start at once)")
    compile_.add_argument("--solve", default=None, metavar="PROBLEM",
                          help="only the kernels of `crocopy solve PROBLEM --solver S` (see `crocopy list`)")
    compile_.add_argument("--solver", choices=sorted(SOLVERS), default="boxfddp", help="with --solve: the solver")
    solve = command("solve", _solve, "solve a problem and write its meshcat animation")
    solve.add_argument("problem", nargs="?", default="jump", help="problem name, see `crocopy list` (default: jump)")
    solve.add_argument("--solver", choices=sorted(SOLVERS), default="boxfddp")
    solve.add_argument("--maxiter", type=_positive_int, default=None, help="iteration limit (default: the problem's)")
    solve.add_argument("--html", default=None, help="animation file (default: <problem>.html)")
    solve.add_argument("--no-html", action="store_true", help="do not write the animation")
    solve.add_argument("--plot", default=None,
                       help="write the convergence plot to this file (format from the suffix; .png added if none)")
    solve.add_argument("--quiet", action="store_true", help="no verbose table")
    table1 = command("table1", _table1, "Box-FDDP paper Table I: Box-DDP vs Box-FDDP on the bundled problems")
    table1.add_argument("problems", nargs="*", help="rows to run, see `crocopy list` (default: all of Table I)")
    paper = command("paper", _paper, "reproduce a paper experiment (prints its metric, writes plots)")
    paper.add_argument("paper", choices=sorted({p for p, _ in PAPER_EXPERIMENTS}))
    paper.add_argument("experiment", help="; ".join(f"{p}: {e}" for p, e in PAPER_EXPERIMENTS))
    paper.add_argument("--out", default=".", help="existing folder for the plots")
    paper.add_argument("--trials", type=_positive_int, default=None,
                       help="hddp table1: perturbed targets per test (100)")
    paper.add_argument("--jobs", type=_positive_int, default=None,
                       help="hddp table1: worker processes for the trials (1)")
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run the ``crocopy`` command on ``argv`` (default ``sys.argv[1:]``) and return its exit status.

    Usage errors print the subcommand's usage and the reason on stderr and return ``2`` (argparse's
    own exits, ``--help`` and ``--version`` included, are turned into their return value too).
    """
    parser = build_parser()
    try:
        args, extra = parser.parse_known_args(argv)
        owner = getattr(args, "subparser", parser)
        if extra:
            owner.error(f"unrecognized arguments: {' '.join(extra)}")
    except SystemExit as exc:
        return exc.code if isinstance(exc.code, int) else EXIT_USAGE
    if not getattr(args, "func", None):
        parser.print_help()
        return 0
    problem = check_args(args)
    if problem is not None:
        owner.print_usage(sys.stderr)
        print(f"{owner.prog}: error: {problem}", file=sys.stderr)
        return EXIT_USAGE
    return args.func(args)


if __name__ == "__main__":
    sys.exit(main())
