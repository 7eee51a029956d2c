"""Compact HTML pages (Collada packing, payloads stored once, compact tracks) and the framing of motions."""

from __future__ import annotations

import base64
import hashlib
import json
import re
import zlib

import example_robot_data as erd
import numpy as np
import pinocchio as pin
import pytest
import umsgpack
from hypothesis import given, settings
from hypothesis import strategies as st

from crocopy.models.display import collada, framing, page
from crocopy.models.display.html import static_html_commands
from crocopy.models.display.meshcat_display import MeshcatDisplay

RNG = np.random.default_rng(7)


def _dae(floats: list[str], ints: list[str], columns: int = 2) -> str:
    inputs = "".join(f'<input semantic="S{k}" source="#s" offset="{k}"/>' for k in range(columns))
    return (
        '<?xml version="1.0"?>\n<COLLADA version="1.4.1"><library_geometries><mesh>'
        f'<source><float_array id="a" count="{len(floats)}">\n  {" ".join(floats)}\n</float_array></source>'
        f'<triangles count="1">{inputs}<p>{" ".join(ints)}</p></triangles>'
        "</mesh></library_geometries></COLLADA>"
    )


def _random_decimal() -> str:
    sign = "-" if RNG.random() < 0.5 else ""
    whole = str(RNG.integers(0, 1000))
    fraction = "".join(str(d) for d in RNG.integers(0, 10, RNG.integers(0, 7)))  # at most 9 digits: uint32
    exponent = f"e{RNG.integers(-30, 30)}" if RNG.random() < 0.1 else ""
    return sign + whole + ("." + fraction if fraction else "") + exponent


def test_collada_numbers_are_packed_exactly():
    floats = [_random_decimal() for _ in range(3000)] + ["0", "-0", "0.000", "-0.5", "4294967295", "1e-7"]
    ints = [str(v) for v in RNG.integers(0, 70000, 2 * 1500)]
    text = _dae(floats, ints)
    packed = collada.pack(text)
    assert [a[0] for a in packed.arrays] == ["f", "i"] and packed.arrays[1][2] == 2  # both arrays packed, 2 columns
    assert collada.unpack(packed).split() == text.split()
    assert sum(len(p) for p in packed.pieces) < 400  # only the markup stays text
    assert collada.is_collada(text) and not collada.is_collada("solid stl\nfacet normal 0 0 1")


@pytest.mark.parametrize("bad", ["1E5", "+1", ".5", "00.5", "1e05", "1e+5", "nan", "4294967296", "1.0.0", "1e500"])
def test_collada_arrays_that_would_not_read_back_stay_text(bad):
    floats = ["1.5", bad, "-2"]
    text = _dae(floats, ["0", "1", "2", "3"])
    packed = collada.pack(text)
    assert [a[0] for a in packed.arrays] == ["i"]  # the float array stays text, the index list is packed
    assert bad in "".join(packed.pieces)
    assert collada.unpack(packed).split() == text.split()


def test_collada_index_lists_that_do_not_fit_their_columns_stay_text():
    for ints in (["0", "1", "2"], ["0", "01"], ["0", "-1"]):  # 3 values in 2 columns, leading zero, sign
        packed = collada.pack(_dae(["1.0"], ints))
        assert [a[0] for a in packed.arrays] == ["f"]
        assert collada.unpack(packed).split() == _dae(["1.0"], ints).split()


def test_collada_robot_meshes_read_back_exactly():
    anymal = erd.load("anymal")
    paths = sorted({go.meshPath for go in anymal.visual_model.geometryObjects if go.meshPath.endswith("shank_l.dae")})
    with open(paths[0], encoding="utf-8") as f:
        text = f.read()
    packed = collada.pack(text)
    assert len(packed.arrays) == text.count("<float_array") + text.count("<p>")
    assert collada.unpack(packed).split() == text.split()


_TOKEN = re.compile(r"(-?)(0|[1-9][0-9]*)(?:\.([0-9]+))?(?:e(-?(?:0|[1-9][0-9]*)))?")


def _reference_decimals(content: str):
    """The decimal-list packing read token by token from its grammar (what the array version must give)."""
    if content[:1].isspace():
        return None
    digits, flags, exponents = [], [], []
    for token in content.split():
        m = _TOKEN.fullmatch(token)
        if m is None:
            return None
        sign, whole, fraction, exponent = m.group(1), m.group(2), m.group(3) or "", m.group(4)
        if len(fraction) > 31 or int(whole + fraction) >= 2**32 or (exponent and not -128 <= int(exponent) <= 127):
            return None
        digits.append(int(whole + fraction))
        flags.append(len(fraction) | (32 if sign else 0) | (64 if exponent else 0))
        exponents += [int(exponent)] if exponent else []
    return np.array(digits, np.uint32), np.array(flags, np.uint8), np.array(exponents, np.int8)


