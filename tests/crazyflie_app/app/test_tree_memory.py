"""T_d and the visited list: merging, per-frame exclusivity, visited association, bounded capacities."""
import pytest

from crazyflie_app.app.tree_memory import TreeMemory

MERGE_RADIUS = 0.45
MAV = (0.0, 0.0)


def add(memory, x, y, t=0):
    tree_id, _ = memory.add(x, y, t, 176.0, 144.0, MAV)
    return tree_id


def test_that_a_detection_within_the_merge_radius_is_the_same_tree_and_refines_it():
    sut = TreeMemory()
    tree_id = add(sut, 1.0, 0.5)
    assert sut.associate([(1.1, 0.5)], [MERGE_RADIUS]) == [("tree", tree_id)]
    sut.update(tree_id, 1.1, 0.5, 100, 170.0, 140.0)
    tree = sut.get(tree_id)
    assert tree.hits == 2 and tree.x == pytest.approx(1.05) and tree.last_ms == 100
    assert sut.associate([(1.6, 0.5)], [MERGE_RADIUS]) == [(None, None)]


def test_that_two_detections_of_one_frame_never_merge_into_one_tree():
    # a cluster: trees 0.47 m apart, the second one's estimate lands 0.40 m from the first stored tree
    sut = TreeMemory()
    first = add(sut, 2.30, 0.40)
    result = sut.associate([(2.32, 0.41), (2.70, 0.52)], [MERGE_RADIUS] * 2)
    assert result[0] == ("tree", first)
    assert result[1] == (None, None)


def test_that_a_detection_goes_to_the_nearest_of_stored_and_visited_trees():
    sut = TreeMemory()
    visited = add(sut, 2.30, 0.40)
    neighbour = add(sut, 2.74, 0.56)
    sut.mark_visited(visited, 1000, MAV)
    # 0.42 m from the visited tree, 0.05 m from its neighbour: it is the neighbour
    assert sut.associate([(2.70, 0.53)], [MERGE_RADIUS]) == [("tree", neighbour)]
    assert sut.associate([(2.31, 0.41)], [MERGE_RADIUS]) == [("visited", visited)]


def test_that_ids_stay_valid_when_another_tree_is_removed():
    # Navigation.c kept the target as an index into an array that removeCoordinate shifted
    sut = TreeMemory()
    ids = [add(sut, x, 0.0) for x in (1.0, 2.0, 3.0)]
    target = ids[2]
    sut.mark_visited(ids[0], 10, MAV)
    assert sut.get(target).x == 3.0
    assert sut.get(ids[0]) is None


def test_that_a_full_memory_evicts_the_farthest_tree_and_counts_it():
    sut = TreeMemory(capacity=3)
    near, far, middle = add(sut, 1.0, 0.0), add(sut, 9.0, 0.0), add(sut, 4.0, 0.0)
    new_id, evicted = sut.add(2.0, 0.0, 0, 176.0, 144.0, MAV)
    assert evicted == [far]
    assert set(sut.trees) == {near, middle, new_id}
    assert sut.evicted == 1 and len(sut) == 3


def test_that_the_visited_list_is_bounded_and_overflow_is_counted():
    # Navigation.c wrote past treeBlacklist[10] on the 11th visited tree
    sut = TreeMemory(capacity=64, visited_capacity=10)
    for i in range(25):
        sut.mark_visited(add(sut, 0.5 * i, 0.0), i, (0.5 * i, 0.0))
    assert len(sut.visited) == 10
    assert sut.visited_forgotten == 15
    assert min(v.x for v in sut.visited) == pytest.approx(0.5 * 15)  # the far (old) ones were forgotten


def test_that_capacities_must_be_positive():
    with pytest.raises(ValueError):
        TreeMemory(capacity=0)


DUP_RADIUS = 0.25


def test_that_a_stored_tree_drifting_onto_a_reached_tree_is_dropped_as_that_tree():
    # sweep flight 6: tree 7's estimate drifted to 0.11 m of reached tree 6 and was reached a second time
    sut = TreeMemory()
    reached = add(sut, 1.604, 0.029)
    sut.mark_visited(reached, 1000, MAV, reached=True)
    twin = add(sut, 1.496, 0.038)
    neighbour = add(sut, 1.155, 0.049)  # the next tree of the column, 0.45 m on
    assert sut.absorb_reached(DUP_RADIUS, 1100, MAV) == [(twin, reached)]
    assert sut.get(twin) is None and sut.get(neighbour) is not None and sut.absorbed == 1
    assert sut.absorb_reached(DUP_RADIUS, 1200, MAV) == []


def test_that_an_absorbed_tree_stays_as_a_visited_entry_that_takes_a_second_detection_of_the_crown():
    # issue 32, wide sweep flight 55: crowns 0.32 m apart; windows over both pulled the second one's estimate
    # 0.24 m from the reached first one: absorbed. The next frame that detected both crowns stored the second
    # one again (exclusivity), approached, absorbed... The absorbed tree now stays in the visited list at the
    # reached tree's position, not reached: that frame's second detection goes to it
    sut = TreeMemory()
    reached = add(sut, 1.419, 2.021)
    sut.mark_visited(reached, 1000, MAV, reached=True)
    pulled = add(sut, 1.60, 1.95)
    assert sut.absorb_reached(DUP_RADIUS, 1100, MAV) == [(pulled, reached)]
    entry = sut.visited[-1]
    assert (entry.id, entry.x, entry.y, entry.t_ms, entry.reached, entry.revisit) == \
        (pulled, 1.419, 2.021, 1100, False, False)
    assert sut.associate([(1.42, 2.02), (1.73, 1.90)], [MERGE_RADIUS] * 2) == [("visited", reached),
                                                                               ("visited", pulled)]
    assert not sut.near_reached(sut.visited[0], DUP_RADIUS)  # the absorbed entry is no reached tree


def test_that_a_tree_near_an_abandoned_one_is_not_absorbed_and_an_abandoned_twin_of_a_reached_tree_is_flagged():
    sut = TreeMemory()
    abandoned = add(sut, 1.265, -0.645)
    sut.mark_visited(abandoned, 1000, MAV, reached=False, revisit=True)
    near_abandoned = add(sut, 1.30, -0.60)
    assert sut.absorb_reached(DUP_RADIUS, 1100, MAV) == []  # only reached trees absorb
    entry = sut.visited[0]
    assert not sut.near_reached(entry, DUP_RADIUS)
    sut.mark_visited(near_abandoned, 2000, MAV, reached=True)  # flight m7: the same crown, reached later
    assert sut.near_reached(entry, DUP_RADIUS)
    assert not sut.near_reached(sut.visited[1], 0.01)
