"""What every test folder shares: where the repository and its committed test fixtures are.

Test folders mirror the code (docs/DESIGN.md, "Tests"); a folder's conftest.py holds what its tests share.
"""
from pathlib import Path

import pytest

from host_tools.errors import ForaNavError
from host_tools.jevois_host import camera_runtime

REPO_ROOT = Path(__file__).resolve().parent.parent
# committed inputs: CI clips, fault maps of docs/faults.md, an unseen map, the replay expectations
FIXTURES = REPO_ROOT / "tests" / "fixtures"
# the short sensor clip of map 3 that the closed-loop commands and the replay tests run on
MAP3_SHORT_SENSOR_CLIP = FIXTURES / "clips" / "map3_short_sensor"


@pytest.fixture(scope="session")
def camera_python():
    """The camera's own interpreter (Python 3.7, numpy 1.16, OpenCV 4.10), built by make camera-runtime."""
    try:
        python = camera_runtime.camera_python()
    except ForaNavError as err:
        pytest.fail(str(err), pytrace=False)
    if python is None:
        pytest.skip("%s=1: no camera runtime on this machine" % camera_runtime.OPT_OUT_VARIABLE)
    return python
