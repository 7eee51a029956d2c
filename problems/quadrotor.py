"""IRIS quadrotor way-point problems (Box-FDDP paper §IV-A2: quad-goal, quad-loop, quad-narrow).

The IRIS model of example-robot-data (free-flyer base, 1.535 kg) is actuated by four
propellers pushing along the base z axis, placed at the model's ``iris__rotor_*`` frames; each
thrust is bounded to ``[0.1, 10.3]`` N (the paper's range, ``u_lb``/``u_ub`` of every running
node).  Rotors 0/1 and 2/3 (the two diagonals) spin in opposite directions; the reaction torque
is ``ctorque = 0.016`` m times the thrust (the paper gives no value; a typical ratio for 10-inch
propellers).  Dynamics: free forward dynamics, explicit Euler, ``dt = 0.03`` s.

A task is a list of way-points ``(node, SE3 placement, base velocity or None)``; the last one sits
on the terminal node.  Costs (weights in :data:`WEIGHTS`, each multiplying ``0.5 ||r||^2``; running
costs are scaled by ``dt`` through the integrator, as in every crocopy/Crocoddyl integrated model):

* running ``state``: base orientation and velocities towards hover at rest, position free,
  weight ``1e-5``;  ``control``: ``||u||^2``, weight ``1e-5``;  ``goal``: placement of the base
  towards the *next* way-point, weight ``1e-2``;
* at a way-point node: placement ``1e2`` (``1e3`` at the terminal node) and, when a velocity is
  given, base velocity (local frame) ``1e1``.

Tasks (none of their geometry is given in the paper; chosen here and documented):

* ``goal``: from ``x0`` (default ``(-0.3, 0, 0)`` at rest, level) to ``(3, 0, 1)`` level and at rest,
  ``T = 50`` nodes (1.5 s) — the Fig. 7 task (start ``(-0.3 ± 0.6, 0, 0)``, target ``(3, 0, 1)``);
* ``loop``: a closed vertical loop in the x-z plane, radius 1 m, whose lowest point is the start
  (centre ``x0 + (0, 0, 1)``): way-points at ``T/4`` (front, ``+x``, pitch ``-π/2``), ``T/2`` (top,
  pitch ``π``, upside down) and ``3T/4`` (back, pitch ``π/2``), each attitude pointing the thrust
  at the centre, then back at ``x0``, level and at rest, at ``T = 100`` nodes (3 s).  Design: a loop
  is a closed manoeuvre, so it starts and ends at the same state (the lowest point used to be
  ``(0, 0, 1)``, 1 m above and 0.3 m beside the default start, which made the task a climb plus a
  loop).  Only targets consistent with a flown loop are given: thrust towards the centre (vertical
  acceleration ``-g`` at the sides, speed at least ``sqrt(g r)`` at the top, left free).  Tangential
  way-point velocities at a uniform speed (2.1 m/s over 3 s) are too slow for the top, and dense
  way-points sampled from a constant-speed loop (attitude from the required acceleration) made
  the loop-skipping trajectory both solvers' local minimum.  Attitude costs (SE(3) log) do not
  tell windings apart: a solution may reach the attitudes by rotating back and forth instead of
  once around (Box-FDDP's does);
* ``narrow``: a passage at ``(1.5, 0, 1)`` crossed rolled by ``π/2`` (the slot is narrower than the
  rotor span) with forward velocity 2 m/s, then the goal ``(3, 0, 1)``, ``T = 60`` nodes.

The warm start is cold (the paper's): ``x0`` at every node and zero thrust.
"""

from __future__ import annotations

from types import ModuleType

import example_robot_data
import numpy as np
import pinocchio as pin

THRUST_RANGE = (0.1, 10.3)
CTORQUE = 0.016
DT = 0.03
BASE_FRAME = "iris__base_link"
WEIGHTS = {
    "state": 1e-5,
    "control": 1e-5,
    "goal": 1e-2,
    "waypoint": 1e2,
    "terminal_waypoint": 1e3,
    "waypoint_velocity": 1e1,
}
"""Cost weights (see the module docstring); each multiplies ``0.5 ||r||^2``."""


def _thrusters(lib: ModuleType, model: pin.Model) -> list:
    thrusters = []
    for i in range(4):
        frame = model.frames[model.getFrameId(f"iris__rotor_{i}")]
        spin = lib.ThrusterType.CCW if i in (0, 1) else lib.ThrusterType.CW
        thrusters.append(
            lib.Thruster(pin.SE3(np.eye(3), frame.placement.translation.copy()), CTORQUE, spin, *THRUST_RANGE)
        )
    return thrusters


def _rot_y(angle: float) -> np.ndarray:
    return pin.utils.rotate("y", angle)


