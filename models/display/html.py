"""Static HTML export of robot trajectories (meshcat animation + ``static_html``).

A trajectory is recorded as a :class:`meshcat.animation.Animation`: node ``i`` becomes the key frame
``round(t_i * fps)`` with ``t_i = factor * sum(dts[:i])`` (of the nodes falling on one frame, the
closest to it). The scene the meshcat server holds is then written by :func:`.page.write_page` as
one compact HTML file (each mesh once, compact animation tracks) that plays from ``file://`` with
no server and no network. Unless the display was given a camera, the camera and the floor frame
the whole trajectory first (:meth:`MeshcatDisplay.fit_view`).

Typical use, headless (no browser is opened; the local meshcat server is ended afterwards)::

    from crocopy.models import export_html
    export_html(robot, solver.xs, "jump.html", dts=[m.dt for m in problem.runningModels])
"""

from __future__ import annotations

import contextlib
import io
import os
from collections.abc import Sequence
from typing import Any

import numpy as np
from meshcat.animation import Animation

from .meshcat_display import MeshcatDisplay
from .page import keyed_animation, meshcat_commands, read_page, write_page
from .server import connect_spawned, stop_meshcat_server

__all__ = ["record_animation", "export_animation", "export_html", "export_html_from_solver", "static_html_commands"]


def _key_frames(n: int, dts: Sequence[float], factor: float, fps: int) -> list[tuple[int, int]]:
    """(node index, animation frame) pairs: per frame, the node whose time is closest to it."""
    if len(dts) == 0:
        times = np.arange(n, dtype=float) / fps
    else:
        d = np.asarray(dts, dtype=float).reshape(-1)
        if d.shape[0] < n - 1:
            raise ValueError(f"dts must have at least len(xs) - 1 = {n - 1} entries, got {d.shape[0]}")
        if np.any(d < 0):
            raise ValueError("dts must be non-negative")
        times = np.concatenate([[0.0], np.cumsum(d[: n - 1])])
    exact = times * factor * fps
    frames = np.rint(exact).astype(int)
    keys: list[tuple[int, int]] = []
    for i, frame in enumerate(frames):
        if keys and keys[-1][1] == frame:
            if abs(exact[i] - frame) < abs(exact[keys[-1][0]] - frame):
                keys[-1] = (i, int(frame))
        else:
            keys.append((i, int(frame)))
    return keys


def record_animation(
    display: MeshcatDisplay,
    xs: Sequence[np.ndarray],
    fs: Sequence[Sequence[dict]] = (),
    dts: Sequence[float] = (),
    factor: float = 1.0,
    fps: int = 30,
) -> Animation:
    """Record a trajectory (robot, force arrows, friction cones) into a meshcat animation.

    Parameters
    ----------
    display : MeshcatDisplay
        Display whose scene is animated.
    xs : list of ndarray
        States (``x[:nq]`` is the configuration).
    fs : list of lists of force records, optional
        Contact forces per node (see :meth:`MeshcatDisplay.display`).
    dts : list of float, optional
        Node durations; by default one animation frame per node.
    factor : float
        Slow-down factor of the playback.
    fps : int
        Animation frame rate.
    """
    if int(fps) < 1:
        raise ValueError(f"fps must be a positive integer, got {fps}")
    if factor <= 0:
        raise ValueError(f"factor must be positive, got {factor}")
    qs = display.configurations(xs)
    if fs:
        display.guarded(display.ensure_force_nodes, fs)
    anim = Animation(default_framerate=int(fps))
    for i, frame in _key_frames(len(qs), dts, factor, int(fps)):
        with anim.at_frame(display.viewer, frame) as target:
            display.set_robot(target, qs[i])
            if fs and i < len(fs):
                display.set_forces(target, fs[i], True)
    return anim


