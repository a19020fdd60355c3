"""ctypes binding of the C navigation core (crazyflie_app/bolt/src, built as build/libforanav_nav.so).

``CNavigationCore(params, flight_path, target_label=None)`` has the calls and attributes of
``navigation_core.NavigationCore`` that the app, the harness and the tests use (``step``, ``on_frame``,
``on_frame_mark``, ``start``, ``abort_no_deck``, ``phase``, ``target_id``, ``counters``, ``memory``, ``events``,
...), plus the camera input of the C app (``feed``, ``end_batch``): bytes in, frames handed to the core.
``params`` is a ``CParams`` view on the C struct itself, with the field names of ``NavigationParams``, so a
PARAM write (``app.altitude``) lands in the C core at once, as on the Bolt.

The library is built by ``make capp`` (part of ``make setup``/``make test``); if it is missing or older than
its sources it is built here with the host gcc (``-Wall -Wextra -Werror``). ``FORANAV_CAPP_LIB`` names another
build to load instead (the sanitizer build: ``make capp-asan``).
"""
import ctypes
import math
import os
import subprocess
import tempfile
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

from crazyflie_app.app.nav_types import focal_px
from crazyflie_app.app.navigation_core import Command, Counters, Detection, Event, NavigationParams

REPO = Path(__file__).resolve().parents[2]
SOURCE_DIR = Path(__file__).resolve().parent / "src"
# the core's files are nav_*: all of them, with the host-only nav_host.c (the Bolt's src/Kbuild lists them too)
SOURCES = tuple(sorted(path.name for path in SOURCE_DIR.glob("nav_*.c")))
HEADERS = tuple(sorted(path.name for path in SOURCE_DIR.glob("nav_*.h")))
LIBRARY = REPO / "build" / "libforanav_nav.so"
HOST_CFLAGS = ("-std=c11", "-O2", "-Wall", "-Wextra", "-Werror", "-fPIC", "-shared")
EVENT_KINDS = ("phase", "tree_added", "tree_evicted", "target_selected", "tree_reached", "recovery",
               "approach_by_memory", "reacquired", "abandoned", "waypoint", "link_lost", "link_restored", "revisit",
               "tree_absorbed")
LINE_KINDS = (None, "T2", "N2", "MARK START", "MARK STOP")
TEXT_SIZE = 160
MAX_ROWS = 256
# a frame the C camera input handed to the core: (detections [(u, v)], tree ids, ground points [(x, y)])
CFrame = tuple[list[tuple[float, float]], list[int], list[tuple[float, float]]]

_D, _I = ctypes.c_double, ctypes.c_int32
# NavParams of nav_core.h, in its order; the names are NavigationParams' fields (a test checks they agree)
_INT_PARAMS = {"takeoff_settle_ms", "land_step_ms", "settle_dwell_ms", "settle_grace_ms", "lost_timeout_ms",
               "recovery_timeout_ms", "target_timeout_ms", "anchor_min_trees", "min_hits", "tree_capacity", "visited_capacity",
               "cam_width_px", "cam_height_px", "cam_latency_ms", "link_hold_ms", "link_land_ms", "camera_wait_ms",
               "frame_capacity", "start"}
PARAM_NAMES = (
    "altitude_m", "takeoff_tolerance_m", "takeoff_settle_ms", "land_height_m", "land_final_m", "land_step_ms",
    "arrival_min_speed", "cruise_speed", "waypoint_tolerance_m", "lookahead_m", "approach_speed", "servo_gain",
    "capture_radius_px", "settle_radius_px", "settle_dwell_ms", "settle_speed", "settle_relax", "settle_grace_ms",
    "servo_integral", "servo_integral_band", "recovery_distance_m", "lost_timeout_ms", "recovery_timeout_ms",
    "target_timeout_ms", "recovery_speed", "return_tolerance_m", "merge_radius_m", "duplicate_radius_m",
    "crown_size_m", "column_factor", "row_spacing_m", "anchor_min_trees", "anchor_gain",
    "min_hits", "tree_capacity", "visited_capacity", "cam_width_px", "cam_height_px", "cam_scale", "cam_offset_x_m",
    "cam_offset_y_m", "cam_latency_ms", "kf_measurement_std_px", "kf_accel_psd", "link_hold_ms", "link_land_ms",
    "camera_wait_ms", "frame_capacity", "start")
