"""Solvers of shooting problems, all behind :class:`SolverAbstract`'s API."""

from .base import BackwardPassError, SolverAbstract
from .ddp import SolverDDP
from .fddp import SolverFDDP

__all__ = ["BackwardPassError", "SolverAbstract", "SolverDDP", "SolverFDDP"]
