"""Run the camera module over frame files and write its serial bytes: the same code on the host and the camera.

    <camera python> host_tools/jevois_host/camera_driver.py job.json

``job.json``::

    {"module_dir": ".../ForaNavTrees",
     "frames": ["a.png", "b.npy", ...],                 # BGR uint8; PNG read with cv2, .npy with numpy
     "runs": [{"params": {"species": "citrus"}, "serial": "out.bin", "usb": false}, ...],
     "models": "models.json"}                           # optional: digests of every shipped model file

Each run loads the module afresh (``engine.load_module``), pushes every frame through ``processNoUSB`` (or
``process`` when ``usb`` is true), and writes the CRLF-terminated serial lines, as sent, to ``serial``.

Only the camera's runtime is used: Python 3.7, numpy 1.16, OpenCV 4.10, the standard library, the libjevois
stand-in and the module folder. The host test runs the same job in its own process and compares the bytes.
"""
from __future__ import annotations

import glob
import hashlib
import io
import json
import os
import sys

import cv2
import numpy as np

try:
    from host_tools.jevois_host import engine
except ImportError:  # run as a script in the camera runtime: this folder holds engine.py and libjevois.py
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    import engine

MODEL_PATTERN = "foranav_*.npz"


def read_frame(path: str) -> np.ndarray:
    """A BGR uint8 frame from a PNG (or any image cv2 reads) or an .npy file."""
    if path.endswith(".npy"):
        frame = np.load(path, allow_pickle=False)
    else:
        frame = cv2.imread(path, cv2.IMREAD_COLOR)
    if frame is None or frame.dtype != np.uint8 or frame.ndim != 3:
        raise ValueError("%s: not a BGR uint8 frame" % path)
    return frame




def run_frames(module_dir: str, frames: list, params: dict, with_usb: bool = False) -> tuple[bytes, np.ndarray | None]:
    """One fresh module over the frames -> (the serial bytes, as sent, the last USB image or None)."""
    serial = io.BytesIO()
    runner = engine.ModuleRunner(module_dir=module_dir, serial_stream=serial, params=params,
                                 log_stream=engine.NullLog())
    for frame in frames:
        runner.process_frame(frame, with_usb=with_usb)
    return serial.getvalue(), runner.output_image


def model_digests(module_dir: str) -> dict[str, dict[str, str]]:
    """{model file: {array name: "dtype shape sha256"}} of every shipped model, loaded by the module itself."""
    instance, _standin = engine.load_module(module_dir, log_stream=engine.NullLog())
    digests = {}
    for name in shipped_models(module_dir):
        arrays = instance.loadModel(name).to_arrays()
        digests[name] = {
            key: "%s %s %s" % (np.asarray(value).dtype.str, list(np.asarray(value).shape),
                               hashlib.sha256(np.ascontiguousarray(value).tobytes()).hexdigest())
            for key, value in sorted(arrays.items())}
    return digests


def shipped_models(module_dir: str) -> list[str]:
    return [os.path.basename(p) for p in sorted(glob.glob(os.path.join(module_dir, MODEL_PATTERN)))]


def run_job(job: dict) -> None:
    """Do what ``job`` (the dict of job.json) asks; write its outputs."""
    frames = [read_frame(path) for path in job["frames"]]
    for run in job["runs"]:
        serial, usb_image = run_frames(job["module_dir"], frames, run.get("params", {}), run.get("usb", False))
        with open(run["serial"], "wb") as out:
            out.write(serial)
        if run.get("usb_image"):
            np.save(run["usb_image"], usb_image, allow_pickle=False)
    if job.get("models"):
        with open(job["models"], "w") as out:
            json.dump({"python": "%d.%d.%d" % sys.version_info[:3], "numpy": np.__version__,
                       "opencv": cv2.__version__, "models": model_digests(job["module_dir"])},
                      out, indent=1, sort_keys=True)


def main(argv: list[str]) -> int:
    if len(argv) != 1:
        print("usage: camera_driver.py job.json", file=sys.stderr)
        return 2
    with open(argv[0]) as handle:
        run_job(json.load(handle))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
