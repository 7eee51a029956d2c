"""crocopy's SolverSQP/SolverCSQP against mim-solvers 0.3.0 (``crocopy bench --vs mim``).

Each problem is built by the same function with either library (``lib`` = :mod:`crocopy` or
``crocoddyl``) and solved by crocopy's and mim-solvers' solver of the same name from ``x0`` at every
node and zero controls.  Per library: iterations, final cost, KKT, the constraint violation
(``max(lb - g, 0, g - ub)``, ∞-norm over nodes, equalities included), convergence and wall time per
iteration (one thread).  The problems:

* ``kinova_free``: Kinova reaching (T = 50, dt = 0.02), no constraint (SQP and CSQP);
* ``kinova_ubound``: the same with ``|u| <= 25`` N m written as constraints on every running node;
* ``ur5_ee_box``: UR5 end effector kept in the box ``[0.3, 1] × [-1, 0.25] × [0.1, 0.6]`` (running and
  terminal nodes) while reaching for ``(0.4, 0.4, 0.4)``, outside it;
* ``ur5_ee_eq``: UR5 terminal end-effector position as an equality (``lb == ub``);
* ``solo12_joint_limits``: Solo12 standing on its four feet, CoM pushed forward, its joint positions
  kept within a narrowed range by state constraints.

mim-solvers needs ``import crocoddyl`` before ``import mim_solvers``; it is only run (black box).
"""

from __future__ import annotations

import time
from types import ModuleType

import numpy as np
import pinocchio as pin

from crocopy.problems.common import load_model

MIM_PROBLEMS = ("kinova_free", "kinova_ubound", "ur5_ee_box", "ur5_ee_eq", "solo12_joint_limits")
"""Problems of the comparison, in report order."""


def _arm(lib: ModuleType, robot: str, T: int, dt: float, target, constraints) -> object:
    """A fixed-base arm reaching ``target``; ``constraints(state, nu, terminal)`` gives each node's manager."""
    frame = {"kinova": "j2s6s200_end_effector", "ur5": "tool0"}[robot]
    model = load_model(robot)
    q0 = (np.array(model.referenceConfigurations["arm_up"]) if robot == "kinova"
          else np.array([0.0, -1.0, 1.5, -0.5, 1.0, 0.0]))
    x0 = np.concatenate([q0, np.zeros(model.nv)])
    state = lib.StateMultibody(model)
    actuation = lib.ActuationModelFull(state)
    nu = actuation.nu
    fid = model.getFrameId(frame)

    def node(terminal: bool):
        costs = lib.CostModelSum(state, nu)
        goal = lib.CostModelResidual(state, lib.ResidualModelFrameTranslation(state, fid, np.asarray(target), nu))
        xreg = lib.CostModelResidual(state, lib.ResidualModelState(state, x0, nu))
        costs.addCost("goal", goal, 1e3 if terminal else 1e1)
        costs.addCost("state", xreg, 1e1 if terminal else 1e-1)
        if not terminal:
            costs.addCost("control", lib.CostModelResidual(state, lib.ResidualModelControl(state, nu)), 1e-3)
        manager = constraints(state, nu, fid, terminal)
        dam = lib.DifferentialActionModelFreeFwdDynamics(state, actuation, costs, manager)
        return lib.IntegratedActionModelEuler(dam, 0.0 if terminal else dt)

    return lib.ShootingProblem(x0, [node(False) for _ in range(T)], node(True))


def _none(lib):
    return lambda state, nu, fid, terminal: lib.ConstraintModelManager(state, nu)


def _control_box(lib, bound: float):
    def make(state, nu, fid, terminal):
        manager = lib.ConstraintModelManager(state, nu)
        if not terminal:
            res = lib.ResidualModelControl(state, nu)
            box = bound * np.ones(nu)
            manager.addConstraint("u", lib.ConstraintModelResidual(state, res, -box, box))
        return manager
    return make


def _ee_box(lib, lb, ub):
    def make(state, nu, fid, terminal):
        manager = lib.ConstraintModelManager(state, nu)
        res = lib.ResidualModelFrameTranslation(state, fid, np.zeros(3), nu)
        manager.addConstraint("ee", lib.ConstraintModelResidual(state, res, np.asarray(lb), np.asarray(ub)))
        return manager
    return make


def _ee_terminal(lib, target):
    def make(state, nu, fid, terminal):
        manager = lib.ConstraintModelManager(state, nu)
        if terminal:
            res = lib.ResidualModelFrameTranslation(state, fid, np.zeros(3), nu)
            manager.addConstraint("ee", lib.ConstraintModelResidual(state, res, np.asarray(target), np.asarray(target)))
        return manager
    return make


