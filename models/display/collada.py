"""Lossless binary packing of the numbers in Collada (``.dae``) text.

Collada meshes are XML whose bulk is decimal text: ``<float_array>`` (positions, normals, texture
coordinates) and the index lists ``<p>`` of the primitives. Deflate compresses that text about
three times; storing the numbers as integers compresses it about five times. The packing is exact:
:func:`unpack` rebuilds the same text, token for token. Only the whitespace between the numbers of
a packed array is rewritten (single spaces), which Collada readers treat alike.

A decimal token ``[-]D[.F][eE]`` (``D`` and ``E`` without leading zeros, no ``+``) becomes

* ``digits`` (uint32): the integer ``DF`` (integer and fraction digits run together);
* ``flags`` (uint8): the number of fraction digits (bits 0-4), ``-`` (bit 5), has ``e`` (bit 6);
* ``exponents`` (int8): ``E``, for the tokens that have one.

It is written back as ``digits`` padded with zeros to ``fraction + 1`` digits, with the point
before the last ``fraction`` digits. An index list ``<p>`` of a primitive with ``k`` inputs
(``k = 1 + max offset``) is read as ``m x k`` integers; each column is stored as its first
differences in zig-zag form (``2d`` for ``d >= 0``, ``-2d - 1`` otherwise), columns one after the
other, in ``indices`` (uint32; at most 9 digits per index). The token grammar admits exactly the
tokens that are written back as they were; arrays with any other token stay text.
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
_NUMBER = r"(?:0|[1-9]\d*)"
_DECIMAL = re.compile(rf"(-?)({_NUMBER})(?:\.(\d+))?(?:e(-?{_NUMBER}))?")
_DECIMAL_LIST = re.compile(rf"(?:-?{_NUMBER}(?:\.\d+)?(?:e-?{_NUMBER})?(?:\s+|$))*")
_INDEX_LIST_TOKENS = re.compile(rf"(?:{_NUMBER}(?:\s+|$))*")
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


def _pack_decimals(content: str) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """Digits, flags and exponents of a whitespace-separated decimal list, or None if one would not
    read back exactly (the grammar admits only tokens :func:`_format_decimals` writes back as they are)."""
    if _DECIMAL_LIST.fullmatch(content) is None:
        return None
    parts = _DECIMAL.findall(content)
    if not parts:
        return np.zeros(0, np.uint32), np.zeros(0, np.uint8), np.zeros(0, np.int8)
    signs, wholes, fractions, exponents = (np.array(p) for p in zip(*parts))
    fraction_digits = np.char.str_len(fractions)
    digit_strings = np.char.add(wholes, fractions)
    if fraction_digits.max() > _MAX_FRACTION or np.char.str_len(digit_strings).max() > 19:
        return None
    digits = digit_strings.astype(np.uint64)
    has_exponent = exponents != ""
    values = exponents[has_exponent].astype(np.int64)
    if digits.max() >= 2**32 or np.any(values < -128) or np.any(values > 127):
        return None
    flags = fraction_digits | np.where(signs == "-", _NEGATIVE, 0) | np.where(has_exponent, _EXPONENT, 0)
    return digits.astype(np.uint32), flags.astype(np.uint8), values.astype(np.int8)


def _zigzag_columns(values: np.ndarray, k: int) -> np.ndarray:
    columns = values.reshape(-1, k).T
    d = np.diff(columns, axis=1, prepend=0).astype(np.int64)
    return ((d << 1) ^ (d >> 63)).astype(np.uint32).reshape(-1)


def _unzigzag_columns(z: np.ndarray, n: int, k: int) -> np.ndarray:
    z = z.astype(np.int64).reshape(k, n // k)
    d = (z >> 1) ^ -(z & 1)
    return np.cumsum(d, axis=1).T.reshape(-1)


def _pack_indices(content: str, k: int) -> tuple[np.ndarray, int] | None:
    """Zig-zag column differences of a whitespace-separated list of ``k``-column indices, and its length."""
    if _INDEX_LIST_TOKENS.fullmatch(content) is None:
        return None
    tokens = np.array(content.split())
    if tokens.size % k or (tokens.size and np.char.str_len(tokens).max() > 9):
        return None
    values = tokens.astype(np.int64)
    return _zigzag_columns(values, k), values.size


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
        if k == 0:
            packed = _pack_decimals(text[start:end])
            if packed is None:
                continue
            digits.append(packed[0])
            flags.append(packed[1])
            exponents.append(packed[2])
            arrays.append(("f", len(packed[0])))
        else:
            z = _pack_indices(text[start:end], k)
            if z is None:
                continue
            indices.append(z[0])
            arrays.append(("i", z[1], k))
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
