"""The libjevois stand-in and module loader: one module object per camera helper, no state left between runs."""
import importlib
import io
import os
import shutil
import subprocess
import sys

import numpy as np
import pytest

import jevois_module.ForaNavTrees as package
from host_tools.jevois_host import DEFAULT_MODULE_DIR, ModuleRunner, libjevois, load_module
from host_tools.maps import load_map
from host_tools.sim.camera import CameraModel, Pose
from host_tools.sim.world import SENSOR_EFFECTS, World
from jevois_module.ForaNavTrees import foranav_serial
from tests.conftest import REPO_ROOT

HELPERS = sorted(f[:-3] for f in os.listdir(DEFAULT_MODULE_DIR) if f.startswith("foranav_") and f.endswith(".py"))
SUBPROCESS_TIMEOUT_S = 120
# Probe module: reports what the bindings tell it, so that state carried over from an earlier run shows up
PROBE_SOURCE = '''
import libjevois as jevois


class Probe:
    def init(self):
        jevois.sendSerial("INIT frame %d" % jevois.frameNum())

    def processNoUSB(self, inframe):
        jevois.sendSerial("FRAME %d mean %d" % (jevois.frameNum(), int(inframe.getCvBGR().mean())))
'''


def rendered(count, seed):
    pmap = load_map("map1")
    world, rng = World.from_map(pmap), np.random.default_rng(seed)
    return [world.render(CameraModel(), Pose(t.x + 0.1, t.y - 0.1, pmap.altitude_m, 20.0 * i), rng=rng,
                         effects=SENSOR_EFFECTS).image for i, t in enumerate(pmap.trees[:count])]


@pytest.mark.parametrize("helper", HELPERS)
def test_that_each_camera_helper_is_one_module_object_under_both_names(helper):
    plain = importlib.import_module(helper)
    assert importlib.import_module(package.__name__ + "." + helper) is plain
    assert getattr(package, helper) is plain
    assert os.path.dirname(os.path.abspath(plain.__file__)) == os.path.abspath(DEFAULT_MODULE_DIR)


def test_that_the_loaded_module_and_host_code_use_the_same_helper_objects():
    import host_tools.detection.reference as reference
    from jevois_module.ForaNavTrees import foranav_detector, foranav_features, foranav_model

    load_module()
    module = sys.modules["ForaNavTrees"]
    assert module.foranav_detector is foranav_detector and module.foranav_model is foranav_model
    assert foranav_detector.features is foranav_features and reference.features is foranav_features
    # an except across the two names catches what the module's copy raises
    with pytest.raises(foranav_model.ModelFormatError):
        module.foranav_model.model_from_arrays({}, name="empty")


SAME_OBJECTS = r"""
import importlib, sys
first, second = sys.argv[1], sys.argv[2]
def load(which):
    if which == "module":
        from host_tools.jevois_host import load_module
        load_module()  # the JeVois way: plain names, before anything imported the package
    else:
        importlib.import_module("jevois_module.ForaNavTrees.foranav_detector")
load(first); load(second)
import jevois_module.ForaNavTrees.foranav_detector as by_package
import foranav_detector, foranav_features
same = (by_package is foranav_detector and by_package.features is foranav_features
        and sys.modules["ForaNavTrees"].foranav_detector is by_package)
copies = [n for n, m in sys.modules.items() if n.endswith("foranav_features")]
print(same, len({id(sys.modules[n]) for n in copies}))
"""


@pytest.mark.parametrize("order", [("package", "module"), ("module", "package")])
def test_that_a_fresh_process_gets_one_copy_whatever_is_imported_first(order):
    result = subprocess.run([sys.executable, "-c", SAME_OBJECTS, *order], capture_output=True, text=True,
                            timeout=SUBPROCESS_TIMEOUT_S, cwd=REPO_ROOT)
    assert result.returncode == 0, result.stderr[-2000:]
    assert result.stdout.split() == ["True", "1"]


def run_bytes(frames, params=None, with_usb=False):
    serial = io.BytesIO()
    runner = ModuleRunner(serial_stream=serial, params=params, log_stream=io.StringIO())
    images = []
    for frame in frames:
        runner.process_frame(frame, with_usb=with_usb)
        images.append(None if runner.output_image is None else runner.output_image.tobytes())
    return serial.getvalue(), images


