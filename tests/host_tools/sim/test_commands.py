"""The simulator's commands: render and record write what they say, deterministically; bad input is one line."""
import subprocess
import sys

import cv2
import pytest

from host_tools.sim.clip import read_clip


def foranav(*args):
    return subprocess.run([sys.executable, "-m", "host_tools.cli", *map(str, args)], capture_output=True, text=True)


def test_that_render_with_the_same_seed_writes_identical_bytes(tmp_path):
    outs = [tmp_path / "a.png", tmp_path / "b.png", tmp_path / "c.png"]
    for out, seed in zip(outs, (7, 7, 8)):
        proc = foranav("render", "--map", "map1", "--x", 1.86, "--y", 0.57, "--yaw", 20, "--seed", seed,
                       "--effects", "sensor", "--out", out)
        assert proc.returncode == 0, proc.stderr
    assert outs[0].read_bytes() == outs[1].read_bytes()
    assert outs[0].read_bytes() != outs[2].read_bytes()


def test_that_render_writes_the_sensor_mode_and_lists_the_trees_in_view(tmp_path):
    out = tmp_path / "f.png"
    proc = foranav("render", "--map", "map1", "--x", 1.86, "--y", 0.57, "--width", 640, "--height", 480,
                   "--out", out)
    assert proc.returncode == 0, proc.stderr
    assert cv2.imread(str(out)).shape == (480, 640, 3)
    assert "tree 3 oil_palm target=true u=" in proc.stdout and "complete" in proc.stdout


@pytest.mark.parametrize("args,needle", [
    (("--width", 300), "--width/--height"),
    (("--z", -1), "--z"),
    (("--z", 0), "--z"),
])
def test_that_bad_render_arguments_are_one_line_and_nonzero(tmp_path, args, needle):
    out = tmp_path / "f.png"
    proc = foranav("render", "--map", "map1", "--x", 1, "--y", 0, "--out", out, *args)
    assert proc.returncode == 2
    assert proc.stderr.strip().count("\n") == 0 and needle in proc.stderr
    assert not out.exists()


def test_that_record_flies_the_path_at_constant_speed_and_altitude(tmp_path):
    out = tmp_path / "clip"
    proc = foranav("record", "--map", "map2", "--out", out, "--speed", 0.5, "--fps", 4, "--duration", 2.0)
    assert proc.returncode == 0, proc.stderr
    clip = read_clip(out)
    assert len(clip) == 9  # 0, 0.25, ..., 2.0 s
    assert [f.t_s for f in clip.frames] == pytest.approx([i / 4 for i in range(9)])
    xs = [f.pose.x for f in clip.frames]
    assert all(b - a == pytest.approx(0.5 / 4) for a, b in zip(xs, xs[1:]))  # first leg runs along +x
    assert {f.pose.z for f in clip.frames} == {1.25}
    assert sum(1 for _ in clip.images()) == 9
    assert clip.map["name"].startswith("Paper Map 2")


def test_that_record_rejects_bad_arguments_without_writing(tmp_path):
    out = tmp_path / "clip"
    for args, needle in ((("--speed", 0), "--speed"), (("--fps", -1), "--fps"), (("--quality", 0), "--quality"),
                         (("--start", 100), "--start")):
        proc = foranav("record", "--map", "map1", "--out", out, *args)
        assert proc.returncode == 2 and needle in proc.stderr and proc.stderr.strip().count("\n") == 0
    assert not out.exists()


def test_that_record_rejects_a_bad_map_with_one_line(tmp_path):
    bad = tmp_path / "bad.json"
    bad.write_text('{"name": "x"}')
    proc = foranav("record", "--map", bad, "--out", tmp_path / "clip")
    assert proc.returncode == 2 and "altitude_m: missing" in proc.stderr
    assert not (tmp_path / "clip").exists()


def test_that_bench_sim_prints_frames_per_second_as_json():
    proc = foranav("bench", "sim", "--json")
    assert proc.returncode == 0, proc.stderr
    import json
    result = json.loads(proc.stdout)
    assert result["frame"] == "352x288" and result["fps"] > 0 and result["fps_sensor_effects"] > 0
