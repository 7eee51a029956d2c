"""Meshcat display of robot trajectories (Crocoddyl-compatible ``MeshcatDisplay``).

The display is built on :class:`pinocchio.visualize.MeshcatVisualizer` (mesh loading and
materials) and :mod:`meshcat` (scene graph, animations, static HTML). It shows

* the robot, one pose per node of a trajectory ``xs`` (only ``q = x[:nq]`` is used);
* the floor (a thin grey box under ``z = 0``, or under the motion if it goes lower, reaching past
  the viewer's far plane so that it ends on a straight horizon; meshcat's grid is hidden);
* frame trajectories ``ps`` as poly-lines;
* contact forces ``fs`` as arrows and their friction cones.

Framing: unless a camera placement ``cameraTF`` is given, every trajectory shown or exported is
framed whole: the camera looks at the box holding the robot at all its nodes and the floor covers
that box (:meth:`MeshcatDisplay.fit_view`, :mod:`.framing`). The live display only widens the
view (a solver's iterates do not make the camera jump back and forth). meshcat's orbit controls
always turn about the viewer's origin, so the scene node ``/meshcat`` is shifted by minus the
camera's target (everything drawn by this class lives under it); meshcat's grid and axes are hidden.

Force arrows: an arrow's length is ``|f| * force_scale``. With ``forceScale = None`` (default)
``force_scale = forceFraction * robot_size / max |f|``, the maximum over the trajectory shown: the
longest arrow is ``forceFraction`` (0.4) times the robot's size (largest side of its box at
``q0``). Setting ``forceScale`` (metres per newton) fixes the scale instead.

Scene layout (meshcat paths under ``/meshcat``)::

    pinocchio/visuals/<geometry>          rigid placement oMg of the geometry
    pinocchio/visuals/<geometry>/shape    the mesh, with its static (possibly mirroring) scale
    floor                                 the floor box
    forces/<key>                          arrow at the contact point, +y along the force
    cones/<key>                           friction cone, apex at the contact point
    trajectories/<name>                   poly-line of a frame's positions

Keeping the mesh scale on a static child makes recorded animations exact: meshcat's animation
tracks store only position and quaternion, which cannot encode a reflection (Talos' right limbs
use ``meshScale = (1, -1, 1)``).

Facts handled (meshcat 0.3.2): the server is a subprocess on 127.0.0.1 that this class kills in
:meth:`MeshcatDisplay.close`; every request has a receive timeout so a dead server raises
:class:`TimeoutError` instead of hanging; Collada meshes whose sub-meshes mix textured and
untextured primitives (ANYmal's trunk) are invisible in the browser and are sent as plain
triangles taken from the collision library's mesh instead.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from typing import Any

import meshcat
import meshcat.geometry as mg
import numpy as np
import pinocchio as pin
import zmq
from pinocchio.visualize import MeshcatVisualizer

from crocopy.callbacks.display import DisplayAbstract

from .framing import box_corners, camera_placement, floor_extent, motion_bounds, motion_points, robot_size
from .meshes import has_mixed_texcoords, plain_mesh
from .server import DEFAULT_TIMEOUT, start_meshcat_server, stop_meshcat_server
from .solver_reading import configurations, force_trajectories, frame_trajectories, trajectory_frame_names

__all__ = ["MeshcatDisplay", "start_meshcat_server", "stop_meshcat_server"]


def _rgb_int(rgba: Sequence[float]) -> int:
    return int(rgba[0] * 255) * 65536 + int(rgba[1] * 255) * 256 + int(rgba[2] * 255)


def _rotation_y_to(direction: np.ndarray) -> np.ndarray:
    """A rotation matrix whose second column (local +y) is the unit vector ``direction``."""
    y = direction / np.linalg.norm(direction)
    helper = np.array([1.0, 0.0, 0.0]) if abs(y[0]) < 0.9 else np.array([0.0, 0.0, 1.0])
    x = np.cross(y, helper)
    x /= np.linalg.norm(x)
    z = np.cross(x, y)
    return np.column_stack([x, y, z])


def _homogeneous(rotation: np.ndarray, translation: np.ndarray) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3] = rotation
    T[:3, 3] = translation
    return T


class MeshcatDisplay(DisplayAbstract):
    """Display robot trajectories in meshcat, with Crocoddyl's ``MeshcatDisplay`` interface.

    Parameters
    ----------
    robot : pinocchio.RobotWrapper
        Robot with ``model``, ``visual_model`` and ``collision_model`` (e.g. from
        ``example_robot_data.load``).
    rate : float
        Display rate in Hz; ``-1`` plays in real time using the node durations ``dts``.
    freq : int
        Display every ``freq``-th node.
    cameraTF : array_like, optional
        Camera rig placement: ``[x, y, z, qx, qy, qz, qw]`` or a 4x4 homogeneous matrix.
    floor : bool
        Draw a floor under ``z = 0``.
    frameNames : list of str, optional
        Frames whose trajectories are drawn in addition to those found in a solver's problem.
    visibility : bool
        Initial visibility of forces, cones and trajectories.
    openDisplay : bool
        Open the viewer in a web browser (``False`` for headless use and HTML export).
    viewer : meshcat.Visualizer, optional
        Existing visualizer to draw into; by default a local server is started (and ended by
        :meth:`close`).
    timeout : float
        Seconds a request to the meshcat server may take before :class:`TimeoutError`.

    Attributes
    ----------
    robot_size : float
        Largest side (m) of the robot's box at ``q0``.
    force_scale : float
        Metres of arrow per newton used for the forces shown last (see the module docstring).
    auto_frame : bool
        Frame every trajectory shown or exported (``True`` unless ``cameraTF`` was given).
    """

    forceScale: float | None = None  # metres of arrow per newton; None: the longest arrow is forceFraction x size
    forceFraction = 0.4
    coneHeight = 0.1
    forceColor = 0xD62728
    coneColor = 0x2CA02C
    trajColors = (0x1F77B4, 0xFF7F0E, 0x9467BD, 0x8C564B, 0xE377C2, 0x17BECF)

    def __init__(
        self,
        robot: Any,
        rate: float = -1,
        freq: int = 1,
        cameraTF: Sequence[float] | np.ndarray | None = None,
        floor: bool = True,
        frameNames: Sequence[str] | None = None,
        visibility: bool = True,
        openDisplay: bool = True,
        viewer: meshcat.Visualizer | None = None,
        timeout: float = DEFAULT_TIMEOUT,
    ) -> None:
        if int(freq) < 1:
            raise ValueError(f"freq must be a positive integer, got {freq}")
        self.robot = robot
        self.rate = float(rate)
        self.freq = int(freq)
        self.floor = bool(floor)
        self.frameNames = list(frameNames) if frameNames is not None else []
        self.visibility = bool(visibility)
        self.model = robot.model
        self.data = self.model.createData()
        self.visual_model = robot.visual_model
        self.visual_data = pin.GeometryData(self.visual_model)
        q0 = getattr(robot, "q0", None)
        self.q0 = pin.neutral(self.model) if q0 is None else np.asarray(q0, dtype=float)
        self.robot_size = robot_size(self.model, self.visual_model, self.q0)
        self.force_scale = float(self.forceScale or 0.0)
        self.auto_frame = cameraTF is None
        self.view_bounds: tuple[np.ndarray, np.ndarray] | None = None
        self._camera = (np.zeros(3), np.array([3.0, 0.0, 1.0]))
        self._owns_viewer = viewer is None
        self.viewer = start_meshcat_server(timeout=timeout) if viewer is None else viewer
        self.viz = MeshcatVisualizer(self.model, robot.collision_model, self.visual_model)
        try:
            self.guarded(self._build_scene, cameraTF)
        except BaseException:
            self.close()
            raise
        self._forceKeys: list[str] = []
        self._force_rest: dict[str, tuple[np.ndarray, np.ndarray]] = {}
        self._trajNames: list[str] = []
        if openDisplay:
            self.viewer.open()

    # ------------------------------------------------------------------ scene construction
    def guarded(self, fn: Any, *args: Any) -> Any:
        """Run ``fn`` and turn a meshcat server timeout into a clear :class:`TimeoutError`."""
        try:
            return fn(*args)
        except zmq.error.Again as e:
            raise TimeoutError(
                "the meshcat server did not answer in time (is it running? see MeshcatDisplay(timeout=...))"
            ) from e

    def _build_scene(self, cameraTF: Any) -> None:
        viz = self.viz
        viz.initViewer(viewer=self.viewer)
        viz.viewerRootNodeName = "pinocchio"
        viz.viewerVisualGroupName = "pinocchio/visuals"
        viz.viewerCollisionGroupName = "pinocchio/collisions"
        viz.viewerFramesGroupName = "pinocchio/frames"
        self._nodes: list[tuple[int, str]] = []
        for gid, go in enumerate(self.visual_model.geometryObjects):
            parent = viz.getViewerNodeName(go, pin.GeometryType.VISUAL)
            child = parent + "/shape"
            if go.meshPath and has_mixed_texcoords(go.meshPath) and hasattr(go.geometry, "num_tris"):
                vertices, faces = plain_mesh(go)
                material = mg.MeshPhongMaterial(color=_rgb_int(go.meshColor))
                self.viewer[child].set_object(mg.TriangularMeshGeometry(vertices, faces), material)
            else:
                shaped = go.copy()
                shaped.name = go.name + "/shape"
                viz.loadViewerGeometryObject(shaped, pin.GeometryType.VISUAL)
            self.viewer[child].set_transform(np.diag(np.append(np.asarray(go.meshScale, dtype=float), 1.0)))
            self._nodes.append((gid, parent))
        self.viewer["/Grid"].set_property("visible", False)
        self.viewer["/Axes"].set_property("visible", False)
        self.set_robot(self.viewer, self.q0)
        if cameraTF is not None:
            self.viewer["/Cameras/default"].set_transform(self._camera_matrix(cameraTF))
            lo, hi = motion_bounds(self.model, self.visual_model, [self.q0])
            self._set_floor(lo, hi)
        else:
            self.fit_view([self.q0])

    @staticmethod
    def _camera_matrix(cameraTF: Any) -> np.ndarray:
        arr = np.asarray(cameraTF, dtype=float)
        if arr.shape == (4, 4):
            return arr
        if arr.shape == (7,):
            return pin.XYZQUATToSE3(arr).homogeneous
        raise ValueError(f"cameraTF must be a 7-vector [x, y, z, qx, qy, qz, qw] or a 4x4 matrix, got {arr.shape}")

    @staticmethod
    def _point(name: str, value: Sequence[float] | np.ndarray) -> np.ndarray:
        p = np.asarray(value, dtype=float).reshape(-1)
        if p.shape != (3,) or not np.all(np.isfinite(p)):
            raise ValueError(f"{name} must be 3 finite numbers (shape (3,)), got shape {p.shape}")
        return p

    def _place_camera(self, target: np.ndarray, position: np.ndarray) -> None:
        # meshcat's orbit controls always look at the viewer's origin: the scene (/meshcat) is
        # shifted by -target instead, and the camera sits at position - target. The camera lives in
        # meshcat's y-up frame, where world (x, y, z) is (x, z, -y).
        offset = position - target
        self.viewer.set_transform(_homogeneous(np.eye(3), -target))
        self.viewer["/Cameras/default"].set_transform(np.eye(4))
        self.viewer["/Cameras/default/rotated/<object>"].set_property("position", [offset[0], offset[2], -offset[1]])
        self._camera = (target.copy(), position.copy())

    def setCameraPosition(self, position: Sequence[float] | np.ndarray) -> None:
        """Put the camera at ``position`` (world frame, z up); it keeps looking at its target."""
        p = self._point("position", position)
        self.guarded(self._place_camera, self._camera[0], p)

    def setCameraTarget(self, target: Sequence[float] | np.ndarray) -> None:
        """Make the camera look at ``target`` (world frame) from where it is."""
        t = self._point("target", target)
        self.guarded(self._place_camera, t, self._camera[1])

    def _set_floor(self, lo: np.ndarray, hi: np.ndarray) -> None:
        if not self.floor:
            return
        centre, sides = floor_extent(lo, hi, self.robot_size)
        self.viewer["floor"].set_object(mg.Box([sides[0], sides[1], 0.02]), mg.MeshPhongMaterial(color=0xB0B0B0))
        self.viewer["floor"].set_transform(_homogeneous(np.eye(3), centre - np.array([0.0, 0.0, 0.0105])))

    def fit_view(self, xs: Sequence[np.ndarray], grow: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """Point the camera at the whole motion ``xs`` and size the floor under it.

        Parameters
        ----------
        xs : list of ndarray, each (nx,) with nx >= nq
            States (or configurations) of the motion.
        grow : bool
            Frame the union of this motion and the ones framed before (the view only widens).

        Returns
        -------
        lo, hi : ndarray (3,)
            Corners of the framed box (world frame): it holds the robot at every node.
        """
        points = motion_points(self.model, self.visual_model, self.configurations(xs))
        lo, hi = points.min(axis=0), points.max(axis=0)
        if grow and self.view_bounds is not None:
            old_lo, old_hi = self.view_bounds
            if np.all(lo >= old_lo) and np.all(hi <= old_hi):
                return old_lo, old_hi
            points = np.concatenate([points, box_corners(old_lo, old_hi)])
            lo, hi = np.minimum(lo, old_lo), np.maximum(hi, old_hi)
        self.view_bounds = (lo, hi)
        target, position = camera_placement(points)
        self.guarded(self._place_camera, target, position)
        self.guarded(self._set_floor, lo, hi)
        return lo, hi
        self.view_bounds = (lo, hi)
        target, position = camera_placement(lo, hi)
        self.guarded(self._place_camera, target, position)
        self.guarded(self._set_floor, lo, hi)
        return lo, hi

    def set_robot(self, target: Any, q: np.ndarray) -> None:
        """Place every visual geometry at configuration ``q`` (``target``: viewer or animation frame)."""
        q = np.asarray(q, dtype=float).reshape(-1)
        if q.shape[0] != self.model.nq:
            raise ValueError(f"q must have shape ({self.model.nq},), got {q.shape}")
        pin.forwardKinematics(self.model, self.data, q)
        pin.updateGeometryPlacements(self.model, self.data, self.visual_model, self.visual_data)
        for gid, node in self._nodes:
            target[node].set_transform(self.visual_data.oMg[gid].homogeneous)

    # ------------------------------------------------------------------ forces and trajectories
    def _force_world(self, item: dict) -> tuple[np.ndarray, np.ndarray]:
        """Contact point and force (world coordinates) of one force record."""
        oMf = item["oMf"]
        f = item["f"]
        lin = np.asarray(f.linear if hasattr(f, "linear") else np.asarray(f)[:3], dtype=float)
        if item.get("type", pin.ReferenceFrame.LOCAL_WORLD_ALIGNED) == pin.ReferenceFrame.LOCAL:
            lin = oMf.rotation @ lin
        return np.asarray(oMf.translation, dtype=float), lin

    def ensure_force_nodes(self, fs: Sequence[Sequence[dict]]) -> None:
        """Create one arrow (and cone) node per contact key seen in the force trajectory ``fs``."""
        keys = sorted({str(item["key"]) for node in fs for item in node})
        if self.forceScale is not None:
            self.force_scale = float(self.forceScale)
        else:
            norms = [float(np.linalg.norm(self._force_world(item)[1])) for node in fs for item in node]
            longest = max(norms, default=0.0)
            self.force_scale = self.forceFraction * self.robot_size / longest if longest > 1e-9 else 0.0
        for node in reversed(fs):  # a contact is first drawn where it starts (see set_forces)
            for key, (arrow_T, _, cone_T, _) in self._force_poses(node).items():
                self._force_rest[key] = (arrow_T, cone_T)
        for key in keys:
            if key in self._forceKeys:
                continue
            self._forceKeys.append(key)
            arrow, cone = self.viewer["forces"][key], self.viewer["cones"][key]
            red = mg.MeshPhongMaterial(color=self.forceColor)
            arrow["shaft"].set_object(mg.Cylinder(0.8, 0.008), red)
            arrow["shaft"].set_transform(_homogeneous(np.eye(3), np.array([0.0, 0.4, 0.0])))
            arrow["head"].set_object(mg.Cylinder(0.2, radiusTop=0.0, radiusBottom=0.02), red)
            arrow["head"].set_transform(_homogeneous(np.eye(3), np.array([0.0, 0.9, 0.0])))
            green = mg.MeshPhongMaterial(color=self.coneColor, transparent=True, opacity=0.35)
            cone["shape"].set_object(mg.Cylinder(1.0, radiusTop=1.0, radiusBottom=0.0), green)
            cone["shape"].set_transform(_homogeneous(np.eye(3), np.array([0.0, 0.5, 0.0])))
        self.setVisibility("forces", self.visibility)
        self.setVisibility("cones", self.visibility)

    def _force_poses(self, node: Sequence[dict]) -> dict[str, tuple[np.ndarray, np.ndarray, np.ndarray]]:
        """Per key: (rigid arrow pose, arrow scale, rigid cone pose with scale folded separately)."""
        poses = {}
        for item in node:
            p, f = self._force_world(item)
            norm = float(np.linalg.norm(f))
            key = str(item["key"])
            R = np.asarray(item.get("R", np.eye(3)), dtype=float)
            mu = float(item.get("mu", 0.7))
            arrow_T = _homogeneous(_rotation_y_to(f) if norm > 1e-9 else np.eye(3), p)
            cone_T = _homogeneous(_rotation_y_to(R[:, 2]), p)
            length = max(norm * self.force_scale, 1e-6)
            h = self.coneHeight
            poses[key] = (arrow_T, np.array([1.0, length, 1.0]), cone_T, np.array([mu * h, h, mu * h]))
        return poses

    def set_forces(self, target: Any, node: Sequence[dict], animation: bool) -> None:
        """Place the force arrows of one node's contacts (``target``: viewer or animation frame).

        A contact that is not active at this node shrinks to nothing where it was last drawn (or
        where it starts), so that animations do not slide it in from elsewhere.
        """
        poses = self._force_poses(node)
        tiny = np.full(3, 1e-6)
        for key in self._forceKeys:
            if key in poses:
                arrow_T, arrow_s, cone_T, cone_s = poses[key]
                self._force_rest[key] = (arrow_T, cone_T)
            else:
                (arrow_T, cone_T), arrow_s, cone_s = self._force_rest.get(key, (np.eye(4), np.eye(4))), tiny, tiny
            for name, T, s in (("forces", arrow_T, arrow_s), ("cones", cone_T, cone_s)):
                if animation:
                    target[name][key].set_transform(T)
                    target[name][key].set_property("scale", "vector3", s.tolist())
                else:
                    target[name][key].set_transform(T @ np.diag(np.append(s, 1.0)))

    def _draw_trajectories(self, ps: dict) -> None:
        for i, (name, points) in enumerate(ps.items()):
            pts = np.asarray(points, dtype=float).reshape(-1, 3)
            if pts.shape[0] < 2:
                continue
            color = self.trajColors[i % len(self.trajColors)]
            line = mg.Line(mg.PointsGeometry(pts.T.astype(np.float32)), mg.LineBasicMaterial(color=color, linewidth=3))
            self.viewer["trajectories"][str(name)].set_object(line)
            if str(name) not in self._trajNames:
                self._trajNames.append(str(name))
        self.setVisibility("trajectories", self.visibility)

    # ------------------------------------------------------------------ Crocoddyl's interface
    def displayContactForce(self, f: Sequence[dict]) -> None:
        """Draw the contact forces (and friction cones) of one node (list of force records)."""
        self.guarded(self.ensure_force_nodes, [f])
        self.guarded(self.set_forces, self.viewer, f, False)

    def displayFrictionCone(self, f: Sequence[dict]) -> None:
        """Draw the friction cones of one node (same records as :meth:`displayContactForce`)."""
        self.displayContactForce(f)

    def displayFramePoses(self, ps: dict) -> None:
        """Draw frame trajectories: ``{name: [[x, y, z], ...]}``."""
        self.guarded(self._draw_trajectories, ps)

    def displayThrustForce(self, f: Any) -> None:
        """Thrust arrows are not drawn (accepted for interface compatibility)."""

    def setVisibility(self, name: str, status: bool) -> None:
        """Show or hide ``"robot"``, ``"floor"``, ``"forces"``, ``"cones"``, ``"trajectories"`` or a meshcat path."""
        path = {"robot": "pinocchio"}.get(name, name)
        self.guarded(self.viewer[path].set_property, "visible", bool(status))

    def display(
        self,
        xs: Sequence[np.ndarray],
        us: Sequence[np.ndarray] = (),
        rs: Sequence[Any] = (),
        ps: dict | Sequence = (),
        pds: Sequence[Any] = (),
        fs: Sequence[Sequence[dict]] = (),
        ss: Sequence[Any] = (),
        dts: Sequence[float] = (),
        factor: float = 1.0,
    ) -> None:
        """Play a state trajectory (with forces ``fs`` and frame trajectories ``ps``).

        Parameters
        ----------
        xs : list of ndarray, each (nx,) with nx >= nq
            States; the configuration is ``x[:nq]``.
        us, rs, pds, ss
            Accepted for Crocoddyl compatibility (torques, thrusts, ...); not drawn.
        ps : dict
            Frame trajectories ``{name: [[x, y, z], ...]}``.
        fs : list (one per node) of lists of force records
            Records are dicts with ``key``, ``oMf`` (pin.SE3), ``f`` (pin.Force), optionally
            ``R`` (3x3 cone orientation), ``mu`` and ``type`` (pin.ReferenceFrame of ``f``).
        dts : list of float
            Node durations for real-time playback when ``rate == -1``.
        factor : float
            Slow-down factor applied to the playback time.
        """
        qs = self.configurations(xs)
        if self.auto_frame:
            self.fit_view(xs, grow=True)
        if ps:
            self.displayFramePoses(dict(ps))
        if fs:
            self.guarded(self.ensure_force_nodes, fs)
        for i in range(0, len(qs), self.freq):
            start = time.time()
            self.guarded(self.set_robot, self.viewer, qs[i])
            if fs and i < len(fs):
                self.guarded(self.set_forces, self.viewer, fs[i], False)
            if self.rate > 0:
                wait = factor / self.rate
            else:
                wait = factor * float(np.sum(dts[i : i + self.freq])) if len(dts) else 0.0
            remaining = wait - (time.time() - start)
            if remaining > 0:
                time.sleep(remaining)

    def displayFromSolver(self, solver: Any, factor: float = 1.0) -> None:
        """Play a solver's current trajectory, with its contact forces and frame trajectories."""
        self.display(
            solver.xs,
            ps=self.getFrameTrajectoryFromSolver(solver),
            fs=self.getForceTrajectoryFromSolver(solver),
            dts=self.getDurationSequenceFromSolver(solver),
            factor=factor,
        )

    def exportHTML(
        self,
        xs: Sequence[np.ndarray],
        path: str,
        fs: Sequence[Sequence[dict]] = (),
        ps: dict | None = None,
        dts: Sequence[float] = (),
        factor: float = 1.0,
        fps: int = 30,
        repetitions: int = 1000,
    ) -> str:
        """Record ``xs`` as a meshcat animation and write a self-contained HTML file.

        See :func:`crocopy.models.display.html.export_animation`; returns ``path``.
        """
        from .html import export_animation

        return export_animation(self, xs, path, fs=fs, ps=ps, dts=dts, factor=factor, fps=fps, repetitions=repetitions)

    def exportHTMLFromSolver(self, solver: Any, path: str, factor: float = 1.0, fps: int = 30) -> str:
        """Export a solver's trajectory (forces, cones, frame trajectories) as a static HTML file."""
        return self.exportHTML(
            solver.xs,
            path,
            fs=self.getForceTrajectoryFromSolver(solver),
            ps=self.getFrameTrajectoryFromSolver(solver),
            dts=self.getDurationSequenceFromSolver(solver),
            factor=factor,
            fps=fps,
        )

    # ------------------------------------------------------------------ reading a solver
    def init(self, solver: Any) -> None:
        """Collect the frames to draw from the solver's problem (contacts and frame residuals)."""
        self.frameTrajNames = trajectory_frame_names(self.model, self.frameNames, solver)

    def getJointTorquesTrajectoryFromSolver(self, solver: Any) -> list[np.ndarray]:
        """The controls ``us`` of the solver (copies)."""
        return [np.array(u, dtype=float) for u in solver.us]

    def getThrustTrajectoryFromSolver(self, solver: Any) -> list[Any]:
        """Thrust trajectories are not extracted (empty list)."""
        return []

    def getFrameTrajectoryFromSolver(self, solver: Any) -> dict[str, list[list[float]]]:
        """Positions of the frames found by :meth:`init`: ``{frame name: [[x, y, z], ...]}``."""
        if not hasattr(self, "frameTrajNames"):
            self.init(solver)
        return frame_trajectories(self.model, self.data, self.frameTrajNames, self.configurations(solver.xs))

    def getForceTrajectoryFromSolver(self, solver: Any) -> list[list[dict]]:
        """Contact (and impulse) forces of every node (see :func:`.solver_reading.force_trajectories`)."""
        return force_trajectories(self.model, self.data, solver, self.configurations(solver.xs))

    # ------------------------------------------------------------------ helpers and lifetime
    def configurations(self, xs: Sequence[np.ndarray]) -> list[np.ndarray]:
        """The configurations ``q`` (first ``nq`` entries) of the states ``xs``, checked."""
        return configurations(self.model.nq, xs)

    def url(self) -> str:
        """Address of the live viewer."""
        return self.viewer.url()

    def close(self) -> None:
        """End the meshcat server started by this display (no-op for a viewer passed in)."""
        if self._owns_viewer and self.viewer is not None:
            stop_meshcat_server(self.viewer)
            self.viewer = None

    def __enter__(self) -> MeshcatDisplay:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()
