"""Rendered datasets: random plantation scenes, annotated camera frames and the paper's crop protocol.

Scenes are small random plots (a few rows of mixed species, sometimes overlapping crowns, roofs and road
crossings) seen by the 352x288 camera from 1.0-1.5 m at random positions and yaw, with random camera effects.
With ``touching_rate`` (``foranav synth --touching``) a tree of a row is, with that probability, moved up
against the previous one so that the two crowns touch on one line, as ``foranav plantation`` places its
clusters (centre distance = sum of the radii + 0..TOUCH_TOLERANCE_M); without it the scenes are the original
ones (same random draws, same bytes).

Crop protocol (paper, Section IV-A): a positive crop is a square window around one complete tree of a target
species (window = 1.15-1.45 x the crown box, centre jittered); a negative crop is a window with no complete
target tree inside. Negative categories: look-alike trees (non-target species), roofs, road crossings, partial
target trees (the window cuts the crown) and background.
Everything here is pure: seeds in, images and records out; cmd_synth writes the files.
"""
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from host_tools.maps import SPECIES, PlantationMap, Tree, WorldObject
from host_tools.plantation import TOUCH_TOLERANCE_M
from host_tools.sim.camera import CameraModel, Pose
from host_tools.sim.crowns import Appearance
from host_tools.sim.world import Frame, ObjectInView, TreeInView, World, random_effects

FRAMES_PER_SCENE = 8
WINDOW_FACTOR = (1.15, 1.45)
CENTRE_JITTER = 0.08  # of the crown box
NEGATIVE_QUOTAS = (("lookalike", 0.35), ("object", 0.2), ("partial", 0.2), ("background", 0.25))
PHOTO_NEGATIVE_QUOTAS = (("partial", 0.5), ("background", 0.5))  # a photo of one species has no look-alikes
PHOTO_HEIGHT_RANGE = (0.8, 1.2)  # views over a photo map: its altitude times this
PLOT_M = (2.2, 1.8)  # plot size (x, y)
MAX_SCENES_PER_CROP = 4  # give up (bug guard) if a scene yields far fewer crops than expected


@dataclass(frozen=True)
class Crop:
    image: np.ndarray
    positive: bool
    category: str  # species (positive or look-alike), roof, road_cross, partial, background
    frame_index: int  # index of the source frame in generation order
    window: tuple  # (x0, y0, side) in the source frame


@dataclass(frozen=True)
class AnnotatedFrame:
    image: np.ndarray
    boxes: tuple  # ((x_center, y_center, width, height, label), ...) complete trees and objects only


def random_scene(rng: np.random.Generator, target_species: str, name: str = "synth",
                 touching_rate: float | None = None) -> PlantationMap:
    """A small random plot: rows of trees (targets and look-alikes), sometimes clusters, roofs and crossings.

    touching_rate: probability that a tree touches the previous tree of its row (see the module docstring);
    None draws nothing for it, so the scenes stay those of the original generator.
    """
    altitude = float(rng.uniform(1.0, 1.5))
    lookalikes = [s for s in SPECIES if s not in target_species]
    trees = []
    rows = int(rng.integers(2, 4))
    for r in range(rows):
        y = -PLOT_M[1] / 2 + (r + 0.5) * PLOT_M[1] / rows + rng.normal(0, 0.05)
        x = -PLOT_M[0] / 2 + rng.uniform(0.1, 0.3)
        previous = None  # the previous tree of this row, None after a gap
        while x < PLOT_M[0] / 2:
            crown = float(rng.uniform(0.3, 0.45))
            if rng.random() < 0.5:
                species = target_species[int(rng.integers(len(target_species)))]
            else:
                species = lookalikes[int(rng.integers(len(lookalikes)))]
            if touching_rate is not None and previous is not None and rng.random() < touching_rate:
                x = previous.x + (previous.crown_m + crown) / 2.0 + float(rng.uniform(0.0, TOUCH_TOLERANCE_M))
                previous = _add_tree(trees, x, previous.y, species, crown, target_species)
            elif rng.random() > 0.12:  # some gaps in the rows
                previous = _add_tree(trees, x, y + rng.normal(0, 0.06), species, crown, target_species)
            else:
                previous = None
            # usually a crown apart, sometimes closer: overlapping canopies
            x += crown * (rng.uniform(0.75, 0.95) if rng.random() < 0.2 else rng.uniform(1.1, 1.6))
    objects = []
    for _ in range(int(rng.integers(0, 3))):
        kind = "roof" if rng.random() < 0.5 else "road_cross"
        objects.append(WorldObject(kind, float(rng.uniform(-1.0, 1.0)), float(rng.uniform(-0.9, 0.9)),
                                   float(rng.uniform(0.3, 0.5)), float(rng.uniform(0, 180))))
    # objects replace the trees they would overlap
    trees = [t for t in trees if all(math.hypot(t.x - o.x, t.y - o.y) > (t.crown_m + o.size_m) * 0.6
                                     for o in objects)]
    waypoints = ((-PLOT_M[0] / 2, 0.0), (PLOT_M[0] / 2, 0.0))
    return PlantationMap(name, altitude, waypoints, tuple(trees), tuple(objects), int(rng.integers(2 ** 31)),
                         target_species[0])


