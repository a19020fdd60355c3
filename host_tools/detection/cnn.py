"""The learned stage of a survey model (`foranav train --cnn`): a small CNN trained with PyTorch on the host,
exported to ONNX and run on the camera by OpenCV's dnn module (jevois_module/ForaNavTrees/foranav_cnn.py).

PyTorch is an optional training dependency (`pip install -e '.[train]'`); nothing else imports it, and a model
with a network runs without it (the camera never has it). Examples are windows labelled by where they lie:
a window centred within CENTRE_HIT of a crown's size on a complete crown of the species, its side 1.0-1.8
crowns, is a crown; one centred farther than CENTRE_MISS from every crown is not; windows in between are not
used. They are the windows the detector hands the network: crown-sized windows around every crown (jittered),
windows between crowns and off their centres, look-alikes and background, and the first stage's own group
representatives on every learning frame. Same data and seed, same network bytes (TRAINING_THREADS threads,
deterministic algorithms).
"""
import io
import math
from collections.abc import Callable, Sequence

import numpy as np

from host_tools.detection import dataset, examples
from host_tools.detection.dataset import Frame
from host_tools.errors import ForaNavError

import foranav_cnn
from foranav_model import TreeModel

CENTRE_HIT = 0.15  # of the crown: a window centred this close frames the crown
CENTRE_MISS = 0.4  # of the crown: a window centred farther from every crown frames none
SIZE_RANGE = (1.0, 1.8)  # window / crown of the windows the detector hands the network
POSITIVES_PER_CROWN = 3
NEAR_MISSES_PER_CROWN = 3
EPOCHS = 12
BATCH = 256
LEARNING_RATE = 3e-3
WEIGHT_DECAY = 1e-4
CHANNELS = (8, 16, 32, 32)  # the four 3x3 convolutions (the first three each followed by 2x2 max pooling)
ONNX_OPSET = 13
TRAINING_THREADS = 1  # fixed: same data and seed, same network (two threads spin-wait on a busy machine)

Log = Callable[[str], None]


def torch_or_error():
    """The torch module, or a one-line ForaNavError saying how to install it."""
    try:
        import torch  # optional training dependency: only `train --cnn` needs it
    except ImportError:
        raise ForaNavError("--cnn needs PyTorch: pip install -e '.[train]' (or pip install torch)")
    return torch


def network(torch, side: int = foranav_cnn.CNN_SIDE):
    """The network: four 3x3 convolutions with ReLU (max pooling after the first three), global average
    pooling, one linear output (a logit). About 15,000 weights at the default channels."""
    nn = torch.nn
    layers, before = [], 3
    for index, channels in enumerate(CHANNELS):
        layers += [nn.Conv2d(before, channels, 3, padding=1), nn.ReLU()]
        if index < len(CHANNELS) - 1:
            layers.append(nn.MaxPool2d(2))
        before = channels
    layers += [nn.AdaptiveAvgPool2d(1), nn.Flatten(), nn.Linear(before, 1)]
    if side % 8:
        raise ValueError("the network's input side must be a multiple of 8")
    return nn.Sequential(*layers)


def window_label(frame: Frame, species: str, cx: float, cy: float, side: float) -> int | None:
    """1: the window frames a complete crown of the species; 0: it frames none; None: in between (not used)."""
    nearest = None
    for box in frame.boxes:
        if box.label != species:
            continue
        crown = dataset.crown_size(box)
        distance = math.hypot(box.x_center - cx, box.y_center - cy) / crown
        if distance <= CENTRE_HIT and frame.complete(box) and SIZE_RANGE[0] <= side / crown <= SIZE_RANGE[1]:
            return 1
        nearest = distance if nearest is None else min(nearest, distance)
    return 0 if nearest is None or nearest > CENTRE_MISS else None


