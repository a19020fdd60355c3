"""Recovery of the navigation core (insect view memory) and going back once for hidden trees.

* RECOVERY: when the MAV is farther than ``recoveryDistance`` (delta) from the stored s_t, or the target has
  not been seen for ``lostTimeoutMs``, the MAV re-approaches s_t by position until a detection associates
  with the target again, then visual guidance resumes; after ``recoveryTimeoutMs`` the tree is abandoned (it
  goes to the visited list, flagged not reached) so the mission goes on. A target not reached
  ``targetTimeoutMs`` after its selection is abandoned too.
* Going back once: a tree abandoned because recovery timed out without seeing it again (it was hidden) is
  flagged in the visited list. At the last waypoint, before landing, the app goes back to each flagged
  tree in turn (nearest first): the entry is restored into T_d as the target and approached by memory
  (RECOVERY, whose timeouts start only once the MAV is within ``returnTolerance`` of s_t), then visually.
  Reached or abandoned again, it is never flagged again; when no flagged tree is left, LAND. A flagged tree
  within ``dupRadius`` of a reached one was that tree (tree_memory) and is not gone back for.
"""
import math
from collections.abc import Iterable
from typing import Any

from crazyflie_app.app.camera_geometry import unrotate
from crazyflie_app.app.nav_types import Event, NavigationParams, Pose
from crazyflie_app.app.tree_memory import StoredTree, TreeMemory

ABANDON, ABANDON_UNSEEN = "abandon", "abandon_unseen"


def nearest(items: Iterable[Any], point: tuple[float, float]) -> Any:
    """The item (tree or visited entry, with x, y, id) nearest to ``point`` (ties: lowest id)."""
    cx, cy = point
    return min(items, key=lambda t: (math.hypot(t.x - cx, t.y - cy), t.id))


class Recovery:
    """The target and recovery clocks and the going-back state."""

    def __init__(self, params: NavigationParams):
        self.params = params
        self.target_since = 0  # target selected (or, going back, the MAV arrived over s_t)
        self.since = None  # recovery began
        self.revisiting = False  # flying back, before landing, to a tree abandoned while hidden
        self.revisit_arrived = False  # ... and over its stored s_t once

    def reason(self, t_ms: int, tree: StoredTree, e_d: float) -> str:
        """Why the recovery began (its event's detail)."""
        return "e_d %.2f m" % e_d if e_d > self.params.recovery_distance_m else "not seen %d ms" % (
            t_ms - tree.last_ms)

    def target_expired(self, t_ms: int) -> bool:
        return t_ms - self.target_since > self.params.target_timeout_ms

    def step(self, t_ms: int, pose: Pose, tree: StoredTree,
             ground_point: tuple[float, float]) -> str | tuple[float, float]:
        """One RECOVERY tick towards s_t of ``tree`` (None: gone): ABANDON, ABANDON_UNSEEN (recovery timed
        out without seeing it again) or the body velocity (vx, vy)."""
        p = self.params
        cx, cy = ground_point
        ex, ey = (tree.x - cx, tree.y - cy) if tree is not None else (0.0, 0.0)
        distance = math.hypot(ex, ey)
        if self.revisiting and not self.revisit_arrived and tree is not None:
            # going back: the recovery and target clocks start once the MAV is over s_t
            self.revisit_arrived = distance <= p.return_tolerance_m
            self.since = self.target_since = t_ms
        if tree is None or self.target_expired(t_ms):
            return ABANDON
        if t_ms - self.since > p.recovery_timeout_ms:
            return ABANDON_UNSEEN
        speed = min(p.recovery_speed, p.servo_gain * distance)
        if distance < 1e-9:
            return 0.0, 0.0
        return unrotate(pose.yaw_deg, ex / distance * speed, ey / distance * speed)

    def start_revisit(self, t_ms: int, memory: TreeMemory, ground_point: tuple[float, float],
                      mav_xy: tuple[float, float], centre: tuple[float, float],
                      events: list[Event]) -> StoredTree | None:
        """Going back once: restore the flagged tree nearest to ``ground_point`` into T_d (``memory``) as the
        target, at the principal point ``centre``. Returns it, or None if no tree is flagged."""
        flagged = [e for e in memory.visited
                   if e.revisit and not memory.near_reached(e, self.params.duplicate_radius_m)]
        if not flagged:
            return None
        entry = nearest(flagged, ground_point)
        tree, evicted = memory.restore(entry.id, self.params.min_hits, centre[0], centre[1], mav_xy)
        for gone in evicted:
            events.append(Event("tree_evicted", t_ms, gone, detail="T_d full"))
        self.revisiting, self.revisit_arrived = True, False
        self.target_since = t_ms
        events.append(Event("revisit", t_ms, tree.id, tree.x, tree.y, detail="abandoned while hidden"))
        return tree
