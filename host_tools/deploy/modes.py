"""Camera modes for the ForaNav module: parsing `WxH@FPS`, checking them against the JeVois-A33 sensor, and the
numbers that follow from a mode (fps text as JeVois writes it, a per-frame serial line budget).
"""
import math
import re
from typing import NamedTuple

from host_tools.errors import ForaNavError

# The module reads YUYV frames (getCvBGR/getCvGRAY convert on the CPU); BAYER/RGB565 are not offered.
CAMERA_FORMAT = "YUYV"
# OV9653 (the standard JeVois-A33 sensor) sizes and their maximum frame rates (jevois CameraSensor.C,
# videomappings-A33.cfg). Any rate from 0.1 fps to the maximum is allowed.
SENSOR_MAX_FPS = {
    (1280, 1024): 15.0, (640, 480): 30.0, (352, 288): 60.0, (320, 240): 60.0,
    (176, 144): 120.0, (160, 120): 60.0, (88, 72): 120.0,
}
MIN_FPS = 0.1
# The flight app's camera model is calibrated at 352x288 (0.0031 m/px/m); 15 fps leaves the detector head-room on
# the A33 (the paper's detector ran at 8.9 fps there; set the rate just below what `jevois.Timer` reports).
DEFAULT_MODE_TEXT = "352x288@15"
CALIBRATED_SIZE = (352, 288)

# Serial budget: 115200 baud 8N1 carries 10 bits per byte. Keep 20 % of the line free for console replies.
SERIAL_BAUD = 115200
BITS_PER_BYTE_8N1 = 10
SERIAL_HEADROOM = 0.8
LONGEST_T2_LINE_BYTES = len("T2 -1000 -750\r\n")
MIN_LINES_PER_FRAME = 2  # one tree and the end-of-frame mark, whatever the rate

class CameraMode(NamedTuple):
    """A camera sensor mode; a tuple (width, height, fps) too."""
    width: int
    height: int
    fps: float

_MODE_RE = re.compile(r"^\s*(\d+)\s*[xX]\s*(\d+)\s*@\s*(\d+(?:\.\d*)?|\.\d+)\s*$")


def parse_mode(text: str) -> CameraMode:
    """'352x288@15' -> CameraMode(352, 288, 15.0); ForaNavError naming the problem otherwise."""
    match = _MODE_RE.match(text or "")
    if not match:
        raise ForaNavError("--mode %r: expected WIDTHxHEIGHT@FPS, e.g. %s" % (text, DEFAULT_MODE_TEXT))
    width, height, fps = int(match.group(1)), int(match.group(2)), float(match.group(3))
    max_fps = SENSOR_MAX_FPS.get((width, height))
    if max_fps is None:
        sizes = ", ".join("%dx%d" % size for size in sorted(SENSOR_MAX_FPS, reverse=True))
        raise ForaNavError("--mode %r: %dx%d is not a JeVois-A33 sensor size (one of %s)"
                           % (text, width, height, sizes))
    if not MIN_FPS <= fps <= max_fps:
        raise ForaNavError("--mode %r: fps must be between %.1f and %s at %dx%d"
                           % (text, MIN_FPS, format_fps(max_fps), width, height))
    # JeVois compares rates to 0.01 fps; more decimals would only be rounded away on the camera.
    return CameraMode(width, height, round(fps, 2))


def format_fps(fps: float) -> str:
    """JeVois style: at least one decimal, at most two ('15.0', '26.1', '26.15')."""
    text = "%.2f" % fps
    return text[:-1] if text.endswith("0") else text


def format_mode(mode: CameraMode) -> str:
    return "%dx%d@%s" % (mode.width, mode.height, format_fps(mode.fps))


def camera_fields(mode: CameraMode) -> str:
    """The camera half of a mapping, as JeVois writes it: 'YUYV 352 288 15.0'."""
    return "%s %d %d %s" % (CAMERA_FORMAT, mode.width, mode.height, format_fps(mode.fps))


def is_calibrated_size(mode: CameraMode) -> bool:
    return (mode.width, mode.height) == CALIBRATED_SIZE


def serial_lines_per_frame(fps: float, baud: int = SERIAL_BAUD) -> int:
    """How many of the longest T2 lines fit through the serial port per frame, with head-room (for `serlimit`)."""
    bytes_per_frame = baud / BITS_PER_BYTE_8N1 / fps * SERIAL_HEADROOM
    return max(MIN_LINES_PER_FRAME, int(math.floor(bytes_per_frame / LONGEST_T2_LINE_BYTES)))
