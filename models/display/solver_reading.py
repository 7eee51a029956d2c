"""What the display reads from a solver: configurations, frame paths and contact forces per node.

``xs`` are the solver's states ``(nx,)`` (a configuration ``q (nq,)`` first); frame paths are world
positions ``[x, y, z]`` per node; a node's forces are records ``{"key", "oMf", "f", "R", "mu", "type"}``
(frame name, frame placement, ``pinocchio.Force``, friction-cone rotation and coefficient, reference
frame), read from the solver's datas as they are after the solve.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import pinocchio as pin

from .scene import active_contacts, frame_ids_of, friction_cones


def solver_nodes(solver: Any) -> list[tuple[Any, Any]]:
    """``(model, data)`` of every node of the solver's problem, the terminal one last."""
    problem = solver.problem
    return list(zip(problem.runningModels, problem.runningDatas, strict=False)) + [
        (problem.terminalModel, problem.terminalData)
    ]


def configurations(nq: int, xs: Sequence[np.ndarray]) -> list[np.ndarray]:
    """The configurations ``q`` (first ``nq`` entries) of the states ``xs``, checked."""
    qs = []
    for i, x in enumerate(xs):
        x = np.asarray(x, dtype=float).reshape(-1)
        if x.shape[0] < nq:
            raise ValueError(f"xs[{i}] must have at least nq={nq} entries, got shape {x.shape}")
        qs.append(x[:nq])
    if not qs:
        raise ValueError("xs must contain at least one state")
    return qs


def trajectory_frame_names(model: pin.Model, names: Sequence[str], solver: Any) -> list[str]:
    """``names`` followed by the frames of the problem's contacts and frame residuals (each once)."""
    found = list(names)
    for node_model, _ in solver_nodes(solver):
        for fid in frame_ids_of(node_model):
            name = model.frames[fid].name
            if name not in found:
                found.append(name)
    return found


def frame_trajectories(model: pin.Model, data: pin.Data, names: Sequence[str],
                       qs: Sequence[np.ndarray]) -> dict[str, list[list[float]]]:
    """World positions of the frames ``names`` at the configurations ``qs``: ``{name: [[x, y, z], ...]}``."""
    ids = {name: model.getFrameId(name) for name in names}
    ps: dict[str, list[list[float]]] = {name: [] for name in ids}
    for q in qs:
        pin.framesForwardKinematics(model, data, q)
        for name, fid in ids.items():
            ps[name].append(data.oMf[fid].translation.tolist())
    return ps


def force_trajectories(model: pin.Model, data: pin.Data, solver: Any,
                       qs: Sequence[np.ndarray]) -> list[list[dict]]:
    """Contact (and impulse) force records of every node; nodes with free dynamics give an empty list.

    Friction-cone orientation and coefficient come from friction-cone residuals on the same frame,
    else ``R = I``, ``mu = 0.7``.
    """
    fs: list[list[dict]] = []
    for i, (node_model, node_data) in enumerate(solver_nodes(solver)):
        records = []
        contacts = active_contacts(node_model, node_data)
        if contacts:
            pin.framesForwardKinematics(model, data, qs[min(i, len(qs) - 1)])
            cones = friction_cones(node_model)
        for fid, force, ftype in contacts:
            R, mu = cones.get(fid, (np.eye(3), 0.7))
            records.append({"key": model.frames[fid].name, "oMf": data.oMf[fid].copy(), "f": force, "R": R,
                            "mu": mu, "type": ftype})
        fs.append(records)
    return fs
