"""The pure cores behind `foranav deploy`: mode parsing, videomappings.cfg parsing and planning, the headless
initscript block, and the serial line budget."""
import pytest

from host_tools.deploy import initscript, modes, videomappings
from host_tools.deploy.card import backup_path
from host_tools.errors import ForaNavError

MODE = modes.parse_mode("352x288@15")


@pytest.mark.parametrize("text,expected", [
    ("352x288@15", (352, 288, 15.0)), ("640X480@26.1", (640, 480, 26.1)), (" 176x144 @ 120 ", (176, 144, 120.0)),
    ("352x288@8.25", (352, 288, 8.25)),
])
def test_that_a_mode_parses(text, expected):
    assert tuple(modes.parse_mode(text)) == expected


@pytest.mark.parametrize("text", ["352x288", "352x288@0", "352x288@60.5", "1280x720@10", "x@", ""])
def test_that_a_mode_the_sensor_cannot_give_is_refused(text):
    with pytest.raises(ForaNavError):
        modes.parse_mode(text)


@pytest.mark.parametrize("fps,text", [(15, "15.0"), (26.1, "26.1"), (8.25, "8.25"), (0.1, "0.1")])
def test_that_fps_is_written_the_jevois_way(fps, text):
    assert modes.format_fps(fps) == text


def test_that_the_serial_budget_shrinks_with_the_frame_rate_and_never_drops_below_two_lines():
    budgets = [modes.serial_lines_per_frame(fps) for fps in (5, 15, 30, 60, 120)]
    assert budgets == sorted(budgets, reverse=True)
    assert budgets[-1] >= modes.MIN_LINES_PER_FRAME
    # 15 fps: 11520 B/s / 15 * 0.8 / 15 B per line
    assert modes.serial_lines_per_frame(15) == 40


def test_that_relative_usb_sizes_and_camera_modifiers_parse_like_jevois():
    mapping = videomappings.parse_mapping("YUYV +0 -16 24.0 Linear:YUYV 800 600 24.0 JeVois SaveVideo # note")
    assert (mapping.usb_width, mapping.usb_height, mapping.cam_format) == (800, 584, "YUYV")
    assert videomappings.parse_mapping("#YUYV 352 288 30.0 YUYV 352 288 30.0 JeVois PassThrough") is None
    assert videomappings.parse_mapping("YUYV 352 288 fast YUYV 352 288 30.0 JeVois PassThrough") is None
    assert videomappings.parse_mapping("YUYV 352 288 30.0") is None


def test_that_a_windows_edited_file_gets_windows_line_endings():
    text = "YUYV 640 480 30.0 YUYV 320 240 30.0 JeVois JeVoisIntro *\r\n"
    plan = videomappings.plan_videomappings(text, "ForaNav", "ForaNavTrees", MODE)
    assert plan.text.startswith(text)
    assert plan.text.count("\r\n") == plan.text.count("\n") == 1 + len(plan.added)


def test_that_an_existing_mapping_with_other_usb_settings_counts_as_present():
    # A user may have edited our USB line (e.g. another USB rate); it still runs our module in our camera mode.
    text = "YUYV 352 288 12.0 YUYV 352 288 15.0 ForaNav ForaNavTrees\nNONE 0 0 0 YUYV 352 288 15 ForaNav ForaNavTrees\n"
    plan = videomappings.plan_videomappings(text, "ForaNav", "ForaNavTrees", MODE)
    assert plan.text == text and plan.added == []


def test_that_mappings_of_another_vendor_do_not_count_as_ours():
    text = "NONE 0 0 0.0 YUYV 352 288 15.0 Other ForaNavTrees\n"
    plan = videomappings.plan_videomappings(text, "ForaNav", "ForaNavTrees", MODE)
    assert "NONE 0 0 0.0 YUYV 352 288 15.0 ForaNav ForaNavTrees" in plan.added


def test_that_damaged_initscript_markers_are_refused():
    text = initscript.BLOCK_BEGIN + "\nsetmapping2 YUYV 352 288 15.0 ForaNav ForaNavTrees\n"
    with pytest.raises(ForaNavError, match="markers"):
        initscript.plan_initscript(text, "ForaNav", "ForaNavTrees", MODE)


def test_that_a_later_serial_routing_line_is_reported():
    first = initscript.plan_initscript("", "ForaNav", "ForaNavTrees", MODE).text
    plan = initscript.plan_initscript(first + "setpar serout USB\n", "ForaNav", "ForaNavTrees", MODE)
    assert plan.text == first + "setpar serout USB\n"
    assert any("serout USB" in note for note in plan.notes)


def test_that_the_block_is_rewritten_in_place_when_the_mode_changes():
    user_after = "setpar camturbo true\n"
    first = initscript.plan_initscript("# mine\n", "ForaNav", "ForaNavTrees", MODE).text + user_after
    second = initscript.plan_initscript(first, "ForaNav", "ForaNavTrees", modes.parse_mode("320x240@30")).text
    assert second.startswith("# mine\n") and second.endswith(user_after)
    assert "setmapping2 YUYV 320 240 30.0 ForaNav ForaNavTrees" in second.splitlines()
    assert "setmapping2 YUYV 352 288 15.0 ForaNav ForaNavTrees" not in second
    assert initscript.block_mapping(second) == "setmapping2 YUYV 320 240 30.0 ForaNav ForaNavTrees"


def test_that_backups_are_numbered_after_the_highest_existing_one():
    names = {"config/videomappings.cfg.foranav-bak-1", "config/videomappings.cfg.foranav-bak-7",
             "config/initscript.cfg.foranav-bak-9"}
    assert backup_path("config/videomappings.cfg", names) == "config/videomappings.cfg.foranav-bak-8"
    assert backup_path("config/params.cfg", names) == "config/params.cfg.foranav-bak-1"
