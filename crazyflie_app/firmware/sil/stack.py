"""The firmware plant on the host: the real Crazyflie firmware's commander, supervisor, PID controller, power
distribution and Kalman estimator flying a rigid-body Bolt-sized quadrotor (``src/``, built by ``build.py``
into ``build/firmware-sil/libforanav_sil.so``), behind the same services the reduced plant offers the
emulated Crazyflie: ``commander`` (``commander_set_setpoint`` ...), ``supervisor`` (``state``, ``events``,
arming), ``model`` (``truth``, ``estimate``, ``crashed``) and a stabilizer task that runs the 1 kHz loop tick by
tick, so a setpoint the app sends at tick t is the one the controller flies from t + 1, as on the Bolt.

Every stack loads its own copy of the library, so its C statics (controller integrators, supervisor
state, the commander's queues) start from zero like a Crazyflie after power-on, and two flights in one
process never share state.
"""
import _ctypes
import ctypes
import math
import os
import shutil
import tempfile
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, fields

from crazyflie_app.firmware import freertos
from crazyflie_app.firmware.commander import setpoint_t
from crazyflie_app.firmware.sil import LIBRARY
from crazyflie_app.firmware.supervisor import (FLYING, LANDED, LOCKED, PRE_FLIGHT, READY_TO_FLY,
                                               WARNING_LEVEL_OUT)

NR_OF_ANCHORS = 8
POSITIONINGS = ("flow", "uwb")
ANCHOR_MARGIN_M = 1.5  # the anchors stand this far outside the flown area
ANCHOR_HEIGHTS_M = (0.2, 2.5)  # four low and four high, the Loco system's usual box
CONSOLE_BUFFER = 8192
# supervisorState_t, in the firmware's order; the names the reduced plant shares keep its spelling
SUPERVISOR_STATE_NAMES = ("NOT_INITIALIZED", "PRE_FLIGHT_CHECKS_NOT_PASSED", PRE_FLIGHT, "ARMING", READY_TO_FLY,
                          FLYING, LANDED, "RESET", WARNING_LEVEL_OUT, "EXCEPTION_FREE_FALL", LOCKED, "CRASHED")
WATCHDOG_STATES = (WARNING_LEVEL_OUT, "EXCEPTION_FREE_FALL", LOCKED, "CRASHED")
CRASH_REASONS = {1: "tumbled (tilt past 90 deg)", 2: "hit the ground faster than 2.5 m/s (a fall from 0.32 m)"}


class FirmwarePlantUnavailable(RuntimeError):
    """The firmware plant's library is not built (or cannot be loaded): the message says how to build it."""


def _setting(default, unit: str, doc: str):
    """A FirmwarePlantConfig field with its unit and meaning (docs/reference/firmware-plant.md shows them)."""
    return field(default=default, metadata={"unit": unit, "doc": doc})


