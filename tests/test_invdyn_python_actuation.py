"""Inverse dynamics with actuation models subclassed in Python, written as for Crocoddyl.

Crocoddyl shows a ``1×n`` or ``n×1`` matrix as a vector of shape ``(n,)``, so such a model sets the
entry of ``Mtau`` (``1×nv`` with one control) or ``dtau_du`` (``nv×1``) by one index.  The joint
data collector of the inverse-dynamics models reads the commands of the RNEA torques through the
actuation's ``commands``/``torqueTransform``/``calcDiff``; the joint-effort and joint-acceleration
costs are differenced (central differences, :mod:`test_invdyn`) for a one-joint actuation of the
double pendulum set by one index, a state-dependent full actuation and a state-dependent
floating-base actuation under contact inverse dynamics.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given
from hypothesis import strategies as st
from robots import load
from test_invdyn import _costs, assert_close, integrate, numeric_jacobians, sample

import crocopy
from crocopy.array_views import ShapeTolerantArray


class OneJointActuation(crocopy.ActuationModelAbstract):
    """One control driving joint ``link`` (1-based) of a fixed-base robot: ``τ = e_link w``."""

    def __init__(self, state, link: int) -> None:
        crocopy.ActuationModelAbstract.__init__(self, state, 1)
        self.index = link - 1

    def calc(self, data, x, u):
        data.tau[:] = data.dtau_du * u

    def calcDiff(self, data, x, u):
        pass

    def commands(self, data, x, tau):
        data.u[:] = tau[self.index]

    def torqueTransform(self, data, x, u):
        pass

    def createData(self):
        return OneJointData(self)


class OneJointData(crocopy.ActuationDataAbstract):
    """Constant Jacobians set by one index, as Crocoddyl shows ``Mtau`` (1×nv) and ``dtau_du`` (nv×1)."""

    def __init__(self, model: OneJointActuation) -> None:
        crocopy.ActuationDataAbstract.__init__(self, model)
        self.dtau_du[model.index] = 1.0
        self.Mtau[model.index] = 1.0
        self.tau_set[:] = False
        self.tau_set[model.index] = True


def _gain(q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``s(q) = 2 + sin q`` and ``s'(q)``."""
    return 2.0 + np.sin(q), np.cos(q)


class ScaledActuation(crocopy.ActuationModelAbstract):
    """State-dependent actuation of the last ``nu`` joints (configuration rows ``-nu:`` of ``q``, one
    per velocity): ``τ = (0; diag(s(q_j)) w)``, commands ``w = τ_j / s(q_j)``."""

    def __init__(self, state, nu: int) -> None:
        crocopy.ActuationModelAbstract.__init__(self, state, nu)

    def _rows(self, x):
        nq, nu = self.state.nq, self.nu
        return _gain(x[nq - nu:nq])

    def calc(self, data, x, u):
        s, _ = self._rows(x)
        data.tau[:] = 0.0
        data.tau[-self.nu:] = s * u

    def calcDiff(self, data, x, u):
        nv, nu = self.state.nv, self.nu
        s, ds = self._rows(x)
        data.dtau_dx[:] = 0.0
        data.dtau_dx[nv - nu:, nv - nu:nv] = np.diag(ds * u)
        data.dtau_du[:] = 0.0
        data.dtau_du[nv - nu:] = np.diag(s)

    def commands(self, data, x, tau):
        s, _ = self._rows(x)
        data.u[:] = tau[-self.nu:] / s

    def torqueTransform(self, data, x, u):
        s, _ = self._rows(x)
        data.Mtau[:] = 0.0
        data.Mtau[:, -self.nu:] = np.diag(1.0 / s)

    def createData(self):
        data = crocopy.ActuationDataAbstract(self)
        data.tau_set[: self.state.nv - self.nu] = False
        return data


def free_dam(actuation):
    state = actuation.state
    fid = state.pinocchio.nframes - 1
    costs = _costs(state, actuation, state.nv, fid)
    return crocopy.DifferentialActionModelFreeInvDynamics(state, actuation, costs)


