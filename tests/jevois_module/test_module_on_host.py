"""The camera module (jevois_module/ForaNavTrees) on the host libjevois stand-in, and its camera constraints."""
import ast
import io
import math
import os
import sys

import cv2
import numpy as np
import pytest

from host_tools.jevois_host import DEFAULT_MODULE_DIR, ModuleRunner, libjevois, load_module
from host_tools.detection import synthetic
from jevois_module.ForaNavTrees import foranav_serial as fs

CAMERA_FILES = sorted(f for f in os.listdir(DEFAULT_MODULE_DIR) if f.endswith(".py") and f != "__init__.py")
CAMERA_THIRD_PARTY = {"numpy", "cv2", "libjevois", "pyjevois"}
BANNED_MODULES = {"sklearn", "skimage", "joblib", "pickle", "serial", "scipy", "torch", "tensorflow", "PIL",
                  "host_tools", "jevois_module", "yaml", "pandas", "numba", "dataclasses_json"}
# numpy >= 1.17 APIs (and names removed from later numpy), Python >= 3.8 library names
BANNED_ATTRIBUTES = {"default_rng", "Generator", "PCG64", "asscalar", "removeprefix", "removesuffix", "prod",
                     "isqrt", "dist", "cached_property", "typing"}
BANNED_NUMPY_ALIASES = {"float", "int", "bool", "object", "str", "complex"}
MATCH_PX = 16  # a T2 line matches a rendered tree when it decodes within this many pixels of its centre


@pytest.mark.parametrize("name", CAMERA_FILES)
def test_that_every_camera_file_is_python_37_with_only_camera_imports(name):
    source = open(os.path.join(DEFAULT_MODULE_DIR, name), encoding="utf-8").read()
    tree = ast.parse(source, filename=name, feature_version=(3, 7))  # SyntaxError for 3.8+ syntax
    siblings = {f[:-3] for f in CAMERA_FILES}
    for node in ast.walk(tree):
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            if isinstance(node, ast.ImportFrom):
                assert node.level == 0, "%s: relative import (the camera imports siblings by name)" % name
                modules = [node.module]
            else:
                modules = [alias.name for alias in node.names]
            for module in modules:
                top = module.split(".")[0]
                assert top not in BANNED_MODULES, "%s imports %s, which the camera lacks" % (name, module)
                assert (top in siblings or top in CAMERA_THIRD_PARTY or top in sys.stdlib_module_names), \
                    "%s imports %s: not stdlib, numpy, cv2 or a sibling" % (name, module)
        if isinstance(node, ast.Attribute):
            assert node.attr not in BANNED_ATTRIBUTES, "%s uses .%s (not on the camera)" % (name, node.attr)
            if isinstance(node.value, ast.Name) and node.value.id in ("np", "numpy"):
                assert node.attr not in BANNED_NUMPY_ALIASES, "%s uses np.%s" % (name, node.attr)
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr == "load":
            keywords = {k.arg: k.value for k in node.keywords}
            assert "allow_pickle" in keywords, "%s: np.load without allow_pickle=False" % name


def test_that_the_module_file_folder_and_class_share_one_name_and_document_their_mappings():
    folder = os.path.basename(DEFAULT_MODULE_DIR)
    source = open(os.path.join(DEFAULT_MODULE_DIR, folder + ".py"), encoding="utf-8").read()
    classes = [n.name for n in ast.parse(source).body if isinstance(n, ast.ClassDef)]
    assert classes == [folder]
    assert "@videomapping NONE 0 0 0.0 YUYV 352 288" in source
    assert "@videomapping YUYV 352 288" in source


def test_that_the_constructor_is_cheap_and_init_creates_the_parameters():
    instance, jevois = load_module()
    names = set(libjevois.parameters(instance))
    assert {"species", "svmthresh", "varthresh", "hsthresh", "edgethresh", "windows", "step", "serstyle",
            "framemark"} <= names
    assert instance.params["species"].get() == "oil_palm"