@dataclass
class FirmwarePlantConfig:
    """The airframe, sensors and environment of the firmware plant. Defaults: a Bolt 1.1 on a 110 mm
    brushless frame carrying the Flow deck v2, the Loco deck and the JeVois (105 g, 2S LiPo)."""
    mass_kg: float = _setting(0.105, "kg", "take-off mass: frame, Bolt, Flow and Loco decks, JeVois, 2S battery")
    arm_m: float = _setting(0.055, "m", "motor axis to centre (a 110 mm diagonal X frame)")
    inertia_roll_kg_m2: float = _setting(8.5e-5, "kg m^2", "moment of inertia about the body x axis")
    inertia_pitch_kg_m2: float = _setting(8.5e-5, "kg m^2", "moment of inertia about the body y axis")
    inertia_yaw_kg_m2: float = _setting(1.5e-4, "kg m^2", "moment of inertia about the body z axis")
    thrust_max_n: float = _setting(0.85, "N", "one motor at full command and reference_v; with thrust growing "
                                   "with the square of the command, hover needs PWM ~36000 (posCtlPid.thrustBase)")
    torque_per_thrust_m: float = _setting(0.01, "m", "propeller drag torque per newton of thrust (yaw authority)")
    motor_tau_s: float = _setting(0.015, "s", "motor speed lag (first order)")
    drag_xy_n_per_mps: float = _setting(0.03, "N s/m", "horizontal linear drag")
    drag_z_n_per_mps: float = _setting(0.03, "N s/m", "vertical linear drag")
    angular_drag_nm_per_radps: float = _setting(2e-6, "N m s", "rotational damping")
    battery_full_v: float = _setting(8.4, "V", "2S LiPo, charged")
    battery_empty_v: float = _setting(7.0, "V", "open-circuit voltage when the capacity is used up")
    battery_capacity_mah: float = _setting(450.0, "mAh", "capacity")
    battery_resistance_ohm: float = _setting(0.08, "ohm", "internal resistance: the sag under load")
    reference_v: float = _setting(8.0, "V", "the voltage thrust_max_n is given at (motor speed scales with it)")
    hover_current_a: float = _setting(2.5, "A", "current at hover thrust (it grows with thrust^1.5)")
    gyro_noise_dps: float = _setting(0.2, "deg/s", "BMI088 gyro white noise per sample (1 kHz)")
    gyro_bias_dps: float = _setting(0.01, "deg/s", "std of the gyro bias left after the driver's still calibration "
                                    "(mean of 512 samples: 0.2 / sqrt(512) = 0.009) and in-run drift: the yaw "
                                    "estimate drifts by it (no magnetometer)")
    acc_noise_g: float = _setting(0.004, "g", "accelerometer white noise per sample")
    acc_bias_g: float = _setting(0.002, "g", "std of the accelerometer bias")
    flow_noise_px: float = _setting(1.0, "counts", "PMW3901 noise (the sensor's units: 10x pixels)")
    flow_scale: float = _setting(1.0, "", "counts the PMW3901 reports per count of true motion (1.05: reads 5 % long; "
                                 "a pixel-angle or lens error; the sweeps' drift condition)")
    flow_bias_counts: float = _setting(0.0, "counts", "added to each 10 ms frame's x and y counts (0.1 at 1.25 m "
                                       "is ~2.6 cm/s of velocity the Kalman filter integrates; a drift condition)")
    ground_texture: float = _setting(1.0, "0..1", "ground texture the flow sensor tracks: below 0.35 frames lose "
                                     "the motion flag, below 0.5 the counts under-read, noise grows as it falls")
    light: float = _setting(1.0, "0..1", "light level: below 0.3 the flow sensor's quality falls with it")
    tof_noise_m: float = _setting(0.003, "m", "VL53L1x range noise")
    tof_max_m: float = _setting(4.0, "m", "VL53L1x range limit (past it: out-of-range readings, dropped)")
    positioning: str = _setting("uwb", "", "uwb: Loco deck ranging to 8 anchors + Flow deck; flow: Flow deck alone")
    uwb_noise_m: float = _setting(0.05, "m", "TWR range noise")
    uwb_nlos_probability: float = _setting(0.03, "0..1", "chance that a range is non-line-of-sight (too long)")
    uwb_nlos_max_m: float = _setting(1.5, "m", "NLOS ranges are long by U(0.2 m, this)")
    wind_gust_mps2: float = _setting(0.0, "m/s^2", "std of the gust acceleration, applied as a force (the "
                                     "sweeps' wind condition)")
    wind_tau_s: float = _setting(2.0, "s", "gust correlation time (Ornstein-Uhlenbeck)")

    def validate(self) -> "FirmwarePlantConfig":
        if self.positioning not in POSITIONINGS:
            raise ValueError("positioning must be one of %s, got %r" % (", ".join(POSITIONINGS), self.positioning))
        for setting in fields(self):
            if setting.name == "positioning":
                continue
            value = getattr(self, setting.name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) or value < 0:
                raise ValueError("%s must be a finite number >= 0, got %r" % (setting.name, value))
        for name in ("mass_kg", "arm_m", "inertia_roll_kg_m2", "inertia_pitch_kg_m2", "inertia_yaw_kg_m2",
                     "thrust_max_n", "motor_tau_s", "battery_capacity_mah", "reference_v", "wind_tau_s"):
            if getattr(self, name) <= 0:
                raise ValueError("%s must be positive" % name)
        for name in ("ground_texture", "light", "uwb_nlos_probability"):
            if getattr(self, name) > 1:
                raise ValueError("%s must lie in [0, 1], got %r" % (name, getattr(self, name)))
        return self


