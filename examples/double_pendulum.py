"""Double-pendulum swing-up with one actuated joint (±5 N m, 1 s, 100 nodes): Box-FDDP vs Box-DDP."""

import example_robot_data

import crocopy
from crocopy.models.display.html import export_html_from_solver
from crocopy.problems.pendulum import build_pendulum

for name in ("SolverBoxFDDP", "SolverBoxDDP"):
    problem, xs, us = build_pendulum(crocopy)
    solver = getattr(crocopy, name)(problem)
    converged = solver.solve(xs, us, 500, False)
    print(f"{name}: converged={converged} iterations={solver.iter} cost={solver.cost:.6g}")

print("animation:", export_html_from_solver(example_robot_data.load("double_pendulum"), solver, "pend.html"))
