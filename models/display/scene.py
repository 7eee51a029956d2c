"""Reading contact forces, friction cones and frames out of a solver's problem and data.

Written defensively against Crocoddyl's attribute layout, so that problems without contacts (free
dynamics) and nodes of any kind (integrated contact dynamics, impulses, terminal nodes) work:

* contact data: ``data.differential.multibody.contacts.contacts[name]`` with ``.f``
  (pinocchio.Force) and ``.frame``; the contact model item ``model.differential.contacts.contacts[name]``
  with ``.active`` and ``.contact.id`` / ``.contact.type``;
* impulse data: ``data.multibody.impulses.impulses[name]`` likewise;
* friction cones: any cost or constraint residual with ``id`` and a ``reference`` holding ``mu``
  and ``R``.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pinocchio as pin

__all__ = ["active_contacts", "friction_cones", "frame_ids_of"]


def _get(obj: Any, *names: str) -> Any:
    """Follow attribute ``names`` from ``obj``; ``None`` when any is missing."""
    for name in names:
        obj = getattr(obj, name, None)
        if obj is None:
            return None
    return obj


def _items(container: Any) -> list[tuple[str, Any]]:
    if container is None:
        return []
    if hasattr(container, "items"):
        return list(container.items())
    return [(k, container[k]) for k in container]


def _contact_stacks(model: Any, data: Any) -> list[tuple[Any, Any]]:
    """(model items, data items) of the contact or impulse stacks of one node, when present."""
    stacks = []
    for m_path, d_path in (
        (("differential", "contacts", "contacts"), ("differential", "multibody", "contacts", "contacts")),
        (("contacts", "contacts"), ("multibody", "contacts", "contacts")),
        (("impulses", "impulses"), ("multibody", "impulses", "impulses")),
    ):
        d_items = _get(data, *d_path)
        if d_items is not None:
            stacks.append((_get(model, *m_path), d_items))
    return stacks


def active_contacts(model: Any, data: Any) -> list[tuple[int, Any, Any]]:
    """(frame id, force, reference frame of the force) of the node's active contacts."""
    out = []
    for m_items, d_items in _contact_stacks(model, data):
        m_dict = dict(_items(m_items))
        for name, cdata in _items(d_items):
            item = m_dict.get(name)
            if item is not None and not getattr(item, "active", True):
                continue
            inner = getattr(item, "contact", None) or getattr(item, "impulse", None)
            fid = getattr(cdata, "frame", None)
            if fid is None:
                fid = getattr(inner, "id", None)
            force = getattr(cdata, "f", None)
            if fid is None or force is None:
                continue
            ftype = getattr(inner, "type", None) or getattr(cdata, "type", None)
            out.append((int(fid), force, ftype if ftype is not None else pin.ReferenceFrame.LOCAL_WORLD_ALIGNED))
    return out


def _residuals_of(model: Any) -> list[Any]:
    """Residual models of the node's costs and constraints."""
    out = []
    for base in (model, getattr(model, "differential", None)):
        if base is None:
            continue
        for _, item in _items(_get(base, "costs", "costs")):
            out.append(_get(item, "cost", "residual"))
        for _, item in _items(_get(base, "constraints", "constraints")):
            out.append(_get(item, "constraint", "residual"))
    return [r for r in out if r is not None]


def friction_cones(model: Any) -> dict[int, tuple[np.ndarray, float]]:
    """Frame id -> (cone rotation R, friction coefficient mu) from friction-cone residuals."""
    cones = {}
    for r in _residuals_of(model):
        ref = getattr(r, "reference", None)
        if hasattr(ref, "mu") and hasattr(ref, "R") and hasattr(r, "id"):
            cones[int(r.id)] = (np.array(ref.R, dtype=float), float(ref.mu))
    return cones


def frame_ids_of(model: Any) -> list[int]:
    """Frames of the node's contacts and frame residuals (placement, translation, ...)."""
    ids = []
    for path in (("differential", "contacts", "contacts"), ("contacts", "contacts"), ("impulses", "impulses")):
        for _, item in _items(_get(model, *path)):
            inner = getattr(item, "contact", None) or getattr(item, "impulse", None)
            if inner is not None and hasattr(inner, "id"):
                ids.append(int(inner.id))
    for r in _residuals_of(model):
        if type(r).__name__.startswith("ResidualModelFrame") and hasattr(r, "id"):
            ids.append(int(r.id))
    return list(dict.fromkeys(ids))
