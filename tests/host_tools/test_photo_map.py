"""foranav plantation --photo: the photo map (rows, targets, scale, checksum) and its bad inputs."""
import json
import math
import shutil

import cv2
import pytest

from host_tools.annotations import Box, write_boxes
from host_tools.cli import main
from host_tools.errors import ForaNavError
from host_tools.maps import load_map, map_from_dict, map_to_dict
from host_tools.photo_map import view_margins

from .conftest import PHOTO_CROWN_PX, write_synthetic_photo

DEFAULT_CROWN_M = 0.35  # the app's crownSize: the default scale puts the median box at this size


def plantation(capsys, *args):
    code = main(["plantation", *map(str, args)])
    return code, capsys.readouterr()


@pytest.fixture
def estate(tmp_path):
    return write_synthetic_photo(tmp_path, heading_deg=20.0)


def test_that_a_photo_map_has_the_photos_rows_trees_and_scale(estate, tmp_path, capsys):
    # Fixture
    out = tmp_path / "maps" / "estate.json"
    out.parent.mkdir()
    # Test
    code, printed = plantation(capsys, "--photo", estate.photo, "--boxes", estate.boxes, "--out", out)
    # Assert
    assert code == 0
    assert "3 rows found (heading 20.0 deg" in printed.out and "3 flown" in printed.out
    data = json.loads(out.read_text())
    assert data["photo"]["path"] == "../estate.png"  # relative to the map's folder
    mpp = data["photo"]["metres_per_pixel"]
    assert mpp == pytest.approx(DEFAULT_CROWN_M / PHOTO_CROWN_PX)
    assert data["row_spacing_m"] == pytest.approx(estate.row_spacing_px * mpp, rel=0.05)
    pmap = load_map(out)
    assert len(pmap.trees) == len(estate.centres)
    assert all(t.crown_m == pytest.approx(DEFAULT_CROWN_M) for t in pmap.trees)
    # 3 rows serpentine: 6 waypoints, each row along the heading (20 deg from photo up = world +x)
    assert len(pmap.waypoints) == 6
    for k in range(3):
        (x0, y0), (x1, y1) = pmap.waypoints[2 * k], pmap.waypoints[2 * k + 1]
        assert math.degrees(math.atan2(y1 - y0, x1 - x0)) % 180 == pytest.approx(20.0, abs=1.0)
    assert "%d of %d trees are targets" % (len(pmap.targets), len(pmap.trees)) in printed.out


def test_that_the_camera_view_stays_inside_the_photo_along_the_path(estate, tmp_path, capsys):
    out = tmp_path / "estate.json"
    plantation(capsys, "--photo", estate.photo, "--boxes", estate.boxes, "--altitude", 1.0, "--out", out)
    pmap = load_map(out)
    x_min, x_max, y_min, y_max = pmap.photo.extent_m
    mx, my = view_margins(1.0)
    for x, y in pmap.waypoints:
        assert x_min + mx - 1e-6 <= x <= x_max - mx + 1e-6 and y_min + my - 1e-6 <= y <= y_max - my + 1e-6


def test_that_rows_and_gsd_and_heading_options_shape_the_map(estate, tmp_path, capsys):
    out = tmp_path / "one_row.json"
    code, printed = plantation(capsys, "--photo", estate.photo, "--boxes", estate.boxes, "--rows", "1",
                               "--gsd", 0.005, "--out", out)
    assert code == 0 and "1 flown" in printed.out
    pmap = load_map(out)
    assert len(pmap.waypoints) == 2 and pmap.photo.metres_per_pixel == 0.005
    assert pmap.trees[0].crown_m == pytest.approx(PHOTO_CROWN_PX * 0.005)


def test_that_given_waypoints_in_photo_pixels_replace_the_rows(estate, tmp_path, capsys):
    out = tmp_path / "given.json"
    code, printed = plantation(capsys, "--photo", estate.photo, "--boxes", estate.boxes,
                               "--waypoints", "400,500", "600,500", "--out", out)
    assert code == 0 and "2 waypoints given" in printed.out
    pmap = load_map(out)
    mpp = pmap.photo.metres_per_pixel
    assert pmap.waypoints[0] == pytest.approx((0.0, 100 * mpp), abs=1e-4)  # photo left of centre = world +y