def task_waypoints(
    task: str, T: int | None = None, start: tuple[float, float, float] | np.ndarray = (-0.3, 0.0, 0.0)
) -> tuple[int, list]:
    """Horizon and way-points ``(node, SE3, velocity or None)`` of a task (see the module docstring).

    ``start`` is the initial base position; only the loop depends on it (its lowest point).
    """
    level = np.eye(3)
    if task == "goal":
        T = 50 if T is None else T
        return T, [(T, pin.SE3(level, np.array([3.0, 0.0, 1.0])), np.zeros(6))]
    if task == "loop":
        T = 100 if T is None else T
        c = np.asarray(start, dtype=float) + [0.0, 0.0, 1.0]
        pts = [
            (T // 4, pin.SE3(_rot_y(-np.pi / 2), c + [1.0, 0.0, 0.0]), None),
            (T // 2, pin.SE3(_rot_y(np.pi), c + [0.0, 0.0, 1.0]), None),
            (3 * T // 4, pin.SE3(_rot_y(np.pi / 2), c + [-1.0, 0.0, 0.0]), None),
            (T, pin.SE3(level, c + [0.0, 0.0, -1.0]), np.zeros(6)),
        ]
        return T, pts
    if task == "narrow":
        T = 60 if T is None else T
        passage = pin.SE3(pin.utils.rotate("x", np.pi / 2), np.array([1.5, 0.0, 1.0]))
        return T, [
            (T // 2, passage, np.array([2.0, 0.0, 0.0, 0.0, 0.0, 0.0])),
            (T, pin.SE3(level, np.array([3.0, 0.0, 1.0])), np.zeros(6)),
        ]
    raise ValueError(f"task must be 'goal', 'loop' or 'narrow', got {task!r}")


def build_quadrotor(
    lib: ModuleType,
    task: str = "goal",
    x0_position: tuple[float, float, float] | np.ndarray = (-0.3, 0.0, 0.0),
    T: int | None = None,
    dt: float = DT,
) -> tuple[object, list, list]:
    """IRIS way-point problem with thrust limits.

    Parameters
    ----------
    lib : module
        ``crocopy`` or ``crocoddyl`` (same problem with either).
    task : {"goal", "loop", "narrow"}
        Way-point task.
    x0_position : array_like
        Initial base position (m); the vehicle starts level and at rest.
    T : int, optional
        Number of running nodes (task default if None).
    dt : float
        Euler step (s).

    Returns
    -------
    problem, xs, us
        ``ShootingProblem`` (nx = 13, ndx = 12, nu = 4) and a cold start.
    """
    model = example_robot_data.load("iris").model
    state = lib.StateMultibody(model)
    actuation = lib.ActuationModelFloatingBaseThrusters(state, _thrusters(lib, model))
    nu = actuation.nu
    x0 = np.concatenate([np.asarray(x0_position, dtype=float).ravel(), [0.0, 0.0, 0.0, 1.0], np.zeros(6)])
    if np.shape(x0_position) != (3,):
        raise ValueError(f"x0_position must have shape (3,), got {np.shape(x0_position)}")
    T, waypoints = task_waypoints(task, T, x0[:3])
    if not all(0 < t <= T for t, _, _ in waypoints):
        raise ValueError(f"way-point nodes must lie in (0, T = {T}]")
    fid = model.getFrameId(BASE_FRAME)
    x_rest = x0.copy()
    state_act = lib.ActivationModelWeightedQuad(np.array([0.0] * 3 + [1.0] * 3 + [1.0] * 6))
    lb, ub = np.full(nu, THRUST_RANGE[0]), np.full(nu, THRUST_RANGE[1])
    by_node = {t: (M, v) for t, M, v in waypoints}

    def node(t: int) -> object:
        terminal = t == T
        costs = lib.CostModelSum(state, nu)
        if not terminal:
            costs.addCost(
                "state",
                lib.CostModelResidual(state, state_act, lib.ResidualModelState(state, x_rest, nu)),
                WEIGHTS["state"],
            )
            costs.addCost(
                "control", lib.CostModelResidual(state, lib.ResidualModelControl(state, nu)), WEIGHTS["control"]
            )
            target = next(M for tw, M, _ in waypoints if tw > t)
            costs.addCost(
                "goal",
                lib.CostModelResidual(state, lib.ResidualModelFramePlacement(state, fid, target, nu)),
                WEIGHTS["goal"],
            )
        if t in by_node:
            M, v = by_node[t]
            costs.addCost(
                "waypoint",
                lib.CostModelResidual(state, lib.ResidualModelFramePlacement(state, fid, M, nu)),
                WEIGHTS["terminal_waypoint" if terminal else "waypoint"],
            )
            if v is not None:
                vel = lib.ResidualModelFrameVelocity(state, fid, pin.Motion(np.asarray(v, dtype=float)), pin.LOCAL, nu)
                costs.addCost("waypoint_velocity", lib.CostModelResidual(state, vel), WEIGHTS["waypoint_velocity"])
        dam = lib.DifferentialActionModelFreeFwdDynamics(state, actuation, costs)
        iam = lib.IntegratedActionModelEuler(dam, 0.0 if terminal else dt)
        for m in (dam, iam):
            m.u_lb, m.u_ub = lb.copy(), ub.copy()
        return iam

    running = [node(t) for t in range(T)]
    problem = lib.ShootingProblem(x0, running, node(T))
    return problem, [x0.copy() for _ in range(T + 1)], [np.zeros(nu) for _ in range(T)]
