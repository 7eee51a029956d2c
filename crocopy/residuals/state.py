"""State residual ``r = x ⊖ xref`` (shape ``(ndx,)``), ``Rx = ∂(x ⊖ xref)/∂x``, ``Ru = 0``."""

from __future__ import annotations

import numpy as np

from ..data_collector import DataCollectorAbstract
from ..state import StateAbstract
from ..validation import as_optional_count, as_vector
from ..versioning import frozen_copy
from .base import ResidualDataAbstract, ResidualModelAbstract


class ResidualModelState(ResidualModelAbstract):
    """``ResidualModelState(state, xref=state.zero(), nu=state.nv)``; also ``(state, nu)``."""

    _value_attributes = frozenset({"reference", "xref"})

    compiled_kind = "state"
    """The kind compiled nodes evaluate this class as (:mod:`crocopy.models.rbd.euler_node_kernel`)."""
    rows_only = True
    """Its ``calc`` writes the rows ``r`` and nothing else (:meth:`.CostStack.calc_residual_datas`)."""

    def compiled_parameters(self) -> np.ndarray:
        """The parameters compiled nodes read: ``xref`` (the read-only array itself)."""
        return self._xref


    def __init__(self, state: StateAbstract, xref: np.ndarray | int | None = None, nu: int | None = None) -> None:
        if isinstance(xref, int | np.integer) and not isinstance(xref, bool | np.bool_):
            xref, nu = None, xref  # Crocoddyl's ResidualModelState(state, nu)
        super().__init__(state, state.ndx, as_optional_count(nu, "nu"), True, True, False)
        self.xref = state.zero() if xref is None else xref

    @property
    def reference(self) -> np.ndarray:
        """Reference state ``xref``, shape ``(nx,)`` (a read-only copy: assign a new array to change it)."""
        return self._xref

    @reference.setter
    def reference(self, value: np.ndarray) -> None:
        self.xref = value

    @property
    def xref(self) -> np.ndarray:
        return self._xref

    @xref.setter
    def xref(self, value: np.ndarray) -> None:
        self._xref = frozen_copy(as_vector(value, self.state.nx, "xref"))

    def calc(self, data: ResidualDataAbstract, x: np.ndarray, u: np.ndarray | None = None) -> None:
        self.state._diff_into(self._xref, x, data.r)

    def calcDiff(self, data: ResidualDataAbstract, x: np.ndarray, u: np.ndarray | None = None) -> None:
        self.state._Jdiff_second_into(self._xref, x, data.Rx)

    def createData(self, data: DataCollectorAbstract | None = None) -> ResidualDataAbstract:
        return ResidualDataAbstract(self, data)
