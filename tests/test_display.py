"""MeshcatDisplay, static HTML export and CallbackDisplay (headless: no browser is opened)."""

from __future__ import annotations

import re
import time
import webbrowser
from types import SimpleNamespace

import example_robot_data as erd
import numpy as np
import pinocchio as pin
import pytest

import crocopy
from crocopy.models.display import meshcat_display as display_module
from crocopy.models.display.html import _key_frames, export_html, static_html_commands
from crocopy.models.display.meshcat_display import MeshcatDisplay, start_meshcat_server

LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED


@pytest.fixture(scope="module")
def anymal():
    return erd.load("anymal")


@pytest.fixture(scope="module")
def anymal_display(anymal):
    with MeshcatDisplay(anymal, openDisplay=False) as d:
        yield d


def _x0(robot):
    return np.concatenate([robot.q0, np.zeros(robot.model.nv)])


def _bobbing(robot, n=12, height=0.1):
    xs = []
    for i in range(n):
        x = _x0(robot)
        x[2] += height * np.sin(np.pi * i / (n - 1))
        xs.append(x)
    return xs


def _animation(commands):
    """{path: {track name: (times (k,), values (k, width))}} of the page's one animation."""
    anims = [c for c in commands if c["type"] == "set_animation"]
    assert len(anims) == 1
    out = {}
    for a in anims[0]["animations"]:
        out[a["path"]] = {}
        for t in a["clip"]["tracks"]:
            times = np.array([k["time"] for k in t["keys"]])
            out[a["path"]][t["name"]] = (times, np.array([k["value"] for k in t["keys"]]))
    return out


def _self_contained(path):
    with open(path, encoding="utf-8") as f:
        html = f.read()
    assert not re.search(r"<script[^>]*\bsrc\s*=", html, re.I)
    assert not re.search(r"<link[^>]*\bhref\s*=\s*[\"']?https?:", html, re.I)
    assert not re.search(r"\bsrc\s*=\s*[\"']https?://", html, re.I)
    assert "viewer.handle_command_bytearray" in html  # the inlined viewer replays the scene
    assert "DecompressionStream" in html and "fetch(\"data:" in html  # the bundle is inlined, not fetched
    return html


def test_display_without_browser_and_server_cleanup(anymal, monkeypatch):
    opened = []
    monkeypatch.setattr(webbrowser, "open", lambda *a, **k: opened.append(a) or True)
    d = MeshcatDisplay(anymal, openDisplay=False)
    proc = d.viewer.window.server_proc
    assert proc.poll() is None
    assert d.url().startswith("http://127.0.0.1:")
    d.close()
    assert proc.poll() is not None
    assert opened == []
    d2 = MeshcatDisplay(anymal, openDisplay=True)
    try:
        assert len(opened) == 1 and opened[0][0] == d2.url()
    finally:
        d2.close()


def test_dead_server_raises_timeout_instead_of_hanging():
    start = time.time()
    with pytest.raises(TimeoutError, match="no meshcat server"):
        start_meshcat_server(zmq_url="tcp://127.0.0.1:5999", timeout=0.3)
    assert time.time() - start < 5.0
    with pytest.raises(ValueError, match="timeout"):
        start_meshcat_server(timeout=0.0)


def test_bad_arguments(anymal, anymal_display):
    with pytest.raises(ValueError, match="freq"):
        MeshcatDisplay(anymal, freq=0, openDisplay=False)
    with pytest.raises(ValueError, match="xs\\[1\\]"):
        anymal_display.display([_x0(anymal), np.zeros(3)])
    with pytest.raises(ValueError, match="xs must contain"):
        anymal_display.display([])
    with pytest.raises(ValueError, match="cameraTF"):
        anymal_display._camera_matrix(np.zeros(5))
    with pytest.raises(ValueError, match="position"):
        anymal_display.setCameraPosition([1.0, 2.0])
    with pytest.raises(ValueError, match="dts"):
        _key_frames(5, [0.1, 0.1], 1.0, 30)
    assert _key_frames(4, [0.01, 0.02, 0.0], 1.0, 30) == [(0, 0), (2, 1)]  # closest node per frame