def _same(a, b) -> bool:
    if a is None or b is None:
        return a is None and b is None
    return all(x.dtype == y.dtype and np.array_equal(x, y) for x, y in zip(a, b))


_DECIMALS = st.lists(
    st.one_of(
        st.builds(lambda s, w, f, e: s + str(w) + (f".{f}" if f else "") + (f"e{e}" if e is not None else ""),
                  st.sampled_from(["", "-"]), st.integers(0, 10**11), st.text("0123456789", max_size=12),
                  st.none() | st.integers(-200, 200)),
        st.text("0123456789.-eE+ \n", min_size=1, max_size=8),
    ),
    max_size=8,
)


@settings(max_examples=300, deadline=None)
@given(_DECIMALS, st.sampled_from([" ", "\n  ", "\t"]), st.sampled_from(["", " "]))
def test_decimal_lists_pack_as_their_grammar_reads_them(tokens, separator, edge):
    content = separator.join(tokens)
    assert _same(collada._pack_decimals(content), _reference_decimals(content))
    assert _same(collada._pack_decimals(content + edge), _reference_decimals(content + edge))
    assert _same(collada._pack_decimals(edge + content), _reference_decimals(edge + content))


@settings(max_examples=300, deadline=None)
@given(st.lists(st.integers(0, 10**10).map(str) | st.sampled_from(["01", "00", "-1", "1.0", "x"]), max_size=9),
       st.integers(1, 3))
def test_index_lists_pack_as_their_grammar_reads_them(tokens, k):
    packed = collada._pack_indices(" ".join(tokens), k)
    plain = all(re.fullmatch(r"0|[1-9][0-9]{0,8}", t) for t in tokens) and len(tokens) % k == 0
    if not plain:
        assert packed is None
    else:
        values = np.array([int(t) for t in tokens], np.int64)
        assert packed[1] == len(tokens) and np.array_equal(collada._unzigzag_columns(packed[0], len(tokens), k), values)


def _track(values, name=".position", kind="vector3"):
    return {"name": name, "type": kind, "keys": [{"time": i, "value": v} for i, v in enumerate(values)]}


def test_compact_tracks_drop_only_keys_inside_runs_of_equal_values():
    a, b, c = [0.0, 0.0, 1.0], [0.0, 0.5, 1.0], [1.0, 0.5, 1.0]
    visible = {"name": ".visible", "type": "boolean", "keys": [{"time": 0, "value": True}]}
    command = {
        "type": "set_animation",
        "animations": [{"path": "/meshcat/x", "clip": {"fps": 30, "tracks": [_track([a, a, a, b, b, c]), visible]}}],
    }
    compact = page.compact_animation(command)
    track, kept_visible = compact["animations"][0]["clip"]["tracks"]
    np.testing.assert_array_equal(np.frombuffer(track["times"].data, "<f4"), [0, 2, 3, 4, 5])
    values = np.frombuffer(track["values"].data, "<f4").reshape(-1, 3)
    np.testing.assert_array_equal(values, [a, a, b, b, c])
    assert kept_visible == visible  # not numeric: unchanged
    keyed = page.keyed_animation(compact)["animations"][0]["clip"]["tracks"][0]["keys"]
    assert [k["time"] for k in keyed] == [0, 2, 3, 4, 5] and keyed[3]["value"] == pytest.approx(b)
    assert page.compact_animation({"type": "set_transform"}) == {"type": "set_transform"}


def _raw_index(path):
    with open(path, encoding="utf-8") as f:
        html = f.read()
    index = json.loads(re.search(r'<script id="crocopy-index"[^>]*>(.*?)</script>', html, re.S).group(1))
    data = re.search(r'<script id="crocopy-data"[^>]*>(.*?)</script>', html, re.S).group(1)
    return index, zlib.decompress(base64.b64decode(data))


@pytest.fixture(scope="module")
def anymal():
    return erd.load("anymal")


