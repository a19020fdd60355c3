"""README pictures of the simulator: every species and look-alike, and a camera frame of Map 1.

    python -m host_tools.sim.gallery --out docs/img

writes sim_gallery.png (each kind as the 352x288 camera sees it from 1.25 m, pixels doubled) and
sim_map1_frame.png (a 352x288 frame over Map 1 with its ground-truth boxes beside the plain frame).
"""
import argparse

import cv2
import numpy as np

from host_tools.maps import load_map
from host_tools.sim.camera import CameraModel, Pose
from host_tools.sim.cmd_render import write_png
from host_tools.sim.specimens import KINDS, render_specimen
from host_tools.sim.world import World

TILE_SCALE = 2
COLUMNS = 4
LABEL_HEIGHT = 26


def gallery(seed: int = 3, size_m: float = 0.4) -> np.ndarray:
    tiles = []
    for kind in KINDS:
        crop = render_specimen(kind, seed, size_m=size_m, yaw_deg=25.0)
        tile = cv2.resize(crop, None, fx=TILE_SCALE, fy=TILE_SCALE, interpolation=cv2.INTER_NEAREST)
        label = np.full((LABEL_HEIGHT, tile.shape[1], 3), 255, np.uint8)
        cv2.putText(label, kind.replace("_", " "), (6, 19), cv2.FONT_HERSHEY_SIMPLEX, 0.6, (30, 30, 30), 1,
                    cv2.LINE_AA)
        tiles.append(np.vstack([tile, label]))
    side = max(t.shape[0] for t in tiles)
    tiles = [cv2.copyMakeBorder(t, 0, side - t.shape[0], 0, 0, cv2.BORDER_CONSTANT, value=(255, 255, 255))
             for t in tiles]
    rows = [np.hstack(tiles[i:i + COLUMNS]) for i in range(0, len(tiles), COLUMNS)]
    return np.vstack(rows)


def map1_frame(pose: Pose = Pose(1.86, 0.45, 1.25, 0.0)) -> np.ndarray:
    world = World.from_map(load_map("map1"))
    frame = world.render(CameraModel(), pose)
    boxed = frame.image.copy()
    for t in frame.trees:
        colour = (0, 255, 255) if t.complete else (0, 128, 255)
        p0 = (int(round(t.u - t.w / 2)), int(round(t.v - t.h / 2)))
        p1 = (int(round(t.u + t.w / 2)), int(round(t.v + t.h / 2)))
        cv2.rectangle(boxed, p0, p1, colour, 1, cv2.LINE_AA)
        cv2.putText(boxed, "T%d" % t.id, (p0[0] + 3, max(p0[1] + 14, 12)), cv2.FONT_HERSHEY_SIMPLEX, 0.45,
                    colour, 1, cv2.LINE_AA)
    gap = np.full((frame.image.shape[0], 8, 3), 255, np.uint8)
    return np.hstack([frame.image, gap, boxed])


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="docs/img", help="output folder (default docs/img)")
    args = parser.parse_args(argv)
    write_png("%s/sim_gallery.png" % args.out, gallery())
    write_png("%s/sim_map1_frame.png" % args.out, map1_frame())
    print("wrote %s/sim_gallery.png and %s/sim_map1_frame.png" % (args.out, args.out))


if __name__ == "__main__":
    main()
