"""The downward JeVois camera: a nadir pinhole posed by the MAV's (x, y, z, yaw).

Conventions (docs/DESIGN.md): world x forward, y left, z up, yaw counter-clockwise in degrees. Image up (smaller
v) is body forward, image left (smaller u) is body left. Pixel coordinates are continuous: (0, 0) is the top-left
corner of the top-left pixel and the principal point is (W/2, H/2). Ground scale: 0.0031 m per pixel per metre
of height at 352x288, i.e. f = 322.58 px at 352 px width, scaled with the width for other sensor modes.
"""
import math
from typing import NamedTuple

import numpy as np

Coordinate = float | np.ndarray  # a scalar, or an array of them (vectorised)

METRES_PER_PIXEL_PER_METRE_AT_352 = 0.0031  # the paper's flight code
REFERENCE_WIDTH = 352
FOCAL_PX_AT_352 = 1.0 / METRES_PER_PIXEL_PER_METRE_AT_352  # 322.58 px
MOUNT_OFFSET_RANGE_M = (-1.0, 1.0)  # a camera on a MAV sits within a metre of its centre
HEIGHT_RANGE_M = (0.05, 100.0)  # camera above the ground: below, no crown fits; above, a tree is a pixel
SENSOR_MODES = ((352, 288), (640, 480), (1280, 1024), (320, 240))  # JeVois-A33 (OV9653); first = default


class Pose(NamedTuple):
    """MAV pose: position in the world frame (metres), yaw (degrees, counter-clockwise from +x) and the body's
    tilt: roll (degrees, right-handed about body x: positive rolls the left side up) and pitch (degrees, the
    Crazyflie's stateEstimate sign: positive is nose up). Roll and pitch zero: the nadir camera of the paper."""
    x: float
    y: float
    z: float
    yaw_deg: float = 0.0
    roll_deg: float = 0.0
    pitch_deg: float = 0.0

    @property
    def tilted(self) -> bool:
        return self.roll_deg != 0.0 or self.pitch_deg != 0.0


def sensor_mode(text: str) -> tuple[int, int]:
    """'352x288' -> (352, 288); one of SENSOR_MODES."""
    try:
        width, height = (int(v) for v in str(text).lower().split("x"))
    except ValueError:
        width = height = None
    if (width, height) not in SENSOR_MODES:
        raise ValueError("unknown sensor mode %r (expected one of %s)"
                         % (text, ", ".join("%dx%d" % m for m in SENSOR_MODES)))
    return width, height


