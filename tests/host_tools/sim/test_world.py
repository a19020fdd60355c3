"""The rendered world: trees appear where the camera model says, frames are deterministic and cheap."""
import numpy as np
import pytest

from host_tools.maps import load_map, map_from_dict
from host_tools.sim.camera import CameraModel, Pose
from host_tools.sim.world import World, SENSOR_EFFECTS, render_species

CENTRE_TOLERANCE_PX = 3.0
WARP_TOLERANCE_PX = 0.05  # cv2.warpAffine interpolates at 1/32 pixel steps


@pytest.fixture(scope="module")
def map1_world():
    return World.from_map(load_map("map1"))


def coordinate_world(mpp=0.002, size=(1600, 1600), bounds_max=(1.9, 1.9)):
    """A world whose mosaic holds its own continuous pixel coordinates (col, row) as linear ramps.

    Bilinear sampling of a linear ramp is exact, so a rendered frame reads back where each pixel came from.
    """
    width, height = size
    cols, rows = np.meshgrid(np.arange(width, dtype=np.float32) + 0.5, np.arange(height, dtype=np.float32) + 0.5)
    ramps = np.dstack([cols, rows, np.zeros_like(cols)])
    x_max, y_max = bounds_max
    bounds = (x_max - height * mpp, x_max, y_max - width * mpp, y_max)
    pmap = map_from_dict({"name": "ramps", "altitude_m": 1.25, "waypoints": [[0, 0], [1, 0]], "trees": []})
    return World(pmap, [ramps], bounds, mpp, 0, None, [])


@pytest.mark.parametrize("pose", [Pose(0.3, 0.2, 1.25, 0.0), Pose(0.45, 0.1, 1.0, 30.0),
                                  Pose(0.2, 0.35, 1.6, -120.0)])
@pytest.mark.parametrize("offset", [(0.0, 0.0), (0.04, -0.02)])
def test_that_each_frame_pixel_shows_the_ground_point_the_camera_model_says(pose, offset):
    # Fixture
    world = coordinate_world()
    camera = CameraModel(mount_offset=offset)
    # Test
    image = world.render(camera, pose).image
    # Assert: the mosaic coordinates read back equal the camera model's ground point of each pixel centre
    vs, us = np.mgrid[0:camera.height, 0:camera.width] + 0.5
    x, y = camera.pixel_to_world(pose, us, vs)
    col, row = world.mosaic_pixel(x, y)
    assert np.max(np.abs(image[..., 0] - col)) < WARP_TOLERANCE_PX
    assert np.max(np.abs(image[..., 1] - row)) < WARP_TOLERANCE_PX


@pytest.mark.parametrize("species", ["oil_palm", "coconut", "date_palm", "citrus", "olive"])
def test_that_a_crown_is_drawn_centred_on_its_position(species):
    rng = np.random.default_rng(8)
    sprite = render_species(species, rng, 100.3, 80.7, diameter_px=120)
    rows, cols = np.mgrid[0:sprite.alpha.shape[0], 0:sprite.alpha.shape[1]] + 0.5
    weight = sprite.alpha / sprite.alpha.sum()
    centre = ((cols * weight).sum() + sprite.origin[0], (rows * weight).sum() + sprite.origin[1])
    assert centre == pytest.approx((100.3, 80.7), abs=CENTRE_TOLERANCE_PX)
    covered = np.nonzero(sprite.alpha.max(axis=0) > 0.5)[0]
    assert covered.max() - covered.min() + 1 <= 120 + 2  # within the crown diameter


def test_that_trees_at_the_frame_edge_are_partial_and_far_trees_are_absent(map1_world):
    camera = CameraModel()
    frame = map1_world.render(camera, Pose(1.86, 0.57, 1.25, 0.0))
    by_id = {t.id: t for t in frame.trees}
    assert by_id[3].complete
    assert not by_id[2].complete and not by_id[4].complete  # cut by the bottom and top edges
    assert 1 not in by_id and 6 not in by_id


