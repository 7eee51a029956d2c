"""Table of the bundled problems: name → builder, description and documented reference results.

Used by the ``crocopy list / solve / table1`` commands and by the tests.  Every builder takes the
library module first (``crocopy`` by default, ``crocoddyl`` for side-by-side runs) and returns
``(problem, xs, us)``.

The reference figures were measured with **Crocoddyl 3.2.1** run as a black box on the very same
problems (same builder, ``lib=crocoddyl``), warm-started with the builder's guess, ``maxiter``
as in :attr:`ProblemSpec.maxiter`, ``isFeasible=False``, default solver settings, one thread.
``iters`` is ``solver.iter`` and ``cost`` is ``solver.cost`` at return; ``converged`` is the
return value of ``solve``.  crocopy's DDP/FDDP reproduce Crocoddyl's iterates; its box solvers
follow the papers where Crocoddyl 3.2 departs from them (``compat_crocoddyl = True`` reproduces
Crocoddyl), so costs must match within :attr:`ProblemSpec.rtol` while iteration counts may
differ by a few, and on long non-convex solves by more.  One reference is not exact: FDDP on the monkey bar (no control
bounds, 180 iterations) ends in another local minimum after round-off-level differences; crocopy
reaches 8339.10 in 119 iterations there, below Crocoddyl's 10569.26.

``TABLE1`` lists the rows of the Box-FDDP paper's Table I (its own figures are in
:data:`PAPER_TABLE1`); the paper used different robots' tunings, weights and horizons, so only
the trend compares: Box-FDDP solves every row, Box-DDP fails on pend, jump, hop and bar.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from dataclasses import dataclass, field
from types import ModuleType

from . import arm, humanoid, pendulum, quadruped, user_residual

SUCCESS_FACTOR = 10.0
"""A converged run counts as a solution when its cost is within this factor of Box-FDDP's."""


@dataclass(frozen=True)
class Reference:
    """Result of one solver on one problem (Crocoddyl 3.2.1, black box)."""

    iters: int
    cost: float
    converged: bool = True
    exact: bool = True
    """False where round-off steers the iterates to another local minimum (crocopy must then
    reach a cost no higher than this one)."""


@dataclass(frozen=True)
class ProblemSpec:
    """A bundled problem.

    Attributes
    ----------
    name : str
        Registry key (Table I names where the paper has the problem).
    builder : callable
        ``builder(lib, **kwargs) -> (problem, xs, us)``.
    kwargs : dict
        Arguments passed to the builder by :meth:`build`.
    description : str
        One line for ``crocopy list``.
    dims : tuple of int
        ``(T, nx, nu)`` of the built problem (nu of the first running node).
    reference : dict
        Solver name (``"fddp"``, ``"boxfddp"``, ``"boxddp"``) → :class:`Reference`.
    maxiter : int
        Iteration budget used for the references.
    rtol : float
        Relative tolerance on the final cost when comparing with the reference.
    slow : bool
        Solving takes more than a few seconds with crocopy.
    """

    name: str
    builder: Callable[..., tuple]
    kwargs: dict = field(default_factory=dict)
    description: str = ""
    dims: tuple[int, int, int] = (0, 0, 0)
    reference: dict[str, Reference] = field(default_factory=dict)
    maxiter: int = 500
    rtol: float = 1e-3
    slow: bool = True

    def solved(self, converged: bool, cost: float) -> bool:
        """Whether a solve found a solution: it converged and its cost is at most
        :data:`SUCCESS_FACTOR` times the documented Box-FDDP cost (a run can meet the stopping
        test in a useless local minimum: Box-DDP on the hop stops at 1.75e6 vs 5148)."""
        ref = self.reference.get("boxfddp")
        return bool(converged) and (ref is None or cost <= SUCCESS_FACTOR * ref.cost)

    def build(self, lib: ModuleType | None = None, **overrides: object) -> tuple:
        """Build the problem with ``lib`` (default ``crocopy``); ``overrides`` update ``kwargs``."""
        if lib is None:
            lib = importlib.import_module("crocopy")
        return self.builder(lib, **{**self.kwargs, **overrides})


