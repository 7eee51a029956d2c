"""What every solver shares: iterate storage, candidate setting, feasibility, callbacks, divergence.

A solver owns ``xs`` (T+1 states), ``us`` (T controls) and the gaps ``fs`` (T+1 tangent
vectors, ``fs[0] = x0 ⊖ xs[0]``, ``fs[t+1] = f(xs[t], us[t]) ⊖ xs[t+1]``).  ``solve`` returns
True on convergence and False otherwise, with the reason in ``solver.reason``; it never leaves
NaN in ``xs``/``us``: a divergent iterate is never accepted.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Sequence

import numpy as np

from ..enums import FeasibilityNorm
from ..guards import trusted_path
from ..shooting import ShootingProblem
from ..validation import ArgumentTypeError, as_bool, as_count, as_number, check_bounds, finite_stack, plain_vectors
from ..versioning import STRUCTURE
from .std_vector import StdVecAttribute, allocate
from .stopwatch import profiled


class BackwardPassError(RuntimeError):
    """Raised by a backward pass that cannot factorise ``Quu`` (the solver raises the regularisation)."""


class ForwardPassError(RuntimeError):
    """Raised by a forward pass that produced a non-finite state or cost."""


def check_solve_arguments(solver: "SolverAbstract", maxiter: object, is_feasible: object, init_reg: object) -> tuple:
    """``(maxiter, is_feasible, init_reg)`` of ``solve`` checked, and the settings read at the start of a solve.

    ``maxiter`` is an integer >= 0, ``is_feasible`` a bool, ``init_reg`` ``None``, NaN (the default
    regularisation) or a number >= 0.  ``reg_min <= reg_max`` and every running model's ``u_lb <= u_ub``
    are checked here, where they are used, so that their setters may be called in any order.  The problem's datas
    made before a registry in their model changed its item set are replaced first (``problem.refresh_datas()``).

    Raises
    ------
    ValueError, TypeError
        Naming the argument or setting, the expected range and what was given.
    """
    maxiter = as_count(maxiter, "maxiter")
    is_feasible = as_bool(is_feasible, "is_feasible")
    if init_reg is not None and not (isinstance(init_reg, float) and init_reg != init_reg):
        init_reg = as_number(init_reg, "init_reg", minimum=0.0)
    reg_min, reg_max = getattr(solver, "reg_min", None), getattr(solver, "reg_max", None)
    if reg_min is not None and reg_max is not None and reg_min > reg_max:
        raise ValueError(f"reg_min = {reg_min} is above reg_max = {reg_max}")
    solver.problem.refresh_datas()
    for t, m in enumerate(solver.problem.runningModels):
        if getattr(m, "inverted_control_limits", False):
            check_bounds(m.u_lb, m.u_ub, f"runningModels[{t}].u_lb", f"runningModels[{t}].u_ub")
    return maxiter, is_feasible, init_reg


def _checked_solve(solve: Callable) -> Callable:
    """``solve`` with its arguments checked, run on the trusted path (:func:`crocopy.guards.trusted_path`)."""
    @functools.wraps(solve)
    def checked(self, init_xs=None, init_us=None, maxiter=100, is_feasible=False, init_reg=None, **kwargs):
        maxiter, is_feasible, init_reg = check_solve_arguments(self, maxiter, is_feasible, init_reg)
        with trusted_path():
            return solve(self, init_xs, init_us, maxiter, is_feasible, init_reg, **kwargs)

    return checked


class Setting:
    """A solver setting checked on assignment: a number ``>= minimum`` (``> minimum`` if ``strict``; any sign when
    ``minimum`` is None) and ``< maximum`` when given, infinite only if ``allow_inf`` (a bound that may be absent, e.g.
    ``reg_max``)."""

    def __init__(self, minimum: float | None = 0.0, strict: bool = False, allow_inf: bool = True,
                 maximum: float | None = None) -> None:
        self.minimum = minimum
        self.strict = strict
        self.allow_inf = allow_inf
        self.maximum = maximum

    def __set_name__(self, owner: type, name: str) -> None:
        self.name = name

    def __get__(self, obj: object, owner: type | None = None) -> object:
        if obj is None:
            return self
        try:
            return obj.__dict__[self.name]
        except KeyError:
            raise AttributeError(self.name) from None

    def __set__(self, obj: object, value: object) -> None:
        obj.__dict__[self.name] = self.convert(value)

    def convert(self, value: object) -> object:
        """``value`` as the setting holds it; ValueError or TypeError naming the setting."""
        out = as_number(value, self.name, self.minimum, self.strict, allow_inf=self.allow_inf)
        if self.maximum is not None and not out < self.maximum:
            raise ValueError(f"{self.name} must be < {self.maximum}, got {out}")
        return out


class CountSetting(Setting):
    """A solver setting that is an integer ``>= minimum`` (mim-solvers' ``max_qp_iters``, ``filter_size``, ...)."""

    def __init__(self, minimum: int = 0) -> None:
        super().__init__(minimum)

    def convert(self, value: object) -> int:
        return as_count(value, self.name, self.minimum)


class FlagSetting(Setting):
    """A solver setting that is a bool."""

    def convert(self, value: object) -> bool:
        return as_bool(value, self.name)


class ChoiceSetting(Setting):
    """A solver setting that is one of the strings ``choices``."""

    def __init__(self, *choices: str) -> None:
        super().__init__()
        self.choices = choices

    def convert(self, value: object) -> str:
        if value not in self.choices or not isinstance(value, str):
            raise ValueError(f"{self.name} must be one of {self.choices}, got {value!r}")
        return value


class NormSetting(Setting):
    """``feasNorm``: a :class:`~crocopy.enums.FeasibilityNorm` (or its integer value)."""

    def convert(self, value: object) -> FeasibilityNorm:
        if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
            raise ArgumentTypeError(f"{self.name} must be a FeasibilityNorm (LInf, L1), got {type(value).__name__}")
        try:
            return FeasibilityNorm(int(value))
        except ValueError:
            raise ValueError(f"{self.name} must be a FeasibilityNorm (LInf, L1), got {value!r}") from None


def _nx(model) -> int:
    return model.state.nx


def _nu(model) -> int:
    return model.nu


def _same_shape(a: np.ndarray, b: np.ndarray) -> bool:
    return a.shape == b.shape


class SolverAbstract:
    """Base class of the shooting-problem solvers (Crocoddyl's ``SolverAbstract``).

    Parameters
    ----------
    problem : ShootingProblem
        Problem to solve.
    """

    #: State trajectory (T+1 arrays), controls (T arrays), gaps (T+1 arrays) and a trial step's states and
    #: controls, each a :class:`~crocopy.solvers.std_vector.Trajectory`: the solver's own arrays (live, as in
    #: Crocoddyl: copy what you keep), into which an assignment copies.
    xs = StdVecAttribute()
    us = StdVecAttribute()
    fs = StdVecAttribute()
    xs_try = StdVecAttribute()
    us_try = StdVecAttribute()

    #: Methods timed by the profiler (:mod:`crocopy.solvers.stopwatch`) as ``"ClassName::method"``.
    _profiled = ("solve", "computeDirection", "calcDiff", "backwardPass", "tryStep", "forwardPass")

    #: Settings checked on assignment (``ValueError`` naming the setting); the pairs whose order
    #: matters (``reg_min <= reg_max``) are checked when ``solve`` starts.
    reg_min = Setting(allow_inf=False)
    reg_max = Setting()
    reg_incFactor = Setting(1.0, allow_inf=False)
    reg_decFactor = Setting(1.0, allow_inf=False)
    th_stop = Setting()
    th_grad = Setting()
    th_gapTol = Setting()
    th_acceptStep = Setting(allow_inf=False)
    th_stepDec = Setting(0.0, strict=True)
    th_stepInc = Setting(0.0, strict=True)
    feasNorm = NormSetting()

    def __init_subclass__(cls, **kwargs) -> None:
        super().__init_subclass__(**kwargs)
        if "solve" in cls.__dict__:
            cls.solve = _checked_solve(cls.__dict__["solve"])
        for name in cls._profiled:
            if name in cls.__dict__:
                setattr(cls, name, profiled(f"{cls.__name__}::{name}", cls.__dict__[name]))

    def __init__(self, problem: ShootingProblem) -> None:
        if not isinstance(problem, ShootingProblem):
            raise ValueError(f"problem must be a ShootingProblem, got {type(problem).__name__}")
        self.problem = problem
        models = [*problem.runningModels, problem.terminalModel]
        self.xs = [m.state.zero() for m in models]
        self.us = [np.zeros(m.nu) for m in problem.runningModels]
        self.fs = [np.zeros(m.state.ndx) for m in models]
        self.isFeasible = False
        self.cost = 0.0
        self.merit = 0.0
        self.stop = 0.0
        self.d = np.zeros(2)
        self.dV = 0.0
        self.dVexp = 0.0
        self.dPhi = 0.0
        self.dPhiexp = 0.0
        self.preg = 0.0
        self.dreg = 0.0
        self.stepLength = 1.0
        self.iter = 0
        self.th_acceptStep = 0.1
        self.th_stop = 1e-9
        self.th_gapTol = 1e-16
        self.feasNorm = FeasibilityNorm.LInf
        self.ffeas = 0.0
        self.gfeas = 0.0
        self.hfeas = 0.0
        self.ffeas_try = 0.0
        self.gfeas_try = 0.0
        self.hfeas_try = 0.0
        self.reason = ""
        self._callbacks: list = []

    def setCallbacks(self, callbacks: Sequence) -> None:
        """Set the callbacks run at the end of every iteration."""
        for c in callbacks:
            if not callable(c):
                raise ValueError(f"callbacks must be callable, got {type(c).__name__}")
        self._callbacks = list(callbacks)

    def getCallbacks(self) -> list:
        return list(self._callbacks)

    def _run_callbacks(self) -> None:
        for c in self._callbacks:
            c(self)

    def setCandidate(
        self, xs: Sequence[np.ndarray] | None = None, us: Sequence[np.ndarray] | None = None, isFeasible: bool = False
    ) -> None:
        """Set the warm start ``(xs, us)``; empty or ``None`` means zero controls and ``state.zero()`` states.

        Raises
        ------
        ValueError
            If ``xs`` does not have T+1 states of shape ``(nx,)`` or ``us`` T controls of shape ``(nu,)``,
            or either contains NaN/inf.
        """
        problem = self.problem
        models = [*problem.runningModels, problem.terminalModel]
        xs = [] if xs is None else list(xs)
        us = [] if us is None else list(us)
        if not us:
            us = [np.zeros(m.nu) for m in problem.runningModels]
        if not xs:
            if isFeasible:
                xs = problem.rollout(us)
            else:
                xs = [m.state.zero() for m in models]
        flats = [self._plain(name, given, [f(m) for m in nodes]) for name, given, nodes, f in
                 (("xs", xs, models, _nx), ("us", us, problem.runningModels, _nu))]
        if flats[0] is not None and flats[1] is not None:
            for name, flat in zip(("xs", "us"), flats):
                start = 0
                for h in self.__dict__[name]:
                    stop = start + h.shape[0]
                    h[:] = flat[start:stop]
                    start = stop
        else:
            xs, us = problem.check_trajectories(xs, us, "init_xs", "init_us")
            self._store("xs", xs)
            self._store("us", us)
        self.isFeasible = bool(isFeasible)

    def _plain(self, name: str, arrays: list, sizes: list[int]) -> np.ndarray | None:
        """``arrays`` stacked (a copy: they may be the solver's own), when they are what the checks let through
        unchanged (float64 vectors of ``sizes``, all finite) and the trajectory ``name`` has entries of those sizes;
        else None (the caller checks them one by one)."""
        held = self.__dict__.get(name)
        shapes = [(n,) for n in sizes]
        if held is None or len(held) != len(arrays) or not plain_vectors(arrays, shapes) or any(
                h.shape != s for h, s in zip(held, shapes)):
            return None
        return finite_stack(arrays)

    def _store(self, name: str, arrays: list[np.ndarray]) -> None:
        """Copy ``arrays`` (checked against the problem) into the trajectory ``name``, or give the solver new
        arrays for it if the problem's dimensions changed since it made them."""
        held = self.__dict__.get(name)
        if held is not None and len(held) == len(arrays) and all(map(_same_shape, held, arrays)):
            held.assign(arrays)
        else:
            allocate(self, name, [np.array(a, dtype=float) for a in arrays])

    def computeDynamicFeasibility(self) -> float:
        """Update the gaps ``fs`` from the nodes' ``xnext`` (after ``problem.calc``) and return their norm."""
        problem = self.problem
        xs = self.xs
        for t, (m, d) in enumerate(zip(problem.runningModels, problem.runningDatas)):
            m.state._diff_into(xs[t + 1], d.xnext, self.fs[t + 1])
        return self._close_gaps()

    def _close_gaps(self) -> float:
        """``fs[0] = x0 ⊖ xs[0]`` and ``ffeas``, the norm of all the gaps (``fs[1:]`` filled by the caller)."""
        problem = self.problem
        if problem.T:
            nodes = getattr(self, "_nodes", None)
            horizon = None if nodes is None else nodes.horizon
            if horizon is None or not horizon.first_gap(self.xs[0], problem.x0, self.fs[0]):
                problem.runningModels[0].state._diff_into(self.xs[0], problem.x0, self.fs[0])
        else:
            self.fs[0][:] = 0.0
        self.ffeas = self._gaps_norm()
        return self.ffeas

    def _gaps_norm(self) -> float:
        """The norm of all the gaps ``fs`` (``feasNorm``)."""
        return self._norm(self.fs)

    def _row_nodes(self) -> tuple[list[int], list[int]]:
        """The nodes whose data has inequality rows ``g`` and those with equality rows ``h`` (indices, the terminal
        node ``T``), found again when the problem, its nodes (node version) or a registry's item set
        (:data:`~crocopy.versioning.STRUCTURE`) changed."""
        problem = self.problem
        key = (id(problem), problem._nodes_version, STRUCTURE[0])
        rows = self.__dict__.get("_row_nodes_seen")
        if rows is None or rows[0] != key:
            datas = [*problem.runningDatas, problem.terminalData]
            rows = self.__dict__["_row_nodes_seen"] = (key, [t for t, d in enumerate(datas) if d.g.size],
                                                       [t for t, d in enumerate(datas) if d.h.size])
        return rows[1], rows[2]

    def _rows(self) -> tuple[list, list]:
        """``(nodes, hs)``: the nodes ``(model, data)`` whose data has inequality rows and the equality rows ``h`` that
        are not empty (:meth:`_row_nodes`)."""
        g_nodes, h_nodes = self._row_nodes()
        if not g_nodes and not h_nodes:
            return [], []
        problem = self.problem
        models, datas, T = problem.runningModels, problem.runningDatas, problem.T
        nodes = [(models[t], datas[t]) if t < T else (problem.terminalModel, problem.terminalData) for t in g_nodes]
        return nodes, [(datas[t] if t < T else problem.terminalData).h for t in h_nodes]

    def computeEqualityFeasibility(self) -> float:
        """Norm of the equality-constraint values ``h`` over all nodes."""
        self.hfeas = self._norm(self._rows()[1]) if self._row_nodes()[1] else 0.0
        return self.hfeas

    def computeInequalityFeasibility(self) -> float:
        """Norm of the inequality-constraint violations ``max(g_lb - g, 0, g - g_ub)`` over all nodes."""
        viol = []
        for m, d in self._rows()[0]:
            if m.ng:
                g = d.g[: m.ng]
                viol.append(np.maximum(np.maximum(m.g_lb - g, 0.0), g - m.g_ub))
        self.gfeas = self._norm(viol)
        return self.gfeas

    def _norm(self, vectors: Sequence[np.ndarray]) -> float:
        if not len(vectors):
            return 0.0
        stacked = np.concatenate(vectors)
        if not stacked.size:
            return 0.0
        if self.feasNorm == FeasibilityNorm.LInf:
            return float(np.abs(stacked).max())
        return float(np.abs(stacked).sum())

    def _check_x0(self) -> None:
        if not np.all(np.isfinite(self.problem.x0)):
            raise ValueError("problem.x0 contains NaN or inf")

    def solve(self, init_xs=None, init_us=None, maxiter: int = 100, is_feasible: bool = False, init_reg=None) -> bool:
        raise NotImplementedError

    def computeDirection(self, recalc: bool = True) -> None:
        raise NotImplementedError

    def tryStep(self, steplength: float = 1.0) -> float:
        raise NotImplementedError

    def stoppingCriteria(self) -> float:
        raise NotImplementedError

    def expectedImprovement(self) -> np.ndarray:
        raise NotImplementedError
