"""What discrete and differential action models share.

Both evaluate at ``(x, u)`` (shapes ``(nx,)``, ``(nu,)``) a cost ``l(x, u)``, a cost residual
``r (nr,)``, inequality constraints ``g_lb <= g(x, u) <= g_ub`` (``ng`` rows on running nodes,
``ng_T`` on terminal ones), equality constraints ``h(x, u) = 0`` (``nh``/``nh_T``) and a dynamics
output with ``nf`` rows and Jacobians ``Fx (nf, ndx)``, ``Fu (nf, nu)``: the next state ``xnext``
(``nf = ndx``) for an action model, the acceleration ``xout`` (``nf = nv``) for a differential one.

:class:`ActionModelBase` holds the constructor (Crocoddyl's ``(state, nu, nr=1, ng=0, nh=0, ng_T=0,
nh_T=0)``), the control bounds and the quasi-static Newton loop; each kind says what "at rest" means
through ``_rest_error``.  :class:`ActionDataBase` allocates the arrays.  :class:`ControlBounds` gives
``u_lb``/``u_ub`` to actuation models as well.
"""

from __future__ import annotations

import numpy as np

from .guards import Guard, Guarded, unchecked
from .state import StateAbstract
from .stored import Stored
from .validation import as_bound, as_count, as_vector, control_arg, data_arg, state_arg, warn_nonfinite
from .versioning import Parametrized


def check_state_and_nu(state: StateAbstract, nu: int) -> int:
    """Validate the ``(state, nu)`` pair every model constructor takes; return ``nu`` as an int.

    Raises
    ------
    ValueError
        If ``state`` is not a :class:`~crocopy.state.StateAbstract` or ``nu`` is negative.
    TypeError
        If ``nu`` is not an integer.
    """
    if not isinstance(state, StateAbstract):
        raise ValueError(f"state must be a StateAbstract, got {type(state).__name__}")
    return as_count(nu, "nu")


def constraint_arrays(ng: int, nh: int, ndx: int, nu: int) -> tuple[np.ndarray, ...]:
    """Zero ``g (ng,)``, ``Gx (ng, ndx)``, ``Gu (ng, nu)``, ``h (nh,)``, ``Hx (nh, ndx)``, ``Hu (nh, nu)``: the
    constraint values and Jacobians of action, constraint and constraint-manager data."""
    return (np.zeros(ng), np.zeros((ng, ndx)), np.zeros((ng, nu)),
            np.zeros(nh), np.zeros((nh, ndx)), np.zeros((nh, nu)))


class ControlBounds:
    """Control bounds ``u_lb``/``u_ub`` (shape ``(nu,)``, default unbounded).

    Each assignment checks the shape and refuses NaN (inf means unbounded).  The order of the pair is
    checked where the bounds are used (``solve``, the box solvers, squashing), not on assignment, so
    that ``u_lb`` and ``u_ub`` can be set one after the other in either order;
    ``inverted_control_limits`` (crocopy extension) tells whether some ``u_lb[i] > u_ub[i]`` now.
    """

    inverted_control_limits = False

    nu: int

    def _init_control_limits(self) -> None:
        self._u_lb = np.full(self.nu, -np.inf)
        self._u_ub = np.full(self.nu, np.inf)

    @property
    def u_lb(self) -> np.ndarray:
        """Lower control bound, shape ``(nu,)``."""
        return self._u_lb

    @u_lb.setter
    def u_lb(self, value: np.ndarray) -> None:
        self._set_control_limits(as_bound(value, self.nu, "u_lb", upper=False), self._u_ub)

    @property
    def u_ub(self) -> np.ndarray:
        """Upper control bound, shape ``(nu,)``."""
        return self._u_ub

    @u_ub.setter
    def u_ub(self, value: np.ndarray) -> None:
        self._set_control_limits(self._u_lb, as_bound(value, self.nu, "u_ub", upper=True))

    def _set_control_limits(self, lb: np.ndarray, ub: np.ndarray) -> None:
        if (lb > ub).any():
            self.inverted_control_limits = True
        else:  # the class default: nothing more per model to copy or pickle
            self.__dict__.pop("inverted_control_limits", None)
        self._u_lb = lb
        self._u_ub = ub


class ControlLimitsMixin(ControlBounds):
    """Control bounds of action and differential models, with ``has_control_limits`` (all bounds finite)."""

    def _init_control_limits(self) -> None:
        super()._init_control_limits()
        self.has_control_limits = False

    def _set_control_limits(self, lb: np.ndarray, ub: np.ndarray) -> None:
        super()._set_control_limits(lb, ub)
        self.has_control_limits = bool(np.all(np.isfinite(lb)) and np.all(np.isfinite(ub)) and self.nu > 0)


