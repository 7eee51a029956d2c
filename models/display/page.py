"""One self-contained, compact HTML page for a meshcat scene (plays from ``file://``, no network).

meshcat's own export (``Visualizer.static_html``) inlines the viewer's JavaScript and one
base64 ``data:`` URL per scene command, so every mesh is stored as often as the robot uses it
(ANYmal's four legs share three meshes) and Collada meshes as text. This page instead holds:

* an index (JSON) and one base64 string: the deflate (zlib, level 1: a few percent larger than level 6, three
  times faster) stream of a bundle of sections;
* the sections: the viewer's JavaScript, the scene commands (msgpack, as meshcat sends them) and
  the payloads, each stored once by content. A payload is any string or binary value of at least
  :data:`MIN_PAYLOAD` bytes inside a command (mesh files, vertex and index arrays, textures); the
  command keeps the marker ``"\\u0000crocopy-blob:<k>"`` in its place;
* Collada text packed by :mod:`.collada` (numbers as integers), rebuilt exactly in the browser; the packed
  form of each text is kept in the user cache (:func:`packed_collada`), so a robot's meshes are packed once
  per machine, not at every export;
* animation tracks in three.js' ``times`` / ``values`` form as float32 arrays (the precision
  three.js plays them at), with the keys inside runs of equal values removed (the interpolation
  between the two ends of a run gives the same value); the animation comes after the scene.

The page's script inflates the bundle with the browser's ``DecompressionStream``, evaluates the
viewer, and replays the commands through ``viewer.handle_command_bytearray``, putting the payloads
back into each decoded command before meshcat handles it.
"""

from __future__ import annotations

import base64
import contextlib
import hashlib
import html as html_module
import json
import os
import re
import zlib
from pathlib import Path
from typing import Any

import meshcat
import numpy as np
import umsgpack

from crocopy.user_cache import user_cache_dir

from . import collada

__all__ = [
    "MIN_PAYLOAD",
    "BLOB_MARK",
    "meshcat_commands",
    "compact_animation",
    "keyed_animation",
    "write_page",
    "read_page",
]

MIN_PAYLOAD = 1024
"""Strings and binary values at least this long (bytes) are stored once, outside the commands."""
BLOB_MARK = "\u0000crocopy-blob:"
"""Prefix of the string left in a command where a payload was taken out."""

_MESHCAT_BLOB = re.compile(r"data:application/octet-binary;base64,([A-Za-z0-9+/=]+)")
_SCRIPT = re.compile(r'<script id="crocopy-(index|data)" type="[^"]+">(.*?)</script>', re.S)
_TYPED = {0x12: "Uint8Array", 0x15: "Int32Array", 0x16: "Uint32Array", 0x17: "Float32Array"}
_FLOAT32 = 0x17


def meshcat_commands(html: str) -> list[dict]:
    """The scene commands inside an HTML page written by meshcat's ``static_html``."""
    return [umsgpack.unpackb(base64.b64decode(blob)) for blob in _MESHCAT_BLOB.findall(html)]


def _float32(values: Any) -> umsgpack.Ext:
    return umsgpack.Ext(_FLOAT32, np.asarray(values, dtype="<f4").tobytes())


def _compact_track(track: dict) -> dict:
    """meshcat's ``keys`` track as three.js' ``times`` / ``values`` float32 arrays without repeats.

    Tracks of non-numeric values (e.g. ``visible``) are returned unchanged.
    """
    keys = track["keys"]
    values = [np.atleast_1d(k["value"]) for k in keys]
    if not keys or any(v.dtype.kind not in "fiu" or v.shape != values[0].shape for v in values):
        return track
    times = np.array([k["time"] for k in keys], dtype=np.float32)
    values = np.array(values, dtype=np.float32)
    same_prev = np.r_[False, np.all(values[1:] == values[:-1], axis=1)]
    same_next = np.r_[np.all(values[1:] == values[:-1], axis=1), False]
    keep = ~(same_prev & same_next)
    compact = {"name": track["name"], "type": track["type"]}
    return {**compact, "times": _float32(times[keep]), "values": _float32(values[keep])}


def compact_animation(command: dict) -> dict:
    """A ``set_animation`` command with compact tracks (other commands are returned unchanged)."""
    if command.get("type") != "set_animation":
        return command
    animations = []
    for anim in command["animations"]:
        clip = dict(anim["clip"])
        clip["tracks"] = [_compact_track(t) if "keys" in t else t for t in clip["tracks"]]
        animations.append({**anim, "clip": clip})
    return {**command, "animations": animations}