def _solo12(lib: ModuleType, T: int = 30, dt: float = 0.02) -> object:
    """Solo12 on its four feet (3D contacts), CoM moved 4 cm forward, joints limited by constraints."""
    model = load_model("solo12")
    q0 = np.array(model.referenceConfigurations["standing"])
    x0 = np.concatenate([q0, np.zeros(model.nv)])
    state = lib.StateMultibody(model)
    actuation = lib.ActuationModelFloatingBase(state)
    nu = actuation.nu
    data = model.createData()
    pin.framesForwardKinematics(model, data, q0)
    com = pin.centerOfMass(model, data, q0) + np.array([0.04, 0.0, 0.0])
    feet = ["FL_FOOT", "FR_FOOT", "HL_FOOT", "HR_FOOT"]
    lower = np.r_[-np.inf * np.ones(6), q0[7:] - 0.15, -np.inf * np.ones(model.nv)]
    upper = np.r_[np.inf * np.ones(6), q0[7:] + 0.15, np.inf * np.ones(model.nv)]

    def node(terminal: bool):
        contacts = lib.ContactModelMultiple(state, nu)
        for name in feet:
            fid = model.getFrameId(name)
            contact = lib.ContactModel3D(state, fid, data.oMf[fid].translation, pin.LOCAL_WORLD_ALIGNED, nu,
                                         np.array([0.0, 50.0]))
            contacts.addContact(name, contact)
        costs = lib.CostModelSum(state, nu)
        costs.addCost("com", lib.CostModelResidual(state, lib.ResidualModelCoMPosition(state, com, nu)),
                      1e4 if terminal else 1e2)
        costs.addCost("state", lib.CostModelResidual(state, lib.ResidualModelState(state, x0, nu)), 1.0)
        if not terminal:
            costs.addCost("control", lib.CostModelResidual(state, lib.ResidualModelControl(state, nu)), 1e-2)
        manager = lib.ConstraintModelManager(state, nu)
        res = lib.ResidualModelState(state, state.zero(), nu)
        manager.addConstraint("joints", lib.ConstraintModelResidual(state, res, lower, upper))
        dam = lib.DifferentialActionModelContactFwdDynamics(state, actuation, contacts, costs, manager, 0.0, True)
        return lib.IntegratedActionModelEuler(dam, 0.0 if terminal else dt)

    return lib.ShootingProblem(x0, [node(False) for _ in range(T)], node(True))


def build_problem(lib: ModuleType, name: str) -> object:
    """The problem ``name`` (one of :data:`MIM_PROBLEMS`) built with ``lib``."""
    if name == "kinova_free":
        return _arm(lib, "kinova", 50, 0.02, (0.4, 0.3, 0.6), _none(lib))
    if name == "kinova_ubound":
        return _arm(lib, "kinova", 50, 0.02, (0.4, 0.3, 0.6), _control_box(lib, 25.0))
    if name == "ur5_ee_box":
        return _arm(lib, "ur5", 40, 0.02, (0.4, 0.4, 0.4), _ee_box(lib, [0.3, -1.0, 0.1], [1.0, 0.25, 0.6]))
    if name == "ur5_ee_eq":
        return _arm(lib, "ur5", 40, 0.02, (0.4, 0.2, 0.5), _ee_terminal(lib, [0.4, 0.2, 0.5]))
    if name == "solo12_joint_limits":
        return _solo12(lib)
    raise KeyError(f"problem must be one of {MIM_PROBLEMS}, got {name!r}")


def violation(problem) -> float:
    """∞-norm of the constraint violation over the nodes (after ``problem.calc``): ``max(lb - g, 0, g - ub)``
    on the inequality rows (only the terminal node's ``ng_T`` rows) and ``|h|`` on the equality rows."""
    worst = 0.0
    models = [*problem.runningModels, problem.terminalModel]
    datas = [*problem.runningDatas, problem.terminalData]
    for t, (m, d) in enumerate(zip(models, datas)):
        terminal = t == problem.T
        ng, nh = (m.ng_T, m.nh_T) if terminal else (m.ng, m.nh)
        if ng:
            lb, ub = _node_bounds(m, terminal)
            g = np.asarray(d.g)[:ng]
            worst = max(worst, float(np.max(np.maximum(np.maximum(lb - g, 0.0), g - ub))))
        if nh:
            worst = max(worst, float(np.abs(np.asarray(d.h)[:nh]).max()))
    return worst


def _node_bounds(model, terminal: bool) -> tuple[np.ndarray, np.ndarray]:
    """Bounds of a node's active inequality rows, read from its constraint items (Crocoddyl's Python
    ``g_lb``/``g_ub`` getters may return garbage)."""
    manager = model.differential.constraints
    entries = manager.constraints
    entries = entries.values() if isinstance(entries, dict) else [pair.data() for pair in entries]
    items = [item.constraint for item in entries
             if item.active and (not terminal or item.constraint.T_constraint) and item.constraint.ng]
    return np.concatenate([np.asarray(c.lb) for c in items]), np.concatenate([np.asarray(c.ub) for c in items])