def test_display_rate_freq_and_dts(anymal, monkeypatch):
    with MeshcatDisplay(anymal, openDisplay=False, freq=3) as d:
        calls = []
        original = d.set_robot
        monkeypatch.setattr(d, "set_robot", lambda target, q: calls.append(q.copy()) or original(target, q))
        xs = _bobbing(anymal, n=10)
        start = time.time()
        d.display(xs, dts=[0.02] * 9)
        elapsed = time.time() - start
        assert len(calls) == 4  # nodes 0, 3, 6, 9
        np.testing.assert_allclose(calls[1], xs[3][: anymal.model.nq])
        assert elapsed >= 0.15  # 3 windows of 3 x 0.02 s, plus the last node's 0 s
        d.rate = 50.0
        calls.clear()
        start = time.time()
        d.display(xs, factor=2.0)
        assert len(calls) == 4 and time.time() - start >= 4 * 2.0 / 50.0 - 1e-3


def test_anymal_export_animation_and_plain_trunk(anymal, tmp_path):
    xs = _bobbing(anymal)
    path = export_html(anymal, xs, tmp_path / "anymal.html", dts=[0.05] * 11, fps=20)
    _self_contained(path)
    cmds = static_html_commands(path)
    objects = {c["path"]: c for c in cmds if c["type"] == "set_object"}
    trunk = objects["/meshcat/pinocchio/visuals/base_0/shape"]
    assert trunk["object"]["geometries"][0]["type"] == "BufferGeometry"  # plain triangles, not the .dae
    leg = objects["/meshcat/pinocchio/visuals/LF_HIP_0/shape"]
    assert leg["object"]["object"]["type"] == "_meshfile_object" and leg["object"]["object"]["format"] == "dae"
    assert "/meshcat/floor" in objects
    times, positions = _animation(cmds)["/meshcat/pinocchio/visuals/base_0"][".position"]
    np.testing.assert_array_equal(times, [int(round(0.05 * i * 20)) for i in range(12)])
    np.testing.assert_allclose(positions[:, 2] - positions[0, 2], [x[2] - xs[0][2] for x in xs], atol=1e-6)
    _, quats = _animation(cmds)["/meshcat/pinocchio/visuals/base_0"][".quaternion"]
    assert quats.shape == (2, 4)  # the trunk does not turn: only the two ends of the run are kept
    np.testing.assert_allclose(np.linalg.norm(quats, axis=1), 1.0, atol=1e-6)


