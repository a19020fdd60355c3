"""A host stand-in for the JeVois ``libjevois`` Python bindings: exactly the names ForaNav's module uses.

Modelled on jevois/src/jevois/Core/PythonSupport.C (1.18+). Semantics kept from the camera:
- ``sendSerial(line)`` appends the line ending itself (CRLF, the serial port's default); no ``\\n`` in the line.
- ``Timer(prefix, interval, loglevel)``: ``stop()`` returns "-- fps, --% CPU" until ``interval`` frames were
  timed, then "<fps> fps, <cpu>% CPU" refreshed every ``interval`` frames; the periodic log line goes to
  the log stream.
- ``Parameter(component, name, type, description, default, category)`` has ``get()``/``set()``; values are
  checked against the type as the engine does. ``setCallback(cb)`` (as PythonParameter.H): ``cb(value)`` is
  called once at once with the current value, then before every change; if it raises, the change is refused
  and the old value stays (the engine then answers ``ERR ...``).
- ``InputFrame.getCvBGR()/getCvGRAY()/getCvRGB()`` return copies; ``OutputFrame.sendCv(img)`` rescales to
  the output size (like the camera) and keeps the image.
- ``LINFO/LERROR/LDEBUG`` log one string; ``LFATAL`` logs and raises.
State (serial and log streams, line ending, frame counter) is module-level, as on the camera: one module at
a time. ``reset()`` puts all of it back to its start values, so that nothing one run leaves behind reaches the
next one in the same process (a worker flies thousands of flights in a row); the loader calls it.

This file is also run by the camera's own runtime (Python 3.7, numpy 1.16, OpenCV 4.10, see
``camera_driver.py``): keep it to that subset.
"""
from __future__ import annotations

import sys
import time
from typing import Any, Callable, NoReturn

import cv2
import numpy as np

LOG_DEBUG, LOG_INFO, LOG_ERR, LOG_CRIT = 7, 6, 3, 2
pro = False
platform = False  # the JeVois-A33 build of the bindings reports platform False on a host
version_major, version_minor, version_patch = 1, 23, 0

_serial_stream = None
_log_stream = sys.stderr
_line_ending = "\r\n"
_frame_number = 0


def configure(serial_stream: Any = None, log_stream: Any = None, line_ending: str = "\r\n") -> None:
    """Host only: where sendSerial() and the log go (text or binary streams; None drops serial output)."""
    global _serial_stream, _log_stream, _line_ending
    _serial_stream = serial_stream
    _log_stream = log_stream if log_stream is not None else sys.stderr
    _line_ending = line_ending


def reset() -> None:
    """Host only: every piece of module-level state back to its start value (no serial sink, frame 0)."""
    configure()
    set_frame_number(0)


def set_frame_number(number: int) -> None:
    """Host only: the value frameNum() returns (the runner counts its own frames)."""
    global _frame_number
    _frame_number = int(number)


def _write(stream: Any, text: str) -> None:
    if stream is None:
        return
    try:
        stream.write(text)
    except TypeError:  # binary stream (a pty, a serial port)
        stream.write(text.encode("ascii", "replace"))
    if hasattr(stream, "flush"):
        stream.flush()


def sendSerial(string: str) -> None:
    _write(_serial_stream, str(string) + _line_ending)


def frameNum() -> int:
    return _frame_number


def _log(prefix: str, message: str) -> None:
    _write(_log_stream, "%s %s\n" % (prefix, message))


def LDEBUG(message: str) -> None:
    pass  # compiled out on the camera


def LINFO(message: str) -> None:
    _log("INF", message)


def LERROR(message: str) -> None:
    _log("ERR", message)


def LFATAL(message: str) -> NoReturn:
    _log("FTL", message)
    raise RuntimeError(message)


class Timer:
    def __init__(self, prefix: str, interval: int, loglevel: int):
        self.prefix = str(prefix)
        self.interval = max(1, int(interval))
        self.loglevel = int(loglevel)
        self.text = "-- fps, --% CPU"
        self._count = 0
        self._busy = 0.0
        self._started = None
        self._window_wall = None
        self._window_cpu = None

    def start(self) -> None:
        now = time.perf_counter()
        if self._window_wall is None:
            self._window_wall, self._window_cpu = now, time.process_time()
        self._started = now

    def stop(self) -> str:
        if self._started is None:
            return self.text
        now = time.perf_counter()
        self._busy += now - self._started
        self._count += 1
        if self._count >= self.interval:
            wall = max(now - self._window_wall, 1e-9)
            cpu = 100.0 * (time.process_time() - self._window_cpu) / wall
            fps = self._count / wall
            self.text = "%.1f fps, %.1f%% CPU" % (fps, cpu)
            if self.loglevel == LOG_INFO:
                LINFO("%s average (%d) duration %.2fms (%.1f fps)"
                      % (self.prefix, self._count, 1000.0 * self._busy / self._count, fps))
            self._count, self._busy = 0, 0.0
            self._window_wall, self._window_cpu = now, time.process_time()
        return self.text