def test_page_stores_each_mesh_once_and_reads_back(anymal, tmp_path):
    x0 = np.concatenate([anymal.q0, np.zeros(anymal.model.nv)])
    x1 = x0.copy()
    x1[2] += 0.2
    with MeshcatDisplay(anymal, openDisplay=False) as d:
        path = d.exportHTML([x0, x1], str(tmp_path / "anymal.html"), dts=[0.1])
        original = page.meshcat_commands(d.viewer.static_html())
    index, raw = _raw_index(path)
    dae_paths = {go.meshPath for go in anymal.visual_model.geometryObjects if go.meshPath.endswith(".dae")}
    dae_paths -= {anymal.visual_model.geometryObjects[0].meshPath}  # the trunk is sent as plain triangles
    assert sum(b["kind"] == "dae" for b in index["blobs"]) == len(dae_paths) == 6  # 16 leg meshes, 6 files
    marks = re.findall(rb"\x00crocopy-blob:(\d+)", raw)
    assert len(marks) > len(index["blobs"])  # some payloads are used by several commands
    commands = static_html_commands(path)
    assert original[0]["type"] == "set_animation"  # meshcat's server lists the root's animation first,
    assert [c["type"] for c in commands].index("set_animation") == len(commands) - 1  # the page last
    original = original[1:] + original[:1]
    assert [(c["type"], c["path"]) for c in commands] == [(c["type"], c["path"]) for c in original]
    meshes = {c["path"]: c["object"]["object"]["data"] for c in commands if c["type"] == "set_object"
              and c["object"].get("object", {}).get("format") == "dae"}
    for go in anymal.visual_model.geometryObjects[1:]:
        if go.meshPath.endswith(".dae"):
            with open(go.meshPath, encoding="utf-8") as f:
                assert meshes[f"/meshcat/pinocchio/visuals/{go.name}/shape"].split() == f.read().split()
    same = [(a, b) for a, b in zip(original, commands, strict=True) if a["type"] != "set_animation"]
    assert all(a == b for a, b in same if a["type"] == "set_object" and a["object"].get("object", {}).get("format")
               != "dae")  # every other object (plain trunk, floor, textures) comes back byte for byte
    size = len(open(path, "rb").read())
    assert size < 4.5e6 and 5 * size < sum(len(umsgpack.packb(c)) for c in original)


