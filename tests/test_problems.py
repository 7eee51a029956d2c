"""Problem builders: they build with crocopy, their first calc/calcDiff is finite, quick ones solve
to their documented (Crocoddyl-measured) cost, and the jump respects its limits."""

from __future__ import annotations

import numpy as np
import pytest

import crocopy
from crocopy.problems import arm, flight, humanoid, pendulum, quadruped, registry

SMALL = {
    "pend": (pendulum.build_pendulum, {"nodes": 10}, (4, 1)),
    "arm": (arm.build_arm_reaching, {"nodes": 10}, (15, 6)),
    "arm-ur5": (arm.build_arm_reaching, {"nodes": 5, "robot": "ur5"}, (12, 6)),
    "walk": (quadruped.build_gait, {"gait": "walk", "cycles": 1, "step_knots": 3, "support_knots": 1}, (37, 12)),
    "trot": (quadruped.build_gait, {"gait": "trot", "cycles": 1, "step_knots": 3, "support_knots": 1}, (37, 12)),
    "pace": (quadruped.build_gait, {"gait": "pace", "cycles": 1, "step_knots": 3, "support_knots": 1}, (37, 12)),
    "bound": (quadruped.build_gait, {"gait": "bound", "cycles": 1, "step_knots": 3, "support_knots": 1}, (37, 12)),
    "trot-solo12": (quadruped.build_gait, {"gait": "trot", "robot": "solo12", "cycles": 1, "step_knots": 3,
                                           "support_knots": 1, "step_length": 0.05, "step_height": 0.03}, (37, 12)),
    "trot-hyq": (quadruped.build_gait, {"gait": "trot", "robot": "hyq", "cycles": 1, "step_knots": 3,
                                        "support_knots": 1}, (37, 12)),
    "jump": (quadruped.build_jump, {"dt": 0.05}, (37, 12)),
    "hop": (quadruped.build_hop, {"hops": 2, "stance_knots": 3, "flight_knots": 2}, (37, 12)),
    "man": (humanoid.build_manipulation, {"nodes": 4}, (77, 32)),
    "taichi": (humanoid.build_taichi, {"phase_knots": 2}, (77, 32)),
    "biped-walk": (humanoid.build_biped_walk, {"steps": 2, "step_knots": 3, "support_knots": 1}, (37, 12)),
    "bar": (humanoid.build_monkey_bar, {"knots": (2, 2, 2, 2)}, (77, 32)),
}


def _perturbed(problem: object, xs: list, us: list, seed: int = 0) -> tuple[list, list]:
    rng = np.random.default_rng(seed)
    state = problem.runningModels[0].state
    xs = [state.integrate(x, 1e-2 * rng.standard_normal(state.ndx)) for x in xs]
    us = [u + 0.1 * rng.standard_normal(len(u)) for u in us]
    return xs, us


@pytest.mark.parametrize("key", sorted(SMALL))
def test_builder_builds_and_first_derivatives_are_finite(key: str) -> None:
    builder, kwargs, (nx, nu) = SMALL[key]
    problem, xs, us = builder(crocopy, **kwargs)
    assert isinstance(problem, crocopy.ShootingProblem)
    assert problem.nx == nx
    assert len(xs) == problem.T + 1 and len(us) == problem.T
    assert max(m.nu for m in problem.runningModels) == nu
    for u, model in zip(us, problem.runningModels, strict=True):
        assert u.shape == (model.nu,)
        if model.nu:
            assert np.all(u >= model.u_lb - 1e-12) and np.all(u <= model.u_ub + 1e-12)
    xs, us = _perturbed(problem, xs, us)
    cost = problem.calc(xs, us)
    problem.calcDiff(xs, us)
    assert np.isfinite(cost) and cost > 0
    for data in list(problem.runningDatas) + [problem.terminalData]:
        for name in ("Lx", "Lxx", "Fx"):
            assert np.all(np.isfinite(getattr(data, name))), name
    for data, model in zip(problem.runningDatas, problem.runningModels, strict=True):
        if model.nu:
            assert np.all(np.isfinite(data.Fu)) and np.all(np.isfinite(data.Luu))


def test_quasi_static_warm_start_keeps_the_robot_still() -> None:
    """The quadruped guess (standing posture, quasi-static torques) is an equilibrium of support nodes."""
    problem, xs, us = quadruped.build_gait(crocopy, gait="trot", cycles=1, step_knots=3, support_knots=1)
    model, data = problem.runningModels[0], problem.runningDatas[0]
    model.calc(data, xs[0], us[0])
    np.testing.assert_allclose(model.state.diff(xs[0], data.xnext), 0.0, atol=1e-8)


