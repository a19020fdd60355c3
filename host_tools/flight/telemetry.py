"""MAVLink 2 telemetry of a flight: a .tlog on disk, optionally the same stream live to a ground station.

A .tlog is a sequence of records: an 8-byte big-endian timestamp (microseconds since 1970) followed by one
MAVLink frame. Timestamps come from the *simulated* clock (``EPOCH_US`` + tick), so the same flight gives the
same bytes. Dialect ``common``, MAVLink 2, system 1 / component 1 (an autopilot, so a GCS accepts it).

Frames: Crazyflie world is FLU (x forward, y left, z up); MAVLink local is NED with north := Crazyflie +x,
so x_N = x, y_E = -y, z_D = -z and yaw_NED = -yaw.

Messages: HEARTBEAT (1 Hz; custom_mode = the ArduCopter mode nearest the app's phase (COPTER_MODES), so
MAVExplorer, mavflightmodes and QGroundControl name it, system_status from the supervisor) with NAMED_VALUE_INT
"phase" (the app's own phase number, nav_types.PHASE_NAMES), LOCAL_POSITION_NED of the estimate, and the same
position on the globe from a geo-reference (GeoReference: the map origin's latitude/longitude and the bearing of
the map's +x axis; DEFAULT_GEO unless given) as GLOBAL_POSITION_INT and GPS_RAW_INT (3D fix), so ground
stations draw the track on a map and mavtogpx / mavflighttime read it, DEBUG_VECT "gt_pos" of the ground truth and DEBUG_VECT "est_err" of the estimate's error
(x, y in NED metres, z = yaw error in degrees, NED sign) (10 Hz), POSITION_TARGET_LOCAL_NED per accepted
setpoint (type mask 2531: vx, vy, z, yaw), LANDING_TARGET per detection (angles from the pixel, distance =
height, target_num = tree id), STATUSTEXT per console line: each line a fresh id (1..65535, MAVLink 2's
chunk id: a ground station joins only the chunks of one id), split into 50-character chunks, a line of a
multiple of 50 characters closed by an empty chunk (the receiver's end-of-message).
"""
import math
import os
import struct
from dataclasses import dataclass
from typing import Any, BinaryIO

from crazyflie_app.app.nav_types import PHASE_NAMES

os.environ.setdefault("MAVLINK20", "1")
from pymavlink import mavutil  # noqa: E402
from pymavlink.dialects.v20 import common as mavlink2  # noqa: E402

EPOCH_US = 1741132800 * 1000000  # 2025-03-05T00:00:00Z: a fixed origin keeps the bytes reproducible
SYSTEM_ID, COMPONENT_ID = 1, 1
TYPE_MASK_HOVER = 2531  # use vx, vy, z, yaw (crazyflie.md 6.5)
STATUSTEXT_CHUNK = 50
EARTH_RADIUS_M = 6371000.0  # mean radius: metres to degrees over a plantation (error < 0.5 %)
# ArduCopter mode numbers (pymavlink's mode_mapping_acm, what mavutil names a quadrotor's custom_mode by) for the
# app's phases, by meaning: on the ground STABILIZE, taking off and flying to a point GUIDED, along the path AUTO,
# searching for a lost tree LOITER, landing and landed LAND. The exact phase is NAMED_VALUE_INT "phase".
COPTER_MODES = {"BOOT": 0, "TAKEOFF": 4, "FOLLOW_PATH": 3, "APPROACH": 4, "RECOVERY": 5, "RETURN_TO_PATH": 4,
                "LAND": 9, "DONE": 9, "NO_DECK": 0, "NO_CAMERA": 0}


