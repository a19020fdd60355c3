"""The camera module on the camera's own runtime (Python 3.7, numpy 1.16.6, OpenCV 4.10) against the host run.

The venv is built once under .venv-camera/ (``make camera-runtime``; the fixture builds it too when missing).
Where this machine has no Python 3.7 these tests fail with one line, unless FORANAV_NO_CAMERA_RUNTIME=1.
"""
import json
import os
import subprocess
from pathlib import Path

import cv2
import numpy as np
import pytest

import host_tools.detection  # noqa: F401 (puts the camera module on the path)
from host_tools.errors import ForaNavError
from host_tools.jevois_host import DEFAULT_MODULE_DIR, camera_driver, camera_runtime
from host_tools.maps import PlantationMap, Tree, load_map
from host_tools.sim.camera import CameraModel, Pose
from host_tools.sim.world import SENSOR_EFFECTS, World

import foranav_features as features

DRIVER = Path(camera_driver.__file__)
DRIVER_TIMEOUT_S = 300
CAMERA_VERSIONS = {"python": "3.7", "numpy": "1.16.6", "opencv": "4.10.0"}
SMALL, LARGE = (352, 288), (1280, 1024)  # the flight sensor mode and the sensor's full size
# one tree of each shipped species, 0.6 m apart, so that every model sees its own species
MIXED_MAP = PlantationMap(name="mixed", altitude_m=1.25, waypoints=((0.0, 0.0), (2.0, 0.0)), seed=3, trees=(
    Tree(1, 0.6, 0.0, "oil_palm", 0.38, True), Tree(2, 1.2, 0.0, "citrus", 0.35, False),
    Tree(3, 1.8, 0.0, "olive", 0.35, False)))


def rendered_frames(folder: Path) -> list:
    """Frame files the camera could take: map 1 and the mixed map at 352x288 (PNG), two at 1280x1024 (npy, PNG)."""
    paths = []
    rng = np.random.default_rng(11)
    map1 = load_map("map1")
    offsets = zip((0.0, 0.2, -0.15, 0.1), (0.0, -0.2, 0.1, 0.25), (0, 15, -30, 90))  # dx, dy (m), yaw (deg)
    shots = [(map1, SMALL, (t.x + dx, t.y + dy, map1.altitude_m, yaw)) for t, (dx, dy, yaw) in zip(map1.trees, offsets)]
    shots += [(MIXED_MAP, SMALL, (t.x, 0.05, MIXED_MAP.altitude_m, 0.0)) for t in MIXED_MAP.trees]
    shots += [(map1, LARGE, (map1.trees[1].x, map1.trees[1].y, map1.altitude_m, 0.0)),
              (MIXED_MAP, LARGE, (1.2, 0.0, 1.5, 0.0))]
    worlds = {}
    for index, (pmap, (width, height), pose) in enumerate(shots):
        world = worlds.setdefault(pmap.name, World.from_map(pmap))
        image = world.render(CameraModel(width, height), Pose(*pose), rng=rng, effects=SENSOR_EFFECTS).image
        path = folder / ("frame%02d_%dx%d.%s" % (index, width, height, "npy" if index % 2 else "png"))
        if path.suffix == ".npy":
            np.save(path, image, allow_pickle=False)
        else:
            cv2.imwrite(str(path), image)
        paths.append(str(path))
    return paths


def job(folder: Path, frames: list, side: str) -> dict:
    runs = [{"params": {"species": model}, "serial": str(folder / ("%s_%s.bin" % (side, model)))}
            for model in camera_driver.shipped_models(DEFAULT_MODULE_DIR)]
    runs.append({"params": {"serstyle": "Normal", "maxtrees": 3}, "usb": True,
                 "serial": str(folder / ("%s_usb.bin" % side)), "usb_image": str(folder / ("%s_usb.npy" % side))})
    return {"module_dir": DEFAULT_MODULE_DIR, "frames": frames, "runs": runs,
            "models": str(folder / ("%s_models.json" % side))}


@pytest.fixture(scope="module")
def both_runs(camera_python, tmp_path_factory):
    """The same job on the host (in this process) and in the camera runtime -> (host job, camera job)."""
    folder = tmp_path_factory.mktemp("camera_runtime")
    frames = rendered_frames(folder)
    host_job, camera_job = job(folder, frames, "host"), job(folder, frames, "camera")
    camera_driver.run_job(host_job)
    (folder / "job.json").write_text(json.dumps(camera_job))
    result = subprocess.run([str(camera_python), str(DRIVER), str(folder / "job.json")], capture_output=True,
                            text=True, timeout=DRIVER_TIMEOUT_S, cwd=str(folder), env=_camera_env())
    assert result.returncode == 0, result.stderr[-3000:]
    return host_job, camera_job


def _camera_env() -> dict:
    # nothing of the host's Python may leak into the camera's: no PYTHONPATH, no user site-packages
    env = {k: v for k, v in os.environ.items() if not k.startswith("PYTHON")}
    env["PYTHONNOUSERSITE"] = "1"
    return env


