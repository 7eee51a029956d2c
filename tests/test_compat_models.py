"""Crocoddyl's remaining models and behaviours: quadratic-flat activations, numdiff activation and
state, CoP support and residual data, centroidal-momentum data, feasibility norm, cost order,
``shareMemory``, ``tolist()``, impulse-model forms and the flat enumeration names."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from robots import load

import crocopy

FLAT = (crocopy.ActivationModelQuadFlatExp, crocopy.ActivationModelQuadFlatLog)
FLAT_VALUES = {
    crocopy.ActivationModelQuadFlatExp: lambda r, a: 1.0 - np.exp(-(r @ r) / a),
    crocopy.ActivationModelQuadFlatLog: lambda r, a: np.log(1.0 + (r @ r) / a),
}


def _fd_gradient(f, r, h=1e-6):
    return np.array([(f(r + h * e) - f(r - h * e)) / (2 * h) for e in np.eye(r.size)])


def _fd_hessian(f, r, h=1e-4):
    n = r.size
    H = np.zeros((n, n))
    for i, ei in enumerate(np.eye(n)):
        for j, ej in enumerate(np.eye(n)):
            plus, minus = h * (ei + ej), h * (ei - ej)
            H[i, j] = f(r + plus) - f(r + minus) - f(r - minus) + f(r - plus)
    return H / (4 * h * h)


vectors = st.lists(st.floats(-2.0, 2.0), min_size=1, max_size=5).map(np.array)
alphas = st.floats(0.05, 5.0)


@settings(max_examples=40, deadline=None)
@given(r=vectors, alpha=alphas)
@pytest.mark.parametrize("cls", FLAT, ids=lambda c: c.__name__)
def test_flat_activations_value_gradient_and_hessians(cls, r, alpha):
    exact, diagonal = cls(r.size, alpha, true_hessian=True), cls(r.size, alpha)
    assert diagonal.diagonal and not exact.diagonal and not diagonal.true_hessian
    value = FLAT_VALUES[cls]

    def a(z):
        d = exact.createData()
        exact.calc(d, z)
        return d.a_value

    de, dd = exact.createData(), diagonal.createData()
    for model, data in ((exact, de), (diagonal, dd)):
        model.calc(data, r)
        model.calcDiff(data, r)
    assert de.a_value == pytest.approx(value(r, alpha), rel=1e-12, abs=1e-15)
    np.testing.assert_allclose(de.Ar, _fd_gradient(a, r), atol=1e-7)
    np.testing.assert_allclose(dd.Ar, de.Ar, rtol=1e-14, atol=0)
    H = _fd_hessian(a, r)
    np.testing.assert_allclose(de.Arr, H, atol=2e-5 * max(1.0, np.abs(H).max()))
    np.testing.assert_allclose(dd.Arr, np.diag(np.diag(de.Arr)), rtol=1e-12, atol=1e-14)


@pytest.mark.parametrize("cls", FLAT, ids=lambda c: c.__name__)
def test_flat_activations_reject_bad_alpha_and_stack_in_cost_sums(cls):
    for bad in (0.0, -1.0, np.inf, np.nan):
        with pytest.raises(ValueError, match="alpha"):
            cls(3, bad)
    model = cls(3, 2.0)
    model.alpha = 0.5
    assert model.alpha == 0.5 and model.nr == 3
    state = crocopy.StateVector(6)
    residual = crocopy.ResidualModelState(state, np.linspace(-1.0, 1.0, 6), 3)
    for true_hessian in (False, True):
        costs = crocopy.CostModelSum(state, 3)
        costs.addCost("flat", crocopy.CostModelResidual(state, cls(6, 0.7, true_hessian), residual), 2.0)
        data = costs.createData(crocopy.DataCollectorAbstract())
        x, u = np.array([0.3, -0.1, 0.5, 0.2, 0.9, -0.4]), np.zeros(3)
        costs.calc(data, x, u)
        costs.calcDiff(data, x, u)
        single = cls(6, 0.7, true_hessian)
        sd = single.createData()
        single.calc(sd, x - np.linspace(-1.0, 1.0, 6))
        single.calcDiff(sd, x - np.linspace(-1.0, 1.0, 6))
        assert data.cost == pytest.approx(2.0 * sd.a_value, rel=1e-14)
        np.testing.assert_allclose(data.Lxx, 2.0 * sd.Arr, rtol=1e-13)


def test_activation_numdiff_matches_analytic_activations():
    r = np.array([0.4, -0.7, 0.25])
    for model in (
        crocopy.ActivationModelQuadFlatLog(3, 0.6, true_hessian=True),
        crocopy.ActivationModelSmooth2Norm(3, 0.3),
        crocopy.ActivationModelWeightedQuad(np.array([1.0, 2.0, 0.5])),
    ):
        nd = crocopy.ActivationModelNumDiff(model)
        assert nd.model is model and nd.nr == 3 and nd.disturbance > 0
        d, dn = model.createData(), nd.createData()
        model.calc(d, r)
        model.calcDiff(d, r)
        nd.calc(dn, r)
        nd.calcDiff(dn, r)
        assert dn.a_value == d.a_value
        assert dn.data_0.a_value == d.a_value
        np.testing.assert_allclose(dn.Ar, d.Ar, atol=1e-9)
        np.testing.assert_allclose(dn.Arr, d.Arr, atol=1e-6)
        assert dn.rp.shape == dn.dr.shape == (3,)
    with pytest.raises(ValueError, match="ActivationModelAbstract"):
        crocopy.ActivationModelNumDiff(object())


@pytest.mark.parametrize("robot", ["vector", "anymal", "talos_arm"])
def test_state_numdiff_matches_analytic_jacobians(robot):
    state = crocopy.StateVector(5) if robot == "vector" else crocopy.StateMultibody(load(robot))
    nd = crocopy.StateNumDiff(state)
    assert (nd.nx, nd.ndx, nd.nq, nd.nv) == (state.nx, state.ndx, state.nq, state.nv)
    np.testing.assert_array_equal(nd.lb, state.lb)
    np.random.seed(4)
    x0, x1 = state.rand(), state.rand()
    dx = 0.3 * np.random.randn(state.ndx)
    np.testing.assert_allclose(nd.diff(x0, x1), state.diff(x0, x1))
    np.testing.assert_allclose(nd.integrate(x0, dx), state.integrate(x0, dx))
    for fs in (crocopy.Jcomponent.first, crocopy.Jcomponent.second):
        (Jn,), (Ja,) = nd.Jdiff(x0, x1, fs), state.Jdiff(x0, x1, fs)
        np.testing.assert_allclose(Jn, Ja, atol=1e-8)
        (Jn,), (Ja,) = nd.Jintegrate(x0, dx, fs), state.Jintegrate(x0, dx, fs)
        np.testing.assert_allclose(Jn, Ja, atol=1e-8)
        Jin = np.random.randn(state.ndx, 3)
        mine, ref = Jin.copy(), Jin.copy()
        nd.JintegrateTransport(x0, dx, mine, fs)
        np.testing.assert_allclose(mine, Ja @ ref, atol=1e-7)
    assert len(nd.Jdiff(x0, x1)) == 2 and len(nd.Jintegrate(x0, dx)) == 2
    with pytest.raises(ValueError, match="first or Jcomponent.second"):
        nd.JintegrateTransport(x0, dx, np.zeros((state.ndx, 1)), crocopy.Jcomponent.both)


def test_cop_support_constructor_attributes_and_update():
    R = pin.rpy.rpyToMatrix(0.1, 0.2, 0.3)
    cop = crocopy.CoPSupport(R, np.array([0.2, 0.1]))
    np.testing.assert_array_equal(cop.R, R)
    np.testing.assert_array_equal(cop.box, [0.2, 0.1])
    np.testing.assert_array_equal(cop.lb, np.full(4, -np.inf))
    np.testing.assert_array_equal(cop.ub, np.zeros(4))
    # a wrench whose CoP is inside the box satisfies A f <= 0, one outside violates it
    f_local = np.array([0.0, 0.0, 100.0, 0.4 * 100.0 * 0.05, -0.4 * 100.0 * 0.1, 0.0])
    f = np.r_[R @ f_local[:3], R @ f_local[3:]]
    assert np.all(cop.A @ f <= 1e-12)
    f_local[3] = 1.2 * 100.0 * 0.05
    assert (cop.A @ np.r_[R @ f_local[:3], R @ f_local[3:]]).max() > 0.0
    A = cop.A.copy()
    cop.box = np.array([0.4, 0.3])
    cop.update()
    assert not np.allclose(cop.A, A)
    default = crocopy.CoPSupport()
    np.testing.assert_array_equal(default.R, np.eye(3))
    torque_rows = np.array([[1.0, 0.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, -1.0, 0.0]])
    np.testing.assert_array_equal(default.A[:, 3:], torque_rows)
    assert np.all(np.isinf(default.A[:, 2]))


def test_cop_and_centroidal_residual_datas_have_crocoddyls_fields():
    model = load("talos_legs")
    state = crocopy.StateMultibody(model)
    act = crocopy.ActuationModelFloatingBase(state)
    fid = model.getFrameId("left_sole_link")
    contacts = crocopy.ContactModelMultiple(state, act.nu)
    contacts.addContact("lf", crocopy.ContactModel6D(state, fid, pin.SE3.Identity(), pin.LOCAL, act.nu, np.zeros(2)))
    costs = crocopy.CostModelSum(state, act.nu)
    support = crocopy.CoPSupport(np.eye(3), np.array([0.2, 0.1]))
    cop = crocopy.ResidualModelContactCoPPosition(state, fid, support, act.nu)
    mom = crocopy.ResidualModelCentroidalMomentum(state, np.zeros(6), act.nu)
    costs.addCost("cop", crocopy.CostModelResidual(state, cop), 1.0)
    costs.addCost("mom", crocopy.CostModelResidual(state, mom), 1.0)
    dam = crocopy.DifferentialActionModelContactFwdDynamics(state, act, contacts, costs, 0.0, True)
    data = dam.createData()
    np.random.seed(3)
    x = state.rand()
    dam.calc(data, x, np.random.randn(act.nu))
    dam.calcDiff(data, x, np.random.randn(act.nu))
    cd = data.costs.costs["cop"].residual
    assert isinstance(cd, crocopy.ResidualDataContactCoPPosition)
    assert cd.pinocchio is data.pinocchio and cd.contact is data.multibody.contacts.contacts["lf"]
    np.testing.assert_allclose(cd.r, cop.reference.A @ cd.contact.f.vector)
    md = data.costs.costs["mom"].residual
    assert isinstance(md, crocopy.ResidualDataCentroidalMomentum)
    assert md.pinocchio is data.pinocchio
    assert md.dhd_dq.shape == md.dhd_dv.shape == (6, state.nv)
    Ag = pin.computeCentroidalMap(model, model.createData(), x[: state.nq])
    np.testing.assert_allclose(md.Rx[:, state.nv:], Ag, atol=1e-10)


def _gapped_solver(norm):
    model = crocopy.ActionModelLQR(3, 2)
    problem = crocopy.ShootingProblem(np.ones(3), [model] * 4, model)
    solver = crocopy.SolverFDDP(problem)
    solver.feasNorm = norm
    rng = np.random.default_rng(0)
    solver.setCandidate([rng.standard_normal(3) for _ in range(5)], [rng.standard_normal(2) for _ in range(4)])
    problem.calc(solver.xs, solver.us)
    return solver


def test_feasibility_norm_selects_linf_or_l1():
    model = crocopy.ActionModelLQR(2, 1)
    assert crocopy.SolverFDDP(crocopy.ShootingProblem(np.ones(2), [model], model)).feasNorm == crocopy.LInf
    linf = _gapped_solver(crocopy.FeasibilityNorm.LInf)
    l1 = _gapped_solver(crocopy.FeasibilityNorm.L1)
    assert linf.computeDynamicFeasibility() == pytest.approx(np.abs(np.concatenate(linf.fs)).max())
    assert l1.computeDynamicFeasibility() == pytest.approx(np.abs(np.concatenate(l1.fs)).sum())
    assert l1.ffeas > linf.ffeas > 0.0
    assert crocopy.LInf is crocopy.FeasibilityNorm.LInf and crocopy.L1 is crocopy.FeasibilityNorm.L1


def test_cost_items_iterate_by_name():
    state = crocopy.StateVector(4)
    costs = crocopy.CostModelSum(state, 2)
    for name in ("zeta", "alpha", "mid"):
        costs.addCost(name, crocopy.CostModelResidual(state, crocopy.ResidualModelControl(state, 2)), 1.0)
    assert list(costs.costs) == ["alpha", "mid", "zeta"]
    assert list(costs.createData(crocopy.DataCollectorAbstract()).costs) == ["alpha", "mid", "zeta"]
    costs.removeCost("mid")
    costs.addCost("beta", crocopy.CostModelResidual(state, crocopy.ResidualModelControl(state, 2)), 1.0)
    assert list(costs.costs) == ["alpha", "beta", "zeta"]


def test_share_memory_on_cost_and_constraint_data():
    dam = crocopy.DifferentialActionModelLQR.Random(2, 2)
    action = dam.createData()
    state = dam.state
    costs = crocopy.CostModelSum(state, 2)
    costs.addCost("x", crocopy.CostModelResidual(state, crocopy.ResidualModelState(state, np.ones(4), 2)), 3.0)
    cdata = costs.createData(crocopy.DataCollectorAbstract())
    cdata.shareMemory(action)
    x, u = np.arange(4.0), np.array([0.5, -0.5])
    costs.calc(cdata, x, u)
    costs.calcDiff(cdata, x, u)
    assert cdata.Lx is action.Lx and cdata.Luu is action.Luu
    np.testing.assert_allclose(action.Lx, 3.0 * (x - 1.0))
    np.testing.assert_allclose(action.Lxx, 3.0 * np.eye(4))
    manager = crocopy.ConstraintModelManager(state, 2)
    manager.addConstraint("u", crocopy.ConstraintModelResidual(state, crocopy.ResidualModelControl(state, 2)))
    mdata = manager.createData(crocopy.DataCollectorAbstract())
    other = crocopy.DifferentialActionModelLQR.Random(2, 2, 0, 2).createData()
    mdata.shareMemory(other)
    manager.calc(mdata, x, u)
    np.testing.assert_allclose(other.h, u)
    with pytest.raises(ValueError, match="shape"):
        costs.createData(crocopy.DataCollectorAbstract()).shareMemory(crocopy.ActionModelLQR(3, 2).createData())


def test_solver_trajectories_have_tolist_and_stay_lists():
    model = crocopy.ActionModelLQR(2, 2)
    solver = crocopy.SolverFDDP(crocopy.ShootingProblem(np.ones(2), [model] * 3, model))
    assert solver.solve()
    for seq in (solver.xs, solver.us, solver.fs):
        assert isinstance(seq, list) and isinstance(seq, crocopy.StdVec_VectorXs)
        listed = seq.tolist()
        assert type(listed) is list and len(listed) == len(seq)
        for a, b in zip(listed, seq):
            np.testing.assert_array_equal(a, b)
            assert a is not b
    listed = solver.xs.tolist()
    listed[0][0] = 99.0
    assert solver.xs[0][0] == 1.0
    assert type(solver.xs.copy()) is crocopy.StdVec_VectorXs and solver.xs.copy()[1] is solver.xs[1]
    solver.xs = [np.zeros(2)] * 4
    assert isinstance(solver.xs, crocopy.StdVec_VectorXs) and len(solver.xs.tolist()) == 4
    solver.setCandidate([], [np.ones(2)] * 3, True)
    assert isinstance(solver.us, crocopy.StdVec_VectorXs)


def test_impulse_model_accepts_crocoddyls_forms():
    model = load("anymal")
    state = crocopy.StateMultibody(model)
    impulses = crocopy.ImpulseModelMultiple(state)
    impulses.addImpulse("lf", crocopy.ImpulseModel3D(state, model.getFrameId("LF_FOOT"), pin.LOCAL_WORLD_ALIGNED))
    np.random.seed(5)
    x = state.rand()
    datas = []
    for nu in (0, state.nv, 12):
        costs = crocopy.CostModelSum(state, nu)
        costs.addCost("x", crocopy.CostModelResidual(state, crocopy.ResidualModelState(state, state.zero(), nu)), 1.0)
        costs.addCost("u", crocopy.CostModelResidual(state, crocopy.ResidualModelControl(state, nu)), 1.0)
        constraints = crocopy.ConstraintModelManager(state, nu)
        constraints.addConstraint(
            "x", crocopy.ConstraintModelResidual(state, crocopy.ResidualModelState(state, state.zero(), nu))
        )
        impulse = crocopy.ActionModelImpulseFwdDynamics(state, impulses, costs, constraints, r_coeff=0.2)
        assert impulse.nu == 0 and impulse.r_coeff == 0.2
        data = impulse.createData()
        impulse.calc(data, x, np.zeros(0))
        impulse.calcDiff(data, x, np.zeros(0))
        assert data.Lu.shape == (0,) and data.Hu.shape == (state.ndx, 0)
        datas.append(data)
    for data in datas[1:]:
        assert data.cost == pytest.approx(datas[0].cost, rel=1e-14)
        np.testing.assert_allclose(data.Lx, datas[0].Lx, rtol=1e-14)
        np.testing.assert_allclose(data.h, datas[0].h, rtol=1e-14)
    costs = crocopy.CostModelSum(state, 0)
    forms = [
        crocopy.ActionModelImpulseFwdDynamics(state, impulses, costs, 0.5, 1e-12, True),
        crocopy.ActionModelImpulseFwdDynamics(
            state, impulses, costs, r_coeff=0.5, inv_damping=1e-12, enable_force=True
        ),
    ]
    for impulse in forms:
        assert (impulse.r_coeff, impulse.JMinvJt_damping, impulse.enable_force) == (0.5, 1e-12, True)


def test_flat_enumeration_values_match_crocoddyl_names():
    assert crocopy.both is crocopy.Jcomponent.both and crocopy.first is crocopy.Jcomponent.first
    assert (crocopy.setto, crocopy.addto, crocopy.rmfrom) == tuple(crocopy.AssignmentOp)
    assert (crocopy.two, crocopy.three, crocopy.four) == tuple(crocopy.RKType)
    assert (crocopy.Inequality, crocopy.Equality, crocopy.Both) == tuple(crocopy.ConstraintType)
    assert (crocopy.CW, crocopy.CCW) == tuple(crocopy.ThrusterType)
    assert crocopy.WITH_CODEGEN is False
