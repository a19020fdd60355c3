"""Photo crowns: trees drawn from annotated aerial photographs instead of the procedural renderers.

A crown library is the boxes of one or more annotation CSVs (``host_tools/annotations.py``, the format of
``shared/data/real``), by label (``LABEL_SPECIES``)::

    oil_palm -> oil_palm     coconut -> coconut     olive_tree (or olive) -> olive
    date_palm -> date_palm   citrus -> citrus       every other label (mango, banana, papaya, tree,
                                                    tree_alive, tree_dead, roof, ...) -> unused

A box is a usable crown when it lies wholly inside its image and is at least ``MIN_CROWN_PX`` on its short
side; a box cut by the image edge or too small is skipped (counted); a box whose centre lies outside its image
is an error (the CSV does not describe that image). Loading cuts every usable box out of its photo once
(``Crown.patch``, the box plus nothing else); the world then scales, rotates and masks one cut-out per tree when
it renders its orthomosaic, i.e. once per flight, never per frame.

Per tree (``assign``): trees of a species, in id order, take that species' crowns in an order shuffled by the
world seed, so different trees get different crowns until the library runs out, and the same map and seed give
the same crowns. The rotation comes from the seed and the tree id. The soft mask is an ellipse inscribed in the
box that fades out over its outer ``MASK_FEATHER``, so the neighbours that interlock into the box's corners do
not show.

Ground (``--ground IMAGE --ground-gsd M_PER_PX``): the photo scaled to the mosaic's ground resolution and tiled
(mirrored, so the tiles meet without a seam), times the world's light.
"""
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Iterable, Optional, Sequence

import cv2
import numpy as np

from host_tools.annotations import read_boxes
from host_tools.errors import ForaNavError
from host_tools.images import read_image as read_image_file
from host_tools.maps import SPECIES
from host_tools.sim.sprite import Sprite

LABEL_SPECIES = {"oil_palm": "oil_palm", "coconut": "coconut", "olive_tree": "olive", "olive": "olive",
                 "date_palm": "date_palm", "citrus": "citrus"}
MIN_CROWN_PX = 40  # smaller boxes would be blown up 4x or more at flight scale: a blur, not a crown
MASK_FEATHER = 0.18  # the soft mask falls from 1 to 0 over this outer fraction of the box's half axes
_SPECIES_STREAM = 3  # rng stream kinds (world.py uses 1 for trees, 2 for objects)
_ANGLE_STREAM = 4


@dataclass(frozen=True, eq=False)  # compared by identity: the patch is an array
class Crown:
    """One usable crown: its cut-out (the box's pixels, BGR uint8) and where it came from."""
    species: str
    patch: np.ndarray
    source: str  # "file.csv:line"


@dataclass
class CrownLibrary:
    """Usable crowns by species, plus what loading skipped (for the messages)."""
    crowns: dict  # species -> [Crown] in CSV order
    csv_paths: tuple
    skipped: dict = field(default_factory=dict)  # reason -> count

    @property
    def species(self) -> tuple[str, ...]:
        return tuple(s for s in SPECIES if self.crowns.get(s))

    def count(self, species: str) -> int:
        return len(self.crowns.get(species, ()))

    def check_covers(self, species: Sequence[str], what: str) -> None:
        """Raise unless the library has a crown for at least one of ``species`` (the species of ``what``)."""
        if not any(self.crowns.get(s) for s in species):
            skipped = ", ".join("%d %s" % (n, reason) for reason, n in sorted(self.skipped.items())) or "none"
            raise ForaNavError("%s: no usable crown for any species of %s (%s); library has %s; rows skipped: %s"
                               % (", ".join(str(p) for p in self.csv_paths), what, ", ".join(species),
                                  ", ".join("%s %d" % (s, self.count(s)) for s in self.species) or "nothing",
                                  skipped))


