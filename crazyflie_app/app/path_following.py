"""Path following of the navigation core, and the planting-column geometry (the one definition: the host's map
tools import it too, so a map's target trees and the app's T_d agree).

* FOLLOW_PATH flies the path F (waypoints) at ``cruiseSpeed`` with a carrot ``lookahead`` ahead of the
  MAV's projection on the current segment, which also pulls it back onto the line. A waypoint is passed
  within ``wpTolerance`` of the segment's end or once the MAV is past that end (a gust must not make it
  circle back for a 3 cm ball).
* A tree is in the planting column of a segment when its distance to it is at most ``columnFactor`` x
  ``crownSize`` (the paper: 1.5 crown sizes), so the column reaches that far beyond the segment's end
  waypoint too. The camera sees a crown whole only up to ``frame half-height x height / focal - crownSize / 2``
  ahead (0.27 m at 1 m; the module and the oracle report whole crowns only), less than the column's reach at
  low flights: a palm 0.2 m beyond the last waypoint was never in view before the app landed (issue 32).
  So a segment ends ``end_reach_m`` beyond its end waypoint, where the rest of the column comes into whole
  view (0.25 m at 1 m, 0.14 m at 1.25 m, none from 1.6 m); the next segment starts at the waypoint.
"""
import math
from collections.abc import Sequence

from crazyflie_app.app.nav_types import COLUMN_FACTOR, NavigationParams, Pose

Point = tuple[float, float]  # (x, y), m


def distance_to_segment(px: float, py: float, a: Point, b: Point) -> float:
    """Horizontal distance from point (px, py) to the segment a-b (metres)."""
    dx, dy = b[0] - a[0], b[1] - a[1]
    length2 = dx * dx + dy * dy
    t = 0.0 if length2 == 0 else max(0.0, min(1.0, ((px - a[0]) * dx + (py - a[1]) * dy) / length2))
    return math.hypot(px - a[0] - t * dx, py - a[1] - t * dy)


def within_column(distance_m: float, crown_size_m: float, column_factor: float = COLUMN_FACTOR) -> bool:
    """The planting-column rule: a tree this far from the flown line is in the column."""
    return distance_m <= column_factor * crown_size_m


class PathFollower:
    """The flight path F, the waypoint being flown to, and the follow law (world velocities)."""

    def __init__(self, params: "NavigationParams", flight_path: Sequence[Point]):
        if len(flight_path) < 2:
            raise ValueError("the flight path needs at least 2 waypoints")
        self.params = params
        self.path = tuple((float(x), float(y)) for x, y in flight_path)
        self.waypoint_index = 0  # the waypoint being flown to

    @property
    def finished(self) -> bool:
        return self.waypoint_index >= len(self.path)

    @property
    def goal(self) -> Point:
        return self.path[self.waypoint_index]

    @property
    def end_reach_m(self) -> float:
        """How far beyond its end waypoint a segment is flown: until every crown of the planting column beyond
        the waypoint has been in whole view (module docstring)."""
        p = self.params
        in_view_m = p.cam_height_px / 2.0 * p.altitude_m / p.focal_px - p.crown_size_m / 2.0
        return max(0.0, p.column_factor * p.crown_size_m - in_view_m)

    def segment_end(self) -> Point:
        """Where the segment to the waypoint being flown to ends: ``end_reach_m`` beyond the waypoint (the first
        waypoint, flown to straight from the take-off point, ends at itself)."""
        goal = self.path[self.waypoint_index]
        if self.waypoint_index == 0:
            return goal
        a = self.path[self.waypoint_index - 1]
        dx, dy = goal[0] - a[0], goal[1] - a[1]
        length = math.hypot(dx, dy)
        if length == 0.0:
            return goal
        reach = self.end_reach_m
        return goal[0] + dx / length * reach, goal[1] + dy / length * reach

    def current_segment(self) -> tuple[Point, Point]:
        k = max(self.waypoint_index, 1)
        k = min(k, len(self.path) - 1)
        return self.path[k - 1], self.path[k]

    def in_planting_column(self, x: float, y: float) -> bool:
        a, b = self.current_segment()
        return within_column(distance_to_segment(x, y, a, b), self.params.crown_size_m, self.params.column_factor)

    def cross_track(self, pose: "Pose") -> float:
        """Distance of the MAV from the current segment (as flown: up to its end beyond the waypoint)."""
        a, b = self.current_segment()
        if 0 < self.waypoint_index < len(self.path):
            b = self.segment_end()
        return distance_to_segment(pose.x, pose.y, a, b)

    def waypoint_reached(self, pose: "Pose") -> bool:
        """Within ``waypoint_tolerance_m`` of the segment's end, or past it (a gust can carry the MAV past a
        3 cm ball; it must not then circle back for it)."""
        end = self.segment_end()
        if math.hypot(end[0] - pose.x, end[1] - pose.y) < self.params.waypoint_tolerance_m:
            return True
        if self.waypoint_index == 0:
            return False
        a = self.path[self.waypoint_index - 1]
        dx, dy = end[0] - a[0], end[1] - a[1]
        return (pose.x - end[0]) * dx + (pose.y - end[1]) * dy >= 0.0

    def follow_velocity(self, pose: "Pose", goal: Point) -> tuple[float, float]:
        """World velocity: towards a carrot on the current segment, up to its end beyond the waypoint ``goal``
        (or straight to the first waypoint)."""
        p = self.params
        end = goal
        if self.waypoint_index == 0:
            carrot = goal
        else:
            a, end = self.path[self.waypoint_index - 1], self.segment_end()
            dx, dy = end[0] - a[0], end[1] - a[1]
            length = math.hypot(dx, dy) or 1e-9
            along = ((pose.x - a[0]) * dx + (pose.y - a[1]) * dy) / length
            s = min(max(along, 0.0) + p.lookahead_m, length) / length
            carrot = (a[0] + s * dx, a[1] + s * dy)
        ex, ey = carrot[0] - pose.x, carrot[1] - pose.y
        distance = math.hypot(ex, ey)
        if distance < 1e-9:
            return 0.0, 0.0
        to_goal = math.hypot(end[0] - pose.x, end[1] - pose.y)
        speed = min(p.cruise_speed, max(p.arrival_min_speed, to_goal))
        return ex / distance * speed, ey / distance * speed
