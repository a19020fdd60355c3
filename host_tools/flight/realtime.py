"""--realtime: the two halves as separate processes that share nothing but the pty, on wall-clock time.

    run_realtime(pmap, *, seed=0, speed=1.0, out_dir=None, options=None, kill_camera_at_s=None,
                 camera_kwargs=None, progress=None) -> summary dict (the fly summary plus "realtime", "vision")

The flight process (this one) runs the emulated Crazyflie with the app, paced so that simulated time follows
the wall clock times ``speed``. The camera process (``python -m host_tools.flight.realtime``) renders frames,
runs the unchanged JeVois module and lets its ``sendSerial`` write straight into the pty master it inherited;
the app reads the slave side with pyserial. The only other channel is the "physics": the flight process
streams the MAV's true pose (what the camera would see) down the camera process's stdin, one line
``t_ms x y z yaw_deg [hidden ids]`` every ``POSE_PERIOD_MS`` of simulated time. Nothing else is shared: no
frames, no detections, no clock.

The camera process takes a frame every ``frame_period_ms / speed`` wall seconds from the latest pose it has,
and sends the module's lines ``latency_ms / speed`` later (the processing latency). When the host cannot keep
up (a high ``speed``), it drops frames as a real camera would, so fewer frames per simulated second arrive.
``kill_camera_at_s`` kills the camera process (SIGKILL) at that simulated time: the pty goes silent, as when
the camera browns out on the aircraft.

Not reproducible by design (wall-clock scheduling); use the lockstep mode for determinism.
"""
import argparse
import json
import os
import select
import subprocess
import sys
import threading
import time
from dataclasses import dataclass

from crazyflie_app.firmware import v_task_delay
from host_tools.errors import ForaNavError
from host_tools.flight import harness
from host_tools.flight.vision_camera import (DEFAULT_FRAME_PERIOD_MS, DEFAULT_LATENCY_FRAMES, VisionCamera,
                                             parse_detections, truth_in_frame)
from host_tools.maps import PlantationMap, map_from_dict, map_to_dict
from jevois_module.ForaNavTrees import foranav_serial

POSE_PERIOD_MS = 10  # simulated ms between pose messages and between wall-clock pacing points
READY_TIMEOUT_S = 60.0  # the camera process renders the orthomosaic and loads the model before READY
STOP_TIMEOUT_S = 5.0
UNSUPPORTED_OPTIONS = ("silence", "garbage_rate", "partial_rate", "dropout")  # lockstep-only wire faults


@dataclass(frozen=True)
class _CameraSpec:
    """What the flight side knows of the remote camera: its timing (the app is told the latency)."""
    frame_period_ms: int
    latency_ms: int


class _RealtimePacer:
    """The realtime world task: paces simulated time to the wall clock and feeds the camera process poses."""

    def __init__(self, flight, speed, kill_camera_at_s):
        self.flight = flight
        self.speed = float(speed)
        self.kill_camera_at_ms = None if kill_camera_at_s is None else int(float(kill_camera_at_s) * 1000)
        self.camera_process = None
        self.wall0 = None
        self.max_lag_s = 0.0

    def task(self):
        rig, flight = self.flight.rig, self.flight
        while True:
            now = rig.now()
            if self.wall0 is None:
                self.wall0 = time.monotonic()
            lag = time.monotonic() - (self.wall0 + now / 1000.0 / self.speed)
            if lag < 0:
                flight.wait_wall(-lag)  # a CRTP client is served while the pacer waits
            self.max_lag_s = max(self.max_lag_s, lag)
            flight.hide.update(now)
            if self.kill_camera_at_ms is not None and now >= self.kill_camera_at_ms and flight.camera_killed_ms is None:
                self.camera_process.kill()
                flight.camera_killed_ms = now
            elif flight.camera_killed_ms is None:
                self._send_pose(now)
            yield v_task_delay(POSE_PERIOD_MS)

    def _send_pose(self, now):
        x, y, z, yaw = self.flight.rig.true_pose()
        hidden = ",".join(str(i) for i in sorted(self.flight.hide.hidden_ids(now)))
        try:
            self.camera_process.stdin.write(("%d %.5f %.5f %.5f %.4f %s\n" % (now, x, y, z, yaw, hidden)).encode())
            self.camera_process.stdin.flush()
        except (BrokenPipeError, OSError):
            pass  # the camera process is gone; the app must cope with the silence


