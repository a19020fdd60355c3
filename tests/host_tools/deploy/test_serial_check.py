"""The serial check a user runs against a deployed camera: counting what arrives and judging the frame rate."""
import os
import sys
import threading

import pytest

from host_tools.deploy import serial_check
from host_tools.deploy.modes import parse_mode

MODE = parse_mode("352x288@15")
LISTEN_S = 0.3
WRITE_DELAY_S = 0.05


def frames(rate, count, trees_per_frame=1, extra=()):
    """(t, line) events of `count` frames at `rate` fps, each with trees and an end mark."""
    events = []
    for i in range(count):
        t = i / rate
        events += [(t, b"T2 -120 84")] * trees_per_frame + [(t + 0.001, b"MARK STOP")]
    return events + [(0.0, line) for line in extra]


def test_that_the_summary_counts_detections_frames_and_other_lines():
    summary = serial_check.summarize(frames(15.0, 31, 2, extra=[b"OK", b"ERR Unknown command", b"\xff\xfe"]), 2.0)
    assert (summary.detections, summary.frames, summary.other) == (62, 31, 3)
    assert summary.frame_rate == pytest.approx(15.0)


def test_that_a_module_keeping_up_is_told_so():
    text = "\n".join(serial_check.verdict(serial_check.summarize(frames(14.9, 50), 4.0), MODE))
    assert "keeps up" in text


def test_that_a_module_held_to_half_the_camera_rate_gets_a_lower_mode_suggested():
    text = "\n".join(serial_check.verdict(serial_check.summarize(frames(7.5, 30), 4.0), MODE))
    assert "drops frames" in text and "--mode 352x288@7.2" in text


def test_that_silence_points_at_the_wiring():
    text = "\n".join(serial_check.verdict(serial_check.summarize([], 5.0), MODE))
    assert "wiring" in text


@pytest.mark.parametrize("rate,expected", [(26.3, 25.5), (8.9, 8.6), (0.05, 0.1)])
def test_that_the_suggested_fps_stays_just_below_the_measured_rate(rate, expected):
    assert serial_check.suggested_fps(rate) == pytest.approx(expected)


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="uses a Linux pty as the camera's port")
def test_that_listen_reads_crlf_lines_from_a_real_port():
    master, slave = os.openpty()
    # pyserial empties the input buffer when it opens the port, which can take longer than any fixed delay on
    # a loaded machine: the camera repeats its lines until the listening ends, as a streaming camera does.
    block = b"T2 1 2\r\nMARK STOP\r\nOK\r\n"
    listening = threading.Event()

    def camera():
        while not listening.wait(WRITE_DELAY_S):
            os.write(master, block)

    speaker = threading.Thread(target=camera)
    speaker.start()
    try:
        events = serial_check.listen(os.ttyname(slave), LISTEN_S)
    finally:
        listening.set()
        speaker.join()
        os.close(master)
        os.close(slave)
    expected = [b"T2 1 2", b"MARK STOP", b"OK"]
    lines = [line for _, line in events]
    # whole lines, CR LF stripped, in order (the block under way when listening stops may be cut)
    assert len(lines) >= 3 and lines == (expected * len(lines))[:len(lines)]


def test_that_a_port_that_cannot_be_opened_gives_one_line_and_exit_2(capsys, tmp_path):
    from host_tools.cli import main
    assert main(["serial-check", str(tmp_path / "no-such-port"), "--seconds", "0.1"]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "no-such-port" in err