@dataclass(frozen=True)
class GeoReference:
    """Where the map's origin is on the globe, and the compass bearing (deg, clockwise from north) of its +x."""
    lat_deg: float
    lon_deg: float
    heading_deg: float = 0.0
    altitude_m: float = 0.0  # above mean sea level, of the ground

    def to_global(self, x: float, y: float) -> tuple[float, float]:
        """(lat_deg, lon_deg) of map point (x forward, y left)."""
        h = math.radians(self.heading_deg)
        north = x * math.cos(h) + y * math.sin(h)
        east = x * math.sin(h) - y * math.cos(h)
        lat = self.lat_deg + math.degrees(north / EARTH_RADIUS_M)
        lon = self.lon_deg + math.degrees(east / (EARTH_RADIUS_M * math.cos(math.radians(self.lat_deg))))
        return lat, lon


# An oil palm estate in Selangor, Malaysia, map +x due north: where a map gives no geo-reference
DEFAULT_GEO = GeoReference(lat_deg=2.95, lon_deg=101.45, heading_deg=0.0, altitude_m=20.0)


def _cm(speed_mps: float) -> int:
    """m/s -> cm/s in an int16 field."""
    return max(-32767, min(32767, int(round(speed_mps * 100))))


class _TimestampedFile:
    """The file object MAVLink.send writes to: prefixes each frame with the simulated-time header."""

    def __init__(self, fileobj: BinaryIO, live: Any = None):
        self.fileobj = fileobj
        self.live = live
        self.t_us = EPOCH_US

    def write(self, buf: bytes) -> None:
        self.fileobj.write(struct.pack(">Q", self.t_us) + bytes(buf))
        if self.live is not None:
            try:
                self.live.write(bytes(buf))
            except OSError:  # the ground station's network went away: the tlog goes on, the live copy stops
                self.live = None


def connect_live(url: str) -> Any:
    """pymavlink's connection for a live copy of the stream (e.g. 'udpout:127.0.0.1:14550')."""
    return mavutil.mavlink_connection(url, source_system=SYSTEM_ID, source_component=COMPONENT_ID, dialect="common")