def test_that_the_same_command_writes_the_same_bytes(estate, tmp_path, capsys):
    a, b = tmp_path / "a.json", tmp_path / "b.json"
    for out in (a, b):
        plantation(capsys, "--photo", estate.photo, "--boxes", estate.boxes, "--out", out)
    assert a.read_bytes() == b.read_bytes()


def test_that_row_spacing_and_photo_round_trip_through_the_map_format(estate, tmp_path, capsys):
    out = tmp_path / "estate.json"
    plantation(capsys, "--photo", estate.photo, "--boxes", estate.boxes, "--out", out)
    data = json.loads(out.read_text())
    again = map_to_dict(map_from_dict(data, str(out)))
    assert again == data
    plain = map_to_dict(load_map("map1"))
    assert "row_spacing_m" not in plain and "photo" not in plain
    plain["row_spacing_m"] = 1.25
    assert map_from_dict(plain).row_spacing_m == 1.25
    assert map_to_dict(map_from_dict(plain)) == plain


def test_that_a_photo_changed_or_moved_since_the_map_is_refused(estate, tmp_path, capsys):
    out = tmp_path / "estate.json"
    plantation(capsys, "--photo", estate.photo, "--boxes", estate.boxes, "--out", out)
    image = cv2.imread(str(estate.photo))
    image[0, 0] = 255 - image[0, 0]
    cv2.imwrite(str(estate.photo), image)
    with pytest.raises(ForaNavError, match=r"estate.json: photo.sha256: .*changed since the map was written"):
        load_map(out)
    shutil.move(estate.photo, tmp_path / "elsewhere.png")
    with pytest.raises(ForaNavError, match=r"estate.json: photo.path: .*not found"):
        load_map(out)
    code = main(["fly", "--map", str(out), "--camera", "oracle", "--out", str(tmp_path / "fly")])
    assert code == 2 and not (tmp_path / "fly").exists()


@pytest.mark.parametrize("case, message", [
    ("unreadable photo", "not an image OpenCV can decode"),
    ("boxes of another image", "no box of"),
    ("box outside the photo", "lies outside the 1000x1000 photo"),
    ("no row", "no planting row found"),
    ("huge scale", "--gsd/--crown-m"),
    ("waypoint outside", "--waypoints: waypoint 1"),
    ("rows out of range", "--rows: 5:5 outside the 3 rows found"),
    ("unknown label", "--label"),
])
def test_that_bad_input_gets_one_line_exit_2_and_nothing_written(estate, tmp_path, capsys, case, message):
    # Fixture
    args = ["--photo", estate.photo, "--boxes", estate.boxes]
    if case == "unreadable photo":
        estate.photo.write_bytes(b"not a png at all")
    elif case == "boxes of another image":
        write_boxes(estate.boxes, [Box("other.png", 500, 500, 90, 90, "oil_palm")])
    elif case == "box outside the photo":
        write_boxes(estate.boxes, [Box("estate.png", 1500, 500, 90, 90, "oil_palm")])
    elif case == "no row":
        write_boxes(estate.boxes, [Box("estate.png", 500, 500, 90, 90, "oil_palm"),
                                   Box("estate.png", 700, 300, 90, 90, "oil_palm")])
    elif case == "huge scale":
        args += ["--gsd", "5"]
    elif case == "waypoint outside":
        args += ["--waypoints", "10,10", "500,500"]
    elif case == "rows out of range":
        args += ["--rows", "5"]
    elif case == "unknown label":
        args += ["--label", "pine"]
    out = tmp_path / "out.json"
    # Test
    code, printed = plantation(capsys, *args, "--out", out)
    # Assert
    assert code == 2
    assert message in printed.err and len(printed.err.strip().splitlines()) == 1
    assert not out.exists()
