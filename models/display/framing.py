"""Where the robot goes during a motion, and a camera and floor that show all of it.

Points. Every visual geometry ``g`` lies inside its local axis-aligned box (Coal's
``computeLocalAABB``, in the geometry's frame). At node ``i`` the box's eight corners are at
``oMg_i * corner``; these points over all nodes and geometries enclose the whole robot at every
node (not only its frames' origins). The motion's box is their axis-aligned box.

Camera. meshcat's default camera is perspective with a vertical field of view of 75 degrees. It
looks along a fixed direction: from the side of the motion's longer horizontal axis, turned by
:data:`AZIMUTH` towards its positive end and raised by :data:`ELEVATION`. With ``(u, v, w)`` a
point's coordinates (right, up, forward) from the box's centre, ``t_h, t_v`` the tangents of the
half fields of view shrunk by :data:`MARGIN` (for a window of aspect :data:`ASPECT`), and the camera
at ``d`` behind the centre shifted by ``(a, b)``, every point is in view when
``|u - a| <= t_h (w + d)`` and ``|v - b| <= t_v (w + d)``. The smallest such ``d`` is
``max(d_h, d_v)`` with ``d_h = (max(u - t_h w) - min(u + t_h w)) / (2 t_h)`` (likewise ``d_v``);
the shifts then centre the points' view angles (``max((u - a) / (w + d)) = -min(...)``, found by
bisection). The motion fills the view along its binding axis and is centred in both. Wider
windows only add room at the sides.

Floor. A box under ``z = 0`` (or under the motion, see :func:`floor_extent`) covering the motion's
horizontal extent plus :data:`FLOOR_BORDER` times the robot's size on every side (at least
:data:`FLOOR_MIN_BORDER`): it reaches past meshcat's far clipping plane (100 m), which cuts it
along one straight horizon, so it reads as ground rather than as a slab with edges and corners.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pinocchio as pin

__all__ = [
    "geometry_corners",
    "box_corners",
    "motion_points",
    "motion_bounds",
    "robot_size",
    "camera_placement",
    "floor_extent",
    "FOVY_DEG",
    "ASPECT",
    "MARGIN",
    "ELEVATION",
    "AZIMUTH",
    "FLOOR_BORDER",
    "FLOOR_MIN_BORDER",
    "FLOOR_SINK",
]

FOVY_DEG = 75.0
"""Vertical field of view of meshcat's default camera (degrees)."""
ASPECT = 4.0 / 3.0
"""Narrowest window aspect ratio (width / height) the framing is computed for."""
MARGIN = 0.9
"""Fraction of the view (in each direction) the motion's box may fill."""
ELEVATION = np.deg2rad(22.0)
"""Height of the camera above the box's centre, as an angle above the horizontal."""
AZIMUTH = np.deg2rad(20.0)
"""Turn of the camera from the side view towards the motion's positive direction."""
FLOOR_BORDER = 25.0
"""Floor margin around the motion, in robot sizes."""
FLOOR_MIN_BORDER = 150.0
"""Smallest floor margin around the motion (m): beyond the viewer's 100 m far plane."""
FLOOR_SINK = 0.1
"""How far (in robot sizes) the motion may reach under ``z = 0`` before the floor moves under it."""


def box_corners(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """The eight corners (8, 3) of the axis-aligned box ``[lo, hi]``."""
    return np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])], dtype=float)


def geometry_corners(visual_model: pin.GeometryModel) -> np.ndarray:
    """Corners (n, 8, 3) of each geometry's local axis-aligned box, in the geometry's frame.

    Geometries whose bounds cannot be computed count as points at their frame's origin.
    """
    corners = np.zeros((len(visual_model.geometryObjects), 8, 3))
    for i, go in enumerate(visual_model.geometryObjects):
        try:
            go.geometry.computeLocalAABB()
            box = go.geometry.aabb_local
            lo, hi = np.asarray(box.min_, dtype=float), np.asarray(box.max_, dtype=float)
        except (AttributeError, RuntimeError, TypeError):
            continue
        if np.all(np.isfinite(lo)) and np.all(np.isfinite(hi)) and np.all(lo <= hi):
            corners[i] = box_corners(lo, hi)
    return corners


