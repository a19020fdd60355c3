"""Clips: a video that OpenCV reads plus a JSON sidecar with the ground truth of every frame. One definition.

A clip is a folder::

    clip.avi    MJPG video (OpenCV's own AVI writer), BGR frames in order
    clip.json   the sidecar (below)

The sidecar (``format`` "foranav-clip", ``version`` 1)::

    {"format": "foranav-clip", "version": 1,
     "video": "clip.avi",                 # file name relative to the folder
     "video_sha256": "3f1c...",           # optional: SHA-256 of that file as written; replay refuses another
     "fps": 5.0,                          # nominal frame rate of the video
     "camera": {"width": 352, "height": 288, "focal_px": 322.58, "mount_offset": [0.0, 0.0]},
     "map": {...} | null,                 # the map file's JSON object (host_tools.maps), null if unknown
     "source": {...},                     # free-form: how the clip was made (command, seed, speed, ...)
     "frames": [
        {"index": 0, "t_s": 0.0,
         "pose": {"x": 0.3, "y": 0.45, "z": 1.25, "yaw_deg": 0.0},   # MAV pose (world frame)
         "trees": [{"id": 1, "species": "oil_palm", "target": true,
                    "u": 176.0, "v": 20.5, "w": 98.1, "h": 98.1, "complete": true,
                    "x": 0.8, "y": 0.45}],                            # null = no ground truth (real footage)
         "objects": [{"kind": "roof", "u": ..., "v": ..., "w": ..., "h": ..., "complete": false,
                      "x": ..., "y": ...}]},                          # optional
        ...]}

Real footage with a pose log uses the same sidecar: ``trees`` null (or the trees of a surveyed map), ``map``
null or the surveyed map. Frame ``index`` i is the i-th decoded video frame; ``t_s`` is seconds from the start.
``video_sha256`` ties the video to its sidecar: a video swapped in from another clip (another map, another
flight) of the same size and length would otherwise replay against the wrong poses and ground truth without a
word. ``write_clip`` always writes it; a hand-made sidecar may leave it out (then nothing is checked).
"""
import hashlib
import math
import os
from collections.abc import Iterable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import NoReturn

import cv2
import numpy as np

from host_tools import fileio
from host_tools.errors import ForaNavError
from host_tools.sim.camera import HEIGHT_RANGE_M, CameraModel, Pose
from host_tools.sim.world import Frame, ObjectInView, TreeInView

FORMAT = "foranav-clip"
VERSION = 1
SIDECAR_NAME = "clip.json"
VIDEO_NAME = "clip.avi"
DEFAULT_QUALITY = 75


@dataclass(frozen=True)
class ClipFrame:
    index: int
    t_s: float
    pose: Pose
    trees: object  # tuple of TreeInView, or None when the clip has no ground truth
    objects: tuple = ()


@dataclass
class Clip:
    directory: Path
    video: str
    fps: float
    camera: CameraModel
    map: object  # the map's JSON object (dict) or None
    frames: list  # [ClipFrame]
    source: dict
    video_sha256: str | None = None  # the video's SHA-256 when the sidecar was written (None: not recorded)

    @property
    def video_path(self) -> Path:
        return self.directory / self.video

    def images(self) -> Iterator[np.ndarray]:
        """Yield the decoded BGR frames in order (OpenCV)."""
        capture = cv2.VideoCapture(str(self.video_path))
        if not capture.isOpened():
            raise ForaNavError("%s: cannot open video" % self.video_path)
        try:
            while True:
                ok, image = capture.read()
                if not ok:
                    return
                yield image
        finally:
            capture.release()

    def check_video(self) -> None:
        """ForaNavError unless the video is the one the sidecar was written with (its SHA-256, when recorded),
        opens and holds at least one frame per sidecar record, of the camera's size (a truncated or swapped
        video would otherwise replay part of the clip, or another map's flight, without a word)."""
        if self.video_sha256 is not None:
            try:
                digest = file_sha256(self.video_path)
            except OSError as err:
                raise ForaNavError("%s: cannot read video: %s" % (self.video_path, err.strerror or err))
            if digest != self.video_sha256:
                raise ForaNavError("%s: video_sha256: %s is not the video this sidecar was recorded with (SHA-256 "
                                   "%s..., the sidecar says %s...): a video of another clip or map? put the clip's "
                                   "own video back" % (self.directory / SIDECAR_NAME, self.video, digest[:12],
                                                       self.video_sha256[:12]))
        capture = cv2.VideoCapture(str(self.video_path))
        if not capture.isOpened():
            raise ForaNavError("%s: cannot open video" % self.video_path)
        try:
            count = 0
            ok, image = capture.read()
            if ok and image.shape[1::-1] != (self.camera.width, self.camera.height):
                raise ForaNavError("%s: frames are %dx%d, the sidecar's camera %dx%d" % (
                    self.video_path, image.shape[1], image.shape[0], self.camera.width, self.camera.height))
            while ok and count < len(self.frames):
                count += 1
                ok = capture.grab()
        finally:
            capture.release()
        if count < len(self.frames):
            raise ForaNavError("%s: %d frames, the sidecar has %d (truncated video?)"
                               % (self.video_path, count, len(self.frames)))

    def __len__(self) -> int:
        return len(self.frames)


