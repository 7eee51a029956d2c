"""Which parameters of a compiled node may change in place, unannounced, and their re-reading.

A compiled node (:mod:`.euler_node`, :mod:`.impulse_node`) copies its models' parameters into its own arrays when it
is refreshed.  Most of them change only through a setter, which moves the parameter clock
(:mod:`crocopy.versioning`): while the clock stands still they are current.  Some do not (``DEVELOPING.md``,
"What keeps caches and compiled copies fresh"): the ``pin.SE3``/``pin.Motion`` references of frame residuals and 6D
contacts, a friction or wrench cone's matrix, a user's ``ResidualModelNumba.parameters()``, and any numpy parameter
that is writeable (a deep-copied or unpickled model's references are).  :class:`LiveParameters` lists those of one
node, so that a solve whose clocks did not move re-reads only them (:meth:`LiveParameters.reread`); the Pinocchio model
is compared with a copy instead (:meth:`.lowered_model.Lowered.current`).

Whatever this module does not know as announced is live: a residual class outside :data:`REFERENCE_ONLY`, a contact
whose reference or gains are not read-only arrays, an actuation outside :data:`CONSTANT_ACTUATIONS` whose matrix is
writeable, a writeable armature.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from crocopy.residuals import ResidualModelControl, ResidualModelState
from crocopy.versioning import LAYOUT, ParametersVersion, changes_since, touched_since

from ..actuations import ActuationModelFloatingBase, ActuationModelFull
from ..residuals_dynamics import ResidualModelCoMPosition
from ..residuals_frame import ResidualModelFrameRotation, ResidualModelFrameTranslation

REFERENCE_ONLY = (ResidualModelState, ResidualModelControl, ResidualModelFrameTranslation, ResidualModelFrameRotation,
                  ResidualModelCoMPosition)
"""Residual classes (exact) whose ``compiled_parameters()`` are their ``reference`` array alone."""
CONSTANT_ACTUATIONS = (ActuationModelFull, ActuationModelFloatingBase)
"""Actuation classes (exact) whose ``compiled_matrix()`` depends on the state's sizes alone."""


def frozen(value: object) -> bool:
    """Whether ``value`` is a read-only numpy array (its owner's setter is then the only way to change it)."""
    return isinstance(value, np.ndarray) and not value.flags.writeable


def residual_live(residual: object) -> bool:
    """Whether ``residual``'s compiled parameters may change without moving the parameter clock."""
    return type(residual) not in REFERENCE_ONLY or not frozen(residual.reference)


def contacts_live(contacts: list) -> bool:
    """Whether a contact's lowered reference or gains may change without moving the parameter clock."""
    return any(not frozen(m.reference) or not frozen(m.gains) for m in contacts)


def actuation_live(actuation: object, matrix: np.ndarray) -> bool:
    """Whether the actuation matrix ``matrix`` (``actuation.compiled_matrix()``) may change without moving the clock."""
    return type(actuation) not in CONSTANT_ACTUATIONS and not frozen(matrix)


def read_parameters(residuals: list, par: list, parameters: Callable, read: dict | None = None) -> LiveParameters:
    """Append the parameters of ``residuals`` (``(kind, residual)`` in ``par`` order; ``parameters(kind, residual)``
    their values, or ``read[id(residual)]`` where the caller has just read them) to the list ``par``; returns which of
    them are live."""
    slices, every = [], []
    for kind, residual in residuals:
        values = parameters(kind, residual) if read is None else read[id(residual)]
        where = (len(par), len(par) + len(values), kind, residual)
        every.append(where)
        if residual_live(residual):
            slices.append(where)
        par.extend(values)
    return LiveParameters(slices, parameters, every)


class LiveParameters:
    """The entries of a node's ``par`` read from live sources (see the module docstring).

    Parameters
    ----------
    slices : list of (start, stop, kind, residual)
        Where the live residuals' parameters are in ``par``.
    parameters : callable
        ``parameters(kind, residual) -> list of float``, the values the node reads.
    every : list of (start, stop, kind, residual)
        Where every residual's parameters are in ``par`` (:meth:`reread_since`).
    """

    def __init__(self, slices: list, parameters: Callable, every: list) -> None:
        self.slices = slices
        self.parameters = parameters
        self.every = every
        self.residual_ids = frozenset(id(entry[3]) for entry in every)
        """The ``id`` of every residual listed (:func:`residuals_only`)."""

    def reread(self, par: np.ndarray) -> bool:
        """Write the live residuals' current parameters into ``par``; False (``par`` partly written) if one changed
        its number of parameters (the node must be refreshed)."""
        return self._write(par, self.slices)

    def reread_since(self, par: np.ndarray, seen: int) -> bool:
        """:meth:`reread` of the live residuals and of those touched after the parameter clock read ``seen`` (a
        reference assigned: :func:`crocopy.versioning.touch`)."""
        return self._write(par, [s for s in self.every if residual_live(s[3]) or getattr(s[3], "_stamp", 0) > seen])

    def _write(self, par: np.ndarray, slices: list) -> bool:
        for start, stop, kind, residual in slices:
            values = self.parameters(kind, residual)
            if len(values) != stop - start:
                return False
            par[start:stop] = values
        return True


def layout_touched(node) -> bool:
    """Whether the layout of an object of a compiled node (``node._owners``) was touched since the node last read its
    parameters (``node._seen``): its items and table must be read again (:func:`crocopy.versioning.changes_since`)."""
    return node._seen != ParametersVersion.value and changes_since(node._owners, node._seen) == LAYOUT


def values_touched(node, read: bool, memo: dict) -> list | None:
    """The start of a compiled node's ``refresh_values`` (:mod:`.euler_node`, :mod:`.impulse_node`) after the
    parameter clock moved: None if the node must be refreshed (``read`` False: its items are to be read again; the
    layout of one of its objects was touched; its live parameters cannot be re-read), an empty list if none of its
    objects was touched (its live parameters re-read, ``node.refresh_live``), else the objects whose values were
    (:func:`crocopy.versioning.touched_since`)."""
    touched = touched_since(node._owners, node._seen) if read else None
    if touched is None or touched:
        return touched
    if not node.refresh_live(memo):
        return None
    node._seen = ParametersVersion.value
    return touched


def residuals_only(touched: list, live: LiveParameters) -> bool:
    """Whether every object of ``touched`` is a residual whose parameters ``live`` lists (its node then re-reads them
    and its live sources only: its dynamics, time step and contacts were not assigned)."""
    ids = live.residual_ids
    return all(id(owner) in ids for owner in touched)
