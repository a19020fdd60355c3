"""Opt-in (-m realdata): clips recorded over a real estate photo of ../shared/data/real (made at test time,
never committed) replay through both halves over the pty: the design card's "CI on recorded clips" on real
imagery."""
import json

import pytest

from host_tools import cli
from host_tools.maps import load_map
from host_tools.sim.clip import read_clip
from tests.conftest import REPO_ROOT

pytestmark = pytest.mark.realdata

ESTATE = REPO_ROOT.parent / "shared" / "data" / "real" / "oilpalm_uav_globalpro_id"
PHOTOS = ("Stani_01", "Stanj_03")  # held-out groups of docs/photo-flights.md


@pytest.mark.parametrize("name", PHOTOS)
def test_that_a_clip_recorded_over_a_real_estate_photo_replays_through_both_halves(name, tmp_path, capsys):
    if not (ESTATE / "images" / (name + ".jpg")).exists():
        pytest.skip("no shared estate photos")
    # Fixture: a photo map of one row, and a clip flown along it
    pmap_path = tmp_path / (name + ".json")
    assert cli.main(["plantation", "--photo", str(ESTATE / "images" / (name + ".jpg")),
                     "--boxes", str(ESTATE / "boxes.csv"), "--rows", "0", "--out", str(pmap_path)]) == 0
    clip = tmp_path / "clip"
    assert cli.main(["record", "--map", str(pmap_path), "--out", str(clip), "--speed", "0.3", "--fps", "9",
                     "--effects", "sensor"]) == 0
    capsys.readouterr()
    # Test
    code = cli.main(["replay", str(clip), "--json"])
    report = json.loads(capsys.readouterr().out)
    # Assert: every frame went through the module, the pty and the app; the ground truth is the photo's boxes
    assert code == 0
    assert report["frames"] == len(read_clip(clip).frames)
    assert report["serial_bytes"] > 0 and report["setpoints"]
    assert report["detection"]["true_positives"] + report["detection"]["missed"] > 0
    assert load_map(pmap_path).photo is not None