def load_library(csv_paths: Sequence, min_crown_px: float = MIN_CROWN_PX) -> CrownLibrary:
    """Read the CSVs and cut out every usable crown; ForaNavError naming the file and line on bad input."""
    crowns, skipped = {}, {}
    for csv_path in csv_paths:
        csv_path = Path(csv_path)
        images = {}
        # read_boxes skips blank lines, so the line number is recomputed here in the same way
        for line_no, box in _numbered_boxes(csv_path):
            species = LABEL_SPECIES.get(box.label)
            if species is None:
                skipped["unused label"] = skipped.get("unused label", 0) + 1
                continue
            image = images.get(box.image)
            if image is None:
                image = images[box.image] = _read_image(csv_path.parent / box.image, csv_path, line_no)
            height, width = image.shape[:2]
            if not (0 <= box.x_center <= width and 0 <= box.y_center <= height):
                raise ForaNavError("%s: line %d: box centre (%g, %g) lies outside its image %s (%dx%d)"
                                   % (csv_path, line_no, box.x_center, box.y_center, box.image, width, height))
            x0, y0, x1, y1 = box.corners()
            if x0 < 0 or y0 < 0 or x1 > width or y1 > height:
                skipped["cut by the image edge"] = skipped.get("cut by the image edge", 0) + 1
                continue
            if min(box.width, box.height) < min_crown_px:
                key = "smaller than %d px" % min_crown_px
                skipped[key] = skipped.get(key, 0) + 1
                continue
            patch = image[int(math.floor(y0)):int(math.ceil(y1)), int(math.floor(x0)):int(math.ceil(x1))].copy()
            crowns.setdefault(species, []).append(Crown(species, patch, "%s:%d" % (csv_path.name, line_no)))
    return CrownLibrary(crowns, tuple(Path(p) for p in csv_paths), skipped)


def _numbered_boxes(csv_path):
    """(line number, Box) of a boxes CSV, rows of empty markers left out."""
    text = csv_path.read_text(encoding="utf-8")  # read_boxes has already reported an unreadable file
    lines = [n for n, line in enumerate(text.splitlines(), start=1) if line.strip()][1:]
    boxes = read_boxes(csv_path)
    return [(n, b) for n, b in zip(lines, boxes) if not b.is_empty_marker]


def _read_image(path, csv_path, line_no):
    try:  # decodes by content (.tif chips that are JPEG); refuses empty, truncated and huge-claiming files
        return read_image_file(path)
    except ForaNavError as err:
        raise ForaNavError("%s: line %d: %s" % (csv_path, line_no, err))


def assign(library: CrownLibrary, trees: Sequence, seed: int) -> dict:
    """{tree id: (Crown, angle_rad)} for the trees whose species the library has (deterministic, see top)."""
    out = {}
    for species in library.species:
        pool = library.crowns[species]
        order = np.random.default_rng([seed & 0xFFFFFFFF, _SPECIES_STREAM, SPECIES.index(species)]) \
            .permutation(len(pool))
        for rank, tree in enumerate(sorted((t for t in trees if t.species == species), key=lambda t: t.id)):
            angle = float(np.random.default_rng([seed & 0xFFFFFFFF, _ANGLE_STREAM, tree.id]).uniform(0, 2 * math.pi))
            out[tree.id] = (pool[int(order[rank % len(pool)])], angle)
    return out


def soft_mask(height: int, width: int, feather: float = MASK_FEATHER) -> np.ndarray:
    """HxW float32: 1 inside the ellipse inscribed in the box, fading to 0 at its edge (smoothstep)."""
    ys = (np.arange(height, dtype=np.float32) + 0.5 - height / 2.0) / (height / 2.0)
    xs = (np.arange(width, dtype=np.float32) + 0.5 - width / 2.0) / (width / 2.0)
    r = np.sqrt(ys[:, None] ** 2 + xs[None, :] ** 2)
    t = np.clip((1.0 - r) / feather, 0.0, 1.0)
    return (t * t * (3.0 - 2.0 * t)).astype(np.float32)


def crown_sprite(crown: Crown, col: float, row: float, diameter_px: float, angle_rad: float,
                 light: float = 1.0) -> Sprite:
    """The crown's cut-out scaled so its box (mean of width and height) spans ``diameter_px``, rotated by
    ``angle_rad`` about its centre and centred at the continuous image position (col, row) -> Sprite."""
    patch = crown.patch.astype(np.float32) * np.float32(light)
    mask = soft_mask(*patch.shape[:2])
    height, width = mask.shape
    scale = diameter_px / ((height + width) / 2.0)
    if scale < 0.5:  # shrink with area averaging first: a warp alone would alias the fronds
        size = (max(2, int(round(width * scale * 2))), max(2, int(round(height * scale * 2))))
        patch = cv2.resize(patch, size, interpolation=cv2.INTER_AREA)
        mask = cv2.resize(mask, size, interpolation=cv2.INTER_AREA)
        scale *= width / float(size[0])
        height, width = mask.shape
    half = int(math.ceil(scale * max(height, width) / 2.0)) + 2
    origin = (int(math.floor(col)) - half, int(math.floor(row)) - half)
    centre = np.array([col - origin[0], row - origin[1]])
    cos, sin = math.cos(angle_rad), math.sin(angle_rad)
    a = scale * np.array([[cos, -sin], [sin, cos]])
    # continuous: dst = a (src - box centre) + centre; pixel indices are continuous coordinates - 0.5
    b = centre - a @ np.array([width / 2.0, height / 2.0])
    matrix = np.hstack([a, (b + a @ np.array([0.5, 0.5]) - 0.5)[:, None]])
    size = (2 * half + 1, 2 * half + 1)
    interpolation = cv2.INTER_CUBIC if scale > 1.0 else cv2.INTER_LINEAR
    premultiplied = cv2.warpAffine(patch * mask[..., None], matrix, size, flags=interpolation,
                                   borderMode=cv2.BORDER_CONSTANT, borderValue=0)
    alpha = cv2.warpAffine(mask, matrix, size, flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT,
                           borderValue=0)
    alpha = np.clip(alpha, 0.0, 1.0)
    premultiplied = np.clip(premultiplied, 0.0, 255.0 * alpha[..., None] * max(1.0, light))
    return Sprite(premultiplied.astype(np.float32), alpha.astype(np.float32), origin)


