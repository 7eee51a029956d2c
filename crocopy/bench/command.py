"""``crocopy bench``: the dispatcher of the benchmark subcommand's options over the modules of :mod:`crocopy.bench`
(the parser and the other subcommands are in :mod:`crocopy.cli`)."""

from __future__ import annotations

import argparse
import functools
import sys


def _bench_batch_scaling(args: argparse.Namespace) -> int:
    if args.batch:
        from .batch import run_batch_bench

        run_batch_bench(workers=args.workers, repeats=args.runs)
    if args.scaling:
        from .scaling import run_scaling_bench

        run_scaling_bench(repeats=args.runs)
    return 0


def _bench_box_parity(args: argparse.Namespace) -> int:
    from .box_parity import BenchDependencyError, run_box_parity

    try:
        print(run_box_parity(args.problems, maxiter=args.maxiter or None,
                             progress=lambda rows: print(rows, file=sys.stderr, flush=True)))
    except (BenchDependencyError, KeyError) as exc:
        print(exc.args[0], file=sys.stderr)
        return 2
    return 0


def _bench_models(args: argparse.Namespace) -> int:
    from .node_eval import MODEL_PROBLEMS, run_model_bench
    from .side_by_side import BenchDependencyError

    try:
        print(run_model_bench(tuple(args.problems or MODEL_PROBLEMS), repeats=args.repeats or 15))
    except (BenchDependencyError, KeyError) as exc:
        print(exc.args[0], file=sys.stderr)
        return 2
    return 0


def run_bench(args: argparse.Namespace) -> int:
    """Run the benchmark ``args`` asks for (the parsed ``crocopy bench`` arguments); returns the exit status."""
    if args.compat:
        from .compat import run_compat_cli

        return run_compat_cli(args.problems, args.out)
    if args.mim_examples:
        from .mim_examples import run_mim_examples_cli

        return run_mim_examples_cli(args.problems, args.out)
    if args.coverage:
        from .coverage import run_coverage_cli

        return run_coverage_cli(args)
    if args.models:
        return _bench_models(args)
    if args.latency:
        from .latency import run_latency_bench

        problem = args.problems[0] if args.problems else "jump"
        print(run_latency_bench(problem, args.solver, repeats=args.repeats or 3))
        return 0
    if args.mpc:
        from .mpc import PROBLEMS as MPC_PROBLEMS
        from .mpc import run_mpc_bench

        print(run_mpc_bench(tuple(args.problems or MPC_PROBLEMS)))
        return 0
    if args.threads:
        from .threads import PROBLEMS, run_threads_bench

        print(run_threads_bench(tuple(args.problems or PROBLEMS), repeats=args.repeats or 15))
        return 0
    if args.first_solve:
        from .first_solve import run_first_solve_bench
        from .fresh_install import run_fresh_install_bench

        problem = args.problems[0] if args.problems else "jump"
        if not args.fresh_install:
            print(run_first_solve_bench(problem, args.solver, repeats=args.repeats or 2))
            return 0
        try:
            _report(run_fresh_install_bench(args.source, problem, args.solver, repeats=args.repeats or 2), args.out,
                    announce=True)
        except ValueError as exc:
            print(exc.args[0], file=sys.stderr)
            return 2
        return 0
    if args.user_residual:
        from .user_residual import run_user_residual_bench

        print(run_user_residual_bench(repeats=args.repeats or 7))
        return 0
    if args.floor:
        from .floor import FLOOR_PROBLEMS, run_floor_bench

        print(run_floor_bench(tuple(args.problems or FLOOR_PROBLEMS), repeats=args.repeats or 7))
        return 0
    if args.box_parity:
        return _bench_box_parity(args)
    if args.batch or args.scaling:
        return _bench_batch_scaling(args)
    if args.vs:
        return _bench_vs(args)
    from .lqr import run_lqr_bench

    print(run_lqr_bench(repeats=args.repeats or 20, T=args.T))
    return 0


def _bench_vs_mim(args: argparse.Namespace) -> int:
    from .mim import run_vs_mim

    try:
        report = run_vs_mim(args.problems, progress=functools.partial(print, file=sys.stderr, flush=True),
                            repeats=args.repeats or 5)
    except (ImportError, KeyError) as exc:
        print(exc.args[0], file=sys.stderr)
        return 2
    _report(report, args.out, announce=False)
    return 0


def _mim_sections(progress, repeats: int) -> list[str]:
    """SolverSQP/SolverCSQP against mim-solvers and mim-solvers' own examples, when mim-solvers is installed (the
    bench extra); else a line saying they were not run."""
    from .mim import import_mim_solvers, run_vs_mim
    from .mim_examples import format_table, run_mim_examples

    try:
        import_mim_solvers()
    except ImportError as exc:
        return [f"## crocopy vs mim-solvers\n\nNot run: {exc.args[0]}\n"]
    progress("mim-solvers: SQP/CSQP cases, then its own examples")
    return [run_vs_mim(None, progress=progress, repeats=repeats), format_table(run_mim_examples(progress=progress))]


def _bench_vs(args: argparse.Namespace) -> int:
    if args.vs == "mim":
        return _bench_vs_mim(args)
    from .shipped import run_shipped
    from .side_by_side import BenchDependencyError, run_vs

    builders = args.problems is not None or args.shipped is None
    shipped = args.shipped is not None or args.problems is None
    progress = functools.partial(print, file=sys.stderr, flush=True)
    parts = []
    try:
        if args.fresh_install:
            from .fresh_install import check_source

            check_source(args.source)  # refused before any work
        if shipped and args.shipped:
            from .compat import jobs

            jobs(args.shipped)  # unknown names are refused before any work
        if builders:
            parts.append(run_vs(args.problems, solver_name=args.solver, repeats=args.repeats or 5,
                                maxiter=args.maxiter or None, solve_budget=args.solve_budget,
                                memory=not args.no_memory, progress=progress))
        if shipped:
            parts.append(run_shipped(args.shipped, repeats=args.repeats or 3, progress=progress))
        if args.problems is None and args.shipped is None:
            from .user_residual import SECTION, run_user_residual_bench

            progress("user residual: the Talos-arm reach, three ways")
            parts.append(SECTION + run_user_residual_bench(repeats=args.repeats or 5, crocoddyl=True) + "\n")
            from .threads import SECTION as THREADS
            from .threads import run_threads_bench

            progress("two threads: taichi and walk")
            parts.append(THREADS + run_threads_bench())
            from .mpc import run_mpc_bench

            progress("model-predictive cycle: quad-goal, arm, walk")
            parts.append(run_mpc_bench())
            from .coverage import run_coverage

            progress("compiled nodes: every builder, script and gait")
            parts.append(run_coverage([], [], progress))
            parts.extend(_mim_sections(progress, args.repeats or 5))
        if args.fresh_install:
            from .fresh_install import run_fresh_install_bench

            parts.append(run_fresh_install_bench(args.source, progress=progress))
    except (BenchDependencyError, KeyError, ValueError) as exc:
        print(exc.args[0], file=sys.stderr)
        return 2
    _report("\n".join(parts), args.out, announce=True)
    return 0


def _report(report: str, out: str | None, announce: bool) -> None:
    """Print ``report`` and write it to ``out`` when given (saying so on stderr if ``announce``)."""
    print(report)
    if out:
        with open(out, "w", encoding="utf-8") as f:
            f.write(report)
        if announce:
            print(f"report written to {out}", file=sys.stderr)
