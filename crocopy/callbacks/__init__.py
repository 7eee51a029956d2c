"""Solver callbacks: verbose table and logger (:mod:`.base`), display (:mod:`.display`) and the
convergence / solution plots (:mod:`.plotting`, matplotlib loaded on first use)."""

from .base import CallbackAbstract, CallbackLogger, CallbackVerbose
from .display import CallbackDisplay