_PARAM_FIELDS = [(name, _I if name in _INT_PARAMS else _D) for name in PARAM_NAMES]


class CParams(ctypes.Structure):
    """NavParams of nav_core.h, read and written in place (attribute names as NavigationParams)."""
    _fields_ = _PARAM_FIELDS

    @property
    def focal_px(self) -> float:
        return focal_px(self.cam_scale, self.cam_width_px)


class _Status(ctypes.Structure):
    _fields_ = ([(name, _I) for name in ("phase", "target_id", "waypoint_index", "num_trees", "num_visited",
                                        "captured", "link_lost", "link_aborted", "has_target")]
                + [(name, ctypes.c_uint32) for name in (
                    "detections", "out_of_column", "on_visited", "reached", "recoveries", "abandoned", "link_losses",
                    "duplicates", "evicted", "forgotten", "lines_dropped", "other_labels", "frames", "frame_overflow",
                    "events_dropped", "unstored")]
                + [(name, _I) for name in ("pending_detections", "revisiting")]
                + [(name, _D) for name in ("err_u", "err_v", "target_x", "target_y")])


def build_library(output: str | os.PathLike = LIBRARY, extra_flags: Sequence[str] = (), compiler: str = "gcc") -> Path:
    """Compile the core into a shared library (temp file + rename: a concurrent loader never sees half)."""
    output = Path(output)
    output.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=str(output.parent), suffix=".so")
    os.close(fd)
    command = [compiler, *HOST_CFLAGS, *extra_flags, "-o", tmp] + [str(SOURCE_DIR / s) for s in SOURCES] + ["-lm"]
    try:
        subprocess.run(command, check=True, capture_output=True, text=True)
    except subprocess.CalledProcessError as err:
        os.unlink(tmp)
        raise RuntimeError("building the C core failed:\n%s" % err.stderr)
    os.replace(tmp, output)
    return output


def _stale(library: Path) -> bool:
    if not library.exists():
        return True
    built = library.stat().st_mtime
    return any((SOURCE_DIR / name).stat().st_mtime > built for name in SOURCES + HEADERS)


_LIB = None