def motion_points(model: pin.Model, visual_model: pin.GeometryModel, qs: Sequence[np.ndarray]) -> np.ndarray:
    """Points (N, 3) enclosing every geometry at every configuration ``qs`` (world frame).

    Without visual geometries: the origins of all frames at every configuration.
    """
    data = model.createData()
    corners = geometry_corners(visual_model)
    gdata = pin.GeometryData(visual_model)
    points = []
    for q in qs:
        pin.forwardKinematics(model, data, np.asarray(q, dtype=float))
        if len(corners):
            pin.updateGeometryPlacements(model, data, visual_model, gdata)
            points += [c @ oMg.rotation.T + oMg.translation for c, oMg in zip(corners, gdata.oMg)]
        else:
            pin.updateFramePlacements(model, data)
            points.append(np.array([oMf.translation for oMf in data.oMf]))
    if not points:
        raise ValueError("qs must contain at least one configuration")
    return np.concatenate(points)


def motion_bounds(
    model: pin.Model, visual_model: pin.GeometryModel, qs: Sequence[np.ndarray]
) -> tuple[np.ndarray, np.ndarray]:
    """Lower and upper corners (3,) of the box holding every geometry at every configuration ``qs``."""
    points = motion_points(model, visual_model, qs)
    return points.min(axis=0), points.max(axis=0)


def robot_size(model: pin.Model, visual_model: pin.GeometryModel, q: np.ndarray) -> float:
    """Largest side (m) of the robot's box at configuration ``q`` (at least 0.1 m)."""
    lo, hi = motion_bounds(model, visual_model, [q])
    return max(float(np.max(hi - lo)), 0.1)


def _view_axes(extent: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Camera right, up and forward unit vectors (world frame, z up) for a box of sides ``extent``."""
    along = np.array([1.0, 0.0, 0.0]) if extent[0] >= extent[1] else np.array([0.0, 1.0, 0.0])
    side = np.cross(np.array([0.0, 0.0, 1.0]), along)  # the camera sits on -side, towards +along
    towards_camera = np.cos(AZIMUTH) * -side + np.sin(AZIMUTH) * along
    forward = -(np.cos(ELEVATION) * towards_camera + np.sin(ELEVATION) * np.array([0.0, 0.0, 1.0]))
    right = np.cross(forward, np.array([0.0, 0.0, 1.0]))
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    return right, up, forward


def _min_distance(x: np.ndarray, w: np.ndarray, tan: float) -> float:
    """Smallest ``d`` for which a shift puts ``|x - shift| <= tan (w + d)`` for all points."""
    return (float(np.max(x - tan * w)) - float(np.min(x + tan * w))) / (2.0 * tan)


def _centred_shift(x: np.ndarray, depth: np.ndarray) -> float:
    """The shift ``s`` with ``max((x - s) / depth) = -min((x - s) / depth)`` (bisection)."""
    low, high = float(np.min(x)), float(np.max(x))
    for _ in range(100):
        s = 0.5 * (low + high)
        ratios = (x - s) / depth
        if ratios.max() + ratios.min() > 0.0:
            low = s
        else:
            high = s
    return 0.5 * (low + high)


def camera_placement(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Target and camera position (world frame) of the tightest view holding ``points`` (N, 3)."""
    points = np.asarray(points, dtype=float).reshape(-1, 3)
    lo, hi = points.min(axis=0), points.max(axis=0)
    centre = 0.5 * (lo + hi)
    right, up, forward = _view_axes(hi - lo)
    tan_v = MARGIN * np.tan(0.5 * np.deg2rad(FOVY_DEG))
    rel = points - centre
    u, v, w = rel @ right, rel @ up, rel @ forward
    distance = max(_min_distance(u, w, ASPECT * tan_v), _min_distance(v, w, tan_v), 0.1 - float(np.min(w)))
    target = centre + _centred_shift(u, w + distance) * right + _centred_shift(v, w + distance) * up
    return target, target - distance * forward


def floor_extent(lo: np.ndarray, hi: np.ndarray, size: float) -> tuple[np.ndarray, np.ndarray]:
    """Centre of the top face (x, y, z) and side lengths (x, y) of a floor under the box ``[lo, hi]``.

    The top face is at ``z = 0`` unless the motion goes lower than :data:`FLOOR_SINK` robot sizes
    under it (a hanging pendulum, a drone starting at the origin): then it is under the motion.
    """
    border = max(FLOOR_BORDER * float(size), FLOOR_MIN_BORDER)
    top = 0.0 if lo[2] >= -FLOOR_SINK * float(size) else float(lo[2])
    centre = np.array([0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), top])
    return centre, (hi[:2] - lo[:2]) + 2.0 * border

