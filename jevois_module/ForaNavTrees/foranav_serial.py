# ForaNav serial-line format: the one definition shared by the camera module and the flight app.
#
# Runs on the JeVois-A33 (Python 3.7, stdlib only) and on the host. The grammar is JeVois' standardized
# serial output (doc/UserSerialStyle.dox):
#
#   T2 x y               one detected tree, Terse 2D: centre in standardized coordinates
#   N2 id x y w h        one detected tree, Normal 2D: id = species label, upright box size
#   MARK START           optional: a frame begins (JeVois sermark=Start)
#   MARK STOP            optional: the frame is done; "frame done, nothing seen" differs from "link silent"
#
# Standardized coordinates (jevois Coordinates.C): image centre (0, 0); x from -1000 (left edge) to 1000
# (right edge); y = 0.75 * (2000*v/H - 1000), from -750 (top) to 750 (bottom): y grows downward. Sizes
# scale the same way. Values are integers (serprec 0). The camera adds the CRLF line ending itself.
#
# Everything else on the line (the console's OK, ERR ..., ALIVE, log lines, noise) is not a detection and
# parse_line() returns None for it.
import collections
import math

STD_HALF_WIDTH = 1000.0
STD_HALF_HEIGHT = 750.0  # 1000 / JEVOIS_CAMERA_ASPECT (4/3), whatever the resolution
FRAME_START = "MARK START"
FRAME_STOP = "MARK STOP"
# Longest valid message: "N2 " + a 31-character id (pprz limit) + 4 numbers of up to 6 characters.
MAX_LINE_LENGTH = 64

Target2D = collections.namedtuple("Target2D", "kind label x y w h")  # kind "T2" or "N2"; w, h None for T2
FrameMark = collections.namedtuple("FrameMark", "what")  # what: "START" or "STOP"


def img_to_std_x(u, width):
    return 2000.0 * u / width - 1000.0


def img_to_std_y(v, height):
    return 0.75 * (2000.0 * v / height - 1000.0)


def std_to_img_x(x, width):
    return (x + 1000.0) * width / 2000.0


def std_to_img_y(y, height):
    return (y / 0.75 + 1000.0) * height / 2000.0


def img_to_std_size(w, h, width, height):
    return 2000.0 * w / width, 0.75 * 2000.0 * h / height


def std_to_img_size(sw, sh, width, height):
    return sw * width / 2000.0, sh / 0.75 * height / 2000.0


def _std_int(value, limit):
    # int(round()) not '%.0f': the latter prints -0.3 as "-0".
    return int(round(min(max(value, -limit), limit)))


def format_t2(u, v, width, height):
    """'T2 x y' for a tree centred at pixel (u, v) of a width x height frame."""
    return "T2 %d %d" % (_std_int(img_to_std_x(u, width), STD_HALF_WIDTH),
                         _std_int(img_to_std_y(v, height), STD_HALF_HEIGHT))


def format_n2(label, u, v, w, h, width, height):
    """'N2 id x y w h' for a tree box centred at (u, v) of size w x h pixels."""
    sw, sh = img_to_std_size(w, h, width, height)
    label = "_".join(str(label).split()) or "unknown"
    return "N2 %s %d %d %d %d" % (label[:31], _std_int(img_to_std_x(u, width), STD_HALF_WIDTH),
                                  _std_int(img_to_std_y(v, height), STD_HALF_HEIGHT),
                                  _std_int(sw, 2 * STD_HALF_WIDTH), _std_int(sh, 2 * STD_HALF_HEIGHT))


def _number(token):
    value = float(token)  # raises ValueError on garbage
    if not math.isfinite(value):
        raise ValueError(token)
    return value


def _in_frame(x, y):
    return abs(x) <= STD_HALF_WIDTH and abs(y) <= STD_HALF_HEIGHT


def parse_line(line):
    """One received line -> Target2D, FrameMark or None (anything that is not a detection or frame mark).

    Accepts str or bytes, with or without CR/LF. Coordinates outside the standardized frame are rejected.
    """
    if isinstance(line, bytes):
        try:
            line = line.decode("ascii")
        except UnicodeDecodeError:
            return None
    if len(line) > MAX_LINE_LENGTH + 2:
        return None
    tokens = line.strip().split()
    if not tokens:
        return None
    try:
        if tokens[0] == "T2" and len(tokens) == 3:
            x, y = _number(tokens[1]), _number(tokens[2])
            return Target2D("T2", None, x, y, None, None) if _in_frame(x, y) else None
        if tokens[0] == "N2" and len(tokens) == 6:
            x, y, w, h = [_number(t) for t in tokens[2:]]
            ok = _in_frame(x, y) and 0 <= w <= 2 * STD_HALF_WIDTH and 0 <= h <= 2 * STD_HALF_HEIGHT
            return Target2D("N2", tokens[1], x, y, w, h) if ok else None
    except ValueError:
        return None
    if tokens[0] == "MARK" and len(tokens) == 2 and tokens[1] in ("START", "STOP"):
        return FrameMark(tokens[1])
    return None


class LineAssembler(object):
    """Bytes from a serial port -> complete lines, tolerant of any terminator (JeVois 'Sloppy' style).

    A line longer than MAX_LINE_LENGTH can never be a valid message: it is dropped whole, up to its end,
    so the buffer stays bounded whatever arrives.
    """

    def __init__(self, max_length=MAX_LINE_LENGTH):
        self.max_length = max_length
        self._buf = bytearray()
        self._overlong = False
        self.dropped = 0  # lines dropped for length

    def feed(self, data):
        """Add received bytes; return the list of complete lines (bytes, without terminators)."""
        lines = []
        for byte in bytes(data):
            if byte in (10, 13, 0):  # LF, CR, NUL end a line
                if self._overlong:
                    self.dropped += 1
                elif self._buf:
                    lines.append(bytes(self._buf))
                self._buf = bytearray()
                self._overlong = False
            elif not self._overlong:
                self._buf.append(byte)
                if len(self._buf) > self.max_length:
                    self._overlong = True
                    self._buf = bytearray()
        return lines
