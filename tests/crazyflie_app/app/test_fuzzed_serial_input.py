"""Fuzzing the flight app, not only the serial parser (issue #11): seeded random byte streams of detection
frames, bursts, floods without MARK STOP, garbage, overlong and truncated lines and long silences, fed
through the app's serial link on the emulated firmware while it boots, takes off, flies and lands, with
PARAM capacities changed in flight. The firmware must never raise, and every buffer stays bounded.

The default run (a few seeds) stays well under 30 s; ``-m slow`` feeds 1,000,000 lines.
"""
import random

import pytest

from crazyflie_app.firmware import Crazyflie
from crazyflie_app.app.navigation import NavigationApp
from crazyflie_app.app.serial_link import SerialLink
from jevois_module.ForaNavTrees import foranav_serial as fs

PATH = ((0.3, 0.45), (3.9, 0.45), (3.9, -0.45), (0.3, -0.45))
TICK_MS = 10  # the fuzz stream produces one chunk of bytes per 10 ms (the camera task's polling period)
CHECK_EVERY_MS = 500
DEFAULT_SEEDS = (1, 2, 3, 4)
DEFAULT_LINES = 40000  # per seed
SLOW_LINES = 1000000
MAX_SIM_MS = 3600 * 1000
LABELS = (b"oil_palm", b"coconut", b"date_palm", b"x" * 40, b"")
GARBAGE = (b"OK", b"ALIVE", b"ERR Unsupported command [foo]", b"INF Camera ready", b"T2", b"T2 15", b"T2 abc def",
           b"T2 5000 0", b"T2 nan inf", b"T2 1e308 -1e308", b"N2 oil_palm 12 -40", b"N2 oil_palm 0 0 -5 -5",
           b"MARK", b"MARK STARTSTOP", b"MARK STOP extra", b"\x00\xff\xfe binary", b"T2 1 2 3 4 5 6 7 8 9 " * 8)


class FuzzStream(object):
    """A seeded generator of serial bytes, one chunk per call, in modes that change every few seconds."""

    MODES = ("frames", "frames", "frames", "burst", "flood", "garbage", "silence", "bytes", "split")

    def __init__(self, seed):
        self.rng = random.Random(seed)
        self.lines = 0
        self.mode, self.mode_left = "frames", 0
        self.frame_phase = 0

    def t2(self):
        r = self.rng
        if r.random() < 0.05:  # the edges and beyond
            return b"T2 %d %d" % (r.choice((-1000, 1000, -1001, 0)), r.choice((-750, 750, 751, 0)))
        return fs.format_t2(r.uniform(0, 352), r.uniform(0, 288), 352, 288).encode()

    def n2(self):
        r = self.rng
        return b"N2 %s %d %d %d %d" % (r.choice(LABELS), r.randint(-1000, 1000), r.randint(-750, 750),
                                       r.randint(0, 2000), r.randint(0, 1500))

    def frame(self, detections):
        body = [self.t2() if self.rng.random() < 0.7 else self.n2() for _ in range(detections)]
        return [fs.FRAME_START.encode()] + body + [fs.FRAME_STOP.encode()]

    def chunk(self):
        r = self.rng
        if self.mode_left <= 0:
            self.mode, self.mode_left = r.choice(self.MODES), r.randint(20, 1500)  # 0.2-15 s per mode
        self.mode_left -= 1
        lines = []
        if self.mode == "frames":
            self.frame_phase += TICK_MS
            if self.frame_phase >= 111:
                self.frame_phase = 0
                lines = self.frame(min(int(r.expovariate(0.4)), 60))
        elif self.mode == "burst":
            lines = self.frame(r.randint(20, 120)) if r.random() < 0.3 else []
        elif self.mode == "flood":  # T2 lines and never a MARK STOP
            lines = [self.t2() for _ in range(r.randint(5, 60))]
        elif self.mode == "garbage":
            lines = [r.choice(GARBAGE) for _ in range(r.randint(0, 20))]
        elif self.mode == "bytes":
            data = bytes(r.getrandbits(8) for _ in range(r.randint(0, 200)))
            self.lines += data.count(b"\n")
            return data
        elif self.mode == "split":  # a frame cut at a random byte, the rest next time (or never)
            data = b"".join(line + b"\r\n" for line in self.frame(r.randint(0, 8)))
            self.lines += len(data.split(b"\r\n")) - 1
            return data[:r.randint(0, len(data))]
        self.lines += len(lines)
        terminators = (b"\r\n", b"\n", b"\r", b"\x00")
        return b"".join(line + (b"\r\n" if r.random() < 0.9 else r.choice(terminators)) for line in lines)


class FuzzPort(object):
    """What ``serial.serial_for_url`` returns, fed by a FuzzStream at the firmware's clock."""

    def __init__(self, stream, clock):
        self.stream, self.clock = stream, clock
        self.pending = b""
        self.next_ms = 0

    def read(self, size):
        while self.next_ms <= self.clock():
            self.pending += self.stream.chunk()
            self.next_ms += TICK_MS
        data, self.pending = self.pending[:size], self.pending[size:]
        return data

    def close(self):
        pass


def fuzz_flight(seed, line_budget):
    """Fly the app on a fuzzed camera until ``line_budget`` lines were sent; check the bounds as it goes."""
    cf = Crazyflie(seed=seed)
    stream = FuzzStream(seed)
    link = SerialLink("fuzz://", port_factory=lambda: FuzzPort(stream, cf.x_task_get_tick_count))
    app = NavigationApp(cf, PATH, "fuzz://", link=link, target_label="oil_palm")
    app.start()
    rng = random.Random(seed + 1000)
    t = 0
    while stream.lines < line_budget and t < MAX_SIM_MS:
        t += CHECK_EVERY_MS
        cf.run_until(t)
        p = app.params
        assert app.num_trees <= max(1, p.tree_capacity)
        assert app.num_visited <= max(1, p.visited_capacity)
        assert app.pending_detections <= p.frame_capacity
        if rng.random() < 0.05:  # a ground station changes a capacity in flight
            name, value = rng.choice((("app.treeCapacity", rng.randint(1, 40)), ("app.visitedCap", rng.randint(1, 80)),
                                      ("app.frameCap", rng.randint(0, 80))))
            cf.registry.param_set(name, value)
    return app, stream


@pytest.mark.parametrize("seed", DEFAULT_SEEDS)
def test_that_the_app_never_raises_on_a_fuzzed_camera(seed):
    app, stream = fuzz_flight(seed, DEFAULT_LINES)
    assert stream.lines >= DEFAULT_LINES  # the whole budget went through the app
    assert app.detections > 0 and app.frames > 0  # valid frames among the noise were taken


def test_that_the_fuzz_stream_is_seeded():
    first, second = FuzzStream(7), FuzzStream(7)
    assert [first.chunk() for _ in range(2000)] == [second.chunk() for _ in range(2000)]


@pytest.mark.slow
@pytest.mark.timeout(3600)
def test_that_the_app_never_raises_on_a_million_fuzzed_lines():
    total = 0
    seed = 100
    while total < SLOW_LINES:
        _, stream = fuzz_flight(seed, SLOW_LINES - total)
        total += stream.lines
        seed += 1
    assert total >= SLOW_LINES