def test_that_each_frame_ends_with_mark_stop_even_without_trees():
    runner = ModuleRunner()
    empty = synthetic.ground(np.random.RandomState(0), 288, 352)
    assert runner.process_frame(empty) == [fs.FRAME_STOP]
    runner.setpar("framemark", "None")
    assert runner.process_frame(empty) == []


def test_that_send_serial_writes_crlf_terminated_lines_to_the_callers_stream():
    text, binary = io.StringIO(), io.BytesIO()
    for stream in (text, binary):
        runner = ModuleRunner(serial_stream=stream)
        runner.process_frame(synthetic.ground(np.random.RandomState(1), 288, 352))
    assert text.getvalue() == "MARK STOP\r\n"
    assert binary.getvalue() == b"MARK STOP\r\n"


def rendered_frames():
    """Frames of paper map 1 rendered over each tree (and 8 cm past it), with complete target trees."""
    sim_world = pytest.importorskip("host_tools.sim.world")
    from host_tools.maps import load_map
    from host_tools.sim.camera import CameraModel, Pose
    plantation = load_map("map1")
    world = sim_world.World.from_map(plantation)
    camera = CameraModel()
    frames = []
    for tree in plantation.trees[:5]:
        for ahead in (0.0, 0.08):
            frame = world.render(camera, Pose(tree.x + ahead, tree.y, plantation.altitude_m, 0.0))
            truths = [(t.u, t.v) for t in frame.trees if t.complete and t.species == "oil_palm"]
            frames.append((frame.image, truths))
    return frames


def decode_t2(lines, width, height):
    targets = [fs.parse_line(line) for line in lines]
    return [(fs.std_to_img_x(t.x, width), fs.std_to_img_y(t.y, height)) for t in targets
            if isinstance(t, fs.Target2D) and t.kind == "T2"]


def test_that_the_module_over_a_video_file_prints_t2_lines_at_the_rendered_trees(tmp_path):
    # Fixture: a rendered clip written as MJPG video, read back frame by frame (as jevois-daemon would).
    frames = rendered_frames()
    path = str(tmp_path / "clip.avi")
    writer = cv2.VideoWriter(path, cv2.VideoWriter_fourcc(*"MJPG"), 10, (352, 288))
    for image, _truths in frames:
        writer.write(image)
    writer.release()
    capture = cv2.VideoCapture(path)
    runner = ModuleRunner()
    # Test
    found = expected = 0
    for _image, truths in frames:
        ok, image = capture.read()
        assert ok
        lines = runner.process_frame(image)
        assert lines[-1] == fs.FRAME_STOP
        positions = decode_t2(lines, 352, 288)
        for u, v in truths:
            expected += 1
            found += any(math.hypot(x - u, y - v) <= MATCH_PX for x, y in positions)
    # Assert: the tree under the camera (and any other complete one) is reported where it was rendered
    assert expected >= len(frames)
    assert found >= 0.8 * expected


def test_that_t2_lines_decode_to_the_detection_centres_within_rounding():
    runner = ModuleRunner()
    image, _truths = rendered_frames()[0]
    detections = runner.instance.currentDetector().detect(image)
    positions = decode_t2(runner.process_frame(image), 352, 288)
    assert len(positions) == len(detections) > 0
    for (x, y), d in zip(positions, detections):
        assert abs(x - d.x) <= 0.5 * 352 / 2000 + 1e-9  # half a standardized unit
        assert abs(y - d.y) <= 0.5 * 288 / 1500 + 1e-9


def test_that_the_usb_output_shows_boxes_and_the_timer_text():
    runner = ModuleRunner(output_size=(352, 288))
    image, _truths = rendered_frames()[0]
    lines = runner.process_frame(image, with_usb=True)
    assert runner.output_image.shape == image.shape
    assert lines[-1] == fs.FRAME_STOP
    changed = np.any(runner.output_image != image, axis=2)
    assert changed[-20:, :120].any()  # the fps/CPU text, bottom left
    assert changed.mean() < 0.2  # drawing, not a different image