def load_library() -> ctypes.CDLL:
    """The loaded library (built first when missing or stale, unless FORANAV_CAPP_LIB names one)."""
    global _LIB
    if _LIB is not None:
        return _LIB
    override = os.environ.get("FORANAV_CAPP_LIB")
    path = Path(override) if override else LIBRARY
    if not override and _stale(path):
        build_library(path)
    lib = ctypes.CDLL(str(path))
    P = ctypes.POINTER
    lib.navHostCreate.restype = ctypes.c_void_p
    lib.navHostCreate.argtypes = [P(CParams), P(_D), _I, ctypes.c_char_p]
    lib.navHostDestroy.argtypes = [ctypes.c_void_p]
    lib.navHostParams.restype = P(CParams)
    lib.navHostParams.argtypes = [ctypes.c_void_p]
    lib.navHostDefaults.argtypes = [P(CParams)]
    lib.navHostCameraAlive.restype = _I
    lib.navHostCameraAlive.argtypes = [ctypes.c_void_p, _I]
    for name in ("navHostStart", "navHostAbortNoDeck", "navHostAbortNoCamera", "navHostOnFrameMark"):
        getattr(lib, name).argtypes = [ctypes.c_void_p, _I]
    lib.navHostStep.restype = _I
    lib.navHostStep.argtypes = [ctypes.c_void_p, _I, P(_D), P(_D)]
    lib.navHostOnFrame.restype = _I
    lib.navHostOnFrame.argtypes = [ctypes.c_void_p, _I, P(_D), _I, P(_D), P(_I), P(_D)]
    lib.navHostFeed.restype = _I
    lib.navHostFeed.argtypes = [ctypes.c_void_p, ctypes.c_char_p, _I, _I, P(_D), _I, P(_I)]
    lib.navHostEndBatch.restype = _I
    lib.navHostEndBatch.argtypes = [ctypes.c_void_p, _I, P(_D), _I]
    lib.navHostLastFrame.restype = _I
    lib.navHostLastFrame.argtypes = [ctypes.c_void_p, P(_D), P(_I), P(_D)]
    lib.navHostStatus.argtypes = [ctypes.c_void_p, P(_Status)]
    for name in ("navHostTrees", "navHostVisited"):
        getattr(lib, name).restype = _I
        getattr(lib, name).argtypes = [ctypes.c_void_p, P(_D), _I]
    lib.navHostNextEvent.restype = _I
    lib.navHostNextEvent.argtypes = [ctypes.c_void_p, ctypes.c_char_p, _I, P(_I), P(_I), P(_D), P(_I),
                                     ctypes.c_char_p, _I]
    lib.navHostParseLine.restype = _I
    lib.navHostParseLine.argtypes = [ctypes.c_char_p, _I, ctypes.c_char_p, _I, P(_D)]
    lib.navHostFormatFixed.restype = _I
    lib.navHostFormatFixed.argtypes = [ctypes.c_char_p, _I, _D, _I]
    lib.navHostMaxFrameDetections.restype = _I
    lib.navHostSizeofParams.restype = _I
    if lib.navHostSizeofParams() != ctypes.sizeof(CParams):
        raise RuntimeError("%s: NavParams layout differs from NavigationParams (%d != %d bytes)"
                           % (path, lib.navHostSizeofParams(), ctypes.sizeof(CParams)))
    _LIB = lib
    return lib


def c_params(params: NavigationParams | None = None) -> CParams:
    """A CParams filled from a NavigationParams (default: the C defaults, which equal NavigationParams())."""
    out = CParams()
    if params is None:
        load_library().navHostDefaults(ctypes.byref(out))
    else:
        for name, _ in _PARAM_FIELDS:
            setattr(out, name, getattr(params, name))
    return out


def parse_line(line: bytes) -> tuple[str | None, str, float, float, float, float]:
    """The C parser on one line (bytes): (kind, label, x, y, w, h); kind None for a non-message."""
    lib = load_library()
    label = ctypes.create_string_buffer(80)
    xywh = (_D * 4)()
    kind = lib.navHostParseLine(line, len(line), label, len(label), xywh)
    return LINE_KINDS[kind], label.value.decode("ascii"), xywh[0], xywh[1], xywh[2], xywh[3]


@dataclass
class CTree:
    id: int
    x: float
    y: float
    hits: int = 0
    last_ms: int = 0


@dataclass
class CVisited:
    id: int
    x: float
    y: float
    t_ms: int
    reached: bool
    revisit: bool = False


class _MemoryView:
    """tree_memory.TreeMemory's read side: trees (dict by id, insertion order), visited, counters."""

    def __init__(self, core: "CNavigationCore"):
        self._core = core

    def _rows(self, fn: Callable, width: int) -> list[tuple]:
        out = (_D * (width * MAX_ROWS))()
        n = fn(self._core.handle, out, MAX_ROWS)
        return [tuple(out[width * i:width * i + width]) for i in range(n)]

    @property
    def trees(self) -> dict[int, CTree]:
        return {int(r[0]): CTree(int(r[0]), r[1], r[2], int(r[3]), int(r[4]))
                for r in self._rows(self._core.lib.navHostTrees, 5)}

    @property
    def visited(self) -> list[CVisited]:
        return [CVisited(int(r[0]), r[1], r[2], int(r[3]), bool(r[4]), bool(r[5]))
                for r in self._rows(self._core.lib.navHostVisited, 6)]

    def get(self, tree_id: int) -> CTree | None:
        return self.trees.get(tree_id)

    def __len__(self) -> int:
        return self._core.status().num_trees

    evicted = property(lambda self: self._core.status().evicted)
    unstored = property(lambda self: self._core.status().unstored)
    visited_forgotten = property(lambda self: self._core.status().forgotten)