def _add_tree(trees: list, x: float, y: float, species: str, crown: float, target_species: Sequence[str]) -> Tree:
    tree = Tree(len(trees) + 1, float(x), float(y), species, crown, species in target_species)
    trees.append(tree)
    return tree


def scene_frames(rng: np.random.Generator, scene: PlantationMap, camera: CameraModel, count: int,
                 appearance: Appearance | None = None) -> list[Frame]:
    """Render count frames of a scene at random poses: [(image, trees_in_view, objects_in_view)]."""
    world = World.from_map(scene, margin_m=0.5, appearance=appearance)
    out = []
    for _ in range(count):
        if scene.photo is not None:
            pose = photo_pose(rng, scene, camera)
        else:
            pose = Pose(float(rng.uniform(-0.9, 0.9)), float(rng.uniform(-0.7, 0.7)),
                        scene.altitude_m * float(rng.uniform(0.95, 1.05)),
                        float(rng.choice([0.0, rng.uniform(-180, 180)])))
        frame = world.render(camera, pose, rng=rng, effects=random_effects(rng))
        out.append((frame.image, frame.trees, frame.objects))
    return out


def photo_pose(rng: np.random.Generator, scene: PlantationMap, camera: CameraModel) -> Pose:
    """A random pose over a photo map whose level view lies inside the photo: height the map's
    x PHOTO_HEIGHT_RANGE, yaw 0 (as the app flies) or any."""
    z = scene.altitude_m * float(rng.uniform(*PHOTO_HEIGHT_RANGE))
    x_min, x_max, y_min, y_max = scene.photo.extent_m
    half = math.hypot(camera.width, camera.height) / 2.0 * camera.metres_per_pixel(z)  # any yaw
    x = float(rng.uniform(min(0.0, x_min + half), max(0.0, x_max - half)))
    y = float(rng.uniform(min(0.0, y_min + half), max(0.0, y_max - half)))
    return Pose(x, y, z, float(rng.choice([0.0, rng.uniform(-180, 180)])))


def frame_boxes(trees: Sequence[TreeInView], objects: Sequence[ObjectInView]) -> tuple:
    """Annotation boxes of the complete trees and objects of a frame (partial ones are not annotated)."""
    boxes = [(t.u, t.v, t.w, t.h, t.species) for t in trees if t.complete]
    boxes += [(o.u, o.v, o.w, o.h, o.kind) for o in objects if o.complete]
    return tuple(boxes)


