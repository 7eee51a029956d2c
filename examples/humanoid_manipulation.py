"""Talos whole-body manipulation (Box-FDDP paper "man"): the right hand reaches a point, feet fixed.

60 nodes of 20 ms in double support (wrench cones, joint limits), solved with Box-FDDP.
Run ``python examples/humanoid_manipulation.py [--target X Y Z] [--maxiter N] [--live]``; the
animation is written to ``man.html``, as by ``crocopy solve man`` (``--live`` also plays it in a meshcat
viewer).
"""

import argparse

import example_robot_data
import numpy as np
import pinocchio as pin

import crocopy
from crocopy.models.display.html import export_html_from_solver
from crocopy.problems.humanoid import HANDS, build_manipulation

parser = argparse.ArgumentParser(description="Talos whole-body manipulation solved with Box-FDDP")
parser.add_argument("--target", type=float, nargs=3, default=(0.4, -0.2, 1.1), help="hand target (m)")
parser.add_argument("--maxiter", type=int, default=100, help="iteration limit")
parser.add_argument("--live", action="store_true", help="also play the motion in a meshcat viewer")
args = parser.parse_args()

problem, xs, us = build_manipulation(crocopy, target=args.target)
solver = crocopy.SolverBoxFDDP(problem)
solver.setCallbacks([crocopy.CallbackVerbose()])
solver.solve(xs, us, args.maxiter, False)
print(f"manipulation: {solver.reason}, {solver.iter} iterations, cost {solver.cost:.2f}")

robot = example_robot_data.load("talos")
model, data = robot.model, robot.model.createData()
pin.framesForwardKinematics(model, data, solver.xs[-1][: model.nq])
hand = data.oMf[model.getFrameId(HANDS[1])].translation
print(f"right hand ends {1e3 * np.linalg.norm(hand - np.array(args.target)):.1f} mm from the target")
print("animation:", export_html_from_solver(robot, solver, "man.html"))
if args.live:
    crocopy.MeshcatDisplay(robot).displayFromSolver(solver)
