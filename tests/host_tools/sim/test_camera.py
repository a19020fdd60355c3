"""The downward camera: conventions of docs/DESIGN.md and the world -> pixel -> world round trip."""
import itertools

import numpy as np
import pytest

from host_tools.sim.camera import CameraModel, Pose, SENSOR_MODES

ROUND_TRIP_TOLERANCE_PX = 1.0
POSES = [Pose(x, y, z, yaw) for x, y, z, yaw in itertools.product((0.0, 1.86), (-0.45, 0.7), (0.5, 1.25, 3.0),
                                                                   (0.0, 37.0, -90.0, 180.0))]
OFFSETS = [(0.0, 0.0), (0.05, -0.03)]


@pytest.mark.parametrize("mode", SENSOR_MODES, ids=["%dx%d" % m for m in SENSOR_MODES])
@pytest.mark.parametrize("offset", OFFSETS)
def test_that_world_to_pixel_to_world_round_trips_within_one_pixel(mode, offset):
    camera = CameraModel(*mode, mount_offset=offset)
    rng = np.random.default_rng(3)
    for pose in POSES:
        # Fixture: ground points that the camera sees (drawn in pixels, mapped to the world)
        u = rng.uniform(0, camera.width, 20)
        v = rng.uniform(0, camera.height, 20)
        x, y = camera.pixel_to_world(pose, u, v)
        # Test: world points back to pixels, and pixels of random world points back to the world
        u2, v2 = camera.world_to_pixel(pose, x, y)
        wx = pose.x + rng.uniform(-0.5, 0.5, 20)
        wy = pose.y + rng.uniform(-0.5, 0.5, 20)
        x3, y3 = camera.pixel_to_world(pose, *camera.world_to_pixel(pose, wx, wy))
        # Assert
        assert np.max(np.hypot(u2 - u, v2 - v)) < ROUND_TRIP_TOLERANCE_PX
        metres_per_px = camera.metres_per_pixel(pose.z)
        assert np.max(np.hypot(x3 - wx, y3 - wy)) / metres_per_px < ROUND_TRIP_TOLERANCE_PX


def test_that_the_ground_scale_is_the_papers():
    camera = CameraModel()
    assert camera.focal_px == pytest.approx(322.58, abs=0.01)
    assert camera.metres_per_pixel(1.0) == pytest.approx(0.0031)
    assert CameraModel(640, 480).focal_px == pytest.approx(322.58 * 640 / 352, abs=0.02)


def test_that_image_up_is_forward_and_image_left_is_left():
    camera = CameraModel()
    pose = Pose(1.0, 2.0, 1.25, 0.0)
    assert camera.world_to_pixel(pose, 1.0, 2.0) == pytest.approx((176.0, 144.0))
    u, v = camera.world_to_pixel(pose, 1.1, 2.0)  # ahead
    assert v < 144.0 and u == pytest.approx(176.0)
    u, v = camera.world_to_pixel(pose, 1.0, 2.1)  # to the left
    assert u < 176.0 and v == pytest.approx(144.0)
    # yaw 90: body forward is world +y, so a point at +y is up in the image
    u, v = camera.world_to_pixel(Pose(1.0, 2.0, 1.25, 90.0), 1.0, 2.1)
    assert v < 144.0 and u == pytest.approx(176.0)


def test_that_the_mount_offset_moves_the_ground_point_with_yaw():
    camera = CameraModel(mount_offset=(0.1, 0.0))
    assert camera.ground_point(Pose(0.0, 0.0, 1.0, 90.0)) == pytest.approx((0.0, 0.1))
    # the point under the camera is at the principal point
    assert camera.world_to_pixel(Pose(0.0, 0.0, 1.0, 90.0), 0.0, 0.1) == pytest.approx((176.0, 144.0))


def test_that_an_unknown_sensor_mode_is_rejected():
    with pytest.raises(ValueError):
        CameraModel(300, 200)


def test_that_the_homography_is_the_affine_map_when_level_and_inverts_world_to_pixel_when_tilted():
    camera = CameraModel(mount_offset=(0.02, -0.01))
    level = Pose(1.0, 2.0, 1.3, 33.0)
    h = camera.pixel_to_world_homography(level)
    assert np.allclose(h / h[2, 2], np.vstack([camera.pixel_to_world_affine(level), [0, 0, 1]]), atol=1e-12)
    tilted = Pose(1.0, 2.0, 1.3, 33.0, 5.0, -4.0)
    u, v = camera.world_to_pixel(tilted, np.array([1.2, 0.8]), np.array([2.1, 2.3]))
    back = camera.pixel_to_world_homography(tilted) @ np.stack([u, v, np.ones(2)])
    assert np.allclose(back[:2] / back[2], [[1.2, 0.8], [2.1, 2.3]], atol=1e-9)
    # roll positive (left side up) turns the belly to the left: the frame centre sees ground to the left (+y)
    centre = camera.pixel_to_world_homography(Pose(0.0, 0.0, 1.0, 0.0, 10.0, 0.0)) @ [176.0, 144.0, 1.0]
    assert centre[1] / centre[2] == pytest.approx(np.tan(np.radians(10.0)) - 0.01, abs=1e-9)
