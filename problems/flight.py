"""What a legged trajectory does in the air: flight time, base apex, foot spread and landing.

Read from a solved :class:`ShootingProblem` of a floating-base robot (``nq = nv + 1``) whose nodes
are contact nodes (``DifferentialActionModelContactFwdDynamics``), impulse nodes and, in flight,
free-dynamics nodes (``DifferentialActionModelFreeFwdDynamics``).  A flight node is a running node
with ``dt > 0`` and no contact; the flight time is the sum of their ``dt``.

Foot spread is measured in the base frame: for the feet ``p_i`` (base-frame positions, ``(n, 3)``)
the spread is ``(max_i |p_i,x|, max_i |p_i,y|)``, the half-extents of the foot polygon around the
base.  ``spread_ratio`` is the largest of the two over the trajectory divided by its value at the
first state.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin


@dataclass(frozen=True)
class FlightReport:
    """Figures of a trajectory with a flight phase (heights in m, times in s).

    Attributes
    ----------
    flight_time : float
        Sum of the ``dt`` of the free-dynamics nodes.
    apex : float
        Highest base height minus the base height of the first state.
    spread_ratio : float
        Largest base-frame foot half-extent (x or y) over its value at the first state.
    feet_below_base : float
        Smallest height of the base above a foot while in flight (tucked feet stay well below).
    landed : bool
        The last state has every foot on the ground (within 1 cm of its height at the first state).
    """

    flight_time: float
    apex: float
    spread_ratio: float
    feet_below_base: float
    landed: bool


def _differential(model: object) -> object | None:
    return getattr(model, "differential", None)


def flight_nodes(problem: object) -> list[int]:
    """Indices of the running nodes in flight (``dt > 0``, free dynamics), in a problem with contacts.

    Empty when no node has contacts (a drone flies throughout: no take-off, no landing).
    """
    models = problem.runningModels
    has_contacts = [hasattr(_differential(m), "contacts") for m in models]
    if not any(has_contacts):
        return []
    return [i for i, (m, c) in enumerate(zip(models, has_contacts, strict=True))
            if getattr(m, "dt", 0.0) > 0 and _differential(m) is not None and not c]


def contact_frames(problem: object) -> list[int]:
    """Frame ids of every contact of the problem's contact nodes (the feet of a legged problem), sorted."""
    ids = set()
    for m in problem.runningModels:
        contacts = getattr(_differential(m), "contacts", None)
        if contacts is not None:
            ids.update(item.contact.id for item in contacts.contacts.values())
    return sorted(ids)


def flight_report(problem: object, xs: Sequence[np.ndarray]) -> FlightReport | None:
    """The :class:`FlightReport` of the trajectory ``xs`` (``T + 1`` states), or ``None`` without flight.

    The feet are the frames of :func:`contact_frames`.
    """
    flying = flight_nodes(problem)
    model = getattr(problem.terminalModel.state, "pinocchio", None)
    if not flying or model is None or model.nq != model.nv + 1:
        return None
    data = model.createData()
    fids = contact_frames(problem)
    spreads, below, ground = [], [], []
    for k, x in enumerate(xs):
        pin.framesForwardKinematics(model, data, np.asarray(x)[: model.nq])
        base = data.oMi[1]
        rel = np.array([base.actInv(data.oMf[f].translation) for f in fids])
        spreads.append(np.abs(rel[:, :2]).max(axis=0))
        ground.append(np.array([data.oMf[f].translation[2] for f in fids]))
        if k in flying:
            below.append(-rel[:, 2].max())
    spreads = np.array(spreads)
    heights = np.array([x[2] for x in xs])
    dts = [problem.runningModels[i].dt for i in flying]
    return FlightReport(
        flight_time=float(np.sum(dts)),
        apex=float(heights.max() - heights[0]),
        spread_ratio=float((spreads / spreads[0]).max()),
        feet_below_base=float(min(below)),
        landed=bool(np.all(np.abs(ground[-1] - ground[0]) < 1e-2)),
    )