# ---- pure: sidecar records ---------------------------------------------------------------------------------


def frame_record(index: int, t_s: float, pose: Pose, trees: Sequence[TreeInView] | None,
                 objects: Sequence[ObjectInView] = ()) -> dict:
    """The sidecar object of one frame (trees None = no ground truth)."""
    record = {"index": int(index), "t_s": round(float(t_s), 6),
              "pose": {"x": _r(pose.x), "y": _r(pose.y), "z": _r(pose.z), "yaw_deg": _r(pose.yaw_deg)},
              "trees": None if trees is None else [_tree_record(t) for t in trees]}
    if objects:
        record["objects"] = [{"kind": o.kind, "u": _r(o.u), "v": _r(o.v), "w": _r(o.w), "h": _r(o.h),
                              "complete": bool(o.complete), "x": _r(o.x), "y": _r(o.y)} for o in objects]
    return record


def sidecar(frames_records: list[dict], camera: CameraModel, fps: float, map_dict: dict | None = None,
            source: dict | None = None, video: str = VIDEO_NAME, video_sha256: str | None = None) -> dict:
    data = {"format": FORMAT, "version": VERSION, "video": video}
    if video_sha256 is not None:
        data["video_sha256"] = video_sha256
    data.update({"fps": float(fps), "camera": camera.to_dict(), "map": map_dict, "source": dict(source or {}),
                 "frames": frames_records})
    return data