def export_animation(
    display: MeshcatDisplay,
    xs: Sequence[np.ndarray],
    path: str | os.PathLike,
    fs: Sequence[Sequence[dict]] = (),
    ps: dict | None = None,
    dts: Sequence[float] = (),
    factor: float = 1.0,
    fps: int = 30,
    repetitions: int = 1000,
) -> str:
    """Write the trajectory as one self-contained HTML file and return its path.

    The scene shows the first state; with more than one state the animation plays on load and
    repeats ``repetitions`` times. ``ps`` draws frame trajectories as lines. The camera and the
    floor frame the whole trajectory when ``display.auto_frame`` is true.
    """
    qs = display.configurations(xs)
    if display.auto_frame:
        display.fit_view(xs)
    if ps:
        display.displayFramePoses(dict(ps))
    if fs:
        display.guarded(display.ensure_force_nodes, fs)
        display.guarded(display.set_forces, display.viewer, fs[0], False)
    display.guarded(display.set_robot, display.viewer, qs[0])
    # An empty animation replaces the one a previous export left in the server's scene.
    anim = record_animation(display, xs, fs=fs, dts=dts, factor=factor, fps=fps) if len(qs) > 1 else Animation()
    display.guarded(display.viewer.set_animation, anim, len(qs) > 1, int(repetitions))
    html = display.guarded(display.viewer.static_html)
    title = f"crocopy: {os.path.splitext(os.path.basename(os.fspath(path)))[0]}"
    return write_page(meshcat_commands(html), path, title=title)


def _quiet_display(robot: Any, display_kwargs: dict) -> MeshcatDisplay:
    """A display without browser whose short-lived server's URL is not printed."""
    display_kwargs.setdefault("openDisplay", False)
    with contextlib.redirect_stdout(io.StringIO()):
        return MeshcatDisplay(robot, **display_kwargs)


def export_html(
    robot: Any,
    xs: Sequence[np.ndarray],
    path: str | os.PathLike,
    fs: Sequence[Sequence[dict]] = (),
    ps: dict | None = None,
    dts: Sequence[float] = (),
    factor: float = 1.0,
    fps: int = 30,
    **display_kwargs: Any,
) -> str:
    """Export a trajectory of ``robot`` to a static HTML file without opening a browser.

    A temporary local meshcat server is started and always ended. ``display_kwargs`` go to
    :class:`MeshcatDisplay` (``floor``, ``cameraTF``, ``visibility``, ``timeout``, ...).
    """
    with _quiet_display(robot, display_kwargs) as display:
        return export_animation(display, xs, path, fs=fs, ps=ps, dts=dts, factor=factor, fps=fps)


def export_html_from_solver(
    robot: Any, solver: Any, path: str | os.PathLike, factor: float = 1.0, fps: int = 30, **display_kwargs: Any
) -> str:
    """Export a solver's trajectory (with contact forces, cones and frame trajectories) to HTML."""
    with _quiet_display(robot, display_kwargs) as display:
        return display.exportHTMLFromSolver(solver, os.fspath(path), factor=factor, fps=fps)


def export_html_on_server(
    robot: Any, solver: Any, path: str | os.PathLike, spawned: tuple, **display_kwargs: Any
) -> str:
    """:func:`export_html_from_solver` through a server started ahead (``spawned``, from
    :func:`~crocopy.models.display.server.spawn_meshcat_server`, e.g. on a thread while the solve runs), which
    is ended afterwards."""
    viewer = connect_spawned(spawned)
    try:
        return export_html_from_solver(robot, solver, path, viewer=viewer, **display_kwargs)
    finally:
        stop_meshcat_server(viewer)


def static_html_commands(path: str | os.PathLike) -> list[dict]:
    """Decode the meshcat commands embedded in an exported HTML file (for inspection and tests).

    Returns the list of command dicts (``type`` is ``set_object``, ``set_transform``,
    ``set_property`` or ``set_animation``; ``path`` is the meshcat path), with the meshes and
    arrays stored once in the page put back in every command that uses them. Animation tracks
    are given as meshcat writes them (``keys``: ``{"time", "value"}``), with the float32 values
    the page stores and without the keys it dropped inside runs of equal values.
    """
    return [keyed_animation(c) for c in read_page(path)]
