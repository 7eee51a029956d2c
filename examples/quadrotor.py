"""IRIS quadrotor way-point tasks (Box-FDDP paper): reach a goal, loop, or cross a narrow passage.

Each of the four thrusts is bounded to 0.1-10.3 N; solved with Box-FDDP from a cold start.
Run ``python examples/quadrotor.py [goal|loop|narrow] [--maxiter N] [--live]``; the animation is
written to ``quad-<task>.html``, as by ``crocopy solve quad-<task>`` (``--live`` also plays it in a
meshcat viewer).
"""

import argparse

import example_robot_data
import numpy as np

import crocopy
from crocopy.models.display.html import export_html_from_solver
from crocopy.problems.quadrotor import THRUST_RANGE, build_quadrotor

parser = argparse.ArgumentParser(description="IRIS quadrotor tasks solved with Box-FDDP")
parser.add_argument("task", nargs="?", default="goal", choices=("goal", "loop", "narrow"))
parser.add_argument("--maxiter", type=int, default=200, help="iteration limit")
parser.add_argument("--live", action="store_true", help="also play the motion in a meshcat viewer")
args = parser.parse_args()

problem, xs, us = build_quadrotor(crocopy, task=args.task)
solver = crocopy.SolverBoxFDDP(problem)
solver.setCallbacks([crocopy.CallbackVerbose()])
solver.solve(xs, us, args.maxiter, False)
print(f"{args.task}: {solver.reason}, {solver.iter} iterations, cost {solver.cost:.4g}")
thrusts = np.array(solver.us)
print(f"thrusts in [{thrusts.min():.2f}, {thrusts.max():.2f}] N (limits {THRUST_RANGE})")
print("final position", np.round(solver.xs[-1][:3], 3), "m")

robot = example_robot_data.load("iris")
camera = [0.0, -3.0, 1.5, 0.0, 0.0, 0.0, 1.0]  # camera rig moved back: the flights span metres
print("animation:", export_html_from_solver(robot, solver, f"quad-{args.task}.html", cameraTF=camera))
if args.live:
    crocopy.MeshcatDisplay(robot, cameraTF=camera).displayFromSolver(solver)
