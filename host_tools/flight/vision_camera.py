"""The vision camera: the simulator renders each frame from the MAV's true pose and the unchanged JeVois
module (through the host ``libjevois`` stand-in) turns it into serial lines. Registered as ``--camera sim``.

It implements the flight harness's camera protocol (``frame_period_ms``, ``latency_ms``,
``capture(t_ms, true_pose, hidden=frozenset()) -> list[str]``). Defaults follow the paper: the detector runs
at ~9 FPS on the JeVois (8.9 fps), so one frame every 111 ms, and its result leaves the camera one frame
period after the image was taken (one frame of processing latency).

A hidden tree is really hidden: the frame is rendered from a second orthomosaic of the same map without that
tree (same ground, same lighting) and the pixels of its crown are pasted over the normal frame, so the module
sees bare ground where the tree was (a temporary occlusion), not a filtered output.

Every frame is scored against the simulator's ground truth (``DetectionScore``); ``report()`` gives the
totals (detections per frame, true/false positives, misses, pixel error) for the flight summary.
"""
import dataclasses
import math

import numpy as np

from host_tools.flight.harness import register_camera
from host_tools.sim.camera import CameraModel, Pose
from host_tools.sim.world import NO_EFFECTS, SENSOR_EFFECTS, World
from jevois_module.ForaNavTrees import foranav_serial

PAPER_FPS = 9.0  # the paper: 8.9 fps on the JeVois-A33
DEFAULT_FRAME_PERIOD_MS = int(round(1000.0 / PAPER_FPS))  # 111 ms
DEFAULT_LATENCY_FRAMES = 1
EFFECTS = {"none": NO_EFFECTS, "sensor": SENSOR_EFFECTS}
DEFAULT_EFFECTS = "sensor"
MATCH_RADIUS_CROWN = 0.5  # a detection matches a tree when it lies within half a crown of its centre
HIDE_MARGIN_CROWN = 0.65  # paste radius around a hidden tree, in crowns (covers the crown's ragged edge)
MIN_RENDER_HEIGHT_M = 0.05  # on the ground the camera sees nothing useful (and the renderer needs z > 0)


class DetectionScore(object):
    """Running comparison of the module's detections with the ground truth of the rendered frames.

    Ground truth per frame: the trees of the detected species whose whole crown is in view (what the
    detector is meant to find). A detection is a true positive when it lies within ``MATCH_RADIUS_CROWN``
    crowns of such a tree (each tree matched once), otherwise a false positive.
    """

    def __init__(self):
        self.frames = 0
        self.detections = 0
        self.true_positives = 0
        self.false_positives = 0
        self.missed = 0
        self.frames_with_false_positives = 0
        self.pixel_errors = []
        self.per_frame = []  # (t_ms, n_detections, n_truth, tp, fp)

    def add(self, t_ms, detections_px, truth):
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

    def report(self):
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


def parse_detections(lines, width, height):
    """Pixel centres (u, v) of the T2/N2 lines of one frame (other lines ignored)."""
    out = []
    for line in lines:
        message = foranav_serial.parse_line(line)
        if isinstance(message, foranav_serial.Target2D):
            out.append((foranav_serial.std_to_img_x(message.x, width),
                        foranav_serial.std_to_img_y(message.y, height)))
    return out


def truth_in_frame(trees, species):
    """(u, v, crown_px) of the complete trees of ``species`` among a frame's TreeInView list."""
    return [(t.u, t.v, t.w) for t in trees if t.complete and t.species == species]


class _NullLog(object):
    def write(self, text):
        pass


