"""Real-browser test: headless Chromium renders the exported HTML and the robot is on the picture.

Needs Debian's ``chromium`` (``apt-get install -y chromium``); without it these tests are skipped
(fail in CI: ``tests/conftest.py``). The page is opened from ``file://`` (no server); software WebGL (SwiftShader)
draws it. Each check compares a screenshot with the robot against one of the same scene with the
robot hidden: thousands of pixels differ when the robot is drawn, none when WebGL fails.
"""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
from types import SimpleNamespace

import example_robot_data as erd
import numpy as np
import pinocchio as pin
import pytest
from conftest import require_chromium
from PIL import Image

from crocopy.models.display.meshcat_display import MeshcatDisplay

pytestmark = pytest.mark.usefixtures("chromium")
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
    "--virtual-time-budget=5000",
]


def _chromium() -> str:
    return require_chromium()


def _screenshot(html: str, png: str, profile: str, attempts: int = 2) -> np.ndarray:
    """Render ``html`` headless and return the RGB screenshot; retries once on a hang."""
    cmd = [_chromium(), *FLAGS, f"--user-data-dir={profile}", f"--screenshot={png}", f"file://{html}"]
    for _ in range(attempts):
        shutil.rmtree(profile, ignore_errors=True)
        proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
        try:
            proc.wait(timeout=90)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
            continue
        if os.path.exists(png):
            return np.asarray(Image.open(png).convert("RGB"), dtype=int)
    pytest.fail(f"chromium produced no screenshot of {html}")


def _differing_pixels(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    assert a.shape == b.shape == (600, 800, 3)
    return np.abs(a - b).sum(axis=2) > 30


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