def file_sha256(path: str | os.PathLike) -> str:
    digest = hashlib.sha256()
    with open(path, "rb") as handle:
        for block in iter(lambda: handle.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def _tree_record(t: TreeInView) -> dict:
    return {"id": t.id, "species": t.species, "target": bool(t.target), "u": _r(t.u), "v": _r(t.v),
            "w": _r(t.w), "h": _r(t.h), "complete": bool(t.complete), "x": _r(t.x), "y": _r(t.y)}


def _r(value: float) -> float:
    return round(float(value), 4)


# ---- adapters: files ---------------------------------------------------------------------------------------


def write_clip(out_dir: str | os.PathLike, frames: Iterable[Frame], times_s: Sequence[float], camera: CameraModel,
               fps: float, map_dict: dict | None = None, source: dict | None = None,
               quality: int = DEFAULT_QUALITY) -> int:
    """Write frames (world.Frame, any iterable) with their times as a clip folder; returns the frame count.

    The video is written to a temporary file and renamed, then the sidecar: a failed run leaves no clip.
    """
    out_dir = Path(out_dir)
    records = []
    size = (camera.width, camera.height)
    with fileio.atomic_path(out_dir / VIDEO_NAME) as tmp:
        # OpenCV's built-in MJPEG writer: no FFmpeg needed, and the same frames give the same bytes
        writer = cv2.VideoWriter(str(tmp), cv2.CAP_OPENCV_MJPEG, cv2.VideoWriter_fourcc(*"MJPG"), float(fps), size)
        if not writer.isOpened():
            raise ForaNavError("%s: cannot open the MJPG writer" % (out_dir / VIDEO_NAME))
        writer.set(cv2.VIDEOWRITER_PROP_QUALITY, float(quality))
        try:
            for index, (frame, t_s) in enumerate(zip(frames, times_s)):
                if frame.image.shape[1::-1] != size:
                    raise ForaNavError("frame %d: size %s differs from the camera's %s"
                                       % (index, frame.image.shape[1::-1], size))
                writer.write(frame.image)
                records.append(frame_record(index, t_s, frame.pose, frame.trees, frame.objects))
        finally:
            writer.release()
        video_sha256 = file_sha256(tmp)
        # a folder is a clip only with its sidecar: drop an old one before the new video replaces the old
        (out_dir / SIDECAR_NAME).unlink(missing_ok=True)
    fileio.write_json(out_dir / SIDECAR_NAME, sidecar(records, camera, fps, map_dict, source,
                                                      video_sha256=video_sha256), indent=1)
    return len(records)


def read_clip(directory: str | os.PathLike) -> Clip:
    """Read a clip folder's sidecar (validated); images are decoded lazily by Clip.images()."""
    directory = Path(directory)
    path = directory / SIDECAR_NAME if directory.is_dir() else directory
    directory = path.parent
    data = fileio.read_json(path, "clip sidecar")
    return clip_from_dict(data, directory, str(path))


def clip_from_dict(data: dict, directory: str | os.PathLike, source_name: str = "<clip>") -> Clip:
    def fail(where: str, message: str) -> NoReturn:
        raise ForaNavError("%s: %s: %s" % (source_name, where, message))

    if not isinstance(data, dict) or data.get("format") != FORMAT:
        fail("format", "not a %s sidecar" % FORMAT)
    if data.get("version") != VERSION:
        fail("version", "unsupported version %r (expected %d)" % (data.get("version"), VERSION))
    try:
        camera = CameraModel.from_dict(data["camera"])
    except (KeyError, IndexError, TypeError, ValueError, OverflowError) as err:
        fail("camera", "bad camera: %s" % err)
    fps = data.get("fps")
    if isinstance(fps, bool) or not isinstance(fps, (int, float)) or not fps > 0:
        fail("fps", "must be a positive number")
    for key, kind in (("frames", list), ("source", dict), ("map", dict), ("video", str)):
        if data.get(key) is not None and not isinstance(data[key], kind):
            fail(key, "must be %s" % {list: "an array", dict: "an object", str: "a file name"}[kind])
    video_sha256 = data.get("video_sha256")
    if video_sha256 is not None and not (isinstance(video_sha256, str) and len(video_sha256) == 64
                                         and all(c in "0123456789abcdef" for c in video_sha256)):
        fail("video_sha256", "must be 64 lower-case hex digits (the video's SHA-256), or left out")
    frames = []
    for i, rec in enumerate(data.get("frames") or []):
        try:
            pose = Pose(*(float(rec["pose"][k]) for k in ("x", "y", "z", "yaw_deg")))
            trees = None if rec.get("trees") is None else tuple(
                TreeInView(int(t["id"]), str(t["species"]), bool(t["target"]), float(t["u"]), float(t["v"]),
                           float(t["w"]), float(t["h"]), bool(t["complete"]), float(t.get("x", 0.0)),
                           float(t.get("y", 0.0))) for t in rec["trees"])
            objs = tuple(ObjectInView(k, str(o["kind"]), float(o["u"]), float(o["v"]), float(o["w"]), float(o["h"]),
                                      bool(o["complete"]), float(o.get("x", 0.0)), float(o.get("y", 0.0)))
                         for k, o in enumerate(rec.get("objects") or ()))
            frame = ClipFrame(int(rec["index"]), float(rec["t_s"]), pose, trees, objs)
        except (AttributeError, KeyError, TypeError, ValueError, OverflowError) as err:
            fail("frames[%d]" % i, "bad frame record (%s)" % (err,))
        if not all(math.isfinite(v) for v in (frame.t_s,) + tuple(frame.pose)):
            fail("frames[%d]" % i, "time and pose must be finite")
        if not HEIGHT_RANGE_M[0] <= frame.pose.z <= HEIGHT_RANGE_M[1]:
            fail("frames[%d].pose.z" % i, "camera height %g m; a camera sees the ground from %g to %g m"
                 % ((frame.pose.z,) + HEIGHT_RANGE_M))
        if frame.index != i:
            fail("frames[%d].index" % i, "expected %d, got %d" % (i, frame.index))
        if frames and not frame.t_s > frames[-1].t_s:
            fail("frames[%d].t_s" % i, "time must increase from frame to frame (%g s after %g s)"
                 % (frame.t_s, frames[-1].t_s))
        frames.append(frame)
    return Clip(Path(directory), str(data.get("video", VIDEO_NAME)), float(fps), camera, data.get("map"), frames,
                dict(data.get("source") or {}), video_sha256)
