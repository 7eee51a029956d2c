"""The last gaps of Crocoddyl's drop-in (issue 26, item 5).

- ``problem.runningModels.tolist()`` / ``runningDatas.tolist()`` (Crocoddyl's containers);
- ``crocoddyl.libcrocoddyl_pywrap_float64`` (the compiled module's name) as an alias of the flat namespace;
- the standalone 1D contact (``Jc``, ``a0``, ``da0_dx``) and the 3D/6D impulses (``Jc``, ``dv0_dq``)
  against central finite differences in every reference frame (LOCAL, LOCAL_WORLD_ALIGNED, WORLD);
- default-constructed cones (``WrenchCone()``, ``CoPSupport()``: Crocoddyl's unbounded box).
"""

from __future__ import annotations

import pickle

import numpy as np
import pinocchio as pin
import pytest
from robots import load

import crocopy

FRAMES = {"LOCAL": pin.LOCAL, "LWA": pin.LOCAL_WORLD_ALIGNED, "WORLD": pin.WORLD}
H = 1e-6
AXIS = pin.rpy.rpyToMatrix(0.3, 0.2, -0.4)


def _lqr_problem(T: int = 4) -> crocopy.ShootingProblem:
    m = crocopy.ActionModelLQR(3, 2)
    return crocopy.ShootingProblem(np.zeros(3), [m] * T, m)


def test_problem_containers_tolist():
    problem = _lqr_problem()
    models, datas = problem.runningModels.tolist(), problem.runningDatas.tolist()
    assert type(models) is list and type(datas) is list
    assert len(models) == len(datas) == problem.T
    assert all(a is b for a, b in zip(datas, problem.runningDatas))
    new = crocopy.ActionModelLQR(3, 2)
    problem.circularAppend(new)
    assert problem.runningModels.tolist()[-1] is new
    problem.updateModel(0, new)
    assert problem.runningModels.tolist()[0] is new
    copy = pickle.loads(pickle.dumps(problem))
    assert len(copy.runningDatas.tolist()) == problem.T
    assert isinstance(problem.runningModels, crocopy.StdVec_ActionModel)


def test_compiled_module_alias():
    import crocopy as crocoddyl

    lib = crocoddyl.libcrocoddyl_pywrap_float64
    for name in ("StateVector", "ShootingProblem", "SolverFDDP", "ActionModelAbstract", "StateMultibody"):
        assert getattr(lib, name) is getattr(crocoddyl, name)

    class Shifted(crocoddyl.StateVector):
        def diff(self, x0, x1):
            return lib.StateVector.diff(self, x0, x1) + 1.0

    np.testing.assert_array_equal(Shifted(2).diff(np.zeros(2), np.ones(2)), [2.0, 2.0])
    with pytest.raises(AttributeError, match="does not implement"):
        lib.GepettoDisplay  # noqa: B018  (Crocoddyl's name crocopy lacks)


def _kinematics(model: pin.Model, x: np.ndarray) -> pin.Data:
    """Pinocchio data as a contact/impulse expects it (zero acceleration)."""
    q, v = x[: model.nq], x[model.nq:]
    pd = model.createData()
    pin.forwardKinematics(model, pd, q, v, np.zeros(model.nv))
    pin.computeJointJacobians(model, pd, q)
    pin.updateFramePlacements(model, pd)
    pin.computeForwardKinematicsDerivatives(model, pd, q, v, np.zeros(model.nv))
    return pd


def _evaluate(item, x: np.ndarray, diff: bool = False):
    model = item.state.pinocchio
    data = item.createData(_kinematics(model, x))
    item.calc(data, x)
    if diff:
        item.calcDiff(data, x)
    return data


def _central(f, state, x: np.ndarray, n: int) -> np.ndarray:
    cols = []
    for i in range(n):
        e = np.zeros(state.ndx)
        e[i] = H
        cols.append((f(state.integrate(x, e)) - f(state.integrate(x, -e))) / (2 * H))
    return np.array(cols).T


