"""The ``crocopy`` command.

* ``crocopy --version``
* ``crocopy bench``: solver timings on LQR problems (and Crocoddyl's, when installed)
* ``crocopy solve [PROBLEM] [--solver ...] [--maxiter N] [--html FILE] [--plot FILE]``: build a
  problem, solve it with the verbose table, print a summary and write the meshcat animation.
  With no problem it solves the ANYmal jump with Box-FDDP and writes ``jump.html``.
"""

from __future__ import annotations

import argparse
import sys
import time

from . import __version__

SOLVERS = {
    "boxfddp": "SolverBoxFDDP",
    "boxddp": "SolverBoxDDP",
    "fddp": "SolverFDDP",
    "ddp": "SolverDDP",
}


def _bench(args: argparse.Namespace) -> int:
    from .bench import run_lqr_bench

    print(run_lqr_bench(repeats=args.repeats, T=args.T))
    return 0


def _build_jump(lib):
    """The ANYmal jump of the Box-FDDP paper and the robot used to display it."""
    import example_robot_data

    from .problems.quadruped import build_jump

    problem, xs, us = build_jump(lib)
    return problem, xs, us, example_robot_data.load("anymal"), 100


PROBLEM_BUILDERS = {"jump": _build_jump}


def _solve(args: argparse.Namespace) -> int:
    import crocopy

    if args.problem not in PROBLEM_BUILDERS:
        print(f"unknown problem {args.problem!r}; choose from: {', '.join(sorted(PROBLEM_BUILDERS))}", file=sys.stderr)
        return 2
    problem, xs, us, robot, maxiter = PROBLEM_BUILDERS[args.problem](crocopy)
    solver = getattr(crocopy, SOLVERS[args.solver])(problem)
    if not args.quiet:
        solver.setCallbacks([crocopy.CallbackVerbose()])
    t0 = time.perf_counter()
    converged = solver.solve(xs, us, args.maxiter or maxiter, False)
    elapsed = time.perf_counter() - t0
    iters = max(solver.iter, 1)
    print(
        f"{args.problem}: {SOLVERS[args.solver]} {'converged' if converged else 'did not converge'}"
        f" ({solver.reason}) after {solver.iter} iterations, cost {solver.cost:.6g},"
        f" {elapsed:.2f} s ({1e3 * elapsed / iters:.1f} ms/iteration)"
    )
    html = args.html or (f"{args.problem}.html" if not args.no_html else None)
    if html:
        from .models.html_export import export_html_from_solver

        path = export_html_from_solver(robot, solver, html)
        print(f"meshcat animation written to {path}")
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="crocopy", description="Optimal control for robots, Crocoddyl-compatible.")
    parser.add_argument("--version", action="version", version=f"crocopy {__version__}")
    sub = parser.add_subparsers(dest="command")
    bench = sub.add_parser("bench", help="time the solvers (and Crocoddyl, if installed) on benchmark problems")
    bench.add_argument("--repeats", type=int, default=20, help="runs per measurement (median reported)")
    bench.add_argument("--T", type=int, default=100, help="horizon of the LQR problems")
    bench.set_defaults(func=_bench)
    solve = sub.add_parser("solve", help="solve a problem and write its meshcat animation")
    solve.add_argument("problem", nargs="?", default="jump", help="problem name (default: jump)")
    solve.add_argument("--solver", choices=sorted(SOLVERS), default="boxfddp")
    solve.add_argument("--maxiter", type=int, default=0, help="iteration limit (default: the problem's)")
    solve.add_argument("--html", default=None, help="animation file (default: <problem>.html)")
    solve.add_argument("--no-html", action="store_true", help="do not write the animation")
    solve.add_argument("--quiet", action="store_true", help="no verbose table")
    solve.set_defaults(func=_solve)
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
