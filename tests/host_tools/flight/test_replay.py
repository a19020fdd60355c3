"""foranav replay: the committed clips through the module, the pty and the app (open loop), compared with the
stored expectations (tests/fixtures/replay_expectations/, tolerances stated in each file)."""
import json

import pytest

from host_tools import cli
from host_tools.flight.replay import expectation_record, map_override_warning, replay_clip
from host_tools.maps import load_map
from host_tools.sim.clip import read_clip
from tests.conftest import FIXTURES, MAP3_SHORT_SENSOR_CLIP, REPO_ROOT

EXPECTATIONS = sorted((FIXTURES / "replay_expectations").glob("*.json"))


def test_that_every_committed_clip_has_expectations():
    clips = {p.name for p in (FIXTURES / "clips").iterdir() if p.is_dir()}
    assert clips and clips == {p.stem for p in EXPECTATIONS}


@pytest.mark.parametrize("path", EXPECTATIONS, ids=lambda p: p.stem)
def test_that_a_replay_matches_its_expectations(path):
    spec = json.loads(path.read_text())
    expected, tol = spec["expected"], spec["tolerance_values"]
    report = replay_clip(read_clip(REPO_ROOT / spec["clip"]))
    got = expectation_record(report)
    assert got["frames"] == expected["frames"]
    assert abs(got["recall"] - expected["recall"]) <= tol["recall"]
    assert abs(got["precision"] - expected["precision"]) <= tol["precision"]
    assert got["mapped_tree_ids"] == expected["mapped_tree_ids"]
    assert got["spurious_app_trees"] == expected["spurious_app_trees"]
    assert got["tree_map_max_error_m"] <= expected["tree_map_max_error_m"] + tol["tree_map_error_m"]
    assert abs(got["setpoints"] - expected["setpoints"]) <= tol["setpoints_fraction"] * expected["setpoints"]
    # open loop: the app's estimate followed the recording, so the map is in the recording's frame
    assert not report["trees_seen_not_mapped"]
    assert report["serial_bytes"] > 0 and report["setpoints"][0]["phase"] == "FOLLOW_PATH"


def test_that_replay_without_a_map_fails_in_one_line(tmp_path, capsys):
    clip_dir = MAP3_SHORT_SENSOR_CLIP
    sidecar = json.loads((clip_dir / "clip.json").read_text())
    sidecar["map"] = None
    sidecar["video"] = str(clip_dir / "clip.avi")
    (tmp_path / "clip.json").write_text(json.dumps(sidecar))
    assert cli.main(["replay", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--map" in err[0]


def test_that_a_clip_whose_video_is_another_maps_is_refused_in_one_line(tmp_path, capsys):
    # Fixture: map3's sidecar beside map1's video (same camera size, more frames than the sidecar needs).
    (tmp_path / "clip.json").write_bytes((MAP3_SHORT_SENSOR_CLIP / "clip.json").read_bytes())
    (tmp_path / "clip.avi").write_bytes((FIXTURES / "clips" / "map1_full" / "clip.avi").read_bytes())
    assert cli.main(["replay", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and str(tmp_path / "clip.json") + ": video_sha256" in err[0] and "clip.avi" in err[0]


def test_that_a_map_other_than_the_recorded_one_is_replayed_with_a_warning(capsys):
    clip = read_clip(MAP3_SHORT_SENSOR_CLIP)
    assert map_override_warning(clip, load_map("map3")) is None  # the recorded map itself: nothing to say
    warning = map_override_warning(clip, load_map("map2"))
    assert "clip.json: map: the clip was recorded over" in warning and "trees" in warning
    assert cli.main(["replay", str(MAP3_SHORT_SENSOR_CLIP), "--map", "map2", "--json"]) == 0
    err = capsys.readouterr().err.strip().splitlines()
    assert err == ["warning: " + warning]
