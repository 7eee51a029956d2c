"""The lean paths of the contact and impulse nodes against the general ones and finite differences.

- A contact node without active contacts runs Pinocchio's ABA and its derivatives; with
  ``computeAllContacts`` (which needs the full kinematics) it runs the general path.  Both give the
  same dynamics, derivatives and costs, and the derivatives match central differences.
"""

from __future__ import annotations

import numpy as np
import pytest
from test_contacts import CASES, assert_close, fd_dam, make_dam, random_point


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