def test_iris_export(tmp_path, capsys):
    iris = erd.load("iris")
    xs = _bobbing(iris, n=6, height=0.5)
    path = export_html(iris, xs, tmp_path / "iris.html", dts=[0.1] * 5)
    assert "127.0.0.1" not in capsys.readouterr().out  # the temporary server's URL is not advertised
    _self_contained(path)
    tracks = _animation(static_html_commands(path))
    assert len(tracks) == len(iris.visual_model.geometryObjects)
    _, rotor = tracks["/meshcat/pinocchio/visuals/iris__rotor_0_0"][".position"]
    assert rotor[-1, 2] == pytest.approx(rotor[0, 2] + 0.5 * np.sin(np.pi * 5 / 5), abs=1e-6)
    assert rotor[len(rotor) // 2, 2] > rotor[0, 2] + 0.45  # it rises half a metre in the middle


def test_talos_mirrored_meshes_keep_scale_out_of_the_animation(tmp_path):
    talos = erd.load("talos")
    xs = _bobbing(talos, n=4)
    path = export_html(talos, xs, tmp_path / "talos.html", dts=[0.1] * 3)
    cmds = static_html_commands(path)
    transforms = {c["path"]: np.array(c["matrix"]).reshape(4, 4).T for c in cmds if c["type"] == "set_transform"}
    gm = talos.visual_model
    go = gm.geometryObjects[gm.getGeometryId("arm_right_1_link_0")]
    node = "/meshcat/pinocchio/visuals/arm_right_1_link_0"
    assert np.linalg.det(transforms[node + "/shape"][:3, :3]) < 0  # the reflection lives on the static child
    np.testing.assert_allclose(np.diag(transforms[node + "/shape"])[:3], go.meshScale)
    rigid = transforms[node][:3, :3]
    np.testing.assert_allclose(rigid.T @ rigid, np.eye(3), atol=1e-12)
    assert np.linalg.det(rigid) == pytest.approx(1.0)
    data, gdata = talos.model.createData(), pin.GeometryData(gm)
    pin.forwardKinematics(talos.model, data, xs[-1][: talos.model.nq])
    pin.updateGeometryPlacements(talos.model, data, gm, gdata)
    tracks = _animation(cmds)[node]
    last = gdata.oMg[gm.getGeometryId(go.name)]
    np.testing.assert_allclose(tracks[".position"][1][-1], last.translation, atol=1e-6)
    qx, qy, qz, qw = tracks[".quaternion"][1][-1].astype(float)
    R = pin.Quaternion(qw, qx, qy, qz).normalized().toRotationMatrix()
    np.testing.assert_allclose(R, last.rotation, atol=1e-6)


def _fake_contact_solver(robot, force_node0):
    """A solver-shaped object: 2 running nodes in contact on LF_FOOT, a free-dynamics terminal node."""
    fid = robot.model.getFrameId("LF_FOOT")
    xs = [_x0(robot)] * 3

    def contact_node(f, active=True):
        item = SimpleNamespace(active=active, contact=SimpleNamespace(id=fid, type=LWA))
        cone = SimpleNamespace(id=fid, reference=SimpleNamespace(mu=0.5, R=np.eye(3)))
        cost = SimpleNamespace(cost=SimpleNamespace(residual=cone))
        costs = SimpleNamespace(costs={"c": cost})
        diff = SimpleNamespace(contacts=SimpleNamespace(contacts={"LF": item}), costs=costs)
        model = SimpleNamespace(dt=0.01, differential=diff)
        cdata = SimpleNamespace(f=pin.Force(np.asarray(f, dtype=float), np.zeros(3)), frame=fid)
        contacts = SimpleNamespace(contacts={"LF": cdata})
        data = SimpleNamespace(differential=SimpleNamespace(multibody=SimpleNamespace(contacts=contacts)))
        return model, data

    (m0, d0), (m1, d1) = contact_node(force_node0), contact_node([0.0, 0.0, 50.0], active=False)
    free = SimpleNamespace(differential=SimpleNamespace(costs=SimpleNamespace(costs={})))
    free_data = SimpleNamespace(differential=SimpleNamespace(multibody=SimpleNamespace()))
    problem = SimpleNamespace(runningModels=[m0, m1], runningDatas=[d0, d1], terminalModel=free, terminalData=free_data)
    return SimpleNamespace(xs=xs, us=[np.zeros(12)] * 2, problem=problem, iter=0), fid


def test_forces_and_cones_from_solver_data(anymal, anymal_display, tmp_path):
    f0 = [30.0, 0.0, 40.0]
    solver, fid = _fake_contact_solver(anymal, f0)
    d = anymal_display
    assert d.getDurationSequenceFromSolver(solver) == [0.01, 0.01]
    assert d.getTimeSequenceFromSolver(solver) == pytest.approx([0.0, 0.01, 0.02])
    fs = d.getForceTrajectoryFromSolver(solver)
    assert [len(node) for node in fs] == [1, 0, 0]  # inactive contact and free terminal node: no force
    rec = fs[0][0]
    assert rec["key"] == "LF_FOOT" and rec["mu"] == 0.5
    ps = d.getFrameTrajectoryFromSolver(solver)
    assert list(ps) == ["LF_FOOT"] and len(ps["LF_FOOT"]) == 3
    np.testing.assert_allclose(ps["LF_FOOT"][0], rec["oMf"].translation)
    d.displayFromSolver(solver)
    path = d.exportHTMLFromSolver(solver, str(tmp_path / "contact.html"))
    cmds = static_html_commands(path)
    arrow = [c for c in cmds if c["type"] == "set_transform" and c["path"] == "/meshcat/forces/LF_FOOT"][-1]
    T = np.array(arrow["matrix"]).reshape(4, 4).T
    np.testing.assert_allclose(T[:3, 3], rec["oMf"].translation, atol=1e-12)
    # +y along f; the longest arrow (50 N here) is forceFraction times the robot's size
    assert d.force_scale == pytest.approx(d.forceFraction * d.robot_size / 50.0)
    np.testing.assert_allclose(T[:3, 1], np.array(f0) * d.force_scale, atol=1e-12)
    assert any(c["type"] == "set_object" and c["path"].startswith("/meshcat/cones/LF_FOOT") for c in cmds)
    assert any(c["type"] == "set_object" and c["path"] == "/meshcat/trajectories/LF_FOOT" for c in cmds)
    _, scale = _animation(cmds)["/meshcat/forces/LF_FOOT"][".scale"]
    assert scale[0, 1] == pytest.approx(d.forceFraction * d.robot_size) and scale[-1, 1] < 1e-5
    for name in ("forces", "cones"):  # an inactive contact shrinks where it was, it does not slide to the origin
        _, positions = _animation(cmds)[f"/meshcat/{name}/LF_FOOT"][".position"]
        np.testing.assert_allclose(positions[-1], rec["oMf"].translation, atol=1e-6)
    d.forceScale = 0.01
    d.exportHTMLFromSolver(solver, str(tmp_path / "fixed.html"))
    assert d.force_scale == 0.01  # a scale set by the user is kept
    d.forceScale = None


def test_local_force_is_rotated_to_world(anymal_display):
    R = pin.utils.rotate("z", 0.5)
    item = {"key": "k", "oMf": pin.SE3(R, np.ones(3)), "f": pin.Force(np.array([1.0, 0, 0]), np.zeros(3))}
    p, f = anymal_display._force_world(dict(item, type=pin.ReferenceFrame.LOCAL))
    np.testing.assert_allclose(f, R[:, 0])
    np.testing.assert_allclose(anymal_display._force_world(item)[1], [1.0, 0, 0])


def test_free_dynamics_solver_has_no_forces(anymal_display):
    x = np.concatenate([erd.load("anymal").q0, np.zeros(18)])
    model = SimpleNamespace(dt=0.02, differential=SimpleNamespace(costs=SimpleNamespace(costs={})))
    data = SimpleNamespace(differential=SimpleNamespace(multibody=SimpleNamespace(pinocchio=None)))
    problem = SimpleNamespace(runningModels=[model], runningDatas=[data], terminalModel=model, terminalData=data)
    solver = SimpleNamespace(xs=[x, x], us=[np.zeros(12)], problem=problem)
    assert anymal_display.getForceTrajectoryFromSolver(solver) == [[], []]
    anymal_display.frameNames = []
    del anymal_display.frameTrajNames
    assert anymal_display.getFrameTrajectoryFromSolver(solver) == {}
    anymal_display.displayFromSolver(solver)


class _RecordingDisplay:
    def __init__(self):
        self.seen = []

    def displayFromSolver(self, solver, factor=1.0):
        self.seen.append((solver.iter, [x.copy() for x in solver.xs]))


def test_callback_display_is_called_every_iteration():
    with pytest.raises(ValueError, match="displayFromSolver"):
        crocopy.CallbackDisplay(object())
    rec = _RecordingDisplay()
    model = crocopy.ActionModelUnicycle()
    problem = crocopy.ShootingProblem(np.array([1.0, 0.5, 0.2]), [model] * 10, model)
    solver = crocopy.SolverFDDP(problem)
    logger = crocopy.CallbackLogger()
    solver.setCallbacks([crocopy.CallbackDisplay(rec), logger])
    solver.solve([], [], 20)
    assert len(rec.seen) == len(logger.iters) >= 1
    assert [it for it, _ in rec.seen] == logger.iters
    np.testing.assert_allclose(rec.seen[-1][1][-1], solver.xs[-1])


def test_lazy_public_names():
    assert crocopy.MeshcatDisplay is MeshcatDisplay
    assert crocopy.models.export_html is export_html
    assert display_module.MeshcatDisplay is MeshcatDisplay


def _standing_anymal_solver(robot, mu=0.6, T=5):
    """ANYmal standing on four 3D contacts (crocopy's API), with friction-cone costs of coefficient ``mu``."""
    model = robot.model
    state = crocopy.StateMultibody(model)
    actuation = crocopy.ActuationModelFloatingBase(state)
    x0 = _x0(robot)
    feet = ["LF_FOOT", "RF_FOOT", "LH_FOOT", "RH_FOOT"]

    def node(dt):
        contacts = crocopy.ContactModelMultiple(state, actuation.nu)
        costs = crocopy.CostModelSum(state, actuation.nu)
        xres = crocopy.ResidualModelState(state, x0, actuation.nu)
        costs.addCost("x", crocopy.CostModelResidual(state, xres), 1e-1)
        costs.addCost("u", crocopy.CostModelResidual(state, crocopy.ResidualModelControl(state, actuation.nu)), 1e-3)
        for foot in feet:
            fid = model.getFrameId(foot)
            contact = crocopy.ContactModel3D(state, fid, np.zeros(3), LWA, actuation.nu, np.array([0.0, 50.0]))
            contacts.addContact(foot + "_contact", contact)
            cone = crocopy.FrictionCone(np.eye(3), mu, 4, False)
            residual = crocopy.ResidualModelContactFrictionCone(state, fid, cone, actuation.nu)
            activation = crocopy.ActivationModelQuadraticBarrier(crocopy.ActivationBounds(cone.lb, cone.ub))
            costs.addCost(foot + "_cone", crocopy.CostModelResidual(state, activation, residual), 1e1)
        dam = crocopy.DifferentialActionModelContactFwdDynamics(state, actuation, contacts, costs)
        return crocopy.IntegratedActionModelEuler(dam, dt)

    problem = crocopy.ShootingProblem(x0, [node(1e-2) for _ in range(T)], node(0.0))
    solver = crocopy.SolverFDDP(problem)
    solver.solve([], [], 5)
    return solver, feet


def test_forces_from_a_real_contact_problem(anymal, tmp_path, monkeypatch):
    solver, feet = _standing_anymal_solver(anymal)
    with MeshcatDisplay(anymal, openDisplay=False, rate=1000.0) as d:
        fs = d.getForceTrajectoryFromSolver(solver)
        assert [len(n) for n in fs] == [4] * (solver.problem.T + 1)
        data = solver.problem.runningDatas[2].differential.multibody.contacts.contacts["RH_FOOT_contact"]
        rec = {r["key"]: r for r in fs[2]}["RH_FOOT"]
        np.testing.assert_allclose(rec["f"].vector, data.f.vector)
        assert rec["mu"] == pytest.approx(0.6) and rec["type"] == LWA
        assert sum(r["f"].linear[2] for r in fs[0]) > 100.0  # the ground pushes the feet up: they carry the robot
        path = d.exportHTMLFromSolver(solver, str(tmp_path / "standing.html"))
        cmds = static_html_commands(path)
        objects = {c["path"] for c in cmds if c["type"] == "set_object"}
        for foot in feet:
            assert f"/meshcat/forces/{foot}/head" in objects and f"/meshcat/cones/{foot}/shape" in objects
            assert f"/meshcat/trajectories/{foot}" in objects
        calls = []
        original = d.display
        monkeypatch.setattr(d, "display", lambda xs, **kw: calls.append(len(kw["fs"])) or original(xs, **kw))
        logger = crocopy.CallbackLogger()
        solver.setCallbacks([crocopy.CallbackDisplay(d), logger])
        solver.solve([], [], 2)
        assert calls == [solver.problem.T + 1] * len(logger.iters) and calls


def test_a_spawned_server_is_connected_quietly_and_ended_with_its_viewer(capsys):
    from crocopy.models.display.server import connect_spawned, spawn_meshcat_server, stop_meshcat_server

    proc, zmq_url = spawned = spawn_meshcat_server()
    assert proc.poll() is None and zmq_url.startswith("tcp://")
    viewer = connect_spawned(spawned, timeout=30)
    viewer["/box"].set_transform(np.eye(4))  # a request the server answers (else TimeoutError)
    stop_meshcat_server(viewer)
    assert proc.poll() is not None  # ended with the viewer
    assert "visualizer" not in capsys.readouterr().out  # no URL printed
