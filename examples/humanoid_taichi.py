"""Talos taichi (Box-FDDP paper): reach with the right hand, stand on the right foot, balance.

Three phases of 40 nodes (20 ms each) with joint-limit penalties, solved with Box-FDDP.
Run ``python examples/humanoid_taichi.py [--maxiter N] [--live]``; the animation is written to
``taichi.html`` (``--live`` also plays it in a meshcat viewer).
"""

import argparse

import example_robot_data

import crocopy
from crocopy.models.display.html import export_html_from_solver
from crocopy.problems.humanoid import build_taichi

parser = argparse.ArgumentParser(description="Talos taichi solved with Box-FDDP")
parser.add_argument("--maxiter", type=int, default=100, help="iteration limit")
parser.add_argument("--live", action="store_true", help="also play the motion in a meshcat viewer")
args = parser.parse_args()

problem, xs, us = build_taichi(crocopy)
solver = crocopy.SolverBoxFDDP(problem)
solver.setCallbacks([crocopy.CallbackVerbose()])
solver.solve(xs, us, args.maxiter, False)
print(f"taichi: {solver.reason}, {solver.iter} iterations, cost {solver.cost:.2f}")

robot = example_robot_data.load("talos")
print("animation:", export_html_from_solver(robot, solver, "taichi.html"))
if args.live:
    crocopy.MeshcatDisplay(robot).displayFromSolver(solver)
