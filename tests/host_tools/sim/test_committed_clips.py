"""The committed CI clips decode and their ground truth agrees with the camera model and the map."""
import pytest

from host_tools.maps import map_from_dict
from host_tools.sim.clip import read_clip
from tests.conftest import FIXTURES

CLIPS = FIXTURES / "clips"
PIXEL_TOLERANCE = 0.01  # sidecar values are rounded to 1e-4


@pytest.mark.parametrize("name", ["map1_full", "map3_short_sensor"])
def test_that_a_fixture_clip_is_consistent(name):
    clip = read_clip(CLIPS / name)
    pmap = map_from_dict(clip.map, name)
    camera = clip.camera
    images = list(clip.images())
    assert len(images) == len(clip.frames) > 0
    assert all(im.shape == (camera.height, camera.width, 3) for im in images)
    seen_targets = set()
    for frame in clip.frames:
        assert frame.pose.z == pmap.altitude_m
        for tree in frame.trees:
            expected = camera.world_to_pixel(frame.pose, pmap.tree(tree.id).x, pmap.tree(tree.id).y)
            assert (tree.u, tree.v) == pytest.approx(expected, abs=PIXEL_TOLERANCE)
            assert tree.target == pmap.tree(tree.id).target
            if tree.complete and tree.target:
                seen_targets.add(tree.id)
    if name == "map1_full":  # flying the whole path shows every target tree whole at least once
        assert seen_targets == {t.id for t in pmap.targets}