def test_jump_limits_match_the_paper() -> None:
    """ANYmal jump: 32 N m control bounds, 7.5 rad/s velocity barrier, phases 300/400/300 ms."""
    problem, _, _ = quadruped.build_jump(crocopy)
    timed = [m for m in problem.runningModels if m.nu]
    assert len(timed) == 100 and problem.T == 101
    assert sum(1 for m in problem.runningModels if m.nu == 0) == 1
    assert problem.runningModels[70].nu == 0
    for m in timed:
        np.testing.assert_allclose(m.u_ub, 32.0)
        np.testing.assert_allclose(m.u_lb, -32.0)
    model, _, _ = quadruped.load_quadruped("anymal", limited=True)
    np.testing.assert_allclose(model.velocityLimit[6:], 7.5)
    np.testing.assert_allclose(model.effortLimit[6:], 32.0)


def _costs(model: object) -> dict:
    return dict(model.differential.costs.costs.items())


def test_jump_flight_asks_for_the_apex_with_the_feet_under_the_body() -> None:
    """The 40 flight nodes (300-700 ms) are free dynamics; the middle one asks the base to be
    JUMP_HEIGHT above standing, every one asks each foot to stay above its standing x/y (height free),
    the flight regularisation leaves the base height free and holds the joints; the impulse lands
    all four feet on their standing spots."""
    problem, xs, _ = quadruped.build_jump(crocopy)
    assert flight.flight_nodes(problem) == list(range(30, 70))
    model = problem.terminalModel.state.pinocchio
    data = model.createData()
    pin = pytest.importorskip("pinocchio")
    pin.framesForwardKinematics(model, data, xs[0][: model.nq])
    feet = quadruped.FEET["anymal"]
    standing = {f: data.oMf[model.getFrameId(f)].translation.copy() for f in feet}
    for k in range(30, 70):
        costs = _costs(problem.runningModels[k])
        assert ("apex" in costs) == (k == 50)
        for f in feet:
            item = costs[f + "_xy"]
            assert item.weight == 1e5
            np.testing.assert_allclose(item.cost.residual.reference, standing[f])
            np.testing.assert_allclose(item.cost.activation.weights, [1.0, 1.0, 0.0])
        weights = costs["state"].cost.activation.weights
        assert weights[2] == 0.0 and np.all(weights[6:18] == quadruped.FLIGHT_JOINT_WEIGHT**2)
    apex = _costs(problem.runningModels[50])["apex"]
    assert apex.cost.residual.reference[2] == pytest.approx(xs[0][2] + quadruped.JUMP_HEIGHT)
    landing = problem.runningModels[70].costs.costs
    for f in feet:
        np.testing.assert_allclose(landing[f + "_landing"].cost.residual.reference, standing[f])
    assert flight.contact_frames(problem) == sorted(model.getFrameId(f) for f in feet)


def test_flight_report_reads_apex_spread_and_landing() -> None:
    """On hand-made trajectories of the jump problem: the standing guess, the base lifted in flight,
    the legs splayed, and a last state off the ground."""
    problem, xs, _ = quadruped.build_jump(crocopy, dt=0.05)
    assert flight.flight_report(quadruped.build_gait(crocopy, gait="trot", cycles=1, step_knots=3,
                                                     support_knots=1)[0], xs) is None  # no free-dynamics node
    still = flight.flight_report(problem, xs)
    assert still.flight_time == pytest.approx(0.4) and still.apex == 0.0
    assert still.spread_ratio == pytest.approx(1.0) and still.landed
    assert still.feet_below_base == pytest.approx(xs[0][2], abs=0.05)
    lifted = [x.copy() for x in xs]
    for k in flight.flight_nodes(problem):
        lifted[k][2] += 0.2
    report = flight.flight_report(problem, lifted)
    assert report.apex == pytest.approx(0.2) and report.spread_ratio == pytest.approx(1.0) and report.landed
    splayed = [x.copy() for x in lifted]
    splayed[8][7:19:3] = [0.5, -0.5, 0.5, -0.5]  # the four hip abduction (HAA) joints turned by 0.5 rad
    assert flight.flight_report(problem, splayed).spread_ratio > 1.3
    lifted[-1][2] += 0.05
    assert not flight.flight_report(problem, lifted).landed


def test_hop_horizon_is_580_nodes_of_10_ms() -> None:
    problem, _, _ = quadruped.build_hop(crocopy)
    timed = [m for m in problem.runningModels if m.nu]
    assert len(timed) == 580
    assert all(abs(m.dt - 0.01) < 1e-15 for m in timed)


