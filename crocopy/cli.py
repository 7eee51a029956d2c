"""The ``crocopy`` command: ``crocopy --version``, ``crocopy bench``."""

from __future__ import annotations

import argparse
import sys

from . import __version__


def _bench(args: argparse.Namespace) -> int:
    from .bench import run_lqr_bench

    print(run_lqr_bench(repeats=args.repeats, T=args.T))
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="crocopy", description="Optimal control for robots, Crocoddyl-compatible.")
    parser.add_argument("--version", action="version", version=f"crocopy {__version__}")
    sub = parser.add_subparsers(dest="command")
    bench = sub.add_parser("bench", help="time the solvers (and Crocoddyl, if installed) on benchmark problems")
    bench.add_argument("--repeats", type=int, default=20, help="runs per measurement (median reported)")
    bench.add_argument("--T", type=int, default=100, help="horizon of the LQR problems")
    bench.set_defaults(func=_bench)
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
