"""The emulated UART2: bytes arrive at 115200 baud into the firmware's 200-byte receive buffer, which drops
bytes silently when full. Both apps keep up with 8 T2 lines + MARK STOP per frame at 60 fps; a reader that
falls behind loses bytes, as on the Bolt."""
import pytest

from crazyflie_app.bolt.c_app import CNavigationApp
from crazyflie_app.firmware import PORT_MAX_DELAY, Crazyflie, v_task_delay
from crazyflie_app.firmware.uart2 import RX_BUFFER_BYTES
from crazyflie_app.app.navigation import BOOT_DELAY_MS, NavigationApp
from crazyflie_app.app.uart2_link import Uart2Link
from host_tools.flight.wire import PtyWire
from jevois_module.ForaNavTrees import foranav_serial as fs

FPS = 60
TREES_PER_FRAME = 8
BYTES_PER_MS = 115200 / 10 / 1000.0
WRITER_PRI = 6  # the camera side of the wire, before the firmware looks at the tick


def burst():
    """8 T2 lines at the frame's corners (the longest numbers) + MARK STOP: the worst frame."""
    lines = [fs.format_t2(u, v, 352, 288) for u, v in [(0, 0), (352, 288), (0, 288), (352, 0)] * 2]
    return b"".join(line.encode() + b"\r\n" for line in lines + [fs.FRAME_STOP])


@pytest.fixture
def wired():
    wire = PtyWire()
    cf = Crazyflie()
    cf.attach_uart2(wire.slave_path)
    yield cf, wire
    cf.uart2.close()
    wire.close()


def camera_task(cf, wire, data, start_ms, frames, fps=FPS):
    """Writes ``data`` once per frame at ``fps`` from ``start_ms``, like the JeVois at the end of each frame."""
    yield v_task_delay(start_ms)
    for k in range(frames):
        wire.write(data)
        next_ms = start_ms + int(round((k + 1) * 1000.0 / fps))
        yield v_task_delay(next_ms - cf.x_task_get_tick_count())
    yield v_task_delay(PORT_MAX_DELAY)


def test_that_a_burst_arrives_at_the_line_rate(wired):
    cf, wire = wired
    data = burst()
    cf.x_task_create(camera_task(cf, wire, data, 10, 1), "CAM", WRITER_PRI)
    cf.run_until(16)  # 5 ms after the write (+ the 1 ms poll)
    got = cf.uart2_get_data_with_timeout(1000, 1)
    assert 4 * BYTES_PER_MS <= len(got) <= 6 * BYTES_PER_MS
    cf.run_until(10 + int(len(data) / BYTES_PER_MS) + 3)
    got += cf.uart2_get_data_with_timeout(1000, 1)
    assert got == data
    assert cf.uart2.dropped_bytes == 0


def test_that_a_zero_timeout_returns_nothing_as_in_the_firmware(wired):
    cf, wire = wired
    cf.x_task_create(camera_task(cf, wire, b"T2 0 0\r\n", 0, 1), "CAM", WRITER_PRI)
    cf.run_until(10)
    assert cf.uart2_get_data_with_timeout(64, 0) == b""
    assert cf.uart2_get_data_with_timeout(64, 1) == b"T2 0 0\r\n"


def test_that_a_full_buffer_drops_the_bytes_that_do_not_fit(wired):
    # Fixture: 500 bytes, nobody reading for 100 ms
    cf, wire = wired
    data = bytes(range(256)) + bytes(range(244))
    cf.x_task_create(camera_task(cf, wire, data, 0, 1), "CAM", WRITER_PRI)
    # Test
    cf.run_until(100)
    got = cf.uart2_get_data_with_timeout(1000, 1)
    # Assert: the oldest 200 bytes kept, the rest lost, only the overrun flag tells
    assert got == data[:RX_BUFFER_BYTES]
    assert cf.uart2.dropped_bytes == len(data) - RX_BUFFER_BYTES
    assert cf.uart2.uart2_did_overrun() and not cf.uart2.uart2_did_overrun()


def test_that_a_reader_that_falls_behind_loses_bytes_at_60_fps(wired):
    # Fixture: a reader polling every 100 ms (Navigation.c slept 100 ms in its camera callback)
    cf, wire = wired
    frames = 60
    data = burst()
    cf.x_task_create(camera_task(cf, wire, data, 0, frames), "CAM", WRITER_PRI)
    received = []

    def slow_reader():
        while True:
            received.append(cf.uart2_get_data_with_timeout(10000, 1))
            yield v_task_delay(100)

    cf.x_task_create(slow_reader(), "READER", 1)
    # Test
    cf.run_until(1200)
    # Assert
    got = b"".join(received)
    assert cf.uart2.dropped_bytes > 0
    assert len(got) + cf.uart2.dropped_bytes == frames * len(data)
    assert got.count(b"MARK STOP") < frames // 2


@pytest.mark.parametrize("app_kind", ["python", "c"])
def test_that_both_apps_keep_up_with_8_trees_per_frame_at_60_fps(wired, app_kind):
    # Fixture: a booted app (estimate ready), then 2 s of the worst frames at 60 fps
    cf, wire = wired
    path = ((0.0, 0.0), (3.0, 0.0))
    app = (NavigationApp(cf, path, None, link=Uart2Link(cf)) if app_kind == "python"
           else CNavigationApp(cf, path))
    app.start()
    frames = 2 * FPS
    data = burst()
    assert len(data) == 123  # 10.7 ms on the wire: 64 % of the line at 60 fps
    cf.x_task_create(camera_task(cf, wire, data, BOOT_DELAY_MS + 100, frames), "CAM", WRITER_PRI)
    # Test
    cf.run_until(BOOT_DELAY_MS + 100 + 2000 + 100)
    # Assert: every byte, every line, every frame
    assert cf.uart2.dropped_bytes == 0
    assert cf.uart2.received_bytes == frames * len(data)
    assert app.link.lines_dropped == 0
    assert app.core.counters.detections == frames * TREES_PER_FRAME