def keyed_animation(command: dict) -> dict:
    """The inverse form of :func:`compact_animation`: tracks as meshcat's ``keys`` lists again
    (``{"time", "value"}`` per key, values as lists of floats; the keys removed stay removed)."""
    if command.get("type") != "set_animation":
        return command
    animations = []
    for anim in command["animations"]:
        tracks = []
        for t in anim["clip"]["tracks"]:
            if "times" in t:
                times = np.frombuffer(t["times"].data, "<f4")
                values = np.frombuffer(t["values"].data, "<f4").reshape(len(times), -1)
                keys = [{"time": float(a), "value": v.tolist()} for a, v in zip(times, values)]
                t = {"name": t["name"], "type": t["type"], "keys": keys}
            tracks.append(t)
        animations.append({**anim, "clip": {**anim["clip"], "tracks": tracks}})
    return {**command, "animations": animations}


class _Bundle:
    """Sections of one binary bundle (4-byte aligned) and the payloads stored once by content."""

    def __init__(self) -> None:
        self.chunks: list[bytes] = []
        self.size = 0
        self.blobs: list[dict] = []
        self._seen: dict[bytes, int] = {}

    def add(self, data: bytes) -> list[int]:
        pad = -self.size % 4
        if pad:
            self.chunks.append(b"\0" * pad)
            self.size += pad
        self.chunks.append(data)
        self.size += len(data)
        return [self.size - len(data), len(data)]

    def add_shuffled(self, array: np.ndarray) -> list[int]:
        """A numeric array stored as byte planes (all first bytes, then all second bytes, ...)."""
        raw = np.ascontiguousarray(array).view(np.uint8).reshape(-1, array.dtype.itemsize)
        return self.add(raw.T.tobytes())

    def blob(self, kind: str, data: bytes, code: int | None = None) -> str:
        digest = hashlib.sha1(kind.encode() + bytes([code or 0]) + data).digest()
        if digest not in self._seen:
            entry: dict[str, Any] = {"kind": kind}
            if code is not None:
                entry["code"] = code
            if kind == "text" and collada.is_collada(data.decode("utf-8")):
                entry = {"kind": "dae", **_pack_collada(self, data.decode("utf-8"))}
            else:
                entry["at"] = self.add(data)
            self._seen[digest] = len(self.blobs)
            self.blobs.append(entry)
        return f"{BLOB_MARK}{self._seen[digest]}"

    def take_payloads(self, value: Any) -> Any:
        """``value`` with its large strings and binary values replaced by markers."""
        if isinstance(value, dict):
            return {k: self.take_payloads(v) for k, v in value.items()}
        if isinstance(value, list):
            return [self.take_payloads(v) for v in value]
        if isinstance(value, str) and len(value) >= MIN_PAYLOAD:
            return self.blob("text", value.encode("utf-8"))
        if isinstance(value, (bytes, bytearray)) and len(value) >= MIN_PAYLOAD:
            return self.blob("bytes", bytes(value))
        if isinstance(value, umsgpack.Ext) and value.type in _TYPED and len(value.data) >= MIN_PAYLOAD:
            return self.blob("ext", value.data, value.type)
        return value


_COLLADA_CACHE: dict[bytes, collada.PackedCollada] = {}


def _packer_version() -> str:
    """What tells one version of the packing from another: the SHA-1 of ``collada.py``."""
    with open(collada.__file__, "rb") as f:
        return hashlib.sha1(f.read()).hexdigest()[:16]


def packed_file(key: bytes) -> Path:
    """The user-cache file (:func:`crocopy.user_cache.user_cache_dir`) of the packed Collada text whose SHA-1 is
    ``key``, for this version of the packing."""
    return user_cache_dir("display") / f"{key.hex()}-{_packer_version()}.npz"


def _read_packed(path: Path) -> collada.PackedCollada | None:
    try:
        with np.load(path, allow_pickle=False) as z:
            return collada.PackedCollada(
                pieces=json.loads(str(z["pieces"])), arrays=[tuple(a) for a in json.loads(str(z["arrays"]))],
                digits=z["digits"], flags=z["flags"], exponents=z["exponents"], indices=z["indices"])
    except Exception:  # noqa: BLE001 - missing, truncated or foreign: packed again
        return None


def _write_packed(path: Path, p: collada.PackedCollada) -> None:
    temporary = path.with_name(f"{path.name}.{os.getpid()}.tmp.npz")
    with contextlib.suppress(OSError):
        path.parent.mkdir(parents=True, exist_ok=True)
        np.savez(temporary, pieces=json.dumps(p.pieces), arrays=json.dumps(p.arrays), digits=p.digits,
                 flags=p.flags, exponents=p.exponents, indices=p.indices)
        os.replace(temporary, path)
    with contextlib.suppress(OSError):
        temporary.unlink()


