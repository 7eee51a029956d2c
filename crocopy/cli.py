"""The ``crocopy`` command.

* ``crocopy --version``
* ``crocopy bench``: solver timings on LQR problems (and Crocoddyl's, when installed)
* ``crocopy bench --vs crocoddyl [--problems ...] [--repeats N] [--out BENCHMARKS.md]``: crocopy and
  Crocoddyl side by side on the bundled problems (:mod:`crocopy.bench.side_by_side`)
* ``crocopy bench --box-parity [--problems ...] [--maxiter N]``: Box-DDP/Box-FDDP iterations and
  final costs next to Crocoddyl's, each library's self-sensitivity to a perturbed guess, a one-step
  replay of Crocoddyl's iterations and a verdict per row, and the box-QP backward-pass overhead
  (:mod:`crocopy.bench.box_parity`)
* ``crocopy bench --models [--problems ...]``: calc + calcDiff time and per-model-kind differences of
  every node against Crocoddyl (:mod:`crocopy.bench.node_eval`)
* ``crocopy bench --batch`` / ``--scaling``: :func:`crocopy.solve_many` speed-up on the quadrotor
  starts; time per iteration vs horizon and peak memory (:mod:`crocopy.bench.batch`,
  :mod:`crocopy.bench.scaling`)
* ``crocopy list``: the bundled problems
* ``crocopy solve [PROBLEM] [--solver ...] [--maxiter N] [--html FILE] [--plot FILE]``: build a
  problem, solve it with the verbose table, print a summary and write the meshcat animation.
  With no problem it solves the ANYmal jump with Box-FDDP and writes ``jump.html``.
* ``crocopy table1``: Box-FDDP paper Table I next to the paper's figures
* ``crocopy paper box-ddp lq|car``, ``paper box-fddp quadrotor``, ``paper projection arm``,
  ``paper hddp table1|table2``: the papers' experiments
"""

from __future__ import annotations

import argparse
import sys
import time

from . import __version__
from .solvers import SOLVERS


def _bench_batch_scaling(args: argparse.Namespace) -> int:
    if args.batch:
        from .bench.batch import run_batch_bench

        run_batch_bench(workers=args.workers, repeats=args.runs)
    if args.scaling:
        from .bench.scaling import run_scaling_bench

        run_scaling_bench(repeats=args.runs)
    return 0


def _bench_box_parity(args: argparse.Namespace) -> int:
    from .bench.box_parity import BenchDependencyError, run_box_parity

    try:
        print(run_box_parity(args.problems, maxiter=args.maxiter or None,
                             progress=lambda rows: print(rows, file=sys.stderr, flush=True)))
    except (BenchDependencyError, KeyError) as exc:
        print(exc.args[0], file=sys.stderr)
        return 2
    return 0


def _bench_models(args: argparse.Namespace) -> int:
    from .bench.node_eval import MODEL_PROBLEMS, run_model_bench
    from .bench.side_by_side import BenchDependencyError

    try:
        print(run_model_bench(tuple(args.problems or MODEL_PROBLEMS), repeats=args.repeats or 15))
    except (BenchDependencyError, KeyError) as exc:
        print(exc.args[0], file=sys.stderr)
        return 2
    return 0


def _bench(args: argparse.Namespace) -> int:
    if args.models:
        return _bench_models(args)
    if args.floor:
        from .bench.floor import FLOOR_PROBLEMS, run_floor_bench

        print(run_floor_bench(tuple(args.problems or FLOOR_PROBLEMS), repeats=args.repeats or 7))
        return 0
    if args.box_parity:
        return _bench_box_parity(args)
    if args.batch or args.scaling:
        return _bench_batch_scaling(args)
    if args.vs:
        return _bench_vs(args)
    from .bench.lqr import run_lqr_bench

    print(run_lqr_bench(repeats=args.repeats or 20, T=args.T))
    return 0


def _bench_vs(args: argparse.Namespace) -> int:
    from .bench.side_by_side import BenchDependencyError, run_vs

    try:
        report = run_vs(args.problems, solver_name=args.solver, repeats=args.repeats or 5, maxiter=args.maxiter or None,
                        solve_budget=args.solve_budget, memory=not args.no_memory,
                        progress=lambda line: print(line, file=sys.stderr, flush=True))
    except (BenchDependencyError, KeyError) as exc:
        print(exc.args[0], file=sys.stderr)
        return 2
    print(report)
    if args.out:
        with open(args.out, "w", encoding="utf-8") as f:
            f.write(report)
        print(f"report written to {args.out}", file=sys.stderr)
    return 0


ROBOT_OF_MODEL = {"2dof_planar": "double_pendulum", "": "talos_legs"}
"""example-robot-data name of a Pinocchio model, where it differs from the model's own name."""


def _display_robot(problem):
    """The example-robot-data robot (with meshes) whose model matches the problem's, or None."""
    import example_robot_data

    model = getattr(problem.terminalModel.state, "pinocchio", None)
    if model is None:
        return None
    name = ROBOT_OF_MODEL.get(model.name, model.name)
    try:
        robot = example_robot_data.load(name)
    except Exception:
        return None
    return robot if robot.model.nq == model.nq and robot.model.nv == model.nv else None


def _list(args: argparse.Namespace) -> int:
    from .problems import registry

    for name in registry.names():
        spec = registry.get(name)
        T, nx, nu = spec.dims
        print(f"{name:12s} T={T:<4d} nx={nx:<3d} nu={nu:<3d} {spec.description}")
    return 0