# -- the C interface (src/sil_api.h) ---------------------------------------------------------------------------

_D, _I, _U = ctypes.c_double, ctypes.c_int32, ctypes.c_uint32


class _Config(ctypes.Structure):
    _fields_ = [("mass_kg", _D), ("arm_m", _D), ("inertia_kg_m2", _D * 3), ("thrust_max_n", _D),
                ("torque_per_thrust_m", _D), ("motor_tau_s", _D), ("drag_n_per_mps", _D * 3),
                ("angular_drag_nm_per_radps", _D), ("battery_full_v", _D), ("battery_empty_v", _D),
                ("battery_capacity_mah", _D), ("battery_resistance_ohm", _D), ("reference_v", _D),
                ("hover_current_a", _D), ("gyro_noise_dps", _D), ("gyro_bias_dps", _D), ("acc_noise_g", _D),
                ("acc_bias_g", _D), ("flow_noise_px", _D), ("flow_scale", _D), ("flow_bias_counts", _D),
                ("ground_texture", _D), ("light", _D),
                ("tof_noise_m", _D), ("tof_max_m", _D), ("positioning", _I), ("uwb_noise_m", _D),
                ("uwb_nlos_probability", _D), ("uwb_nlos_max_m", _D), ("anchors", (_D * 3) * NR_OF_ANCHORS),
                ("wind_gust_mps2", _D), ("wind_tau_s", _D), ("start", _D * 3), ("start_yaw_deg", _D),
                ("seed", ctypes.c_uint64)]


class SilState(ctypes.Structure):
    """sil_state_t: a pose and velocity the C loop writes every tick (truth or stateEstimate)."""
    _fields_ = [(name, _D) for name in ("x", "y", "z", "vx", "vy", "vz", "yaw", "roll", "pitch")]

    def as_tuple(self) -> tuple[float, ...]:
        return (self.x, self.y, self.z, self.vx, self.vy, self.vz, self.yaw)


class SilStatus(ctypes.Structure):
    _fields_ = [("tick", _U), ("supervisor_state", _I), ("armed", _I), ("crashed", _I), ("battery_v", _D),
                ("motor_ratio", _D * 4), ("thrust_n", _D), ("estimator_resets", _I), ("flow_updates", _I),
                ("tof_updates", _I), ("uwb_updates", _I), ("uwb_rejected", _I), ("console_pending", _I)]


class _Setpoint(ctypes.Structure):
    _fields_ = [("mode_x", _I), ("mode_y", _I), ("mode_z", _I), ("mode_roll", _I), ("mode_pitch", _I),
                ("mode_yaw", _I), ("position", _D * 3), ("velocity", _D * 3), ("attitude", _D * 3),
                ("attitude_rate", _D * 3), ("thrust", _D), ("velocity_body", _I)]


