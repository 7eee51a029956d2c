"""The lean paths of the contact and impulse nodes against the general ones and finite differences.

- Contact and impulse sets bring their joint forces up to date when ``fext`` is read; a user's impulse
  with an ``updateForce`` of its own is still called.
- A contact node without active contacts runs Pinocchio's ABA and its derivatives; with
  ``computeAllContacts`` (which needs the full kinematics) it runs the general path.  Both give the
  same dynamics, derivatives and costs, and the derivatives match central differences.
- The impulse node's velocity-jump derivative (from the KKT inverse's identity) matches central
  differences, also with a damped KKT system or an armature.
- ``StateMultibody``'s Euler chain rule on its per-thread scratch matrix equals ``Jintegrate``'s, for any
  control size and from several threads at once.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
import test_impulses
from test_contacts import CASES, assert_close, fd_dam, make_dam, random_point
from test_impulses import FEET
from test_impulses import make_model as make_impulse_node

import crocopy


def _matches_fd(dam, d, x, u):
    """``Fx, Fu, Lx, Lu, df_dx, df_du`` of ``d`` against central differences, when the active contacts
    come first in name order (the inactive contacts' forces must stay zero)."""
    J = fd_dam(dam, x, u)
    nv, ndx, nc = dam.state.nv, dam.state.ndx, dam.contacts.nc
    assert_close(d.Fx, J[:nv, :ndx], "Fx")
    assert_close(d.Fu, J[:nv, ndx:], "Fu")
    assert_close(d.Lx, J[nv, :ndx], "Lx")
    assert_close(d.Lu, J[nv, ndx:], "Lu")
    if nc:
        assert_close(d.df_dx, J[nv + 1:nv + 1 + nc, :ndx], "df_dx")
        assert_close(d.df_du, J[nv + 1:nv + 1 + nc, ndx:], "df_du")
    assert np.all(J[nv + 1 + nc:] == 0.0)


def _without_active_contacts(case, seed=0):
    dam = make_dam(*case, seed=seed)
    for name in dam.contacts.contacts:
        dam.contacts.changeContactStatus(name, False)
    return dam


@pytest.mark.parametrize("case", [CASES[1], CASES[4]], ids=["anymal-LWA", "talos-LOCAL"])
def test_node_without_active_contacts_matches_finite_differences(case):
    dam = _without_active_contacts(case)
    x, u = random_point(dam, seed=5)
    d = dam.createData()
    dam.calc(d, x, u)
    dam.calcDiff(d, x, u)
    assert d.aba
    _matches_fd(dam, d, x, u)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_aba_path_equals_the_general_path(seed):
    dam = _without_active_contacts(CASES[1], seed)
    x, u = random_point(dam, seed=seed + 10)
    dl, df = dam.createData(), dam.createData()
    for compute_all, d in ((False, dl), (True, df)):
        dam.contacts.computeAllContacts = compute_all
        dam.calc(d, x, u)
        dam.calcDiff(d, x, u)
    assert dl.aba and not df.aba
    for name in ("xout", "Fx", "Fu", "Lx", "Lu", "Lxx", "Luu", "df_dx", "df_du"):
        a, b = getattr(dl, name), getattr(df, name)
        assert np.allclose(a, b, rtol=1e-9, atol=1e-9 * max(1.0, np.abs(b).max(initial=0.0))), name
    assert dl.cost == pytest.approx(df.cost, rel=1e-12)


def test_armature_keeps_the_general_path():
    """(The general path used to invert Pinocchio's ``M`` after the RNEA derivatives had overwritten it
    without the armature: wrong ``Fx``/``Fu`` on a node without active contacts and with an armature.)"""
    dam = _without_active_contacts(CASES[1])
    dam.armature = np.full(dam.state.nv, 0.1)
    x, u = random_point(dam, seed=7)
    d = dam.createData()
    dam.calc(d, x, u)
    dam.calcDiff(d, x, u)
    assert not d.aba
    _matches_fd(dam, d, x, u)


def test_reactivated_contact_leaves_the_aba_path():
    dam = _without_active_contacts(CASES[0])
    x, u = random_point(dam, seed=4)
    d = dam.createData()
    dam.calc(d, x, u)
    assert d.aba
    first = sorted(dam.contacts.contacts)[0]
    dam.contacts.changeContactStatus(first, True)
    d = dam.createData()
    dam.calc(d, x, u)
    dam.calcDiff(d, x, u)
    assert not d.aba
    _matches_fd(dam, d, x, u)


# ---------------------------------------------------------------------------------- impulses
@pytest.mark.parametrize("typ", [pin.LOCAL, pin.LOCAL_WORLD_ALIGNED], ids=["LOCAL", "LWA"])
def test_impulse_joint_forces_are_brought_up_to_date_when_read(typ):
    """After calc, reading ``fext`` gives each impulse's ``f_local``/``fext`` and the joint sums that the
    eager per-impulse ``updateForce`` gives."""
    node = make_impulse_node("anymal", "3333", typ, 0.3)
    x = node.state.rand()
    d = node.createData()
    node.calc(d, x)
    idata = d.multibody.impulses
    assert idata.joint_forces_pending
    fext = [f.vector.copy() for f in idata.fext]
    assert not idata.joint_forces_pending
    expected = [np.zeros(6) for _ in fext]
    i = 0
    for name, item in node.impulses.impulses.items():
        md = idata.impulses[name]
        lam = d.pinocchio.impulse_c[i:i + 3].copy()
        f_local, joint_force = md.f_local.vector.copy(), md.fext.vector.copy()
        item.impulse.updateForce(md, lam)
        assert np.allclose(md.f_local.vector, f_local, atol=1e-12)
        assert np.allclose(md.fext.vector, joint_force, atol=1e-12)
        expected[md.joint] += md.fext.vector
        i += 3
    assert np.allclose(np.array(fext), np.array(expected), atol=1e-12)
    assert np.abs(np.array(fext)).max() > 0.0


def test_impulse_with_its_own_update_force_is_honoured():
    """A user's impulse overriding ``updateForce`` (Crocoddyl's API) is still called by the impulse set."""
    calls = []

    class Recording(crocopy.ImpulseModel3D):
        def updateForce(self, data, force):
            calls.append(np.array(force))
            data.f.linear = 2.0 * force
            data.fext = data.jMf.act(data.f)

    state = crocopy.StateMultibody(make_dam(*CASES[0]).state.pinocchio)
    impulses = crocopy.ImpulseModelMultiple(state)
    fid = state.pinocchio.getFrameId(FEET["anymal"][0])
    impulses.addImpulse("foot", Recording(state, fid, pin.LOCAL))
    data = impulses.createData(state.pinocchio.createData())
    impulses.updateForce(data, np.array([1.0, 2.0, 3.0]))
    assert len(calls) == 1 and np.array_equal(calls[0], [1.0, 2.0, 3.0])
    joint = data.impulses["foot"].joint
    expected = data.impulses["foot"].jMf.act(pin.Force(np.r_[2.0, 4.0, 6.0, 0.0, 0.0, 0.0]))
    assert np.allclose(data.fext[joint].vector, expected.vector)


# ---------------------------------------------------------------------------------- state
@pytest.mark.parametrize("nu", [0, 1, 12])
def test_chain_rule_on_scratch_rows_equals_jintegrate(nu):
    """The Euler chain rule (on a per-thread scratch matrix) equals ``Jintegrate``'s for every control
    size, twice in a row (the scratch matrix is reused)."""
    state = make_dam(*CASES[0]).state
    rng = np.random.default_rng(nu)
    for _ in range(2):
        x, dx = state.rand(), 0.3 * rng.normal(size=state.ndx)
        Fx, Fu = rng.normal(size=(state.ndx, state.ndx)), rng.normal(size=(state.ndx, nu))
        Jx, Jdx = state.Jintegrate(x, dx)
        expected_x, expected_u = Jx + Jdx @ Fx, Jdx @ Fu
        state._integrate_chain_rule(x, dx, Fx, Fu)
        np.testing.assert_allclose(Fx, expected_x, atol=1e-12)
        np.testing.assert_allclose(Fu, expected_u, atol=1e-12)


def test_chain_rule_in_threads():
    """Threads calling the chain rule on one state at once each get their own result."""
    from concurrent.futures import ThreadPoolExecutor

    state = make_dam(*CASES[0]).state

    def run(seed):
        rng = np.random.default_rng(seed)
        worst = 0.0
        for _ in range(50):
            x, dx = state.rand(), 0.3 * rng.normal(size=state.ndx)
            Fx, Fu = rng.normal(size=(state.ndx, state.ndx)), rng.normal(size=(state.ndx, 12))
            Jx, Jdx = state.Jintegrate(x, dx)
            expected = np.hstack((Jx + Jdx @ Fx, Jdx @ Fu))
            state._integrate_chain_rule(x, dx, Fx, Fu)
            worst = max(worst, np.abs(np.hstack((Fx, Fu)) - expected).max())
        return worst

    with ThreadPoolExecutor(4) as pool:
        assert max(pool.map(run, range(8))) < 1e-12


def test_all_finite():
    from crocopy.models.contact_fwd_dynamics import all_finite

    assert all_finite(np.array([1.0, -2.0, 0.0]))
    assert all_finite(np.array([1e308, 1e308]))
    assert not all_finite(np.array([1.0, np.nan]))
    assert not all_finite(np.array([np.inf, 1.0]))
    assert not all_finite(np.array([np.inf, -np.inf]))


@pytest.mark.parametrize("option", ["damping", "armature"])
@pytest.mark.parametrize("case", [test_impulses.CASES[1], test_impulses.CASES[5]],
                         ids=[test_impulses.IDS[1], test_impulses.IDS[5]])
def test_impulse_derivatives_with_damping_or_armature(case, option, monkeypatch):
    """The velocity-jump derivatives (``∂v⁺/∂v⁻ = I - (1 + e) B Jc`` from the KKT inverse) against central
    differences, also with a damped KKT system or an armature."""
    def with_option(*args, **kwargs):
        node = make_impulse_node(*args, **kwargs)
        if option == "damping":
            node.JMinvJt_damping = 1e-3
        else:
            node.armature = np.full(node.state.nv, 0.05)
        return node

    monkeypatch.setattr(test_impulses, "make_model", with_option)
    test_impulses.test_impulse_derivatives(case)
