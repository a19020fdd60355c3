"""The plantation world: an orthomosaic rendered once per map, and camera frames warped out of it.

``World.from_map(pmap)`` draws the ground, cast shadows, look-alike objects and tree crowns into one top-down
image (plus a few 2x-downsampled levels); ``world.render(camera, pose)`` is then one ``cv2.warpAffine`` of the
level closest to the camera's ground resolution plus optional per-frame effects, and the ground truth of every
tree and object in view. Same map seed + pose (+ rng seed when effects are on) = same frame.

Mosaic layout: image up is world +x and image left is world +y (what a camera at yaw 0 sees), so the
mosaic pixel of world (x, y) is ((y_max - y) / mpp, (x_max - x) / mpp) in continuous coordinates.

A photo map's world (``maps.PhotoGround``) is the photograph itself: no ground is drawn and no crown pasted;
the photo (checked against the map's checksum) is the finest level, area-averaged down to twice the camera's
ground resolution at the map altitude when it is finer than that, and outside it the frame shows the no-data
colour ``NO_DATA_BGR`` (never invented texture).

Attitude: a pose with roll or pitch (the firmware plant's true body attitude) is rendered through the ground
plane's homography (``CameraModel.pixel_to_world_homography``, one ``cv2.warpPerspective``); a level pose
takes the affine warp, so the nadir frames keep their bytes.
"""
import hashlib
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import NamedTuple

import cv2
import numpy as np

from host_tools import images
from host_tools.sim import broadleaf, crowns, ground, objects, palms
from host_tools.errors import ForaNavError
from host_tools.maps import SPECIES, PhotoGround, PlantationMap, Tree
from host_tools.sim.camera import METRES_PER_PIXEL_PER_METRE_AT_352, CameraModel, Pose
from host_tools.sim.sprite import Sprite, composite, darken

SUPERSAMPLING = 2  # the finest level has twice the ground resolution of a 352x288 camera at the map altitude
LEVELS = 4  # finest + 3 halvings: good down to 1/8 the resolution (8x the altitude)
# the whole ground is rendered at once, ~45 bytes per finest pixel while it is built (float ground, strokes,
# sprites): a map needing more is refused in one line (a map 1 km long once asked numpy for terabytes)
MAX_MOSAIC_PIXELS = 100 * 10 ** 6
NO_DATA_BGR = (0, 0, 0)  # outside a photo map's photo: black, as a GIS viewer shows no-data
SHADOW_STRENGTH = 0.45
TREE_HEIGHT_PER_CROWN = 0.5  # model trees: height about half the crown diameter (sets the shadow length)


class TreeInView(NamedTuple):
    """Ground truth of one tree in a frame: pixel centre (u, v), box size (w, h) and world position."""
    id: int
    species: str
    target: bool
    u: float
    v: float
    w: float
    h: float
    complete: bool  # the whole crown is inside the frame
    x: float = 0.0
    y: float = 0.0


class ObjectInView(NamedTuple):
    """Ground truth of one look-alike object (roof, road_cross): axis-aligned pixel box of its footprint."""
    index: int
    kind: str
    u: float
    v: float
    w: float
    h: float
    complete: bool
    x: float = 0.0
    y: float = 0.0


@dataclass
class Frame:
    image: np.ndarray  # HxWx3 uint8 BGR
    pose: object  # camera.Pose of the MAV
    trees: list = field(default_factory=list)  # [TreeInView] (in view, partially or completely)
    objects: list = field(default_factory=list)  # [ObjectInView]


