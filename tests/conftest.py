"""What every test folder shares: where the repository and its committed test fixtures are.

Test folders mirror the code (docs/DESIGN.md, "Tests"); a folder's conftest.py holds what its tests share.
"""
from pathlib import Path

REPO_ROOT = Path(__file__).resolve().parent.parent
# committed inputs: CI clips, fault maps of docs/faults.md, an unseen map, the replay expectations
FIXTURES = REPO_ROOT / "tests" / "fixtures"
# the short sensor clip of map 3 that the closed-loop commands and the replay tests run on
MAP3_SHORT_SENSOR_CLIP = FIXTURES / "clips" / "map3_short_sensor"