def frame_windows(frame: Frame, species: str, model: TreeModel, rng: np.random.RandomState, survey: bool,
                  representatives: examples.Representatives) -> list[tuple[float, float, float]]:
    """(cx, cy, side) windows of one learning frame: around each crown, between crowns, the first stage's
    examples (look-alikes, cut crowns, background) and, on survey frames, its group representatives."""
    windows = []
    for box in frame.boxes:
        if box.label != species:
            continue
        crown = dataset.crown_size(box)
        for _ in range(POSITIVES_PER_CROWN):
            offset, angle = rng.uniform(0, CENTRE_HIT) * crown, rng.uniform(0, 2 * math.pi)
            windows.append((box.x_center + offset * math.cos(angle), box.y_center + offset * math.sin(angle),
                            crown * rng.uniform(*SIZE_RANGE)))
        for _ in range(NEAR_MISSES_PER_CROWN):
            offset, angle = rng.uniform(CENTRE_MISS, 1.0) * crown, rng.uniform(0, 2 * math.pi)
            windows.append((box.x_center + offset * math.cos(angle), box.y_center + offset * math.sin(angle),
                            crown * rng.uniform(*SIZE_RANGE)))
    windows += examples.negative_windows(frame, species, model.window_margin, rng, survey)
    if survey:
        windows += [(cx, cy, side) for _score, cx, cy, side in representatives(frame)]
    return [w for w in windows if w[2] >= foranav_cnn.CNN_SIDE / 2 and frame.window_fits(*w)
            and (not survey or frame.in_area(w[0], w[1]))]


def frame_examples(frames: Sequence[Frame], species: str, model: TreeModel, rng: np.random.RandomState,
                   survey: bool, representatives: examples.Representatives | None = None
                   ) -> tuple[np.ndarray, np.ndarray]:
    """(inputs (n, 3, side, side) float32, labels (n,) float32) of one imagery's learning frames, each window in
    a random quarter turn or mirror."""
    inputs, labels = [], []
    representatives = representatives or examples.Representatives(model)
    for frame in frames:
        for cx, cy, side in frame_windows(frame, species, model, rng, survey, representatives):
            label = window_label(frame, species, cx, cy, side)
            if label is None:
                continue
            rows, cols = dataset.pixel_window(frame, cx, cy, side)
            window = frame.hsv[rows, cols]
            transform = rng.randint(8)
            window = np.rot90(window, transform % 4)
            if transform >= 4:
                window = window[:, ::-1]
            inputs.append(foranav_cnn.cnn_input(window))
            labels.append(float(label))
    side = foranav_cnn.CNN_SIDE
    return np.array(inputs, np.float32).reshape(-1, 3, side, side), np.array(labels, np.float32)


def train_network(inputs: np.ndarray, labels: np.ndarray, seed: int, log: Log,
                  epoch_done: Callable[[], None] = lambda: None) -> bytes:
    """Train the network on (inputs, labels) and return it as ONNX bytes (same inputs and seed, same bytes)."""
    torch = torch_or_error()
    torch.manual_seed(seed)
    torch.set_num_threads(TRAINING_THREADS)
    torch.use_deterministic_algorithms(True)
    net = network(torch)
    x = torch.from_numpy(inputs)
    y = torch.from_numpy(labels)
    positives = float(labels.sum())
    weight = torch.tensor((len(labels) - positives) / max(positives, 1.0))
    loss_of = torch.nn.BCEWithLogitsLoss(pos_weight=weight)
    optimiser = torch.optim.AdamW(net.parameters(), lr=LEARNING_RATE, weight_decay=WEIGHT_DECAY)
    steps = EPOCHS * math.ceil(len(labels) / BATCH)
    schedule = torch.optim.lr_scheduler.OneCycleLR(optimiser, max_lr=LEARNING_RATE, total_steps=steps)
    generator = torch.Generator().manual_seed(seed)
    for epoch in range(EPOCHS):
        net.train()
        order = torch.randperm(len(labels), generator=generator)
        total = 0.0
        for start in range(0, len(labels), BATCH):
            batch = order[start:start + BATCH]
            optimiser.zero_grad()
            loss = loss_of(net(x[batch]).squeeze(1), y[batch])
            loss.backward()
            optimiser.step()
            schedule.step()
            total += float(loss.detach()) * len(batch)
        log("network epoch %d/%d: loss %.4f" % (epoch + 1, EPOCHS, total / len(labels)))
        epoch_done()
    net.eval()
    buffer = io.BytesIO()
    side = inputs.shape[-1]
    torch.onnx.export(net, torch.zeros(1, 3, side, side), buffer, dynamo=False, opset_version=ONNX_OPSET,
                      input_names=["window"], output_names=["logit"],
                      dynamic_axes={"window": {0: "n"}, "logit": {0: "n"}})
    return buffer.getvalue()
