"""ANYmal's jump (Box-FDDP paper): 32 N m torque limits, solved with Box-FDDP, shown in meshcat.

The cost asks for the base 22 cm above standing at mid-flight (the height 32 N m reach: a 400 ms
flight rises 19.6 cm, from a take-off with the legs extended) with the feet kept under the body;
the robot lands back on its four feet.  The script prints the flight time, the base apex, the feet's
spread and the landing, measured on the solution (:mod:`crocopy.problems.flight`).

Run ``python examples/quadruped_jump.py`` (add ``--live`` to open the meshcat viewer in a browser);
the animation is written to ``jump.html``, as by ``crocopy solve``.
"""

import sys

import example_robot_data

import crocopy
from crocopy.models.display.html import export_html_from_solver
from crocopy.problems import registry
from crocopy.problems.flight import flight_report
from crocopy.problems.quadruped import JUMP_HEIGHT, build_jump

problem, xs, us = build_jump(crocopy)
solver = crocopy.SolverBoxFDDP(problem)
solver.setCallbacks([crocopy.CallbackVerbose()])
converged = solver.solve(xs, us, registry.get("jump").maxiter, False)
print(f"converged={converged} ({solver.reason}): {solver.iter} iterations, cost {solver.cost:.2f}")
print("max |torque| =", max(abs(u).max() for u in solver.us if u.size), "N m (limit 32)")
report = flight_report(problem, solver.xs)
print(f"flight {report.flight_time:.2f} s, base apex {100 * report.apex:.1f} cm (asked {100 * JUMP_HEIGHT:.0f} cm),"
      f" feet within {report.spread_ratio:.2f}x their standing spread, landed on every foot: {report.landed}")

robot = example_robot_data.load("anymal")
print("animation:", export_html_from_solver(robot, solver, "jump.html"))
if "--live" in sys.argv:
    display = crocopy.MeshcatDisplay(robot)
    display.displayFromSolver(solver)
