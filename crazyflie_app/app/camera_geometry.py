"""Camera geometry of the navigation core (DESIGN.md, "Frames and the camera"): body <-> world rotation, the
camera's ground point, pixel <-> ground, the ego-motion correction of a measured pixel, the pose history that
finds the pose at a frame's capture time, and the merge of one frame's duplicate detections.

* One frame, one detection per crown: detections of one frame closer than ``dupRadius`` on the ground are
  merged first (``merge_duplicates``); without this, two detector windows on one big crown (1.0 m
  altitude) became two stored trees and the tree was reached twice.
"""
import math
from collections import deque
from collections.abc import Sequence

from crazyflie_app.app.nav_types import POSE_HISTORY_LENGTH, Detection, NavigationParams, Pose

Point = tuple[float, float]  # (x, y) m or (u, v) px
MIN_HEIGHT_M = 0.05  # the ground scale uses at least this height (never zero on the ground)


def rotate(yaw_deg: float, bx: float, by: float) -> Point:
    """Body (forward, left) -> world."""
    c, s = math.cos(math.radians(yaw_deg)), math.sin(math.radians(yaw_deg))
    return bx * c - by * s, bx * s + by * c


def unrotate(yaw_deg: float, wx: float, wy: float) -> Point:
    """World -> body (forward, left)."""
    c, s = math.cos(math.radians(yaw_deg)), math.sin(math.radians(yaw_deg))
    return wx * c + wy * s, -wx * s + wy * c


class CameraGeometry:
    """The downward camera of ``params`` (size, scale, mount offset; read live, PARAMs may change)."""

    def __init__(self, params: NavigationParams):
        self.params = params

    @property
    def centre(self) -> Point:
        """The principal point (u, v), px."""
        return self.params.cam_width_px / 2.0, self.params.cam_height_px / 2.0

    def ground_point(self, pose: Pose) -> Point:
        """The camera's nadir on the ground: MAV position + R(yaw) * mount offset."""
        ox, oy = rotate(pose.yaw_deg, self.params.cam_offset_x_m, self.params.cam_offset_y_m)
        return pose.x + ox, pose.y + oy

    def pixel_to_world(self, u: float, v: float, pose: Pose) -> Point:
        """DESIGN.md camera model: body offset = ((H/2 - v), (W/2 - u)) * z / f, rotated by yaw."""
        p = self.params
        scale = max(pose.z, MIN_HEIGHT_M) / p.focal_px
        fwd, left = (p.cam_height_px / 2.0 - v) * scale, (p.cam_width_px / 2.0 - u) * scale
        wx, wy = rotate(pose.yaw_deg, fwd, left)
        cx, cy = self.ground_point(pose)
        return cx + wx, cy + wy

    def centre_error(self, u: float, v: float) -> Point:
        """Pixel offset (eu, ev) of (u, v) from the principal point."""
        return u - self.params.cam_width_px / 2.0, v - self.params.cam_height_px / 2.0

    def metric_offset(self, eu: float, ev: float, z: float) -> Point:
        """Ground offset (forward, left) in metres of a target at pixel offset (eu, ev) seen from height z."""
        scale = max(z, MIN_HEIGHT_M) / self.params.focal_px
        return -ev * scale, -eu * scale

    def ego_corrected(self, det: Detection, pose_capture: Pose, pose_now: Pose) -> Point:
        """The measured pixel moved to where the tree appears now, given the MAV's motion since capture."""
        fwd, left = unrotate(pose_now.yaw_deg, pose_now.x - pose_capture.x, pose_now.y - pose_capture.y)
        scale = self.params.focal_px / max(pose_now.z, MIN_HEIGHT_M)
        return det.u + left * scale, det.v + fwd * scale


class PoseHistory:
    """The last ``length`` (t_ms, Pose) of the control ticks, for latency compensation."""

    def __init__(self, length: int = POSE_HISTORY_LENGTH):
        self._poses = deque(maxlen=length)

    def append(self, t_ms: int, pose: Pose) -> None:
        self._poses.append((t_ms, pose))

    def at(self, t_ms: int) -> Pose | None:
        """The newest recorded pose not later than ``t_ms`` (the oldest kept one if none)."""
        best = None
        for t, pose in reversed(self._poses):
            best = pose
            if t <= t_ms:
                break
        return best


def merge_duplicates(detections: Sequence[Detection], points: Sequence[Point],
                     radius_m: float) -> tuple[list[tuple[Detection, Point]], list[int]]:
    """Detections of one frame closer than ``radius_m`` on the ground are one tree seen twice (overlapping
    detector windows on one large crown): distinct trees stand at least a crown apart. Greedy, in line
    order: each detection joins the first kept one within the radius (running mean of pixel and ground
    position) or is kept. Returns ([(Detection, (x, y)), ...] kept, index into it for every detection)."""
    kept, counts, owner = [], [], []
    for det, (x, y) in zip(detections, points):
        for k, (other, (ox, oy)) in enumerate(kept):
            if math.hypot(x - ox, y - oy) < radius_m:
                n = counts[k] + 1
                kept[k] = (Detection(other.u + (det.u - other.u) / n, other.v + (det.v - other.v) / n),
                           (ox + (x - ox) / n, oy + (y - oy) / n))
                counts[k] = n
                owner.append(k)
                break
        else:
            kept.append((det, (x, y)))
            counts.append(1)
            owner.append(len(kept) - 1)
    return kept, owner
