"""Getting started: solve a bundled problem from Python and write its animation."""

import example_robot_data

import crocopy
from crocopy.problems import registry

spec = registry.get("quad-goal")  # `crocopy list` shows every name
problem, xs, us = spec.build()  # the problem and its warm start
solver = crocopy.SolverBoxFDDP(problem)
solver.setCallbacks([crocopy.CallbackVerbose()])
converged = solver.solve(xs, us, spec.maxiter, False)
print(f"converged={converged} iterations={solver.iter} cost={solver.cost:.4g}")
print("final position", solver.xs[-1][:3])

robot = example_robot_data.load("iris")
print("animation:", crocopy.export_html_from_solver(robot, solver, "quad-goal.html"))
