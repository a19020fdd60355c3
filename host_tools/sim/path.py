"""Flying the path F: MAV poses at constant speed and altitude along the waypoints (a pure function)."""
import math
from collections.abc import Sequence

from host_tools.sim.camera import Pose


def path_length(waypoints: Sequence[tuple[float, float]]) -> float:
    return sum(math.dist(a, b) for a, b in zip(waypoints[:-1], waypoints[1:]))


def point_at(waypoints: Sequence[tuple[float, float]], distance: float) -> tuple[float, float]:
    """(x, y) at a distance along the polyline (clamped to its ends)."""
    remaining = max(0.0, distance)
    for a, b in zip(waypoints[:-1], waypoints[1:]):
        seg = math.dist(a, b)
        if remaining <= seg and seg > 0:
            t = remaining / seg
            return a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])
        remaining -= seg
    return tuple(waypoints[-1])


def poses_along_path(waypoints: Sequence[tuple[float, float]], speed: float, fps: float, altitude: float,
                     yaw_deg: float = 0.0, duration_s: float | None = None,
                     start_m: float = 0.0) -> list[tuple[float, Pose]]:
    """[(t_s, Pose)] sampled at fps while flying from start_m along the path at speed (m/s), ends included."""
    length = path_length(waypoints) - start_m
    total = length / speed
    if duration_s is not None:
        total = min(total, duration_s)
    count = int(math.floor(total * fps + 1e-9)) + 1
    out = []
    for i in range(count):
        t = i / fps
        x, y = point_at(waypoints, start_m + speed * t)
        out.append((t, Pose(x, y, altitude, yaw_deg)))
    return out