def test_that_a_run_gives_the_same_bytes_after_another_run_in_the_same_process():
    # Fixture: the frames of one flight, and a different run (other species, settings, console commands)
    frames, others = rendered(4, seed=1), rendered(3, seed=2)
    # Test
    first = run_bytes(frames, with_usb=True)
    other = ModuleRunner(params={"species": "olive", "serstyle": "Normal", "framemark": "None"})
    assert other.command("foranav maxtrees 1") == ""
    for frame in others:
        other.process_frame(frame)
    libjevois.configure(line_ending="\n")  # anything left in the bindings must not reach the next run
    again = run_bytes(frames, with_usb=True)
    # Assert
    assert b"T2 " in first[0]
    assert again == first


def test_that_frame_numbers_and_streams_start_afresh_with_each_runner(tmp_path, monkeypatch):
    folder = tmp_path / "Probe"
    folder.mkdir()
    (folder / "Probe.py").write_text(PROBE_SOURCE)
    monkeypatch.setattr(sys, "path", list(sys.path))
    monkeypatch.delitem(sys.modules, "Probe", raising=False)
    frames = [np.full((8, 8, 3), value, np.uint8) for value in (10, 20, 30)]

    def probe_run(count):
        serial = io.StringIO()
        runner = ModuleRunner(module_dir=str(folder), serial_stream=serial)
        for frame in frames[:count]:
            runner.process_frame(frame)
        return serial.getvalue()

    first = probe_run(3)
    between = probe_run(2)
    assert probe_run(3) == first
    assert first == "INIT frame 0\r\nFRAME 0 mean 10\r\nFRAME 1 mean 20\r\nFRAME 2 mean 30\r\n"
    assert between == "INIT frame 0\r\nFRAME 0 mean 10\r\nFRAME 1 mean 20\r\n"


def test_that_two_runners_in_turn_keep_their_own_streams_and_counts():
    frame = rendered(1, seed=3)[0]
    one, two = io.StringIO(), io.StringIO()
    runner_one = ModuleRunner(serial_stream=one)
    runner_two = ModuleRunner(serial_stream=two, params={"serstyle": "Normal"})
    runner_one.process_frame(frame)
    runner_two.process_frame(frame)
    runner_one.process_frame(frame)
    assert runner_one.frame_number == 2 and runner_two.frame_number == 1
    assert "N2 " not in one.getvalue() and one.getvalue().count("MARK STOP") == 2
    assert two.getvalue().count("MARK STOP") == 1 and two.getvalue().startswith("N2 oil_palm ")


def test_that_each_load_runs_the_files_of_the_folder_it_was_given(tmp_path, monkeypatch):
    # Fixture: a copy of the module folder whose main file and one helper differ from the repository's
    copy = tmp_path / "ForaNavTrees"
    shutil.copytree(DEFAULT_MODULE_DIR, copy, ignore=shutil.ignore_patterns("__init__.py", "__pycache__"))
    main = copy / "ForaNavTrees.py"
    main.write_text(main.read_text().replace('"serstyle", "str", "Serial message', '"serstyle", "str", "Copy:'))
    helper = copy / "foranav_serial.py"
    helper.write_text(helper.read_text().replace('FRAME_STOP = "MARK STOP"', 'FRAME_STOP = "MARK END"'))
    monkeypatch.setattr(sys, "path", list(sys.path))
    frame = rendered(1, seed=4)[0]

    def last_line_and_doc(module_dir=None):
        runner = ModuleRunner(module_dir=module_dir)
        return runner.process_frame(frame)[-1], libjevois.parameters(runner.instance)["serstyle"].description

    # Test: the repository's, the copy, the repository's again, in one process
    first = last_line_and_doc()
    from_copy = last_line_and_doc(str(copy))
    again = last_line_and_doc()
    # Assert
    assert first == again and first[0] == "MARK STOP" and not first[1].startswith("Copy:")
    assert from_copy[0] == "MARK END" and from_copy[1].startswith("Copy:")
    assert sys.modules["foranav_serial"] is foranav_serial
    assert sys.modules["ForaNavTrees"].foranav_serial is foranav_serial
