"""A photo map's world is its photo: the frame is warped from the photo at the camera's ground resolution,
rotated with yaw, a no-data border outside, and its bytes checked against the map's checksum."""
import hashlib

import cv2
import numpy as np
import pytest

from host_tools.errors import ForaNavError
from host_tools.maps import map_from_dict
from host_tools.sim.camera import CameraModel, Pose
from host_tools.sim.world import NO_DATA_BGR, World

PHOTO_PX = 600
MPP = 0.0025  # photo metres per pixel: finer than the camera's 3.9 mm at 1.25 m, as the estate photos are
FINE_MPP = 0.001  # finer than the world's finest level at 1.25 m (half a camera pixel, 1.9 mm)
MARK_PX = 20  # side of the coloured marks painted into the photo
COLOUR_TOLERANCE = 40  # grey levels: bilinear resampling blurs the mark's edge, not its middle


def marked_photo(tmp_path, mpp=MPP):
    """A grey photo with a red mark at photo pixel (200, 300) and a blue one at (400, 300); its photo map."""
    image = np.full((PHOTO_PX, PHOTO_PX, 3), 128, np.uint8)
    image[290:310, 190:210] = (0, 0, 255)
    image[290:310, 390:410] = (255, 0, 0)
    path = tmp_path / "marked.png"
    cv2.imwrite(str(path), image)
    data = {"name": "marked", "altitude_m": 1.25, "waypoints": [[0, 0], [0.5, 0]], "trees": [],
            "photo": {"path": str(path), "sha256": hashlib.sha256(path.read_bytes()).hexdigest(),
                      "metres_per_pixel": mpp, "width_px": PHOTO_PX, "height_px": PHOTO_PX}}
    return path, map_from_dict(data, str(tmp_path / "marked.json"))


def colour_at(image, u, v):
    return image[int(v), int(u)].astype(int)


@pytest.mark.parametrize("yaw", [0.0, 37.0, -90.0])
def test_that_the_frame_shows_the_photo_where_the_camera_looks_rotated_with_yaw(tmp_path, yaw):
    # Fixture
    _, pmap = marked_photo(tmp_path)
    world = World.from_map(pmap)
    camera = CameraModel()
    red = pmap.photo.pixel_to_world(200.0, 300.0)
    blue = pmap.photo.pixel_to_world(400.0, 300.0)
    pose = Pose(0.0, 0.0, 1.25, yaw)
    # Test
    image = world.render(camera, pose).image
    # Assert: each mark's middle is its colour where the camera model puts it; the rest is the photo's grey
    for (x, y), colour in ((red, (0, 0, 255)), (blue, (255, 0, 0))):
        u, v = camera.world_to_pixel(pose, x, y)
        assert np.abs(colour_at(image, u, v) - colour).max() <= COLOUR_TOLERANCE
    assert np.abs(colour_at(image, 176, 144) - 128).max() <= 2


def test_that_outside_the_photo_is_the_no_data_colour_never_texture(tmp_path):
    _, pmap = marked_photo(tmp_path)
    world = World.from_map(pmap)
    camera = CameraModel()
    x_min, x_max, y_min, y_max = pmap.photo.extent_m
    pose = Pose(x_max, 0.0, 1.25)  # over the photo's top edge: the upper half of the frame is beyond it
    image = world.render(camera, pose).image
    assert (image[:130] == NO_DATA_BGR).all()
    assert np.abs(image[160:].astype(int) - 128).max() <= 2
    far = world.render(camera, Pose(x_max + 5.0, y_max + 5.0, 1.25)).image
    assert (far == NO_DATA_BGR).all()


def test_that_the_photo_is_area_averaged_to_the_cameras_resolution_not_kept_finer(tmp_path):
    _, pmap = marked_photo(tmp_path, FINE_MPP)
    world = World.from_map(pmap)
    assert world.metres_per_pixel == pytest.approx(0.0031 * 1.25 / 2, rel=0.01)
    assert world.levels[0].shape[0] == round(PHOTO_PX * FINE_MPP / world.metres_per_pixel)
    _, coarse = marked_photo(tmp_path, MPP)  # coarser than that: the photo's own pixels, nothing invented
    assert World.from_map(coarse).levels[0].shape[:2] == (PHOTO_PX, PHOTO_PX)


def test_that_a_photo_changed_after_the_map_was_loaded_is_refused_by_the_renderer(tmp_path):
    path, pmap = marked_photo(tmp_path)
    image = cv2.imread(str(path))
    image[0, 0] = 0
    cv2.imwrite(str(path), image)
    with pytest.raises(ForaNavError, match="photo.sha256: .*changed since the map was written"):
        World.from_map(pmap)
