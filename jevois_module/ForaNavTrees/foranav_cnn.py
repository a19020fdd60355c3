# ForaNav tree detector: the learned stage, a small convolutional network run by OpenCV's dnn module.
#
# Models trained on survey imagery with `foranav train --cnn` carry a network in ONNX form (the model file's
# cnn_onnx field: its bytes, no pickle). Each group's representative window that passed the colour test is
# resized to CNN_SIDE x CNN_SIDE, turned to BGR and normalised by its own mean and contrast (the light and
# the camera's gain drop out), and the network's one output, a logit, must exceed the imagery's threshold.
# The windows of one frame go through the network in one batch. The network is a few thousand weights
# (host_tools/detection/cnn.py defines and trains it): it learns what the linear HOG cannot, the crown's
# centre against its neighbours' fronds and the gaps between crowns.
# Camera and host alike: Python 3.7, numpy 1.16, OpenCV 4.10 (cv2.dnn.readNetFromONNX of a byte buffer).
import re

import cv2
import numpy as np

CNN_SIDE = 32  # pixels of the network's square input
CNN_CONTRAST_FLOOR = 8.0  # grey levels added to a window's standard deviation before dividing by it


def cnn_input(hsv_window, side=CNN_SIDE):
    """One window (HSV_FULL, any size) as the network sees it: (3, side, side) float32 BGR, less its mean,
    over its standard deviation plus CNN_CONTRAST_FLOOR."""
    small = cv2.resize(np.ascontiguousarray(hsv_window), (side, side), interpolation=cv2.INTER_AREA)
    bgr = cv2.cvtColor(small, cv2.COLOR_HSV2BGR_FULL).astype(np.float32)
    mean, std = cv2.meanStdDev(bgr.reshape(-1, 1))
    scaled = (bgr - np.float32(mean[0, 0])) / np.float32(std[0, 0] + CNN_CONTRAST_FLOOR)
    return np.ascontiguousarray(scaled.transpose(2, 0, 1))


class CnnStage(object):
    """The network of one model: scores batches of HSV windows (a logit each; above 0 = crown-like)."""

    def __init__(self, onnx_bytes, side=CNN_SIDE):
        self.side = int(side)
        self.net = cv2.dnn.readNetFromONNX(np.frombuffer(bytes(onnx_bytes), np.uint8))

    def scores(self, hsv_windows):
        """Logits (float list) of the windows, in order."""
        if not hsv_windows:
            return []
        blob = np.stack([cnn_input(w, self.side) for w in hsv_windows])
        self.net.setInput(blob)
        return [float(v) for v in np.asarray(self.net.forward()).reshape(len(hsv_windows), -1)[:, 0]]


def network_problem(onnx_bytes, side=CNN_SIDE):
    """'' when the network loads and gives one finite logit for a window of the model's side, else why not
    (OpenCV's first line: what its ONNX importer or the forward pass says)."""
    try:
        stage = CnnStage(onnx_bytes, side)
        logits = stage.scores([np.zeros((int(side), int(side), 3), np.uint8)])
    except (cv2.error, ValueError, IndexError) as err:
        lines = [line.strip() for line in str(err).splitlines() if line.strip()]
        text = lines[-1] if lines else type(err).__name__
        found = re.search(r"error: \([^)]*\) (.*?)(?: in function .*)?$", text)  # OpenCV's: drop file and line
        return (found.group(1) if found else text)[:200]
    if len(logits) != 1 or not np.isfinite(logits[0]):
        return "its output is not one finite logit per window"
    return ""