class VisionCamera(object):
    """Rendered frames from the true pose -> the JeVois module -> serial lines (see the module docstring)."""

    def __init__(self, pmap, *, seed=0, frame_period_ms=DEFAULT_FRAME_PERIOD_MS, latency_ms=None,
                 effects=DEFAULT_EFFECTS, width=352, height=288, mount_offset=(0.0, 0.0), module_params=None,
                 world=None, serial_stream=None, log_stream=None):
        if frame_period_ms <= 0:
            raise ValueError("frame_period_ms must be > 0, got %r" % frame_period_ms)
        if latency_ms is not None and latency_ms < 0:
            raise ValueError("latency_ms must be >= 0, got %r" % latency_ms)
        if effects not in EFFECTS:
            raise ValueError("effects must be one of %s, got %r" % (", ".join(sorted(EFFECTS)), effects))
        from host_tools.jevois_host import ModuleRunner  # loads the module the JeVois way

        self.pmap = pmap
        self.frame_period_ms = int(frame_period_ms)
        self.latency_ms = int(DEFAULT_LATENCY_FRAMES * self.frame_period_ms if latency_ms is None else latency_ms)
        self.camera = CameraModel(width, height, mount_offset)
        self.effects = EFFECTS[effects]
        self.world = world if world is not None else World.from_map(pmap)
        self._hidden_worlds = {}
        self._rng = np.random.default_rng([int(seed) & 0xFFFFFFFF, 0xCA3])  # sensor noise, per flight seed
        params = {"species": pmap.target_species}
        params.update(module_params or {})
        # the module's periodic timing log ("INF ForaNavTrees average ...") would interleave with the CLI output
        self.runner = ModuleRunner(serial_stream=serial_stream, params=params, log_stream=log_stream or _NullLog())
        self.score = DetectionScore()
        self.last_frame = None

    def render(self, true_pose, hidden=frozenset()):
        """The frame the camera takes at ``true_pose`` (x, y, z, yaw_deg), with ``hidden`` trees removed."""
        pose = Pose(*(float(v) for v in true_pose))
        frame = self.world.render(self.camera, pose, rng=self._rng, effects=self.effects)
        hidden = [t for t in self.pmap.trees if t.id in hidden]
        if hidden:
            frame.image = self._paste_bare_ground(frame.image, pose, hidden)
            frame.trees = [t for t in frame.trees if t.id not in {h.id for h in hidden}]
        return frame

    def _paste_bare_ground(self, image, pose, hidden):
        key = frozenset(t.id for t in hidden)
        world = self._hidden_worlds.get(key)
        if world is None:
            bare = dataclasses.replace(self.pmap, trees=tuple(t for t in self.pmap.trees if t.id not in key))
            world = self._hidden_worlds[key] = World.from_map(bare, seed=self.world.seed)
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

    def process(self, image):
        """Run the module on one frame -> its serial lines (also written to serial_stream, if any)."""
        return self.runner.process_frame(image)

    def capture(self, t_ms, true_pose, hidden=frozenset()):
        if true_pose[2] <= MIN_RENDER_HEIGHT_M:
            # on the ground: an empty frame, not rendered (the module streams from power-on, and the app
            # takes off only once it has heard the camera)
            return [foranav_serial.FRAME_START, foranav_serial.FRAME_STOP]
        frame = self.render(true_pose, hidden)
        lines = self.process(frame.image)
        self.last_frame = frame
        self.score.add(t_ms, parse_detections(lines, self.camera.width, self.camera.height),
                       truth_in_frame(frame.trees, self.pmap.target_species))
        return lines

    def frames_csv(self):
        """One row per frame: capture time, detections sent, trees that should be found, true/false positives."""
        rows = ["t_ms,detections,truth,true_positives,false_positives"]
        rows.extend("%d,%d,%d,%d,%d" % row for row in self.score.per_frame)
        return "\n".join(rows) + "\n"

    def report(self):
        """Detection totals of the flight so far (for the summary's "vision" entry)."""
        report = self.score.report()
        report.update(fps=round(1000.0 / self.frame_period_ms, 2), latency_ms=self.latency_ms)
        return report


def fly_with_vision(pmap, *, seed=0, out_dir=None, options=None, progress=None, **camera_kwargs):
    """run_flight with a VisionCamera; the summary has "vision" (the camera's detection report)."""
    from host_tools.flight.harness import run_flight

    camera = VisionCamera(pmap, seed=seed, **camera_kwargs)
    return run_flight(pmap, camera, seed=seed, out_dir=out_dir, options=options, progress=progress)


def _sim(pmap, seed=0, **kwargs):
    # fly's --pixel-noise belongs to the oracle; a rendered camera has its own (sensor) noise
    kwargs.pop("pixel_noise_px", None)
    return VisionCamera(pmap, seed=seed, **kwargs)


register_camera("sim", _sim)
