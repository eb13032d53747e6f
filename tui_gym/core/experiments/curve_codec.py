"""Curves as a few bytes: how the run history stores a run's curves."""

from __future__ import annotations

import math
import struct
import zlib
from collections.abc import Mapping

import numpy as np

FORMAT_FLOAT16 = 1
_RAW, _ZLIB, _EVEN = 0, 1, 2
_TOP_EXPONENT = 14  # the largest magnitude is scaled into [2**14, 2**15)
_MAX_EXPONENT = 1100  # a float64 scaled from float16 needs no more
_MAX_VARINT = 10  # bytes of a 64-bit varint


class CurveFormatError(ValueError):
    """Bytes that are not a stored curve."""


def _uvarint(value: int, out: bytearray) -> None:
    while True:
        byte = value & 0x7F
        value >>= 7
        if value:
            out.append(byte | 0x80)
        else:
            out.append(byte)
            return


def _read_uvarint(data: bytes, pos: int) -> tuple[int, int]:
    value = shift = 0
    while True:
        if pos >= len(data) or shift > 63:
            raise CurveFormatError("truncated number")
        byte = data[pos]
        pos += 1
        value |= (byte & 0x7F) << shift
        if not byte & 0x80:
            return value, pos
        shift += 7


def _zigzag(value: int) -> int:
    return value * 2 if value >= 0 else -value * 2 - 1


def _unzigzag(value: int) -> int:
    return value // 2 if value % 2 == 0 else -(value + 1) // 2


def _scale_exponent(values: np.ndarray) -> int:
    finite = np.abs(values[~np.isnan(values)])
    top = float(finite.max()) if len(finite) else 0.0
    if top == 0.0:
        return 0
    return math.frexp(top)[1] - 1 - _TOP_EXPONENT  # top / 2**e lands in [2**14, 2**15)


def encode_curve(episodes: np.ndarray, values: np.ndarray) -> bytes:
    """The bytes of a curve (episodes strictly increasing integers, values finite or NaN)."""
    episodes = np.asarray(episodes, dtype=np.int64)
    values = np.asarray(values, dtype=np.float64)
    n = len(values)
    out = bytearray([FORMAT_FLOAT16])
    _uvarint(n, out)
    gaps = bytearray()
    steps = np.diff(episodes)
    if n:
        _uvarint(_zigzag(int(episodes[0])), gaps)
    if n > 1 and (steps == steps[0]).all():
        mode = _EVEN
        _uvarint(int(steps[0]), gaps)
        body = bytes(gaps)
    else:
        for gap in steps.tolist():
            _uvarint(gap, gaps)
        packed = zlib.compress(bytes(gaps), 9)
        mode, body = (_ZLIB, packed) if len(packed) < len(gaps) else (_RAW, bytes(gaps))
    out.append(mode)
    _uvarint(len(body), out)
    out += body
    exponent = _scale_exponent(values)
    out += struct.pack("<h", exponent)
    scaled = np.ldexp(values, -exponent)
    out += scaled.astype("<f2").tobytes()
    return bytes(out)


def decode_curve(data: bytes) -> tuple[np.ndarray, np.ndarray]:
    """(episodes, values) from the bytes `encode_curve` made; CurveFormatError otherwise.

    The point count is checked against the bytes there are before anything is
    allocated, and the episodes inflate to at most the bytes that count needs.
    """
    if not data or data[0] != FORMAT_FLOAT16:
        raise CurveFormatError("unknown curve format")
    n, pos = _read_uvarint(data, 1)
    if pos >= len(data):
        raise CurveFormatError("truncated curve")
    mode = data[pos]
    if mode not in (_RAW, _ZLIB, _EVEN):
        raise CurveFormatError("unknown episode encoding")
    length, pos = _read_uvarint(data, pos + 1)
    if len(data) != pos + length + 2 + 2 * n:
        raise CurveFormatError(f"curve of the wrong length for {n:,} points")
    body = data[pos : pos + length]
    pos += length
    gaps = _inflate(body, n) if mode == _ZLIB else bytes(body)
    episodes = np.empty(n, dtype=np.int64)
    try:
        if n:
            first, at = _read_uvarint(gaps, 0)
            episodes[0] = _unzigzag(first)
            if mode == _EVEN and n > 1:
                step, at = _read_uvarint(gaps, at)
                if step < 1 or int(episodes[0]) + step * (n - 1) >= 2**63:
                    raise CurveFormatError("episodes out of range")
                episodes[1:] = episodes[0] + step * np.arange(1, n)
            else:
                for i in range(1, n):
                    gap, at = _read_uvarint(gaps, at)
                    episodes[i] = episodes[i - 1] + gap
    except OverflowError:
        raise CurveFormatError("episodes out of range") from None
    (exponent,) = struct.unpack_from("<h", data, pos)
    if abs(exponent) > _MAX_EXPONENT:
        raise CurveFormatError("values out of range")
    scaled = np.frombuffer(data, dtype="<f2", count=n, offset=pos + 2)
    return episodes, np.ldexp(scaled.astype(np.float64), exponent)


def _inflate(body: bytes, n: int) -> bytes:
    """The episodes' gaps, inflated to at most the bytes n points can take."""
    limit = _MAX_VARINT * max(n, 1)
    inflater = zlib.decompressobj()
    try:
        gaps = inflater.decompress(body, limit)
    except zlib.error as exc:
        raise CurveFormatError(f"damaged episodes ({exc})") from None
    if inflater.unconsumed_tail or not inflater.eof:
        raise CurveFormatError(f"episodes that inflate past {limit:,} bytes or stop short")
    return gaps


def pack_curves(curves: Mapping[str, bytes]) -> bytes:
    """One blob holding several encoded curves by name."""
    out = bytearray()
    _uvarint(len(curves), out)
    for name, data in curves.items():
        encoded = name.encode("utf-8")
        _uvarint(len(encoded), out)
        out += encoded
        _uvarint(len(data), out)
        out += data
    return bytes(out)


def unpack_curves(blob: bytes) -> dict[str, bytes]:
    """The encoded curves of a blob `pack_curves` made, by name."""
    count, pos = _read_uvarint(blob, 0)
    curves: dict[str, bytes] = {}
    for _ in range(count):
        length, pos = _read_uvarint(blob, pos)
        name_bytes = blob[pos : pos + length]
        pos += length
        length, pos = _read_uvarint(blob, pos)
        if pos + length > len(blob):
            raise CurveFormatError("truncated curves")
        try:
            name = name_bytes.decode("utf-8")
        except UnicodeDecodeError:
            raise CurveFormatError("a curve's name is not text") from None
        curves[name] = blob[pos : pos + length]
        pos += length
    if pos != len(blob):
        raise CurveFormatError("curves of the wrong length")
    return curves