def test_that_the_console_offers_the_same_settings_as_the_parameters():
    runner = ModuleRunner()
    image, _truths = rendered_frames()[0]
    assert "svmthresh=" in runner.command("foranav")
    assert runner.command("foranav serstyle Normal") == ""
    assert runner.getpar("serstyle") == "Normal"
    lines = runner.process_frame(image)
    assert lines[0].startswith("N2 oil_palm ") and lines[-1] == fs.FRAME_STOP
    assert runner.command("foranav step 99").startswith("ERR")
    assert runner.command("foranav nosuch 1").startswith("ERR")
    assert runner.command("hello").startswith("ERR")
    assert runner.command("foranav maxtrees 1") == ""
    assert len(runner.process_frame(image)) <= 2
    assert "foranav" in runner.instance.supportedCommands()


def test_that_load_module_applies_params_like_params_cfg():
    instance, _jevois = load_module(params={"serstyle": "Normal", "step": 8})
    assert instance.params["serstyle"].get() == "Normal" and instance.params["step"].get() == 8
    with pytest.raises(KeyError):
        load_module(params={"nosuch": 1})


def test_that_the_timer_reports_fps_and_cpu_after_its_interval():
    timer = libjevois.Timer("t", 3, libjevois.LOG_DEBUG)
    texts = []
    for _ in range(3):
        timer.start()
        texts.append(timer.stop())
    assert texts[0] == "-- fps, --% CPU"
    assert texts[-1].endswith("% CPU") and " fps, " in texts[-1]


def test_that_parameters_check_their_type():
    class Component(object):
        pass
    component = Component()
    category = libjevois.ParameterCategory("c", "d")
    flag = libjevois.Parameter(component, "flag", "bool", "d", True, category)
    flag.set("false")
    assert flag.get() is False
    number = libjevois.Parameter(component, "n", "int", "d", 3, category)
    with pytest.raises(ValueError):
        number.set("x")
    with pytest.raises(ValueError):
        libjevois.Parameter(component, "bad", "nosuchtype", "d", 1, category)


def test_that_thresholds_follow_the_species_model_unless_set_explicitly():
    runner = ModuleRunner(params={"species": "olive", "svmthresh": "0.25"})
    image = synthetic.ground(np.random.RandomState(2), 288, 352)
    runner.process_frame(image)
    detector = runner.instance.currentDetector()
    assert detector.model.species == "olive"
    assert detector.threshold("svm_threshold") == 0.25  # explicit, as params.cfg would set it
    assert detector.threshold("hs_threshold") == pytest.approx(detector.model.hs_threshold)  # auto
    assert runner.command("foranav svmthresh auto") == ""
    runner.process_frame(image)
    assert runner.instance.currentDetector().threshold("svm_threshold") == pytest.approx(
        runner.instance.model.svm_threshold)
    assert runner.command("foranav species nosuch").startswith("ERR")


def test_that_the_edge_test_follows_the_model_unless_set_or_switched_off():
    runner = ModuleRunner()
    image = synthetic.ground(np.random.RandomState(2), 288, 352)
    runner.process_frame(image)
    detector = runner.instance.currentDetector()
    assert detector.threshold("edge_threshold") == pytest.approx(detector.model.edge_threshold)  # auto
    assert runner.command("foranav edgethresh off") == ""
    runner.process_frame(image)
    assert runner.instance.currentDetector().threshold("edge_threshold") == float("-inf")
    assert runner.command("foranav edgethresh 0.5") == ""
    runner.process_frame(image)
    assert runner.instance.currentDetector().threshold("edge_threshold") == 0.5
    assert runner.command("foranav edgethresh maybe").startswith("ERR")


def test_that_two_runners_in_one_process_keep_their_serial_streams_apart():
    first, second = io.StringIO(), io.StringIO()
    runner_a = ModuleRunner(serial_stream=first)
    runner_b = ModuleRunner(serial_stream=second, params={"framemark": "None"})
    empty = synthetic.ground(np.random.RandomState(3), 288, 352)
    assert runner_a.process_frame(empty) == [fs.FRAME_STOP]
    assert runner_b.process_frame(empty) == []
    assert first.getvalue() == "MARK STOP\r\n" and second.getvalue() == ""
