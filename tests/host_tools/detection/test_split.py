"""foranav split: by image, by group (name prefix or a tiles.csv's regions), and the tile-overlap guard."""
from pathlib import Path

from host_tools import annotations, cli


def _source(folder: Path, images: list[str], tiles: list[tuple] | None = None) -> Path:
    folder.mkdir(parents=True)
    annotations.write_boxes(folder / "boxes.csv", [annotations.Box(im, 50, 50, 20, 20, "oil_palm") for im in images])
    if tiles is not None:
        rows = ["image,region,tile_y0,tile_x0,width,height"] + ["%s,%s,%d,%d,100,100" % t for t in tiles]
        (folder / "tiles.csv").write_text("\n".join(rows) + "\n")
    return folder / "boxes.csv"


def _images(path: Path) -> set[str]:
    if not path.exists():
        return set()
    return {Path(b.image).name for b in annotations.read_boxes(path)}


def test_that_a_group_split_holds_out_whole_name_groups_and_is_seeded(tmp_path):
    csv = _source(tmp_path / "estate", ["images/%s_%02d.jpg" % (g, i) for g in "ABCD" for i in range(3)])
    for seed in (0, 1):
        for run in ("a", "b"):
            assert cli.main(["split", "--data", str(csv), "--by", "group", "--seed", str(seed),
                             "--out", str(tmp_path / ("s%d%s" % (seed, run)))]) == 0
        test = _images(tmp_path / ("s%da" % seed) / "test" / "estate" / "boxes.csv")
        train = _images(tmp_path / ("s%da" % seed) / "train" / "estate" / "boxes.csv")
        assert test and train and not test & train and len(test | train) == 12
        groups = {name.split("_")[0] for name in test}
        assert len(groups) == 1 and len(test) == 3  # one whole group of four (0.25)
        assert not groups & {name.split("_")[0] for name in train}
        assert test == _images(tmp_path / ("s%db" % seed) / "test" / "estate" / "boxes.csv")  # same seed, same split


def test_that_tiles_split_by_region_and_tiles_overlapping_a_held_out_tile_leave_the_training_side(tmp_path):
    # region 1: three tiles in a row overlapping by 20 px; region 2: two tiles
    tiles = [("R1_a.png", 1, 0, 0), ("R1_b.png", 1, 0, 80), ("R1_c.png", 1, 0, 160),
             ("R2_a.png", 2, 0, 0), ("R2_b.png", 2, 0, 80)]
    csv = _source(tmp_path / "ortho", ["images/" + t[0] for t in tiles], tiles)
    assert cli.main(["split", "--data", str(csv), "--by", "group", "--held-out", "0.5", "--out",
                     str(tmp_path / "g")]) == 0
    test = _images(tmp_path / "g" / "test" / "ortho" / "boxes.csv")
    assert test in ({"R1_a.png", "R1_b.png", "R1_c.png"}, {"R2_a.png", "R2_b.png"})
    # by image, a training tile sharing pixels with a held-out one of its region is left out
    assert cli.main(["split", "--data", str(csv), "--held-out", "0.2", "--seed", "3", "--out",
                     str(tmp_path / "i")]) == 0
    test = _images(tmp_path / "i" / "test" / "ortho" / "boxes.csv")
    train = _images(tmp_path / "i" / "train" / "ortho" / "boxes.csv")
    held = {t[0]: t for t in tiles if t[0] in test}
    assert len(held) == 1
    (name, region, _y, x), = held.values()
    for other, other_region, _y2, other_x in tiles:
        if other != name:
            assert (other in train) == (other_region != region or abs(other_x - x) >= 100)


def test_that_a_tiles_csv_with_a_bad_row_is_one_error_line_naming_it(tmp_path, capsys):
    csv = _source(tmp_path / "ortho", ["images/R1_a.png", "images/R1_b.png"], [("R1_a.png", 1, 0, 0)])
    with open(tmp_path / "ortho" / "tiles.csv", "a") as handle:
        handle.write("R1_b.png,1,zero,0,100,100\n")
    assert cli.main(["split", "--data", str(csv), "--by", "group", "--out", str(tmp_path / "s")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "tiles.csv: line 3" in err[0]
    assert not (tmp_path / "s" / "train").exists()
