"""Regenerate docs/img/det_example.png: the camera module's USB output on rendered frames of paper maps 1-3.

    .venv/bin/python -m host_tools.detection.figures [--out docs/img]

Each view is one rendered frame with the flight's sensor effects (blur, noise, JPEG), run through the
unchanged JeVois module on the host stand-in (process(), so boxes, scores and the jevois.Timer text are
drawn as on the camera). The views: map 1 between two palms, the coconut of map 2 next to an oil palm,
the clustered crowns of map 3, and a palm cut by the frame edge (map 1).
"""
import argparse
from collections.abc import Sequence
from pathlib import Path

import cv2
import numpy as np

from host_tools import fileio
from host_tools.jevois_host import ModuleRunner
from host_tools.maps import load_map
from host_tools.sim.camera import CameraModel, Pose
from host_tools.sim.world import SENSOR_EFFECTS, World

TIMER_FRAMES = 101  # the module's Timer reports every 100 frames
VIEWS = (("map1", 1.60, 0.45), ("map2", 2.45, 0.70), ("map3", 3.00, 0.50), ("map1", 2.95, 0.20))


def example_mosaic(views: Sequence[tuple[str, float, float]] = VIEWS, seed: int = 0) -> np.ndarray:
    """2 x 2 mosaic (BGR) of the module's drawn output on the given (map, x, y) views."""
    runner = ModuleRunner()
    tiles = []
    for index, (name, x, y) in enumerate(views):
        pmap = load_map(name)
        frame = World.from_map(pmap).render(CameraModel(), Pose(x, y, pmap.altitude_m, 0.0),
                                            rng=np.random.default_rng([seed, index]), effects=SENSOR_EFFECTS)
        for _ in range(TIMER_FRAMES):
            runner.process_frame(frame.image, with_usb=True)
        tiles.append(runner.output_image.copy())
    return np.vstack([np.hstack(tiles[:2]), np.hstack(tiles[2:4])])


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="docs/img", help="output folder (default docs/img)")
    args = parser.parse_args(argv)
    ok, data = cv2.imencode(".png", example_mosaic(), [cv2.IMWRITE_PNG_COMPRESSION, 6])
    path = Path(args.out) / "det_example.png"
    fileio.write_bytes(str(path), data.tobytes())
    print("wrote %s" % path)
    return 0 if ok else 1


if __name__ == "__main__":
    raise SystemExit(main())