def test_that_the_camera_runtime_is_python_37_with_numpy_116_and_opencv_410(both_runs):
    _host, camera = both_runs
    report = json.loads(Path(camera["models"]).read_text())
    assert report["python"].rsplit(".", 1)[0] == CAMERA_VERSIONS["python"]
    assert report["numpy"] == CAMERA_VERSIONS["numpy"]
    assert report["opencv"] == CAMERA_VERSIONS["opencv"]


def test_that_every_shipped_model_loads_there_to_the_same_arrays(both_runs):
    host, camera = both_runs
    host_models = json.loads(Path(host["models"]).read_text())["models"]
    camera_models = json.loads(Path(camera["models"]).read_text())["models"]
    assert sorted(camera_models) == camera_driver.shipped_models(DEFAULT_MODULE_DIR)
    assert len(camera_models) >= 3
    assert camera_models == host_models


def test_that_the_serial_bytes_equal_the_host_runs_for_every_model(both_runs):
    host, camera = both_runs
    for host_run, camera_run in zip(host["runs"], camera["runs"]):
        host_bytes, camera_bytes = Path(host_run["serial"]).read_bytes(), Path(camera_run["serial"]).read_bytes()
        assert camera_bytes.count(b"MARK STOP\r\n") == len(host["frames"])
        assert camera_bytes == host_bytes, "params %s" % host_run["params"]


def test_that_the_frames_hold_trees_of_every_species_for_its_model(both_runs):
    # guards the comparison above against frames on which every model sees nothing
    host, _camera = both_runs
    for run in host["runs"]:
        lines = Path(run["serial"]).read_bytes().decode("ascii").split("\r\n")
        assert any(not line.startswith("MARK") for line in lines if line), "no detection with %s" % run["params"]


def test_that_the_usb_output_image_equals_the_host_runs(both_runs):
    host, camera = both_runs
    host_image, camera_image = np.load(host["runs"][-1]["usb_image"]), np.load(camera["runs"][-1]["usb_image"])
    assert camera_image.shape == host_image.shape == (LARGE[1], LARGE[0], 3)
    assert np.array_equal(camera_image, host_image)


def test_that_building_again_is_a_no_op(camera_python):
    stamp = camera_runtime.DEFAULT_VENV / camera_runtime.STAMP_NAME
    before = stamp.stat().st_mtime_ns
    assert camera_runtime.build() == camera_python
    assert stamp.stat().st_mtime_ns == before


def _no_python37_here(monkeypatch, tmp_path):
    empty = tmp_path / "empty"
    empty.mkdir()
    monkeypatch.setenv("HOME", str(empty))
    monkeypatch.setenv("PYENV_ROOT", str(empty))
    monkeypatch.setenv("PATH", str(empty))
    monkeypatch.delenv(camera_runtime.PYTHON_VARIABLE, raising=False)


def test_that_without_python_37_the_check_fails_with_one_line(monkeypatch, tmp_path):
    _no_python37_here(monkeypatch, tmp_path)
    monkeypatch.delenv(camera_runtime.OPT_OUT_VARIABLE, raising=False)
    with pytest.raises(ForaNavError) as caught:
        camera_runtime.camera_python(tmp_path / "venv")
    assert "no Python 3.7" in str(caught.value) and "\n" not in str(caught.value)
    assert not (tmp_path / "venv").exists()


def test_that_only_the_explicit_opt_out_skips_it(monkeypatch, tmp_path):
    _no_python37_here(monkeypatch, tmp_path)
    monkeypatch.setenv(camera_runtime.OPT_OUT_VARIABLE, "1")
    assert camera_runtime.camera_python(tmp_path / "venv") is None
    monkeypatch.setenv(camera_runtime.OPT_OUT_VARIABLE, "0")
    with pytest.raises(ForaNavError):
        camera_runtime.camera_python(tmp_path / "venv")


RADIAL_ON_THE_CAMERA = """
import json, sys
import numpy as np
sys.path.insert(0, sys.argv[1])
import foranav_features as features
window = np.load(sys.argv[2], allow_pickle=False)
print(json.dumps([[float(v) for v in features.second_stage_descriptor(window, 48, "hog+radial", views)]
                  for views in features.SECOND_STAGE_VIEWS]))
"""


def test_that_the_second_stage_descriptor_in_every_view_is_the_hosts_there(camera_python, tmp_path):
    ys, xs = np.mgrid[0:120, 0:120] - 59.5  # a star of 7 rays about a point 9 px left of the centre
    window = (128 + 90 * np.cos(7 * np.arctan2(ys, xs + 9.0)) * np.exp(-(xs * xs + ys * ys) / 4000.0)).astype(np.uint8)
    np.save(tmp_path / "window.npy", window, allow_pickle=False)
    result = subprocess.run([str(camera_python), "-c", RADIAL_ON_THE_CAMERA, str(DEFAULT_MODULE_DIR),
                             str(tmp_path / "window.npy")], capture_output=True, text=True, timeout=DRIVER_TIMEOUT_S,
                            env=_camera_env())
    assert result.returncode == 0, result.stderr[-3000:]
    camera = json.loads(result.stdout)  # one descriptor per number of views
    assert len(camera) == len(features.SECOND_STAGE_VIEWS) > 1
    for views, values in zip(features.SECOND_STAGE_VIEWS, camera):
        assert np.allclose(values, features.second_stage_descriptor(window, 48, "hog+radial", views), atol=1e-4)