class CNavigationCore:
    """The C core behind NavigationCore's interface. Events are moved into ``events`` after every call."""

    def __init__(self, params: NavigationParams | CParams | None, flight_path: Sequence[tuple[float, float]],
                 target_label: str | None = None):
        if len(flight_path) < 2:
            raise ValueError("the flight path needs at least 2 waypoints")
        self.lib = load_library()
        xy = [float(c) for point in flight_path for c in point]
        wanted = c_params(params) if not isinstance(params, CParams) else params
        handle = self.lib.navHostCreate(ctypes.byref(wanted), (_D * len(xy))(*xy), len(flight_path),
                                        (target_label or "").encode("ascii"))
        if not handle:
            raise ValueError("the C core takes 2 to 64 waypoints, got %d" % len(flight_path))
        self.handle = handle
        self.params = self.lib.navHostParams(handle).contents  # lives in the C struct
        self.path = tuple((float(x), float(y)) for x, y in flight_path)
        self.memory = _MemoryView(self)
        self.events = []
        self.last_frame_points = []
        self._pose = (_D * 6)()
        self._out = (_D * 3)()
        self._status = _Status()
        self._max_frame = self.lib.navHostMaxFrameDetections()

    def close(self) -> None:
        if self.handle:
            self.lib.navHostDestroy(self.handle)
            self.handle = None

    def __del__(self) -> None:
        try:
            self.close()
        except Exception:  # interpreter shutdown: the library may be gone already
            pass

    # -- calls ------------------------------------------------------------------------------------------------

    def _set_pose(self, pose: Sequence[float]) -> ctypes.Array:
        p = self._pose
        p[0], p[1], p[2], p[3], p[4], p[5] = pose
        return p

    def start(self, t_ms: int) -> None:
        self.lib.navHostStart(self.handle, int(t_ms))
        self._drain()

    def abort_no_deck(self, t_ms: int) -> None:
        self.lib.navHostAbortNoDeck(self.handle, int(t_ms))
        self._drain()

    def abort_no_camera(self, t_ms: int) -> None:
        self.lib.navHostAbortNoCamera(self.handle, int(t_ms))
        self._drain()

    def format_fixed(self, value: float, decimals: int) -> str:
        """The C console's number format ("%.*f", as the Bolt build prints it)."""
        out = ctypes.create_string_buffer(48)
        self.lib.navHostFormatFixed(out, len(out), float(value), int(decimals))
        return out.value.decode("ascii")

    def camera_alive(self, t_ms: int) -> bool:
        """The adapters' pre-flight check: a camera message within app.linkHoldMs (camWaitMs 0: none)."""
        return bool(self.lib.navHostCameraAlive(self.handle, int(t_ms)))

    def step(self, t_ms: int, pose: Sequence[float]) -> Command:
        kind = self.lib.navHostStep(self.handle, int(t_ms), self._set_pose(pose), self._out)
        self._drain()
        if kind == 0:
            return Command("null", 0.0, 0.0, 0.0)
        return Command("hover", self._out[0], self._out[1], self._out[2])

    def on_frame_mark(self, t_ms: int) -> None:
        self.lib.navHostOnFrameMark(self.handle, int(t_ms))

    def on_frame(self, t_ms: int, detections: Sequence[Detection], pose_now: Sequence[float]) -> list[int]:
        n = min(len(detections), self._max_frame)
        uv = (_D * (2 * max(n, 1)))(*[c for d in detections[:n] for c in (d.u, d.v)])
        ids, points = (_I * max(n, 1))(), (_D * (2 * max(n, 1)))()
        taken = self.lib.navHostOnFrame(self.handle, int(t_ms), uv, n, self._set_pose(pose_now), ids, points)
        self.last_frame_points = [(points[2 * i], points[2 * i + 1]) for i in range(taken)]
        self._drain()
        return [ids[i] for i in range(taken)]

    def feed(self, data: bytes, t_ms: int, pose_now: Sequence[float] | None, pose_valid: bool) -> list[CFrame]:
        """UART bytes into the camera input; returns [(detections [(u, v)], ids, points)] of the frames it
        handed to the core."""
        frames = []
        view = bytes(data)
        pose = self._set_pose(pose_now if pose_now is not None else (0.0,) * 6)
        done = _I()
        while view:
            used = self.lib.navHostFeed(self.handle, view, len(view), int(t_ms), pose, int(bool(pose_valid)),
                                        ctypes.byref(done))
            view = view[used:]
            if done.value:
                frames.append(self.last_frame())
        self._drain()
        return frames

    def end_batch(self, t_ms: int, pose_now: Sequence[float] | None, pose_valid: bool) -> list[CFrame]:
        pose = self._set_pose(pose_now if pose_now is not None else (0.0,) * 6)
        handed = self.lib.navHostEndBatch(self.handle, int(t_ms), pose, int(bool(pose_valid)))
        self._drain()
        return [self.last_frame()] if handed else []

    def last_frame(self) -> CFrame:
        m = self._max_frame
        uv, ids, points = (_D * (2 * m))(), (_I * m)(), (_D * (2 * m))()
        n = self.lib.navHostLastFrame(self.handle, uv, ids, points)
        self.last_frame_points = [(points[2 * i], points[2 * i + 1]) for i in range(n)]
        return ([(uv[2 * i], uv[2 * i + 1]) for i in range(n)], [ids[i] for i in range(n)],
                list(self.last_frame_points))

    def _drain(self) -> None:
        text, detail = ctypes.create_string_buffer(TEXT_SIZE), ctypes.create_string_buffer(64)
        kind, tree_id, t_ms, xy = _I(), _I(), _I(), (_D * 2)()
        while self.lib.navHostNextEvent(self.handle, text, TEXT_SIZE, ctypes.byref(kind), ctypes.byref(tree_id), xy,
                                        ctypes.byref(t_ms), detail, len(detail)):
            event = Event(EVENT_KINDS[kind.value], t_ms.value, tree_id.value, xy[0], xy[1],
                          detail.value.decode("ascii"))
            event.text = text.value.decode("ascii")  # the C console line (navFormatEvent)
            self.events.append(event)

    # -- state --------------------------------------------------------------------------------------------------

    def status(self) -> _Status:
        self.lib.navHostStatus(self.handle, ctypes.byref(self._status))
        return self._status

    phase = property(lambda self: self.status().phase)
    target_id = property(lambda self: self.status().target_id)
    waypoint_index = property(lambda self: self.status().waypoint_index)
    captured = property(lambda self: bool(self.status().captured))
    link_lost = property(lambda self: bool(self.status().link_lost))
    link_aborted = property(lambda self: bool(self.status().link_aborted))
    lines_dropped = property(lambda self: self.status().lines_dropped)
    other_labels = property(lambda self: self.status().other_labels)
    frames = property(lambda self: self.status().frames)
    frame_overflow = property(lambda self: self.status().frame_overflow)
    pending_detections = property(lambda self: self.status().pending_detections)
    revisiting = property(lambda self: bool(self.status().revisiting))

    @property
    def pixel_error(self) -> tuple[float, float]:
        s = self.status()
        return (s.err_u, s.err_v)

    @property
    def target_xy(self) -> tuple[float, float]:
        s = self.status()
        return (s.target_x, s.target_y) if s.has_target else (math.nan, math.nan)

    @property
    def counters(self) -> Counters:
        s = self.status()
        return Counters(s.detections, s.out_of_column, s.on_visited, s.reached, s.recoveries, s.abandoned,
                        s.link_losses, s.duplicates)