def test_that_rendering_is_deterministic_and_seeded(map1_world):
    camera = CameraModel()
    pose = Pose(2.4, 0.4, 1.25, 12.0)
    again = World.from_map(load_map("map1"))
    assert np.array_equal(map1_world.render(camera, pose).image, again.render(camera, pose).image)
    noisy1 = map1_world.render(camera, pose, rng=np.random.default_rng(4), effects=SENSOR_EFFECTS).image
    noisy2 = again.render(camera, pose, rng=np.random.default_rng(4), effects=SENSOR_EFFECTS).image
    assert np.array_equal(noisy1, noisy2)
    other_seed = World.from_map(load_map("map1"), seed=12345)
    assert not np.array_equal(map1_world.render(camera, pose).image, other_seed.render(camera, pose).image)


@pytest.mark.parametrize("mode", [(352, 288), (640, 480), (1280, 1024), (320, 240)])
def test_that_every_sensor_mode_renders_a_bgr_frame(map1_world, mode):
    frame = map1_world.render(CameraModel(*mode), Pose(1.0, 0.45, 1.25, 0.0))
    assert frame.image.shape == (mode[1], mode[0], 3) and frame.image.dtype == np.uint8
    assert frame.image.std() > 5  # not a blank image


def test_that_objects_are_reported_in_view():
    data = {"name": "o", "altitude_m": 1.25, "waypoints": [[0, 0], [1, 0]], "trees": [],
            "objects": [{"kind": "roof", "x": 0.5, "y": 0.0, "size_m": 0.4, "yaw_deg": 0},
                        {"kind": "road_cross", "x": 5.0, "y": 0.0, "size_m": 0.4, "yaw_deg": 0}]}
    world = World.from_map(map_from_dict(data))
    frame = world.render(CameraModel(), Pose(0.5, 0.0, 1.25, 0.0))
    assert [o.kind for o in frame.objects] == ["roof"]
    assert frame.objects[0].complete
    assert frame.objects[0].h == pytest.approx(0.4 / 0.0031 / 1.25, rel=0.01)  # long side along x = image up


@pytest.mark.parametrize("pose", [Pose(0.3, 0.2, 1.25, 0.0, 4.0, -3.0), Pose(0.45, 0.1, 1.0, 30.0, -6.0, 5.0),
                                  Pose(0.2, 0.35, 1.6, -120.0, 2.0, 8.0)])
def test_that_a_tilted_camera_shows_the_ground_point_of_the_ground_plane_homography(pose):
    # Fixture
    world = coordinate_world()
    camera = CameraModel(mount_offset=(0.03, 0.01))
    # Test
    image = world.render(camera, pose).image
    # Assert: each pixel centre reads back the mosaic coordinate of the ground point its ray meets
    vs, us = np.mgrid[0:camera.height, 0:camera.width] + 0.5
    h = camera.pixel_to_world_homography(pose) @ np.stack([us.ravel(), vs.ravel(), np.ones(us.size)])
    col, row = world.mosaic_pixel(h[0] / h[2], h[1] / h[2])
    assert np.max(np.abs(image[..., 0].ravel() - col)) < WARP_TOLERANCE_PX
    assert np.max(np.abs(image[..., 1].ravel() - row)) < WARP_TOLERANCE_PX


def test_that_a_level_pose_keeps_the_nadir_bytes_and_a_tilt_moves_the_view(map1_world):
    camera = CameraModel()
    level = map1_world.render(camera, Pose(1.0, 0.5, 1.25, 10.0)).image
    assert np.array_equal(map1_world.render(camera, Pose(1.0, 0.5, 1.25, 10.0, 0.0, 0.0)).image, level)
    # nose up by 5 degrees: the belly, and the camera, turn forward; a tree straight below moves back (down)
    tree = load_map("map1").trees[0]
    u0, v0 = camera.world_to_pixel(Pose(tree.x, tree.y, 1.25), tree.x, tree.y)
    u1, v1 = camera.world_to_pixel(Pose(tree.x, tree.y, 1.25, 0.0, 0.0, 5.0), tree.x, tree.y)
    assert u1 == pytest.approx(u0) and v1 - v0 == pytest.approx(camera.focal_px * np.tan(np.radians(5.0)), rel=1e-6)
    pitched = map1_world.render(camera, Pose(1.0, 0.5, 1.25, 10.0, 0.0, 5.0)).image
    assert not np.array_equal(pitched, level)
