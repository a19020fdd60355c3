"""Camera module settings: every value is checked on the way in (console and params.cfg alike), and a frame
that fails anyway still ends with MARK STOP and logs its error once (issue #11 item 3)."""
import io
import subprocess

import numpy as np
import pytest

from host_tools.detection import synthetic
from host_tools.jevois_host import DEFAULT_MODULE_DIR, ModuleRunner, libjevois
from jevois_module.ForaNavTrees import foranav_serial as fs

BAD_CONSOLE_SETTINGS = [("windows", "300"), ("windows", "nan"), ("windows", "10,96"), ("maxtrees", "0"),
                        ("maxtrees", "-3"), ("step", "0"), ("step", "25"), ("svmthresh", "nan"),
                        ("varthresh", "inf"), ("hsthresh", "x"), ("edgethresh", "-inf"), ("serstyle", "Loud"),
                        ("framemark", "Sometimes"), ("species", "nosuch")]
BAD_PARAMS_CFG = [("maxtrees", 0), ("step", 40), ("windows", "2000"), ("framemark", "Never"),
                  ("serstyle", "terse"), ("svmthresh", "nan"), ("species", "nosuch"), ("edgethresh", "maybe")]


def empty_frame(seed=0):
    return synthetic.ground(np.random.RandomState(seed), 288, 352)


@pytest.mark.parametrize("name,value", BAD_CONSOLE_SETTINGS)
def test_that_the_console_refuses_a_setting_that_would_break_the_frames(name, value):
    runner = ModuleRunner()
    runner.process_frame(empty_frame())  # a running camera: the frame size is known
    before = runner.getpar(name)
    reply = runner.command("foranav %s %s" % (name, value))
    assert reply.startswith("ERR ") and "\n" not in reply
    assert runner.getpar(name) == before
    assert runner.process_frame(empty_frame(1))[-1] == fs.FRAME_STOP


@pytest.mark.parametrize("name,value", BAD_PARAMS_CFG)
def test_that_params_cfg_values_that_would_break_the_frames_are_refused_at_load(name, value):
    with pytest.raises(ValueError, match=name if name != "species" else "species"):
        ModuleRunner(params={name: value})


def test_that_setpar_refuses_a_bad_value_and_keeps_the_old_one():
    runner = ModuleRunner()
    with pytest.raises(ValueError, match="maxtrees"):
        runner.setpar("maxtrees", 0)
    assert runner.getpar("maxtrees") >= 1
    runner.setpar("maxtrees", 3)
    assert runner.getpar("maxtrees") == 3


def test_that_good_values_are_still_accepted_at_the_console():
    runner = ModuleRunner()
    runner.process_frame(empty_frame())
    for name, value in (("windows", "72,96"), ("windows", "288"), ("maxtrees", "5"), ("step", "8"),
                        ("svmthresh", "0.4"), ("svmthresh", "auto"), ("edgethresh", "off"), ("species", "olive")):
        assert runner.command("foranav %s %s" % (name, value)) == "", (name, value)


def test_that_a_frame_that_fails_still_ends_with_mark_stop_and_logs_the_error_once():
    log = io.StringIO()
    # accepted before any frame (any sensor mode could come), too large for the 352x288 frames that do
    runner = ModuleRunner(params={"windows": "600"}, log_stream=log)
    frames = [runner.process_frame(empty_frame(seed)) for seed in range(3)]
    assert frames == [[fs.FRAME_STOP]] * 3
    errors = [line for line in log.getvalue().splitlines() if line.startswith("ERR")]
    assert len(errors) == 1 and "600" in errors[0]
    assert runner.command("foranav windows auto") == ""
    assert runner.process_frame(empty_frame(4))[-1] == fs.FRAME_STOP
    # a larger mode accepts larger windows; back at 352x288 the frames fail again: a new episode, logged again
    runner.process_frame(synthetic.ground(np.random.RandomState(5), 480, 640))
    runner.setpar("windows", "400")
    assert runner.process_frame(empty_frame(6)) == [fs.FRAME_STOP]
    errors = [line for line in log.getvalue().splitlines() if line.startswith("ERR")]
    assert len(errors) == 2 and "400" in errors[1]


ON_THE_CAMERAS_PYTHON = """
import importlib.util, io, sys
import numpy as np
spec = importlib.util.spec_from_file_location("libjevois", sys.argv[1])
jevois = importlib.util.module_from_spec(spec)
spec.loader.exec_module(jevois)
sys.modules["libjevois"] = jevois
sys.path.append(sys.argv[2])
import ForaNavTrees
serial, log = io.StringIO(), io.StringIO()
jevois.configure(serial_stream=serial, log_stream=log)
module = ForaNavTrees.ForaNavTrees()
module.init()
try:
    module.params["maxtrees"].set(0)
    sys.exit("maxtrees=0 accepted")
except ValueError:
    pass
module.params["windows"].set("600")
frame = (np.random.RandomState(0).rand(288, 352, 3) * 255).astype(np.uint8)
for _ in range(3):
    module.processNoUSB(jevois.InputFrame(frame))
assert serial.getvalue() == "MARK STOP\\r\\n" * 3, serial.getvalue()
assert log.getvalue().count("ERR") == 1, log.getvalue()
assert module.parseSerial("foranav windows 300").startswith("ERR")
print(sys.version_info[:2], np.__version__)
"""


def test_that_the_settings_checks_run_on_the_cameras_python(camera_python):
    # the camera's own runtime (Python 3.7, numpy 1.16, OpenCV 4.10: make camera-runtime)
    proc = subprocess.run([str(camera_python), "-c", ON_THE_CAMERAS_PYTHON, libjevois.__file__, DEFAULT_MODULE_DIR],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.startswith("(3, 7) 1.16")
