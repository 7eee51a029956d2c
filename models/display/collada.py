"""Lossless binary packing of the numbers in Collada (``.dae``) text.

Collada meshes are XML whose bulk is decimal text: ``<float_array>`` (positions, normals, texture
coordinates) and the index lists ``<p>`` of the primitives. Deflate compresses that text about
three times; storing the numbers as integers compresses it about five times. The packing is exact:
:func:`unpack` rebuilds the same text, token for token. Only the whitespace between the numbers of
a packed array is rewritten (single spaces), which Collada readers treat alike.

A decimal token ``[-]D[.F][eE]`` (no ``+``, no leading zeros in ``E``) becomes

* ``digits`` (uint32): the integer ``DF`` (integer and fraction digits run together);
* ``flags`` (uint8): the number of fraction digits (bits 0-4), ``-`` (bit 5), has ``e`` (bit 6);
* ``exponents`` (int8): ``E``, for the tokens that have one.

It is written back as ``digits`` padded with zeros to ``fraction + 1`` digits, with the point
before the last ``fraction`` digits. An index list ``<p>`` of a primitive with ``k`` inputs
(``k = 1 + max offset``) is read as ``m x k`` integers; each column is stored as its first
differences in zig-zag form (``2d`` for ``d >= 0``, ``-2d - 1`` otherwise), columns one after the
other, in ``indices`` (uint32). Arrays that do not read back exactly this way stay text.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

import numpy as np

__all__ = ["PackedCollada", "is_collada", "pack", "unpack"]

_FLOAT_ARRAY = re.compile(r"(<float_array\b[^>]*>)([^<]*)(</float_array>)")
_PRIMITIVE = re.compile(r"<(triangles|polylist|polygons|lines|linestrips|tristrips|trifans)\b.*?</\1>", re.S)
_INDEX_LIST = re.compile(r"(<p>)([^<]*)(</p>)")
_OFFSET = re.compile(r"<input\b[^>]*\boffset=\"(\d+)\"")
_DECIMAL = re.compile(r"(-?)(\d+)(?:\.(\d+))?(?:e(-?\d+))?")
_MAX_FRACTION = 31
_NEGATIVE, _EXPONENT = 32, 64


@dataclass
class PackedCollada:
    """A Collada text with its numeric arrays taken out.

    ``pieces`` are the text around the arrays (``len(arrays) + 1`` strings); ``arrays`` describe
    the arrays in order: ``("f", n)`` for ``n`` decimals, ``("i", n, k)`` for ``n`` integers in
    ``k`` columns. The other fields hold the numbers of all arrays, in order.
    """

    pieces: list[str]
    arrays: list[tuple] = field(default_factory=list)
    digits: np.ndarray = field(default_factory=lambda: np.zeros(0, np.uint32))
    flags: np.ndarray = field(default_factory=lambda: np.zeros(0, np.uint8))
    exponents: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int8))
    indices: np.ndarray = field(default_factory=lambda: np.zeros(0, np.uint32))


def is_collada(text: str) -> bool:
    """Whether ``text`` looks like a Collada document."""
    return "<COLLADA" in text[:2000]


def _format_decimals(digits: np.ndarray, flags: np.ndarray, exponents: np.ndarray) -> list[str]:
    out = []
    e = iter(exponents.tolist())
    for d, f in zip(digits.tolist(), flags.tolist()):
        s = str(d)
        fraction = f & _MAX_FRACTION
        if fraction:
            s = s.rjust(fraction + 1, "0")
            s = s[:-fraction] + "." + s[-fraction:]
        if f & _NEGATIVE:
            s = "-" + s
        if f & _EXPONENT:
            s += "e" + str(next(e))
        out.append(s)
    return out


def _pack_decimals(tokens: list[str]) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    digits, flags, exponents = [], [], []
    for token in tokens:
        m = _DECIMAL.fullmatch(token)
        if m is None:
            return None
        sign, whole, fraction, exponent = m.groups()
        fraction = fraction or ""
        value = int(whole + fraction)
        if len(fraction) > _MAX_FRACTION or value >= 2**32:
            return None
        flag = len(fraction) | (_NEGATIVE if sign else 0)
        if exponent is not None:
            if not -128 <= int(exponent) < 128:
                return None
            flag |= _EXPONENT
            exponents.append(int(exponent))
        digits.append(value)
        flags.append(flag)
    packed = np.array(digits, np.uint32), np.array(flags, np.uint8), np.array(exponents, np.int8)
    return packed if _format_decimals(*packed) == tokens else None


def _zigzag_columns(values: np.ndarray, k: int) -> np.ndarray:
    columns = values.reshape(-1, k).T
    d = np.diff(columns, axis=1, prepend=0).astype(np.int64)
    return ((d << 1) ^ (d >> 63)).astype(np.uint32).reshape(-1)


def _unzigzag_columns(z: np.ndarray, n: int, k: int) -> np.ndarray:
    z = z.astype(np.int64).reshape(k, n // k)
    d = (z >> 1) ^ -(z & 1)
    return np.cumsum(d, axis=1).T.reshape(-1)


def _pack_indices(tokens: list[str], k: int) -> np.ndarray | None:
    if not all(t.isdigit() for t in tokens):
        return None
    values = np.array([int(t) for t in tokens], dtype=np.int64)
    if len(values) % k or (len(values) and values.max() >= 2**31):
        return None
    z = _zigzag_columns(values, k)
    return z if [str(v) for v in _unzigzag_columns(z, len(values), k).tolist()] == tokens else None


def _trimmed(text: str, start: int, end: int) -> tuple[int, int]:
    """``[start, end)`` without the whitespace at both ends (kept as text)."""
    content = text[start:end]
    return start + len(content) - len(content.lstrip()), start + len(content.rstrip())


def _array_spans(text: str) -> list[tuple[int, int, int]]:
    """(start, end, columns) of every array's content; columns 0 for ``<float_array>``."""
    spans = [(*_trimmed(text, m.start(2), m.end(2)), 0) for m in _FLOAT_ARRAY.finditer(text)]
    for prim in _PRIMITIVE.finditer(text):
        offsets = [int(o) for o in _OFFSET.findall(prim.group(0))]
        k = max(offsets, default=0) + 1
        base = prim.start()
        spans += [(*_trimmed(text, base + m.start(2), base + m.end(2)), k) for m in _INDEX_LIST.finditer(prim.group(0))]
    return sorted(spans)


