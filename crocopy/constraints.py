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
from dataclasses import dataclass

import numpy as np

from .data_collector import DataCollectorAbstract
from .named_items import NamedItems
from .residual_base import ResidualModelAbstract
from .state import StateAbstract
from .validation import as_vector, check_bounds


class ConstraintType(enum.IntEnum):
    """Kind of rows a constraint holds."""

    Inequality = 0
    Equality = 1
    Both = 2


class ConstraintModelAbstract:
    """Abstract constraint (Crocoddyl's ``ConstraintModelAbstract``).

    Constructed as ``(state, residual, ng, nh)``, ``(state, nu, ng, nh, T_const=True)`` or
    ``(state, ng, nh, T_const=True)`` (then ``nu = state.nv``).
    """

    def __init__(self, state: StateAbstract, *args, T_const: bool = True) -> None:
        if not isinstance(state, StateAbstract):
            raise ValueError(f"state must be a StateAbstract, got {type(state).__name__}")
        self.state = state
        self.residual: ResidualModelAbstract | None = None
        if args and isinstance(args[0], ResidualModelAbstract):
            if len(args) != 3:
                raise ValueError("ConstraintModelAbstract(state, residual, ng, nh) takes exactly ng and nh")
            self.residual, ng, nh = args
            self.nu = self.residual.nu
            T_const = True
        elif len(args) in (3, 4):
            nu, ng, nh = args[:3]
            if len(args) == 4:
                T_const = args[3]
            self.nu = int(nu)
        elif len(args) in (2,):
            ng, nh = args
            self.nu = state.nv
        else:
            raise ValueError("ConstraintModelAbstract takes (state, residual, ng, nh), (state, nu, ng, nh[, T_const])"
                             " or (state, ng, nh[, T_const])")
        if int(ng) < 0 or int(nh) < 0:
            raise ValueError(f"ng and nh must be non-negative, got ng={ng}, nh={nh}")
        self.ng = int(ng)
        self.nh = int(nh)
        self.T_constraint = bool(T_const)
        self._lb = np.full(self.ng, -np.inf)
        self._ub = np.full(self.ng, np.inf)
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
        """Lower bound of the inequality rows, shape ``(ng,)``."""
        return self._lb

    @property
    def ub(self) -> np.ndarray:
        """Upper bound of the inequality rows, shape ``(ng,)``."""
        return self._ub

    def updateBounds(self, lower: np.ndarray, upper: np.ndarray) -> None:
        """Set the inequality bounds (each of shape ``(ng,)``, ``lower <= upper``)."""
        lower = as_vector(lower, self.ng, "lower", allow_nonfinite=True)
        upper = as_vector(upper, self.ng, "upper", allow_nonfinite=True)
        check_bounds(lower, upper, "lower", "upper")
        self._lb, self._ub = lower.copy(), upper.copy()

    def removeBounds(self) -> None:
        """Make the inequality rows unbounded."""
        self._lb = np.full(self.ng, -np.inf)
        self._ub = np.full(self.ng, np.inf)

    def createData(self, data: DataCollectorAbstract | None = None) -> "ConstraintDataAbstract":
        """Allocate the data this constraint writes into (``data`` is the node's data collector)."""
        return ConstraintDataAbstract(self, data)

    def calc(self, data: "ConstraintDataAbstract", x: np.ndarray, u: np.ndarray | None = None) -> None:
        raise NotImplementedError(f"{type(self).__name__}.calc is not implemented")

    def calcDiff(self, data: "ConstraintDataAbstract", x: np.ndarray, u: np.ndarray | None = None) -> None:
        raise NotImplementedError(f"{type(self).__name__}.calcDiff is not implemented")

    def __repr__(self) -> str:
        inner = f"{{{type(self.residual).__name__}}}" if self.residual is not None else f"(ng={self.ng}, nh={self.nh})"
        return f"{type(self).__name__} {inner}"