def _solve(args: argparse.Namespace) -> int:
    import crocopy

    from .problems import registry

    try:
        spec = registry.get(args.problem)
    except KeyError as exc:
        print(exc.args[0], file=sys.stderr)
        return 2
    problem, xs, us = spec.build(crocopy)
    solver = getattr(crocopy, SOLVERS[args.solver])(problem)
    if not args.quiet:
        solver.setCallbacks([crocopy.CallbackVerbose()])
    logger = crocopy.CallbackLogger()
    solver.setCallbacks([*solver.getCallbacks(), logger])
    t0 = time.perf_counter()
    converged = solver.solve(xs, us, args.maxiter or spec.maxiter, False)
    elapsed = time.perf_counter() - t0
    iters = max(solver.iter, 1)
    print(
        f"{args.problem}: {SOLVERS[args.solver]} {'converged' if converged else 'did not converge'}"
        f" ({solver.reason}) after {solver.iter} iterations, cost {solver.cost:.6g},"
        f" {elapsed:.2f} s ({1e3 * elapsed / iters:.1f} ms/iteration)"
    )
    if args.plot:
        from .callbacks.plotting import plot_convergence_from_logger

        print(f"convergence plot written to {plot_convergence_from_logger(logger, args.plot)}")
    html = None if args.no_html else (args.html or f"{args.problem}.html")
    if html:
        robot = _display_robot(problem)
        if robot is None:
            print(f"no meshcat model for {args.problem}; animation not written", file=sys.stderr)
        else:
            from .models.display.html import export_html_from_solver

            print(f"meshcat animation written to {export_html_from_solver(robot, solver, html)}")
    return 0


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
        if name not in registry.PROBLEMS:
            continue
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
    elif key == ("hddp", "table2"):
        from .experiments.hddp import run_hddp_weighted

        run_hddp_weighted()
    else:
        known = ", ".join(" ".join(k) for k in PAPER_EXPERIMENTS)
        print(f"unknown experiment {args.paper} {args.experiment}; known: {known}", file=sys.stderr)
        return 2
    return 0


PAPER_EXPERIMENTS = (
    ("box-ddp", "lq"), ("box-ddp", "car"), ("box-fddp", "quadrotor"),
    ("projection", "arm"), ("hddp", "table1"), ("hddp", "table2"),
)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="crocopy", description="Optimal control for robots, Crocoddyl-compatible.")
    parser.add_argument("--version", action="version", version=f"crocopy {__version__}")
    sub = parser.add_subparsers(dest="command")
    bench = sub.add_parser("bench", help="time the solvers (and Crocoddyl, if installed) on benchmark problems")
    bench.add_argument("--repeats", type=int, default=0,
                       help="runs per measurement, median reported (default 20; 5 with --vs)")
    bench.add_argument("--T", type=int, default=100, help="horizon of the LQR problems")
    bench.add_argument("--vs", choices=["crocoddyl"], default=None,
                       help="side-by-side run on the bundled problems against Crocoddyl (needs the bench extra)")
    bench.add_argument("--problems", nargs="+", default=None, help="with --vs: problems (default: Table I, walk, arm)")
    bench.add_argument("--solver", choices=sorted(SOLVERS), default="boxfddp", help="with --vs: the solver")
    bench.add_argument("--maxiter", type=int, default=0, help="with --vs: iteration limit (default: the problem's)")
    bench.add_argument("--solve-budget", type=float, default=30.0,
                       help="with --vs: no further full-solve round starts after this many seconds per problem")
    bench.add_argument("--no-memory", action="store_true", help="with --vs: skip the peak-memory subprocesses")
    bench.add_argument("--out", default=None, help="with --vs: also write the markdown report to this file")
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
    bench.add_argument("--workers", type=int, default=2, help="with --batch: worker processes")
    bench.add_argument("--runs", type=int, default=3, help="with --batch/--scaling: repetitions (median reported)")
    bench.set_defaults(func=_bench)
    sub.add_parser("list", help="list the bundled problems").set_defaults(func=_list)
    solve = sub.add_parser("solve", help="solve a problem and write its meshcat animation")
    solve.add_argument("problem", nargs="?", default="jump", help="problem name (default: jump)")
    solve.add_argument("--solver", choices=sorted(SOLVERS), default="boxfddp")
    solve.add_argument("--maxiter", type=int, default=0, help="iteration limit (default: the problem's)")
    solve.add_argument("--html", default=None, help="animation file (default: <problem>.html)")
    solve.add_argument("--no-html", action="store_true", help="do not write the animation")
    solve.add_argument("--plot", default=None, help="write the convergence plot (PNG) to this file")
    solve.add_argument("--quiet", action="store_true", help="no verbose table")
    solve.set_defaults(func=_solve)
    table1 = sub.add_parser("table1", help="Box-FDDP paper Table I: Box-DDP vs Box-FDDP on the bundled problems")
    table1.add_argument("problems", nargs="*", help="rows to run (default: all of Table I)")
    table1.set_defaults(func=_table1)
    paper = sub.add_parser("paper", help="reproduce a paper experiment (prints its metric, writes plots)")
    paper.add_argument("paper", choices=sorted({p for p, _ in PAPER_EXPERIMENTS}))
    paper.add_argument("experiment")
    paper.add_argument("--out", default=".", help="folder for the plots")
    paper.add_argument("--trials", type=int, default=None, help="hddp table1: perturbed targets per test (100)")
    paper.add_argument("--jobs", type=int, default=None, help="hddp table1: worker processes for the trials (1)")
    paper.set_defaults(func=_paper)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_help()
        return 0
    return args.func(args)


if __name__ == "__main__":
    sys.exit(main())