def contact_dam():
    """ANYmal on two 3D feet with the state-dependent actuation of its 12 joints."""
    state = crocopy.StateMultibody(load("anymal"))
    actuation = ScaledActuation(state, state.nv - 6)
    nu = state.nv + 6
    contacts = crocopy.ContactModelMultiple(state, nu)
    for name in ("LF_FOOT", "RH_FOOT"):
        fid = state.pinocchio.getFrameId(name)
        contact = crocopy.ContactModel3D(state, fid, np.zeros(3), pin.LOCAL_WORLD_ALIGNED, nu, np.array([0.0, 10.0]))
        contacts.addContact(name, contact)
    fid = state.pinocchio.getFrameId("LF_FOOT")
    costs = _costs(state, actuation, nu, state.pinocchio.getFrameId("RF_FOOT"), (fid, 3))
    return crocopy.DifferentialActionModelContactInvDynamics(state, actuation, contacts, costs)


def pendulum_state():
    return crocopy.StateMultibody(load("double_pendulum"))


BUILDERS = {
    "pendulum-link1": lambda: free_dam(OneJointActuation(pendulum_state(), 1)),
    "pendulum-link2": lambda: free_dam(OneJointActuation(pendulum_state(), 2)),
    "pendulum-scaled": lambda: free_dam(ScaledActuation(pendulum_state(), 2)),
    "talos_arm-scaled": lambda: free_dam(ScaledActuation(crocopy.StateMultibody(load("talos_arm")), 7)),
    "contact-anymal-scaled": contact_dam,
}


@pytest.mark.parametrize("integrator", ("none", "euler", "rk4"))
@pytest.mark.parametrize("case", BUILDERS)
def test_joint_costs_vs_finite_differences(case, integrator):
    model = integrate(BUILDERS[case](), integrator)
    x, u = sample(model, seed=3)
    data = model.createData()
    model.calc(data, x, u)
    model.calcDiff(data, x, u)
    _, L, Hh, _ = numeric_jacobians(model, x, u)
    assert_close(np.concatenate([data.Lx, data.Lu]), L[0], "L")
    assert_close(np.hstack([data.Hx, data.Hu]), Hh, "H")


@pytest.mark.parametrize("link", (1, 2))
def test_one_index_sets_the_entry_crocoddyl_shows(link):
    actuation = OneJointActuation(pendulum_state(), link)
    data = actuation.createData()
    expected = np.eye(2)[link - 1]
    np.testing.assert_array_equal(data.Mtau, expected[None, :])
    np.testing.assert_array_equal(data.dtau_du, expected[:, None])
    model = free_dam(actuation)
    md = model.createData()
    x, u = np.array([0.3, -0.4, 0.5, 0.1]), np.array([0.2, -0.7])
    model.calc(md, x, u)
    model.calcDiff(md, x, u)
    joint = md.multibody.joint
    np.testing.assert_allclose(joint.tau, md.pinocchio.tau[link - 1:link])
    np.testing.assert_allclose(joint.dtau_du, md.pinocchio.M[link - 1:link])


@given(n=st.integers(2, 6), data=st.data())
def test_single_key_indexes_a_unit_dimension_matrix_as_a_vector(n, data):
    i = data.draw(st.integers(-n, n - 1))
    stop = data.draw(st.integers(0, n))
    values = np.arange(1.0, n + 1)
    for shape in ((1, n), (n, 1)):
        a = np.zeros(shape).view(ShapeTolerantArray)
        a[i] = 5.0
        vector = np.zeros(n)
        vector[i] = 5.0
        np.testing.assert_array_equal(a.reshape(-1), vector)
        assert a[i] == 5.0
        a[:stop] = values[:stop]
        vector[:stop] = values[:stop]
        np.testing.assert_array_equal(a.reshape(-1), vector)
        np.testing.assert_array_equal(a[:stop], vector[:stop])
    with pytest.raises(IndexError):
        np.zeros((1, n)).view(ShapeTolerantArray)[n] = 1.0


def test_matrices_keep_row_indexing():
    a = np.zeros((2, 3)).view(ShapeTolerantArray)
    a[1] = 1.0
    a[0, 2] = 4.0
    np.testing.assert_array_equal(a, [[0.0, 0.0, 4.0], [1.0, 1.0, 1.0]])
    b = np.zeros((1, 3)).view(ShapeTolerantArray)
    b[:, 1] = 2.0
    b[0, 2] = 3.0
    np.testing.assert_array_equal(b, [[0.0, 2.0, 3.0]])