class TlogWriter:
    """Write telemetry; every method takes the simulated time in ms."""

    def __init__(self, path: str | os.PathLike, live_url: str | None = None, live: Any = None,
                 geo: GeoReference = DEFAULT_GEO):
        self.path = str(path)
        self.geo = geo
        if live_url:  # first: a bad URL must fail before any file exists
            live = connect_live(live_url)
        self._live = live
        self._tmp_path = self.path + ".part"  # renamed over path by close(): never a half-written .tlog
        self._file = open(self._tmp_path, "wb")
        self._sink = _TimestampedFile(self._file, live)
        self.mav = mavlink2.MAVLink(self._sink, srcSystem=SYSTEM_ID, srcComponent=COMPONENT_ID)
        self._status_id = 0
        self.messages = 0

    def _at(self, t_ms: int) -> None:
        self._sink.t_us = EPOCH_US + int(t_ms) * 1000
        self.messages += 1

    def heartbeat(self, t_ms: int, phase: int, armed: bool, system_status: int) -> None:
        self._at(t_ms)
        base_mode = mavlink2.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED | mavlink2.MAV_MODE_FLAG_GUIDED_ENABLED
        if armed:
            base_mode |= mavlink2.MAV_MODE_FLAG_SAFETY_ARMED
        self.mav.heartbeat_send(mavlink2.MAV_TYPE_QUADROTOR, mavlink2.MAV_AUTOPILOT_GENERIC, base_mode,
                                COPTER_MODES[PHASE_NAMES[int(phase)]], system_status)
        self._at(t_ms)
        self.mav.named_value_int_send(int(t_ms), b"phase", int(phase))

    def local_position(self, t_ms: int, x: float, y: float, z: float, vx: float, vy: float, vz: float) -> None:
        """The estimate: LOCAL_POSITION_NED, and on the globe GLOBAL_POSITION_INT and GPS_RAW_INT."""
        self._at(t_ms)
        self.mav.local_position_ned_send(int(t_ms), x, -y, -z, vx, -vy, -vz)
        lat, lon = self.geo.to_global(x, y)
        h = math.radians(self.geo.heading_deg)
        v_north, v_east = vx * math.cos(h) + vy * math.sin(h), vx * math.sin(h) - vy * math.cos(h)
        speed = math.hypot(v_north, v_east)
        course = math.degrees(math.atan2(v_east, v_north)) % 360.0
        lat_e7, lon_e7 = int(round(lat * 1e7)), int(round(lon * 1e7))
        alt_mm = int(round((self.geo.altitude_m + z) * 1000))
        self._at(t_ms)
        self.mav.global_position_int_send(int(t_ms), lat_e7, lon_e7, alt_mm, int(round(z * 1000)),
                                          _cm(v_north), _cm(v_east), _cm(-vz), 65535)
        self._at(t_ms)
        self.mav.gps_raw_int_send(EPOCH_US + int(t_ms) * 1000, 3, lat_e7, lon_e7, alt_mm, 100, 100,
                                  min(int(round(speed * 100)), 65534), int(round(course * 100)) % 36000, 10)

    def ground_truth(self, t_ms: int, x: float, y: float, z: float) -> None:
        self._at(t_ms)
        self.mav.debug_vect_send(b"gt_pos", EPOCH_US + int(t_ms) * 1000, x, -y, -z)

    def estimate_error(self, t_ms: int, dx: float, dy: float, dyaw_deg: float) -> None:
        """DEBUG_VECT "est_err": stateEstimate minus the truth (x, y in NED metres, yaw in degrees)."""
        self._at(t_ms)
        self.mav.debug_vect_send(b"est_err", EPOCH_US + int(t_ms) * 1000, dx, -dy, -dyaw_deg)

    def position_target(self, t_ms: int, vx_world: float, vy_world: float, z: float, yaw_deg: float) -> None:
        self._at(t_ms)
        self.mav.position_target_local_ned_send(int(t_ms), mavlink2.MAV_FRAME_LOCAL_NED, TYPE_MASK_HOVER,
                                                0.0, 0.0, -z, vx_world, -vy_world, 0.0, 0.0, 0.0, 0.0,
                                                -math.radians(yaw_deg), 0.0)

    def landing_target(self, t_ms: int, tree_id: int, u: float, v: float, width: int, height: int, focal_px: float,
                       distance_m: float) -> None:
        self._at(t_ms)
        angle_x = math.atan((u - width / 2.0) / focal_px)  # + = right of centre (+y FRD)
        angle_y = math.atan((v - height / 2.0) / focal_px)  # + = towards the tail
        self.mav.landing_target_send(EPOCH_US + int(t_ms) * 1000, min(max(int(tree_id), 0), 255),
                                     mavlink2.MAV_FRAME_BODY_FRD, angle_x, angle_y, distance_m, 0.0, 0.0,
                                     type=mavlink2.LANDING_TARGET_TYPE_VISION_OTHER, position_valid=0)

    def status_text(self, t_ms: int, text: str, severity: int = mavlink2.MAV_SEVERITY_INFO) -> None:
        data = text.encode("ascii", "replace")
        chunks = [data[i:i + STATUSTEXT_CHUNK] for i in range(0, len(data), STATUSTEXT_CHUNK)] or [b""]
        if len(chunks) > 1 and len(chunks[-1]) == STATUSTEXT_CHUNK:
            chunks.append(b"")  # a full last chunk has no terminating NUL: the receiver would wait for more
        self._status_id = self._status_id % 65535 + 1  # a fresh id per line, also for one chunk
        for seq, chunk in enumerate(chunks):
            self._at(t_ms)
            self.mav.statustext_send(severity, chunk, id=self._status_id, chunk_seq=seq)

    def close(self, keep: bool = True) -> None:
        """Finish the log (keep=True: rename it into place; False: delete the partial file)."""
        if self._file is not None:
            self._file.close()
            self._file = None
            if keep:
                os.replace(self._tmp_path, self.path)
            else:
                os.unlink(self._tmp_path)
        if self._live is not None:
            self._live.close()
            self._live = None
