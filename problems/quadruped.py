"""Quadruped problems (ANYmal, Solo12, HyQ): gaits, the jump and two-leg hopping.

Box-FDDP paper §IV-A3: ANYmal with torque limits reduced to 32 N m and joint-velocity limits to
7.5 rad/s (the URDF's 80 N m and 15 rad/s scaled by 0.4 and 0.5); warm start = reference posture
with zero velocity and quasi-static torques.  Velocity (and joint position) limits are quadratic
penalties; torque limits are the control bounds seen by the box solvers.

All builders take the library module first (``crocopy`` or ``crocoddyl``) and return
``(problem, xs, us)``.  Feet are ordered LF, RF, LH, RH.  Costs and their default weights are
described in :mod:`crocopy.problems.common`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from types import ModuleType

import numpy as np

from .common import LeggedSetup, load_model, swing_point

FEET: dict[str, tuple[str, str, str, str]] = {
    "anymal": ("LF_FOOT", "RF_FOOT", "LH_FOOT", "RH_FOOT"),
    "solo12": ("FL_FOOT", "FR_FOOT", "HL_FOOT", "HR_FOOT"),
    "hyq": ("lf_foot", "rf_foot", "lh_foot", "rh_foot"),
}
"""Foot frames of each supported robot, in the order LF, RF, LH, RH."""

GAITS: dict[str, tuple[tuple[int, ...], ...]] = {
    "walk": ((3,), (1,), (2,), (0,)),
    "trot": ((0, 3), (1, 2)),
    "pace": ((0, 2), (1, 3)),
    "bound": ((0, 1), (2, 3)),
}
"""Swing groups of one gait cycle (indices into the LF, RF, LH, RH foot tuple)."""

TORQUE_SCALE = 0.4
"""ANYmal's URDF effort limit (80 N m) × 0.4 = the paper's 32 N m."""
VELOCITY_SCALE = 0.5
"""ANYmal's URDF velocity limit (15 rad/s) × 0.5 = the paper's 7.5 rad/s."""
JUMP_HEIGHT = 0.22
"""Base apex above standing asked by :func:`build_jump` (m): what 32 N m reach (the paper's 0.3 is not)."""
FLIGHT_JOINT_WEIGHT = 10.0
"""Joint-position weight of the jump's flight regularisation (0.01 elsewhere): legs stay in posture."""


def load_quadruped(robot: str = "anymal", limited: bool = True) -> tuple[object, np.ndarray, tuple[str, ...]]:
    """Pinocchio model, reference state (standing, zero velocity) and foot frames of ``robot``.

    With ``limited`` the model's effort and velocity limits are scaled by :data:`TORQUE_SCALE`
    and :data:`VELOCITY_SCALE` (ANYmal: 32 N m and 7.5 rad/s).
    """
    if robot not in FEET:
        raise KeyError(f"robot must be one of {sorted(FEET)}, got {robot!r}")
    model = load_model(robot)
    if limited:
        model.effortLimit = model.effortLimit * np.r_[np.ones(6), np.full(model.nv - 6, TORQUE_SCALE)]
        model.velocityLimit = model.velocityLimit * np.r_[np.ones(6), np.full(model.nv - 6, VELOCITY_SCALE)]
    q0 = np.array(model.referenceConfigurations["standing"])
    x0 = np.concatenate([q0, np.zeros(model.nv)])
    return model, x0, FEET[robot]


def _setup(lib: ModuleType, robot: str, limited: bool, weights: Mapping[str, float] | None) -> LeggedSetup:
    model, x0, feet = load_quadruped(robot, limited)
    return LeggedSetup(lib, model, x0, feet, contact_dim=3, mu=0.7, weights=weights)


def _shifted_state(setup: LeggedSetup, shift: np.ndarray) -> np.ndarray:
    x = setup.x0.copy()
    x[:3] += shift
    return x


def build_gait(
    lib: ModuleType,
    gait: str = "walk",
    robot: str = "anymal",
    step_length: float = 0.25,
    step_height: float = 0.15,
    dt: float = 1e-2,
    step_knots: int = 25,
    support_knots: int = 2,
    cycles: int = 2,
    limited: bool = False,
    weights: Mapping[str, float] | None = None,
) -> tuple[object, list, list]:
    """Walking, trotting, pacing or bounding on flat ground.

    Phases per cycle, for each swing group of :data:`GAITS` (walk: RH, RF, LH, LF; trot: LF+RH,
    RF+LH; pace: LF+LH, RF+RH; bound: LF+RF, LH+RH): ``support_knots`` nodes in four-foot support,
    ``step_knots`` nodes with the group in the air, then an impulse node where it lands.  Swing
    feet track a parabola of apex ``step_height`` that advances each foot by ``step_length``
    (weight ``swing`` 1e6); the CoM tracks the initial CoM shifted by the mean foot displacement
    (weight ``com`` 1e5); landing targets weight 1e7.  The horizon ends with ``support_knots``
    support nodes and a terminal node regularised towards the standing posture moved by the
    walked distance.  ANYmal walk (defaults): T = 2 × 4 × 28 + 2 = 226 nodes.

    Returns
    -------
    problem, xs, us
        ``ShootingProblem`` and warm start (standing posture, quasi-static torques).
    """
    if gait not in GAITS:
        raise KeyError(f"gait must be one of {sorted(GAITS)}, got {gait!r}")
    setup = _setup(lib, robot, limited, weights)
    feet = FEET[robot]
    pos = {f: setup.placements0[f].translation.copy() for f in feet}
    mean0 = np.mean([pos[f] for f in feet], axis=0)
    advance = np.array([step_length, 0.0, 0.0])
    running: list[object] = []

    def com_ref(current: dict[str, np.ndarray]) -> np.ndarray:
        shift = np.mean([current[f] for f in feet], axis=0) - mean0
        return setup.com0 + np.array([shift[0], shift[1], 0.0])

    for _ in range(cycles):
        for group in GAITS[gait]:
            swing_feet = [feet[i] for i in group]
            stance = {f: pos[f].copy() for f in feet if f not in swing_feet}
            running += [setup.contact_node(dt, dict(pos)) for _ in range(support_knots)]
            for k in range(1, step_knots + 1):
                s = k / step_knots
                targets = {f: swing_point(pos[f], pos[f] + advance, step_height, s) for f in swing_feet}
                current = {**pos, **targets}
                running.append(setup.contact_node(dt, stance, swing=targets, com_ref=com_ref(current)))
            for f in swing_feet:
                pos[f] = pos[f] + advance
            running.append(setup.impulse_node({f: pos[f] for f in swing_feet}, support=list(stance)))
    running += [setup.contact_node(dt, dict(pos)) for _ in range(support_knots)]
    shift = np.mean([pos[f] for f in feet], axis=0) - mean0
    shift[2] = 0.0
    terminal = setup.contact_node(0.0, dict(pos), terminal=True, xref=_shifted_state(setup, shift))
    return setup.problem(running, terminal)


def build_jump(
    lib: ModuleType,
    robot: str = "anymal",
    jump_height: float = JUMP_HEIGHT,
    jump_length: Sequence[float] = (0.0, 0.0, 0.0),
    dt: float = 1e-2,
    phases_ms: tuple[int, int, int] = (300, 400, 300),
    limited: bool = True,
    weights: Mapping[str, float] | None = None,
) -> tuple[object, list, list]:
    """The Box-FDDP paper's jump: push-off, a flight with the feet kept under the body, landing.

    Phases (default ``dt`` 10 ms): push-off 0–300 ms (30 four-foot support nodes with friction
    cones), flight 300–700 ms (40 free-dynamics nodes), an impulse node at 700 ms where the four
    feet land on their standing positions moved by ``jump_length`` (weight ``impulse_foot`` 1e7),
    then landing 700–1000 ms (30 support nodes) and a terminal node regularised towards the
    standing posture at the landing spot (weight ``terminal_state`` 1e3).  T = 101 running nodes
    (100 with dt > 0 and one impulse).

    Flight costs: at mid-flight the base (``root_joint``) is asked to be ``jump_height`` above its
    standing position moved by half of ``jump_length`` (weight ``apex``); at every flight node each
    foot's horizontal position is asked to stay at its standing x/y moved by the flown fraction of
    ``jump_length`` (weight ``foot_xy``: the feet stay under the body, at their standing spread),
    and the state regularisation leaves the base height free while holding the joints near the
    standing posture (joint weight :data:`FLIGHT_JOINT_WEIGHT` instead of 0.01).  With ``limited``
    (default) torques are bounded by 32 N m and joint velocities penalised beyond 7.5 rad/s (ANYmal).

    Height.  In a flight of ``T_f`` the centre of mass rises ``g T_f^2 / 8`` (19.6 cm for 400 ms)
    from take-off to apex.  With 32 N m ANYmal needs its whole leg stroke to reach that take-off
    speed, so it leaves the ground with its legs extended, the base 2.8 cm above standing, and its
    base tops out 22 cm above standing: :data:`JUMP_HEIGHT`.  The paper's 30 cm is out of reach with
    these limits: asked for it, Box-FDDP still peaks at 22.6 cm and does not converge in 800
    iterations (asked 20 cm, it peaks at 22.6 cm too).

    Returns
    -------
    problem, xs, us
        ``ShootingProblem`` and warm start (standing posture, quasi-static torques).
    """
    setup = _setup(lib, robot, limited, weights)
    feet = FEET[robot]
    n_jump, n_fly, n_land = (int(round(p * 1e-3 / dt)) for p in phases_ms)
    if min(n_jump, n_fly, n_land) < 1:
        raise ValueError(f"phases_ms {phases_ms} give an empty phase with dt={dt}")
    shift = np.asarray(jump_length, dtype=float)
    if shift.shape != (3,):
        raise ValueError(f"jump_length must have shape (3,), got {shift.shape}")
    start = {f: setup.placements0[f].translation.copy() for f in feet}
    land = {f: start[f] + shift for f in feet}
    apex = setup.placements0["root_joint"].translation + 0.5 * shift + np.array([0.0, 0.0, jump_height])
    running = [setup.contact_node(dt, dict(start)) for _ in range(n_jump)]
    posture = setup.state_weights().copy()
    posture[2] = 0.0
    posture[6 : setup.model.nv] = FLIGHT_JOINT_WEIGHT**2
    for k in range(n_fly):
        s = k / n_fly
        tasks = {f + "_xy": (_horizontal_cost(setup, f, start[f] + s * shift), setup.weights["foot_xy"]) for f in feet}
        if k == n_fly // 2:
            tasks["apex"] = (setup._frame_cost("root_joint", apex, setup.nu), setup.weights["apex"])
        running.append(setup.contact_node(dt, {}, extra=tasks, state_weights=posture))
    running.append(setup.impulse_node(land))
    running += [setup.contact_node(dt, dict(land)) for _ in range(n_land)]
    terminal = setup.contact_node(0.0, dict(land), terminal=True, xref=_shifted_state(setup, shift))
    return setup.problem(running, terminal)


def _horizontal_cost(setup: LeggedSetup, name: str, target: np.ndarray) -> object:
    """``0.5 ||(p - target)_xy||^2`` for frame ``name``'s position ``p`` (its height is free)."""
    lib = setup.lib
    res = lib.ResidualModelFrameTranslation(setup.state, setup.ids[name], np.asarray(target, float), setup.nu)
    return lib.CostModelResidual(setup.state, lib.ActivationModelWeightedQuad(np.array([1.0, 1.0, 0.0])), res)


def build_hop(
    lib: ModuleType,
    robot: str = "anymal",
    hops: int = 10,
    hop_height: float = 0.03,
    lift_height: float = 0.1,
    dt: float = 1e-2,
    stance_knots: int = 30,
    flight_knots: int = 10,
    limited: bool = True,
    weights: Mapping[str, float] | None = None,
) -> tuple[object, list, list]:
    """Unstable two-leg hopping with a leg switch (Box-FDDP paper: 10 hops, 5.8 s, 580 nodes).

    Hops alternate stance (``stance_knots``) on a diagonal pair with flight (``flight_knots``,
    hopping feet track a parabola of apex ``hop_height``, then an impulse where they land back).
    The other pair is held ``lift_height`` above the ground.  Timeline with the defaults
    (10 ms nodes): 30 support nodes; 5 hops of 300 ms stance + 100 ms flight on LF+RH (RF+LH lift
    during the first stance); leg switch: 30 nodes where RF+LH come down, their impulse, 40
    support nodes; 5 hops on RF+LH; 30 nodes where LF+RH come down, their impulse; 50 support
    nodes: 580 nodes with dt > 0 (5.8 s) plus 12 impulse nodes (T = 592).  With ``hops`` other
    than 10 the horizon ends with 30 support nodes.  Weights as in :mod:`crocopy.problems.common`
    except the control regularisation, 1.0 (with 0.1 the torques sit on their 32 N m bounds
    through most stances and Box-FDDP needs ~800 iterations instead of ~170); ANYmal limits
    32 N m and 7.5 rad/s by default.

    Returns
    -------
    problem, xs, us
        ``ShootingProblem`` and warm start (standing posture, quasi-static torques).
    """
    if hops < 2 or hops % 2:
        raise ValueError(f"hops must be an even number >= 2, got {hops}")
    setup = _setup(lib, robot, limited, {"control": 1.0, **(weights or {})})
    feet = FEET[robot]
    pos = {f: setup.placements0[f].translation.copy() for f in feet}
    up = np.array([0.0, 0.0, lift_height])
    pair_a, pair_b = (feet[0], feet[3]), (feet[1], feet[2])
    running: list[object] = [setup.contact_node(dt, dict(pos)) for _ in range(30)]

    def lift(pair: tuple[str, ...], k: int, n: int, down: bool) -> dict[str, np.ndarray]:
        s = k / n
        s = 1.0 - s if down else s
        return {f: pos[f] + s * up for f in pair}

    for hopping, lifted in ((pair_a, pair_b), (pair_b, pair_a)):
        for h in range(hops // 2):
            stance = {f: pos[f] for f in hopping}
            for k in range(1, stance_knots + 1):
                held = lift(lifted, k, stance_knots, False) if h == 0 else lift(lifted, 1, 1, False)
                running.append(setup.contact_node(dt, stance, swing=held))
            for k in range(1, flight_knots + 1):
                s = k / flight_knots
                targets = {f: swing_point(pos[f], pos[f], hop_height, s) for f in hopping}
                running.append(setup.contact_node(dt, {}, swing={**targets, **lift(lifted, 1, 1, False)}))
            running.append(setup.impulse_node({f: pos[f] for f in hopping}))
        stance = {f: pos[f] for f in hopping}
        for k in range(1, stance_knots + 1):
            running.append(setup.contact_node(dt, stance, swing=lift(lifted, k, stance_knots, True)))
        running.append(setup.impulse_node({f: pos[f] for f in lifted}, support=hopping))
        if hopping == pair_a:
            running += [setup.contact_node(dt, dict(pos)) for _ in range(40)]
    n_dt = sum(1 for m in running if m.nu > 0)
    total = int(round(5.8 / dt)) if hops == 10 else n_dt + 30
    running += [setup.contact_node(dt, dict(pos)) for _ in range(max(total - n_dt, 1))]
    terminal = setup.contact_node(0.0, dict(pos), terminal=True)
    return setup.problem(running, terminal)
