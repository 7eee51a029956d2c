"""Models written from Python on crocopy's bases, with Crocoddyl's constructor signatures.

Each base (cost, residual, activation, constraint, actuation, squashing) gets a Python subclass
that re-implements a built-in model.  Built positionally and with keywords, it is used inside a
cost sum, a constraint manager or a dynamics model of a double pendulum, and the result is
compared with the built-in model's (same solver iterates, or same values and derivatives), or
against numerical differentiation.
"""

from __future__ import annotations

import numpy as np
import pytest
from robots import load

import crocopy

T = 20
DT = 0.02


@pytest.fixture(scope="module")
def state():
    return crocopy.StateMultibody(load("double_pendulum"))


def _xref(state):
    return np.array([np.pi, 0.3, 0.0, 0.0])[: state.nx]


# --------------------------------------------------------------------------------------- subclasses
class PyStateResidual(crocopy.ResidualModelAbstract):
    """``r = x ⊖ xref`` (a vector space here), written from Python."""

    def __init__(self, state, xref, *args, **kwargs):
        crocopy.ResidualModelAbstract.__init__(self, state, *args, **kwargs)
        self.xref = xref

    def calc(self, data, x, u=None):
        data.r[:] = self.state.diff(self.xref, x)

    def calcDiff(self, data, x, u=None):
        data.Rx[:] = self.state.Jdiff(self.xref, x, crocopy.Jcomponent.second)[0]


class PyStateCost(crocopy.CostModelAbstract):
    """``½‖x ⊖ xref‖²`` written as a whole cost (residual and activation by hand), Crocoddyl style."""

    def __init__(self, state, xref, *args, **kwargs):
        crocopy.CostModelAbstract.__init__(self, state, *args, **kwargs)
        self.xref = xref

    def calc(self, data, x, u=None):
        data.residual.r[:] = self.state.diff(self.xref, x)
        self.activation.calc(data.activation, data.residual.r)
        data.cost = data.activation.a_value

    def calcDiff(self, data, x, u=None):
        Rx = self.state.Jdiff(self.xref, x, crocopy.Jcomponent.second)[0]
        data.residual.Rx[:] = Rx
        self.activation.calcDiff(data.activation, data.residual.r)
        data.Lx[:] = Rx.T @ data.activation.Ar
        data.Lxx[:] = Rx.T @ data.activation.Arr @ Rx


class PyWeightedQuad(crocopy.ActivationModelAbstract):
    """``½ Σ wᵢ rᵢ²`` with a dense ``Arr``."""

    def __init__(self, weights, *args, **kwargs):
        crocopy.ActivationModelAbstract.__init__(self, *args, **kwargs)
        self.weights = np.asarray(weights, dtype=float)

    def calc(self, data, r):
        data.a_value = 0.5 * float(r @ (self.weights * r))

    def calcDiff(self, data, r):
        data.Ar[:] = self.weights * r
        data.Arr[:, :] = np.diag(self.weights)


class PyVelocityBound(crocopy.ConstraintModelAbstract):
    """Inequality ``lb <= v <= ub`` and equality ``q_0 - 0.1 = 0``, written from Python."""

    def __init__(self, state, *args, **kwargs):
        crocopy.ConstraintModelAbstract.__init__(self, state, *args, **kwargs)

    def calc(self, data, x, u=None):
        nq = self.state.nq
        data.g[:] = x[nq:]
        data.h[:] = x[:1] - 0.1

    def calcDiff(self, data, x, u=None):
        nv = self.state.nv
        data.Gx[:, nv:] = np.eye(nv)
        data.Hx[0, 0] = 1.0


class PyFullActuation(crocopy.ActuationModelAbstract):
    """``tau = u`` written from Python."""

    def calc(self, data, x, u=None):
        if u is not None:
            data.tau[:] = u

    def calcDiff(self, data, x, u=None):
        data.dtau_du[:] = np.eye(self.state.nv)


class PyElbowActuation(crocopy.ActuationModelAbstract):
    """One motor on the second joint, written as Crocoddyl users do: ``tau = dtau_du * u``.

    Crocoddyl shows the ``(2, 1)`` ``dtau_du`` as a vector, so the product is assigned into ``tau``
    with shape ``(2, 1)`` here; crocopy's arrays of Python models accept it.
    """

    def __init__(self, state):
        crocopy.ActuationModelAbstract.__init__(self, state, nu=1)

    def calc(self, data, x, u=None):
        if u is None:
            return
        data.dtau_du[1] = 1.0
        data.tau[:] = data.dtau_du * u

    def calcDiff(self, data, x, u=None):
        data.dtau_du[1] = 1.0


