"""Analytic action models: LQR, differential LQR and the unicycle."""

from .diff_lqr import DifferentialActionModelLQR
from .lqr import ActionModelLQR
from .unicycle import ActionModelUnicycle

__all__ = ["ActionModelLQR", "ActionModelUnicycle", "DifferentialActionModelLQR"]