def _spec(name: str, builder: Callable[..., tuple], description: str, dims: tuple[int, int, int],
          reference: dict[str, Reference], slow: bool = True, maxiter: int = 500, **kwargs: object) -> ProblemSpec:
    return ProblemSpec(name, builder, dict(kwargs), description, dims, reference, maxiter, 1e-3, slow)


R = Reference
_SPECS = [
    _spec("pend", pendulum.build_pendulum, "double pendulum swing-up, elbow actuated, ±5 N m, 1 s / 100 nodes",
          (100, 4, 1), {"fddp": R(110, 0.111367), "boxfddp": R(92, 0.111455), "boxddp": R(500, 3.5608, False)},
          slow=False),
    _spec("arm", arm.build_arm_reaching, "Kinova arm reaching a point in 1 s (100 nodes)",
          (100, 15, 6), {"fddp": R(13, 5.74301), "boxfddp": R(14, 5.74302), "boxddp": R(46, 7.87886)}, slow=False),
    _spec("reach", user_residual.build_user_reach,
          "Talos arm reaching a point in 1 s (100 nodes), its goal a user's residual (ResidualModelNumba)",
          (100, 14, 7), {"fddp": R(55, 186.988338), "boxfddp": R(131, 115.953970), "boxddp": R(131, 115.953970)},
          slow=False),
    _spec("man", humanoid.build_manipulation, "Talos whole-body manipulation, right hand to a target",
          (60, 77, 32), {"fddp": R(23, 381.07740), "boxfddp": R(46, 381.75535), "boxddp": R(112, 381.75517)}),
    _spec("taichi", humanoid.build_taichi, "Talos taichi: manipulation, one foot, balance (3 phases)",
          (120, 77, 32), {"fddp": R(21, 810.68472), "boxfddp": R(14, 811.22359), "boxddp": R(80, 811.22359)}),
    _spec("jump", quadruped.build_jump,
          "ANYmal jump (base apex 22 cm asked; Box-FDDP reaches base +23 cm, CoM +21 cm, feet under the body),"
          " 32 N m / 7.5 rad/s, 0-300/300-700/700-1000 ms",
          (101, 37, 12),
          {"fddp": R(410, 5476.47975), "boxfddp": R(465, 7069.18086), "boxddp": R(7, 2.90985341e18, False)},
          maxiter=800),
    _spec("hop", quadruped.build_hop, "ANYmal two-leg hopping, 10 hops with a leg switch, 5.8 s / 580 nodes",
          (592, 37, 12), {"fddp": R(10, 4974.6918), "boxfddp": R(168, 5147.8078), "boxddp": R(404, 1.754609e6)}),
    _spec("bar", humanoid.build_monkey_bar, "Talos monkey bar: grasp, climb, land (arm torques x10)",
          (112, 77, 32),
          {"fddp": R(180, 10569.256, exact=False), "boxfddp": R(331, 10978.1), "boxddp": R(17, 9.63317e6, False)}),
    _spec("walk", quadruped.build_gait, "ANYmal walking, 2 cycles", (226, 37, 12),
          {"fddp": R(18, 1213.4269), "boxfddp": R(12, 1215.3013), "boxddp": R(12, 1215.3013)}, gait="walk"),
    _spec("trot", quadruped.build_gait, "ANYmal trotting, 2 cycles", (114, 37, 12),
          {"fddp": R(11, 1232.2010), "boxfddp": R(15, 1234.2793), "boxddp": R(15, 1234.2793)}, gait="trot"),
    _spec("pace", quadruped.build_gait, "ANYmal pacing, 2 cycles", (114, 37, 12),
          {"fddp": R(13, 1581.5243), "boxfddp": R(14, 1599.9556), "boxddp": R(14, 1599.9556)}, gait="pace"),
    _spec("bound", quadruped.build_gait, "ANYmal bounding, 2 cycles", (114, 37, 12),
          {"fddp": R(25, 2844.8753), "boxfddp": R(64, 2912.0540), "boxddp": R(64, 2912.0540)}, gait="bound"),
    _spec("biped-walk", humanoid.build_biped_walk, "Talos legs walking, 4 steps", (129, 37, 12),
          {"fddp": R(32, 2111.0519), "boxfddp": R(28, 2111.0519), "boxddp": R(28, 2111.0519)}),
    _spec("trot-short", quadruped.build_gait, "ANYmal trotting, 1 short cycle (quick test problem)", (28, 37, 12),
          {"fddp": R(16, 1385.7154), "boxfddp": R(22, 1437.6938), "boxddp": R(22, 1437.6938)},
          slow=False, gait="trot", cycles=1, step_knots=10, support_knots=2),
]