def _declare(lib: ctypes.CDLL) -> None:
    lib.sil_boot.argtypes = [ctypes.POINTER(_Config), ctypes.POINTER(SilState), ctypes.POINTER(SilState),
                             ctypes.POINTER(SilStatus)]
    lib.sil_advance_to.argtypes = [_U]
    lib.sil_advance_to.restype = None
    lib.sil_commander_set_setpoint.argtypes = [ctypes.POINTER(_Setpoint), ctypes.c_int]
    lib.sil_commander_relax_priority.restype = None
    lib.sil_commander_get_inactivity_time.restype = _U
    lib.sil_supervisor_request_arming.argtypes = [ctypes.c_int]
    lib.sil_supervisor_state_name.argtypes = [ctypes.c_int]
    lib.sil_supervisor_state_name.restype = ctypes.c_char_p
    lib.sil_console_read.argtypes = [ctypes.c_char_p, ctypes.c_int]
    lib.sil_high_level_command.argtypes = [ctypes.c_char_p, ctypes.c_int]
    lib.sil_trajectory_memory_size.restype = _U
    lib.sil_trajectory_memory_write.argtypes = [_U, ctypes.c_char_p, ctypes.c_int]
    lib.sil_trajectory_memory_read.argtypes = [_U, ctypes.c_char_p, ctypes.c_int]


def library_path() -> str:
    """The library to load: $FORANAV_SIL_LIB, else the one build.py writes."""
    return os.environ.get("FORANAV_SIL_LIB") or str(LIBRARY)


def check_available() -> None:
    """FirmwarePlantUnavailable (one line: what is missing, how to build it) unless the library is there."""
    path = library_path()
    if not os.path.exists(path):
        raise FirmwarePlantUnavailable(
            "the firmware plant is not built (%s missing): run `make firmware-sil` (it builds the Crazyflie "
            "firmware from ../shared/vendor/crazyflie-firmware-*.tar.gz or FORANAV_FIRMWARE=PATH)" % path)


def _fresh_library() -> ctypes.CDLL:
    """A private copy of the library: its statics are those of a Crazyflie just powered on."""
    check_available()
    with tempfile.NamedTemporaryFile(prefix="foranav_sil_", suffix=".so", delete=False) as copy:
        name = copy.name
    try:
        shutil.copyfile(library_path(), name)
        lib = ctypes.CDLL(name, mode=os.RTLD_LOCAL)
    except OSError as err:
        raise FirmwarePlantUnavailable("the firmware plant library %s does not load: %s; rebuild it with "
                                       "`make firmware-sil`" % (library_path(), err))
    finally:
        os.unlink(name)  # the mapping stays; nothing is left on disk
    if lib.sil_api_version() != 1 or lib.sil_state_size() != ctypes.sizeof(SilState):
        raise FirmwarePlantUnavailable("the firmware plant library %s is from another version: run "
                                       "`make firmware-sil`" % library_path())
    _declare(lib)
    return lib


def anchor_positions(bounds: tuple[float, float, float, float]) -> list[tuple[float, float, float]]:
    """Eight Loco anchors on a box around (xmin, ymin, xmax, ymax): four corners low, the same four high."""
    xmin, ymin, xmax, ymax = bounds
    corners = [(xmin - ANCHOR_MARGIN_M, ymin - ANCHOR_MARGIN_M), (xmax + ANCHOR_MARGIN_M, ymin - ANCHOR_MARGIN_M),
               (xmax + ANCHOR_MARGIN_M, ymax + ANCHOR_MARGIN_M), (xmin - ANCHOR_MARGIN_M, ymax + ANCHOR_MARGIN_M)]
    return [(x, y, z) for z in ANCHOR_HEIGHTS_M for x, y in corners]


def _c_config(config: FirmwarePlantConfig, seed: int, start: Sequence[float], anchors: Sequence) -> _Config:
    c = _Config()
    for setting in fields(config):
        if hasattr(c, setting.name) and setting.name != "positioning":
            setattr(c, setting.name, getattr(config, setting.name))
    c.inertia_kg_m2[:] = (config.inertia_roll_kg_m2, config.inertia_pitch_kg_m2, config.inertia_yaw_kg_m2)
    c.drag_n_per_mps[:] = (config.drag_xy_n_per_mps, config.drag_xy_n_per_mps, config.drag_z_n_per_mps)
    c.positioning = POSITIONINGS.index(config.positioning)
    for i, anchor in enumerate(anchors):
        c.anchors[i][:] = tuple(float(v) for v in anchor)
    c.start[:] = (float(start[0]), float(start[1]), float(start[2]))
    c.start_yaw_deg = 0.0
    c.seed = seed & 0xFFFFFFFFFFFFFFFF
    return c