def load_ground(path: str | Path) -> np.ndarray:
    """The ground photo (BGR uint8); ForaNavError naming the file when it does not load."""
    try:
        return read_image_file(path)
    except ForaNavError as err:
        raise ForaNavError("--ground %s" % err)


def ground_from_photo(photo: np.ndarray, gsd_m: float, height: int, width: int, metres_per_pixel: float,
                      light: float = 1.0) -> np.ndarray:
    """HxWx3 float32: the photo at the mosaic's resolution, tiled with mirrored copies, times ``light``."""
    scale = gsd_m / metres_per_pixel
    size = (max(1, int(round(photo.shape[1] * scale))), max(1, int(round(photo.shape[0] * scale))))
    if size[0] > width or size[1] > height:
        # more photo than the ground holds (a 100000 x 1 px strip, a huge --ground-gsd): only the part that
        # covers the ground is resized, so the tile is never larger than the ground on either side
        keep = (min(photo.shape[1], int(math.ceil(width / scale)) + 1),
                min(photo.shape[0], int(math.ceil(height / scale)) + 1))
        photo = photo[:keep[1], :keep[0]]
        size = (max(1, min(width, int(round(keep[0] * scale)))), max(1, min(height, int(round(keep[1] * scale)))))
    tile = cv2.resize(photo, size, interpolation=cv2.INTER_AREA if scale < 1 else cv2.INTER_CUBIC)
    tile = tile.astype(np.float32) * np.float32(light)
    block = np.concatenate([tile, tile[:, ::-1]], axis=1)
    block = np.concatenate([block, block[::-1]], axis=0)
    reps = (int(math.ceil(height / block.shape[0])), int(math.ceil(width / block.shape[1])), 1)
    return np.ascontiguousarray(np.tile(block, reps)[:height, :width])


@dataclass(frozen=True)
class AppearanceSpec:
    """What the command line asked for (paths only: cheap to send to worker processes)."""
    crowns: tuple = ()  # CSV paths
    ground: Optional[str] = None
    ground_gsd_m: Optional[float] = None
    crown_shadows: bool = False

    @property
    def default(self) -> bool:
        return not self.crowns and self.ground is None

    def to_dict(self) -> dict:
        return {"crowns": list(self.crowns), "ground": self.ground, "ground_gsd_m": self.ground_gsd_m,
                "crown_shadows": self.crown_shadows}

    @classmethod
    def from_dict(cls, data: dict | None) -> "AppearanceSpec":
        data = dict(data or {})
        return cls(tuple(data.get("crowns") or ()), data.get("ground"), data.get("ground_gsd_m"),
                   bool(data.get("crown_shadows", False)))


@dataclass
class Appearance:
    """A loaded AppearanceSpec: the crown library and the ground photo, ready for World.from_map."""
    spec: AppearanceSpec
    library: Optional[CrownLibrary] = None
    ground_photo: Optional[np.ndarray] = None

    @classmethod
    def load(cls, spec: AppearanceSpec) -> "Appearance":
        library = load_library(spec.crowns) if spec.crowns else None
        photo = load_ground(spec.ground) if spec.ground is not None else None
        return cls(spec, library, photo)

    def check_species(self, species: Iterable[str], what: str) -> None:
        if self.library is not None:
            self.library.check_covers(tuple(species), what)


_LOADED = {}


def load_appearance(spec: Optional[AppearanceSpec]) -> Optional[Appearance]:
    """The Appearance of a spec, loaded once per process (worlds of the same flight share the cut-outs)."""
    if spec is None or spec.default:
        return None
    if spec not in _LOADED:
        _LOADED.clear()  # one library at a time: a process flies with one appearance
        _LOADED[spec] = Appearance.load(spec)
    return _LOADED[spec]