PROBLEMS: dict[str, ProblemSpec] = {s.name: s for s in _SPECS}
"""Every bundled problem by name (quadrotor problems are added when :mod:`.quadrotor` exists)."""

_QUADROTOR = {
    "quad-goal": ("goal", 50, "iris quadrotor to the goal (3, 0, 1), thrusts 0.1-10.3 N, cold start",
                  {"fddp": R(47, 0.0215018), "boxfddp": R(28, 0.0307787, exact=False), "boxddp": R(72, 0.0420025)}),
    "quad-loop": ("loop", 100, "iris quadrotor closed vertical loop from the start, thrusts 0.1-10.3 N, cold start",
                  {"fddp": R(27, 0.0229817), "boxfddp": R(132, 0.204852), "boxddp": R(500, 22.0924, False)}),
    "quad-narrow": ("narrow", 60, "iris quadrotor through a narrow passage, thrusts 0.1-10.3 N, cold start",
                    {"fddp": R(33, 0.0156986), "boxfddp": R(69, 0.036865, exact=False),
                     "boxddp": R(500, 0.584226, False)}),
}
"""Quadrotor rows: task, T, description and Crocoddyl 3.2.1's figures.  crocopy's Box-FDDP follows
the paper and ends lower than Crocoddyl's on goal (0.0307088) and narrow (0.0352124), hence
``exact=False`` there."""


def _register_quadrotor() -> None:
    """Add the quadrotor problems of :mod:`.quadrotor` (``build_quadrotor(lib, task=...)``)."""
    try:
        module = importlib.import_module(".quadrotor", __package__)
    except ImportError:
        return
    builder = getattr(module, "build_quadrotor", None)
    if builder is None:
        return
    for name, (task, T, description, ref) in _QUADROTOR.items():
        PROBLEMS[name] = ProblemSpec(name, builder, {"task": task}, description, (T, 13, 4), ref, 500, 1e-3, False)


_register_quadrotor()

TABLE1 = ("pend", "quad-goal", "quad-loop", "quad-narrow", "man", "taichi", "jump", "hop", "bar")
"""Rows of the Box-FDDP paper's Table I, in its order."""

PAPER_TABLE1: dict[str, dict[str, tuple[int, float, bool]]] = {
    "pend": {"boxddp": (424, 0.223, False), "boxfddp": (31, 0.0273, True)},
    "quad-goal": {"boxddp": (23, 0.0764, True), "boxfddp": (18, 0.0072, True)},
    "quad-loop": {"boxddp": (133, 6.7211, True), "boxfddp": (56, 0.6444, True)},
    "quad-narrow": {"boxddp": (70, 1.9492, True), "boxfddp": (35, 0.4577, True)},
    "man": {"boxddp": (88, 4.6193, True), "boxfddp": (80, 4.6193, True)},
    "taichi": {"boxddp": (148, 6.8184, True), "boxfddp": (141, 6.8184, True)},
    "jump": {"boxddp": (646, 7.21e4, False), "boxfddp": (454, 1.81e4, True)},
    "hop": {"boxddp": (18, 1.13e6, False), "boxfddp": (205, 2.23e4, True)},
    "bar": {"boxddp": (27, 927.7, False), "boxfddp": (358, 23.316, True)},
}
"""Box-FDDP paper, Table I: ``(iterations, cost, solved)`` per solver."""


def names() -> list[str]:
    """Registered problem names."""
    return list(PROBLEMS)


def get(name: str) -> ProblemSpec:
    """The :class:`ProblemSpec` called ``name`` (``KeyError`` lists the known names)."""
    try:
        return PROBLEMS[name]
    except KeyError:
        raise KeyError(f"unknown problem {name!r}; known problems: {', '.join(PROBLEMS)}") from None


def build(name: str, lib: ModuleType | None = None, **overrides: object) -> tuple:
    """Build problem ``name`` with ``lib`` (default ``crocopy``): ``(problem, xs, us)``."""
    return get(name).build(lib, **overrides)
