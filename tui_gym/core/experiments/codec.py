"""How the run history stores a run's curves (a few bytes each) and its finished tasks
(`TaskRecord`s), and reads them back."""

from __future__ import annotations

import json
import math
import struct
import zlib
from collections.abc import Mapping
from typing import Any

import numpy as np

from tui_gym.core.experiments.records import TaskRecord, to_json_text

FORMAT_FLOAT16 = 1
_RAW, _ZLIB, _EVEN = 0, 1, 2
_TOP_EXPONENT = 14  # the largest magnitude is scaled into [2**14, 2**15)
_MAX_EXPONENT = 1100  # a float64 scaled from float16 needs no more
_MAX_VARINT = 10  # bytes of a 64-bit varint


class CurveFormatError(ValueError):
    """Bytes that are not a stored curve."""


def _uvarint(value: int, out: bytearray) -> None:
    while value > 0x7F:
        out.append(value & 0x7F | 0x80)
        value >>= 7
    out.append(value)


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
        first = int(episodes[0])
        _uvarint(first * 2 if first >= 0 else -first * 2 - 1, gaps)  # zigzag: small either way
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
    finite = np.abs(values[~np.isnan(values)])
    top = float(finite.max()) if len(finite) else 0.0
    # The largest magnitude scaled into [2**14, 2**15): float16 keeps its digits.
    exponent = 0 if top == 0.0 else math.frexp(top)[1] - 1 - _TOP_EXPONENT
    out += struct.pack("<h", exponent)
    scaled = np.ldexp(values, -exponent)
    out += scaled.astype("<f2").tobytes()
    return bytes(out)


def decode_curve(data: bytes) -> tuple[np.ndarray, np.ndarray]:
    """(episodes, values) from the bytes `encode_curve` made; CurveFormatError otherwise
    (checked against the bytes there are before anything is allocated or inflated)."""
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
    gaps = _inflate(body, _MAX_VARINT * max(n, 1)) if mode == _ZLIB else bytes(body)
    if gaps is None:
        raise CurveFormatError("episodes that do not inflate within the bytes their points take")
    episodes = np.empty(n, dtype=np.int64)
    try:
        if n:
            first, at = _read_uvarint(gaps, 0)
            episodes[0] = first // 2 if first % 2 == 0 else -(first + 1) // 2
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


def _inflate(data: bytes, limit: int) -> bytes | None:
    """`data` decompressed, None if it does not decompress whole within `limit` bytes."""
    inflater = zlib.decompressobj()
    try:
        found = inflater.decompress(data, limit)
    except zlib.error:
        return None
    return None if inflater.unconsumed_tail or not inflater.eof else found


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


MAX_TASK_BYTES = 64 * 1024 * 1024  # what one task's arrays may take once decompressed
LEVEL = 1  # zlib's quickest: several times quicker than its default, nearly as small


class BadTask(ValueError):
    """A stored task that does not read as what tui-gym writes."""


def encode(task: TaskRecord) -> tuple[int, str, bytes, bytes | None]:
    """The row's first row, inputs, returns and exact values."""
    returns = np.ascontiguousarray(task.returns, dtype="<f8")
    if returns.shape != (len(task.rows), task.episodes) or len(task.seeds) != len(task.rows):
        raise ValueError("a task's returns must be one row of `episodes` per seed")
    exact = None
    if task.exact is not None:
        exact = zlib.compress(np.ascontiguousarray(task.exact, dtype="<f8").tobytes(), LEVEL)
    return (min(task.rows), to_json_text(task.inputs(), "a task's inputs"),
            zlib.compress(returns.tobytes(), LEVEL), exact)


def _array(blob: object, shape: tuple[int, int], what: str) -> np.ndarray:
    if not isinstance(blob, bytes):
        raise BadTask(f"its {what} are not a blob")
    data = _inflate(blob, MAX_TASK_BYTES + 1)
    if data is None or len(data) != shape[0] * shape[1] * 8:
        raise BadTask(f"its {what} are not {shape[0]} × {shape[1]} numbers")
    return np.frombuffer(data, dtype="<f8").reshape(shape).astype(np.float64)


def _ints(value: object, what: str) -> tuple[int, ...]:
    if not isinstance(value, list) or not value or not all(
            isinstance(v, int) and not isinstance(v, bool) and v >= 0 for v in value):
        raise BadTask(f"its {what} are not a list of whole numbers")
    return tuple(value)


def decode_rows(inputs: object) -> tuple[int, ...]:
    """The rows a stored task's inputs name; BadTask if they do not read."""
    return _ints(_inputs(inputs).get("rows"), "rows")


def _inputs(inputs: object) -> dict[str, Any]:
    try:
        data = json.loads(inputs) if isinstance(inputs, str) else None
    except ValueError:
        data = None
    if not isinstance(data, dict):
        raise BadTask("its inputs are not a JSON object")
    return data


def decode(inputs: object, returns: object, exact: object) -> TaskRecord:
    """A stored task's row as a `TaskRecord`; BadTask if it does not read."""
    data = _inputs(inputs)
    rows, seeds = _ints(data.get("rows"), "rows"), _ints(data.get("seeds"), "seeds")
    episodes, checkpoints = data.get("episodes"), data.get("checkpoints")
    if len(rows) != len(seeds) or not isinstance(episodes, int) or episodes < 1:
        raise BadTask("its seeds, rows and episodes do not agree")
    hp = data.get("hyperparameters")
    if not isinstance(hp, dict) or not isinstance(data.get("algorithm"), str):
        raise BadTask("its algorithm or hyperparameters do not read")
    table = None
    if checkpoints is not None:
        if not isinstance(checkpoints, int) or checkpoints < 0:
            raise BadTask("its count of checkpoints is not a whole number")
        table = _array(exact, (len(rows), checkpoints), "exact values")
    return TaskRecord(rows, seeds, episodes, _array(returns, (len(rows), episodes), "returns"),
                      table, data["algorithm"], hp)
