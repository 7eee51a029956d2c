"""Talos on the monkey bar (Box-FDDP paper "bar"): grasp the bar, climb, land on the ground.

The arms' torque limits are ten times Talos' (as in the paper) and the hands have no friction
cone while they hold the bar; solved with Box-FDDP, whose controls stay within those limits.
Run ``python examples/monkey_bar.py [--maxiter N] [--live]``; the animation is written to
``bar.html``, as by ``crocopy solve bar`` (``--live`` also plays it in a meshcat viewer).
"""

import argparse

import example_robot_data
import numpy as np

import crocopy
from crocopy.models.display.html import export_html_from_solver
from crocopy.problems.humanoid import build_monkey_bar

parser = argparse.ArgumentParser(description="Talos monkey bar solved with Box-FDDP")
parser.add_argument("--maxiter", type=int, default=400, help="iteration limit")
parser.add_argument("--live", action="store_true", help="also play the motion in a meshcat viewer")
args = parser.parse_args()

problem, xs, us = build_monkey_bar(crocopy)
solver = crocopy.SolverBoxFDDP(problem)
solver.setCallbacks([crocopy.CallbackVerbose()])
solver.solve(xs, us, args.maxiter, False)
print(f"monkey bar: {solver.reason}, {solver.iter} iterations, cost {solver.cost:.2f}")
excess = max(np.max(np.r_[u - m.u_ub, m.u_lb - u]) for m, u in zip(problem.runningModels, solver.us) if u.size)
print(f"largest torque above its limit: {max(excess, 0.0):.3g} N m")

robot = example_robot_data.load("talos")
print("animation:", export_html_from_solver(robot, solver, "bar.html"))
if args.live:
    crocopy.MeshcatDisplay(robot).displayFromSolver(solver)
