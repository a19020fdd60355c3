"""Photo crowns (host_tools/sim/crowns.py): trees drawn from an annotated photograph.

Every test builds its own tiny crown library: a rendered "aerial photo" (crowns as coloured discs with a
texture, neighbours of another colour reaching into each box's corners) written as a PNG plus boxes.csv.
"""
import math
from pathlib import Path

import cv2
import numpy as np
import pytest

from host_tools.cli import main
from host_tools.maps import PlantationMap, Tree
from host_tools.sim.camera import CameraModel, Pose
from host_tools.sim.crowns import Appearance, AppearanceSpec, assign, load_library
from host_tools.sim.world import World
from jevois_module.ForaNavTrees import MODULE_DIR as MODULE_FOLDER

MODULE_DIR = Path(MODULE_FOLDER)

# BGR colours of the library's crowns; the test finds them again in the rendered frames
RED, MAGENTA, ORANGE, BLUE = (30, 30, 230), (230, 30, 230), (30, 140, 250), (230, 60, 30)
NEIGHBOUR = (250, 250, 250)  # white: the procedural ground has none
BOX_PX = 80
CROWN_PX = 72  # disc diameter inside its box
COLOUR_TOLERANCE = 60  # grey levels (blending, interpolation)
POSITION_TOLERANCE_PX = 3.0
SIZE_TOLERANCE = 0.12  # of the crown diameter


