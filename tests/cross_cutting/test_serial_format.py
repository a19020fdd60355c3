"""The serial-line format (camera <-> flight app): standardized coordinates, parsing, line assembly."""
import pytest

from jevois_module.ForaNavTrees import foranav_serial as fs

SIZES = [(352, 288), (640, 480), (1280, 1024), (320, 240)]


@pytest.mark.parametrize("width,height", SIZES)
def test_that_standardized_coordinates_round_trip_within_half_a_unit(width, height):
    for u in (0, 1, width / 3, width / 2, width - 1, width):
        for v in (0, height / 4, height / 2, height - 1):
            line = fs.format_t2(u, v, width, height)
            msg = fs.parse_line(line + "\r\n")
            assert msg.kind == "T2"
            # one standardized unit is width/2000 px: integer rounding costs at most half of it
            assert abs(fs.std_to_img_x(msg.x, width) - u) <= 0.5 * width / 2000 + 1e-9
            assert abs(fs.std_to_img_y(msg.y, height) - v) <= 0.5 * height / 1500 + 1e-9


def test_that_the_frame_corners_and_centre_map_to_the_jevois_values():
    assert fs.format_t2(0, 0, 352, 288) == "T2 -1000 -750"
    assert fs.format_t2(352, 288, 352, 288) == "T2 1000 750"
    assert fs.format_t2(176, 144, 352, 288) == "T2 0 0"
    assert fs.format_t2(175.9, 144, 352, 288) == "T2 -1 0"  # never "-0"


def test_that_n2_carries_label_and_size():
    line = fs.format_n2("oil palm", 176, 144, 88, 72, 352, 288)
    assert line == "N2 oil_palm 0 0 500 375"
    msg = fs.parse_line(line.encode())
    assert (msg.kind, msg.label, msg.x, msg.y, msg.w, msg.h) == ("N2", "oil_palm", 0, 0, 500, 375)
    w, h = fs.std_to_img_size(msg.w, msg.h, 352, 288)
    assert (w, h) == pytest.approx((88, 72))


@pytest.mark.parametrize("line", ["OK", "ERR Unsupported command", "ALIVE", "INF Timer average", "T2 12",
                                  "T2 a b", "T2 1 2 3", "T2 1001 0", "T2 0 751", "T2 nan 0", "T2 inf 0",
                                  "N2 x 0 0 -5 10", "", "   ", "\x00\xff", b"\xff\xfeT2 1 1", "MARK MIDDLE",
                                  "T2 " + "1" * 80])
def test_that_anything_but_a_detection_or_mark_is_ignored(line):
    assert fs.parse_line(line) is None


def test_that_frame_marks_parse():
    assert fs.parse_line("MARK STOP\r\n") == fs.FrameMark("STOP")
    assert fs.parse_line(fs.FRAME_START) == fs.FrameMark("START")


def test_that_the_line_assembler_handles_partial_lines_and_any_terminator():
    sut = fs.LineAssembler()
    assert sut.feed(b"T2 1") == []
    assert sut.feed(b"0 20\r\nOK\nMARK ST") == [b"T2 10 20", b"OK"]
    assert sut.feed(b"OP\r") == [b"MARK STOP"]
    assert sut.feed(b"\n\n") == []


def test_that_a_huge_line_is_dropped_whole_and_the_next_line_survives():
    sut = fs.LineAssembler()
    lines = sut.feed(b"X" * 10000)
    lines += sut.feed(b"Y" * 10 + b"\r\nT2 5 -5\r\n")
    assert lines == [b"T2 5 -5"]
    assert sut.dropped == 1
    assert len(sut._buf) == 0