class ParameterCategory:
    def __init__(self, name: str, description: str):
        self.name, self.description = str(name), str(description)


_TYPES = {"bool": bool, "char": str, "byte": int, "uint8": int, "int16": int, "uint16": int, "int": int,
          "int32": int, "uint": int, "uint32": int, "long": int, "int64": int, "uint64": int, "float": float,
          "double": float, "str": str}


class Parameter:
    """A module parameter; the engine's setpar/getpar are host_tools.jevois_host.ModuleRunner.setpar/getpar."""

    def __init__(self, component: object, name: str, type_str: str, description: str, default: Any,
                 category: ParameterCategory):
        if type_str not in _TYPES:
            raise ValueError("Unsupported parameter type %r; valid: %s" % (type_str, ", ".join(sorted(_TYPES))))
        self.component, self.name, self.type_str = component, str(name), type_str
        self.description, self.category = str(description), category
        self._value = self._convert(default)
        self._callback = None
        registry = component.__dict__.setdefault("_jevois_host_parameters", {})
        if self.name in registry:
            raise ValueError("Parameter %s already exists" % self.name)
        registry[self.name] = self

    def _convert(self, value: Any) -> Any:
        kind = _TYPES[self.type_str]
        if kind is bool and isinstance(value, str):
            if value.lower() not in ("true", "false", "1", "0"):
                raise ValueError("Parameter %s: bad bool %r" % (self.name, value))
            return value.lower() in ("true", "1")
        return kind(value)

    def get(self) -> Any:
        return self._value

    def set(self, value: Any) -> None:
        value = self._convert(value)
        if self._callback is not None:
            self._callback(value)  # raises to refuse the value
        self._value = value

    def setCallback(self, callback: Callable[[Any], None]) -> None:
        callback(self._value)
        self._callback = callback


def parameters(component: object) -> dict[str, Parameter]:
    """Host only: {name: Parameter} created by a module instance."""
    return component.__dict__.get("_jevois_host_parameters", {})


class InputFrame:
    """One camera frame (BGR on the host)."""

    def __init__(self, bgr: np.ndarray):
        self._bgr = np.ascontiguousarray(bgr)

    def getCvBGR(self, casync: bool = False) -> np.ndarray:
        return self._bgr.copy()

    def getCvGRAY(self, casync: bool = False) -> np.ndarray:
        return cv2.cvtColor(self._bgr, cv2.COLOR_BGR2GRAY)

    def getCvRGB(self, casync: bool = False) -> np.ndarray:
        return cv2.cvtColor(self._bgr, cv2.COLOR_BGR2RGB)

    def getCvRGBA(self, casync: bool = False) -> np.ndarray:
        return cv2.cvtColor(self._bgr, cv2.COLOR_BGR2RGBA)

    def done(self) -> None:
        pass


class OutputFrame:
    """The USB video output of one frame; keeps what the module sent in ``image`` (BGR)."""

    def __init__(self, width: int, height: int):
        self.width, self.height = int(width), int(height)
        self.image = None

    def sendCv(self, img: np.ndarray, quality: int = 75) -> None:
        if img.ndim == 2:
            img = cv2.cvtColor(img, cv2.COLOR_GRAY2BGR)
        elif img.shape[2] == 4:
            img = cv2.cvtColor(img, cv2.COLOR_BGRA2BGR)
        if (img.shape[1], img.shape[0]) != (self.width, self.height):
            img = cv2.resize(img, (self.width, self.height), interpolation=cv2.INTER_AREA)
        self.image = img.copy()

    def sendCvBGR(self, img: np.ndarray, quality: int = 75) -> None:
        if (img.shape[1], img.shape[0]) != (self.width, self.height):
            raise ValueError("sendCvBGR: image is %dx%d, output is %dx%d"
                             % (img.shape[1], img.shape[0], self.width, self.height))
        self.image = img.copy()

    def sendScaledCvBGR(self, img: np.ndarray, quality: int = 75) -> None:
        self.sendCv(img, quality)
