"""Numerical differentiation of a state's ``diff``/``integrate`` (Crocoddyl's ``StateNumDiff(state)``).

Every Jacobian is a central difference in tangent coordinates with step ``h = disturbance``
(default ``ε^(1/3)``, ε machine epsilon), each perturbed output read in the tangent space at the
unperturbed output ``y``::

    column i = (y ⊖ y(+h eᵢ) - y ⊖ y(-h eᵢ)) / 2h     (a ⊖ b = diff(a, b))

with ``y = x1 ⊖ x0`` (a vector: plain differences) for ``Jdiff`` and ``y = x ⊕ dx`` for
``Jintegrate``.  ``zero``, ``rand``, ``diff`` and ``integrate`` are the wrapped state's.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ..enums import Jcomponent
from ..state import StateAbstract

_EPS = np.finfo(float).eps


class StateNumDiff(StateAbstract):
    """State whose Jacobians are finite differences of ``state``'s ``diff`` and ``integrate``.

    Parameters
    ----------
    state : StateAbstract
        State to differentiate.
    """

    def __init__(self, state: StateAbstract) -> None:
        if not isinstance(state, StateAbstract):
            raise ValueError(f"state must be a StateAbstract, got {type(state).__name__}")
        super().__init__(state.nx, state.ndx)
        self.state = state
        self.nq, self.nv = state.nq, state.nv
        self._set_limits(state.lb, state.ub)
        self.disturbance = _EPS ** (1.0 / 3.0)

    def zero(self) -> np.ndarray:
        return self.state.zero()

    def rand(self) -> np.ndarray:
        return self.state.rand()

    def diff(self, x0: np.ndarray, x1: np.ndarray) -> np.ndarray:
        return self.state.diff(x0, x1)

    def integrate(self, x: np.ndarray, dx: np.ndarray) -> np.ndarray:
        return self.state.integrate(x, dx)

    def _jacobian(self, f: Callable[[np.ndarray], np.ndarray], gap: Callable[[np.ndarray], np.ndarray]) -> np.ndarray:
        """Central differences of ``gap(f(δ))`` over the tangent perturbation ``δ`` (``gap(f(0)) = 0``)."""
        h = self.disturbance
        J = np.zeros((self.ndx, self.ndx))
        delta = np.zeros(self.ndx)
        for i in range(self.ndx):
            delta[i] = h
            plus = gap(f(delta))
            delta[i] = -h
            J[:, i] = (plus - gap(f(delta))) / (2.0 * h)
            delta[i] = 0.0
        return J

    def Jdiff(self, x0: np.ndarray, x1: np.ndarray, firstsecond: Jcomponent = Jcomponent.both) -> list:
        """``[∂(x1 ⊖ x0)/∂x0, ∂(x1 ⊖ x0)/∂x1]`` (or the one asked), each ``(ndx, ndx)``."""
        st = self.state
        y = st.diff(x0, x1)

        def gap(v: np.ndarray) -> np.ndarray:
            return v - y

        return _select(
            (
                lambda: self._jacobian(lambda d: st.diff(st.integrate(x0, d), x1), gap),
                lambda: self._jacobian(lambda d: st.diff(x0, st.integrate(x1, d)), gap),
            ),
            firstsecond,
        )

    def Jintegrate(self, x: np.ndarray, dx: np.ndarray, firstsecond: Jcomponent = Jcomponent.both) -> list:
        """``[∂(x ⊕ dx)/∂x, ∂(x ⊕ dx)/∂dx]`` (or the one asked), each ``(ndx, ndx)``."""
        st = self.state
        y = st.integrate(x, dx)

        def gap(z: np.ndarray) -> np.ndarray:
            return st.diff(y, z)

        return _select(
            (
                lambda: self._jacobian(lambda d: st.integrate(st.integrate(x, d), dx), gap),
                lambda: self._jacobian(lambda d: st.integrate(x, dx + d), gap),
            ),
            firstsecond,
        )

    def JintegrateTransport(self, x: np.ndarray, dx: np.ndarray, Jin: np.ndarray, firstsecond: Jcomponent) -> None:
        """``Jin ← J Jin`` in place, with ``J`` the numerical ``Jintegrate`` block named by ``firstsecond``."""
        if firstsecond == Jcomponent.both:
            raise ValueError("JintegrateTransport needs firstsecond = Jcomponent.first or Jcomponent.second")
        Jin[:] = self.Jintegrate(x, dx, firstsecond)[0] @ Jin

    def __repr__(self) -> str:
        return f"StateNumDiff({self.state!r})"


def _select(blocks: tuple[Callable[[], np.ndarray], Callable[[], np.ndarray]], firstsecond: Jcomponent) -> list:
    """Evaluate the Jacobian(s) named by ``firstsecond`` (Crocoddyl's list convention)."""
    if firstsecond == Jcomponent.first:
        return [blocks[0]()]
    if firstsecond == Jcomponent.second:
        return [blocks[1]()]
    return [blocks[0](), blocks[1]()]
