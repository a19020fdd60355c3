"""The shipped flight model on a crown touching a larger one, seen from straight above (docs/detector.md)."""
import json
import math

import host_tools.detection  # noqa: F401  (puts the camera module's folder on the path)
import foranav_detector as detector_core
import foranav_model
from host_tools.flight.vision_camera import VisionCamera
from host_tools.maps import map_from_dict
from host_tools.sim.camera import Pose
from tests.conftest import FIXTURES, REPO_ROOT

# sweep flight 43's plantation: tree 3 (0.31 m crown, 75 px at 1.34 m) touches tree 4 (0.35 m) in its column
TOUCHING_MAP = FIXTURES / "maps" / "touching_crowns.json"
SHIPPED_MODEL = REPO_ROOT / "jevois_module" / "ForaNavTrees" / "foranav_oil_palm.npz"
CENTRED_PX = 16  # a detection this close to the crown's centre is that crown
MIN_FOUND = 10  # of the 20 frames; before the colour fallback the detector found it in none


def _frames_above(camera, tree, altitude):
    for yaw in (0, 90, 180, 270):
        for dx, dy in ((0, 0), (0.02, 0), (-0.02, 0), (0, 0.02), (0, -0.02)):
            pose = (tree.x + dx, tree.y + dy, altitude, yaw)
            yield camera.render(pose), camera.camera.world_to_pixel(Pose(*pose), tree.x, tree.y)


def test_that_a_crown_touching_a_larger_one_is_found_from_straight_above():
    pmap = map_from_dict(json.loads(TOUCHING_MAP.read_text()), source=str(TOUCHING_MAP))
    tree = next(t for t in pmap.trees if t.id == 3)
    detector = detector_core.TreeDetector(foranav_model.load_model(str(SHIPPED_MODEL)))
    camera = VisionCamera(pmap, seed=1)
    found = 0
    for frame, (u, v) in _frames_above(camera, tree, pmap.altitude_m):
        found += any(math.hypot(d.x - u, d.y - v) <= CENTRED_PX for d in detector.detect(frame.image))
    assert found >= MIN_FOUND, "found in %d of 20 frames" % found
