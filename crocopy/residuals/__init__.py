"""Residuals that need nothing but the state and control."""

from .control import ResidualModelControl
from .state import ResidualModelState

__all__ = ["ResidualModelControl", "ResidualModelState"]
