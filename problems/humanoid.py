"""Humanoid problems (Talos): taichi, whole-body manipulation, biped walking and the monkey bar.

Box-FDDP paper §IV-A4: joint position limits in every scenario (quadratic barrier penalties);
taichi in three phases (manipulation, standing on one foot, balancing); monkey bar in three
phases (grasping the bar, climbing up, landing on the ground) with the arms' torque limits ×10
and no friction/wrench cone on the hands while they hold the bar.

Soles and hands make 6D contacts (wrench cone on the soles: mu 0.7, 0.2 m × 0.1 m foot).  All
builders take the library module first and return ``(problem, xs, us)``; the warm start is the
half-sitting posture at rest with quasi-static torques.  Cost names and default weights are
those of :mod:`crocopy.problems.common` except control 1e-3 and terminal state 1e1, with a
humanoid state regularisation (base position free, base orientation 500, legs 0.01,
torso/arms/grippers/head 1, velocities 10; squared).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from types import ModuleType

import numpy as np
import pinocchio as pin

from .common import LeggedSetup, load_model

FEET = ("left_sole_link", "right_sole_link")
HANDS = ("gripper_left_joint", "gripper_right_joint")


UPPER_BODY_WEIGHT = 1.0
"""Posture weight of the torso, arms, grippers and head (legs 0.01, base orientation 500)."""
HUMANOID_WEIGHTS = {"control": 1e-3, "terminal_state": 1e1}
"""Humanoid overrides of :data:`crocopy.problems.common.DEFAULT_WEIGHTS` (Talos' torques are large)."""


def _humanoid_state_weights(nv: int, n_legs: int = 12) -> np.ndarray:
    w = np.concatenate([[0.0] * 3, [500.0] * 3, [0.01] * n_legs, [UPPER_BODY_WEIGHT] * (nv - 6 - n_legs),
                        [10.0] * nv])
    return w**2


def _setup(
    lib: ModuleType,
    robot: str = "talos",
    arm_torque_scale: float = 1.0,
    weights: Mapping[str, float] | None = None,
    with_hands: bool = True,
) -> LeggedSetup:
    model = load_model(robot)
    if arm_torque_scale != 1.0:
        scale = np.ones(model.nv)
        for j in range(1, model.njoints):
            if model.names[j].startswith("arm_"):
                scale[model.joints[j].idx_v] = arm_torque_scale
        model.effortLimit = model.effortLimit * scale
    q0 = np.array(model.referenceConfigurations["half_sitting"])
    x0 = np.concatenate([q0, np.zeros(model.nv)])
    frames = FEET + HANDS if with_hands else FEET
    return LeggedSetup(lib, model, x0, frames, contact_dim=6, mu=0.7, foot_size=(0.2, 0.1),
                       weights={**HUMANOID_WEIGHTS, **(weights or {})}, state_weights=_humanoid_state_weights(model.nv))


def _feet(setup: LeggedSetup) -> dict[str, pin.SE3]:
    return {f: setup.placements0[f].copy() for f in FEET}


def build_manipulation(
    lib: ModuleType,
    target: Sequence[float] = (0.4, -0.2, 1.1),
    dt: float = 2e-2,
    nodes: int = 60,
    weights: Mapping[str, float] | None = None,
) -> tuple[object, list, list]:
    """Whole-body manipulation ("man"): reach ``target`` with the right hand on both feet.

    ``nodes`` double-support nodes (default 60 × 20 ms): right-hand translation tracking
    (weight 1e3 running, 1e5 terminal), CoM kept above its initial position (weight 1e3),
    wrench cones, joint limits, state and control regularisation.  T = 60, nx = 77, nu = 32.
    """
    setup = _setup(lib, weights=weights)
    target = np.asarray(target, dtype=float)
    if target.shape != (3,):
        raise ValueError(f"target must have shape (3,), got {target.shape}")
    feet = _feet(setup)
    hand = HANDS[1]
    running = [_node(setup, dt, feet, {hand: (target, 1e3)}, setup.com0, 1e3) for _ in range(nodes)]
    terminal = _node(setup, 0.0, feet, {hand: (target, 1e5)}, setup.com0, 1e3, terminal=True)
    return setup.problem(running, terminal)


def _node(
    setup: LeggedSetup,
    dt: float,
    support: Mapping[str, pin.SE3 | None],
    tasks: Mapping[str, tuple[np.ndarray | pin.SE3, float]],
    com_ref: np.ndarray | None = None,
    com_weight: float = 1e3,
    terminal: bool = False,
    friction: Sequence[str] | None = None,
) -> object:
    """Contact node with frame tasks ``name -> (target, weight)`` and a CoM task."""
    extra = {}
    for name, (target, weight) in tasks.items():
        extra[name + "_task"] = (setup._frame_cost(name, target, setup.nu), weight)
    if com_ref is not None:
        res = setup.lib.ResidualModelCoMPosition(setup.state, np.asarray(com_ref, float), setup.nu)
        extra["com"] = (setup.lib.CostModelResidual(setup.state, res), com_weight)
    if friction is None:
        friction = [f for f in support if f in FEET]
    return setup.contact_node(dt, support, extra=extra, terminal=terminal, friction=friction)


def build_taichi(
    lib: ModuleType,
    hand_target: Sequence[float] = (0.4, -0.1, 1.2),
    foot_lift: float = 0.15,
    dt: float = 2e-2,
    phase_knots: int = 40,
    weights: Mapping[str, float] | None = None,
) -> tuple[object, list, list]:
    """Taichi: manipulation, then standing on one foot, then balancing (3 × ``phase_knots`` nodes).

    1. manipulation: both feet in contact, right hand to ``hand_target`` (weight 1e3);
    2. standing on one foot: the left foot leaves the ground and tracks a placement ``foot_lift``
       higher (weight 1e4), the CoM moves above the right sole (weight 1e4), the hand keeps its
       target;
    3. balancing: on the right foot, the left foot moves forward/outward to a raised pose, the
       CoM stays above the right sole, the hand keeps its target.

    Terminal node: hand 1e5, foot 1e5, CoM 1e5.  Defaults: T = 120 (2.4 s), nx = 77, nu = 32.
    """
    setup = _setup(lib, weights=weights)
    target = np.asarray(hand_target, dtype=float)
    if target.shape != (3,):
        raise ValueError(f"hand_target must have shape (3,), got {target.shape}")
    feet = _feet(setup)
    hand, left, right = HANDS[1], FEET[0], FEET[1]
    com_right = np.array([feet[right].translation[0], feet[right].translation[1], setup.com0[2]])
    lifted = feet[left].copy()
    lifted.translation = lifted.translation + np.array([0.0, 0.0, foot_lift])
    forward = feet[left].copy()
    forward.translation = forward.translation + np.array([0.15, 0.05, foot_lift])
    running = [_node(setup, dt, feet, {hand: (target, 1e3)}, setup.com0, 1e3) for _ in range(phase_knots)]
    single = {right: feet[right]}
    running += [
        _node(setup, dt, single, {hand: (target, 1e3), left: (lifted, 1e4)}, com_right, 1e4)
        for _ in range(phase_knots)
    ]
    running += [
        _node(setup, dt, single, {hand: (target, 1e3), left: (forward, 1e4)}, com_right, 1e4)
        for _ in range(phase_knots)
    ]
    terminal = _node(setup, 0.0, single, {hand: (target, 1e5), left: (forward, 1e5)}, com_right, 1e5, True)
    return setup.problem(running, terminal)


def build_biped_walk(
    lib: ModuleType,
    robot: str = "talos_legs",
    step_length: float = 0.2,
    step_height: float = 0.08,
    dt: float = 3e-2,
    step_knots: int = 25,
    support_knots: int = 5,
    steps: int = 4,
    weights: Mapping[str, float] | None = None,
) -> tuple[object, list, list]:
    """Biped walking (Talos legs by default): ``steps`` steps alternating right and left foot.

    Each step: ``support_knots`` double-support nodes, ``step_knots`` single-support nodes where
    the swing sole tracks a flat placement along a parabola of apex ``step_height`` moving it by
    ``step_length`` (the first and last steps by half), weight 1e6, with the CoM tracking the
    midpoint of the planned sole positions (weight 1e5), then a 6D impulse at touch-down
    (landing placement weight 1e7).  Ends with ``support_knots`` double-support nodes and a
    terminal node.  Defaults: T = 4 × 31 + 5 = 129, nx = 37, nu = 12.
    """
    setup = _setup(lib, robot=robot, weights=weights, with_hands=False)
    feet = _feet(setup)
    running: list[object] = []
    order = [FEET[1], FEET[0]]
    com_offset = setup.com0 - 0.5 * (feet[FEET[0]].translation + feet[FEET[1]].translation)
    for i in range(steps):
        swing_foot = order[i % 2]
        stance_foot = order[(i + 1) % 2]
        length = step_length * (0.5 if i in (0, steps - 1) else 1.0)
        start = feet[swing_foot].translation.copy()
        end = start + np.array([length, 0.0, 0.0])
        running += [_node(setup, dt, dict(feet), {}) for _ in range(support_knots)]
        for k in range(1, step_knots + 1):
            s = k / step_knots
            goal = feet[swing_foot].copy()
            goal.translation = (1 - s) * start + s * end + np.array([0.0, 0.0, 4 * step_height * s * (1 - s)])
            com = 0.5 * (feet[stance_foot].translation + goal.translation) + com_offset
            com[2] = setup.com0[2]
            running.append(
                _node(setup, dt, {stance_foot: feet[stance_foot]}, {swing_foot: (goal, setup.weights["swing"])},
                      com, setup.weights["com"])
            )
        feet[swing_foot] = feet[swing_foot].copy()
        feet[swing_foot].translation = end
        running.append(setup.impulse_node({swing_foot: feet[swing_foot]}, support=[stance_foot]))
    running += [_node(setup, dt, dict(feet), {}) for _ in range(support_knots)]
    xref = setup.x0.copy()
    for f in FEET:
        xref[:2] += 0.5 * (feet[f].translation - setup.placements0[f].translation)[:2]
    terminal = setup.contact_node(0.0, dict(feet), terminal=True, xref=xref)
    return setup.problem(running, terminal)


def build_monkey_bar(
    lib: ModuleType,
    bar: Sequence[float] = (0.3, 0.0, 1.65),
    hand_gap: float = 0.5,
    climb_height: float = 0.25,
    landing_shift: float = 0.3,
    dt: float = 3e-2,
    knots: tuple[int, int, int, int] = (30, 30, 30, 20),
    arm_torque_scale: float = 10.0,
    climb_weight: float = 1e5,
    weights: Mapping[str, float] | None = None,
) -> tuple[object, list, list]:
    """Monkey bar: grasp a horizontal bar, climb up, land on the ground (Box-FDDP paper "bar").

    The bar is a line parallel to y through ``bar``; the hands grasp it ``hand_gap`` apart.
    The arms' torque limits are multiplied by ``arm_torque_scale`` (10 in the paper).

    1. grasping (``knots[0]`` nodes on both feet): the hands track their grasp points (weight
       1e3, CoM held, wrench cones on the soles), then a 6D impulse where the hands close on
       the bar (grasp-point weight 1e7; the soles take part in the impact);
    2. climbing (``knots[1]`` nodes hanging by the hands, no cone on the hands): the feet leave
       the ground and track points ``climb_height`` higher, the CoM rises by ``climb_height``
       (both weighted ``climb_weight``);
    3. landing (``knots[2]`` nodes still hanging): the feet move to their initial places shifted
       by ``landing_shift`` forward (weight 1e4), then a 6D impulse at touch-down, then
       ``knots[3]`` nodes standing on the feet with the hands released, the CoM above the new
       feet (weight 1e3).

    Defaults: T = 112 (110 × 30 ms + 2 impulses), nx = 77, nu = 32.
    """
    setup = _setup(lib, arm_torque_scale=arm_torque_scale, weights=weights)
    bar = np.asarray(bar, dtype=float)
    if bar.shape != (3,):
        raise ValueError(f"bar must have shape (3,), got {bar.shape}")
    feet = _feet(setup)
    grips = {
        HANDS[0]: bar + np.array([0.0, 0.5 * hand_gap, 0.0]),
        HANDS[1]: bar + np.array([0.0, -0.5 * hand_gap, 0.0]),
    }
    grip_placements = {h: pin.SE3(setup.placements0[h].rotation, p) for h, p in grips.items()}
    up = np.array([0.0, 0.0, climb_height])
    forward = np.array([landing_shift, 0.0, 0.0])
    n_grasp, n_climb, n_land, n_stand = knots
    running = [
        _node(setup, dt, feet, {h: (p, 1e3) for h, p in grips.items()}, setup.com0, 1e3) for _ in range(n_grasp)
    ]
    running.append(setup.impulse_node(grips, support=FEET))
    hanging = {h: grip_placements[h] for h in HANDS}
    for k in range(1, n_climb + 1):
        s = k / n_climb
        tasks = {f: (feet[f].translation + s * up, climb_weight) for f in FEET}
        running.append(_node(setup, dt, hanging, tasks, setup.com0 + s * up, climb_weight, friction=[]))
    land = {f: pin.SE3(feet[f].rotation, feet[f].translation + forward) for f in FEET}
    for k in range(1, n_land + 1):
        s = k / n_land
        tasks = {f: ((1 - s) * (feet[f].translation + up) + s * land[f].translation, 1e4) for f in FEET}
        running.append(_node(setup, dt, hanging, tasks, setup.com0 + (1 - s) * up + s * forward, 1e3, friction=[]))
    running.append(setup.impulse_node(land, support=HANDS))
    com_end = setup.com0 + forward
    running += [_node(setup, dt, land, {}, com_end, 1e3) for _ in range(n_stand)]
    xref = setup.x0.copy()
    xref[:3] += forward
    terminal = setup.contact_node(0.0, land, terminal=True, xref=xref)
    return setup.problem(running, terminal)
