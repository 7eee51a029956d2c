"""Solver callbacks: called as ``callback(solver)`` at the end of every iteration.

``CallbackVerbose`` prints Crocoddyl's table: an ``iter`` column then, depending on the level,
``cost, merit, stop, |grad|, preg, dreg, step, ||ffeas||, ||gfeas||, ||hfeas||, dV-exp, dV,
dPhi-exp, dPhi``; scientific fields have ``precision`` digits, ``step`` four decimals, and each
header name is centred over its value.  The header is repeated every 10 iterations.  When a solve
stops on NaN/inf it also prints ``solve stopped: <solver.reason>`` (which node, which quantity).
"""

from __future__ import annotations

import copy

from ..enums import VerboseLevel

_COLUMNS_BY_LEVEL = {
    VerboseLevel._0: ("cost", "stop", "|grad|", "preg", "step", "dV-exp", "dV"),
    VerboseLevel._1: ("cost", "merit", "stop", "|grad|", "preg", "step", "||ffeas||", "dV-exp", "dV"),
    VerboseLevel._2: ("cost", "merit", "stop", "|grad|", "preg", "dreg", "step", "||ffeas||", "dV-exp", "dV"),
    VerboseLevel._3: (
        "cost", "merit", "stop", "|grad|", "preg", "dreg", "step",
        "||ffeas||", "||gfeas||", "||hfeas||", "dV-exp", "dV",
    ),
    VerboseLevel._4: (
        "cost", "merit", "stop", "|grad|", "preg", "dreg", "step",
        "||ffeas||", "||gfeas||", "||hfeas||", "dV-exp", "dV", "dPhi-exp", "dPhi",
    ),
}

_SOLVER_VALUE = {
    "cost": lambda s: s.cost,
    "merit": lambda s: s.merit,
    "stop": lambda s: s.stop,
    "|grad|": lambda s: abs(s.d[0]),
    "preg": lambda s: s.preg,
    "dreg": lambda s: s.dreg,
    "step": lambda s: s.stepLength,
    "||ffeas||": lambda s: s.ffeas,
    "||gfeas||": lambda s: s.gfeas,
    "||hfeas||": lambda s: s.hfeas,
    "dV-exp": lambda s: s.dVexp,
    "dV": lambda s: s.dV,
    "dPhi-exp": lambda s: s.dPhiexp,
    "dPhi": lambda s: s.dPhi,
}


class CallbackAbstract:
    """Base class of solver callbacks."""

    def __call__(self, solver) -> None:
        raise NotImplementedError

    def copy(self) -> "CallbackAbstract":
        return copy.copy(self)


class CallbackVerbose(CallbackAbstract):
    """Print one line per iteration (Crocoddyl's ``CallbackVerbose(level=VerboseLevel._4, precision=3)``)."""

    def __init__(self, level: VerboseLevel = VerboseLevel._4, precision: int = 3) -> None:
        self.level = level
        self.precision = precision

    @property
    def level(self) -> VerboseLevel:
        return self._level

    @level.setter
    def level(self, value: VerboseLevel) -> None:
        try:
            self._level = VerboseLevel(value)
        except ValueError as exc:
            raise ValueError(f"level must be a VerboseLevel (_0 to _4), got {value!r}") from exc

    @property
    def precision(self) -> int:
        return self._precision

    @precision.setter
    def precision(self, value: int) -> None:
        if int(value) < 0:
            raise ValueError(f"precision must be non-negative, got {value}")
        self._precision = int(value)

    def _value_width(self, name: str) -> int:
        return 6 if name == "step" else self._precision + 6

    def header(self) -> str:
        """The header line for the current level and precision."""
        out, field_start = "iter", 4
        for name in _COLUMNS_BY_LEVEL[self._level]:
            width = self._value_width(name)
            value_start = field_start + 2
            start = value_start + (width - len(name)) // 2
            out += " " * max(start - len(out), 1) + name
            field_start += width + 2
        return out

    def line(self, solver) -> str:
        """The table row of ``solver``'s current iteration."""
        out = f"{solver.iter:4d}"
        p = self._precision
        for name in _COLUMNS_BY_LEVEL[self._level]:
            value = _SOLVER_VALUE[name](solver)
            if name == "step":
                out += f" {value:7.4f}"
            else:
                out += f" {value:{p + 7}.{p}e}"
        return out

    def __call__(self, solver) -> None:
        if solver.iter % 10 == 0:
            print(self.header())
        print(self.line(solver), flush=True)

    def stopped(self, solver) -> None:
        """Print why ``solver`` stopped on NaN/inf (``solver.reason``); the solver calls it then (crocopy extension)."""
        print(f"solve stopped: {solver.reason}", flush=True)


class CallbackLogger(CallbackAbstract):
    """Record the solver's iterates and figures (Crocoddyl's ``CallbackLogger``).

    Attributes are lists with one entry per iteration: ``iters, costs, pregs, dregs, steps,
    stops, grads, ffeass, hfeass, fs`` (the gaps); ``xs``/``us`` hold the last iterate.
    """

    def __init__(self) -> None:
        self.xs: list = []
        self.us: list = []
        self.fs: list = []
        self.iters: list[int] = []
        self.costs: list[float] = []
        self.pregs: list[float] = []
        self.dregs: list[float] = []
        self.steps: list[float] = []
        self.stops: list[float] = []
        self.grads: list[float] = []
        self.ffeass: list[float] = []
        self.hfeass: list[float] = []

    def __call__(self, solver) -> None:
        self.xs = [x.copy() for x in solver.xs]
        self.us = [u.copy() for u in solver.us]
        self.fs.append([f.copy() for f in solver.fs])
        self.iters.append(solver.iter)
        self.costs.append(solver.cost)
        self.pregs.append(solver.preg)
        self.dregs.append(solver.dreg)
        self.steps.append(solver.stepLength)
        self.stops.append(solver.stop)
        self.grads.append(abs(solver.d[0]))
        self.ffeass.append(solver.ffeas)
        self.hfeass.append(solver.hfeas)