def packed_collada(text: str) -> collada.PackedCollada:
    """:func:`collada.pack` of ``text``, kept in memory and in the user cache (a robot's meshes are packed once per
    machine, not once per export); an unreadable cache file is packed again and replaced."""
    key = hashlib.sha1(text.encode("utf-8")).digest()
    if key not in _COLLADA_CACHE:
        path = packed_file(key)
        p = _read_packed(path)
        if p is None:
            p = collada.pack(text)
            _write_packed(path, p)
        _COLLADA_CACHE[key] = p
    return _COLLADA_CACHE[key]


def _pack_collada(bundle: _Bundle, text: str) -> dict:
    p = packed_collada(text)
    return {
        "pieces": bundle.add(json.dumps(p.pieces).encode("utf-8")),
        "arrays": [list(a) for a in p.arrays],
        "digits": bundle.add_shuffled(p.digits),
        "flags": bundle.add(p.flags.tobytes()),
        "exponents": bundle.add(p.exponents.tobytes()),
        "indices": bundle.add_shuffled(p.indices),
    }


def _viewer_js() -> bytes:
    with open(os.path.join(os.path.dirname(meshcat.__file__), "viewer", "dist", "main.min.js"), "rb") as f:
        return f.read()


def write_page(commands: list[dict], path: str | os.PathLike, title: str = "crocopy") -> str:
    """Write ``commands`` (meshcat scene commands) as a compact self-contained page; return the path."""
    bundle = _Bundle()
    viewer = bundle.add(_viewer_js())
    # The server lists the root's animation first; it must come after the nodes it animates exist
    # and have their static transforms, else three.js may not apply some of its tracks.
    ordered = [c for c in commands if c.get("type") != "set_animation"]
    ordered += [c for c in commands if c.get("type") == "set_animation"]
    packed = [umsgpack.packb(bundle.take_payloads(compact_animation(c))) for c in ordered]
    index = {"viewer": viewer, "commands": [bundle.add(p) for p in packed], "blobs": bundle.blobs, "mark": BLOB_MARK}
    data = base64.b64encode(zlib.compress(b"".join(bundle.chunks), 1)).decode("ascii")
    page = _TEMPLATE.format(
        title=html_module.escape(title), index=json.dumps(index, separators=(",", ":")), data=data, loader=_LOADER
    )
    path = os.fspath(path)
    with open(path, "w", encoding="utf-8") as f:
        f.write(page)
    return path


def _read_blob(raw: bytes, entry: dict) -> Any:
    def section(at: list[int]) -> bytes:
        return raw[at[0] : at[0] + at[1]]

    def unshuffled(at: list[int], dtype: str) -> np.ndarray:
        planes = np.frombuffer(section(at), np.uint8).reshape(np.dtype(dtype).itemsize, -1)
        return np.ascontiguousarray(planes.T).view(dtype).reshape(-1)

    kind = entry["kind"]
    if kind == "dae":
        packed = collada.PackedCollada(
            json.loads(section(entry["pieces"])),
            [tuple(a) for a in entry["arrays"]],
            unshuffled(entry["digits"], "<u4"),
            np.frombuffer(section(entry["flags"]), np.uint8),
            np.frombuffer(section(entry["exponents"]), np.int8),
            unshuffled(entry["indices"], "<u4"),
        )
        return collada.unpack(packed)
    data = section(entry["at"])
    if kind == "text":
        return data.decode("utf-8")
    if kind == "ext":
        return umsgpack.Ext(entry["code"], data)
    return data


def read_page(path: str | os.PathLike) -> list[dict]:
    """The scene commands of a page written by :func:`write_page`, payloads put back (for tests)."""
    with open(os.fspath(path), encoding="utf-8") as f:
        scripts = dict(_SCRIPT.findall(f.read()))
    index = json.loads(scripts["index"])
    raw = zlib.decompress(base64.b64decode(scripts["data"]))
    blobs = [_read_blob(raw, entry) for entry in index["blobs"]]

    def restore(value: Any) -> Any:
        if isinstance(value, dict):
            return {k: restore(v) for k, v in value.items()}
        if isinstance(value, list):
            return [restore(v) for v in value]
        if isinstance(value, str) and value.startswith(BLOB_MARK):
            return blobs[int(value[len(BLOB_MARK) :])]
        return value

    return [restore(umsgpack.unpackb(raw[a : a + n])) for a, n in index["commands"]]