def write_library(folder, crowns, name="lib"):
    """A photo with one textured disc per (label, colour) in its own box, neighbours in the box corners.

    Returns the boxes.csv path."""
    folder.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(0)
    image = np.full((2 * BOX_PX, BOX_PX * (len(crowns) + 1), 3), 110, np.uint8)
    rows = ["image,x_center,y_center,width,height,label"]
    for i, (label, colour) in enumerate(crowns):
        cx, cy = BOX_PX * (i + 1), BOX_PX
        for dx, dy in ((-1, -1), (1, -1), (-1, 1), (1, 1)):  # neighbours: discs centred on the box corners
            cv2.circle(image, (cx + dx * BOX_PX // 2, cy + dy * BOX_PX // 2), 22, NEIGHBOUR, -1)
        cv2.circle(image, (cx, cy), CROWN_PX // 2, colour, -1, cv2.LINE_AA)
        rows.append("%s.png,%d,%d,%d,%d,%s" % (name, cx, cy, BOX_PX, BOX_PX, label))
    texture = rng.integers(-12, 13, image.shape)
    image = np.clip(image.astype(int) + texture, 0, 255).astype(np.uint8)
    cv2.imwrite(str(folder / ("%s.png" % name)), image)
    csv_path = folder / "boxes.csv"
    csv_path.write_text("\n".join(rows) + "\n")
    return csv_path


def one_tree_map(trees, seed=5):
    return PlantationMap("crowns test", 1.4, ((-1.0, 0.0), (1.0, 0.0)), tuple(trees), (), seed, "oil_palm")


def appearance(csv_paths):
    return Appearance.load(AppearanceSpec(tuple(str(p) for p in csv_paths)))


def colour_mask(image, colour):
    return np.all(np.abs(image.astype(int) - np.array(colour)) <= COLOUR_TOLERANCE, axis=2)


def frame_above(world, x, y, yaw=0.0):
    return world.render(CameraModel(), Pose(x, y, world.map.altitude_m, yaw))


def test_that_a_photo_crown_is_drawn_at_its_tree_with_the_trees_crown_size(tmp_path):
    # Fixture
    library = write_library(tmp_path / "lib", [("oil_palm", RED)])
    pmap = one_tree_map([Tree(1, 0.1, -0.05, "oil_palm", 0.40, True)])
    world = World.from_map(pmap, appearance=appearance([library]))
    # Test
    frame = frame_above(world, 0.0, 0.0, yaw=30.0)
    # Assert: the red disc is centred on the tree's ground truth and spans its crown (disc = 72/80 of the box)
    truth = frame.trees[0]
    rows, cols = np.nonzero(colour_mask(frame.image, RED))
    assert abs(cols.mean() + 0.5 - truth.u) <= POSITION_TOLERANCE_PX
    assert abs(rows.mean() + 0.5 - truth.v) <= POSITION_TOLERANCE_PX
    diameter = 2 * math.sqrt(len(rows) / math.pi)
    assert diameter == pytest.approx(truth.w * CROWN_PX / BOX_PX, rel=SIZE_TOLERANCE)


def test_that_each_tree_gets_a_crown_of_its_species_and_others_are_drawn(tmp_path):
    library = write_library(tmp_path / "lib", [("oil_palm", RED), ("olive_tree", BLUE), ("mango", ORANGE)])
    trees = [Tree(1, -0.3, 0.0, "oil_palm", 0.38, True), Tree(2, 0.3, 0.0, "olive", 0.38, False),
             Tree(3, 0.0, 0.45, "coconut", 0.38, False)]
    world = World.from_map(one_tree_map(trees), appearance=appearance([library]))
    frame = frame_above(world, 0.0, 0.15)
    by_id = {t.id: t for t in frame.trees}

    def share_near(tree, colour):
        rows, cols = np.mgrid[0:frame.image.shape[0], 0:frame.image.shape[1]]
        near = (cols + 0.5 - tree.u) ** 2 + (rows + 0.5 - tree.v) ** 2 <= (0.35 * tree.w) ** 2
        return colour_mask(frame.image, colour)[near].mean()

    assert share_near(by_id[1], RED) > 0.8 and share_near(by_id[1], BLUE) == 0
    assert share_near(by_id[2], BLUE) > 0.8 and share_near(by_id[2], RED) == 0
    # mango is not a species of ours: unused; the coconut has no crown in the library and is drawn as before
    assert share_near(by_id[3], ORANGE) < 0.02 and share_near(by_id[3], RED) < 0.02
    assert world.photo_species == ("oil_palm", "olive")


def test_that_the_neighbours_in_a_crowns_box_do_not_show(tmp_path):
    library = write_library(tmp_path / "lib", [("oil_palm", RED)])
    world = World.from_map(one_tree_map([Tree(1, 0.0, 0.0, "oil_palm", 0.45, True)]),
                           appearance=appearance([library]))
    frame = frame_above(world, 0.0, 0.0, yaw=45.0)
    assert colour_mask(frame.image, RED).sum() > 1000
    # a neighbour blended in at even a third of its coverage would lift a pixel above this
    assert (frame.image.min(axis=2) > 160).sum() == 0


def test_that_different_trees_get_different_crowns_deterministically(tmp_path):
    library = write_library(tmp_path / "lib", [("oil_palm", RED), ("oil_palm", MAGENTA), ("oil_palm", ORANGE)])
    trees = [Tree(i + 1, -0.45 + 0.45 * i, 0.0, "oil_palm", 0.36, True) for i in range(3)]
    pmap = one_tree_map(trees)
    look = appearance([library])
    first, again = World.from_map(pmap, appearance=look), World.from_map(pmap, appearance=look)
    frame = frame_above(first, 0.0, 0.0)
    colours = []
    for tree in sorted(frame.trees, key=lambda t: t.id):
        shares = [colour_mask(frame.image, c)[int(tree.v) - 5:int(tree.v) + 5, int(tree.u) - 5:int(tree.u) + 5].mean()
                  for c in (RED, MAGENTA, ORANGE)]
        colours.append(int(np.argmax(shares)))
    assert sorted(colours) == [0, 1, 2]  # three trees, three crowns while the library lasts
    assert np.array_equal(frame.image, frame_above(again, 0.0, 0.0).image)
    assert first.photo_crowns == again.photo_crowns
    # a map with more trees than crowns reuses them, still deterministic
    many = [Tree(i + 1, 0.1 * i, 0.0, "oil_palm", 0.3, True) for i in range(7)]
    assert assign(look.library, many, 5) == assign(look.library, many, 5)
    assert len({id(crown) for crown, _ in assign(look.library, many, 5).values()}) == 3


def test_that_ground_truth_and_unphotographed_trees_are_unchanged(tmp_path):
    library = write_library(tmp_path / "lib", [("oil_palm", RED)])
    trees = [Tree(1, -0.6, 0.0, "oil_palm", 0.38, True), Tree(2, 0.6, 0.0, "coconut", 0.38, False)]
    pmap = one_tree_map(trees)
    drawn = World.from_map(pmap)
    photo = World.from_map(pmap, appearance=appearance([library]))
    pose = Pose(0.6, 0.0, 1.4, 0.0)
    assert drawn.trees_in_view(CameraModel(), pose) == photo.trees_in_view(CameraModel(), pose)
    a, b = drawn.render(CameraModel(), pose), photo.render(CameraModel(), pose)
    coconut = [t for t in a.trees if t.id == 2][0]
    r = int(0.5 * coconut.w)
    window = (slice(int(coconut.v) - r, int(coconut.v) + r), slice(int(coconut.u) - r, int(coconut.u) + r))
    assert np.array_equal(a.image[window], b.image[window])


def test_that_a_hidden_tree_leaves_the_other_trees_their_crowns(tmp_path):
    library = write_library(tmp_path / "lib", [("oil_palm", RED), ("oil_palm", MAGENTA)])
    trees = [Tree(1, -0.3, 0.0, "oil_palm", 0.36, True), Tree(2, 0.3, 0.0, "oil_palm", 0.36, True)]
    pmap = one_tree_map(trees)
    look = appearance([library])
    full = World.from_map(pmap, appearance=look)
    bare = World.from_map(one_tree_map(trees[1:]), appearance=look, crown_trees=pmap.trees)
    assert bare.photo_crowns == {2: full.photo_crowns[2]}


def test_that_a_ground_photo_is_tiled_at_its_ground_scale(tmp_path):
    stripes = np.zeros((40, 40, 3), np.uint8)
    stripes[:, 10:30] = (200, 200, 200)  # symmetric: mirrored tiles keep 20 px bright, 20 px dark (0.4 m)
    cv2.imwrite(str(tmp_path / "ground.png"), stripes)
    library = write_library(tmp_path / "lib", [("oil_palm", RED)])
    spec = AppearanceSpec((str(library),), str(tmp_path / "ground.png"), 0.01)
    world = World.from_map(one_tree_map([Tree(1, 0.8, 0.6, "oil_palm", 0.3, True)]), appearance=Appearance.load(spec))
    row = world.levels[0][5, :, 1].astype(float)  # a row far from the tree
    bright = row > row.mean()
    period_px = 2 * len(bright) / max(1, np.count_nonzero(np.diff(bright.astype(int))))
    assert period_px * world.metres_per_pixel == pytest.approx(0.4, rel=0.1)


def test_that_boxes_cut_by_the_edge_or_too_small_are_skipped(tmp_path):
    folder = tmp_path / "lib"
    write_library(folder, [("oil_palm", RED)])
    (folder / "boxes.csv").write_text("image,x_center,y_center,width,height,label\n"
                                      "lib.png,80,80,80,80,oil_palm\nlib.png,10,80,80,80,oil_palm\n"
                                      "lib.png,80,80,20,20,oil_palm\n")
    library = load_library([folder / "boxes.csv"])
    assert library.count("oil_palm") == 1
    assert sum(library.skipped.values()) == 2


# ---- the command line ---------------------------------------------------------------------------------------


def test_that_render_with_crowns_says_which_species_came_from_photos(tmp_path, capsys):
    library = write_library(tmp_path / "lib", [("oil_palm", RED)])
    out = tmp_path / "frame.png"
    assert main(["render", "--map", "map2", "--x", "1.5", "--y", "0.3", "--out", str(out),
                 "--crowns", str(library)]) == 0
    assert "crowns from photos: oil_palm" in capsys.readouterr().out
    assert colour_mask(cv2.imread(str(out)), RED).sum() > 500


def _bad(tmp_path, capsys, argv):
    out = tmp_path / "out.png"
    code = main(["render", "--map", "map1", "--x", "1.8", "--y", "0.5", "--out", str(out)] + argv)
    err = capsys.readouterr().err.strip()
    assert code == 2 and not out.exists()
    assert len(err.splitlines()) == 1
    return err


def test_that_an_unreadable_crown_image_is_named_with_its_row(tmp_path, capsys):
    library = write_library(tmp_path / "lib", [("oil_palm", RED)])
    (tmp_path / "lib" / "lib.png").write_bytes(b"not a png")
    err = _bad(tmp_path, capsys, ["--crowns", str(library)])
    assert "boxes.csv: line 2" in err and "lib.png" in err


def test_that_a_box_outside_its_image_is_named_with_its_row(tmp_path, capsys):
    library = write_library(tmp_path / "lib", [("oil_palm", RED), ("oil_palm", MAGENTA)])
    library.write_text(library.read_text() + "lib.png,5000,80,80,80,oil_palm\n")
    err = _bad(tmp_path, capsys, ["--crowns", str(library)])
    assert "boxes.csv: line 4" in err and "outside" in err


def test_that_a_library_without_any_species_of_the_map_is_refused(tmp_path, capsys):
    library = write_library(tmp_path / "lib", [("olive_tree", BLUE), ("mango", ORANGE)])
    err = _bad(tmp_path, capsys, ["--crowns", str(library)])
    assert "no usable crown for any species of map map1" in err and "boxes.csv" in err


def test_that_a_ground_image_that_does_not_load_is_refused(tmp_path, capsys):
    (tmp_path / "ground.png").write_bytes(b"\x89PNG broken")
    err = _bad(tmp_path, capsys, ["--ground", str(tmp_path / "ground.png"), "--ground-gsd", "0.005"])
    assert "ground.png" in err
    err = _bad(tmp_path, capsys, ["--ground", str(tmp_path / "ground.png")])
    assert "--ground-gsd" in err


def test_that_fly_refuses_a_bad_model_and_crowns_with_the_oracle(tmp_path, capsys):
    (tmp_path / "model.npz").write_bytes(b"junk")
    assert main(["fly", "--map", "map1", "--model", str(tmp_path / "model.npz"), "--out", str(tmp_path / "f")]) == 2
    assert "model.npz" in capsys.readouterr().err
    library = write_library(tmp_path / "lib", [("oil_palm", RED)])
    assert main(["fly", "--map", "map1", "--camera", "oracle", "--crowns", str(library),
                 "--out", str(tmp_path / "f")]) == 2
    assert "--camera sim" in capsys.readouterr().err
    assert not (tmp_path / "f").exists()


def test_that_synth_with_crowns_writes_frames_of_photo_crowns(tmp_path, capsys):
    library = write_library(tmp_path / "lib", [("oil_palm", RED), ("oil_palm", MAGENTA)])
    argv = ["synth", "--count", "3", "--frames", "3", "--seed", "4", "--crowns", str(library)]
    assert main(argv + ["--out", str(tmp_path / "a")]) == 0
    assert main(argv + ["--out", str(tmp_path / "b")]) == 0
    assert "crowns from photos: oil_palm (2 crowns)" in capsys.readouterr().out
    frames = sorted((tmp_path / "a" / "frames").glob("*.png"))
    crops = sorted((tmp_path / "a" / "crops" / "pos").glob("*.png"))
    assert any((colour_mask(cv2.imread(str(p)), RED) | colour_mask(cv2.imread(str(p)), MAGENTA)).sum() > 200
               for p in frames)
    assert all((colour_mask(cv2.imread(str(p)), RED) | colour_mask(cv2.imread(str(p)), MAGENTA)).mean() > 0.2
               for p in crops)
    for p in frames + crops:
        assert p.read_bytes() == (tmp_path / "b" / p.relative_to(tmp_path / "a")).read_bytes()


def test_that_the_vision_camera_runs_the_module_with_the_given_model_file(tmp_path):
    from host_tools.flight.vision_camera import VisionCamera, model_option
    from host_tools.maps import load_map

    model = tmp_path / "my_model.npz"
    model.write_bytes((MODULE_DIR / "foranav_citrus.npz").read_bytes())
    camera = VisionCamera(load_map("map1"), model=model_option(model))
    camera.capture(0, (1.0, 0.45, 1.4, 0.0))
    assert camera.runner.getpar("species") == str(model.resolve())
    assert camera.runner.instance.model.species == "citrus"  # the file's, not the map's target species


def test_that_the_trajectory_plot_shows_the_photo_crowns_where_the_trees_are(tmp_path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from host_tools.flight.plot import show_mosaic

    library = write_library(tmp_path / "lib", [("oil_palm", RED)])
    tree = Tree(1, 0.5, 0.3, "oil_palm", 0.4, True)
    world = World.from_map(one_tree_map([tree]), appearance=appearance([library]))
    fig, ax = plt.subplots()
    show_mosaic(ax, world, level=0)
    image = np.asarray(ax.images[0].get_array())
    x0, x1, y0, y1 = ax.images[0].get_extent()
    plt.close(fig)

    def rgb_at(x, y):  # plot x to the right, y up
        return image[int((y1 - y) / (y1 - y0) * image.shape[0]), int((x - x0) / (x1 - x0) * image.shape[1])]

    assert np.all(np.abs(rgb_at(tree.x, tree.y).astype(int) - np.array(RED[::-1])) <= COLOUR_TOLERANCE)
    # a crown's width away the ground shows, in every direction
    for dx, dy in ((0.4, 0.0), (-0.4, 0.0), (0.0, 0.4), (0.0, -0.4)):
        assert not np.all(np.abs(rgb_at(tree.x + dx, tree.y + dy).astype(int) - np.array(RED[::-1]))
                          <= COLOUR_TOLERANCE)


def test_that_photo_crowns_cast_a_shadow_only_when_asked(tmp_path):
    library = write_library(tmp_path / "lib", [("oil_palm", RED)])
    pmap = one_tree_map([Tree(1, 0.0, 0.0, "oil_palm", 0.4, True)])
    plain = World.from_map(pmap, appearance=Appearance.load(AppearanceSpec((str(library),))))
    shaded = World.from_map(pmap, appearance=Appearance.load(AppearanceSpec((str(library),), crown_shadows=True)))
    red = colour_mask(plain.levels[0], RED)
    outside = ~cv2.dilate(red.astype(np.uint8), np.ones((9, 9), np.uint8)).astype(bool)
    darker = plain.levels[0].astype(int).sum(axis=2) - shaded.levels[0].astype(int).sum(axis=2)
    assert (darker[outside] > 30).sum() > 500  # a shadow on the ground beside the crown
    assert (darker[outside] < 0).sum() == 0


def test_that_paper_tests_refuse_a_bad_library_before_flying(tmp_path, capsys):
    library = write_library(tmp_path / "lib", [("mango", ORANGE)])
    out = tmp_path / "paper"
    assert main(["paper-tests", "--crowns", str(library), "--out", str(out)]) == 2
    assert "no usable crown" in capsys.readouterr().err
    assert not out.exists()