def pack(text: str) -> PackedCollada:
    """Take the numeric arrays out of a Collada text (see the module docstring)."""
    pieces, arrays = [], []
    digits, flags, exponents, indices = [], [], [], []
    last = 0
    for start, end, k in _array_spans(text):
        tokens = text[start:end].split()
        if k == 0:
            packed = _pack_decimals(tokens)
            if packed is None:
                continue
            digits.append(packed[0])
            flags.append(packed[1])
            exponents.append(packed[2])
            arrays.append(("f", len(tokens)))
        else:
            z = _pack_indices(tokens, k)
            if z is None:
                continue
            indices.append(z)
            arrays.append(("i", len(tokens), k))
        pieces.append(text[last:start])
        last = end
    pieces.append(text[last:])

    def cat(parts: list[np.ndarray], dtype: type) -> np.ndarray:
        return np.concatenate(parts).astype(dtype) if parts else np.zeros(0, dtype)

    return PackedCollada(
        pieces, arrays, cat(digits, np.uint32), cat(flags, np.uint8), cat(exponents, np.int8), cat(indices, np.uint32)
    )


def unpack(packed: PackedCollada) -> str:
    """The Collada text of ``packed`` (packed arrays written with single spaces)."""
    out = [packed.pieces[0]]
    f = e = i = 0
    for j, spec in enumerate(packed.arrays):
        n = spec[1]
        if spec[0] == "f":
            flags = packed.flags[f : f + n]
            n_exp = int(np.count_nonzero(flags & _EXPONENT))
            tokens = _format_decimals(packed.digits[f : f + n], flags, packed.exponents[e : e + n_exp])
            f, e = f + n, e + n_exp
        else:
            tokens = [str(v) for v in _unzigzag_columns(packed.indices[i : i + n], n, spec[2]).tolist()]
            i += n
        out += [" ".join(tokens), packed.pieces[j + 1]]
    return "".join(out)