_LOADER = r"""
(async () => {
  const pane = document.getElementById("meshcat-pane");
  try {
    const index = JSON.parse(document.getElementById("crocopy-index").textContent);
    const packed = document.getElementById("crocopy-data").textContent.trim();
    const response = await fetch("data:application/octet-stream;base64," + packed);
    const inflated = response.body.pipeThrough(new DecompressionStream("deflate"));
    const buffer = await new Response(inflated).arrayBuffer();
    const bytes = (at) => new Uint8Array(buffer, at[0], at[1]).slice();
    const utf8 = new TextDecoder();
    const unshuffle = (at, Type) => {
      const planes = bytes(at), n = planes.length / Type.BYTES_PER_ELEMENT, out = new Uint8Array(planes.length);
      for (let b = 0; b < Type.BYTES_PER_ELEMENT; b++)
        for (let i = 0; i < n; i++) out[i * Type.BYTES_PER_ELEMENT + b] = planes[b * n + i];
      return new Type(out.buffer);
    };
    const collada = (e) => {
      const pieces = JSON.parse(utf8.decode(bytes(e.pieces)));
      const digits = unshuffle(e.digits, Uint32Array), flags = bytes(e.flags);
      const exps = new Int8Array(bytes(e.exponents).buffer), ints = unshuffle(e.indices, Uint32Array);
      const out = [pieces[0]];
      let f = 0, x = 0, i = 0;
      e.arrays.forEach((a, j) => {
        const n = a[1], tokens = new Array(n);
        if (a[0] === "f") {
          for (let t = 0; t < n; t++, f++) {
            const fl = flags[f], fraction = fl & 31;
            let s = String(digits[f]);
            if (fraction) { s = s.padStart(fraction + 1, "0"); s = s.slice(0, -fraction) + "." + s.slice(-fraction); }
            if (fl & 32) s = "-" + s;
            if (fl & 64) s += "e" + exps[x++];
            tokens[t] = s;
          }
        } else {
          const k = a[2], m = n / k;
          for (let c = 0; c < k; c++) {
            let v = 0;
            for (let r = 0; r < m; r++, i++) { const z = ints[i]; v += (z >>> 1) ^ -(z & 1); tokens[r * k + c] = v; }
          }
        }
        out.push(tokens.join(" "), pieces[j + 1]);
      });
      return out.join("");
    };
    const typed = {18: Uint8Array, 21: Int32Array, 22: Uint32Array, 23: Float32Array};
    const texts = new Map();
    const blob = (k) => {
      const e = index.blobs[k];
      if (e.kind === "ext") return new typed[e.code](bytes(e.at).buffer);
      if (e.kind === "bytes") return bytes(e.at);
      if (!texts.has(k)) texts.set(k, e.kind === "dae" ? collada(e) : utf8.decode(bytes(e.at)));
      return texts.get(k);
    };
    const restore = (v) => {
      if (typeof v === "string") return v.startsWith(index.mark) ? blob(Number(v.slice(index.mark.length))) : v;
      if (Array.isArray(v)) { for (let i = 0; i < v.length; i++) v[i] = restore(v[i]); return v; }
      if (v !== null && typeof v === "object" && !ArrayBuffer.isView(v))
        for (const key of Object.keys(v)) v[key] = restore(v[key]);
      return v;
    };
    (0, eval)(utf8.decode(bytes(index.viewer)));
    const viewer = new MeshCat.Viewer(pane);
    window.viewer = viewer;
    const handle = viewer.handle_command.bind(viewer);
    viewer.handle_command = (command) => handle(restore(command));
    for (const at of index.commands) viewer.handle_command_bytearray(bytes(at));
    // meshcat starts with its controls folded under "Open Controls": unfold them with the
    // animation's folder (play, pause, time) open and the scene tree folded, so play is in view.
    viewer.gui.open();
    for (const folder of Object.values(viewer.gui.__folders)) folder.close();
    if (viewer.animator) viewer.animator.folder.open();
  } catch (error) {
    pane.textContent = "This page could not show the scene (it needs a browser with DecompressionStream: "
      + "Chrome 80, Firefox 113, Safari 16.4 or newer): " + error;
  }
})();
"""

_TEMPLATE = """<!DOCTYPE html>
<html>
<head>
<meta charset="utf-8">
<title>{title}</title>
<style>
body {{ margin: 0; }}
#meshcat-pane {{ width: 100vw; height: 100vh; overflow: hidden; }}
</style>
</head>
<body>
<div id="meshcat-pane"></div>
<script id="crocopy-index" type="application/json">{index}</script>
<script id="crocopy-data" type="application/octet-stream">{data}</script>
<script>{loader}</script>
</body>
</html>
"""
