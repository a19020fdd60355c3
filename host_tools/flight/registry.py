"""The flight harness's registries and options: the cameras (``register_camera``, ``camera_factory``), the
flight apps (``register_app``: the Python app and the C core, both reading the emulated UART2), and the
flight options (``DEFAULT_OPTIONS``, checked by ``check_options``). Re-exported by ``host_tools.flight.harness``.
"""
import importlib
from collections.abc import Callable, Sequence
from typing import Any, Protocol

from crazyflie_app.bolt.c_app import CNavigationApp  # the C core's library is loaded (built if stale) on first use
from crazyflie_app.firmware import Crazyflie
from crazyflie_app.firmware.system import PLANTS
from crazyflie_app.app.navigation import NavigationApp
from crazyflie_app.app.uart2_link import Uart2Link
from host_tools.argtypes import parse_udp_endpoint
from host_tools.errors import ForaNavError

DEFAULT_OPTIONS = {
    "dropout": 0.0, "hide_tree": None, "hide_s": 5.0, "hide_at_s": None, "silence": (), "garbage_rate": 0.0,
    "partial_rate": 0.0, "lockstep": True, "max_time_s": 900.0, "model": None, "params": None, "start": None,
    "mavlink": None, "decks": ("bcFlow2", "bcLoco"), "app": "python", "plant": "reduced", "crtp": None,
    "profile": False,
}
POSITIONINGS = ("uwb", "flow")  # Loco deck + Flow deck, or the Flow deck alone

# Camera frame rates the app can fly on: below 2 fps frames come further apart than its link watch allows
# (app.linkHoldMs, 1000 ms). fly --fps, and a replayed clip's own rate.
FPS_RANGE = (2.0, 120.0)
PIXEL_NOISE_RANGE_PX = (0.0, 1000.0)  # added to each detection: beyond that no detection lands in a frame
WIND_RANGE_MPS2 = (0.0, 20.0)  # gusts: 2 g, far past what the plant flies
# the Flow deck's drift conditions (firmware plant): counts per count of motion, counts added per 10 ms frame,
# ground texture 1 textured .. 0 featureless
FLOW_SCALE_RANGE = (0.5, 2.0)
FLOW_BIAS_RANGE_COUNTS = (0.0, 5.0)
GROUND_TEXTURE_RANGE = (0.0, 1.0)


class Camera(Protocol):
    """What the harness asks of a camera (see the harness docstring); ``mount_offset`` is optional.
    ``true_pose`` is (x, y, z, yaw, roll, pitch) (``FlightRig.camera_pose``); a camera may use the first four."""

    frame_period_ms: int
    latency_ms: int

    def capture(self, t_ms: int, true_pose: tuple[float, ...],
                hidden: frozenset[int] = frozenset()) -> list[str]: ...


CameraFactory = Callable[..., Camera]  # (pmap, seed=..., **camera_kwargs) -> a camera
AppFactory = Callable[[Crazyflie, Sequence, str | None], Any]  # (cf, waypoints, target_label) -> an app
_CAMERAS: dict[str, CameraFactory] = {}
# cameras that live in their own module, imported on first use; the module calls register_camera()
CAMERA_MODULES = {"sim": "host_tools.flight.vision_camera"}


def register_camera(name: str, factory: CameraFactory) -> None:
    """Make ``foranav fly --camera NAME`` available: factory(pmap, seed=..., **kwargs) -> camera object."""
    _CAMERAS[name] = factory


def camera_factory(name: str) -> CameraFactory:
    """The factory registered for ``name``, importing its module first if it has one (see CAMERA_MODULES)."""
    if name not in _CAMERAS and name in CAMERA_MODULES:
        try:
            importlib.import_module(CAMERA_MODULES[name])
        except ModuleNotFoundError as err:
            if err.name != CAMERA_MODULES[name]:
                raise
    if name not in _CAMERAS:
        if name in CAMERA_MODULES:
            raise ForaNavError("--camera %s: not available yet (needs the vision half: %s)"
                               % (name, CAMERA_MODULES[name]))
        raise ForaNavError("--camera %s: unknown camera (have %s)" % (name, ", ".join(sorted(_CAMERAS))))
    return _CAMERAS[name]


def check_options(options: dict | None) -> dict:
    """``options`` merged over DEFAULT_OPTIONS, checked (ForaNavError names the bad one)."""
    merged = dict(DEFAULT_OPTIONS)
    for key, value in (options or {}).items():
        if key not in DEFAULT_OPTIONS:
            raise ForaNavError("flight option %r: unknown (known: %s)" % (key, ", ".join(sorted(DEFAULT_OPTIONS))))
        merged[key] = value
    for key in ("dropout", "garbage_rate", "partial_rate"):
        if not 0.0 <= float(merged[key]) <= 1.0:
            raise ForaNavError("flight option %s: must be a probability in [0, 1], got %r" % (key, merged[key]))
    if float(merged["hide_s"]) < 0 or float(merged["max_time_s"]) <= 0:
        raise ForaNavError("flight options hide_s / max_time_s must be positive")
    if merged["plant"] not in PLANTS:
        raise ForaNavError("flight option plant: unknown plant %r (have %s)" % (merged["plant"], ", ".join(PLANTS)))
    if merged["crtp"] is not None:
        try:
            merged["crtp"] = "%s:%d" % parse_udp_endpoint(merged["crtp"], low_port=0)
        except ValueError as err:
            raise ForaNavError("flight option crtp: %s" % err)
    return merged


def plant_model_options(plant: str, positioning: str, wind_gust_mps2: float) -> dict:
    """The flight option ``model`` (the plant's config fields) for a positioning system and gust strength:
    the reduced model draws its estimate error from the positioning (``estimator``), the firmware plant flies
    the decks' sensors into the Kalman filter (``positioning``)."""
    key = "positioning" if plant == "firmware" else "estimator"
    return {key: positioning, "wind_gust_mps2": wind_gust_mps2}


# -- the app: a component the flight is composed with -----------------------------------------------------------

def _python_app(cf: Crazyflie, waypoints: Sequence, target_label: str | None) -> NavigationApp:
    return NavigationApp(cf, waypoints, None, link=Uart2Link(cf), target_label=target_label)


def _c_app(cf: Crazyflie, waypoints: Sequence, target_label: str | None) -> CNavigationApp:
    return CNavigationApp(cf, waypoints, target_label=target_label)


_APPS = {"python": _python_app, "c": _c_app}


def register_app(name: str, factory: AppFactory) -> None:
    """Make flight option ``app=NAME`` available.

    ``factory(cf, waypoints, target_label) -> app``, ``cf`` with the camera's wire attached to its emulated
    UART2 (``cf.attach_uart2``), which the app reads as the Bolt's deck port; the app registers its PARAM/LOG tables on
    ``cf.registry`` and offers what the harness reads of the Python app: ``start()``, ``phase``,
    ``target_x``/``target_y``, ``params`` (cam_offset_x_m, cam_offset_y_m, cam_width_px, cam_height_px,
    focal_px), ``link`` (``close()``, ``lines_dropped``), ``core.counters`` (detections, out_of_column,
    recoveries, abandoned, link_losses), ``core.link_aborted``; it emits the console events ``detection``,
    ``tree_added``, ``tree_reached`` and ``phase``.
    """
    _APPS[name] = factory


def app_names() -> list[str]:
    return sorted(_APPS)


def app_factory(name: str) -> AppFactory:
    if name not in _APPS:
        raise ForaNavError("flight option app: unknown app %r (have %s)" % (name, ", ".join(app_names())))
    return _APPS[name]
