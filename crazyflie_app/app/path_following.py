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
* Where the planting gives its row spacing (``rowSpacing``, a map's ``row_spacing_m``; 0: not given), the
  column is at most half of it wide on each side: a tree belongs to the row it stands nearest to, so rows
  closer than the paper's 1.5 crowns do not lend each other their trees.
* Re-anchoring on the trees (issue 42): the path is flown in the frame of the state estimate, which drifts
  with the Flow deck alone (0.5-1 m over a wide map), while the rows stay where they are. So each time a
  tree is reached the row line is corrected from what the camera sees at that instant: the reached tree (the
  camera is centred over it) and the trees of the column in view, all in the same estimate frame, so the
  drift so far cancels out. The path's offset across the *planned* segment moves ``anchorGain`` of the way
  to their mean distance across it (the offset along it is kept); every waypoint moves by the offset, so the flown line, the
  column rule and the segment ends follow the trees, and the offset carries on to the next rows (the drift
  is the estimate's, the same for every row). A snapshot of fewer than ``anchorMin`` trees (a gap, a lone
  tree) leaves the offset as it is; until a row has given one, the path is the waypoints. ``anchorMin`` 0
  turns it off.
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


def column_half_width(crown_size_m: float, column_factor: float = COLUMN_FACTOR, row_spacing_m: float = 0.0) -> float:
    """How far from its row line a tree may stand and be in the planting column: ``column_factor`` crowns (the
    paper: 1.5), at most half the row spacing when the planting gives it (> 0)."""
    half = column_factor * crown_size_m
    if row_spacing_m > 0.0 and row_spacing_m / 2.0 < half:
        half = row_spacing_m / 2.0
    return half


def within_column(distance_m: float, crown_size_m: float, column_factor: float = COLUMN_FACTOR,
                  row_spacing_m: float = 0.0) -> bool:
    """The planting-column rule: a tree this far from the flown line is in the column."""
    return distance_m <= column_half_width(crown_size_m, column_factor, row_spacing_m)


class PathFollower:
    """The flight path F, the waypoint being flown to, and the follow law (world velocities)."""

    def __init__(self, params: "NavigationParams", flight_path: Sequence[Point]):
        if len(flight_path) < 2:
            raise ValueError("the flight path needs at least 2 waypoints")
        self.params = params
        self.planned = tuple((float(x), float(y)) for x, y in flight_path)  # the waypoints as given
        self.offset = (0.0, 0.0)  # the re-anchoring's shift of every waypoint (m, estimate frame)
        self.path = self.planned  # the path flown: the waypoints moved by the offset
        self.waypoint_index = 0  # the waypoint being flown to
        self.progress = None  # along the current segment: where its last tree was reached (m; None: none yet)
        self.progress_ms = 0  # ... and when

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
        return max(0.0, self.half_width_m - in_view_m)

    @property
    def half_width_m(self) -> float:
        """Half the planting column's width (``column_half_width`` of the PARAMs)."""
        p = self.params
        return column_half_width(p.crown_size_m, p.column_factor, p.row_spacing_m)

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

    def advance(self) -> None:
        """On to the next waypoint; a new segment has no tree reached yet (the first waypoint's leg and the
        first segment are one row)."""
        self.waypoint_index += 1
        if self.waypoint_index >= 2:
            self.progress = None

    def along(self, x: float, y: float) -> float:
        """How far (x, y) lies along the current segment from its start (m)."""
        a, b = self.current_segment()
        dx, dy = b[0] - a[0], b[1] - a[1]
        length = math.hypot(dx, dy) or 1e-9
        return ((x - a[0]) * dx + (y - a[1]) * dy) / length

    def note_reached(self, x: float, y: float, t_ms: int) -> None:
        """A tree of the current segment was reached with the camera over (x, y) at ``t_ms``."""
        self.progress = self.along(x, y)
        self.progress_ms = t_ms

    def behind(self, x: float, y: float, first_ms: int) -> bool:
        """A tree first seen at ``first_ms`` at (x, y) lies more than ``mergeRadius`` behind the last tree reached
        on this segment and was first seen after that tree was reached: a reached tree seen again after the
        estimate drifted past ``mergeRadius`` (``mergeRadius``: a cluster neighbour may stand that close). A tree
        seen before (one the approach passed, e.g. before the first waypoint) stays a target to go back for."""
        return (self.progress is not None and first_ms > self.progress_ms
                and self.along(x, y) < self.progress - self.params.merge_radius_m)

    def _segment_index(self) -> int:
        return min(max(self.waypoint_index, 1), len(self.path) - 1)

    def current_segment(self) -> tuple[Point, Point]:
        k = self._segment_index()
        return self.path[k - 1], self.path[k]

    def in_planting_column(self, x: float, y: float) -> bool:
        a, b = self.current_segment()
        return distance_to_segment(x, y, a, b) <= self.half_width_m

    def reanchor(self, points: Sequence[Point]) -> bool:
        """Correct the row line from ``points``, the trees of the current segment's column seen at one instant
        (module docstring): the path's offset across the planned segment moves ``anchor_gain`` of the way to
        their mean distance across it. False (nothing changed) for fewer than ``anchor_min_trees`` points or a zero-length segment."""
        minimum = self.params.anchor_min_trees
        if minimum <= 0 or len(points) < minimum:
            return False
        k = self._segment_index()
        a, b = self.planned[k - 1], self.planned[k]
        dx, dy = b[0] - a[0], b[1] - a[1]
        length = math.hypot(dx, dy)
        if length == 0.0:
            return False
        nx, ny = -dy / length, dx / length
        across = 0.0
        for px, py in points:
            across += (px - a[0]) * nx + (py - a[1]) * ny
        shift = self.params.anchor_gain * (across / len(points) - (self.offset[0] * nx + self.offset[1] * ny))
        self.offset = (self.offset[0] + shift * nx, self.offset[1] + shift * ny)
        self.path = tuple((x + self.offset[0], y + self.offset[1]) for x, y in self.planned)
        return True

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
            return self.in_first_row(pose)
        a = self.path[self.waypoint_index - 1]
        dx, dy = end[0] - a[0], end[1] - a[1]
        return (pose.x - end[0]) * dx + (pose.y - end[1]) * dy >= 0.0

    def in_first_row(self, pose: "Pose") -> bool:
        """The MAV is in the first row already, past its first waypoint (inside the column, beyond the
        waypoint along the row): it took off there, or reached the row's trees on its way to it. The first
        waypoint is then passed, not flown back to: with the Flow deck alone the trees reached would have
        drifted by the time they were seen again, and were taken for new ones (issue 42)."""
        a, b = self.path[0], self.path[1]
        along = (pose.x - a[0]) * (b[0] - a[0]) + (pose.y - a[1]) * (b[1] - a[1])
        return along > 0.0 and distance_to_segment(pose.x, pose.y, a, b) <= self.half_width_m

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
