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


class _Tokens:
    """The whitespace-separated tokens of an ASCII text, read with array operations on its bytes (a regular
    expression or a per-token loop costs seconds on a robot's meshes).

    ``chars`` is the text's bytes; per character, ``token`` is the index of the token it belongs to (-1 for
    whitespace); ``first`` indexes each token's first character.  ``None`` from :meth:`read` for a text
    that is not ASCII, starts with whitespace or holds a byte outside ``allowed``.
    """

    def __init__(self, chars: np.ndarray, token: np.ndarray, first: np.ndarray) -> None:
        self.chars, self.token, self.first = chars, token, first

    @classmethod
    def read(cls, content: str, allowed: bytes) -> _Tokens | None:
        try:
            chars = np.frombuffer(content.encode("ascii"), np.uint8)
        except UnicodeEncodeError:
            return None
        space = (chars == 32) | ((chars >= 9) & (chars <= 13))
        if chars.size and space[0]:
            return None
        if not np.isin(chars[~space], np.frombuffer(allowed, np.uint8)).all():
            return None
        starts = ~space & np.concatenate(([True], space[:-1]))
        token = np.where(space, -1, np.cumsum(starts, dtype=np.int32) - 1)
        return cls(chars, token, np.flatnonzero(starts))

    def before(self, mask: np.ndarray) -> np.ndarray:
        """Per character, how many characters of ``mask`` precede it in its token."""
        counts = np.cumsum(mask, dtype=np.int32) - mask
        return counts - counts[self.first][np.maximum(self.token, 0)]

    def counts(self, mask: np.ndarray) -> np.ndarray:
        """Per token, how many of its characters are in ``mask``."""
        return np.bincount(self.token[mask], minlength=self.first.size)

    def number(self, mask: np.ndarray, tokens: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Per token of ``tokens`` (sorted; each holds a character of ``mask``, and no other token does): the
        integer its ``mask`` digits spell (exact for at most 19 digits) and how many digits there are."""
        where = np.flatnonzero(mask)
        starts = np.searchsorted(self.token[where], tokens)
        places = np.diff(np.append(starts, where.size))
        if where.size == 0 or places.max() > 19:
            return np.zeros(tokens.size, np.uint64), places
        rank = np.arange(where.size) - np.repeat(starts, places)
        power = np.power(np.uint64(10), (np.repeat(places, places) - rank - 1).astype(np.uint64))
        terms = (self.chars[where].astype(np.uint64) - np.uint64(48)) * power
        return np.add.reduceat(terms, starts), places


def _pack_decimals(content: str) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """Digits, flags and exponents of a whitespace-separated decimal list, or None if one would not
    read back exactly (the grammar admits only tokens :func:`_format_decimals` writes back as they are:
    ``[-]D[.F][e[-]E]``, ``D`` and ``E`` without leading zeros)."""
    tokens = _Tokens.read(content, b"0123456789.-e")
    if tokens is None:
        return None
    c = tokens.chars
    if c.size == 0:
        return np.zeros(0, np.uint32), np.zeros(0, np.uint8), np.zeros(0, np.int8)
    digit = (c >= 48) & (c <= 57)
    minus, dot, e = c == 45, c == 46, c == 101
    previous = np.concatenate(([32], c[:-1]))
    following = np.concatenate((c[1:], [32]))
    prev_digit = (previous >= 48) & (previous <= 57)
    next_digit = (following >= 48) & (following <= 57)
    in_exponent = tokens.before(e) > 0
    in_fraction = tokens.before(dot) > 0
    first = np.zeros(c.size, bool)
    first[tokens.first] = True
    bad = (
        (minus & ~(first | (previous == 101)))  # a sign opens the token or the exponent
        | ((minus | dot) & ~next_digit)
        | (dot & (~prev_digit | in_exponent | in_fraction))  # one point, between digits
        | (e & (~prev_digit | ~(next_digit | (following == 45)) | in_exponent))  # one exponent after a digit
        | ((c == 48) & next_digit & ~prev_digit & (previous != 46))  # a leading zero
    )
    if bad.any():
        return None
    ids = np.arange(tokens.first.size)
    mantissa = digit & ~in_exponent
    digits, places = tokens.number(mantissa, ids)
    fraction_digits = tokens.counts(mantissa & in_fraction)
    if places.max() > 19 or fraction_digits.max() > _MAX_FRACTION or digits.max() >= 2**32:
        return None
    has_exponent = np.zeros(ids.size, bool)
    has_exponent[tokens.token[e]] = True
    with_e = np.flatnonzero(has_exponent)
    magnitudes, exponent_places = tokens.number(digit & in_exponent, with_e)
    if exponent_places.size and exponent_places.max() > 3:
        return None
    negative_exponent = np.zeros(ids.size, bool)
    negative_exponent[tokens.token[minus & in_exponent]] = True
    values = np.where(negative_exponent[with_e], -magnitudes.astype(np.int64), magnitudes.astype(np.int64))
    if np.any(values < -128) or np.any(values > 127):
        return None
    negative = c[tokens.first] == 45
    flags = fraction_digits | np.where(negative, _NEGATIVE, 0) | np.where(has_exponent, _EXPONENT, 0)
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
    tokens = _Tokens.read(content, b"0123456789")
    if tokens is None:
        return None
    ids = np.arange(tokens.first.size)
    if ids.size % k:
        return None
    values, places = tokens.number(tokens.token >= 0, ids)
    if places.size and (places.max() > 9 or np.any((tokens.chars[tokens.first] == 48) & (places > 1))):
        return None  # more than 9 digits, or a leading zero
    return _zigzag_columns(values.astype(np.int64), k), ids.size


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
