"""The vision camera: the simulator renders each frame from the MAV's true pose and the unchanged JeVois
module (through the host ``libjevois`` stand-in) turns it into serial lines. Registered as ``--camera sim``.

It implements the flight harness's camera protocol (``frame_period_ms``, ``latency_ms``,
``capture(t_ms, true_pose, hidden=frozenset()) -> list[str]``). Defaults follow the paper: the detector runs
at ~9 FPS on the JeVois (8.9 fps), so one frame every 111 ms, and its result leaves the camera one frame
period after the image was taken (one frame of processing latency).

A hidden tree is really hidden: the frame is rendered from a second orthomosaic of the same map without that
tree (same ground, same lighting) and the pixels of its crown are pasted over the normal frame, so the module
sees bare ground where the tree was (a temporary occlusion), not a filtered output.

``pixel_noise_px`` (default 0) adds Gaussian jitter to the centres the module reports (a fault on top of
the rendered sensor noise); frames are scored on what is sent.
Appearance (``appearance``: a crowns.AppearanceSpec or its dict): photo crowns and a ground photo, loaded once
per process and rendered into the orthomosaic once per flight. ``model`` (a .npz path): the module runs with
that model file, as the JeVois does with its ``species`` parameter set to a model file (the module joins the
name to its folder, so an absolute path loads that file).

Every frame is scored against the simulator's ground truth (``DetectionScore``); ``report()`` gives the
totals (detections per frame, true/false positives, misses, pixel error) for the flight summary.
"""
import dataclasses
import math
import os
import time
from collections.abc import Collection, Iterable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from host_tools.threads import single_threaded
from host_tools.errors import ForaNavError
from host_tools.flight.harness import Progress, register_camera, run_flight
from host_tools.jevois_host import ModuleRunner, NullLog
from host_tools.maps import PlantationMap, Tree
from host_tools.sim.camera import CameraModel, Pose
from host_tools.sim.crowns import AppearanceSpec, load_appearance
from host_tools.sim.world import NO_EFFECTS, SENSOR_EFFECTS, Frame, TreeInView, World
from jevois_module.ForaNavTrees import foranav_serial

import foranav_model  # noqa: E402  (the camera's own module: jevois_module.ForaNavTrees put it on sys.path)

PAPER_FPS = 9.0  # the paper: 8.9 fps on the JeVois-A33
DEFAULT_FRAME_PERIOD_MS = int(round(1000.0 / PAPER_FPS))  # 111 ms
DEFAULT_LATENCY_FRAMES = 1
EFFECTS = {"none": NO_EFFECTS, "sensor": SENSOR_EFFECTS}
DEFAULT_EFFECTS = "sensor"
MATCH_RADIUS_CROWN = 0.5  # a detection matches a tree when it lies within half a crown of its centre
HIDE_MARGIN_CROWN = 0.65  # paste radius around a hidden tree, in crowns (covers the crown's ragged edge)
Pixel = tuple[float, float]  # (u, v), px
MIN_RENDER_HEIGHT_M = 0.05  # on the ground the camera sees nothing useful (and the renderer needs z > 0)


class DetectionScore:
    """Running comparison of the module's detections with the ground truth of the rendered frames.

    Ground truth per frame: the trees of the detected species whose whole crown is in view (what the
    detector is meant to find). A detection is a true positive when it lies within ``MATCH_RADIUS_CROWN``
    crowns of such a tree (each tree matched once), otherwise a false positive.
    """

    def __init__(self) -> None:
        self.frames = 0
        self.detections = 0
        self.true_positives = 0
        self.false_positives = 0
        self.missed = 0
        self.frames_with_false_positives = 0
        self.pixel_errors = []
        self.per_frame = []  # (t_ms, n_detections, n_truth, tp, fp)

    def add(self, t_ms: int, detections_px: Sequence[Pixel], truth: Sequence[tuple[float, float, float]]) -> None:
        """detections_px: [(u, v)]; truth: [(u, v, crown_px)] of the trees that should be found."""
        unmatched = list(truth)
        tp = fp = 0
        for u, v in detections_px:
            best = None
            for i, (tu, tv, crown) in enumerate(unmatched):
                d = math.hypot(u - tu, v - tv)
                if d <= MATCH_RADIUS_CROWN * crown and (best is None or d < best[1]):
                    best = (i, d)
            if best is None:
                fp += 1
            else:
                tp += 1
                self.pixel_errors.append(best[1])
                unmatched.pop(best[0])
        self.frames += 1
        self.detections += len(detections_px)
        self.true_positives += tp
        self.false_positives += fp
        self.missed += len(unmatched)
        self.frames_with_false_positives += 1 if fp else 0
        self.per_frame.append((int(t_ms), len(detections_px), len(truth), tp, fp))

    def report(self) -> dict:
        truth = self.true_positives + self.missed
        return {
            "frames": self.frames,
            "detections": self.detections,
            "detections_per_frame": round(self.detections / self.frames, 3) if self.frames else None,
            "true_positives": self.true_positives,
            "false_positives": self.false_positives,
            "missed": self.missed,
            "recall": round(self.true_positives / truth, 4) if truth else None,
            "precision": round(self.true_positives / self.detections, 4) if self.detections else None,
            "frames_with_false_positives": self.frames_with_false_positives,
            "mean_pixel_error": round(float(np.mean(self.pixel_errors)), 2) if self.pixel_errors else None,
        }


