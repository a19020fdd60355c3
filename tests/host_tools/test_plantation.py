"""Random plantations: reproducible, every feature drawn, never an oil palm where the column rule is ambiguous."""
import json

import pytest

from host_tools import cli
from host_tools.maps import COLUMN_RULE_FACTOR, distance_to_path, load_map
from host_tools.plantation import AMBIGUITY_MARGIN_M, APP_CROWN_M, PlantationRanges, generate

SEEDS = range(150)
FEATURES = ("clusters", "gaps", "lookalikes_in_column", "lookalikes_beside", "off_column_palms", "roofs",
            "road_crossings")


def test_that_the_same_seed_gives_the_same_map_bytes_and_another_seed_another_map(tmp_path, capsys):
    # Test
    paths = [tmp_path / name for name in ("a.json", "b.json", "c.json")]
    for path, seed in zip(paths, (5, 5, 6)):
        assert cli.main(["plantation", "--seed", str(seed), "--out", str(path)]) == 0
    # Assert
    assert paths[0].read_bytes() == paths[1].read_bytes()
    assert paths[0].read_bytes() != paths[2].read_bytes()
    assert load_map(str(paths[0])).targets  # a valid map with targets


@pytest.mark.parametrize("seed", SEEDS)
def test_that_no_oil_palm_stands_where_the_column_rule_is_ambiguous(seed):
    pmap, _ = generate(seed)
    for tree in pmap.trees:
        if tree.species != "oil_palm":
            assert not tree.target
            continue
        distance = distance_to_path(tree.x, tree.y, pmap.waypoints)
        rules = (COLUMN_RULE_FACTOR * tree.crown_m, COLUMN_RULE_FACTOR * APP_CROWN_M)
        if tree.target:
            assert distance <= min(rules) - AMBIGUITY_MARGIN_M + 1e-3
        else:
            assert distance >= max(rules) + AMBIGUITY_MARGIN_M - 1e-3


def test_that_the_loader_derives_the_same_targets_as_the_generator(tmp_path):
    for seed in range(20):
        path = tmp_path / ("p%d.json" % seed)
        assert cli.main(["plantation", "--seed", str(seed), "--out", str(path)]) == 0
        data = json.loads(path.read_text())
        for tree in data["trees"]:
            del tree["target"]  # let the loader apply the column rule itself
        path.write_text(json.dumps(data))
        pmap, _ = generate(seed)
        assert [t.id for t in load_map(str(path)).targets] == [t.id for t in pmap.targets]


def test_that_every_feature_is_drawn_within_its_range_over_many_seeds():
    ranges = PlantationRanges()
    seen = {name: 0 for name in FEATURES}
    columns, altitudes = set(), []
    for seed in SEEDS:
        pmap, factors = generate(seed, ranges)
        for name in FEATURES:
            seen[name] += factors[name] > 0
        columns.add(factors["columns"])
        altitudes.append(pmap.altitude_m)
        assert len(pmap.waypoints) == 2 * factors["columns"]
        assert sum(t.target for t in pmap.trees) == factors["targets"] > 0
        kinds = [o.kind for o in pmap.objects]
        assert kinds.count("roof") == factors["roofs"] and kinds.count("road_cross") == factors["road_crossings"]
    assert all(count > 0 for count in seen.values()), seen
    assert columns == set(range(ranges.columns[0], ranges.columns[1] + 1))
    assert ranges.altitude_m[0] <= min(altitudes) and max(altitudes) <= ranges.altitude_m[1]


def test_that_range_options_bound_the_draw(tmp_path):
    path = tmp_path / "p.json"
    assert cli.main(["plantation", "--seed", "3", "--columns", "3", "--altitude-m", "1.1", "--off-column-palms",
                     "2:2", "--out", str(path)]) == 0
    pmap = load_map(str(path))
    assert len(pmap.waypoints) == 6 and pmap.altitude_m == 1.1
    assert sum(1 for t in pmap.trees if t.species == "oil_palm" and not t.target) == 2


def test_that_a_range_that_would_make_the_rule_ambiguous_fails_in_one_line(tmp_path, capsys):
    path = tmp_path / "never.json"
    assert cli.main(["plantation", "--seed", "1", "--lateral-jitter-m", "0:0.4", "--out", str(path)]) == 2
    assert cli.main(["plantation", "--seed", "1", "--columns", "2", "--column-spacing-m", "0.6",
                     "--out", str(path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 2 and "--lateral-jitter-m" in err[0] and "--column-spacing-m" in err[1]
    assert not path.exists()


def test_that_rounding_the_written_map_never_brings_an_off_column_palm_inside_the_margin():
    # seed 630509346 drew an off-column palm 0.6975 m from the path that the map's mm rounding put at 0.697
    pmap, factors = generate(630509346)
    assert factors["off_column_palms"] == 2
    for tree in pmap.trees:
        if tree.species == "oil_palm" and not tree.target:
            rules = (COLUMN_RULE_FACTOR * tree.crown_m, COLUMN_RULE_FACTOR * APP_CROWN_M)
            assert distance_to_path(tree.x, tree.y, pmap.waypoints) >= max(rules) + AMBIGUITY_MARGIN_M
