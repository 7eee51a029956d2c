"""Real-browser test: headless Chromium renders the exported HTML and the robot is on the picture.

Needs Debian's ``chromium`` (``apt-get install -y chromium``); without it these tests are skipped
(fail in CI: ``tests/conftest.py``). The page is opened from ``file://`` (no server); software WebGL (SwiftShader)
draws it. Each check compares a screenshot with the robot against one of the same scene with the
robot hidden: thousands of pixels differ when the robot is drawn, none when WebGL fails. One more
reads the page's DOM after its scripts ran (the controls panel open on the animation's play button)
and the empty scene's screenshot (a floor filling the view's bottom up to one straight horizon).
"""

from __future__ import annotations

import os
import re
import shutil
import signal
import subprocess
from types import SimpleNamespace

import example_robot_data as erd
import numpy as np
import pinocchio as pin
import pytest
from optional_requirements import require_chromium, skip_without_chromium
from PIL import Image

import crocopy
from crocopy.models.display.meshcat_display import MeshcatDisplay
from crocopy.problems import registry

pytestmark = [skip_without_chromium(), pytest.mark.usefixtures("chromium")]
FLAGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--enable-unsafe-swiftshader",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--window-size=800,600",
    # Without these a page sometimes never finishes its virtual time (no screenshot until the timeout: 3 of 20 shots
    # of an ANYmal page; 0 of 18 with them).
    "--disable-renderer-backgrounding",
    "--disable-background-timer-throttling",
    "--disable-backgrounding-occluded-windows",
    "--run-all-compositor-stages-before-draw",
]
STILL, PLAYED = 1000, 5000
"""Virtual milliseconds a page runs before its screenshot (``--virtual-time-budget``): a still scene is drawn within
the first; an animation needs the second to have played once.  The browser draws every frame of that virtual time in
software (an ANYmal page: about 10 s for the first, minutes for the second on the 2-core machine)."""


def _chromium() -> str:
    return require_chromium()


def _screenshot(html: str, png: str, profile: str, attempts: int = 3, budget: int = STILL) -> np.ndarray:
    """Render ``html`` headless for ``budget`` virtual milliseconds and return the RGB screenshot; tries again (fresh
    profile) when Chromium hangs or exits without one, which happens on a loaded machine (two hangs of 90 s seen at
    load 5)."""
    cmd = [_chromium(), *FLAGS, f"--virtual-time-budget={budget}", f"--user-data-dir={profile}", f"--screenshot={png}",
           f"file://{html}"]
    for _ in range(attempts):
        shutil.rmtree(profile, ignore_errors=True)
        proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
        try:
            proc.wait(timeout=120)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
            continue
        if os.path.exists(png):
            return np.asarray(Image.open(png).convert("RGB"), dtype=int)
    pytest.fail(f"chromium produced no screenshot of {html}")


PANEL = (slice(0, 310), slice(550, 800))
"""Where the page's controls panel (open, with the animation's play button) sits in an 800 x 600 shot."""


def _differing_pixels(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Pixels that differ between two shots, outside the controls panel (its time read-out moves)."""
    assert a.shape == b.shape == (600, 800, 3)
    diff = np.abs(a - b).sum(axis=2) > 30
    diff[PANEL] = False
    return diff


def _dom(html: str, profile: str) -> str:
    """The page's DOM after its scripts ran (headless Chromium's ``--dump-dom``)."""
    cmd = [_chromium(), *FLAGS, f"--virtual-time-budget={STILL}", f"--user-data-dir={profile}", "--dump-dom",
           f"file://{html}"]
    return subprocess.run(cmd, capture_output=True, text=True, timeout=300).stdout


def test_page_opens_with_play_in_view_over_ground_reaching_the_horizon(tmp_path):
    """The controls panel is open with the "Animations" folder unfolded (play, pause, time), and the
    floor covers the whole lower part of the view up to one straight horizon: no slab corner or edge."""
    anymal = erd.load("anymal")
    x0 = np.concatenate([anymal.q0, np.zeros(anymal.model.nv)])
    with MeshcatDisplay(anymal, openDisplay=False) as display:
        display.setVisibility("robot", False)
        page = display.exportHTML([x0, x0], str(tmp_path / "empty.html"), dts=[0.1])
    dom = _dom(page, str(tmp_path / "dom"))
    assert '<div class="close-button close-bottom" style="width: 245px;">Close Controls</div>' in dom  # open
    folder = re.search(r'<ul( class="closed")?><li class="title">Animations</li>(.*?)</ul>', dom, re.S)
    assert folder and not folder.group(1), "the Animations folder is folded"
    assert all(f'<span class="property-name">{b}</span>' in folder.group(2) for b in ("play", "pause", "time"))
    shot = _screenshot(page, str(tmp_path / "empty.png"), str(tmp_path / "profile"))
    sky = shot[..., 2] > shot[..., 0] + 40  # meshcat's blue background; the floor is grey
    view = sky[:, :PANEL[1].start]
    assert view[0].all() and not view[-150:].any(), "the floor does not fill the bottom of the view"
    horizon = np.argmin(view, axis=0)  # first floor row of each column
    assert horizon.max() - horizon.min() <= 3, f"the floor's far edge is not a straight horizon: rows {horizon}"


def _shots_with_and_without_robot(robot, xs, dts, tmp_path, name):
    with MeshcatDisplay(robot, openDisplay=False) as display:
        shown = display.exportHTML(xs, str(tmp_path / f"{name}.html"), dts=dts)
        display.setVisibility("robot", False)
        hidden = display.exportHTML(xs, str(tmp_path / f"{name}_hidden.html"), dts=dts)
    a = _screenshot(shown, str(tmp_path / f"{name}.png"), str(tmp_path / "profile"))
    b = _screenshot(hidden, str(tmp_path / f"{name}_hidden.png"), str(tmp_path / "profile"))
    return a, b


def test_talos_trajectory_is_drawn(tmp_path):
    talos = erd.load("talos")
    x0 = np.concatenate([talos.q0, np.zeros(talos.model.nv)])
    xs = []
    for i in range(11):
        x = x0.copy()
        x[2] += 0.05 * np.sin(np.pi * i / 10)
        xs.append(x)
    shown, hidden = _shots_with_and_without_robot(talos, xs, [0.1] * 10, tmp_path, "talos")
    diff = _differing_pixels(shown, hidden)
    assert diff.sum() > 3000, f"only {diff.sum()} pixels differ: the robot is not drawn"
    rows, cols = np.nonzero(diff)
    assert 200 < cols.mean() < 600 and 100 < rows.mean() < 500  # the robot is in the middle of the view
    assert hidden.std() > 10  # the scene itself (sky, floor) was rendered


def test_anymal_trunk_is_visible(tmp_path):
    """ANYmal's trunk mesh alone (the .dae the browser cannot merge is sent as plain triangles)."""
    anymal = erd.load("anymal")
    trunk_only = pin.GeometryModel()
    trunk_only.addGeometryObject(anymal.visual_model.geometryObjects[anymal.visual_model.getGeometryId("base_0")])
    robot = SimpleNamespace(
        model=anymal.model, visual_model=trunk_only, collision_model=trunk_only, q0=anymal.q0.copy()
    )
    x0 = np.concatenate([anymal.q0, np.zeros(anymal.model.nv)])
    shown, hidden = _shots_with_and_without_robot(robot, [x0], [], tmp_path, "anymal_trunk")
    diff = _differing_pixels(shown, hidden)
    assert diff.sum() > 3000, f"only {diff.sum()} pixels differ: the trunk is not drawn"


