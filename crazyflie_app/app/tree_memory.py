"""The detected-tree memory T_d and the visited list (paper Algorithm 1), bounded and without index hazards.

Trees are keyed by a stable integer id, never by their position in a list, so removing one tree cannot
make a stored target index point at another (the C app kept ``KalmantreeNum`` as an index into an array
that ``removeCoordinate`` shifted). Both collections are bounded, and overflow is never silent:

* T_d holds at most ``capacity`` trees; a new tree when full evicts the stored tree farthest from the MAV
  (the least useful one) and counts it in ``evicted``, except the trees a detection of the same camera frame
  was associated with (``protected``: evicting one would leave that detection pointing at nothing). When
  every stored tree is protected, the new tree is not stored and counted in ``unstored``;
* the visited list holds at most ``visited_capacity`` entries; when full the entry farthest from the MAV is
  forgotten and counted in ``visited_forgotten`` (the C app wrote past the end of ``treeBlacklist[10]``).

Association is nearest-neighbour with exclusivity per camera frame: each detection of a frame goes to the
nearest stored *or visited* tree within its radius (the caller's choice per detection: frame_input), and no
two detections of one frame go to the same tree (two trees seen together are two trees, even 0.47 m apart in
a cluster). One crown seen twice in one
frame (two detector windows closer than ``app.dupRadius``) is merged by the core before association
(``camera_geometry.merge_duplicates``).

A stored tree whose position comes within ``app.dupRadius`` of a tree already reached is that tree, seen
again from a drifted estimate (flow) or through an off-centre window on a crown cut by the frame edge: it
is dropped from T_d (``absorb_reached``, counted in ``absorbed``) instead of being approached and reached a
second time, and an abandoned tree within that distance of a reached one is not gone back for. The dropped
tree stays in the visited list, not reached, at the reached tree's position: a frame that detects the crown
and its second window (or a neighbour taken for it) sends the second detection there instead of storing it
again. Without that entry a crown touching a reached one, whose estimate windows over both crowns had pulled
within ``app.dupRadius``, was dropped while approached, stored again at the next frame that saw both,
approached, dropped... until the 900 s limit (issue 32).
"""
import math
from collections.abc import Collection, Iterable, Sequence
from dataclasses import dataclass
from typing import Any

Point = tuple[float, float]  # (x, y), m

POSITION_AVERAGE_WINDOW = 20  # detections: the stored position is a running mean over about this many


@dataclass
class StoredTree:
    id: int
    x: float  # estimated world position s_t (m)
    y: float
    hits: int
    first_ms: int
    last_ms: int
    u: float  # last measured image position (px)
    v: float


@dataclass
class VisitedTree:
    id: int
    x: float
    y: float
    t_ms: int
    reached: bool  # False: abandoned after a failed recovery
    revisit: bool = False  # abandoned while unseen (hidden): the app goes back for it once before landing


