"""Single specimens: one tree species or look-alike alone on the ground, as the camera sees it.

Used for the README gallery and to measure the detector's features per class (host_tools.sim.featurecheck).
"""
import numpy as np

from host_tools.maps import PlantationMap, Tree, WorldObject, SPECIES, OBJECT_KINDS
from host_tools.sim.camera import CameraModel, Pose
from host_tools.sim.world import NO_EFFECTS, Effects, World

KINDS = SPECIES + OBJECT_KINDS + ("ground",)
ALTITUDE_M = 1.25


def specimen_map(kind: str, seed: int, size_m: float | None = None, yaw_deg: float = 0.0) -> PlantationMap:
    """A one-element map at the world origin: a tree of a species, an object, or only ground."""
    rng = np.random.default_rng([seed & 0xFFFFFFFF, 7])
    size = float(size_m if size_m is not None else rng.uniform(0.3, 0.45))
    trees, objs = (), ()
    if kind in SPECIES:
        trees = (Tree(1, 0.0, 0.0, kind, size, kind == "oil_palm"),)
    elif kind in OBJECT_KINDS:
        objs = (WorldObject(kind, 0.0, 0.0, size, float(yaw_deg)),)
    elif kind != "ground":
        raise ValueError("unknown specimen kind %r" % kind)
    return PlantationMap("specimen " + kind, ALTITUDE_M, ((-0.1, 0.0), (0.1, 0.0)), trees, objs, int(seed))


def render_specimen(kind: str, seed: int, size_m: float | None = None, window_factor: float = 1.3,
                    camera: CameraModel | None = None, yaw_deg: float = 0.0,
                    effects: Effects = NO_EFFECTS) -> np.ndarray:
    """A square crop (BGR uint8) centred on one specimen, window = window_factor x its size, camera scale.

    ``effects`` (world.Effects) are applied to the camera frame before cropping, seeded by ``seed``.
    """
    camera = camera or CameraModel()
    pmap = specimen_map(kind, seed, size_m, yaw_deg)
    size = pmap.trees[0].crown_m if pmap.trees else (pmap.objects[0].size_m if pmap.objects else 0.4)
    world = World.from_map(pmap, margin_m=size * window_factor * 0.5 + 0.05)
    frame = world.render(camera, Pose(0.0, 0.0, ALTITUDE_M, 0.0), rng=np.random.default_rng(seed), effects=effects)
    side = int(round(size * window_factor / camera.metres_per_pixel(ALTITUDE_M)))
    u0 = int(round(camera.width / 2.0 - side / 2.0))
    v0 = int(round(camera.height / 2.0 - side / 2.0))
    return frame.image[v0:v0 + side, u0:u0 + side].copy()