def parse_detections(lines: Iterable[str], width: int, height: int) -> list[Pixel]:
    """Pixel centres (u, v) of the T2/N2 lines of one frame (other lines ignored)."""
    out = []
    for line in lines:
        message = foranav_serial.parse_line(line)
        if isinstance(message, foranav_serial.Target2D):
            out.append((foranav_serial.std_to_img_x(message.x, width),
                        foranav_serial.std_to_img_y(message.y, height)))
    return out


def truth_in_frame(trees: Iterable[TreeInView], species: str) -> list[tuple[float, float, float]]:
    """(u, v, crown_px) of the complete trees of ``species`` among a frame's TreeInView list."""
    return [(t.u, t.v, t.w) for t in trees if t.complete and t.species == species]


class VisionCamera:
    """Rendered frames from the true pose -> the JeVois module -> serial lines (see the module docstring)."""

    def __init__(self, pmap: PlantationMap, *, seed: int = 0, frame_period_ms: int = DEFAULT_FRAME_PERIOD_MS,
                 latency_ms: int | None = None, effects: str = DEFAULT_EFFECTS, width: int = 352, height: int = 288,
                 mount_offset: tuple[float, float] = (0.0, 0.0), module_params: dict | None = None,
                 world: World | None = None, serial_stream: Any = None, log_stream: Any = None,
                 pixel_noise_px: float = 0.0, appearance: AppearanceSpec | dict | None = None,
                 model: str | None = None):
        if frame_period_ms <= 0:
            raise ValueError("frame_period_ms must be > 0, got %r" % frame_period_ms)
        if latency_ms is not None and latency_ms < 0:
            raise ValueError("latency_ms must be >= 0, got %r" % latency_ms)
        if not pixel_noise_px >= 0:
            raise ValueError("pixel_noise_px must be >= 0, got %r" % pixel_noise_px)
        if effects not in EFFECTS:
            raise ValueError("effects must be one of %s, got %r" % (", ".join(sorted(EFFECTS)), effects))

        # one frame at a time on one core, as the camera: OpenCV's thread pool spin-waits (sched_yield) between
        # the small calls of a frame, a second of system time per flight for nothing (same pixels either way)
        single_threaded()
        self.pmap = pmap
        self.frame_period_ms = int(frame_period_ms)
        self.latency_ms = int(DEFAULT_LATENCY_FRAMES * self.frame_period_ms if latency_ms is None else latency_ms)
        self.camera = CameraModel(width, height, mount_offset)
        self.effects = EFFECTS[effects]
        if isinstance(appearance, dict):
            appearance = AppearanceSpec.from_dict(appearance)
        self.appearance = load_appearance(appearance)
        self.world = world if world is not None else World.from_map(pmap, appearance=self.appearance)
        self._hidden_worlds = {}
        self._rng = np.random.default_rng([int(seed) & 0xFFFFFFFF, 0xCA3])  # sensor noise, per flight seed
        self.pixel_noise_px = float(pixel_noise_px)
        self._jitter_rng = np.random.default_rng([int(seed) & 0xFFFFFFFF, 0x71D])  # its own stream: 0 = no change
        params = {"species": pmap.target_species if model is None else str(model)}
        params.update(module_params or {})
        # the module's periodic timing log ("INF ForaNavTrees average ...") would interleave with the CLI output
        self.runner = ModuleRunner(serial_stream=serial_stream, params=params, log_stream=log_stream or NullLog())
        self.score = DetectionScore()
        self.last_frame = None
        self.stage_cpu_s = {"render": 0.0, "module": 0.0}  # where this camera's CPU time went

    def render(self, true_pose: Sequence[float], hidden: Collection[int] = frozenset()) -> Frame:
        """The frame the camera takes at ``true_pose`` (x, y, z, yaw_deg), with ``hidden`` trees removed."""
        pose = Pose(*(float(v) for v in true_pose))
        frame = self.world.render(self.camera, pose, rng=self._rng, effects=self.effects)
        hidden = [t for t in self.pmap.trees if t.id in hidden]
        if hidden:
            frame.image = self._paste_bare_ground(frame.image, pose, hidden)
            frame.trees = [t for t in frame.trees if t.id not in {h.id for h in hidden}]
        return frame

    def _paste_bare_ground(self, image: np.ndarray, pose: Pose, hidden: list[Tree]) -> np.ndarray:
        key = frozenset(t.id for t in hidden)
        world = self._hidden_worlds.get(key)
        if world is None:
            bare = dataclasses.replace(self.pmap, trees=tuple(t for t in self.pmap.trees if t.id not in key))
            # the other trees keep the photo crowns they have in the full map
            world = self._hidden_worlds[key] = World.from_map(bare, seed=self.world.seed, appearance=self.appearance,
                                                              crown_trees=self.pmap.trees)
        # same effects seed for both renders so the pasted patch carries the same sensor noise statistics
        under = world.render(self.camera, pose, rng=np.random.default_rng(0), effects=self.effects).image
        rows, cols = np.mgrid[0:image.shape[0], 0:image.shape[1]]
        mask = np.zeros(image.shape[:2], bool)
        for tree in hidden:
            u, v = self.camera.world_to_pixel(pose, tree.x, tree.y)
            radius = HIDE_MARGIN_CROWN * tree.crown_m / self.camera.metres_per_pixel(pose.z)
            mask |= (cols + 0.5 - u) ** 2 + (rows + 0.5 - v) ** 2 <= radius ** 2
        out = image.copy()
        out[mask] = under[mask]
        return out

    def process(self, image: np.ndarray) -> list[str]:
        """Run the module on one frame -> its serial lines (also written to serial_stream, if any)."""
        return self.runner.process_frame(image)

    def capture(self, t_ms: int, true_pose: Sequence[float], hidden: Collection[int] = frozenset()) -> list[str]:
        if true_pose[2] <= MIN_RENDER_HEIGHT_M:
            # on the ground: an empty frame, not rendered (the module streams from power-on, and the app
            # takes off only once it has heard the camera)
            return [foranav_serial.FRAME_START, foranav_serial.FRAME_STOP]
        cpu0 = time.process_time()
        frame = self.render(true_pose, hidden)
        cpu1 = time.process_time()
        lines = self._jitter(self.process(frame.image))
        self.stage_cpu_s["render"] += cpu1 - cpu0
        self.stage_cpu_s["module"] += time.process_time() - cpu1
        self.last_frame = frame
        self.score.add(t_ms, parse_detections(lines, self.camera.width, self.camera.height),
                       truth_in_frame(frame.trees, self.pmap.target_species))
        return lines

    def _jitter(self, lines: list[str]) -> list[str]:
        """Fault: Gaussian noise of pixel_noise_px on each reported centre (detection jitter beyond the
        module's own), re-encoded in the serial grammar; other lines pass unchanged."""
        if self.pixel_noise_px <= 0:
            return lines
        out = []
        w, h = self.camera.width, self.camera.height
        for line in lines:
            message = foranav_serial.parse_line(line)
            if isinstance(message, foranav_serial.Target2D):
                du, dv = self._jitter_rng.normal(0.0, self.pixel_noise_px, 2)
                line = foranav_serial.format_t2(foranav_serial.std_to_img_x(message.x, w) + du,
                                                foranav_serial.std_to_img_y(message.y, h) + dv, w, h)
            out.append(line)
        return out

    def frames_csv(self) -> str:
        """One row per frame: capture time, detections sent, trees that should be found, true/false positives."""
        rows = ["t_ms,detections,truth,true_positives,false_positives"]
        rows.extend("%d,%d,%d,%d,%d" % row for row in self.score.per_frame)
        return "\n".join(rows) + "\n"

    def report(self) -> dict:
        """Detection totals of the flight so far (for the summary's "vision" entry)."""
        report = self.score.report()
        report.update(fps=round(1000.0 / self.frame_period_ms, 2), latency_ms=self.latency_ms)
        if self.world.photo_crowns:  # only then: a default flight's summary keeps its bytes
            report["photo_species"] = list(self.world.photo_species)
        return report


def fly_with_vision(pmap: PlantationMap, *, seed: int = 0, out_dir: str | os.PathLike | None = None,
                    options: dict | None = None, progress: Progress | None = None, **camera_kwargs: Any) -> dict:
    """run_flight with a VisionCamera; the summary has "vision" (the camera's detection report)."""
    camera = VisionCamera(pmap, seed=seed, **camera_kwargs)
    return run_flight(pmap, camera, seed=seed, out_dir=out_dir, options=options, progress=progress)


def model_option(path: str | os.PathLike) -> str:
    """--model M: the absolute path of a model file the module can load; ForaNavError naming it otherwise."""
    try:
        foranav_model.load_model(str(path))
    except foranav_model.ModelFormatError as err:
        raise ForaNavError("--model %s" % err)
    return str(Path(path).resolve())


def _sim(pmap: PlantationMap, seed: int = 0, **kwargs: Any) -> "VisionCamera":
    return VisionCamera(pmap, seed=seed, **kwargs)


register_camera("sim", _sim)