def test_monkey_bar_scales_arm_torques_by_ten() -> None:
    problem, _, _ = humanoid.build_monkey_bar(crocopy, knots=(2, 2, 2, 2))
    plain = humanoid.load_model("talos")
    ub = problem.runningModels[0].u_ub
    names = [plain.names[j] for j in range(2, plain.njoints)]
    for i, name in enumerate(names):
        factor = 10.0 if name.startswith("arm_") else 1.0
        assert ub[i] == pytest.approx(factor * plain.effortLimit[6 + i])


def test_pendulum_is_underactuated_and_bounded() -> None:
    problem, _, _ = pendulum.build_pendulum(crocopy)
    assert problem.T == 100
    model = problem.runningModels[0]
    assert model.nu == 1 and model.dt == pytest.approx(0.01)
    np.testing.assert_allclose(model.u_ub, 5.0)
    data = model.createData()
    model.calc(data, problem.x0, np.array([1.0]))
    model.calcDiff(data, problem.x0, np.array([1.0]))
    # the shoulder is passive: a control moves the elbow's acceleration through the coupling only
    assert abs(data.Fu[3, 0]) > abs(data.Fu[2, 0]) > 0


def test_bad_arguments_raise() -> None:
    with pytest.raises(KeyError, match="gait"):
        quadruped.build_gait(crocopy, gait="gallop")
    with pytest.raises(KeyError, match="robot"):
        quadruped.load_quadruped("spot")
    with pytest.raises(ValueError, match="jump_length"):
        quadruped.build_jump(crocopy, jump_length=(0.1, 0.0))
    with pytest.raises(ValueError, match="hops"):
        quadruped.build_hop(crocopy, hops=3)
    with pytest.raises(ValueError, match="actuated_joint"):
        pendulum.build_pendulum(crocopy, actuated_joint=2)
    with pytest.raises(ValueError, match="target"):
        arm.build_arm_reaching(crocopy, target=(1.0, 2.0))
    with pytest.raises(KeyError, match="weights"):
        quadruped.build_jump(crocopy, weights={"nope": 1.0})


def test_registry_table() -> None:
    names = registry.names()
    for row in ("pend", "man", "taichi", "jump", "hop", "bar"):
        assert row in names
        assert row in registry.TABLE1
    assert set(registry.PAPER_TABLE1) == set(registry.TABLE1)
    with pytest.raises(KeyError, match="known problems"):
        registry.get("nope")
    hop = registry.get("hop")
    assert hop.solved(True, hop.reference["boxfddp"].cost)
    assert not hop.solved(True, 1.75e6)
    assert not hop.solved(False, hop.reference["boxfddp"].cost)
    for spec in registry.PROBLEMS.values():
        assert spec.description
        for ref in spec.reference.values():
            assert ref.iters > 0 and np.isfinite(ref.cost)


@pytest.mark.parametrize("name,solver_name", [("arm", "fddp"), ("trot-short", "fddp"), ("pend", "boxfddp")])
def test_quick_problem_solves_to_documented_cost(name: str, solver_name: str) -> None:
    spec = registry.get(name)
    problem, xs, us = spec.build(crocopy)
    assert (problem.T, problem.nx, problem.runningModels[0].nu) == spec.dims
    solver = {"fddp": crocopy.SolverFDDP, "boxfddp": crocopy.SolverBoxFDDP}[solver_name](problem)
    assert solver.solve(xs, us, spec.maxiter, False)
    ref = spec.reference[solver_name]
    assert solver.cost == pytest.approx(ref.cost, rel=spec.rtol)
    assert abs(solver.iter - ref.iters) <= 2


SLOW_CASES = [
    (name, solver)
    for name, spec in registry.PROBLEMS.items()
    for solver in ("fddp", "boxfddp")
    if solver in spec.reference and spec.reference[solver].converged
]


@pytest.mark.slow
@pytest.mark.parametrize("name,solver", SLOW_CASES)
def test_problem_solves_to_documented_cost(name: str, solver: str) -> None:
    spec = registry.get(name)
    problem, xs, us = spec.build(crocopy)
    cls = {"fddp": crocopy.SolverFDDP, "boxfddp": crocopy.SolverBoxFDDP}[solver]
    s = cls(problem)
    assert s.solve(xs, us, spec.maxiter, False)
    ref = spec.reference[solver]
    if ref.exact:
        assert s.cost == pytest.approx(ref.cost, rel=spec.rtol)
    else:
        assert s.cost <= ref.cost * (1.0 + spec.rtol)


@pytest.mark.slow
def test_jump_box_fddp_torques_stay_within_limits() -> None:
    problem, xs, us = registry.build("jump")
    solver = crocopy.SolverBoxFDDP(problem)
    assert solver.solve(xs, us, registry.get("jump").maxiter, False)
    for u, model in zip(solver.us, problem.runningModels, strict=True):
        if model.nu:
            assert np.all(np.abs(u) <= 32.0 + 1e-9)