def _assert_close(A, B, name, rtol=1e-5):
    scale = max(1.0, np.abs(B).max())
    err = np.abs(A - B).max()
    assert err <= rtol * scale, f"{name}: max error {err:.3e} (scale {scale:.3e})"


def _anymal_point(seed: int):
    model = load("anymal")
    state = crocopy.StateMultibody(model)
    rng = np.random.default_rng(seed)
    x = state.rand()
    x[model.nq:] = rng.normal(size=model.nv)
    return model, state, x


@pytest.mark.parametrize("frame", FRAMES, ids=list(FRAMES))
@pytest.mark.parametrize("gains", [(0.0, 0.0), (4.0, 2.0)], ids=["nogains", "gains"])
def test_contact1d_derivatives_every_frame(frame, gains):
    model, state, x = _anymal_point(3)
    contact = crocopy.ContactModel1D(state, "LF_FOOT", 0.2, FRAMES[frame], AXIS, 12, np.array(gains))
    data = _evaluate(contact, x, diff=True)
    assert data.Jc.shape == (1, model.nv) and data.da0_dx.shape == (1, state.ndx)
    J = _central(lambda y: _evaluate(contact, y).a0.copy(), state, x, state.ndx)
    _assert_close(data.da0_dx, J, "da0_dx")


@pytest.mark.parametrize("frame", FRAMES, ids=list(FRAMES))
@pytest.mark.parametrize("kind", ["ImpulseModel3D", "ImpulseModel6D"])
def test_impulse_dv0_dq_every_frame(frame, kind):
    model, state, x = _anymal_point(5)
    impulse = getattr(crocopy, kind)(state, model.getFrameId("RH_FOOT"), FRAMES[frame])
    data = _evaluate(impulse, x, diff=True)
    v = x[model.nq:]
    J = _central(lambda y: _evaluate(impulse, y).Jc @ v, state, x, model.nv)
    _assert_close(data.dv0_dq, J, "dv0_dq")


def test_world_frame_matches_local_world_aligned():
    model, state, x = _anymal_point(7)
    for make in (lambda t: crocopy.ImpulseModel6D(state, "LF_FOOT", t),
                 lambda t: crocopy.ContactModel1D(state, "LF_FOOT", 0.1, t, AXIS, 12, np.array([1.0, 1.0]))):
        a, b = _evaluate(make(pin.WORLD), x, True), _evaluate(make(pin.LOCAL_WORLD_ALIGNED), x, True)
        np.testing.assert_allclose(a.Jc, b.Jc, atol=1e-12)


def test_default_cones():
    w = crocopy.WrenchCone()
    assert np.all(np.isinf(w.box)) and w.mu == 0.7 and w.nf == 4
    assert w.A.shape == (17, 6) and w.lb.shape == w.ub.shape == (17,)
    np.testing.assert_array_equal(w.lb[:5], [-np.inf] * 4 + [0.0])
    assert w.ub[4] == np.inf and not np.any(w.ub[5:])
    finite = crocopy.WrenchCone(np.eye(3), 0.7, np.array([0.2, 0.1]))
    np.testing.assert_array_equal(w.A[:5], finite.A[:5])  # friction and normal rows do not depend on the box
    assert not np.isfinite(w.A[5:]).all()  # CoP and yaw rows: Crocoddyl's unbounded-box values
    cop = crocopy.CoPSupport()
    assert np.all(np.isinf(cop.box)) and cop.A.shape == (4, 6)
    np.testing.assert_array_equal(cop.A[:, 3:], finite.A[5:9, 3:])
    for bad in ([np.nan, 1.0], [-1.0, 1.0], [1.0]):
        with pytest.raises(ValueError, match="box"):
            crocopy.WrenchCone(np.eye(3), 0.7, np.array(bad))
