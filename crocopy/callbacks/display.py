"""Displays of solutions: Crocoddyl's ``DisplayAbstract`` interface and ``CallbackDisplay``.

A display plays a state trajectory ``xs`` (``display``), possibly with controls ``us``, thrusts
``rs``, frame poses ``ps``/``pds``, contact forces ``fs``, friction surfaces ``ss`` and node
durations ``dts``; ``displayFromSolver`` reads them from a solver.  ``crocopy.MeshcatDisplay``
implements it with meshcat; a subclass written from Python implements the abstract methods.
:class:`CallbackDisplay` shows the solver's current trajectory after every iteration.  This module
imports nothing from Pinocchio or meshcat.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Sequence
from typing import Any

import numpy as np

from .base import CallbackAbstract

__all__ = ["CallbackDisplay", "DisplayAbstract"]


class DisplayAbstract(ABC):
    """Crocoddyl's ``DisplayAbstract(robot, rate=-1, freq=1)``.

    Parameters
    ----------
    robot : pinocchio.RobotWrapper
        Robot to display.
    rate : float
        Display rate in Hz; ``-1`` plays in real time using the node durations.
    freq : int
        Display every ``freq``-th node.
    """

    def __init__(self, robot: Any, rate: float = -1, freq: int = 1) -> None:
        if int(freq) < 1:
            raise ValueError(f"freq must be a positive integer, got {freq}")
        self.robot = robot
        self.rate = float(rate)
        self.freq = int(freq)

    @abstractmethod
    def display(
        self,
        xs: Sequence[np.ndarray],
        us: Sequence[np.ndarray] = (),
        rs: Sequence[Any] = (),
        ps: Any = (),
        pds: Sequence[Any] = (),
        fs: Sequence[Any] = (),
        ss: Sequence[Any] = (),
        dts: Sequence[float] = (),
        factor: float = 1.0,
    ) -> None:
        """Play the trajectory ``xs`` (``factor`` slows the playback down)."""

    @abstractmethod
    def setVisibility(self, name: str, status: bool) -> None:
        """Show or hide the element ``name``."""

    @abstractmethod
    def displayFramePoses(self, ps: Any) -> None:
        """Draw frame trajectories."""

    @abstractmethod
    def displayContactForce(self, f: Any) -> None:
        """Draw the contact forces of one node."""

    @abstractmethod
    def displayThrustForce(self, f: Any) -> None:
        """Draw the thrust forces of one node."""

    def displayFromSolver(self, solver: Any, factor: float = 1.0) -> None:
        """Play the solver's ``xs`` and ``us`` with its nodes' durations."""
        self.display(solver.xs, us=solver.us, dts=self.getDurationSequenceFromSolver(solver), factor=factor)

    def getDurationSequenceFromSolver(self, solver: Any) -> list[float]:
        """Duration ``dt`` of every running node (0 for nodes without one, e.g. impulses)."""
        return [float(getattr(m, "dt", 0.0)) for m in solver.problem.runningModels]

    def getTimeSequenceFromSolver(self, solver: Any) -> list[float]:
        """Start time of every node, terminal included."""
        return [0.0, *np.cumsum(self.getDurationSequenceFromSolver(solver)).tolist()]


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
