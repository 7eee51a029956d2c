"""Oracle: constraint managers and the models holding them, running and terminal (bench extra).

The same manager (inequality and equality items, some running-only) is built in both libraries and
put under free dynamics and both integrators.  Counts (``ng, nh, ng_T, nh_T``) of the manager and of
every model must be Crocoddyl's, also after ``changeConstraintStatus``; the manager's stacked rows
``g``/``h`` and Jacobians must be equal on running and terminal nodes (the terminal rows first, then
zeros), and so must the models' first ``ng``/``nh`` (running) or ``ng_T``/``nh_T`` (terminal) rows.

Crocoddyl 3.2.1's ``g_lb``/``g_ub`` are not compared: they hold uninitialised memory on a
manager (and, depending on the run, on the models holding it); crocopy's are the stacked bounds.
"""

from __future__ import annotations

import numpy as np
import pytest

crocoddyl = pytest.importorskip("crocoddyl")

import oracle_models as om  # noqa: E402

import crocopy  # noqa: E402

pytestmark = pytest.mark.usefixtures("bench_crocoddyl")

TOL = 1e-10


def _build(lib):
    model = om.robot("anymal")
    state = lib.StateMultibody(model)
    act = lib.ActuationModelFloatingBase(state)
    nu = act.nu
    m = lib.ConstraintModelManager(state, nu)
    foot = model.getFrameId("LF_FOOT")
    m.addConstraint("a_run", lib.ConstraintModelResidual(
        state, lib.ResidualModelFrameTranslation(state, foot, np.zeros(3), nu), -np.ones(3), np.ones(3), False))
    m.addConstraint("b_both", lib.ConstraintModelResidual(
        state, lib.ResidualModelFrameTranslation(state, foot + 1, np.ones(3), nu), -2 * np.ones(3), 2 * np.ones(3)))
    m.addConstraint("c_eq_run", lib.ConstraintModelResidual(state, lib.ResidualModelControl(state, nu), False))
    m.addConstraint("d_eq", lib.ConstraintModelResidual(state, lib.ResidualModelState(state, state.zero(), nu)))
    dam = lib.DifferentialActionModelFreeFwdDynamics(state, act, lib.CostModelSum(state, nu), m)
    models = {"dam": dam, "euler": lib.IntegratedActionModelEuler(dam, om.DT),
              "rk4": lib.IntegratedActionModelRK(dam, lib.RKType.four, om.DT)}
    return m, models


def _counts(obj) -> tuple[int, int, int, int]:
    return obj.ng, obj.nh, obj.ng_T, obj.nh_T


@pytest.mark.parametrize("off", [None, "a_run", "b_both", "d_eq"])
def test_counts_follow_the_manager_as_in_crocoddyl(off):
    built = {lib.__name__: _build(lib) for lib in (crocopy, crocoddyl)}
    for m, _ in built.values():
        if off is not None:
            m.changeConstraintStatus(off, False)
    (mine, my_models), (theirs, their_models) = built["crocopy"], built["crocoddyl"]
    assert _counts(mine) != (0, 0, 0, 0)
    assert _counts(mine) == _counts(theirs)
    for name in my_models:
        assert _counts(my_models[name]) == _counts(their_models[name]), name
        assert my_models[name].g_lb.shape == (their_models[name].ng,)


@pytest.mark.parametrize("terminal", [False, True], ids=["running", "terminal"])
@pytest.mark.parametrize("name", ["dam", "euler", "rk4"])
def test_rows_equal_crocoddyl(name, terminal):
    built = {lib.__name__: _build(lib)[1][name] for lib in (crocopy, crocoddyl)}
    x, u = om.sample(om.FREE, built["crocopy"].nu, 3)
    found = {}
    for lib, model in built.items():
        data = model.createData()
        args = (x,) if terminal else (x, u)
        model.calc(data, *args)
        model.calcDiff(data, *args)
        found[lib] = data
    ng, nh = (built["crocoddyl"].ng_T, built["crocoddyl"].nh_T) if terminal else (built["crocoddyl"].ng,
                                                                                   built["crocoddyl"].nh)
    mine, theirs = found["crocopy"], found["crocoddyl"]
    for field, rows in (("g", ng), ("Gx", ng), ("h", nh), ("Hx", nh)) + ((("Gu", ng), ("Hu", nh)) if not terminal
                                                                          else ()):
        a, b = np.asarray(getattr(mine, field))[:rows], np.asarray(getattr(theirs, field))
        assert b.shape[0] == rows
        assert np.abs(a - b).max() <= TOL * max(1.0, np.abs(b).max()), field
        assert not np.any(np.asarray(getattr(mine, field))[rows:]), f"{field}: rows after the terminal ones"
