"""ANYmal walking, trotting, pacing or bounding (two gait cycles) solved with Box-FDDP.

Run ``python examples/quadruped_gaits.py [walk|trot|pace|bound] [--maxiter N] [--live]``;
the animation is written to ``<gait>.html`` (``--live`` also plays it in a meshcat viewer).
"""

import argparse

import example_robot_data

import crocopy
from crocopy.models.display.html import export_html_from_solver
from crocopy.problems.quadruped import GAITS, build_gait

parser = argparse.ArgumentParser(description="ANYmal gaits solved with Box-FDDP")
parser.add_argument("gait", nargs="?", default="walk", choices=list(GAITS))
parser.add_argument("--maxiter", type=int, default=100, help="iteration limit")
parser.add_argument("--live", action="store_true", help="also play the motion in a meshcat viewer")
args = parser.parse_args()

problem, xs, us = build_gait(crocopy, args.gait)
solver = crocopy.SolverBoxFDDP(problem)
solver.setCallbacks([crocopy.CallbackVerbose()])
solver.solve(xs, us, args.maxiter, False)
print(f"{args.gait}: {solver.reason}, {solver.iter} iterations, cost {solver.cost:.2f}")
print(f"base moved {solver.xs[-1][0] - solver.xs[0][0]:.3f} m forward")

robot = example_robot_data.load("anymal")
print("animation:", export_html_from_solver(robot, solver, f"{args.gait}.html"))
if args.live:
    crocopy.MeshcatDisplay(robot).displayFromSolver(solver)