class TreeMemory:
    def __init__(self, capacity: int = 32, visited_capacity: int = 64):
        if capacity < 1 or visited_capacity < 1:
            raise ValueError("tree memory capacities must be >= 1")
        self.capacity = int(capacity)
        self.visited_capacity = int(visited_capacity)
        self.trees = {}  # id -> StoredTree, in insertion order
        self.visited = []  # VisitedTree, oldest first
        self.evicted = 0
        self.unstored = 0  # new trees not stored: T_d full of trees seen in the same frame
        self.visited_forgotten = 0
        self.absorbed = 0  # stored trees dropped as a reached tree seen again
        self._next_id = 1

    def __len__(self) -> int:
        return len(self.trees)

    def get(self, tree_id: int) -> StoredTree | None:
        return self.trees.get(tree_id)

    def associate(self, points: Sequence[Point], radii: Sequence[float]) -> list[tuple[str | None, int | None]]:
        """For each world point (x, y) of one frame: ('tree', id), ('visited', id) or (None, None); point i
        goes only to a tree within ``radii[i]`` of it."""
        pairs = []
        for i, ((px, py), merge_radius) in enumerate(zip(points, radii)):
            for t in self.trees.values():
                d = math.hypot(px - t.x, py - t.y)
                if d <= merge_radius:
                    pairs.append((d, i, "tree", t.id))
            for k, t in enumerate(self.visited):
                d = math.hypot(px - t.x, py - t.y)
                if d <= merge_radius:
                    pairs.append((d, i, "visited", -1 - k))
        pairs.sort(key=lambda p: (p[0], p[1]))
        result = [(None, None)] * len(points)
        taken = set()
        for d, i, kind, key in pairs:
            if result[i][0] is None and (kind, key) not in taken:
                taken.add((kind, key))
                result[i] = (kind, key if kind == "tree" else self.visited[-1 - key].id)
        return result

    def add(self, x: float, y: float, t_ms: int, u: float, v: float, mav_xy: Point,
            protected: Collection[int] = ()) -> tuple[int, list[int]]:
        """Store a new tree; returns (new id, [ids evicted to make room]), or (0, []) when T_d is full of
        ``protected`` trees (ids that must stay: detections of this frame refer to them)."""
        evicted = []
        while len(self.trees) >= self.capacity:
            candidates = [t for t in self.trees.values() if t.id not in protected]
            if not candidates:
                self.unstored += 1
                return 0, evicted
            evicted.append(self._farthest(candidates, mav_xy).id)
            del self.trees[evicted[-1]]
            self.evicted += 1
        tree = StoredTree(self._next_id, x, y, 1, t_ms, t_ms, u, v)
        self._next_id += 1
        self.trees[tree.id] = tree
        return tree.id, evicted

    def evict_to_capacity(self, mav_xy: Point) -> list[int]:
        """After ``capacity`` was lowered (a PARAM set in flight): evict the farthest trees until T_d fits;
        returns their ids."""
        evicted = []
        while len(self.trees) > self.capacity:
            evicted.append(self._farthest(self.trees.values(), mav_xy).id)
            del self.trees[evicted[-1]]
            self.evicted += 1
        return evicted

    def update(self, tree_id: int, x: float, y: float, t_ms: int, u: float, v: float) -> None:
        """Merge one more detection into a stored tree (running mean of its position)."""
        t = self.trees[tree_id]
        t.hits += 1
        weight = 1.0 / min(t.hits, POSITION_AVERAGE_WINDOW)
        t.x += weight * (x - t.x)
        t.y += weight * (y - t.y)
        t.last_ms, t.u, t.v = t_ms, u, v

    def absorb_reached(self, radius: float, t_ms: int, mav_xy: Point) -> list[tuple[int, int]]:
        """Drop every stored tree within ``radius`` of a reached visited entry (the same tree seen again) into
        the visited list, not reached, at that entry's position (module docstring); returns [(dropped id,
        reached id)]."""
        dropped = []
        for t in list(self.trees.values()):
            twin = next((e for e in self.visited if e.reached and math.hypot(t.x - e.x, t.y - e.y) <= radius),
                        None)
            if twin is not None:
                del self.trees[t.id]
                self.absorbed += 1
                self._append_visited(VisitedTree(t.id, twin.x, twin.y, t_ms, reached=False), mav_xy)
                dropped.append((t.id, twin.id))
        return dropped

    def near_reached(self, entry: VisitedTree, radius: float) -> bool:
        """True when a reached visited entry lies within ``radius`` of ``entry`` (x, y)."""
        return any(e.reached and e is not entry and math.hypot(entry.x - e.x, entry.y - e.y) <= radius
                   for e in self.visited)

    def mark_visited(self, tree_id: int, t_ms: int, mav_xy: Point, reached: bool = True,
                     revisit: bool = False) -> StoredTree:
        """Move a tree from T_d to the visited list (reached, or abandoned when reached is False; ``revisit``
        flags an abandoned tree worth going back for once)."""
        t = self.trees.pop(tree_id)
        self._append_visited(VisitedTree(t.id, t.x, t.y, t_ms, reached, revisit), mav_xy)
        return t

    def _append_visited(self, entry: VisitedTree, mav_xy: Point) -> None:
        """Append to the visited list; a full list forgets its entry farthest from the MAV first."""
        while len(self.visited) >= self.visited_capacity:
            self.visited.remove(self._farthest(self.visited, mav_xy))
            self.visited_forgotten += 1
        self.visited.append(entry)

    def restore(self, tree_id: int, hits: int, u: float, v: float,
                mav_xy: Point) -> tuple[StoredTree | None, list[int]]:
        """Move a visited entry back into T_d (same id and position, ``hits`` detections, last seen when it
        was visited, image position (u, v)) so it can be a target again. A full T_d evicts its farthest tree
        first, as ``add`` does. Returns (StoredTree or None if ``tree_id`` is not visited, [ids evicted])."""
        entry = next((e for e in self.visited if e.id == tree_id), None)
        if entry is None:
            return None, []
        self.visited.remove(entry)
        evicted = []
        while len(self.trees) >= self.capacity:
            evicted.append(self._farthest(self.trees.values(), mav_xy).id)
            del self.trees[evicted[-1]]
            self.evicted += 1
        tree = StoredTree(entry.id, entry.x, entry.y, hits, entry.t_ms, entry.t_ms, u, v)
        self.trees[tree.id] = tree
        return tree, evicted

    @staticmethod
    def _farthest(items: Iterable, mav_xy: Point) -> Any:
        mx, my = mav_xy
        return max(items, key=lambda t: (math.hypot(t.x - mx, t.y - my), -t.id))
