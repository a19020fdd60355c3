"""No import circles among the project's Python modules, and no call circles among the C core's files: each
layer calls only the layers below it (DESIGN.md), so a reader can read any file knowing only what is under it.
The picture of docs/DESIGN.md names only functions that exist."""
from host_tools import architecture


def test_that_the_circle_finder_finds_a_circle():
    assert architecture.circles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert architecture.circles({"a": {"b"}, "b": set()}) == []


def test_that_no_python_module_imports_itself_round_a_circle():
    graph = architecture.python_imports()
    assert "crazyflie_app.app.nav_types" in graph["crazyflie_app.app.path_following"], "the import graph is read"
    assert architecture.circles(graph) == []


def test_that_no_c_core_file_calls_back_into_a_file_that_calls_it():
    graph = architecture.c_calls()
    assert "nav_state.c" in graph["nav_core.c"], "the call graph is read"
    assert architecture.circles(graph) == []


def test_that_the_camera_module_and_the_firmware_emulation_import_no_other_room():
    # (the app's own rule, only the serial grammar of the camera: test_app_on_firmware.py)
    rooms = architecture.room_imports()
    assert rooms["jevois_module.ForaNavTrees"] == []
    assert rooms["crazyflie_app.firmware"] == []


def test_that_every_step_of_the_picture_names_a_function_that_is_there():
    assert architecture.missing_steps() == []
    moved = (architecture.Step("camera", "x", "jevois_module/ForaNavTrees/foranav_detector.py:TreeDetector.gone"),
             architecture.Step("app", "x", "navNoSuchFunction"))
    assert architecture.missing_steps(moved) == [step.done_by for step in moved]
