"""Double-pendulum swing-up with one actuated joint (±5 N m, 1 s, 100 nodes): Box-FDDP vs Box-DDP.

Both box solvers start from the same guess; Box-FDDP converges (92 iterations) while Box-DDP, whose
first rollout must already be feasible, does not find the swing-up: it ends far from it, either at its
500-iteration limit or converged to a worse minimum (which one is round-off sensitive; each solver's line
prints its actual outcome).  The animation ``pend.html`` shows Box-FDDP's converged swing-up.
"""

import example_robot_data

import crocopy
from crocopy.models.display.html import export_html_from_solver
from crocopy.problems.pendulum import build_pendulum

solvers = {}
for name in ("SolverBoxFDDP", "SolverBoxDDP"):
    problem, xs, us = build_pendulum(crocopy)
    solver = getattr(crocopy, name)(problem)
    converged = solver.solve(xs, us, 500, False)
    solvers[name] = solver
    print(f"{name}: converged={converged} ({solver.reason}) iterations={solver.iter} cost={solver.cost:.6g}")

shown = solvers["SolverBoxFDDP"]
page = export_html_from_solver(example_robot_data.load("double_pendulum"), shown, "pend.html")
print(f"animation of SolverBoxFDDP's swing-up ({shown.iter} iterations, cost {shown.cost:.6g}): {page}")
