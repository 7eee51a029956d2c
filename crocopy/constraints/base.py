"""Constraint models: residuals used as inequalities ``lb <= g(x, u) <= ub`` or equalities ``h(x, u) = 0``.

A constraint holds ``ng`` inequality rows (value ``g (ng,)``, Jacobians ``Gx (ng, ndx)``,
``Gu (ng, nu)``, bounds ``lb``/``ub``) and ``nh`` equality rows (``h (nh,)``, ``Hx (nh, ndx)``,
``Hu (nh, nu)``).  :class:`ConstraintModelManager` stacks named constraints, ordered by name as in
Crocoddyl; on terminal nodes (``u`` omitted) only constraints with ``T_constraint`` contribute,
and they fill the first ``ng_T``/``nh_T`` rows.  A differential or action model with constraints
exposes the manager's counts as its ``ng, nh, ng_T, nh_T`` and bounds as ``g_lb, g_ub``, and hands
its data arrays to the manager's data with :meth:`ConstraintDataManager.shareMemory`.
"""

from __future__ import annotations

import enum

import numpy as np

from ..action_common import constraint_arrays
from ..array_views import tolerate_python_model
from ..data_collector import DataCollectorAbstract
from ..guards import Guarded, point_control_guards
from ..residuals.base import ResidualModelAbstract
from ..state import StateAbstract
from ..validation import as_vector, check_bounds
from ..versioning import Parametrized, frozen_copy, touch


class ConstraintType(enum.IntEnum):
    """Kind of rows a constraint holds."""

    Inequality = 0
    Equality = 1
    Both = 2


class ConstraintModelAbstract(Parametrized, Guarded):
    """Abstract constraint (Crocoddyl's ``ConstraintModelAbstract``).

    Constructed, positionally or with keywords, as ``(state, residual, ng, nh)``,
    ``(state, nu, ng, nh, T_const=True)`` or ``(state, ng, nh, T_const=True)`` (then
    ``nu = state.nv``).  A constraint written from Python fills ``data.g``/``data.Gx``/``data.Gu``
    (inequality rows, bounded by ``lb``/``ub``) and ``data.h``/``data.Hx``/``data.Hu`` (equality rows).
    As in Crocoddyl, the residual form is a terminal constraint when the residual reads ``q`` or
    ``v``, and the other forms hold an abstract residual of ``ng + nh`` rows that sizes
    ``data.residual``.  A user's ``calc``/``calcDiff`` is checked (``x (nx,)``, ``u (nu,)`` or ``None``).
    """

    _read_only = frozenset({"state"})

    _guards = point_control_guards()

    def __init__(
        self,
        state: StateAbstract,
        *args,
        residual: ResidualModelAbstract | None = None,
        nu: int | None = None,
        ng: int | None = None,
        nh: int | None = None,
        T_const: bool = True,
    ) -> None:
        if not isinstance(state, StateAbstract):
            raise ValueError(f"state must be a StateAbstract, got {type(state).__name__}")
        given = _positional_form(args, residual is not None, nu is not None)
        named = {"residual": residual, "nu": nu, "ng": ng, "nh": nh}
        for key, value in given.items():
            if key == "T_const":
                T_const = value
            elif named[key] is not None:
                raise TypeError(f"ConstraintModelAbstract got {key} both by position and by keyword")
            else:
                named[key] = value
        residual, nu, ng, nh = named["residual"], named["nu"], named["ng"], named["nh"]
        if ng is None or nh is None:
            raise TypeError("ConstraintModelAbstract needs ng and nh")
        if int(ng) < 0 or int(nh) < 0 or (nu is not None and int(nu) < 0):
            raise ValueError(f"nu, ng and nh must be non-negative, got nu={nu}, ng={ng}, nh={nh}")
        if residual is None:
            residual = ResidualModelAbstract(state, int(ng) + int(nh), nu)
        else:
            if not isinstance(residual, ResidualModelAbstract):
                raise ValueError(f"residual must be a ResidualModelAbstract, got {type(residual).__name__}")
            if nu is not None and int(nu) != residual.nu:
                raise ValueError(f"nu = {nu} does not match residual.nu = {residual.nu}")
            T_const = residual.q_dependent or residual.v_dependent
        self.state = state
        self.residual = residual
        self.nu = residual.nu
        self.ng = int(ng)
        self.nh = int(nh)
        self.T_constraint = bool(T_const)
        self._lb = frozen_copy(np.full(self.ng, -np.inf))
        self._ub = frozen_copy(np.full(self.ng, np.inf))
        self._update_type()

    def _update_type(self) -> None:
        if self.ng and self.nh:
            self.type = ConstraintType.Both
        elif self.ng:
            self.type = ConstraintType.Inequality
        else:
            self.type = ConstraintType.Equality

    @property
    def lb(self) -> np.ndarray:
        """Lower bound of the inequality rows, shape ``(ng,)`` (read-only: :meth:`updateBounds` changes them)."""
        return self._lb

    @property
    def ub(self) -> np.ndarray:
        """Upper bound of the inequality rows, shape ``(ng,)`` (read-only: :meth:`updateBounds` changes them)."""
        return self._ub

    def updateBounds(self, lower: np.ndarray, upper: np.ndarray) -> None:
        """Set the inequality bounds (each of shape ``(ng,)``, ``lower <= upper``)."""
        lower = as_vector(lower, self.ng, "lower", allow_nonfinite=True)
        upper = as_vector(upper, self.ng, "upper", allow_nonfinite=True)
        check_bounds(lower, upper, "lower", "upper")
        self._lb, self._ub = frozen_copy(lower), frozen_copy(upper)
        touch(self)

    def removeBounds(self) -> None:
        """Make the inequality rows unbounded."""
        self._lb = frozen_copy(np.full(self.ng, -np.inf))
        self._ub = frozen_copy(np.full(self.ng, np.inf))
        touch(self)

    def createData(self, data: DataCollectorAbstract | None = None) -> "ConstraintDataAbstract":
        """Allocate the data this constraint writes into (``data`` is the node's data collector)."""
        return ConstraintDataAbstract(self, data)

    def calc(self, data: "ConstraintDataAbstract", x: np.ndarray, u: np.ndarray | None = None) -> None:
        raise NotImplementedError(f"{type(self).__name__}.calc is not implemented")

    def calcDiff(self, data: "ConstraintDataAbstract", x: np.ndarray, u: np.ndarray | None = None) -> None:
        raise NotImplementedError(f"{type(self).__name__}.calcDiff is not implemented")

    def __repr__(self) -> str:
        inner = (
            f"(ng={self.ng}, nh={self.nh})"
            if type(self.residual) is ResidualModelAbstract
            else f"{{{type(self.residual).__name__}}}"
        )
        return f"{type(self).__name__} {inner}"


