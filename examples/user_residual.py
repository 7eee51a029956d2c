"""Talos' arm reaching a point, its goal written by the user: as numba functions (``ResidualModelNumba``, the
node stays compiled) and as a Crocoddyl-style Python subclass (only that residual runs in Python), next to the
built-in ``ResidualModelFrameTranslation``.  The residual classes are in ``crocopy/problems/user_residual.py``
(``NumbaFrameTranslation``, ``python_frame_translation``).  Prints each variant's iterations, cost and time per
iteration, checks the numba residual's derivatives, and writes ``reach.html``."""

import time

import numpy as np

import crocopy
from crocopy.cli import main
from crocopy.problems.user_residual import VARIANTS, NumbaFrameTranslation, build_user_reach

for variant in VARIANTS:
    problem, xs, us = build_user_reach(crocopy, variant)
    solver = crocopy.SolverFDDP(problem)
    solver.solve(xs, us, 100)  # the first solve compiles what the problem needs
    start = time.perf_counter()
    solver = crocopy.SolverFDDP(problem)
    solver.solve(xs, us, 100)
    elapsed = time.perf_counter() - start
    print(f"{variant:8s} {solver.iter:4d} iterations  cost {solver.cost:.6f}  "
          f"{1e3 * elapsed / max(solver.iter, 1):.2f} ms/iteration")

state = problem.runningModels[0].state
goal = NumbaFrameTranslation(state, "gripper_left_joint", np.array([0.4, 0.0, 0.4]))
crocopy.check_residual_derivatives(goal)  # raises naming the entry if compute_jacobians were wrong
print("NumbaFrameTranslation: derivatives agree with finite differences")
main(["solve", "reach", "--solver", "fddp"])
