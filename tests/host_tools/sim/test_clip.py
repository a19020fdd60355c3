"""The clip format: written frames and ground truth read back; bad sidecars are one clear line."""
import hashlib
import json

import numpy as np
import pytest

from host_tools.errors import ForaNavError
from host_tools.maps import load_map, map_to_dict
from host_tools.sim.camera import CameraModel
from host_tools.sim.clip import SIDECAR_NAME, read_clip, write_clip
from host_tools.sim.path import path_length, poses_along_path
from host_tools.sim.world import World

MJPG_MEAN_ERROR = 4.0  # grey levels: lossy compression at quality 90


@pytest.fixture(scope="module")
def written_clip(tmp_path_factory):
    pmap = load_map("map3")
    world = World.from_map(pmap)
    camera = CameraModel()
    timed = poses_along_path(pmap.waypoints, 0.5, 5.0, pmap.altitude_m, duration_s=1.2)
    frames = [world.render(camera, pose) for _, pose in timed]
    out = tmp_path_factory.mktemp("clip") / "c"
    write_clip(out, frames, [t for t, _ in timed], camera, 5.0, map_to_dict(pmap), {"why": "test"}, quality=90)
    return out, frames, timed


def test_that_a_clip_reads_back_frames_poses_and_ground_truth(written_clip):
    out, frames, timed = written_clip
    clip = read_clip(out)
    assert len(clip) == len(frames) == 7
    assert clip.fps == 5.0 and clip.camera.width == 352 and clip.source == {"why": "test"}
    for rec, frame, (t, pose) in zip(clip.frames, frames, timed):
        assert rec.t_s == pytest.approx(t) and rec.pose == pytest.approx(pose, abs=1e-4)
        assert [tr.id for tr in rec.trees] == [tr.id for tr in frame.trees]
        for a, b in zip(rec.trees, frame.trees):
            assert (a.u, a.v, a.w, a.complete, a.x) == pytest.approx((b.u, b.v, b.w, b.complete, b.x), abs=1e-3)
    images = list(clip.images())
    assert len(images) == len(frames)
    for decoded, frame in zip(images, frames):
        assert decoded.shape == frame.image.shape
        assert np.abs(decoded.astype(int) - frame.image.astype(int)).mean() < MJPG_MEAN_ERROR


def test_that_writing_the_same_frames_gives_the_same_bytes(written_clip, tmp_path):
    out, frames, timed = written_clip
    pmap = load_map("map3")
    write_clip(tmp_path / "again", frames, [t for t, _ in timed], CameraModel(), 5.0, map_to_dict(pmap),
               {"why": "test"}, quality=90)
    for name in ("clip.avi", SIDECAR_NAME):
        assert (out / name).read_bytes() == (tmp_path / "again" / name).read_bytes()


@pytest.mark.parametrize("change,needle", [
    (lambda d: d.update(format="other"), "format"),
    (lambda d: d.update(version=9), "version"),
    (lambda d: d.update(fps=0), "fps"),
    (lambda d: d["frames"][1]["pose"].pop("z"), "frames[1]"),
    (lambda d: d["frames"][2].update(index=5), "frames[2].index"),
    (lambda d: d["frames"][0]["pose"].update(x=float("nan")), "frames[0]"),
    (lambda d: d.update(video_sha256="not a digest"), "video_sha256"),
])
def test_that_a_bad_sidecar_is_named_in_one_line(written_clip, tmp_path, change, needle):
    data = json.loads((written_clip[0] / SIDECAR_NAME).read_text())
    change(data)
    (tmp_path / SIDECAR_NAME).write_text(json.dumps(data))
    with pytest.raises(ForaNavError) as err:
        read_clip(tmp_path)
    assert needle in str(err.value) and "\n" not in str(err.value)


def test_that_a_clip_without_ground_truth_reads_as_unknown_trees(written_clip, tmp_path):
    data = json.loads((written_clip[0] / SIDECAR_NAME).read_text())
    for rec in data["frames"]:
        rec["trees"] = None
    data["map"] = None
    (tmp_path / SIDECAR_NAME).write_text(json.dumps(data))
    clip = read_clip(tmp_path)
    assert all(f.trees is None for f in clip.frames) and clip.map is None


def test_that_poses_along_the_path_keep_constant_speed_and_end_at_the_last_waypoint():
    waypoints = ((0.3, 0.45), (3.9, 0.45), (3.9, -0.45), (0.3, -0.45))
    timed = poses_along_path(waypoints, speed=0.3, fps=10, altitude=1.25)
    assert timed[-1][0] == pytest.approx(path_length(waypoints) / 0.3)
    assert (timed[-1][1].x, timed[-1][1].y) == pytest.approx((0.3, -0.45))
    steps = [np.hypot(b.x - a.x, b.y - a.y) for (_, a), (_, b) in zip(timed, timed[1:])]
    assert max(steps) <= 0.03 + 1e-9 and np.median(steps) == pytest.approx(0.03)
    assert {p.z for _, p in timed} == {1.25}


def test_that_the_sidecar_records_its_videos_digest_and_the_clip_reads_it_back(written_clip):
    out = written_clip[0]
    clip = read_clip(out)
    assert clip.video_sha256 == hashlib.sha256((out / "clip.avi").read_bytes()).hexdigest()
    clip.check_video()


def test_that_a_video_swapped_in_from_another_clip_is_refused_in_one_line(written_clip, tmp_path):
    # Fixture: the same sidecar with another clip's video of the same size and length (another map's flight).
    out, frames, timed = written_clip
    other_map = load_map("map1")
    other = [World.from_map(other_map).render(CameraModel(), pose) for _, pose in timed]
    write_clip(tmp_path / "other", other, [t for t, _ in timed], CameraModel(), 5.0, map_to_dict(other_map))
    (tmp_path / "swapped").mkdir()
    (tmp_path / "swapped" / SIDECAR_NAME).write_bytes((out / SIDECAR_NAME).read_bytes())
    (tmp_path / "swapped" / "clip.avi").write_bytes((tmp_path / "other" / "clip.avi").read_bytes())
    # Test
    with pytest.raises(ForaNavError) as err:
        read_clip(tmp_path / "swapped").check_video()
    # Assert
    message = str(err.value)
    assert "\n" not in message and "swapped/clip.json: video_sha256" in message and "clip.avi" in message
    # A hand-made sidecar without the digest is not checked (real footage written by other tools).
    data = json.loads((out / SIDECAR_NAME).read_text())
    del data["video_sha256"]
    (tmp_path / "swapped" / SIDECAR_NAME).write_text(json.dumps(data))
    read_clip(tmp_path / "swapped").check_video()