def _positional_form(args: tuple, has_residual: bool, has_nu: bool) -> dict:
    """Name the positional arguments after ``state`` by Crocoddyl's constructor forms."""
    if args and isinstance(args[0], ResidualModelAbstract):
        names = ("residual", "ng", "nh")
    elif has_residual:
        names = ("ng", "nh")
    elif not has_nu and (len(args) == 4 or (len(args) == 3 and not isinstance(args[2], (bool, np.bool_)))):
        names = ("nu", "ng", "nh", "T_const")
    else:
        names = ("ng", "nh", "T_const")
    if len(args) > len(names):
        raise TypeError(
            "ConstraintModelAbstract takes (state, residual, ng, nh), (state, nu, ng, nh[, T_const])"
            f" or (state, ng, nh[, T_const]); got {len(args) + 1} positional arguments"
        )
    return dict(zip(names, args))


class ConstraintDataAbstract:
    """Values ``g, h``, Jacobians ``Gx, Gu, Hx, Hu``, the residual data and the ``shared`` collector."""

    def __init__(self, model: ConstraintModelAbstract, data: DataCollectorAbstract | None) -> None:
        ndx, nu = model.state.ndx, model.nu
        self.shared = data
        self.residual = model.residual.createData(data)
        self.g, self.Gx, self.Gu, self.h, self.Hx, self.Hu = constraint_arrays(model.ng, model.nh, ndx, nu)
        tolerate_python_model(model, self, ("g", "Gx", "Gu", "h", "Hx", "Hu"))


class ConstraintDataResidual(ConstraintDataAbstract):
    """Data of :class:`ConstraintModelResidual` (the fields of :class:`ConstraintDataAbstract`)."""


class ConstraintModelResidual(ConstraintModelAbstract):
    """A residual as a constraint (Crocoddyl's ``ConstraintModelResidual``).

    ``ConstraintModelResidual(state, residual, lower, upper, T_constraint=True)`` gives the
    inequality ``lower <= r(x, u) <= upper``; ``ConstraintModelResidual(state, residual,
    T_constraint=True)`` gives the equality ``r(x, u) = 0``.  A residual that reads only ``u``
    is never a terminal constraint.
    """

    def __init__(self, state: StateAbstract, residual: ResidualModelAbstract, *args, T_constraint: bool = True) -> None:
        if not isinstance(residual, ResidualModelAbstract):
            raise ValueError(f"residual must be a ResidualModelAbstract, got {type(residual).__name__}")
        if residual.state.nx != state.nx or residual.state.ndx != state.ndx:
            raise ValueError("residual was built on a state of another dimension than the constraint")
        if len(args) >= 2 and not isinstance(args[0], bool):
            lower, upper = args[0], args[1]
            if len(args) == 3:
                T_constraint = args[2]
            elif len(args) > 3:
                raise ValueError("ConstraintModelResidual takes (state, residual, lower, upper[, T_constraint])")
            super().__init__(state, residual, residual.nr, 0)
            self.updateBounds(lower, upper)
        elif len(args) <= 1:
            if args:
                T_constraint = args[0]
            super().__init__(state, residual, 0, residual.nr)
        else:
            raise ValueError("ConstraintModelResidual takes (state, residual[, T_constraint]) or "
                             "(state, residual, lower, upper[, T_constraint])")
        self.T_constraint = bool(T_constraint) and (residual.q_dependent or residual.v_dependent)

    def createData(self, data: DataCollectorAbstract | None = None) -> ConstraintDataResidual:
        """Allocate the data this constraint writes into (``data`` is the node's data collector)."""
        return ConstraintDataResidual(self, data)

    def calc(self, data: ConstraintDataAbstract, x: np.ndarray, u: np.ndarray | None = None) -> None:
        """Evaluate the residual into ``g`` (inequality) or ``h`` (equality)."""
        self.residual.calc(data.residual, x, u)
        if self.ng:
            data.g[:] = data.residual.r
        else:
            data.h[:] = data.residual.r

    def calcDiff(self, data: ConstraintDataAbstract, x: np.ndarray, u: np.ndarray | None = None) -> None:
        """Copy the residual Jacobians into ``Gx, Gu`` or ``Hx, Hu`` (``Gu``/``Hu`` zero when ``u`` is None)."""
        rdata = data.residual
        self.residual.calcDiff(rdata, x, u)
        Jx, Ju = (data.Gx, data.Gu) if self.ng else (data.Hx, data.Hu)
        Jx[:] = rdata.Rx
        if u is None or not self.residual.u_dependent:
            Ju[:] = 0.0
        else:
            Ju[:] = rdata.Ru