class PyTanhSquashing(crocopy.SquashingModelAbstract):
    """``u = lb + (ub - lb)(tanh(s) + 1)/2``; ``calcDiff`` needs no prior ``calc``."""

    def __init__(self, lb, ub, *args, **kwargs):
        crocopy.SquashingModelAbstract.__init__(self, *args, **kwargs)
        self.lb, self.ub = np.asarray(lb, dtype=float), np.asarray(ub, dtype=float)

    def calc(self, data, s):
        data.u[:] = self.lb + 0.5 * (self.ub - self.lb) * (np.tanh(s) + 1.0)

    def calcDiff(self, data, s):
        data.du_ds[:] = np.diag(0.5 * (self.ub - self.lb) * (1.0 - np.tanh(s) ** 2))


# ------------------------------------------------------------------------------------ problem helpers
def _problem(state, running_cost, terminal_cost, actuation=None, constraints=None):
    """A swing-up of the double pendulum with the given costs (built for nu = actuation.nu)."""
    actuation = actuation or crocopy.ActuationModelFull(state)
    nu = actuation.nu

    def node(cost, terminal):
        costs = crocopy.CostModelSum(state, nu)
        costs.addCost("u", crocopy.CostModelResidual(state, crocopy.ResidualModelControl(state, nu)), 1e-3)
        costs.addCost("x", cost(), 1e3 if terminal else 1.0)
        dam = crocopy.DifferentialActionModelFreeFwdDynamics(state, actuation, costs, constraints)
        return crocopy.IntegratedActionModelEuler(dam, 0.0 if terminal else DT)

    return crocopy.ShootingProblem(state.zero(), [node(running_cost, False)] * T, node(terminal_cost, True))


def _solve(problem):
    solver = crocopy.SolverFDDP(problem)
    converged = solver.solve([], [], 200)
    return solver, converged


def _builtin_state_cost(state, nu):
    return lambda: crocopy.CostModelResidual(state, crocopy.ResidualModelState(state, _xref(state), nu))


def _same_solution(a, b):
    assert a.iter == b.iter
    assert a.cost == pytest.approx(b.cost, rel=1e-10)
    for xa, xb in zip(a.xs, b.xs):
        np.testing.assert_allclose(xa, xb, atol=1e-9)


# --------------------------------------------------------------------------------------------- tests
def _cost_forms(state, nu):
    act = crocopy.ActivationModelQuad(state.ndx)
    xref = _xref(state)
    return {
        "(state, activation, nu=)": lambda: PyStateCost(state, xref, act, nu=nu),
        "(state, activation, nu)": lambda: PyStateCost(state, xref, act, nu),
        "(state, nr, nu=)": lambda: PyStateCost(state, xref, state.ndx, nu=nu),
        "(state, nr, nu)": lambda: PyStateCost(state, xref, state.ndx, nu),
        "keywords": lambda: PyStateCost(state, xref, activation=act, nu=nu),
        "nr keyword": lambda: PyStateCost(state, xref, nr=state.ndx, nu=nu),
    }


@pytest.mark.parametrize("form", list(_cost_forms(crocopy.StateVector(4), 2)))
def test_python_cost_solves_like_the_builtin_state_cost(state, form):
    make = _cost_forms(state, state.nv)[form]
    cost = make()
    assert cost.nu == state.nv and cost.activation.nr == state.ndx and cost.residual.nr == state.ndx
    mine, mine_ok = _solve(_problem(state, make, make))
    builtin = _builtin_state_cost(state, state.nv)
    ref, ref_ok = _solve(_problem(state, builtin, builtin))
    assert mine_ok and ref_ok
    _same_solution(mine, ref)


def test_python_cost_defaults_follow_crocoddyl(state):
    xref = _xref(state)
    cost = PyStateCost(state, xref, crocopy.ActivationModelQuad(state.ndx))
    assert cost.nu == state.nv
    cost = PyStateCost(state, xref, state.ndx)
    assert isinstance(cost.activation, crocopy.ActivationModelQuad) and cost.nu == state.nv
    data = cost.createData(crocopy.DataCollectorAbstract())
    assert data.residual.r.shape == (state.ndx,) and data.Lxu.shape == (state.ndx, state.nv)
    assert data.Rx is data.residual.Rx and data.r is data.residual.r
    with pytest.raises(ValueError, match="activation.nr"):
        PyStateCost(state, xref, crocopy.ActivationModelQuad(3), nr=4)
    with pytest.raises(ValueError, match="needs an activation"):
        crocopy.CostModelAbstract(state)
    residual = crocopy.ResidualModelControl(state, 2)
    with pytest.raises(ValueError, match="does not match residual.nu"):
        crocopy.CostModelAbstract(state, residual, nu=3)


RESIDUAL_FORMS = {
    "positional": lambda st: (st.ndx, st.nv, True, True, False),
    "no nu (bools)": lambda st: (st.ndx, True, True, False),
    "keywords": lambda st: dict(nr=st.ndx, nu=st.nv, u_dependent=False),
    "nr and keyword flags": lambda st: (st.ndx, {"u_dependent": False}),
}


