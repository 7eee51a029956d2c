"""Enumerations shared across crocopy (Crocoddyl names)."""

from __future__ import annotations

import enum


class Jcomponent(enum.IntEnum):
    """Which Jacobian(s) of a binary state operation to compute."""

    both = 0
    first = 1
    second = 2


class AssignmentOp(enum.IntEnum):
    """How a Jacobian is written into its destination."""

    setto = 0
    addto = 1
    rmfrom = 2


class RKType(enum.IntEnum):
    """Order of the explicit Runge-Kutta integrator."""

    two = 2
    three = 3
    four = 4


class VerboseLevel(enum.IntEnum):
    """Columns printed by :class:`CallbackVerbose` (``_0`` fewest, ``_4`` all)."""

    _0 = 0
    _1 = 1
    _2 = 2
    _3 = 3
    _4 = 4


class FeasibilityNorm(enum.IntEnum):
    """Norm of a solver's ``ffeas``/``gfeas``/``hfeas`` (``solver.feasNorm``): max-abs or sum-abs."""

    LInf = 0
    L1 = 1