def crop_candidates(rng: np.random.Generator, image: np.ndarray, trees: Sequence[TreeInView],
                    objects: Sequence[ObjectInView], target_species: str, frame_index: int) -> list:
    """All crops one frame offers: positives, and negatives by category."""
    height, width = image.shape[:2]
    targets = [t for t in trees if t.complete and t.species in target_species]
    out = []

    def window_around(u, v, size, jitter=True):
        side = size * rng.uniform(*WINDOW_FACTOR)
        cu = u + (rng.normal(0, CENTRE_JITTER * size) if jitter else 0.0)
        cv = v + (rng.normal(0, CENTRE_JITTER * size) if jitter else 0.0)
        return _fit(cu - side / 2, cv - side / 2, side, width, height)

    def add(window, positive, category):
        if window is None:
            return
        inside = [t for t in targets if _contains(window, t)]
        if positive != bool(inside) or (positive and len(inside) != 1):
            return  # a positive holds exactly one complete target; a negative none
        x0, y0, side = window
        out.append(Crop(image[y0:y0 + side, x0:x0 + side].copy(), positive, category, frame_index, window))

    for t in trees:
        if not t.complete:
            continue
        if t.species in target_species:
            add(window_around(t.u, t.v, t.w), True, t.species)
            # the same tree cut by the window: shift by half to two thirds of the crown
            angle = rng.uniform(0, 2 * math.pi)
            shift = rng.uniform(0.45, 0.7) * t.w
            add(window_around(t.u + shift * math.cos(angle), t.v + shift * math.sin(angle), t.w, False),
                False, "partial")
        else:
            add(window_around(t.u, t.v, t.w), False, t.species)
    for o in objects:
        if o.complete:
            add(window_around(o.u, o.v, max(o.w, o.h)), False, o.kind)
    for _ in range(2):
        side = int(rng.uniform(70, 150))
        if side < min(width, height):
            add((int(rng.integers(0, width - side)), int(rng.integers(0, height - side)), side), False,
                "background")
    return out


def _fit(x0, y0, side, width, height):
    """Integer window inside the frame, or None."""
    x0, y0, side = int(round(x0)), int(round(y0)), int(round(side))
    if side < 16 or x0 < 0 or y0 < 0 or x0 + side > width or y0 + side > height:
        return None
    return x0, y0, side


def _contains(window, tree):
    x0, y0, side = window
    return (tree.u - tree.w / 2 >= x0 and tree.u + tree.w / 2 <= x0 + side
            and tree.v - tree.h / 2 >= y0 and tree.v + tree.h / 2 <= y0 + side)


def negative_group(category: str) -> str:
    if category in ("partial", "background"):
        return category
    if category in ("roof", "road_cross"):
        return "object"
    return "lookalike"


def generate(seed: int, count: int, frame_count: int, target_species: Sequence[str] = ("oil_palm",),
             camera: CameraModel | None = None, appearance: Appearance | None = None,
             touching_rate: float | None = None,
             photo_maps: Sequence[PlantationMap] = ()) -> tuple[list, list, list]:
    """(positives, negatives, frames): count crops of each class and frame_count annotated frames.

    Deterministic for a seed. ``photo_maps``: the scenes are these photo maps (random views inside their
    photos) instead of random plots. ``touching_rate``: see ``random_scene`` (None: the original scenes). ``appearance`` (crowns.Appearance): photo crowns / ground photo for the scenes. Negatives follow NEGATIVE_QUOTAS, topped up from any category when one runs short.
    """
    camera = camera or CameraModel()
    rng = np.random.default_rng([seed & 0xFFFFFFFF, 2024])
    quotas = {name: int(round(share * count)) for name, share in (PHOTO_NEGATIVE_QUOTAS if photo_maps
                                                                   else NEGATIVE_QUOTAS)}
    positives, pools, frames = [], {name: [] for name, _ in NEGATIVE_QUOTAS}, []
    frame_index = 0
    max_scenes = MAX_SCENES_PER_CROP * (count + frame_count) + 4
    for _ in range(max_scenes):
        if len(positives) >= count and len(frames) >= frame_count and \
                all(len(pools[k]) >= quotas[k] for k in quotas):
            break
        if photo_maps:  # frames over the photographs, their boxes the ground truth
            scene = photo_maps[int(rng.integers(len(photo_maps)))]
        else:
            scene = random_scene(rng, tuple(target_species), touching_rate=touching_rate)
        for image, trees, objects in scene_frames(rng, scene, camera, FRAMES_PER_SCENE, appearance):
            if len(frames) < frame_count:
                frames.append(AnnotatedFrame(image, frame_boxes(trees, objects)))
            for crop in crop_candidates(rng, image, trees, objects, target_species, frame_index):
                if crop.positive:
                    positives.append(crop)
                else:
                    pools[negative_group(crop.category)].append(crop)
            frame_index += 1
    negatives = []
    for name in quotas:
        negatives += pools[name][:quotas[name]]
    leftovers = [c for name in quotas for c in pools[name][quotas[name]:]]
    negatives += leftovers[:max(0, count - len(negatives))]
    return positives[:count], negatives[:count], frames[:frame_count]