@pytest.mark.parametrize("form", sorted(RESIDUAL_FORMS))
def test_python_residual_in_a_cost_sum_solves_like_the_builtin(state, form):
    spec = RESIDUAL_FORMS[form](state)
    if isinstance(spec, dict):
        args, kwargs = (), spec
    elif isinstance(spec[-1], dict):
        args, kwargs = spec[:-1], spec[-1]
    else:
        args, kwargs = spec, {}

    def make():
        return crocopy.CostModelResidual(state, PyStateResidual(state, _xref(state), *args, **kwargs))

    residual = make().residual
    assert (residual.nr, residual.nu) == (state.ndx, state.nv)
    assert (residual.q_dependent, residual.v_dependent, residual.u_dependent) == (True, True, False)
    mine, _ = _solve(_problem(state, make, make))
    builtin = _builtin_state_cost(state, state.nv)
    ref, _ = _solve(_problem(state, builtin, builtin))
    _same_solution(mine, ref)


@pytest.mark.parametrize("form", ["positional", "keyword"])
def test_python_activation_matches_weighted_quadratic(state, form):
    w = np.array([3.0, 1.0, 0.5, 0.2])
    act = PyWeightedQuad(w, nr=4) if form == "keyword" else PyWeightedQuad(w, 4)
    assert act.nr == 4 and not act.diagonal

    def mine():
        return crocopy.CostModelResidual(state, act, crocopy.ResidualModelState(state, _xref(state), state.nv))

    def builtin():
        return crocopy.CostModelResidual(
            state, crocopy.ActivationModelWeightedQuad(w), crocopy.ResidualModelState(state, _xref(state), state.nv)
        )

    a, _ = _solve(_problem(state, mine, mine))
    b, _ = _solve(_problem(state, builtin, builtin))
    _same_solution(a, b)


CONSTRAINT_FORMS = {
    "(state, nu, ng, nh)": lambda st: PyVelocityBound(st, st.nv, st.nv, 1),
    "(state, ng, nh)": lambda st: PyVelocityBound(st, st.nv, 1),
    "(state, ng, nh, T_const)": lambda st: PyVelocityBound(st, st.nv, 1, False),
    "(state, nu, ng, nh, T_const)": lambda st: PyVelocityBound(st, st.nv, st.nv, 1, True),
    "keywords": lambda st: PyVelocityBound(st, ng=st.nv, nh=1, nu=st.nv, T_const=False),
}


@pytest.mark.parametrize("form", sorted(CONSTRAINT_FORMS))
def test_python_constraint_evaluates_like_residual_constraints(state, form):
    mine = CONSTRAINT_FORMS[form](state)
    assert (mine.nu, mine.ng, mine.nh) == (state.nv, state.nv, 1)
    assert mine.T_constraint == (form not in ("(state, ng, nh, T_const)", "keywords"))
    assert mine.type == crocopy.ConstraintType.Both
    assert (mine.residual.nr, mine.residual.nu) == (state.nv + 1, state.nv)
    lb, ub = -np.ones(state.nv), np.ones(state.nv)
    mine.updateBounds(lb, ub)
    ours = crocopy.ConstraintModelManager(state, state.nv)
    ours.addConstraint("v", mine)
    ref = crocopy.ConstraintModelManager(state, state.nv)
    ref.addConstraint(
        "v",
        crocopy.ConstraintModelResidual(
            state, crocopy.ResidualModelState(state, np.zeros(state.nx), state.nv), np.r_[-np.inf, -np.inf, lb],
            np.r_[np.inf, np.inf, ub],
        ),
    )
    x, u = np.array([0.3, -0.2, 0.7, -1.4]), np.array([0.1, 0.2])
    datas = []
    for manager in (ours, ref):
        costs = crocopy.CostModelSum(state, state.nv)
        dam = crocopy.DifferentialActionModelFreeFwdDynamics(state, crocopy.ActuationModelFull(state), costs, manager)
        d = dam.createData()
        dam.calc(d, x, u)
        dam.calcDiff(d, x, u)
        datas.append((dam, d))
    (dam, d), (rdam, rd) = datas
    np.testing.assert_allclose(d.g, rd.g[state.nq:])
    np.testing.assert_allclose(d.Gx, rd.Gx[state.nq:])
    np.testing.assert_allclose(d.h, x[:1] - 0.1)
    np.testing.assert_allclose(d.Hx, np.eye(1, state.ndx))
    np.testing.assert_allclose(d.Gu, 0.0)
    np.testing.assert_allclose(dam.g_lb, lb)
    np.testing.assert_allclose(dam.g_ub, ub)