def _data(args: list, kwargs: dict) -> object:
    return args[0] if args else kwargs.get("data")


def _after_calc(model: "ActionModelBase", args: list, kwargs: dict) -> None:
    warn_nonfinite(model, _data(args, kwargs), ("cost", "xnext", "xout"))


def _after_calc_diff(model: "ActionModelBase", args: list, kwargs: dict) -> None:
    warn_nonfinite(model, _data(args, kwargs), ("Fx", "Fu", "Lx", "Lu", "Lxx", "Lxu", "Luu"))


def _calc_first(model: "ActionModelBase", args: list, kwargs: dict) -> None:
    """A direct ``calcDiff`` on a data never evaluated (``cost`` still NaN) runs ``calc`` first at the
    same point: derivatives may read what ``calc`` computes (contact dynamics read Pinocchio's KKT data)."""
    data = _data(args, kwargs)
    cost = getattr(data, "cost", 0.0)
    if isinstance(cost, float) and cost != cost:
        with unchecked():
            model.calc(*args, **kwargs)


_ACTION_DATA = data_arg({"Lx": lambda m: (m.state.ndx,), "Lu": lambda m: (m.nu,)})
_ACTION_PARAMS = (("data", _ACTION_DATA), ("x", state_arg), ("u", control_arg))


class ActionModelBase(Parametrized, ControlLimitsMixin, Guarded):
    """Constructor, stubs and quasi-static solve of Crocoddyl's two action-model abstractions.

    The parameters ``(state, nu, nr=1, ng=0, nh=0, ng_T=0, nh_T=0)`` are described by
    :class:`~crocopy.action_base.ActionModelAbstract`; they are stored under the same names.

    Attributes
    ----------
    g_lb, g_ub : numpy.ndarray
        Inequality bounds of running nodes, shape ``(ng,)``, default unbounded.
    u_lb, u_ub : numpy.ndarray
        Control bounds, shape ``(nu,)``, default unbounded (``has_control_limits`` False).

    Notes
    -----
    ``calc``, ``calcDiff`` and ``quasiStatic`` of every subclass check their arguments when a user
    calls them (:mod:`crocopy.guards`): ``data`` from this model, ``x (nx,)``, ``u (nu,)`` or ``None``,
    finite (NaN/inf raise ``ValueError``); a result that is not finite warns
    (:class:`~crocopy.validation.NonFiniteWarning`); a ``calcDiff`` on a data that ``calc`` never
    evaluated runs ``calc`` first.  A solve calls them unchecked.
    """

    _read_only = frozenset(
        {"state", "actuation", "differential", "control", "costs", "contacts", "impulses", "constraints"}
    )

    _guards = {
        "calc": Guard(_ACTION_PARAMS, after=_after_calc),
        "calcDiff": Guard(_ACTION_PARAMS, check=_calc_first, after=_after_calc_diff),
        "quasiStatic": Guard((("data", _ACTION_DATA), ("x", state_arg))),
    }

    def __init__(
        self, state: StateAbstract, nu: int, nr: int = 1, ng: int = 0, nh: int = 0, ng_T: int = 0, nh_T: int = 0
    ) -> None:
        self.nu = check_state_and_nu(state, nu)
        self.state = state
        self.nr = as_count(nr, "nr")
        self._constraint_source = None
        self.ng = as_count(ng, "ng")
        self.nh = as_count(nh, "nh")
        self.ng_T = as_count(ng_T, "ng_T")
        self.nh_T = as_count(nh_T, "nh_T")
        self.g_lb = np.full(self.ng, -np.inf)
        self.g_ub = np.full(self.ng, np.inf)
        self._init_control_limits()

    def _follow_constraints(self, source: object) -> None:
        """Read ``ng, nh, ng_T, nh_T, g_lb, g_ub`` from ``source`` (a ``ConstraintModelManager`` or the
        wrapped model) whenever they are read, so that they follow ``changeConstraintStatus`` and
        ``addConstraint`` as Crocoddyl's models do; a data created afterwards has the new sizes."""
        self._constraint_source = source
        for name in ("_g_lb", "_g_ub"):
            self.__dict__.pop(name, None)

    def _constraint_count(name: str) -> property:  # noqa: N805 (a property factory used in the class body)
        private = "_" + name

        def get(self) -> int:
            source = self._constraint_source
            return getattr(self, private) if source is None else getattr(source, name)

        def set(self, value: int) -> None:
            setattr(self, private, int(value))

        return property(get, set, doc=f"``{name}`` (follows the constraints, if any)")

    def _constraint_bound(name: str) -> property:  # noqa: N805
        private = "_" + name

        def get(self) -> np.ndarray:
            if private in self.__dict__ or self._constraint_source is None:
                return self.__dict__[private]
            return getattr(self._constraint_source, name)

        def set(self, value: np.ndarray) -> None:
            self.__dict__[private] = as_bound(value, None, name, upper=name.endswith("ub")).copy()

        return property(get, set, doc=f"``{name}``, shape ``(ng,)`` (the constraints' unless assigned)")

    ng = _constraint_count("ng")
    nh = _constraint_count("nh")
    ng_T = _constraint_count("ng_T")
    nh_T = _constraint_count("nh_T")
    g_lb = _constraint_bound("g_lb")
    g_ub = _constraint_bound("g_ub")
    del _constraint_count, _constraint_bound

    def calc(self, data: "ActionDataBase", x: np.ndarray, u: np.ndarray | None = None) -> None:
        raise NotImplementedError(f"{type(self).__name__}.calc is not implemented")

    def calcDiff(self, data: "ActionDataBase", x: np.ndarray, u: np.ndarray | None = None) -> None:
        raise NotImplementedError(f"{type(self).__name__}.calcDiff is not implemented")

    def _rest_error(self, data: "ActionDataBase", x: np.ndarray) -> np.ndarray:
        """What is zero when the system rests at ``x`` (rows of ``Fu``), read after ``calc``."""
        raise NotImplementedError

    def quasiStatic(self, data: "ActionDataBase", x: np.ndarray, maxiter: int = 100, tol: float = 1e-9) -> np.ndarray:
        """Control that keeps the system at rest at ``x``.

        Newton iterations ``u ← u - Fu⁺ e(x, u)`` on the rest error ``e`` (``xnext ⊖ x`` for an action
        model, ``xout`` for a differential one), stopped when the step is below ``tol`` (max norm) or
        after ``maxiter`` iterations.

        Returns
        -------
        numpy.ndarray
            Quasi-static control, shape ``(nu,)``.
        """
        x = as_vector(x, self.state.nx, "x")
        u = np.zeros(self.nu)
        if self.nu == 0:
            return u
        for _ in range(maxiter):
            self.calc(data, x, u)
            self.calcDiff(data, x, u)
            du = np.linalg.lstsq(data.Fu, -self._rest_error(data, x), rcond=None)[0]
            u += du
            if np.linalg.norm(du, np.inf) <= tol:
                break
        return u

    def __repr__(self) -> str:
        return f"{type(self).__name__}(nx={self.state.nx}, nu={self.nu})"


