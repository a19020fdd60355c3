"""Paparazzi's JeVois parser (GPL, not in this repository) against the module's serial output: runs only when
PAPARAZZI_AIRBORNE names a folder holding modules/sensors/cameras/jevois.c (docs/hardware.md, "Other
autopilots"); it checks the setting docs/hardware.md recommends to Paparazzi users."""
import os
import shutil
from pathlib import Path

import pytest

from docs.measure import paparazzi_jevois
from host_tools.sim.clip import read_clip
from tests.conftest import FIXTURES

AIRBORNE = os.environ.get("PAPARAZZI_AIRBORNE")
pytestmark = pytest.mark.skipif(
    not AIRBORNE or not (Path(AIRBORNE) / "modules/sensors/cameras/jevois.c").is_file() or not shutil.which("cc"),
    reason="set PAPARAZZI_AIRBORNE to Paparazzi's sw/airborne to run the parser (not shipped here)")


def test_that_maxtrees_1_with_frame_marks_is_whole_and_the_defaults_lose_trees(tmp_path):
    binary = paparazzi_jevois.build_harness(Path(AIRBORNE), tmp_path)
    clips = [read_clip(FIXTURES / "clips" / "map1_full")]
    whole = paparazzi_jevois.measure(binary, paparazzi_jevois.module_lines(clips, 1, "Stop", "Terse"), "\r\n")
    assert whole["sent"] > 0 and whole["received"] == whole["sent"] == whole["exact"]
    default = paparazzi_jevois.measure(binary, paparazzi_jevois.module_lines(clips, 8, "Stop", "Terse"), "\r\n")
    assert default["received"] < default["sent"] and default["frames_best"] == default["frames"]
