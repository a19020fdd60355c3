"""config/initscript.cfg for headless flight: start the ForaNav module at power-on, without a USB host.

JeVois runs this file's console commands at boot. We keep one managed block, always at the place it was first
added (the end of the file):

    # >>> ForaNav headless boot (foranav deploy --headless) >>>
    setmapping2 YUYV 352 288 15.0 ForaNav ForaNavTrees
    setpar serlog None
    setpar serout Hard
    streamon
    # <<< ForaNav headless boot <<<

Only one mapping can stream, and `setmapping2` fails while another one streams, so any other active
`setmapping`/`setmapping2`/`streamon` line outside the block is turned into a comment that keeps its text
(`#foranav-off# setmapping2 ...`); remove the prefix to restore it. Every other line of the user's stays as it was.
"""
from collections.abc import Sequence
from dataclasses import dataclass

from host_tools.deploy.modes import CameraMode, camera_fields
from host_tools.deploy.videomappings import append_lines, newline_of
from host_tools.errors import ForaNavError

BLOCK_BEGIN = "# >>> ForaNav headless boot (foranav deploy --headless) >>>"
BLOCK_END = "# <<< ForaNav headless boot <<<"
DISABLED_PREFIX = "#foranav-off# "
# Commands that select or start another mapping: they would clash with ours at boot.
CONFLICTING_COMMANDS = ("setmapping", "setmapping2", "streamon")
# Serial routing: a later line overrides ours and would keep T2 lines from the flight controller.
SERIAL_ROUTING = ("serout", "serlog")
NEW_FILE_HEADER = "# JeVois initialization script: console commands run at boot (headless set-up by ForaNav)"

@dataclass(frozen=True)
class InitscriptPlan:
    text: str  # the new file
    notes: list  # what the user should know


def headless_commands(vendor: str, module: str, mode: CameraMode) -> list[str]:
    return ["setmapping2 %s %s %s" % (camera_fields(mode), vendor, module),
            "setpar serlog None",
            "setpar serout Hard",
            "streamon"]


def _command_words(line: str) -> list[str]:
    stripped = line.strip()
    return [] if not stripped or stripped.startswith("#") else stripped.split()


def find_block(lines: Sequence[str]) -> tuple[int, int] | None:
    """(begin, end) indices of the managed block's marker lines, or None; ForaNavError if it is broken."""
    begins = [i for i, line in enumerate(lines) if line.strip() == BLOCK_BEGIN]
    ends = [i for i, line in enumerate(lines) if line.strip() == BLOCK_END]
    if not begins and not ends:
        return None
    if len(begins) != 1 or len(ends) != 1 or ends[0] < begins[0]:
        raise ForaNavError("config/initscript.cfg: the ForaNav block markers are damaged (%d begin, %d end "
                           "lines); fix or remove them by hand" % (len(begins), len(ends)))
    return begins[0], ends[0]


def block_mapping(text: str) -> str | None:
    """The `setmapping2 ...` command inside the managed block, or None (for reports on a non-headless deploy)."""
    lines = (text or "").splitlines()
    span = find_block(lines)
    if span is None:
        return None
    for line in lines[span[0] + 1:span[1]]:
        if _command_words(line)[:1] == ["setmapping2"]:
            return line.strip()
    return None


def _disable_conflicts(lines: list[str], span: tuple[int, int]) -> list[str]:
    """Comment out other modules' boot commands in place (lines keep their own endings)."""
    notes = []
    for i, line in enumerate(lines):
        if span and span[0] <= i <= span[1]:
            continue
        words = _command_words(line)
        if words and words[0] in CONFLICTING_COMMANDS:
            lines[i] = DISABLED_PREFIX + line
            notes.append("initscript.cfg line %d %r disabled (kept as a comment): only the ForaNav module starts "
                         "at boot" % (i + 1, line.strip()))
    return notes


def _warn_late_serial_routing(lines: Sequence[str], block_end: int) -> list[str]:
    notes = []
    for i in range(block_end + 1, len(lines)):
        words = _command_words(lines[i])
        if words[:1] == ["setpar"] and len(words) >= 3 and words[1] in SERIAL_ROUTING:
            if (words[1], words[2]) not in (("serout", "Hard"), ("serlog", "None")):
                notes.append("initscript.cfg line %d %r runs after the ForaNav block and overrides it: T2 lines "
                             "may not reach the flight controller" % (i + 1, lines[i].strip()))
    return notes


def plan_initscript(text: str | None, vendor: str, module: str, mode: CameraMode) -> InitscriptPlan:
    """New initscript text that boots the module headless (text None = no file yet). Idempotent.

    The block belongs to ForaNav and is rewritten whole (a new --mode replaces the old mapping); put your own
    commands outside it.
    """
    block = [BLOCK_BEGIN] + headless_commands(vendor, module, mode) + [BLOCK_END]
    if text is None:
        return InitscriptPlan(append_lines("", [NEW_FILE_HEADER] + block), ["initscript.cfg created"])
    newline = newline_of(text)
    lines = text.splitlines(True)  # keep each line's own ending: untouched lines stay byte-identical
    span = find_block(lines)
    notes = _disable_conflicts(lines, span)
    if span is None:
        new_text = append_lines("".join(lines), block)
    else:
        begin, end = span
        last_ending = lines[end][len(lines[end].rstrip("\r\n")):]
        lines[begin:end + 1] = [line + newline for line in block[:-1]] + [block[-1] + last_ending]
        new_text = "".join(lines)
    block_end = find_block(new_text.splitlines())[1]
    notes += _warn_late_serial_routing(new_text.splitlines(), block_end)
    return InitscriptPlan(new_text, notes)
