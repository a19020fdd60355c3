"""How much slower the JeVois-A33 runs the detector than this host: a factor measured through a published figure.

No A33 is at hand. OpenCV's model zoo publishes the time of its benchmark networks under OpenCV 4.10's dnn module
on a quad Cortex-A7 at 1.5 GHz (Toybrick RV1126, the A33's core, OpenCV's default threads): MobileNet v1 at
224 x 224, mean 1567.09 ms (opencv_zoo benchmark/README.md). This runs the same network (its published layer
list, seeded weights: the time does not depend on them) under OpenCV 4.10 on one core of this host, in the
camera's own runtime (.venv-camera), and prints the ratio scaled by the clocks (A33: 1.34 GHz):

    python -m host_tools.detection.a33_factor          # needs PyTorch to write the network (the train extra)

`foranav bench detector` multiplies its host times by the factor recorded in A33_FACTOR (docs/hardware.md).
"""
import argparse
import io
import json
import subprocess
import sys
import tempfile
from pathlib import Path

from host_tools.detection.cnn import torch_or_error
from host_tools.jevois_host import camera_runtime

ZOO_A7_MOBILENET_MS = 1567.09  # opencv_zoo benchmark/README.md, Toybrick RV1126 (4x Cortex-A7 1.5 GHz), 4.10
ZOO_A7_GHZ = 1.5
A33_GHZ = 1.34
MOBILENET_CHANNELS = ((32, 64, 1), (64, 128, 2), (128, 128, 1), (128, 256, 2), (256, 256, 1), (256, 512, 2),
                      (512, 512, 1), (512, 512, 1), (512, 512, 1), (512, 512, 1), (512, 512, 1), (512, 1024, 2),
                      (1024, 1024, 1))
TIMING_SCRIPT = """
import sys, time, cv2, numpy as np
cv2.setNumThreads(1)
net = cv2.dnn.readNetFromONNX(sys.argv[1])
x = np.random.RandomState(0).rand(1, 3, 224, 224).astype(np.float32)
times = []
for i in range(25):  # CPU time: the figure of this core's work, whatever else the machine runs
    start = time.process_time(); net.setInput(x); net.forward(); times.append(time.process_time() - start)
print(1000.0 * float(np.median(times[5:])))
"""


def mobilenet_onnx() -> bytes:
    """MobileNet v1 (1.0, 224) with seeded weights, as ONNX bytes."""
    torch = torch_or_error()
    nn = torch.nn
    torch.manual_seed(0)
    layers = [nn.Conv2d(3, 32, 3, 2, 1, bias=False), nn.BatchNorm2d(32), nn.ReLU()]
    for before, after, stride in MOBILENET_CHANNELS:
        layers += [nn.Conv2d(before, before, 3, stride, 1, groups=before, bias=False), nn.BatchNorm2d(before),
                   nn.ReLU(), nn.Conv2d(before, after, 1, bias=False), nn.BatchNorm2d(after), nn.ReLU()]
    layers += [nn.AdaptiveAvgPool2d(1), nn.Flatten(), nn.Linear(1024, 1000)]
    buffer = io.BytesIO()
    torch.onnx.export(nn.Sequential(*layers).eval(), torch.zeros(1, 3, 224, 224), buffer, dynamo=False,
                      opset_version=13)
    return buffer.getvalue()


def measure() -> dict:
    python = camera_runtime.build()
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "mobilenet_v1.onnx"
        path.write_bytes(mobilenet_onnx())
        # one core, as `foranav bench detector` times the detector
        out = subprocess.run(["taskset", "-c", "0", str(python), "-c", TIMING_SCRIPT, str(path)], check=True,
                             capture_output=True, text=True).stdout
    host_ms = float(out.split()[-1])
    factor = ZOO_A7_MOBILENET_MS / host_ms * ZOO_A7_GHZ / A33_GHZ
    return {"host_mobilenet_ms": round(host_ms, 2), "a7_mobilenet_ms": ZOO_A7_MOBILENET_MS,
            "clock_ratio": round(ZOO_A7_GHZ / A33_GHZ, 3), "factor": round(factor, 1)}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)
    result = measure()
    if args.json:
        print(json.dumps(result))
    else:
        print("MobileNet v1 224x224, OpenCV 4.10 dnn, one core: this host %.2f ms, quad Cortex-A7 1.5 GHz %.2f ms "
              "(published); A33 (1.34 GHz) / host factor %.1f" % (result["host_mobilenet_ms"],
                                                                 result["a7_mobilenet_ms"], result["factor"]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
