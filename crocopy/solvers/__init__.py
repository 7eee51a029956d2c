"""Solvers of shooting problems, all behind :class:`SolverAbstract`'s API."""

from .base import BackwardPassError, SolverAbstract
from .ddp import SolverDDP
from .fddp import SolverFDDP

SOLVERS = {
    "boxfddp": "SolverBoxFDDP",
    "boxddp": "SolverBoxDDP",
    "fddp": "SolverFDDP",
    "ddp": "SolverDDP",
    "intro": "SolverIntro",
    "kkt": "SolverKKT",
}
"""Short solver names (the CLI's ``--solver`` choices) → class names, the same in crocopy and Crocoddyl."""

__all__ = ["SOLVERS", "BackwardPassError", "SolverAbstract", "SolverDDP", "SolverFDDP"]