class ConstraintDataAbstract:
    """Values ``g, h``, Jacobians ``Gx, Gu, Hx, Hu``, the residual data and the ``shared`` collector."""

    def __init__(self, model: ConstraintModelAbstract, data: DataCollectorAbstract | None) -> None:
        ndx, nu = model.state.ndx, model.nu
        self.shared = data
        self.residual = model.residual.createData(data) if model.residual is not None else None
        self.g = np.zeros(model.ng)
        self.Gx = np.zeros((model.ng, ndx))
        self.Gu = np.zeros((model.ng, nu))
        self.h = np.zeros(model.nh)
        self.Hx = np.zeros((model.nh, ndx))
        self.Hu = np.zeros((model.nh, nu))


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


@dataclass
class ConstraintItem:
    """A named constraint in a :class:`ConstraintModelManager`."""

    name: str
    constraint: ConstraintModelAbstract
    active: bool = True

    def __repr__(self) -> str:
        return f"{{{self.constraint!r}}}"


class ConstraintModelManager(NamedItems):
    """Named constraints stacked into one ``g``/``h`` (Crocoddyl's ``ConstraintModelManager``).

    Parameters
    ----------
    state : StateAbstract
        State manifold.
    nu : int, optional
        Control dimension (default ``state.nv``).
    """

    _kind = "constraint"

    def __init__(self, state: StateAbstract, nu: int | None = None) -> None:
        if not isinstance(state, StateAbstract):
            raise ValueError(f"state must be a StateAbstract, got {type(state).__name__}")
        self.state = state
        self.nu = state.nv if nu is None else int(nu)
        if self.nu < 0:
            raise ValueError(f"nu must be non-negative, got {self.nu}")
        self._items: dict[str, ConstraintItem] = {}
        self._recount()

    @property
    def constraints(self) -> dict[str, ConstraintItem]:
        """All items (active or not), ordered by name."""
        return self._items

    def _recount(self) -> None:
        active = [c.constraint for c in self._items.values() if c.active]
        self.ng = sum(c.ng for c in active)
        self.nh = sum(c.nh for c in active)
        self.ng_T = sum(c.ng for c in active if c.T_constraint)
        self.nh_T = sum(c.nh for c in active if c.T_constraint)
        self._running = active
        self._terminal = [c for c in active if c.T_constraint]

    @property
    def g_lb(self) -> np.ndarray:
        """Stacked lower bounds of the active inequality rows, shape ``(ng,)``."""
        parts = [c.lb for c in self._running if c.ng]
        return np.concatenate(parts) if parts else np.zeros(0)

    @property
    def g_ub(self) -> np.ndarray:
        """Stacked upper bounds of the active inequality rows, shape ``(ng,)``."""
        parts = [c.ub for c in self._running if c.ng]
        return np.concatenate(parts) if parts else np.zeros(0)

    def addConstraint(self, name: str, constraint: ConstraintModelAbstract, active: bool = True) -> None:
        """Add ``constraint`` under ``name`` (items are kept ordered by name)."""
        if not isinstance(constraint, ConstraintModelAbstract):
            raise ValueError(f"constraint must be a ConstraintModelAbstract, got {type(constraint).__name__}")
        self._check_new_name(name)
        if constraint.nu != self.nu:
            raise ValueError(f"constraint {name!r} has nu = {constraint.nu}, expected nu = {self.nu}")
        if constraint.state.nx != self.state.nx or constraint.state.ndx != self.state.ndx:
            raise ValueError(f"constraint {name!r} was built on a state of another dimension")
        self._insert(name, ConstraintItem(name, constraint, bool(active)))

    def removeConstraint(self, name: str) -> None:
        """Remove the constraint ``name``."""
        self._remove(name)

    def changeConstraintStatus(self, name: str, active: bool) -> None:
        """Activate or deactivate the constraint ``name``."""
        self._set_active(name, active)

    def getConstraintStatus(self, name: str) -> bool:
        """True if the constraint ``name`` is active."""
        return self._get(name).active

    def createData(self, data: DataCollectorAbstract | None = None) -> "ConstraintDataManager":
        """Allocate one data per item plus the stacked arrays, sized for the current active set."""
        return ConstraintDataManager(self, data)

    def _check(self, data: "ConstraintDataManager") -> None:
        if data.g.shape[0] != self.ng or data.h.shape[0] != self.nh:
            raise ValueError(
                f"constraint data holds ng={data.g.shape[0]}, nh={data.h.shape[0]} but the manager now has "
                f"ng={self.ng}, nh={self.nh}: create the data again after changing the active set"
            )

    def calc(self, data: "ConstraintDataManager", x: np.ndarray, u: np.ndarray | None = None) -> None:
        """Stack the active constraints (only ``T_constraint`` ones when ``u`` is None) into ``g``/``h``."""
        self._check(data)
        ig = ih = 0
        for name, item in self._items.items():
            c = item.constraint
            if not item.active or (u is None and not c.T_constraint):
                continue
            cd = data.constraints[name]
            c.calc(cd, x, u)
            if c.ng:
                data.g[ig:ig + c.ng] = cd.g
                ig += c.ng
            if c.nh:
                data.h[ih:ih + c.nh] = cd.h
                ih += c.nh
        data.g[ig:] = 0.0
        data.h[ih:] = 0.0

    def calcDiff(self, data: "ConstraintDataManager", x: np.ndarray, u: np.ndarray | None = None) -> None:
        """Stack the Jacobians of the active constraints into ``Gx, Gu, Hx, Hu`` (same rows as :meth:`calc`)."""
        self._check(data)
        ig = ih = 0
        for name, item in self._items.items():
            c = item.constraint
            if not item.active or (u is None and not c.T_constraint):
                continue
            cd = data.constraints[name]
            c.calcDiff(cd, x, u)
            if c.ng:
                data.Gx[ig:ig + c.ng] = cd.Gx
                data.Gu[ig:ig + c.ng] = cd.Gu
                ig += c.ng
            if c.nh:
                data.Hx[ih:ih + c.nh] = cd.Hx
                data.Hu[ih:ih + c.nh] = cd.Hu
                ih += c.nh
        for J in (data.Gx, data.Gu):
            J[ig:] = 0.0
        for J in (data.Hx, data.Hu):
            J[ih:] = 0.0

    def __repr__(self) -> str:
        return "ConstraintModelManager(" + ", ".join(f"{n}: {c!r}" for n, c in self._items.items()) + ")"


