"""Crocoddyl's compiled module under its name, as an alias of crocopy's flat namespace.

Crocoddyl's classes live in ``crocoddyl.libcrocoddyl_pywrap_float64`` (``crocoddyl.StateVector`` is
``crocoddyl.libcrocoddyl_pywrap_float64.StateVector``); code that reaches a base implementation
through it (``crocoddyl.libcrocoddyl_pywrap_float64.StateVector.diff(self, x0, x1)``) runs with
``import crocopy as crocoddyl``: every public name of :mod:`crocopy` is here, the same object.
"""

from __future__ import annotations

from types import ModuleType as _ModuleType

import crocopy as _crocopy
from crocopy import *  # noqa: F403  (the same objects as crocopy's flat namespace)


def __getattr__(name: str):
    """The names :mod:`crocopy` loads lazily (``MeshcatDisplay``, ...), and its "not implemented" message
    (not crocopy's submodules: this module is not a package)."""
    value = None if name.startswith("__") else getattr(_crocopy, name)
    if value is None or isinstance(value, _ModuleType):
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return value
