"""Solver callbacks: verbose table and logger (:mod:`~crocopy.callbacks.base`), display
(:mod:`~crocopy.callbacks.display`) and the convergence / solution plots
(:mod:`~crocopy.callbacks.plotting`, matplotlib loaded on first use)."""

from .base import CallbackAbstract, CallbackLogger, CallbackVerbose
from .display import CallbackDisplay
