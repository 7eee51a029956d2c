"""Oracle: the proof of every declared deviation from Crocoddyl (docs/crocoddyl_deviations.md).

- Jacobians: on a representative node, the two libraries' values are equal, Crocoddyl's Jacobian
  disagrees with the central differences of Crocoddyl's own values and crocopy's agrees with those
  of crocopy's.  (test_oracle_nodes repeats the proof on every node where the difference shows.)
- Values: Crocoddyl's value does not move with the state it should depend on, crocopy's equals the
  quantity computed directly with Pinocchio.
- Terminal nodes: what each library computes for control-dependent residuals, and where the
  totals differ.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

crocoddyl = pytest.importorskip("crocoddyl")

import oracle_deviations as od  # noqa: E402
import oracle_models as om  # noqa: E402

import crocopy  # noqa: E402

COSTS = ("quad",)
LIBS = (crocopy, crocoddyl)


def evaluated(kind: str, residual: str, integrator: str | None, seed: int = 1, terminal: bool = False):
    models = {lib.__name__: om.node(lib, kind, residual, integrator, COSTS) for lib in LIBS}
    x, u = om.sample(kind, models["crocopy"].nu, seed)
    u = None if terminal else u
    found = {name: om.evaluate(model, x, u, COSTS) for name, model in models.items()}
    return models, found, x, u


# (deviation, dynamics kind, residual, integrator (None: the differential/impulse model), Jacobian key)
JACOBIAN_PROOFS = [
    ("frame-velocity-lwa", om.FREE, "frame_velocity_lwa", None, "cost[quad].residual.Rx"),
    ("frame-velocity-lwa", om.CONTACT3, "frame_velocity_lwa", None, "cost[quad].residual.Rx"),
    ("centroidal-momentum-jacobian", om.CONTACT3, "centroidal", None, "cost[quad].residual.Rx"),
    ("centroidal-momentum-jacobian", om.IMPULSE3, "centroidal", None, "cost[quad].residual.Rx"),
    ("impulse-frame-velocity", om.IMPULSE3, "frame_velocity_local", None, "cost[quad].residual.Rx"),
    ("impulse-frame-velocity", om.IMPULSE3, "frame_velocity_world", None, "cost[quad].residual.Rx"),
    ("impulse-restitution", om.IMPULSE6, "state", None, "Fx"),
    ("impulse-restitution", om.IMPULSE6, "contact_force", None, "cost[quad].residual.Rx"),
    ("runge-kutta-jacobians", om.FREE, "state", "rk2", "Fx"),
    ("runge-kutta-jacobians", om.FREE, "state", "rk3", "Fx"),
    ("runge-kutta-jacobians", om.FREE, "state", "rk4", "Fx"),
    ("runge-kutta-jacobians", om.CONTACT3, "state", "rk3", "Lx"),
]


@pytest.mark.parametrize("name,kind,residual,integrator,key", JACOBIAN_PROOFS,
                         ids=[f"{p[0]}-{p[1]}-{p[3] or 'model'}-{p[4]}" for p in JACOBIAN_PROOFS])
def test_crocoddyl_jacobian_disagrees_with_its_own_values(name, kind, residual, integrator, key):
    case = od.Case(kind, residual, integrator, False)
    assert name in {d.name for d in od.deviations(case, "derivative")}
    models, found, x, u = evaluated(kind, residual, integrator)
    value = om.value_key(key)
    assert od.relative_error(found["crocopy"][value], found["crocoddyl"][value]) <= od.TOL, "values differ"
    assert od.relative_error(found["crocopy"][key], found["crocoddyl"][key]) > od.TOL, "Jacobians agree"
    (proof,) = od.prove(models, found, case, x, u, [key], COSTS, crocoddyl_too=True)
    assert proof.crocopy_right, f"crocopy {proof.crocopy:.2e} off its numdiff"
    assert proof.crocoddyl_wrong, f"Crocoddyl only {proof.crocoddyl:.2e} off its numdiff (crocopy {proof.crocopy:.2e})"


def test_frame_velocity_lwa_on_anymal_is_far_off_in_crocoddyl():
    """The figure the issue quotes: Crocoddyl's Rx is ~0.3 off on ANYmal, crocopy's within 1e-7."""
    case = od.Case(om.FREE, "frame_velocity_lwa", None, False)
    models, found, x, u = evaluated(om.FREE, "frame_velocity_lwa", None)
    (proof,) = od.prove(models, found, case, x, u, ["cost[quad].residual.Rx"], COSTS, crocoddyl_too=True)
    assert proof.crocoddyl > 0.1 and proof.crocopy < 1e-7


def _residual_values(kind: str, residual: str, seed: int) -> dict[str, np.ndarray]:
    _, found, _, _ = evaluated(kind, residual, None, seed)
    return {lib: f["cost[quad].residual.r"] for lib, f in found.items()} | {
        lib + ".Rx": f["cost[quad].residual.Rx"] for lib, f in found.items()}


@pytest.mark.parametrize("residual,reference", [("com", "com"), ("centroidal", "centroidal")])
def test_crocoddyl_value_ignores_the_state_under_free_dynamics(residual, reference):
    model = om.robot(om.DYNAMICS[om.FREE].robot)
    spec = om.RESIDUALS[residual]
    ref = spec.build(crocopy, om.context(crocopy, om.FREE)).reference
    for seed in (1, 2):
        got = _residual_values(om.FREE, residual, seed)
        x, _ = om.sample(om.FREE, 12, seed)
        q, v = x[: model.nq], x[model.nq:]
        data = model.createData()
        if reference == "com":
            truth = pin.centerOfMass(model, data, q) - ref
        else:
            truth = pin.computeCentroidalMomentum(model, data, q, v).vector - ref
        np.testing.assert_allclose(got["crocoddyl"], -ref, atol=1e-12)  # the state never enters
        np.testing.assert_allclose(got["crocopy"], truth, atol=1e-10)
        assert np.abs(truth + ref).max() > 1e-2
    if residual == "com":
        assert np.abs(got["crocoddyl.Rx"]).max() == 0.0


def test_crocoddyl_contact_control_grav_leaves_out_the_contact_forces():
    """Documented ``u - (g(q) - Σ Jcᵀ f)``: Crocoddyl computes ``u - g(q)``; crocopy the documented value."""
    models, found, x, u = evaluated(om.CONTACT3, "contact_control_grav", None)
    model = om.robot(om.DYNAMICS[om.CONTACT3].robot)
    q = x[: model.nq]
    tau = np.concatenate([np.zeros(6), u])
    gravity = pin.computeGeneralizedGravity(model, model.createData(), q)
    data = models["crocopy"].createData()
    models["crocopy"].calc(data, x, u)
    static = pin.computeStaticTorque(model, model.createData(), q, data.multibody.contacts.fext)
    np.testing.assert_allclose(found["crocoddyl"]["cost[quad].residual.r"], tau - gravity, atol=1e-9)
    np.testing.assert_allclose(found["crocopy"]["cost[quad].residual.r"], tau - static, atol=1e-9)
    assert np.abs(static - gravity).max() > 1.0  # the forces matter


def _terminal_residual(lib, kind: str, residual: str, after_running: bool) -> np.ndarray:
    model = om.node(lib, kind, residual, "euler", COSTS)
    x, u = om.sample(kind, model.nu, 1)
    data = model.createData()
    if after_running:
        model.calc(data, x, u)
    model.calc(data, x)
    return np.array(data.differential.costs.costs["quad"].residual.r, copy=True)


#: control-dependent residuals on a terminal node: crocopy's value, Crocoddyl's on fresh data
TERMINAL = [("control", "zero", "zero"), ("joint_effort", "zero", "-uref"), ("joint_effort_fwddyn", "zero", "zero"),
            ("joint_acceleration", "zero", "zero"), ("contact_force", "zero", "zero"),
            ("friction_cone", "zero", "zero"), ("contact_control_grav", "-g", "-g")]


@pytest.mark.parametrize("residual,mine,theirs", TERMINAL, ids=[t[0] for t in TERMINAL])
def test_terminal_control_dependent_residuals(residual, mine, theirs):
    kind = om.CONTACT3
    spec = om.RESIDUALS[residual]
    c = om.context(crocopy, kind)
    model = om.robot(om.DYNAMICS[kind].robot)
    x, _ = om.sample(kind, 12, 1)
    expected = {"zero": np.zeros(spec.build(crocopy, c).nr),
                "-g": -pin.computeGeneralizedGravity(model, model.createData(), x[: model.nq])}
    if theirs == "-uref":
        expected["-uref"] = -spec.build(crocopy, c).reference
    fresh = {lib.__name__: _terminal_residual(lib, kind, residual, False) for lib in LIBS}
    np.testing.assert_allclose(fresh["crocopy"], expected[mine], atol=1e-9)
    np.testing.assert_allclose(fresh["crocoddyl"], expected[theirs], atol=1e-9)
    # crocopy never reads an earlier evaluation's control, forces or efforts
    np.testing.assert_allclose(_terminal_residual(crocopy, kind, residual, True), fresh["crocopy"], atol=1e-12)


def test_terminal_totals_differ_by_the_joint_effort_cost_only():
    """A terminal node holding every control-dependent residual as a cost: the totals differ by
    Crocoddyl's ``½‖uref‖²`` of the joint-effort residual and nothing else."""
    kind = om.CONTACT3
    totals = {}
    for lib in LIBS:
        c = om.context(lib, kind)
        costs = lib.CostModelSum(c.state, c.nu)
        for name, *_ in TERMINAL:
            costs.addCost(name, lib.CostModelResidual(c.state, om.RESIDUALS[name].build(lib, c)), 1.0)
        dam = om.dynamics(lib, kind, c, costs, None)
        node = lib.IntegratedActionModelEuler(dam, om.DT)
        x, _ = om.sample(kind, c.nu, 1)
        data = node.createData()
        node.calc(data, x)
        totals[lib.__name__] = data.cost
    uref = om.RESIDUALS["joint_effort"].build(crocopy, om.context(crocopy, kind)).reference
    assert totals["crocoddyl"] - totals["crocopy"] == pytest.approx(0.5 * uref @ uref, rel=1e-10)
