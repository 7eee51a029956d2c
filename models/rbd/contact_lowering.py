"""The rigid contacts of a contact-dynamics node, lowered for :mod:`.euler_node_kernel`.

A ``DifferentialActionModelContactFwdDynamics`` node compiles when its active contacts are all ``ContactModel1D``,
``ContactModel2D``, ``ContactModel3D`` or ``ContactModel6D`` (exact classes), and the set is not redundant
(``_redundant_contacts``: without damping, contacts sharing a body or a stacked Jacobian of deficient rank at a
generic configuration; such a set takes the least-squares path of the Python model, which the kernels do not
implement).  Its contacts
become, in the order of the contact model (by name):

* ``ints``: per contact ``(frame, rows, reference frame, first row)`` (:data:`.node_table.CONTACT_FIELDS`;
  ``WORLD`` is read as ``LOCAL_WORLD_ALIGNED``, as the contacts do);
* arrays ``gains (n, 2)`` (Baumgarte ``kp, kd``), ``ref_R (n, 3, 3)`` and ``ref_p (n, 3)`` (the reference
  placement; a 3D contact's rotation is unused and left zero; a 1D or 2D contact's ``ref_R`` holds its rows of the
  point contact, :mod:`.contact_kernel`), rewritten in place at each solve.

The force residuals (``ResidualModelContactFrictionCone``, ``ResidualModelContactWrenchCone``,
``ResidualModelContactForce``) find their contact's first row here.  They read the contact's force ``f`` (``ncf``
components); a 1D contact's is ``(0, 0, λ, …)``, a 2D contact's ``(λ₀, 0, λ₁, …)``: ``f = E λ``, so their matrix
``A (nr, ncf)`` becomes ``A E (nr, nc)`` over the contact's own rows (:func:`force_parameters`).
Inverse-dynamics nodes take the same contacts (their model takes no 2D contact).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from crocopy.not_compiled import class_reason, decline

from .. import contacts
from .lowering import declaring
from .node_table import CONTACT_FIELDS

CONTACTS = declaring(contacts.ContactModelAbstract, "compiled_reference")
"""The contacts compiled nodes take: those that lower their reference themselves (``compiled_reference(R, p)``)."""


def active_contacts(dam, memo: dict) -> list | None:
    """The active contact models of ``dam`` (a ``DifferentialActionModelContactFwdDynamics``), or None if the node
    cannot compile (see the module docstring; the reason is recorded in ``memo``, :mod:`crocopy.not_compiled`)."""
    models = [m for _, m in dam.contacts._active]
    other = next((m for m in models if type(m) not in CONTACTS), None)
    if other is not None:
        return decline(memo, class_reason(other, "contact"))
    if dam._redundant_contacts():
        return decline(memo, "redundant contacts")
    return models


class ContactSet:
    """The lowered contacts of one node: :attr:`ints`, the arrays :attr:`gains`, :attr:`ref_R`, :attr:`ref_p`, and
    :attr:`rows`, each contact frame's ``(first row, rows)``."""

    def __init__(self, models: list) -> None:
        n = len(models)
        self.nc = sum(m.nc for m in models)
        self.gains = np.zeros((n, 2))
        self.ref_R = np.zeros((n, 3, 3))
        self.ref_p = np.zeros((n, 3))
        self.ints = _ints(models)
        self.rows = frame_rows(self.ints)
        self.models = list(models)
        self.refresh()

    def refresh(self) -> None:
        """Read the gains and references again (into the same arrays)."""
        for k, m in enumerate(self.models):
            self.gains[k] = m.gains
            m.compiled_reference(self.ref_R[k], self.ref_p[k])

    def same(self, models: list) -> bool:
        """Whether ``models`` are this set's contacts (same objects, frames, sizes and reference frames)."""
        return len(models) == len(self.models) and all(a is b for a, b in zip(models, self.models)) and \
            self.ints == _ints(models)


def frame_rows(ints: list[int]) -> dict[int, tuple[int, int]]:
    """Each frame's ``(first row, rows)`` in a flat ``(frame, rows, reference frame, first row)`` list (the first
    contact or impulse on the frame): where the force residuals find their rows."""
    rows: dict[int, tuple[int, int]] = {}
    for frame, nc, _, row in zip(*[iter(ints)] * CONTACT_FIELDS):
        rows.setdefault(frame, (row, nc))
    return rows


def force_item(residual, rows: dict[int, tuple[int, int]]) -> tuple[int, int] | None:
    """The ``(first row, force components)`` a force residual's or cone's item reads on its contact or impulse
    (``rows``: :func:`frame_rows`; a 1D or 2D contact's own rows, :func:`force_parameters`), or None when that contact
    is not active or has fewer force components than the residual reads."""
    first, nc = rows.get(residual.id, (0, 0))
    if nc < residual.min_nc or (nc > 2 and nc < residual.ncf):
        return None
    return first, nc if nc in (1, 2) else residual.ncf


def _ints(models: list) -> list[int]:
    """``(frame, rows, reference frame, first row)`` of each contact, flat."""
    ints, row = [], 0
    for m in models:
        reference = int(pin.LOCAL) if m.type == pin.LOCAL else int(pin.LOCAL_WORLD_ALIGNED)
        ints += [int(m.id), int(m.nc), reference, row]
        row += m.nc
    return ints


def force_parameters(values, nr: int, ncf: int, nc: int) -> list[float]:
    """A force residual's parameters (``A (nr, ncf)`` row-major, then the rest: ``fref``) for a contact of ``nc``
    rows: ``A`` becomes ``A E (nr, nc)``, ``E`` the embedding of the contact's ``λ`` in its force components (a 1D
    contact's ``λ`` is the third, a 2D contact's the first and the third; the module docstring)."""
    values = np.asarray(values, dtype=float)
    if nc not in (1, 2):
        return list(values)
    A = values[: nr * ncf].reshape(nr, ncf)
    columns = (2,) if nc == 1 else (0, 2)
    return [*A[:, columns].reshape(-1), *values[nr * ncf:]]
