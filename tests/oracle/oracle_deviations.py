"""Where crocopy's numbers differ from Crocoddyl's on purpose, and how the suite accepts a difference.

Each :class:`Deviation` names one behaviour (documented in docs/crocoddyl_deviations.md), says on
which oracle cases it shows, and of which sort it is:

- ``derivative``: Crocoddyl's Jacobian disagrees with the numerical derivative of Crocoddyl's own
  values.  The node test proves it on every case where it shows (:func:`prove`).
- ``value``: Crocoddyl's value ignores the state (or part of it); proven in test_oracle_deviations.
- ``activation``: Crocoddyl's ``Arr`` is not the derivative of its own ``Ar``; proven in
  test_oracle_activations.
- ``terminal``: a choice for the terminal node (no control), measured in test_oracle_deviations.
- ``gap``: crocopy does not yet reproduce a Crocoddyl behaviour (to be fixed, not a deviation).
"""

from __future__ import annotations

import dataclasses
import re
from collections.abc import Callable

import numpy as np
import oracle_models as om

#: relative tolerance of "equal to Crocoddyl"
TOL = 1e-10
#: a library's Jacobian agrees with its numerical derivative within this (relative, central differences)
ND_TOL = 1e-6
#: Crocoddyl is proven off when its error against its own numerical derivative exceeds TOL and
#: PROOF_FACTOR times crocopy's error against crocopy's (the two libraries' values being equal, their
#: numerical derivatives are the same to that accuracy)
PROOF_FACTOR = 4.0


@dataclasses.dataclass(frozen=True)
class Case:
    """One oracle node: dynamics kind, residual, integrator (None for impulses) and node type."""

    kind: str
    residual: str
    integrator: str | None
    terminal: bool

    @property
    def id(self) -> str:
        node = "terminal" if self.terminal else "running"
        return f"{self.kind}-{self.residual}-{self.integrator or 'impulse'}-{node}"


@dataclasses.dataclass(frozen=True)
class Deviation:
    name: str
    sort: str
    summary: str
    applies: Callable[[Case], bool]
    activations: tuple[str, ...] = ()


def _impulse(case: Case) -> bool:
    return om.DYNAMICS[case.kind].impulse


DEVIATIONS: tuple[Deviation, ...] = (
    Deviation("frame-velocity-lwa", "derivative",
              "ResidualModelFrameVelocity in LOCAL_WORLD_ALIGNED: Crocoddyl's Rx misses the rotation of the "
              "world-aligned frame",
              lambda c: c.residual == "frame_velocity_lwa"),
    Deviation("centroidal-momentum-jacobian", "derivative",
              "ResidualModelCentroidalMomentum: Crocoddyl's Rx is not the derivative of its momentum",
              lambda c: c.residual == "centroidal"),
    Deviation("impulse-frame-velocity", "derivative",
              "ResidualModelFrameVelocity under impulse dynamics: Crocoddyl's Rx is not the derivative of its "
              "(correct) value",
              lambda c: _impulse(c) and c.residual.startswith("frame_velocity")),
    Deviation("impulse-restitution", "derivative",
              "ActionModelImpulseFwdDynamics with r_coeff > 0: Crocoddyl's Fx (and the impulse Jacobians the "
              "force residuals read) drop the restitution term",
              lambda c: _impulse(c) and om.DYNAMICS[c.kind].r_coeff > 0.0),
    Deviation("runge-kutta-jacobians", "derivative",
              "IntegratedActionModelRK: Crocoddyl's Fx (and, for RK3, Lx) are approximations of the derivative of "
              "its own xnext and cost",
              lambda c: (c.integrator or "").startswith("rk") and not c.terminal),
    Deviation("com-free-dynamics", "value",
              "ResidualModelCoMPosition under free dynamics: Crocoddyl never computes the centre of mass and "
              "returns -cref with a zero Jacobian",
              lambda c: c.residual == "com" and c.kind == om.FREE and not c.terminal),
    Deviation("centroidal-free-dynamics", "value",
              "ResidualModelCentroidalMomentum under free dynamics: Crocoddyl never computes the momentum and "
              "returns -href",
              lambda c: c.residual == "centroidal" and c.kind == om.FREE and not c.terminal),
    Deviation("contact-control-grav-forces", "value",
              "ResidualModelContactControlGrav: Crocoddyl computes u - g(q) and leaves out the contact forces its "
              "documentation includes, u - (g(q) - Σ Jcᵀ f)",
              lambda c: c.residual == "contact_control_grav" and not c.terminal),
    Deviation("activation-hessians", "activation",
              "Smooth1Norm, Smooth2Norm, 2NormBarrier(true_hessian=True), WeightedQuadraticBarrier: Crocoddyl's "
              "Arr is not the derivative of its Ar",
              lambda c: True,
              ("smooth1", "smooth2", "norm_barrier_true_hessian", "weighted_quad_barrier")),
    Deviation("quad-flat-hessian", "activation",
              "QuadFlatExp, QuadFlatLog: Crocoddyl's Arr is neither the Hessian of its value nor its diagonal; "
              "crocopy's is the diagonal of the Hessian (the whole of it with true_hessian=True)",
              lambda c: True, ("quad_flat_exp", "quad_flat_log")),
    Deviation("norm-barrier-gauss-newton", "activation",
              "2NormBarrier(true_hessian=False): Crocoddyl keeps the diagonal of the Gauss-Newton Hessian "
              "∇s∇sᵀ (s = ‖r‖ - alpha); crocopy the whole of it",
              lambda c: True, ("norm_barrier",)),
    Deviation("terminal-joint-effort", "terminal",
              "ResidualModelJointEffort on a terminal node: Crocoddyl reads the joint efforts its data last held "
              "(-uref on fresh data); crocopy's residual is 0 (no control, no effort)",
              lambda c: c.terminal and c.residual == "joint_effort"),
    Deviation("terminal-constraint-rows", "gap",
              "On terminal nodes Crocoddyl's g/h and their Jacobians hold only the ng_T/nh_T terminal rows; "
              "crocopy's keep ng/nh rows",
              lambda c: c.terminal),
)

