"""How log and param values travel: the type codes of log.h and param.h, and C's conversions on the way.

The registry names types by their C spelling ("uint16_t", "float"); the TOCs carry them as codes. A log
block may fetch a variable as another type than it is stored as (cflib's ``fetch_as``); the firmware then
converts as C does (``valuei = v`` for a float fetched as an integer, the low bytes of ``valuei`` for a
narrower integer), which ``pack_log_value`` repeats: a float is truncated towards zero and saturated to
int32 (the Cortex-M4's VCVT; NaN gives 0), a float too large for float32 or FP16 becomes an infinity.
"""
import math
import struct

# log.h: LOG_UINT8 .. LOG_FLOAT, and LOG_FP16 (a fetch type only)
LOG_TYPE_CODES = {"uint8_t": 1, "uint16_t": 2, "uint32_t": 3, "int8_t": 4, "int16_t": 5, "int32_t": 6, "float": 7}
LOG_FP16 = 8
_LOG_FORMATS = {1: "<B", 2: "<H", 3: "<I", 4: "<b", 5: "<h", 6: "<i", 7: "<f", 8: "<e"}
_FLOAT_FETCHES = (7, LOG_FP16)

# param.h: PARAM_UINT8 .. PARAM_FLOAT (size, int/float and signedness bits) and the read-only flag
PARAM_TYPE_CODES = {"uint8_t": 0x08, "uint16_t": 0x09, "uint32_t": 0x0A, "int8_t": 0x00, "int16_t": 0x01,
                    "int32_t": 0x02, "float": 0x06}
PARAM_RONLY = 0x40
_PARAM_FORMATS = {"uint8_t": "<B", "uint16_t": "<H", "uint32_t": "<I", "int8_t": "<b", "int16_t": "<h",
                  "int32_t": "<i", "float": "<f"}
_INT32_MIN, _INT32_MAX = -2 ** 31, 2 ** 31 - 1


def log_type_size(code: int) -> int | None:
    """Bytes of a log fetch type, or None for a code log.h does not know."""
    fmt = _LOG_FORMATS.get(code)
    return None if fmt is None else struct.calcsize(fmt)


def _c_float_to_int(value: float) -> int:
    if math.isnan(value):
        return 0
    if math.isinf(value):
        return _INT32_MAX if value > 0 else _INT32_MIN
    return max(_INT32_MIN, min(_INT32_MAX, int(value)))


def _pack_float(fmt: str, value: float) -> bytes:
    try:
        return struct.pack(fmt, value)
    except OverflowError:  # beyond float32/FP16: C gives an infinity
        return struct.pack(fmt, math.copysign(math.inf, value))


def pack_log_value(value: float | int, fetch_code: int) -> bytes:
    """``value`` (as the registry reads it) fetched as log type ``fetch_code`` (a valid code)."""
    fmt = _LOG_FORMATS[fetch_code]
    if fetch_code in _FLOAT_FETCHES:
        return _pack_float(fmt, float(value))
    valuei = _c_float_to_int(value) if isinstance(value, float) else int(value)
    size = struct.calcsize(fmt)
    return (valuei & ((1 << (8 * size)) - 1)).to_bytes(size, "little")


def param_size(c_type: str) -> int:
    return struct.calcsize(_PARAM_FORMATS[c_type])


def pack_param_value(value: float | int, c_type: str) -> bytes:
    """A param's value as it sits in the firmware's memory (little-endian, the param's own size)."""
    if c_type == "float":
        return _pack_float("<f", float(value))
    size = param_size(c_type)
    return (int(value) & ((1 << (8 * size)) - 1)).to_bytes(size, "little")


def unpack_param_value(raw: bytes, c_type: str) -> float | int:
    """The value a client wrote: exactly ``param_size(c_type)`` bytes."""
    return struct.unpack(_PARAM_FORMATS[c_type], raw)[0]
