"""Control residual ``r = u - uref`` (shape ``(nu,)``), ``Rx = 0``, ``Ru = I``."""

from __future__ import annotations

import numpy as np

from ..data_collector import DataCollectorAbstract
from ..state import StateAbstract
from ..validation import as_count, as_vector
from ..versioning import frozen_copy
from .base import ResidualDataAbstract, ResidualModelAbstract


class ResidualModelControl(ResidualModelAbstract):
    """``ResidualModelControl(state, uref)``, ``(state, nu)`` or ``(state)`` (``uref = 0``, ``nu = nv``)."""

    _value_attributes = frozenset({"reference", "uref"})

    compiled_kind = "control"
    """The kind compiled nodes evaluate this class as (:mod:`crocopy.models.rbd.euler_node_kernel`)."""
    rows_only = True
    """Its ``calc`` writes the rows ``r`` and nothing else (:meth:`.CostStack.calc_residual_datas`)."""

    def compiled_parameters(self) -> np.ndarray:
        """The parameters compiled nodes read: ``uref`` (the read-only array itself)."""
        return self._uref


    def __init__(self, state: StateAbstract, uref: np.ndarray | int | None = None) -> None:
        if uref is None or (isinstance(uref, int | np.integer) and not isinstance(uref, bool | np.bool_)):
            uref = np.zeros(state.nv if uref is None else as_count(uref, "nu"))  # Crocoddyl's (state, nu)
        uref = as_vector(uref, None, "uref")
        super().__init__(state, uref.size, uref.size, False, False, True)
        self.uref = uref

    @property
    def reference(self) -> np.ndarray:
        """Reference control ``uref``, shape ``(nu,)`` (a read-only copy: assign a new array to change it)."""
        return self._uref

    @reference.setter
    def reference(self, value: np.ndarray) -> None:
        self.uref = value

    @property
    def uref(self) -> np.ndarray:
        return self._uref

    @uref.setter
    def uref(self, value: np.ndarray) -> None:
        self._uref = frozen_copy(as_vector(value, self.nu, "uref"))

    def calc(self, data: ResidualDataAbstract, x: np.ndarray, u: np.ndarray | None = None) -> None:
        if u is None:
            data.r[:] = 0.0
        else:
            np.subtract(u, self._uref, out=data.r)

    def calcDiff(self, data: ResidualDataAbstract, x: np.ndarray, u: np.ndarray | None = None) -> None:
        """``Ru = I`` is constant and set once in :meth:`createData`."""

    def createData(self, data: DataCollectorAbstract | None = None) -> ResidualDataAbstract:
        d = ResidualDataAbstract(self, data)
        d.Ru[:] = np.eye(self.nu)
        return d
