"""Meshes the browser cannot show as they are, sent as plain triangles instead.

Collada files whose sub-meshes mix primitives with and without texture coordinates (ANYmal's trunk)
are invisible in meshcat's viewer; their collision mesh (Coal's BVH, already loaded by Pinocchio)
gives the same surface as vertices and triangles.
"""

from __future__ import annotations

import re

import numpy as np
import pinocchio as pin

__all__ = ["has_mixed_texcoords", "plain_mesh"]

_PRIMITIVE_OPENING = re.compile(r"<(?:triangles|polylist|polygons)\b")
_PRIMITIVE_CLOSINGS = ("</triangles>", "</polylist>", "</polygons>")
_PLAIN_MESH_CACHE: dict[str, tuple[np.ndarray, np.ndarray]] = {}


def has_mixed_texcoords(path: str) -> bool:
    """Whether a Collada file mixes primitives with and without texture coordinates."""
    if not path.lower().endswith(".dae"):
        return False
    with open(path, encoding="utf-8", errors="replace") as f:
        text = f.read()
    blocks = textured = 0
    closing = {tag: 0 for tag in _PRIMITIVE_CLOSINGS}  # next position of each closing tag (-1: none left)
    opening = _PRIMITIVE_OPENING.search(text)
    while opening is not None:  # each block runs to the first closing tag of a primitive after it
        for tag, at in closing.items():
            if 0 <= at < opening.end():
                closing[tag] = text.find(tag, opening.end())
        ends = [at for at in closing.values() if at >= 0]
        if not ends:
            break
        end = min(ends)
        blocks += 1
        textured += text.find('semantic="TEXCOORD"', opening.start(), end) >= 0
        opening = _PRIMITIVE_OPENING.search(text, end + 1)
    return 0 < textured < blocks


def plain_mesh(geometry_object: pin.GeometryObject) -> tuple[np.ndarray, np.ndarray]:
    """Vertices (unscaled) and triangles of a mesh geometry, read from its collision mesh."""
    key = geometry_object.meshPath
    if key not in _PLAIN_MESH_CACHE:
        bvh = geometry_object.geometry
        scale = np.where(np.abs(geometry_object.meshScale) > 0, geometry_object.meshScale, 1.0)
        vertices = np.asarray(bvh.vertices(), dtype=np.float32) / scale.astype(np.float32)
        faces = np.empty((bvh.num_tris, 3), dtype=np.uint32)
        for i in range(bvh.num_tris):
            tri = bvh.tri_indices(i)
            faces[i] = (tri[0], tri[1], tri[2])
        _PLAIN_MESH_CACHE[key] = (vertices, faces)
    return _PLAIN_MESH_CACHE[key]
