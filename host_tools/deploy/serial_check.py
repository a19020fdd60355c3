"""Check a deployed camera from a PC: listen to its serial output for a few seconds and say what arrives.

    foranav serial-check /dev/ttyUSB0 [--seconds 10] [--mode 352x288@15]

Wire a 3.3 V USB-serial adapter where the Bolt would be (JeVois white -> adapter RX, black -> GND, red IOREF ->
the adapter's 3.3 V), power the camera, and run it. It counts T2/N2 detections, frame marks (`MARK STOP`, one per
processed frame) and other lines (console replies, logs, noise), and compares the frame rate with the deployed
mode: a module that keeps up delivers the camera's rate; one that cannot is held to a fraction of it, and the
mode's fps should then be lowered to just below what the module's Timer reports (JeVois' advice).

The summary is a pure function of (time, line) pairs; only `listen` touches the port (pyserial, read-only: it
sends nothing, since the camera runs every received line as a console command).
"""
import argparse
import math
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import serial

from host_tools import argtypes
from host_tools.cli import main
from host_tools.deploy.modes import DEFAULT_MODE_TEXT, CameraMode, format_fps, parse_mode
from host_tools.errors import ForaNavError
from jevois_module.ForaNavTrees.foranav_serial import FRAME_STOP, FrameMark, LineAssembler, parse_line

DEFAULT_SECONDS = 10.0
MAX_SECONDS = 3600.0  # an hour of listening; longer is a typo (and inf would never return)
READ_TIMEOUT_S = 0.1
# A module keeping up delivers the camera rate up to timing jitter; below this share it is dropping frames.
KEEPS_UP_SHARE = 0.95
# Margin under a measured rate when suggesting a mode: the camera then never waits a whole extra frame.
RATE_MARGIN = 0.97
END_OF_FRAME = FRAME_STOP.split()[1]  # FrameMark.what of "MARK STOP"

@dataclass(frozen=True)
class LinkSummary:
    seconds: float  # of listening
    lines: int
    detections: int  # T2/N2 lines
    frames: int  # MARK STOP lines
    other: int  # lines that are neither
    frame_rate: float | None  # frames per second from the MARK STOP times; None with fewer than two marks


def summarize(events: Sequence[tuple[float, bytes]], seconds: float) -> LinkSummary:
    """events: [(t_s, line)] received in `seconds` of listening -> LinkSummary.

    frame_rate comes from the MARK STOP times (frames - 1 intervals), None with fewer than two marks.
    """
    detections = frames = other = 0
    stop_times = []
    for t_s, line in events:
        parsed = parse_line(line)
        if isinstance(parsed, FrameMark):
            if parsed.what == END_OF_FRAME:
                frames += 1
                stop_times.append(t_s)
        elif parsed is not None:
            detections += 1
        else:
            other += 1
    rate = None
    if len(stop_times) >= 2 and stop_times[-1] > stop_times[0]:
        rate = (len(stop_times) - 1) / (stop_times[-1] - stop_times[0])
    return LinkSummary(seconds, len(events), detections, frames, other, rate)


def suggested_fps(measured_rate: float) -> float:
    """A camera fps just below a measured processing rate, to 0.1 fps."""
    return max(0.1, math.floor(measured_rate * RATE_MARGIN * 10) / 10)


def verdict(summary: LinkSummary, mode: CameraMode) -> list[str]:
    """Lines for the user: what arrived, and whether the module keeps up with the mode's fps."""
    lines = ["%d lines in %.1f s: %d detections, %d frames, %d other lines"
             % (summary.lines, summary.seconds, summary.detections, summary.frames, summary.other)]
    if summary.lines == 0:
        lines.append("nothing arrived: check the wiring (JeVois white -> RX, GND, IOREF), the baud rate (115200), "
                     "and that the module streams (headless deploy, or `streamon`)")
        return lines
    if summary.frame_rate is None:
        lines.append("no frame marks (MARK STOP): the frame rate cannot be measured from the link")
        return lines
    lines.append("frames arrive at %.1f fps; the mode asks %s fps" % (summary.frame_rate, format_fps(mode.fps)))
    if summary.frame_rate >= KEEPS_UP_SHARE * mode.fps:
        lines.append("the module keeps up with the camera")
    else:
        lines.append("the module drops frames: redeploy with --mode %dx%d@%s (or just below the fps its Timer "
                     "reports)" % (mode.width, mode.height, format_fps(suggested_fps(summary.frame_rate))))
    if summary.other:
        lines.append("%d lines were not detections or marks (console replies, logs or noise): the flight app "
                     "ignores them, but `setpar serlog None` keeps logs off the port" % summary.other)
    return lines


def listen(port_url: str, seconds: float, baudrate: int = 115200,
           clock: Callable[[], float] = time.monotonic) -> list[tuple[float, bytes]]:
    """Adapter: [(t_s, line bytes)] read from the port for `seconds` (t_s from the start)."""
    events = []
    assembler = LineAssembler()
    port = serial.serial_for_url(port_url, baudrate=baudrate, timeout=READ_TIMEOUT_S)
    try:
        start = clock()
        while clock() - start < seconds:
            data = port.read(4096)
            now = clock() - start
            events.extend((now, line) for line in assembler.feed(data))
    finally:
        port.close()
    return events


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("port", help="serial port of the USB-serial adapter (e.g. /dev/ttyUSB0, COM3)")
    parser.add_argument("--seconds", type=argtypes.float_range(0.1, MAX_SECONDS), default=DEFAULT_SECONDS,
                        help="how long to listen, 0.1-%g s (default %g)" % (MAX_SECONDS, DEFAULT_SECONDS))
    parser.add_argument("--mode", default=DEFAULT_MODE_TEXT, help="the deployed mode (default %(default)s)")


def run(args: argparse.Namespace) -> int:
    """Listen, then print the verdict; ForaNavError for a bad mode or a port that cannot be opened."""
    mode = parse_mode(args.mode)
    try:
        events = listen(args.port, args.seconds)
    except (OSError, ValueError) as err:  # serial.SerialException is an OSError
        raise ForaNavError("%s: %s" % (args.port, err))
    for line in verdict(summarize(events, args.seconds), mode):
        print(line)
    return 0


if __name__ == "__main__":
    sys.exit(main(["serial-check"] + sys.argv[1:]))