def _short_solve(name: str, maxiter: int) -> list[np.ndarray]:
    """States after a few FDDP iterations of a bundled problem (enough for it to move)."""
    problem, xs, us = registry.build(name)
    solver = crocopy.SolverFDDP(problem)
    solver.solve(xs, us, maxiter, False)
    return [np.array(x) for x in solver.xs]


def _fitted_shots(robot, xs, tmp_path, name, dts=()):
    """Screenshots at the first, middle and last node with the camera framing the whole motion, of
    the same scene without the robot and, with ``dts``, of the animation after it has played."""
    nodes = (0, len(xs) // 2, len(xs) - 1)
    with MeshcatDisplay(robot, openDisplay=False) as display:
        display.fit_view(xs)
        display.auto_frame = False  # every page below keeps the camera framing the whole motion
        pages = [display.exportHTML([xs[i]], str(tmp_path / f"{name}_{i}.html")) for i in nodes]
        if dts:
            pages.append(display.exportHTML(xs, str(tmp_path / f"{name}_played.html"), dts=dts, repetitions=1))
        display.setVisibility("robot", False)
        pages.append(display.exportHTML([xs[0]], str(tmp_path / f"{name}_hidden.html")))
    budgets = [STILL] * len(nodes) + ([PLAYED] if dts else []) + [STILL]
    # One browser at a time: two headless Chromiums at once (even with their own profiles) left one hanging until its
    # timeout, every other run on the 2-core machine.
    shots = [_screenshot(page, page[:-5] + ".png", str(tmp_path / f"p{k}"), budget=budget)
             for k, (page, budget) in enumerate(zip(pages, budgets, strict=True))]
    return shots[:-1], shots[-1]


def _assert_robot_inside(shot, empty, min_pixels):
    """The robot is drawn (many pixels differ from the empty scene) and none of it touches the border."""
    diff = _differing_pixels(shot, empty)
    assert diff.sum() > min_pixels, f"only {diff.sum()} pixels differ: the robot is not on screen"
    rows, cols = np.nonzero(diff)
    assert rows.min() > 0 and cols.min() > 0 and rows.max() < 599 and cols.max() < 799, "the robot is cut off"
    return np.array([cols.mean(), rows.mean()])


def test_quadrotor_goal_is_on_screen_from_start_to_end(tmp_path):
    xs = _short_solve("quad-goal", 20)
    assert np.linalg.norm(xs[-1][:3] - xs[0][:3]) > 2.5  # it flies to the goal, 3 m away
    problem, _, _ = registry.build("quad-goal")
    dts = [m.dt for m in problem.runningModels]
    (start, middle, end, played), empty = _fitted_shots(erd.load("iris"), xs, tmp_path, "quad", dts)
    centres = [_assert_robot_inside(shot, empty, 700) for shot in (start, middle, end)]  # a 0.55 m drone, 4 m view
    assert np.linalg.norm(centres[2] - centres[0]) > 150  # the drone crosses the view
    assert empty.std() > 10  # the scene itself (sky, floor) was rendered
    # The compact animation plays: after it has run once it rests on the last node.
    assert _differing_pixels(played, end).sum() < 100 < _differing_pixels(played, start).sum()


def test_jump_is_on_screen_from_start_to_end(tmp_path):
    xs = _short_solve("jump", 25)
    heights = [x[2] for x in xs]
    assert max(heights) - min(heights) > 0.1  # the trunk moves
    shots, empty = _fitted_shots(erd.load("anymal"), xs, tmp_path, "jump")
    for shot in shots:
        _assert_robot_inside(shot, empty, 5000)
    assert _differing_pixels(shots[0], shots[1]).sum() > 1000  # the robot is seen moving