class CameraModel:
    """Pinhole nadir camera of the JeVois-A33 mounted under the MAV.

    ``mount_offset`` is the camera's position relative to the MAV's estimated position in the body frame
    (forward, left) metres; the camera's ground point is MAV + R(yaw) * mount_offset.
    """

    def __init__(self, width: int = 352, height: int = 288, mount_offset: tuple[float, float] = (0.0, 0.0)):
        if (width, height) not in SENSOR_MODES:
            raise ValueError("unknown sensor mode %dx%d" % (width, height))
        self.width = int(width)
        self.height = int(height)
        if len(mount_offset) != 2 or not all(math.isfinite(float(v)) and MOUNT_OFFSET_RANGE_M[0] <= float(v)
                                             <= MOUNT_OFFSET_RANGE_M[1] for v in mount_offset):
            raise ValueError("mount_offset must be two numbers (forward, left) in [%g, %g] m, got %r"
                             % (MOUNT_OFFSET_RANGE_M + (list(mount_offset),)))
        self.mount_offset = (float(mount_offset[0]), float(mount_offset[1]))
        self.focal_px = FOCAL_PX_AT_352 * self.width / REFERENCE_WIDTH

    def __repr__(self) -> str:
        return "CameraModel(width=%d, height=%d, mount_offset=%r)" % (self.width, self.height, self.mount_offset)

    def to_dict(self) -> dict:
        return {"width": self.width, "height": self.height, "focal_px": self.focal_px,
                "mount_offset": list(self.mount_offset)}

    @classmethod
    def from_dict(cls, data: dict) -> "CameraModel":
        return cls(int(data["width"]), int(data["height"]), tuple(data.get("mount_offset", (0.0, 0.0))))

    def metres_per_pixel(self, z: float) -> float:
        """Ground size of one pixel (metres) seen from height z (metres)."""
        return z / self.focal_px

    def ground_point(self, pose: Pose) -> tuple[float, float]:
        """World (x, y) of the camera's nadir: MAV position + R(yaw) * mount offset."""
        c, s = _cos_sin(pose.yaw_deg)
        fwd, left = self.mount_offset
        return pose.x + c * fwd - s * left, pose.y + s * fwd + c * left

    def pixel_to_world(self, pose: Pose, u: Coordinate, v: Coordinate) -> tuple[Coordinate, Coordinate]:
        """Ground point (x, y) seen at pixel (u, v); works on scalars and numpy arrays."""
        scale = pose.z / self.focal_px
        forward = (self.height / 2.0 - np.asarray(v, dtype=float)) * scale
        left = (self.width / 2.0 - np.asarray(u, dtype=float)) * scale
        c, s = _cos_sin(pose.yaw_deg)
        gx, gy = self.ground_point(pose)
        return _scalar(gx + c * forward - s * left), _scalar(gy + s * forward + c * left)

    def world_to_pixel(self, pose: Pose, x: Coordinate, y: Coordinate) -> tuple[Coordinate, Coordinate]:
        """Pixel (u, v) of the ground point (x, y); works on scalars and numpy arrays."""
        if pose.tilted:
            to_pixel = np.linalg.inv(self.pixel_to_world_homography(pose))
            xs, ys = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
            h = to_pixel @ np.stack([xs.ravel(), ys.ravel(), np.ones(xs.size)])
            return _scalar((h[0] / h[2]).reshape(xs.shape)), _scalar((h[1] / h[2]).reshape(xs.shape))
        gx, gy = self.ground_point(pose)
        dx = np.asarray(x, dtype=float) - gx
        dy = np.asarray(y, dtype=float) - gy
        c, s = _cos_sin(pose.yaw_deg)
        forward = c * dx + s * dy
        left = -s * dx + c * dy
        scale = self.focal_px / pose.z
        return _scalar(self.width / 2.0 - left * scale), _scalar(self.height / 2.0 - forward * scale)

    def pixel_to_world_affine(self, pose: Pose) -> np.ndarray:
        """2x3 matrix A with [x, y] = A @ [u, v, 1] (continuous pixel coordinates)."""
        scale = pose.z / self.focal_px
        c, s = _cos_sin(pose.yaw_deg)
        gx, gy = self.ground_point(pose)
        # forward = (H/2 - v) * scale, left = (W/2 - u) * scale
        # x = gx + c*forward - s*left ; y = gy + s*forward + c*left
        hw, hh = self.width / 2.0, self.height / 2.0
        return np.array([
            [s * scale, -c * scale, gx + c * hh * scale - s * hw * scale],
            [-c * scale, -s * scale, gy + s * hh * scale + c * hw * scale],
        ])


    def pixel_to_world_homography(self, pose: Pose) -> np.ndarray:
        """3x3 matrix H with [x, y, 1] ~ H @ [u, v, 1]: the ground plane seen by the camera tilted with the body.

        The ray of pixel (u, v) in the body frame (forward, left, up) is ((H/2 - v) / f, (W/2 - u) / f, -1);
        the body's rotation R = Rz(yaw) Ry(-pitch) Rx(roll) (pitch in the stateEstimate sign) turns it into
        the world, and it meets the ground z = 0 from the camera at height z over its ground point (the mount
        offset turns with yaw only: millimetres at these tilts). With roll = pitch = 0 this is
        ``pixel_to_world_affine`` exactly.
        """
        f = self.focal_px
        to_ray = np.array([[0.0, -1.0 / f, self.height / 2.0 / f],
                           [-1.0 / f, 0.0, self.width / 2.0 / f],
                           [0.0, 0.0, -1.0]])
        gx, gy = self.ground_point(pose)
        to_ground = np.array([[pose.z, 0.0, -gx], [0.0, pose.z, -gy], [0.0, 0.0, -1.0]])
        return to_ground @ body_rotation(pose) @ to_ray


def body_rotation(pose: Pose) -> np.ndarray:
    """Body (forward, left, up) -> world rotation Rz(yaw) Ry(-pitch) Rx(roll); see Pose for the signs."""
    cy, sy = _cos_sin(pose.yaw_deg)
    cp, sp = _cos_sin(-pose.pitch_deg)
    cr, sr = _cos_sin(pose.roll_deg)
    rz = np.array([[cy, -sy, 0.0], [sy, cy, 0.0], [0.0, 0.0, 1.0]])
    ry = np.array([[cp, 0.0, sp], [0.0, 1.0, 0.0], [-sp, 0.0, cp]])
    rx = np.array([[1.0, 0.0, 0.0], [0.0, cr, -sr], [0.0, sr, cr]])
    return rz @ ry @ rx


def _cos_sin(yaw_deg: float) -> tuple[float, float]:
    rad = math.radians(yaw_deg)
    return math.cos(rad), math.sin(rad)


def _scalar(value: Coordinate) -> Coordinate:
    return float(value) if np.ndim(value) == 0 else value
