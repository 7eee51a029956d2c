"""Data collectors: the shared data a node hands to every residual, cost and constraint.

A differential action model fills its collector once per ``calc``/``calcDiff`` (e.g. with the
Pinocchio data of that node) and every residual reads from it, so kinematics is computed once.
"""

from __future__ import annotations


class DataCollectorAbstract:
    """Empty collector, for residuals that need nothing but ``x`` and ``u``."""