def _project(points, target, position):
    forward = (target - position) / np.linalg.norm(target - position)
    right = np.cross(forward, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    rel = points - position
    depth = rel @ forward
    return (rel @ right) / depth, (rel @ up) / depth, depth


@pytest.mark.parametrize(
    "lo, hi",
    [
        ([-0.6, -0.35, -0.3], [3.3, 0.35, 1.4]),  # a drone's flight
        ([-0.3, -0.4, 0.0], [0.3, 0.4, 1.8]),  # a humanoid standing
        ([-0.2, -3.0, 0.0], [0.2, 2.0, 0.5]),  # a walk along y
    ],
)
def test_camera_sees_every_point_and_no_more_than_needed(lo, hi):
    lo, hi = np.array(lo), np.array(hi)
    corners = framing.box_corners(lo, hi)
    points = np.concatenate([corners, lo + (hi - lo) * RNG.random((200, 3))])
    target, position = framing.camera_placement(points)
    u, v, depth = _project(points, target, position)
    tan_v = framing.MARGIN * np.tan(np.deg2rad(framing.FOVY_DEG) / 2)
    tan_h = framing.ASPECT * tan_v
    assert np.all(depth > 0)
    assert np.all(np.abs(v) <= tan_v + 1e-9) and np.all(np.abs(u) <= tan_h + 1e-9)
    # tight along the binding axis, and centred along both
    assert max(np.max(np.abs(v)) / tan_v, np.max(np.abs(u)) / tan_h) == pytest.approx(1.0)
    assert np.max(u) == pytest.approx(-np.min(u)) and np.max(v) == pytest.approx(-np.min(v))
    assert position[2] > target[2]  # seen from above
    horizontal = np.abs((target - position)[:2])
    longer = int(np.argmax(hi[:2] - lo[:2]))
    assert horizontal[1 - longer] > horizontal[longer]  # from the side of the longer horizontal axis


def test_floor_covers_the_motion_and_sinks_under_it_when_needed():
    centre, sides = framing.floor_extent(np.array([-1.0, 0.0, -0.02]), np.array([3.0, 1.0, 1.0]), 0.6)
    np.testing.assert_allclose(centre, [1.0, 0.5, 0.0])
    border = framing.FLOOR_MIN_BORDER  # the minimum border: 25 robot sizes of 0.6 m are less
    np.testing.assert_allclose(sides, [4.0 + 2 * border, 1.0 + 2 * border])
    centre, sides = framing.floor_extent(np.array([-0.1, -0.1, -0.5]), np.array([0.1, 0.1, 0.1]), 2.0)
    assert centre[2] == -0.5
    assert sides[0] == pytest.approx(0.2 + 2 * max(framing.FLOOR_BORDER * 2.0, framing.FLOOR_MIN_BORDER))
    _, sides = framing.floor_extent(np.array([-0.1, -0.1, 0.0]), np.array([0.1, 0.1, 0.1]), 10.0)
    assert sides[0] == pytest.approx(0.2 + 2 * framing.FLOOR_BORDER * 10.0)  # a big robot: 25 of its sizes


def test_motion_bounds_hold_every_geometry_at_every_node(anymal):
    model, gmodel = anymal.model, anymal.visual_model
    qs = [pin.randomConfiguration(model, -np.ones(model.nq), np.ones(model.nq)) for _ in range(4)]
    lo, hi = framing.motion_bounds(model, gmodel, qs)
    data, gdata = model.createData(), pin.GeometryData(gmodel)
    corners = framing.geometry_corners(gmodel)
    touching = 0
    for q in qs:
        pin.framesForwardKinematics(model, data, q)
        pin.updateGeometryPlacements(model, data, gmodel, gdata)
        for c, oMg in zip(corners, gdata.oMg):
            p = c @ oMg.rotation.T + oMg.translation
            assert np.all(p >= lo - 1e-12) and np.all(p <= hi + 1e-12)
            touching += int(np.any(np.isclose(p, lo)) or np.any(np.isclose(p, hi)))
    assert touching > 0  # the box is tight
    with pytest.raises(ValueError, match="qs"):
        framing.motion_bounds(model, gmodel, [])
    empty = pin.GeometryModel()
    lo, hi = framing.motion_bounds(model, empty, qs[:1])
    pin.framesForwardKinematics(model, data, qs[0])
    points = np.array([f.translation for f in data.oMf])
    np.testing.assert_allclose(lo, points.min(axis=0))
    np.testing.assert_allclose(hi, points.max(axis=0))


def test_fit_view_camera_scene_shift_and_live_widening(tmp_path):
    iris = erd.load("iris")
    x0 = np.concatenate([iris.q0, np.zeros(iris.model.nv)])
    far = x0.copy()
    far[:3] = [3.0, 0.0, 1.0]
    with MeshcatDisplay(iris, openDisplay=False) as d:
        path = d.exportHTML([x0, far], str(tmp_path / "iris.html"), dts=[1.0])
        lo, hi = d.view_bounds
        assert lo[0] < -0.1 and hi[0] > 3.1 and hi[2] > 1.0
        commands = static_html_commands(path)
        transforms = {c["path"]: np.reshape(c["matrix"], (4, 4)).T for c in commands if c["type"] == "set_transform"}
        target, position = framing.camera_placement(framing.motion_points(iris.model, iris.visual_model,
                                                                          [x0[:7], far[:7]]))
        np.testing.assert_allclose(transforms["/meshcat"][:3, 3], -target, atol=1e-6)  # the scene moves, not the rig
        props = {(c["path"], c["property"]): c["value"] for c in commands if c["type"] == "set_property"}
        offset = position - target
        np.testing.assert_allclose(props[("/Cameras/default/rotated/<object>", "position")],
                                   [offset[0], offset[2], -offset[1]], atol=1e-6)
        assert props[("/Grid", "visible")] is False and props[("/Axes", "visible")] is False
        d.display([x0, x0])  # the live view only widens: showing the start alone keeps the whole flight
        np.testing.assert_array_equal(d.view_bounds[1], hi)
        high = x0.copy()
        high[2] = 5.0
        d.display([x0, high])
        assert d.view_bounds[1][2] > 5.0 and d.view_bounds[1][0] == hi[0]
        d.setCameraTarget([1.0, 2.0, 3.0])
        d.setCameraPosition([4.0, 2.0, 3.0])
        with pytest.raises(ValueError, match="target"):
            d.setCameraTarget([1.0, np.nan, 0.0])


def test_packed_collada_is_kept_in_the_user_cache_and_a_damaged_file_is_packed_again(monkeypatch, tmp_path):
    monkeypatch.setenv("CROCOPY_CACHE_DIR", str(tmp_path))
    packs = []
    pack = collada.pack
    monkeypatch.setattr(collada, "pack", lambda text: packs.append(text) or pack(text))
    text = _dae(["0.5", "-1.25e-3", "7"], ["0", "1", "2", "2", "1", "0"])
    for process in range(3):  # each a later process: nothing in memory
        monkeypatch.setattr(page, "_COLLADA_CACHE", {})
        packed = page.packed_collada(text)
        assert collada.unpack(packed).split() == text.split() and [a[0] for a in packed.arrays] == ["f", "i"]
        (cached,) = (tmp_path / "display").glob("*.npz")
        assert cached == page.packed_file(hashlib.sha1(text.encode()).digest())
        if process == 1:
            cached.write_bytes(cached.read_bytes()[:40])  # truncated: read as missing, packed and written again
    assert len(packs) == 2  # the first process, and the one after the damage
    assert page._read_packed(cached) is not None
