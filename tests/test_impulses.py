"""Impulses and ActionModelImpulseFwdDynamics: derivatives, impact physics and bad input.

Derivatives are checked against central finite differences (step ``H = 1e-6``) to ``RTOL = 1e-5``
relative to the largest entry, as in ``test_contacts.py``.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from robots import load

import crocopy

H = 1e-6
RTOL = 1e-5
LOCAL, LWA = pin.LOCAL, pin.LOCAL_WORLD_ALIGNED
FEET = {
    "anymal": ["LF_FOOT", "RF_FOOT", "LH_FOOT", "RH_FOOT"],
    "solo12": ["FL_FOOT", "FR_FOOT"],
    "talos_legs": ["left_sole_link", "right_sole_link"],
}
CASES = [
    ("anymal", "3333", LOCAL, 0.0),
    ("anymal", "3333", LWA, 0.5),
    ("solo12", "33", LWA, 0.0),
    ("talos_legs", "66", LOCAL, 0.3),
    ("talos_legs", "66", LWA, 0.0),
    ("talos_legs", "36", LWA, 0.7),
]
IDS = [f"{r}-{k}-{'LWA' if t == LWA else 'LOCAL'}-e{e}" for r, k, t, e in CASES]


def make_model(robot, kinds, typ, r_coeff, with_com=True):
    model = load(robot)
    state = crocopy.StateMultibody(model)
    impulses = crocopy.ImpulseModelMultiple(state)
    for name, kind in zip(FEET[robot], kinds):
        cls = crocopy.ImpulseModel3D if kind == "3" else crocopy.ImpulseModel6D
        impulses.addImpulse(name, cls(state, model.getFrameId(name), typ))
    costs = crocopy.CostModelSum(state, 0)
    costs.addCost("x", crocopy.CostModelResidual(state, crocopy.ResidualModelState(state, state.zero(), 0)), 0.1)
    if with_com:
        costs.addCost("com", crocopy.CostModelResidual(state, crocopy.ResidualModelImpulseCoM(state)), 1.0)
    return crocopy.ActionModelImpulseFwdDynamics(state, impulses, costs, r_coeff, 0.0, True)


def random_x(model, seed=2):
    np.random.seed(seed)
    return model.state.rand()


def assert_close(A, B, name):
    scale = max(1.0, np.abs(B).max())
    err = np.abs(A - B).max()
    assert err <= RTOL * scale, f"{name}: max error {err:.3e} (scale {scale:.3e})"


@pytest.mark.parametrize("case", CASES, ids=IDS)
def test_impulse_derivatives(case):
    model = make_model(*case)
    x, u = random_x(model), np.zeros(0)
    st, d = model.state, model.createData()
    model.calc(d, x, u)
    x0 = d.xnext.copy()
    nf = model.impulses.nc
    J = np.zeros((st.ndx + 1 + nf, st.ndx))

    def out():
        f = np.concatenate([c.f.vector[: c.Jc.shape[0]] for c in d.multibody.impulses.impulses.values()])
        return np.r_[st.diff(x0, d.xnext), d.cost, f]

    for i in range(st.ndx):
        e = np.zeros(st.ndx)
        e[i] = H
        model.calc(d, st.integrate(x, e), u)
        op = out()
        model.calc(d, st.integrate(x, -e), u)
        J[:, i] = (op - out()) / (2 * H)
    model.calc(d, x, u)
    model.calcDiff(d, x, u)
    assert_close(d.Fx, J[: st.ndx], "Fx")
    assert_close(d.Lx, J[st.ndx], "Lx")
    assert_close(d.df_dx, J[st.ndx + 1:], "df_dx")
    assert_close(d.multibody.impulses.dvnext_dx, J[st.nv: st.ndx], "dvnext_dx")


@pytest.mark.parametrize("case", CASES, ids=IDS)
def test_impact_physics(case):
    """Contact velocity after impact is -e times before; M (v⁺ - v⁻) = Jcᵀ Λ; q is unchanged."""
    model = make_model(*case, with_com=False)
    x = random_x(model, seed=4)
    d = model.createData()
    model.calc(d, x, np.zeros(0))
    nq, nc = model.state.nq, model.impulses.nc
    v, vnext = x[nq:], d.xnext[nq:]
    Jc = d.multibody.impulses.Jc[:nc]
    np.testing.assert_allclose(Jc @ vnext, -case[3] * (Jc @ v), atol=1e-9)
    np.testing.assert_array_equal(d.xnext[:nq], x[:nq])
    pmodel = model.state.pinocchio
    M = pin.crba(pmodel, pmodel.createData(), x[:nq])
    M = np.triu(M) + np.triu(M, 1).T
    lam = np.concatenate([c.f.vector[: c.Jc.shape[0]] for c in d.multibody.impulses.impulses.values()])
    np.testing.assert_allclose(M @ (vnext - v), Jc.T @ lam, atol=1e-8 * max(1.0, np.abs(lam).max()))


def test_elastic_impact_conserves_energy():
    """With e = 1 (perfectly elastic) the impact keeps the kinetic energy."""
    model = make_model("anymal", "3333", LOCAL, 1.0, with_com=False)
    x = random_x(model, seed=8)
    d = model.createData()
    model.calc(d, x, np.zeros(0))
    nq = model.state.nq
    pmodel = model.state.pinocchio
    M = pin.crba(pmodel, pmodel.createData(), x[:nq])
    M = np.triu(M) + np.triu(M, 1).T
    v, vn = x[nq:], d.xnext[nq:]
    assert vn @ M @ vn == pytest.approx(v @ M @ v, rel=1e-9)


def test_no_active_impulse_keeps_state():
    model = make_model("anymal", "3333", LOCAL, 0.0, with_com=False)
    for name in list(model.impulses.impulses):
        model.impulses.changeImpulseStatus(name, False)
    assert model.impulses.nc == 0 and model.impulses.nc_total == 12
    x = random_x(model)
    d = model.createData()
    model.calc(d, x, np.zeros(0))
    model.calcDiff(d, x, np.zeros(0))
    np.testing.assert_array_equal(d.xnext, x)
    np.testing.assert_array_equal(d.Fx, np.eye(model.state.ndx))


def test_bad_input():
    pm = load("anymal")
    state = crocopy.StateMultibody(pm)
    with pytest.raises(ValueError, match="id"):
        crocopy.ImpulseModel3D(state, -1)
    with pytest.raises(ValueError, match="no frame named"):
        crocopy.ImpulseModel6D(state, "NO_FOOT")
    with pytest.raises(ValueError, match="type"):
        crocopy.ImpulseModel3D(state, "LF_FOOT", "LOCAL")
    impulses = crocopy.ImpulseModelMultiple(state)
    impulses.addImpulse("lf", crocopy.ImpulseModel3D(state, "LF_FOOT"))
    with pytest.raises(ValueError, match="already exists"):
        impulses.addImpulse("lf", crocopy.ImpulseModel3D(state, "RF_FOOT"))
    with pytest.raises(KeyError):
        impulses.removeImpulse("nope")
    costs = crocopy.CostModelSum(state, 0)
    with pytest.raises(ValueError, match="r_coeff"):
        crocopy.ActionModelImpulseFwdDynamics(state, impulses, costs, -0.1)
    with pytest.raises(ValueError, match="impulse data collector"):
        crocopy.ResidualModelImpulseCoM(state).createData(crocopy.DataCollectorMultibody(pm.createData()))


def test_the_overload_without_constraints_takes_its_arguments_in_crocoddyls_order():
    """``(state, impulses, costs, r_coeff, inv_damping[, enable_force])``, as Crocoddyl's second overload."""
    import example_robot_data

    state = crocopy.StateMultibody(example_robot_data.load("anymal").model)
    impulses = crocopy.ImpulseModelMultiple(state)
    costs = crocopy.CostModelSum(state, 0)
    for args, kwargs, expected in (((0.2, 1e-3), {}, (0.2, 1e-3, False)), ((0.0, 1e-3), {}, (0.0, 1e-3, False)),
                                   ((0.1, 1e-2, True), {}, (0.1, 1e-2, True)),
                                   ((0.3, 1e-3), {"enable_force": True}, (0.3, 1e-3, True))):
        model = crocopy.ActionModelImpulseFwdDynamics(state, impulses, costs, *args, **kwargs)
        assert (model.r_coeff, model.JMinvJt_damping, model.enable_force) == expected
        assert model.constraints is None
