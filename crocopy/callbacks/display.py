"""``CallbackDisplay``: show the solver's current trajectory after every iteration.

The display is any object with ``displayFromSolver(solver)`` (e.g. ``crocopy.models.MeshcatDisplay``);
this module imports nothing from Pinocchio or meshcat.
"""

from __future__ import annotations

from typing import Any

from .base import CallbackAbstract

__all__ = ["CallbackDisplay"]


class CallbackDisplay(CallbackAbstract):
    """Call ``display.displayFromSolver(solver)`` at the end of each solver iteration.

    Parameters
    ----------
    display : object
        Display with a ``displayFromSolver(solver)`` method (Crocoddyl's ``DisplayAbstract``
        interface), e.g. ``MeshcatDisplay``.
    """

    def __init__(self, display: Any) -> None:
        if not callable(getattr(display, "displayFromSolver", None)):
            raise ValueError(f"display must have a displayFromSolver(solver) method, got {type(display).__name__}")
        self.display = display

    def __call__(self, solver: Any) -> None:
        self.display.displayFromSolver(solver)