DERIVATIVES = {jac for pair in om.JACOBIANS.values() for jac in pair}
HESSIANS = {"Lxx", "Lxu", "Luu"}
ACTIVATION_KEYS = {"Ar", "Arr"}
_ITEM = re.compile(r"^(.*(?:cost|constraint)\[[^\]]+\]\.)")


def deviations(case: Case, sort: str) -> list[Deviation]:
    return [d for d in DEVIATIONS if d.sort == sort and d.applies(case)]


def item_of(key: str) -> str:
    """``"differential[0].cost[quad].residual.Rx"`` → ``"differential[0].cost[quad]."`` ("" outside items)."""
    match = _ITEM.match(key)
    return match.group(1) if match else ""


def activation_of(key: str) -> str | None:
    match = re.search(r"cost\[([^\]]+)\]", key)
    return match.group(1) if match else None


def relative_error(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.abs(a - b).max() / max(1.0, np.abs(b).max())) if b.size else 0.0


@dataclasses.dataclass
class Proof:
    """Jacobian ``key``: each library's relative error against the numerical derivative of its own value."""

    key: str
    crocopy: float
    crocoddyl: float | None

    @property
    def crocopy_right(self) -> bool:
        return self.crocopy <= ND_TOL

    @property
    def crocoddyl_wrong(self) -> bool:
        return self.crocoddyl is not None and self.crocoddyl > max(TOL, PROOF_FACTOR * self.crocopy)


def stage(key: str) -> int:
    """Runge-Kutta stage of a key (0 outside ``differential[i]``)."""
    match = re.match(r"differential\[(\d+)\]\.", key)
    return int(match.group(1)) if match else 0


def first_stage(key: str) -> str:
    """The same key in the first stage (evaluated at the node's own state and control)."""
    return re.sub(r"^differential\[\d+\]\.", "differential[0].", key)


def prove(models: dict[str, object], found: dict[str, dict], case: Case, x, u, keys, costs, crocoddyl_too: bool):
    """For each Jacobian ``key``: the error of each library against central differences of its own values
    (the Crocoddyl side only when ``crocoddyl_too``)."""
    value_keys = sorted({om.value_key(k) for k in keys})
    numeric = {lib: om.numeric_jacobians(models[lib], x, u, value_keys, costs)
               for lib in (("crocopy", "crocoddyl") if crocoddyl_too else ("crocopy",))}
    proofs = []
    for key in keys:
        vk = om.value_key(key)
        errors = {}
        for lib, num in numeric.items():
            analytic, numeric_vk = om.analytic_jacobian(found[lib], vk), num[vk]
            if analytic.shape[1] != numeric_vk.shape[1]:  # a stage's Jacobian in its own control (a
                ndx = models[lib].state.ndx                # parametrization): compare the state columns
                analytic, numeric_vk = analytic[:, :ndx], numeric_vk[:, :ndx]
            errors[lib] = relative_error(analytic, numeric_vk)
        proofs.append(Proof(key, errors["crocopy"], errors.get("crocoddyl")))
    return proofs