@dataclass(frozen=True)
class Effects:
    """Per-frame camera effects; all off by default (the fast path)."""
    gain: float = 1.0  # exposure
    blur_sigma: float = 0.0  # defocus / motion, pixels
    noise_sigma: float = 0.0  # sensor noise, grey levels
    jpeg_quality: int = 0  # 0 = no compression round trip

    @property
    def active(self) -> bool:
        return self.gain != 1.0 or self.blur_sigma > 0 or self.noise_sigma > 0 or self.jpeg_quality > 0

    def apply(self, image: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        if self.gain != 1.0:
            image = cv2.convertScaleAbs(image, alpha=self.gain)
        if self.blur_sigma > 0:
            image = cv2.GaussianBlur(image, (0, 0), self.blur_sigma)
        if self.noise_sigma > 0:
            noise = _noise_patch(rng, image.shape, self.noise_sigma)
            image = cv2.add(image, noise, dtype=cv2.CV_8U)
        if self.jpeg_quality > 0:
            ok, data = cv2.imencode(".jpg", image, [cv2.IMWRITE_JPEG_QUALITY, int(self.jpeg_quality)])
            image = cv2.imdecode(data, cv2.IMREAD_COLOR)
        return image


_NOISE_BANK = {}


def _noise_patch(rng, shape, sigma):
    """Gaussian sensor noise (float32) for one frame: a random window of a fixed unit-variance noise field.

    Drawing fresh normals per frame costs more than the whole warp; a random offset into a field twice the
    frame size gives independent-looking noise per frame at the cost of a slice.
    """
    bank = _NOISE_BANK.get(shape)
    if bank is None:
        bank = np.random.default_rng(17).standard_normal((2 * shape[0], 2 * shape[1]) + shape[2:], np.float32)
        _NOISE_BANK[shape] = bank
    dy, dx = int(rng.integers(0, shape[0])), int(rng.integers(0, shape[1]))
    return bank[dy:dy + shape[0], dx:dx + shape[1]] * np.float32(sigma)


NO_EFFECTS = Effects()
SENSOR_EFFECTS = Effects(blur_sigma=0.6, noise_sigma=3.0, jpeg_quality=85)  # a plausible JeVois frame


def random_effects(rng: np.random.Generator) -> Effects:
    """Effects drawn at random for dataset variety (exposure, blur, noise, compression)."""
    # mostly sharp, as the JeVois is at 352x288 (a binned sensor); a heavy blur in one frame of eight
    return Effects(gain=float(rng.uniform(0.8, 1.2)),
                   blur_sigma=float(rng.choice([0.0, 0.0, 0.0, 0.4, 0.4, 0.7, 0.7, 1.1])),
                   noise_sigma=float(rng.uniform(0.0, 5.0)), jpeg_quality=int(rng.choice([0, 95, 85, 70])))


@dataclass(frozen=True)
class Lighting:
    light: float  # overall brightness factor
    sun_dir: tuple  # unit vector in mosaic image coordinates pointing towards the sun
    shadow_per_height: float  # shadow length per metre of object height (cot of the sun's elevation)

    @classmethod
    def random(cls, rng: np.random.Generator) -> "Lighting":
        azimuth = rng.uniform(0, 2 * math.pi)
        elevation = math.radians(rng.uniform(45, 80))
        return cls(float(rng.uniform(0.85, 1.15)), (math.cos(azimuth), math.sin(azimuth)),
                   1.0 / math.tan(elevation))


class World:
    """An orthomosaic of one map with the ground truth needed to annotate frames."""

    def __init__(self, pmap: PlantationMap, levels: list[np.ndarray], bounds: tuple[float, float, float, float],
                 metres_per_pixel: float, seed: int, lighting: Lighting, object_corners: list,
                 photo_crowns: dict | None = None, no_data: bool = False):
        self.map = pmap
        self.no_data = no_data  # outside the mosaic: the no-data colour (a photo), else mirrored ground
        self.levels = levels  # [uint8 HxWx3], finest first, each half the previous
        self.bounds = bounds  # (x_min, x_max, y_min, y_max) metres
        self.metres_per_pixel = metres_per_pixel  # of the finest level
        self.seed = seed
        self.lighting = lighting
        self._tree_xy = np.array([(t.x, t.y) for t in pmap.trees], float).reshape(-1, 2)
        self._tree_crown = np.array([t.crown_m for t in pmap.trees], float)
        self._object_corners = object_corners  # [(4, 2) world corners] per object
        self.photo_crowns = dict(photo_crowns or {})  # tree id -> "file.csv:line" of the photo crown drawn

    @property
    def photo_species(self) -> tuple[str, ...]:
        """The species of this map drawn from photographs (the others are drawn by the renderers)."""
        ids = set(self.photo_crowns)
        return tuple(s for s in SPECIES if any(t.species == s and t.id in ids for t in self.map.trees))

    # ---- building ------------------------------------------------------------------------------------

    @classmethod
    def from_map(cls, pmap: PlantationMap, seed: int | None = None, metres_per_pixel: float | None = None,
                 margin_m: float | None = None, appearance: crowns.Appearance | None = None,
                 crown_trees: Sequence[Tree] | None = None) -> "World":
        """Render the map's orthomosaic once. ``seed`` overrides the map's seed (ground and tree variation).

        ``metres_per_pixel`` sets the finest level (default: half a 352x288 pixel at the map altitude; use a
        finer one for 1280x1024 frames); ``margin_m`` the ground shown around the map's content (default: a
        camera footprint at the map altitude; beyond it the ground is mirrored). ``appearance``
        (crowns.Appearance, optional): photo crowns for the species of its library and a ground photo;
        ``crown_trees`` the trees the crowns are dealt to (default the map's; a map with a tree removed passes
        the full map's, so every other tree keeps its crown).
        """
        seed = pmap.seed if seed is None else int(seed)
        mpp = metres_per_pixel or METRES_PER_PIXEL_PER_METRE_AT_352 * pmap.altitude_m / SUPERSAMPLING
        if pmap.photo is not None:
            return cls.from_photo(pmap, mpp, seed)
        bounds = _bounds(pmap, margin_m)
        x_min, x_max, y_min, y_max = bounds
        multiple = 2 ** (LEVELS - 1)
        width = int(math.ceil((y_max - y_min) / mpp / multiple)) * multiple
        height = int(math.ceil((x_max - x_min) / mpp / multiple)) * multiple
        if width * height > MAX_MOSAIC_PIXELS:
            raise ForaNavError("%s: its ground (%.1f x %.1f m at %.2f mm per pixel, for altitude_m %g) needs %d Mpx; "
                               "the simulator renders at most %d Mpx: a smaller map or a higher flight"
                               % (pmap.source or pmap.name, x_max - x_min, y_max - y_min, mpp * 1000, pmap.altitude_m,
                                  width * height // 10 ** 6, MAX_MOSAIC_PIXELS // 10 ** 6))
        bounds = (x_max - height * mpp, x_max, y_max - width * mpp, y_max)
        rng = np.random.default_rng([seed & 0xFFFFFFFF, 0])
        lighting = Lighting.random(rng)
        image = ground.render_ground(rng, height, width, mpp, lighting.light)
        if appearance is not None and appearance.ground_photo is not None:
            # the procedural ground is still drawn (same rng draws) so that a photo ground changes nothing else
            image = crowns.ground_from_photo(appearance.ground_photo, appearance.spec.ground_gsd_m, height, width,
                                             mpp, lighting.light)
        library = appearance.library if appearance is not None else None
        photos = crowns.assign(library, crown_trees or pmap.trees, seed) if library is not None else {}
        drawn_ids = {t.id for t in pmap.trees}
        photos = {i: p for i, p in photos.items() if i in drawn_ids}
        shadows = appearance.spec.crown_shadows if appearance is not None else False
        corners = _draw_map(image, pmap, seed, mpp, bounds, lighting, photos, shadows)
        finest = np.empty(image.shape, np.uint8)
        for rows in ground.row_bands(height):
            finest[rows] = np.clip(image[rows] + 0.5, 0, 255).astype(np.uint8)
        del image  # the float ground is the largest array of a world: gone before the pyramid is built
        levels = _pyramid(finest)
        return cls(pmap, levels, bounds, mpp, seed, lighting, corners,
                   {tree_id: crown.source for tree_id, (crown, _) in photos.items()})

    @classmethod
    def from_photo(cls, pmap: PlantationMap, metres_per_pixel: float, seed: int = 0) -> "World":
        """The world of a photo map: its photo (no drawing), at most ``metres_per_pixel`` fine."""
        photo = pmap.photo
        image = read_photo(photo, pmap.source or pmap.name)
        mpp = photo.metres_per_pixel
        if mpp < metres_per_pixel:  # finer than the camera will ever use at this altitude: area-average it down
            width = max(1, int(round(photo.width_px * mpp / metres_per_pixel)))
            height = max(1, int(round(photo.height_px * mpp / metres_per_pixel)))
            image = cv2.resize(image, (width, height), interpolation=cv2.INTER_AREA)
            mpp = photo.width_px * photo.metres_per_pixel / width
        x_min, x_max, y_min, y_max = photo.extent_m
        bounds = (x_max - image.shape[0] * mpp, x_max, y_max - image.shape[1] * mpp, y_max)
        return cls(pmap, _pyramid(image), bounds, mpp, seed, Lighting(1.0, (0.7, -0.7), 0.0), [], no_data=True)

    # ---- camera frames -------------------------------------------------------------------------------

    def render(self, camera: CameraModel, pose: Pose, rng: np.random.Generator | None = None,
               effects: Effects = NO_EFFECTS) -> Frame:
        """One camera frame at ``pose`` with the ground truth of the trees and objects in view.

        ``rng`` (numpy Generator) drives per-frame noise; when effects need it and none is given, a generator
        seeded by the world seed is used, so the call stays deterministic.
        """
        if not pose.z > 0:
            raise ValueError("camera height must be positive, got %r" % (pose.z,))
        level, mpp = self._level_for(camera.metres_per_pixel(pose.z))
        border = dict(borderMode=cv2.BORDER_CONSTANT, borderValue=NO_DATA_BGR) if self.no_data else \
            dict(borderMode=cv2.BORDER_REFLECT_101)
        if pose.tilted:
            image = cv2.warpPerspective(self.levels[level], self._camera_to_mosaic_homography(camera, pose, mpp),
                                        (camera.width, camera.height), flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP,
                                        **border)
        else:
            matrix = self._camera_to_mosaic(camera, pose, mpp)
            image = cv2.warpAffine(self.levels[level], matrix, (camera.width, camera.height),
                                   flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP, **border)
        if effects.active:
            image = effects.apply(image, rng if rng is not None else np.random.default_rng(self.seed))
        return Frame(image, pose, self.trees_in_view(camera, pose), self.objects_in_view(camera, pose))

    def trees_in_view(self, camera: CameraModel, pose: Pose) -> list[TreeInView]:
        if not len(self._tree_crown):
            return []
        u, v = camera.world_to_pixel(pose, self._tree_xy[:, 0], self._tree_xy[:, 1])
        size = self._tree_crown / camera.metres_per_pixel(pose.z)
        seen = _overlaps(u, v, size, size, camera)
        whole = _inside(u, v, size, size, camera)
        return [TreeInView(t.id, t.species, t.target, float(u[i]), float(v[i]), float(size[i]), float(size[i]),
                           bool(whole[i]), t.x, t.y)
                for i, t in enumerate(self.map.trees) if seen[i]]

    def objects_in_view(self, camera: CameraModel, pose: Pose) -> list[ObjectInView]:
        out = []
        for index, (obj, corners) in enumerate(zip(self.map.objects, self._object_corners)):
            u, v = camera.world_to_pixel(pose, corners[:, 0], corners[:, 1])
            cu, cv_ = (u.min() + u.max()) / 2.0, (v.min() + v.max()) / 2.0
            w, h = u.max() - u.min(), v.max() - v.min()
            if _overlaps(cu, cv_, w, h, camera):
                out.append(ObjectInView(index, obj.kind, float(cu), float(cv_), float(w), float(h),
                                        bool(_inside(cu, cv_, w, h, camera)), obj.x, obj.y))
        return out

    def _level_for(self, camera_mpp):
        """The coarsest level that is still at least as fine as the camera (no aliasing, least work)."""
        level = 0
        while level + 1 < len(self.levels) and self.metres_per_pixel * 2 ** (level + 1) <= camera_mpp * 1.05:
            level += 1
        return level, self.metres_per_pixel * 2 ** level

    def _camera_to_mosaic(self, camera, pose, level_mpp):
        """2x3 matrix: camera pixel index (col, row) -> mosaic level pixel index, for warpAffine."""
        to_world = camera.pixel_to_world_affine(pose)  # continuous (u, v, 1) -> (x, y)
        x_max, y_max = self.bounds[1], self.bounds[3]
        # world -> continuous mosaic (col, row) = ((y_max - y) / mpp, (x_max - x) / mpp)
        to_mosaic = np.array([[0.0, -1.0 / level_mpp, y_max / level_mpp],
                              [-1.0 / level_mpp, 0.0, x_max / level_mpp]])
        m = to_mosaic[:, :2] @ to_world
        m[:, 2] += to_mosaic[:, 2]
        # pixel index i <-> continuous i + 0.5 on both sides
        m[:, 2] += m[:, :2] @ np.array([0.5, 0.5]) - 0.5
        return m

    def _camera_to_mosaic_homography(self, camera, pose, level_mpp):
        """3x3 matrix: camera pixel index -> mosaic level pixel index through the tilted camera's ground plane."""
        x_max, y_max = self.bounds[1], self.bounds[3]
        to_mosaic = np.array([[0.0, -1.0 / level_mpp, y_max / level_mpp],
                              [-1.0 / level_mpp, 0.0, x_max / level_mpp], [0.0, 0.0, 1.0]])
        index_to_continuous = np.array([[1.0, 0.0, 0.5], [0.0, 1.0, 0.5], [0.0, 0.0, 1.0]])
        continuous_to_index = np.array([[1.0, 0.0, -0.5], [0.0, 1.0, -0.5], [0.0, 0.0, 1.0]])
        return continuous_to_index @ to_mosaic @ camera.pixel_to_world_homography(pose) @ index_to_continuous

    def mosaic_pixel(self, x: float, y: float, level: int = 0) -> tuple[float, float]:
        """Continuous mosaic pixel (col, row) of world (x, y) at a level (for pictures and tests)."""
        mpp = self.metres_per_pixel * 2 ** level
        return (self.bounds[3] - y) / mpp, (self.bounds[1] - x) / mpp


def read_photo(photo: PhotoGround, map_name: str) -> np.ndarray:
    """The photo of a photo map, refused unless its bytes are the ones the map was written with."""
    path = photo.resolved or photo.path
    data, image = images.read_image_file(path)
    if hashlib.sha256(data).hexdigest() != photo.sha256:
        raise ForaNavError("%s: photo.sha256: %s has changed since the map was written (checksum differs)"
                           % (map_name, path))
    if image.shape[:2] != (photo.height_px, photo.width_px):
        raise ForaNavError("%s: photo: %s is %dx%d px, the map says %dx%d" % (map_name, path, image.shape[1],
                           image.shape[0], photo.width_px, photo.height_px))
    return image


def _draw_map(image, pmap, seed, mpp, bounds, lighting, photos=None, photo_shadows=False):
    """Draw the map's objects and crowns (and their shadows) onto the ground; returns object footprints.

    ``photos``: {tree id: (Crown, angle)} trees drawn from photographs, casting a shadow only with
    ``photo_shadows`` (the photo has its own shading).
    """
    photos = photos or {}
    x_max, y_max = bounds[1], bounds[3]

    def to_px(x, y):  # world -> continuous mosaic pixel (col, row)
        return (y_max - y) / mpp, (x_max - x) / mpp

    sprites = []  # (sprite, height_m) in drawing order: objects under trees
    corners = []
    for index, obj in enumerate(pmap.objects):
        sprite, footprint = _render_object(obj, index, seed, mpp, to_px, lighting)
        sprites.append((sprite, 0.25 * obj.size_m if obj.kind == "roof" else 0.0))
        corners.append(footprint)
    for index, tree in enumerate(pmap.trees):
        height_m = TREE_HEIGHT_PER_CROWN * tree.crown_m
        if tree.id in photos:
            crown, angle = photos[tree.id]
            col, row = to_px(tree.x, tree.y)
            sprite = crowns.crown_sprite(crown, col, row, tree.crown_m / mpp, angle, lighting.light)
            sprites.append((sprite, height_m if photo_shadows else 0.0))
        else:
            sprites.append((_render_tree(tree, index, seed, mpp, to_px, lighting), height_m))
    for sprite, height_m in sprites:  # shadows first: they fall on the ground, not on the canopies
        if height_m > 0:
            _cast_shadow(image, sprite, height_m / mpp, lighting)
    for sprite, _ in sprites:
        composite(image, sprite)
    return corners


def _pyramid(finest):
    """The finest level and LEVELS - 1 halvings (area averaging: no aliasing of the fine leaflets)."""
    levels = [finest]
    for _ in range(LEVELS - 1):
        finer = levels[-1]
        levels.append(cv2.resize(finer, (finer.shape[1] // 2, finer.shape[0] // 2), interpolation=cv2.INTER_AREA))
    return levels


def _overlaps(u, v, w, h, camera):
    return (u + w / 2 > 0) & (u - w / 2 < camera.width) & (v + h / 2 > 0) & (v - h / 2 < camera.height)


def _inside(u, v, w, h, camera):
    return (u - w / 2 >= 0) & (u + w / 2 <= camera.width) & (v - h / 2 >= 0) & (v + h / 2 <= camera.height)


def _bounds(pmap, margin_m=None):
    """World rectangle the mosaic covers: everything in the map plus a camera footprint of margin."""
    xs = [p[0] for p in pmap.waypoints] + [t.x for t in pmap.trees] + [o.x for o in pmap.objects]
    ys = [p[1] for p in pmap.waypoints] + [t.y for t in pmap.trees] + [o.y for o in pmap.objects]
    reach = max([t.crown_m for t in pmap.trees] + [o.size_m for o in pmap.objects] + [0.0])
    if margin_m is None:
        margin_m = 0.75 * pmap.altitude_m + 0.2  # 0.71 x altitude = half diagonal of a 352x288 view
    margin = reach + margin_m
    return min(xs) - margin, max(xs) + margin, min(ys) - margin, max(ys) + margin


def _element_rng(seed, kind, index):
    """Each tree/object draws from its own stream: adding one does not change the others."""
    return np.random.default_rng([seed & 0xFFFFFFFF, kind, index])


def _render_tree(tree, index, seed, mpp, to_px, lighting):
    rng = _element_rng(seed, 1, index)
    col, row = to_px(tree.x, tree.y)
    diameter = tree.crown_m / mpp
    light = lighting.light * rng.uniform(0.9, 1.1)
    return render_species(tree.species, rng, col, row, diameter, light, lighting.sun_dir)


def render_species(species: str, rng: np.random.Generator, col: float, row: float, diameter_px: float,
                   light: float = 1.0, sun_dir: tuple[float, float] = (0.7, -0.7)) -> Sprite:
    """Draw one crown of a species centred at a continuous image position -> Sprite."""
    if species in palms.STYLES:
        return palms.render_palm(palms.STYLES[species], rng, col, row, diameter_px, light, sun_dir)
    if species == "citrus":
        return broadleaf.render_citrus(rng, col, row, diameter_px, light, sun_dir)
    if species == "olive":
        return broadleaf.render_olive(rng, col, row, diameter_px, light, sun_dir)
    raise ValueError("no renderer for species %r" % species)


def _render_object(obj, index, seed, mpp, to_px, lighting):
    """Sprite and world footprint corners (4, 2) of a look-alike object."""
    rng = _element_rng(seed, 2, index)
    col, row = to_px(obj.x, obj.y)
    yaw = math.radians(obj.yaw_deg)
    # a world direction (cos, sin) appears in the mosaic as (-sin, -cos): image angle = atan2(-cos, -sin)
    yaw_img = math.atan2(-math.cos(yaw), -math.sin(yaw))
    size_px = obj.size_m / mpp
    if obj.kind == "roof":
        aspect = float(rng.uniform(0.6, 1.0))
        sprite = objects.render_roof(rng, col, row, size_px, aspect, yaw_img, lighting.light, lighting.sun_dir)
        half_a, half_c = objects.roof_footprint(obj.size_m, aspect)
    else:
        sprite = objects.render_road_cross(rng, col, row, size_px, yaw_img, lighting.light)
        half_a = half_c = obj.size_m / 2.0
    axis = np.array([math.cos(yaw), math.sin(yaw)])
    across = np.array([-axis[1], axis[0]])
    centre = np.array([obj.x, obj.y])
    footprint = np.array([centre + sa * half_a * axis + sc * half_c * across
                          for sa, sc in ((-1, -1), (1, -1), (1, 1), (-1, 1))])
    return sprite, footprint


def _cast_shadow(image, sprite, height_px, lighting):
    """Darken the ground where the sprite's silhouette falls, shifted away from the sun, soft-edged."""
    shift = height_px * lighting.shadow_per_height
    dx, dy = -lighting.sun_dir[0] * shift, -lighting.sun_dir[1] * shift
    sigma = max(1.0, 0.06 * sprite.alpha.shape[0])
    pad = int(math.ceil(3 * sigma))  # room for the soft edge, or the blur would end in a square
    mask = cv2.GaussianBlur(cv2.copyMakeBorder(sprite.alpha, pad, pad, pad, pad, cv2.BORDER_CONSTANT, value=0),
                            (0, 0), sigma)
    origin = (sprite.origin[0] - pad + int(round(dx)), sprite.origin[1] - pad + int(round(dy)))
    darken(image, mask, origin, SHADOW_STRENGTH)
