"""argparse helpers shared by every command: range-checked numbers and options that may be given once.

Each ``type=`` helper turns the text into a value or raises ``argparse.ArgumentTypeError``; the parser then
prints one line naming the option (``foranav fly: error: argument --wind: must be finite, got 'nan'``) and
exits with status 2, before any work starts. Use them instead of ``type=float``/``type=int``, which accept
``nan``, ``inf`` and values no command can use::

    parser.add_argument("--fps", type=argtypes.float_range(0.5, 120.0), default=10.0)
    parser.add_argument("--seed", type=argtypes.seed, default=0)
    parser.add_argument("--mount-offset", type=argtypes.finite, nargs=2, action=argtypes.Once)
"""
import argparse
import ipaddress
import math
from typing import Callable

# numpy.random.RandomState (camera code, synthetic data) takes seeds 0 .. 2**32 - 1
SEED_MAX = 2 ** 32 - 1
DEFAULT_UDP_HOST = "127.0.0.1"  # a served port is local unless a host is given


def _number(text: str, kind: type) -> float:
    try:
        value = kind(text)
    except (TypeError, ValueError):
        raise argparse.ArgumentTypeError("expected %s, got %r" % ("an integer" if kind is int else "a number", text))
    if kind is float and not math.isfinite(value):
        raise argparse.ArgumentTypeError("must be finite, got %r" % text)
    return value


def finite(text: str) -> float:
    """Any finite number (not nan, not inf)."""
    return _number(text, float)


def positive(text: str) -> float:
    """A finite number > 0."""
    value = finite(text)
    if not value > 0:
        raise argparse.ArgumentTypeError("must be positive, got %r" % text)
    return value


def nonnegative(text: str) -> float:
    """A finite number >= 0."""
    value = finite(text)
    if value < 0:
        raise argparse.ArgumentTypeError("must not be negative, got %r" % text)
    return value


def probability(text: str) -> float:
    """A number in [0, 1]."""
    return float_range(0.0, 1.0)(text)


def float_range(low: float, high: float) -> Callable[[str], float]:
    """A finite number in [low, high]."""
    def parse(text):
        value = finite(text)
        if not low <= value <= high:
            raise argparse.ArgumentTypeError("must be in [%g, %g], got %r" % (low, high, text))
        return value
    parse.__name__ = "number in [%g, %g]" % (low, high)
    return parse


def int_range(low: int, high: int) -> Callable[[str], int]:
    """An integer in [low, high]."""
    def parse(text):
        value = _number(text, int)
        if not low <= value <= high:
            raise argparse.ArgumentTypeError("must be an integer in [%d, %d], got %r" % (low, high, text))
        return value
    parse.__name__ = "integer in [%d, %d]" % (low, high)
    return parse


def seed(text: str) -> int:
    """A seed: an integer 0 .. 2**32 - 1 (what numpy's RandomState takes)."""
    value = _number(text, int)
    if not 0 <= value <= SEED_MAX:
        raise argparse.ArgumentTypeError("must be an integer from 0 to %d, got %r" % (SEED_MAX, text))
    return value


def parse_udp_endpoint(text: str, low_port: int = 1) -> tuple[str, int]:
    """'[HOST:]PORT' -> (host, port), host 127.0.0.1 when absent; ValueError saying what is wrong."""
    host, _, port_text = str(text).strip().rpartition(":")
    host = host or DEFAULT_UDP_HOST
    try:
        port = int(port_text)
    except ValueError:
        raise ValueError("expected [HOST:]PORT, got %r" % text)
    if not low_port <= port <= 65535:
        raise ValueError("port must be in [%d, 65535], got %r" % (low_port, text))
    if any(c.isspace() for c in host) or ":" in host:
        raise ValueError("expected [HOST:]PORT with an IPv4 host or name, got %r" % text)
    return host, port


def udp_endpoint(text: str) -> str:
    """'[HOST:]PORT' (a UDP port to serve; host 127.0.0.1 when absent), normalised to 'HOST:PORT'."""
    try:
        return "%s:%d" % parse_udp_endpoint(text)
    except ValueError as err:
        raise argparse.ArgumentTypeError(str(err))


MAVLINK_SCHEMES = ("udpout", "udpin", "udp", "udpbcast", "tcp", "tcpin")  # pymavlink's network connections


def mavlink_url(text: str) -> str:
    """'SCHEME:HOST:PORT' for pymavlink's mavlink_connection (udpout:127.0.0.1:14550): a known network scheme,
    a host that is a valid IPv4 address when it is written as one, a port 1..65535."""
    scheme, _, rest = str(text).partition(":")
    if scheme not in MAVLINK_SCHEMES or rest.count(":") != 1 or rest.startswith(":"):
        raise argparse.ArgumentTypeError("expected SCHEME:HOST:PORT with SCHEME one of %s (e.g. udpout:127.0.0.1:14550), "
                                         "got %r" % (", ".join(MAVLINK_SCHEMES), text))
    try:
        host, port = parse_udp_endpoint(rest)
    except ValueError as err:
        raise argparse.ArgumentTypeError(str(err))
    if all(c.isdigit() or c == "." for c in host):
        try:
            ipaddress.IPv4Address(host)
        except ValueError:
            raise argparse.ArgumentTypeError("%r is not an IPv4 address (four numbers 0..255), in %r" % (host, text))
    return "%s:%s:%d" % (scheme, host, port)


class Once(argparse.Action):
    """An option that may be given once: a repeated --mount-offset 1 2 --mount-offset 3 4 is refused instead
    of silently keeping the last (for options whose values are one fixed-size group, e.g. nargs=2)."""

    def __call__(self, parser, namespace, values, option_string=None):
        if getattr(namespace, "_given_once", None) is None:
            namespace._given_once = set()
        if self.dest in namespace._given_once:
            parser.error("argument %s: given more than once" % option_string)
        namespace._given_once.add(self.dest)
        setattr(namespace, self.dest, values)
