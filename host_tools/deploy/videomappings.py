"""config/videomappings.cfg: read its mapping lines and add the ForaNav module's two mappings, idempotently.

Line format (jevois VideoMapping.C):
    <USBmode> <USBw> <USBh> <USBfps> <CAMmode> <CAMw> <CAMh> <CAMfps> <Vendor> <Module> [*] [# comment]
USB sizes may be relative to the camera size (`+0`, `-16`); the camera format may carry `Linear:`-style
modifiers. Lines starting with `#` are comments; lines with fewer than 10 fields are skipped by JeVois.

The edit only ever appends: every existing byte of the file stays where it was, so comments, blank lines, the
user's mappings, their order and the single `*` default are untouched.
"""
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

from host_tools.deploy.modes import CAMERA_FORMAT, CameraMode, camera_fields, format_fps

USB_NONE = "NONE"
# JeVois treats two USB modes as the same when their rates differ by less than 0.01 fps, and resolves a clash by
# slowing the later one by 1 fps; we pick the free rate ourselves so the file says what the host will see.
SAME_FPS_TOLERANCE = 0.01
USB_FPS_STEP = 1.0
MAPPING_FIELDS = 10


@dataclass(frozen=True)
class Mapping:
    """One mapping line: the USB output (format NONE: headless), the camera mode, the module that runs."""
    usb_format: str
    usb_width: int
    usb_height: int
    usb_fps: float
    cam_format: str
    cam_width: int
    cam_height: int
    cam_fps: float
    vendor: str
    module: str


@dataclass(frozen=True)
class VideoMappingsPlan:
    text: str  # the new file
    added: list  # the lines added
    notes: list  # what the user should know (a mapping not added, a USB rate changed)


def _dimension(token: str, camera_value: int) -> int:
    # `+N`/`-N` are relative to the camera size (jevois parse_relative_dim).
    if token[:1] in "+-":
        return camera_value + int(token)
    return int(token)


def parse_mapping(line: str) -> Mapping | None:
    """One line of the file -> Mapping, or None for comments, blank and malformed lines (as JeVois skips them)."""
    tokens = line.split()
    if len(tokens) < MAPPING_FIELDS or tokens[0].startswith("#"):
        return None
    try:
        cam_width, cam_height = int(tokens[5]), int(tokens[6])
        return Mapping(tokens[0], _dimension(tokens[1], cam_width), _dimension(tokens[2], cam_height),
                       float(tokens[3]), tokens[4].split(":")[-1], cam_width, cam_height, float(tokens[7]),
                       tokens[8], tokens[9])
    except ValueError:
        return None


def parse_mappings(text: str) -> list[Mapping]:
    """All valid mappings of the file, in file order."""
    return [m for m in (parse_mapping(line) for line in text.splitlines()) if m is not None]


def same_fps(a: float, b: float) -> bool:
    return abs(a - b) < SAME_FPS_TOLERANCE


def _runs_module_in_mode(mapping: Mapping, vendor: str, module: str, mode: CameraMode) -> bool:
    return (mapping.vendor == vendor and mapping.module == module and mapping.cam_format == CAMERA_FORMAT
            and (mapping.cam_width, mapping.cam_height) == (mode.width, mode.height)
            and same_fps(mapping.cam_fps, mode.fps))


def has_usb_mapping(mappings: Iterable[Mapping], vendor: str, module: str, mode: CameraMode) -> bool:
    return any(m.usb_format != USB_NONE and _runs_module_in_mode(m, vendor, module, mode) for m in mappings)


def has_headless_mapping(mappings: Iterable[Mapping], vendor: str, module: str, mode: CameraMode) -> bool:
    return any(m.usb_format == USB_NONE and _runs_module_in_mode(m, vendor, module, mode) for m in mappings)


def free_usb_fps(mappings: Iterable[Mapping], width: int, height: int, wanted_fps: float) -> float | None:
    """The highest USB rate <= wanted_fps, in 1 fps steps, that no other YUYV WxH USB mapping uses (or None)."""
    taken = [m.usb_fps for m in mappings
             if m.usb_format == CAMERA_FORMAT and (m.usb_width, m.usb_height) == (width, height)]
    fps = wanted_fps
    while any(same_fps(fps, other) for other in taken):
        fps = round(fps - USB_FPS_STEP, 2)
    return fps if fps > 0 else None


def usb_line(vendor: str, module: str, mode: CameraMode, usb_fps: float) -> str:
    return "%s %d %d %s %s %s %s" % (CAMERA_FORMAT, mode.width, mode.height, format_fps(usb_fps),
                                     camera_fields(mode), vendor, module)


def headless_line(vendor: str, module: str, mode: CameraMode) -> str:
    return "%s 0 0 0.0 %s %s %s" % (USB_NONE, camera_fields(mode), vendor, module)


def header_comment(vendor: str, module: str) -> str:
    return "# %s %s tree detector: USB video (JeVois Inventor) and headless (added by ForaNav)" % (vendor, module)


def newline_of(text: str) -> str:
    """The file's own line ending, so added lines match a file edited on Windows."""
    return "\r\n" if "\r\n" in text else "\n"


def append_lines(text: str, lines: Sequence[str]) -> str:
    """text with lines appended, each ended by the file's newline; a missing final newline is supplied first."""
    if not lines:
        return text
    newline = newline_of(text)
    if text and not text.endswith("\n"):
        text += newline
    return text + "".join(line + newline for line in lines)


def plan_videomappings(text: str, vendor: str, module: str, mode: CameraMode) -> VideoMappingsPlan:
    """The file's new text with the module's USB and NONE mappings added where missing.

    Returns VideoMappingsPlan(text, added lines, notes). Never adds a `*`: the user's default stays the default.
    """
    mappings = parse_mappings(text)
    added, notes = [], []
    if not has_usb_mapping(mappings, vendor, module, mode):
        usb_fps = free_usb_fps(mappings, mode.width, mode.height, mode.fps)
        if usb_fps is None:
            notes.append("no free USB frame rate for YUYV %dx%d: USB video mapping not added (headless unaffected)"
                         % (mode.width, mode.height))
        else:
            if not same_fps(usb_fps, mode.fps):
                notes.append("USB mode YUYV %dx%d@%s is used by another mapping: the ForaNav USB mapping announces "
                             "%s fps to the host (the camera still runs at %s)"
                             % (mode.width, mode.height, format_fps(mode.fps), format_fps(usb_fps),
                                format_fps(mode.fps)))
            added.append(usb_line(vendor, module, mode, usb_fps))
    if not has_headless_mapping(mappings, vendor, module, mode):
        added.append(headless_line(vendor, module, mode))
    if added:
        added.insert(0, header_comment(vendor, module))
    return VideoMappingsPlan(append_lines(text, added), added, notes)