class ConstraintDataManager:
    """Data of a :class:`ConstraintModelManager`: per-item data in ``constraints`` plus stacked arrays."""

    def __init__(self, model: ConstraintModelManager, data: DataCollectorAbstract | None) -> None:
        ndx, nu = model.state.ndx, model.nu
        self.shared = data
        self.constraints = {name: item.constraint.createData(data) for name, item in model.constraints.items()}
        self.g = np.zeros(model.ng)
        self.Gx = np.zeros((model.ng, ndx))
        self.Gu = np.zeros((model.ng, nu))
        self.h = np.zeros(model.nh)
        self.Hx = np.zeros((model.nh, ndx))
        self.Hu = np.zeros((model.nh, nu))

    def shareMemory(self, data) -> None:
        """Write straight into ``data``'s ``g, Gx, Gu, h, Hx, Hu`` (an action or differential data).

        Raises
        ------
        ValueError
            If ``data``'s arrays do not have this manager data's shapes.
        """
        for name in ("g", "Gx", "Gu", "h", "Hx", "Hu"):
            mine, theirs = getattr(self, name), getattr(data, name)
            if theirs.shape != mine.shape:
                raise ValueError(f"data.{name} has shape {theirs.shape}, expected {mine.shape}")
            setattr(self, name, theirs)