class ActionDataBase:
    """Cost ``cost``, residual ``r (nr,)``, dynamics Jacobians ``Fx (nf, ndx)``, ``Fu (nf, nu)``, cost
    derivatives ``Lx, Lu, Lxx, Lxu, Luu`` and constraints ``g, Gx, Gu`` (``max(ng, ng_T)`` rows),
    ``h, Hx, Hu`` (``max(nh, nh_T)`` rows).

    Assigning an array field (``data.Fx = M``) copies into the array made here (:mod:`crocopy.stored`), as
    Crocoddyl's bindings do: the solvers' compiled passes and nodes hold these arrays."""

    r, Fx, Fu, Lx, Lu, Lxx, Lxu, Luu, g, Gx, Gu, h, Hx, Hu = (Stored() for _ in range(14))

    def __init__(self, model: ActionModelBase, nf: int) -> None:
        ndx, nu = model.state.ndx, model.nu
        ng, nh = max(model.ng, model.ng_T), max(model.nh, model.nh_T)
        self.cost = np.nan
        self.r = np.zeros(model.nr)
        self.Fx = np.zeros((nf, ndx))
        self.Fu = np.zeros((nf, nu))
        self.Lx = np.zeros(ndx)
        self.Lu = np.zeros(nu)
        self.Lxx = np.zeros((ndx, ndx))
        self.Lxu = np.zeros((ndx, nu))
        self.Luu = np.zeros((nu, nu))
        self.g, self.Gx, self.Gu, self.h, self.Hx, self.Hu = constraint_arrays(ng, nh, ndx, nu)
