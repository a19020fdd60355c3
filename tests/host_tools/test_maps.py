"""Map files: the paper's maps load, bad files get one clear line, the format round-trips."""
import json
import subprocess
import sys

import pytest

from host_tools.errors import ForaNavError
from host_tools.maps import load_map, map_from_dict, map_to_dict, save_map, builtin_map_names

PAPER_PATH = [(0.3, 0.45), (3.9, 0.45), (3.9, -0.45), (0.3, -0.45)]


def good_map():
    return {"name": "t", "altitude_m": 1.25, "waypoints": [[0.3, 0.45], [3.9, 0.45]],
            "trees": [{"id": 1, "x": 1.0, "y": 0.45, "species": "oil_palm", "crown_m": 0.4}],
            "objects": [{"kind": "roof", "x": 2.0, "y": 1.5, "size_m": 0.5, "yaw_deg": 10}]}


@pytest.mark.parametrize("name,n_trees,n_targets", [("map1", 7, 6), ("map2", 7, 5), ("map3", 9, 9)])
def test_that_the_paper_maps_load_with_their_layouts(name, n_trees, n_targets):
    pmap = load_map(name)
    assert pmap.altitude_m == 1.25
    assert pmap.waypoints == tuple(PAPER_PATH)
    assert len(pmap.trees) == n_trees
    assert len(pmap.targets) == n_targets
    assert all(0.3 <= t.crown_m <= 0.45 for t in pmap.trees)


def test_that_target_follows_the_planting_column_rule_when_absent():
    data = good_map()
    data["trees"] += [{"id": 2, "x": 1.5, "y": 0.45 + 0.61, "species": "oil_palm", "crown_m": 0.4},  # 1.5*0.4=0.6
                      {"id": 3, "x": 2.0, "y": 0.45 + 0.59, "species": "oil_palm", "crown_m": 0.4},
                      {"id": 4, "x": 2.5, "y": 0.45, "species": "coconut", "crown_m": 0.4},
                      {"id": 5, "x": 3.0, "y": 5.0, "species": "oil_palm", "crown_m": 0.4, "target": True}]
    pmap = map_from_dict(data)
    assert [t.target for t in pmap.trees] == [True, False, True, False, True]


def test_that_a_map_round_trips_through_its_file(tmp_path):
    pmap = load_map("map2")
    save_map(pmap, tmp_path / "m.json")
    again = load_map(tmp_path / "m.json")
    assert again == pmap
    assert map_to_dict(again) == map_to_dict(pmap)


def mutate(path, value):
    data = good_map()
    target = data
    for key in path[:-1]:
        target = target[key]
    if value is KeyError:
        del target[path[-1]]
    else:
        target[path[-1]] = value
    return data


BAD = [
    (("name",), KeyError, "name: missing"),
    (("altitude_m",), "high", "altitude_m: must be a number"),
    (("altitude_m",), -1.0, "altitude_m: must be a positive number"),
    (("bogus",), 1, "bogus: unknown field"),
    (("waypoints",), [[0, 0]], "waypoints: needs at least 2 waypoints"),
    (("waypoints",), [[0, 0], [1]], "waypoints[1]: must be [x, y]"),
    (("trees", 0, "crown_m"), -0.3, "trees[0].crown_m: must be a positive number"),
    (("trees", 0, "x"), float("nan"), "trees[0].x: must be finite"),
    (("trees", 0, "species"), "banana", "trees[0].species: unknown value"),
    (("trees", 0, "id"), "one", "trees[0].id: must be an integer"),
    (("trees", 0, "height"), 3, "trees[0].height: unknown field"),
    (("trees", 0, "target"), "yes", "trees[0].target: must be true or false"),
    (("objects", 0, "kind"), "barn", "objects[0].kind: unknown value"),
    (("objects", 0, "size_m"), 0, "objects[0].size_m: must be a positive number"),
]


@pytest.mark.parametrize("path,value,message", BAD, ids=[b[2].split(":")[0] for b in BAD])
def test_that_a_bad_field_is_named_in_one_line(path, value, message):
    with pytest.raises(ForaNavError) as err:
        map_from_dict(mutate(path, value), "bad.json")
    text = str(err.value)
    assert text.startswith("bad.json: ") and message in text and "\n" not in text


def test_that_a_duplicate_tree_id_is_rejected():
    data = good_map()
    data["trees"].append(dict(data["trees"][0]))
    with pytest.raises(ForaNavError, match=r"trees\[1\]\.id: duplicate id 1"):
        map_from_dict(data, "dup.json")


def test_that_the_command_line_rejects_a_bad_map_with_one_line_and_nonzero_exit(tmp_path):
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(mutate(("trees", 0, "crown_m"), -1)))
    proc = subprocess.run([sys.executable, "-m", "host_tools.cli", "render", "--map", str(bad), "--x", "1",
                           "--y", "0", "--out", str(tmp_path / "f.png")], capture_output=True, text=True)
    assert proc.returncode != 0
    assert proc.stderr.strip().count("\n") == 0
    assert "trees[0].crown_m" in proc.stderr
    assert not (tmp_path / "f.png").exists()


def test_that_builtin_maps_are_listed():
    assert {"map1", "map2", "map3"} <= set(builtin_map_names())


def test_that_atomic_writes_leave_a_normal_file_mode(tmp_path):
    import os
    from host_tools import fileio
    old = os.umask(0o022)
    try:
        fileio.write_text(tmp_path / "a.txt", "x")
    finally:
        os.umask(old)
    assert (tmp_path / "a.txt").stat().st_mode & 0o777 == 0o644
    assert [p.name for p in tmp_path.iterdir()] == ["a.txt"]


def test_that_a_row_spacing_caps_the_target_rule_and_round_trips():
    # rows 0.8 m apart: a palm 0.45 m off the path is in the paper's 0.525 m column (crown 0.35 m), but
    # nearer the next row than half the spacing allows; the field is kept through a save
    data = {"name": "rows", "altitude_m": 1.25, "waypoints": [[0, 0], [3, 0]],
            "trees": [{"id": 1, "x": 1.0, "y": 0.45, "species": "oil_palm", "crown_m": 0.35},
                      {"id": 2, "x": 2.0, "y": 0.1, "species": "oil_palm", "crown_m": 0.35}]}
    plain = map_from_dict(dict(data))
    spaced = map_from_dict(dict(data, row_spacing_m=0.8))
    assert [t.target for t in plain.trees] == [True, True]
    assert [t.target for t in spaced.trees] == [False, True]
    assert map_to_dict(spaced)["row_spacing_m"] == 0.8 and "row_spacing_m" not in map_to_dict(plain)
    with pytest.raises(ForaNavError, match="row_spacing_m"):
        map_from_dict(dict(data, row_spacing_m=-1))