def _start_camera_process(pmap, master_fd, speed, seed, camera_kwargs):
    command = [sys.executable, "-m", "host_tools.flight.realtime", "--fd", str(master_fd), "--speed", repr(speed),
               "--seed", str(seed), "--camera", json.dumps(camera_kwargs or {})]
    process = subprocess.Popen(command, stdin=subprocess.PIPE, stdout=subprocess.PIPE, pass_fds=(master_fd,),
                               cwd=os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
    process.stdin.write((json.dumps(map_to_dict(pmap)) + "\n").encode())
    process.stdin.flush()
    ready, _, _ = select.select([process.stdout], [], [], READY_TIMEOUT_S)
    line = process.stdout.readline() if ready else b"(nothing within %.0f s)" % READY_TIMEOUT_S
    if line.strip() != b"READY":
        process.kill()
        process.wait()
        raise ForaNavError("--realtime: the camera process did not start (said %r)" % line[:200])
    return process


def _stop_camera_process(process):
    """Close the pose feed (the camera process then prints its report and exits) -> its report or None."""
    if process.poll() is None:
        try:
            process.stdin.close()
        except OSError:
            pass
    try:
        out, _ = process.communicate(timeout=STOP_TIMEOUT_S)
    except subprocess.TimeoutExpired:
        process.kill()
        out, _ = process.communicate()
    except ValueError:  # stdin already closed
        out = process.stdout.read() if process.stdout else b""
        process.wait()
    for line in reversed((out or b"").decode("utf-8", "replace").splitlines()):
        if line.startswith("{"):
            return json.loads(line)
    return None


def run_realtime(pmap: PlantationMap, *, seed: int = 0, speed: float = 1.0, out_dir: str | os.PathLike | None = None,
                 options: dict | None = None, kill_camera_at_s: float | None = None, camera_kwargs: dict | None = None,
                 progress: harness.Progress | None = None) -> dict:
    """Fly ``pmap`` with the camera in its own process (see the module docstring) -> summary dict."""
    if not speed > 0:
        raise ForaNavError("--speed: must be positive, got %r" % speed)
    options = dict(options or {})
    for key in UNSUPPORTED_OPTIONS:
        if options.get(key):
            raise ForaNavError("--realtime: option %s is a lockstep wire fault (not with --realtime)" % key)
    if (camera_kwargs or {}).get("pixel_noise_px"):
        # the module writes straight into the pty there: nothing between it and the wire to add noise
        raise ForaNavError("--realtime: --pixel-noise is a lockstep fault (not with --realtime)")
    options["lockstep"] = False  # bytes arrive when the camera process sends them

    kwargs = dict(camera_kwargs or {})
    period = int(kwargs.get("frame_period_ms", DEFAULT_FRAME_PERIOD_MS))
    latency = kwargs.get("latency_ms")
    latency = DEFAULT_LATENCY_FRAMES * period if latency is None else int(latency)
    flight = harness.Flight(pmap, _CameraSpec(period, latency), seed=seed, out_dir=out_dir, options=options,
                            progress=progress)
    pacer = _RealtimePacer(flight, speed, kill_camera_at_s)
    report = None
    started = time.monotonic()
    try:
        pacer.camera_process = _start_camera_process(pmap, flight.rig.wire.master_fd, speed, seed, kwargs)
        flight.run(pacer.task())
    except BaseException:
        if pacer.camera_process is not None and pacer.camera_process.poll() is None:
            pacer.camera_process.kill()
            pacer.camera_process.wait()
        flight.close(keep=False)
        raise
    finally:
        if pacer.camera_process is not None:
            report = _stop_camera_process(pacer.camera_process)
    wall = time.monotonic() - started
    flight.close(keep=True)
    summary = flight.summary()
    summary["cpu_s"] = round(flight.cpu_s, 2)
    done_ms = flight.record.done_ms
    if report is not None and done_ms:
        # frames that reached the app per simulated second: below the nominal rate when the host lags
        report["effective_fps"] = round(report["frames"] / (done_ms / 1000.0), 2)
    summary["vision"] = report
    summary["realtime"] = {"speed": speed, "wall_s": round(wall, 2), "max_lag_s": round(pacer.max_lag_s, 3),
                           "camera_killed_at_s": None if flight.camera_killed_ms is None
                           else flight.camera_killed_ms / 1000.0}
    summary["after_camera_loss"] = _after_camera_loss(flight)
    if flight.out_dir is not None:
        flight.write_outputs(summary)
    return summary


def _after_camera_loss(flight):
    """How far the MAV went after the camera died, and whether it ended on the ground (None if it did not die)."""
    if flight.camera_killed_ms is None:
        return None
    after = [(x, y) for t, x, y, _, _, _ in flight.trajectory if t >= flight.camera_killed_ms]
    if not after:
        return None
    x0, y0 = after[0]
    farthest = max(((x - x0) ** 2 + (y - y0) ** 2) ** 0.5 for x, y in after)
    cf = flight.rig.cf
    truth = cf.model.truth
    return {"max_distance_m": round(farthest, 3), "final_height_m": round(truth.z, 3),
            "landed": cf.supervisor.state in ("LANDED", "LOCKED") or truth.z < 0.05,
            "supervisor": str(cf.supervisor.state), "phase": flight.rig.app.phase}


# -- the camera process -------------------------------------------------------------------------------------------

class _PoseFeed:
    """The latest pose line from stdin (a reader thread); ``ended`` once the flight side closed it."""

    def __init__(self, stream):
        self.stream = stream
        self.latest = None
        self.ended = threading.Event()
        self.first = threading.Event()
        threading.Thread(target=self._read, daemon=True).start()

    def _read(self):
        for raw in self.stream:
            parts = raw.decode("ascii", "replace").split()
            if len(parts) >= 5:
                hidden = frozenset(int(i) for i in parts[5].split(",")) if len(parts) > 5 else frozenset()
                self.latest = (int(parts[0]), tuple(float(v) for v in parts[1:5]), hidden)
                self.first.set()
        self.ended.set()


def camera_process_main(argv: list[str] | None = None) -> int:
    """Entry of the camera process: map JSON on the first stdin line, then poses; module output to --fd."""
    parser = argparse.ArgumentParser(description="ForaNav realtime camera process (started by --realtime)")
    parser.add_argument("--fd", type=int, required=True)
    parser.add_argument("--speed", type=float, required=True)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--camera", default="{}")
    args = parser.parse_args(argv)

    stdin = sys.stdin.buffer
    pmap = map_from_dict(json.loads(stdin.readline().decode("utf-8")), source="<realtime>")
    pty_master = os.fdopen(args.fd, "wb", buffering=0)
    camera = VisionCamera(pmap, seed=args.seed, serial_stream=pty_master, **json.loads(args.camera))
    sys.stdout.write("READY\n")
    sys.stdout.flush()
    feed = _PoseFeed(stdin)
    period_s = camera.frame_period_ms / 1000.0 / args.speed
    latency_s = camera.latency_ms / 1000.0 / args.speed
    while not feed.first.wait(0.1) and not feed.ended.is_set():
        pass
    next_frame = time.monotonic()
    while not feed.ended.is_set():
        now = time.monotonic()
        if now < next_frame:
            time.sleep(next_frame - now)
            continue
        t_ms, pose, hidden = feed.latest
        if pose[2] > 0.05:
            frame = camera.render(pose, hidden)  # the image is taken now ...
            time.sleep(max(0.0, next_frame + latency_s - time.monotonic()))
            lines = camera.process(frame.image)  # ... and its lines leave the module a latency later
            camera.score.add(t_ms, _pixels(lines, camera), _truth(frame, pmap))
        else:  # on the ground: an empty frame, not rendered (the module streams from power-on; the app takes
            #    off only once it has heard the camera)
            pty_master.write(("%s\r\n%s\r\n" % (foranav_serial.FRAME_START, foranav_serial.FRAME_STOP)).encode())
        # the next frame is taken when this one is out (period = latency, as on the JeVois, where processing
        # sets the frame rate); a host more than a frame behind drops the frames it missed, as the camera does
        next_frame += period_s
        if time.monotonic() - next_frame > period_s:
            next_frame = time.monotonic()
    sys.stdout.write(json.dumps(camera.report()) + "\n")
    sys.stdout.flush()
    return 0


def _pixels(lines, camera):
    return parse_detections(lines, camera.camera.width, camera.camera.height)


def _truth(frame, pmap):
    return truth_in_frame(frame.trees, pmap.target_species)


if __name__ == "__main__":
    sys.exit(camera_process_main())
