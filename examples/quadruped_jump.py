"""ANYmal's jump (Box-FDDP paper): 32 N m torque limits, solved with Box-FDDP, shown in meshcat.

The cost asks for the base 30 cm up at mid-flight; with 32 N m the solution lifts the base by 13 cm
and the centre of mass by 18 cm (a 400 ms flight rises at most about 20 cm).

Run ``python examples/quadruped_jump.py`` (add ``--live`` to open the meshcat viewer in a browser);
the animation is written to ``jump.html``.
"""

import sys

import example_robot_data

import crocopy
from crocopy.models.display.html import export_html_from_solver
from crocopy.problems.quadruped import build_jump

problem, xs, us = build_jump(crocopy)
solver = crocopy.SolverBoxFDDP(problem)
solver.setCallbacks([crocopy.CallbackVerbose()])
solver.solve(xs, us, 300, False)
print(f"{solver.reason}: {solver.iter} iterations, cost {solver.cost:.2f}")
print("max |torque| =", max(abs(u).max() for u in solver.us if u.size), "N m (limit 32)")

robot = example_robot_data.load("anymal")
print("animation:", export_html_from_solver(robot, solver, "jump.html"))
if "--live" in sys.argv:
    display = crocopy.MeshcatDisplay(robot)
    display.displayFromSolver(solver)
