"""Camera input of the navigation core: one frame's detections (their ground points, at the pose of capture)
are merged when they are one crown seen twice, associated with T_d or the visited list (within
``mergeRadius``, or ``dupRadius`` outside the planting column), and new trees admitted by the planting-column
rule of the current segment.

* A tree enters T_d when seen inside the planting column of the *current* segment (orthogonal distance
  <= ``columnFactor`` x ``crownSize``); after ``minHits`` detections the nearest such tree becomes the target t*.
* After each frame the core drops a stored tree within ``dupRadius`` of a reached tree as that tree seen
  again (event ``tree_absorbed``; tree_memory).
"""
from collections.abc import Callable, Sequence

from crazyflie_app.app.camera_geometry import Point, merge_duplicates
from crazyflie_app.app.nav_types import Counters, Detection, Event, NavigationParams
from crazyflie_app.app.path_following import PathFollower
from crazyflie_app.app.tree_memory import TreeMemory


class FrameInput:
    """Feeds T_d (``memory``) from frames; the target's own detections go back to the caller."""

    def __init__(self, params: NavigationParams, route: PathFollower, memory: TreeMemory, counters: Counters):
        self.params = params
        self.route = route  # the PathFollower: its current segment's planting column admits new trees
        self.memory = memory
        self.counters = counters

    def take(self, t_ms: int, detections: Sequence[Detection], points: Sequence[Point], mav_xy: Point,
             events: list[Event], target_id: Callable[[], int], evicted: Callable[[int, list, str], None],
             measure: Callable[[int, Detection], None]) -> list[int]:
        """Handle one frame: ``points`` the ground positions of ``detections``. ``target_id()`` is the
        current target, ``evicted(t_ms, ids, why)`` is told of trees pushed out of T_d and ``measure(t_ms,
        det)`` of each detection of the target, as they happen. Returns, per detection, the id of its tree
        (0: ignored, outside the planting column or no room in T_d)."""
        p = self.params
        merged, owner = merge_duplicates(detections, points, p.duplicate_radius_m)
        self.counters.duplicates += len(detections) - len(merged)
        merged_points = [point for _, point in merged]
        assignment = self.memory.associate(merged_points, [self.association_radius(x, y) for x, y in merged_points])
        protected = {tree_id for kind, tree_id in assignment if kind == "tree"}
        merged_ids = []
        for (det, (wx, wy)), (kind, tree_id) in zip(merged, assignment):
            tree_id, stored = self._take_detection(t_ms, det, wx, wy, kind, tree_id, protected, mav_xy, events,
                                                   evicted)
            if stored and tree_id == target_id():
                measure(t_ms, det)
            merged_ids.append(tree_id)
        self.counters.detections += len(detections)
        return [merged_ids[k] for k in owner]

    def association_radius(self, x: float, y: float) -> float:
        """How far from a stored tree a detection at (x, y) may be and still be that tree.

        Inside the planting column, ``mergeRadius``. Outside it, only ``dupRadius``: such a detection is
        either a stored tree near the column's edge, seen again a few cm off, or a tree the column rule never
        admitted. The latter must not pass for a stored neighbour: on a turn segment the next column's first
        tree (0.36 m from the target, outside the turn's column) otherwise took the target's place in every
        frame that dropped the target's own detection, and the target's filter never settled."""
        p = self.params
        if self.route.in_planting_column(x, y):
            return p.merge_radius_m
        return min(p.merge_radius_m, p.duplicate_radius_m)

    def _take_detection(self, t_ms, det, wx, wy, kind, tree_id, protected, mav_xy, events, evicted):
        """One (de-duplicated) detection -> (the id of its tree, 0: ignored; whether it is in T_d)."""
        if kind == "visited":
            self.counters.on_visited += 1
            return tree_id, False
        if kind is None:
            if not self.route.in_planting_column(wx, wy):
                self.counters.out_of_column += 1
                return 0, False
            tree_id, gone = self.memory.add(wx, wy, t_ms, det.u, det.v, mav_xy, protected)
            evicted(t_ms, gone, "T_d full")
            if not tree_id:
                return 0, False  # T_d full of trees seen in this very frame: counted in memory.unstored
            protected.add(tree_id)  # a later new tree of this frame must not evict this one
            events.append(Event("tree_added", t_ms, tree_id, wx, wy))
        else:
            self.memory.update(tree_id, wx, wy, t_ms, det.u, det.v)
        return tree_id, True