class FirmwareStack:
    """One booted firmware: the C library and the memory it writes its outputs into."""

    def __init__(self, config: FirmwarePlantConfig, seed: int, start: Sequence[float],
                 bounds: tuple[float, float, float, float]):
        self.config = config.validate()
        self.lib = _fresh_library()
        self.truth, self.estimate, self.status = SilState(), SilState(), SilStatus()
        self.anchors = anchor_positions(bounds)
        self._c_config = _c_config(self.config, seed, start, self.anchors)
        self.lib.sil_boot(ctypes.byref(self._c_config), ctypes.byref(self.truth), ctypes.byref(self.estimate),
                          ctypes.byref(self.status))
        self._setpoint = _Setpoint()
        self._console = ctypes.create_string_buffer(CONSOLE_BUFFER)
        self._pending_text = ""
        self.tick = -1  # the last tick the loop ran

    def advance_to(self, tick: int) -> None:
        """Run the 1 kHz loop up to and including ``tick``."""
        if tick > self.tick:
            self.lib.sil_advance_to(tick)
            self.tick = tick

    def set_setpoint(self, sp: setpoint_t, priority: int) -> bool:
        c = self._setpoint
        m = sp.mode
        c.mode_x, c.mode_y, c.mode_z, c.mode_roll, c.mode_pitch, c.mode_yaw = m.x, m.y, m.z, m.roll, m.pitch, m.yaw
        c.position[:] = (sp.position.x, sp.position.y, sp.position.z)
        c.velocity[:] = (sp.velocity.x, sp.velocity.y, sp.velocity.z)
        c.attitude[:] = (sp.attitude.roll, sp.attitude.pitch, sp.attitude.yaw)
        c.attitude_rate[:] = (sp.attitudeRate.roll, sp.attitudeRate.pitch, sp.attitudeRate.yaw)
        c.thrust = sp.thrust
        c.velocity_body = 1 if sp.velocity_body else 0
        return bool(self.lib.sil_commander_set_setpoint(ctypes.byref(c), priority))

    def console_lines(self) -> list[tuple[str, str]]:
        """(module, text) of each complete line the firmware printed since the last call."""
        if not self.status.console_pending:
            return []
        length = self.lib.sil_console_read(self._console, CONSOLE_BUFFER)
        if length == 0:
            return []
        text = self._pending_text + self._console.raw[:length].decode("ascii", "replace")
        *lines, self._pending_text = text.split("\n")
        out = []
        for line in lines:
            module, sep, rest = line.partition(": ")
            out.append((module, rest) if sep and module.isupper() else ("FW", line))
        return out

    def high_level_command(self, payload: bytes) -> int:
        """A port-8 packet's data to the firmware's high-level commander -> its answer (0, or an errno)."""
        return self.lib.sil_high_level_command(bytes(payload), len(payload))

    def trajectory_memory_size(self) -> int:
        return self.lib.sil_trajectory_memory_size()

    def trajectory_memory_write(self, address: int, data: bytes) -> bool:
        """The firmware's trajectory memory handler: False when the write would end past the memory."""
        return bool(self.lib.sil_trajectory_memory_write(address & 0xFFFFFFFF, bytes(data), len(data)))

    def trajectory_memory_read(self, address: int, length: int) -> bytes | None:
        buffer = ctypes.create_string_buffer(max(1, length))
        if not self.lib.sil_trajectory_memory_read(address & 0xFFFFFFFF, buffer, length):
            return None
        return buffer.raw[:length]

    def close(self) -> None:
        """Unload this stack's copy of the library (its outputs stay readable: they are Python's memory)."""
        handle = getattr(self.lib, "_handle", None)
        self.lib = None
        if handle:
            _ctypes.dlclose(handle)