def run(lib: ModuleType, solvers: ModuleType, name: str, solver: str = "SolverCSQP", maxiter: int = 200,
        tolerance: float = 1e-6, settings: dict | None = None, repeats: int = 1) -> dict:
    """Solve ``name`` with ``solvers.<solver>`` (``solvers``: :mod:`crocopy` or ``mim_solvers``) on a
    problem built with ``lib``, with the solver's attributes ``settings``; returns the figures of the
    comparison (``ms_per_iter``: the median over ``repeats`` solves, each on a fresh problem and solver;
    ``ms_per_iter_range``: their minimum and maximum)."""
    times = []
    for _ in range(max(int(repeats), 1)):
        problem = build_problem(lib, name)
        if hasattr(problem, "nthreads"):
            problem.nthreads = 1
        s = getattr(solvers, solver)(problem)
        s.termination_tolerance = tolerance
        for key, value in (settings or {}).items():
            setattr(s, key, value)
        xs = [problem.x0.copy() for _ in range(problem.T + 1)]
        us = [np.zeros(m.nu) for m in problem.runningModels]
        start = time.perf_counter()
        converged = s.solve(xs, us, maxiter)
        times.append(1e3 * (time.perf_counter() - start) / max(int(s.iter), 1))
    xs, us = [np.array(x) for x in s.xs], [np.array(u) for u in s.us]
    cost = problem.calc(xs, us)
    return {
        "problem": name, "solver": solver, "converged": bool(converged), "iter": int(s.iter),
        "cost": float(cost), "KKT": float(s.KKT), "violation": violation(problem),
        "ms_per_iter": float(np.median(times)), "ms_per_iter_range": (min(times), max(times)),
        "qp_iters": float(getattr(s, "qp_iters", 0.0)),
    }


#: The comparison's cases: (problem, solver, termination tolerance, solver settings); see
#: ``tests/oracle/test_mim_solvers.py`` for why the UR5 box asks the QP for more accuracy.
MIM_CASES = (
    ("kinova_free", "SolverSQP", 1e-6, {}),
    ("kinova_free", "SolverCSQP", 1e-6, {}),
    ("kinova_ubound", "SolverCSQP", 1e-6, {}),
    ("ur5_ee_box", "SolverCSQP", 1e-5, {"eps_abs": 1e-7, "eps_rel": 0.0}),
    ("ur5_ee_eq", "SolverCSQP", 1e-6, {}),
    ("solo12_joint_limits", "SolverCSQP", 1e-4, {}),
)


def import_mim_solvers() -> tuple[ModuleType, ModuleType]:
    """``(crocoddyl, mim_solvers)``, imported in that order; ImportError naming the bench extra if missing."""
    try:
        import crocoddyl
        import mim_solvers
    except ImportError as exc:
        raise ImportError(f"--vs mim needs the bench extra (crocoddyl 3.2.1 and mim-solvers 0.3.0): {exc}") from exc
    return crocoddyl, mim_solvers


def run_vs_mim(problems: list[str] | None = None, progress=None, repeats: int = 5) -> str:
    """The markdown report of crocopy's SQP/CSQP against mim-solvers on ``problems`` (default: all cases);
    time per iteration: the median of ``repeats`` solves per library (the two libraries alternate) and its
    spread."""
    import crocopy
    import crocopy.mim_solvers as crocopy_mim

    crocoddyl, mim_solvers = import_mim_solvers()
    cases = [c for c in MIM_CASES if problems is None or c[0] in problems]
    unknown = set(problems or ()) - set(MIM_PROBLEMS)
    if unknown:
        raise KeyError(f"problems must be among {MIM_PROBLEMS}, got {sorted(unknown)}")
    run(crocopy, crocopy_mim, "kinova_free", "SolverSQP", 2)  # numba kernels loaded before any timing
    run(crocopy, crocopy_mim, "kinova_ubound", "SolverCSQP", 2)
    lines = [
        "| problem | solver | library | converged | iterations | cost | KKT | violation | QP iters (last) | ms/iter "
        "(median, min-max) | crocopy / mim-solvers |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for name, solver, tol, settings in cases:
        results = {}
        for label, lib, solvers in (("mim-solvers 0.3.0", crocoddyl, mim_solvers), ("crocopy", crocopy, crocopy_mim)):
            if progress is not None:
                progress(f"{name} {solver} {label}")
            results[label] = run(lib, solvers, name, solver, 200, tol, settings, repeats)
        ratio = results["crocopy"]["ms_per_iter"] / results["mim-solvers 0.3.0"]["ms_per_iter"]
        for label, r in results.items():
            lo, hi = r["ms_per_iter_range"]
            versus = f"{ratio:.2f}x" if label == "crocopy" else ""
            lines.append(f"| {name} | {solver} | {label} | {'yes' if r['converged'] else 'no'} | {r['iter']} | "
                         f"{r['cost']:.10g} | {r['KKT']:.2e} | {r['violation']:.1e} | {r['qp_iters']:g} | "
                         f"{r['ms_per_iter']:.2f} ({lo:.2f}-{hi:.2f}) | {versus} |")
    header = ("## crocopy vs mim-solvers (SolverSQP / SolverCSQP)\n\nFrom `x0` at every node and zero controls, "
              f"one thread, at most 200 iterations, {repeats} solves per library and case. crocopy's ADMM "
              "iterations and the SQP glue are compiled; so are the nodes, their constraint managers' rows "
              "included.\n")
    return header + "\n" + "\n".join(lines) + "\n"