def test_constraint_forms_reject_conflicts(state):
    with pytest.raises(TypeError, match="both by position and by keyword"):
        crocopy.ConstraintModelAbstract(state, 1, 2, ng=1)
    with pytest.raises(TypeError, match="needs ng and nh"):
        crocopy.ConstraintModelAbstract(state, nu=2)
    with pytest.raises(TypeError, match="positional"):
        crocopy.ConstraintModelAbstract(state, 1, 2, 3, True, 5)
    with pytest.raises(ValueError, match="non-negative"):
        crocopy.ConstraintModelAbstract(state, -1, 2)
    residual = crocopy.ResidualModelControl(state, 2)
    assert not crocopy.ConstraintModelAbstract(state, residual, 2, 0).T_constraint
    assert crocopy.ConstraintModelAbstract(state, crocopy.ResidualModelState(state, state.zero(), 2), 4, 0).T_constraint


@pytest.mark.parametrize("keyword", [False, True])
def test_python_actuation_solves_like_full_actuation(state, keyword):
    act = PyFullActuation(state, nu=state.nv) if keyword else PyFullActuation(state, state.nv)
    cost = _builtin_state_cost(state, state.nv)
    mine, _ = _solve(_problem(state, cost, cost, actuation=act))
    ref, _ = _solve(_problem(state, cost, cost))
    _same_solution(mine, ref)


def test_crocoddyl_style_underactuated_model_accepts_column_products(state):
    act = PyElbowActuation(state)
    cost = _builtin_state_cost(state, 1)
    problem = _problem(state, cost, cost, actuation=act)
    us0 = [np.zeros(1)] * T
    initial = problem.calc(problem.rollout(us0), us0)
    solver, _ = _solve(problem)
    assert solver.cost < 0.9 * initial
    data = act.createData()
    act.calc(data, state.zero(), np.array([2.0]))
    np.testing.assert_allclose(data.tau, [0.0, 2.0])
    with pytest.raises(ValueError):
        data.tau[:] = np.ones((3, 1))


def _check_dam_numdiff(dam, x, u):
    nd = crocopy.DifferentialActionModelNumDiff(dam)
    d, dn = dam.createData(), nd.createData()
    dam.calc(d, x, u)
    dam.calcDiff(d, x, u)
    nd.calc(dn, x, u)
    nd.calcDiff(dn, x, u)
    np.testing.assert_allclose(d.xout, dn.xout)
    np.testing.assert_allclose(d.Fx, dn.Fx, atol=1e-5, rtol=1e-5)
    np.testing.assert_allclose(d.Fu, dn.Fu, atol=1e-5, rtol=1e-5)
    np.testing.assert_allclose(d.Lu, dn.Lu, atol=1e-5, rtol=1e-5)


@pytest.mark.parametrize("keyword", [False, True])
def test_python_squashing_in_actuation_squashing_model(state, keyword):
    lb, ub = np.array([-2.0, -1.0]), np.array([3.0, 1.5])
    sq = PyTanhSquashing(lb, ub, ns=2) if keyword else PyTanhSquashing(lb, ub, 2)
    assert sq.ns == 2
    act = crocopy.ActuationSquashingModel(crocopy.ActuationModelFull(state), sq, 2)
    costs = crocopy.CostModelSum(state, 2)
    costs.addCost("u", crocopy.CostModelResidual(state, crocopy.ResidualModelControl(state, 2)), 1.0)
    dam = crocopy.DifferentialActionModelFreeFwdDynamics(state, act, costs)
    _check_dam_numdiff(dam, np.array([0.3, -0.2, 0.7, -1.4]), np.array([0.8, -2.5]))
    data = sq.createData()
    sq.calcDiff(data, np.array([0.0, 40.0]))
    np.testing.assert_allclose(np.diag(data.du_ds), [2.5, 0.0], atol=1e-12)


def test_builtin_squashing_calcdiff_needs_no_calc():
    sq = crocopy.SquashingModelSmoothSat(np.array([-1.0, 0.0]), np.array([2.0, 5.0]), 2)
    fresh, warmed = sq.createData(), sq.createData()
    s = np.array([0.4, 7.0])
    sq.calcDiff(fresh, s)
    sq.calc(warmed, np.array([-3.0, 1.0]))
    sq.calc(warmed, s)
    sq.calcDiff(warmed, s)
    np.testing.assert_allclose(fresh.du_ds, warmed.du_ds, rtol=0, atol=0)
    h = 1e-6
    for i in range(2):
        e = np.zeros(2)
        e[i] = h
        up, down = sq.createData(), sq.createData()
        sq.calc(up, s + e)
        sq.calc(down, s - e)
        assert fresh.du_ds[i, i] == pytest.approx((up.u[i] - down.u[i]) / (2 * h), rel=1e-7)
