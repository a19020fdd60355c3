"""The oracle camera: an ideal tree detector that reads the map's ground truth instead of images.

It implements the camera interface of the flight harness (``frame_period_ms``, ``latency_ms``,
``capture(t_ms, true_pose, hidden=frozenset()) -> list[str]``): for each tree of the map's target species
whose whole crown is inside the 352x288 frame seen from the true pose, it emits a ``T2`` line in JeVois
standardized coordinates (with Gaussian pixel noise and an independent dropout per detection), then
``MARK STOP``. It detects *species*, not the planting-column rule: an oil palm outside the column is reported
too, and the app must ignore it. Camera model and frames as in docs/DESIGN.md.
"""
from collections.abc import Collection, Sequence

import numpy as np

from host_tools.maps import PlantationMap, Tree
from host_tools.sim.camera import CameraModel, Pose
from jevois_module.ForaNavTrees import foranav_serial

DEFAULT_FRAME_PERIOD_MS = 100  # ~10 fps (the paper's detector runs at 8.9 fps on the JeVois)
DEFAULT_LATENCY_MS = 50
# the app takes at most 64 detections of a frame (NAV_MAX_FRAME_DETECTIONS): the oracle sends no more (10,000
# trees in view sent lines faster than the serial link carries them)
MAX_LINES_PER_FRAME = 64
DEFAULT_PIXEL_NOISE_PX = 1.5


class OracleCamera:
    def __init__(self, pmap: PlantationMap, *, seed: int = 0, frame_period_ms: int = DEFAULT_FRAME_PERIOD_MS,
                 latency_ms: int = DEFAULT_LATENCY_MS, pixel_noise_px: float = DEFAULT_PIXEL_NOISE_PX,
                 dropout: float = 0.0, width: int = 352, height: int = 288,
                 mount_offset: tuple[float, float] = (0.0, 0.0), frame_marks: bool = True):
        if not 0.0 <= dropout <= 1.0:
            raise ValueError("dropout must be in [0, 1], got %r" % dropout)
        if frame_period_ms <= 0 or latency_ms < 0:
            raise ValueError("frame_period_ms must be > 0 and latency_ms >= 0")
        self.frame_period_ms = int(frame_period_ms)
        self.latency_ms = int(latency_ms)
        self.pixel_noise_px = float(pixel_noise_px)
        self.dropout = float(dropout)
        self.camera = CameraModel(width, height, mount_offset)
        self.width, self.height = self.camera.width, self.camera.height
        self.focal_px = self.camera.focal_px
        self.mount_offset = self.camera.mount_offset
        self.frame_marks = frame_marks
        self.trees = [t for t in pmap.trees if t.species == pmap.target_species]
        self._rng = np.random.default_rng(seed)

    def ground_point(self, true_pose: Sequence[float]) -> tuple[float, float]:
        return self.camera.ground_point(Pose(*true_pose[:4]))

    def project(self, tree_x: float, tree_y: float, true_pose: Sequence[float]) -> tuple[float, float]:
        """Pixel (u, v) of a ground point seen from ``true_pose`` (x, y, z, yaw_deg; the oracle stays a nadir
        camera: it reports where the tree is under the MAV, whatever the body's tilt)."""
        return self.camera.world_to_pixel(Pose(*true_pose[:4]), tree_x, tree_y)

    def visible(self, true_pose: Sequence[float],
                hidden: Collection[int] = frozenset()) -> list[tuple[Tree, float, float]]:
        """(tree, u, v) for each target-species tree whose whole crown is in the frame."""
        z = true_pose[2]
        if z <= 0.05:
            return []
        out = []
        for tree in self.trees:
            if tree.id in hidden:
                continue
            u, v = self.project(tree.x, tree.y, true_pose)
            r = 0.5 * tree.crown_m * self.focal_px / z
            if r <= u <= self.width - r and r <= v <= self.height - r:
                out.append((tree, u, v))
        return out

    def capture(self, t_ms: int, true_pose: Sequence[float], hidden: Collection[int] = frozenset()) -> list[str]:
        lines = []
        for tree, u, v in self.visible(true_pose, hidden):
            # draw both random numbers for every tree so dropout does not shift the noise sequence
            noise = self._rng.normal(0.0, self.pixel_noise_px, 2) if self.pixel_noise_px > 0 else (0.0, 0.0)
            keep = self._rng.random() >= self.dropout
            if keep and len(lines) < MAX_LINES_PER_FRAME:
                lines.append(foranav_serial.format_t2(u + noise[0], v + noise[1], self.width, self.height))
        if self.frame_marks:
            lines.append(foranav_serial.FRAME_STOP)
        return lines
