"""The flight harness: the app on the emulated Crazyflie, a camera on the other end of a real pty, faults,
telemetry, scoring. ``run_flight`` is the interface the flight commands (fly, paper-tests, replay) build on.

    run_flight(pmap, camera, *, seed=0, out_dir=None, options=None, progress=None) -> summary dict

``camera`` is any object with ``frame_period_ms``, ``latency_ms`` and
``capture(t_ms, true_pose, hidden=frozenset()) -> list[str]`` (the serial lines of one frame, without line
ends; the harness adds CRLF and delivers them ``latency_ms`` later). ``true_pose`` is the MAV's true
(x, y, z, yaw_deg, roll_deg, pitch_deg: FlightRig.camera_pose; roll and pitch are 0 on the reduced plant);
the camera applies its own mount offset (optional attribute ``mount_offset`` = (forward, left) m, used for
scoring; default: the app's camOffset params). ``hidden`` is the set of tree ids the camera
must not see at that moment (fault injection).

Simulated time only: the harness runs the firmware scheduler tick by tick, writes each frame's bytes into
the pty master at delivery time and, in lockstep mode, waits until they are readable on the slave side
before the clock moves on, so the same map and seed give the same summary and the same tlog bytes.

``options`` (all optional; unknown keys are an error):

    dropout        probability that the harness drops a detection line (after the camera's own dropout)
    hide_tree      tree id to hide from the camera ...
    hide_s         ... for this many seconds (default 5) ...
    hide_at_s      ... starting at this time, or (None) when the app first approaches that tree
    silence        [(start_s, duration_s), ...]: windows in which nothing reaches the wire
    garbage_rate   probability per frame of injecting a non-detection line (console replies, noise,
                   malformed and overlong lines, truncated detections)
    partial_rate   probability per frame that its bytes are split into two writes 3 ms apart
    lockstep       wait for the bytes to cross the pty (default True; False = no waiting, not reproducible)
    max_time_s     simulated-time limit (default 900)
    model          dict of MavModelConfig fields (estimator, noise, bias, wind_gust_mps2, ...)
    params         dict of app parameters to set before flight, by 'group.name' ('app.settleRadius': 5)
    start          (x, y) take-off point (default: the first waypoint)
    mavlink        live MAVLink output URL (e.g. 'udpout:127.0.0.1:14550'); needs out_dir (it tees the tlog)
    app            the flight app: 'python' (crazyflie_app/app/navigation.py, default) or 'c' (the C core of
                   crazyflie_app/bolt, crazyflie_app/bolt/c_app.py); both read the camera through the emulated UART2
    decks          decks present (default ('bcFlow2', 'bcLoco'))
    app            the flight app under test, by registered name (default 'python'; see register_app)
    plant          'reduced' (default: the reduced MAV model) or 'firmware' (the real firmware, docs/firmware-plant.md)
    profile        count the CPU time of every task: the summary gets "stage_cpu_s" (host_tools.flight.stages)
    crtp           'HOST:PORT': the emulated Crazyflie serves CRTP there (cflib's udp:// link; port 0: any
                   free port, see ``Flight.crtp.uri``); docs/crtp.md. Without a client the flight's outputs
                   are the same bytes as without it

``progress(t_s, phase_name)`` is called every simulated second.

A flight is composed, not subclassed: ``FlightRig`` (emulated Crazyflie + pty wire + the app, built by a
registered app factory: ``register_app``), ``FlightRecord`` (taps: reached trees, trajectory, tlog),
``HideFault``, ``CameraFeed`` (the lockstep world task: frames, wire faults, latency, via ``Delivery``) and
``Monitor`` (trajectory, telemetry, progress, stop after landing), assembled by ``Flight``; ``summarize``
scores it. ``realtime`` and ``replay`` build a ``Flight`` and pass their own world task. ``fly(...)`` is the
harness as a picklable function of plain data, for sweeps. The components live in ``flight.components``, the
camera and app registries and the options in ``flight.registry``, the scoring in ``flight.summary``; this
module re-exports their public names.
"""
import os
import time
from collections.abc import Callable, Iterator
from pathlib import Path

from host_tools import fileio
from host_tools.errors import ForaNavError
from host_tools.flight.components import (  # noqa: F401  (the harness's public names)
    AFTER_LANDING_MS, GARBAGE_LINES, HEARTBEAT_PERIOD_MS, MAV_STATE_ACTIVE, MAV_STATE_CRITICAL, MAV_STATE_EMERGENCY,
    MAV_STATE_STANDBY, MONITOR_PERIOD_MS, MONITOR_TASK_PRI, PARTIAL_SPLIT_DELAY_MS, PROGRESS_PERIOD_MS,
    REACHED_MATCH_RADIUS_M, TELEMETRY_PERIOD_MS, TRAJECTORY_PERIOD_MS, WORLD_TASK_PRI, CameraFeed, Delivery,
    FlightRecord, FlightRig, HideFault, Monitor, open_crtp, open_tlog)
from host_tools.flight.registry import (  # noqa: F401
    CAMERA_MODULES, DEFAULT_OPTIONS, Camera, app_factory, app_names, camera_factory, check_options, register_app,
    register_camera)
from host_tools.flight.stages import stage_split
from host_tools.flight.summary import summarize
from host_tools.maps import PlantationMap, map_from_dict

Progress = Callable[[float, str], None]  # progress(t_s, phase name), about once a simulated second
STOP_CHECK_MS = 100  # Flight.run(stop=...): how often the stop condition is asked


class Flight:
    """One flight, composed: rig + record (+ tlog) + hide fault + monitor; the world task is pluggable.

    ``world_task`` (a generator run at WORLD_TASK_PRI) defaults to the camera feed (CameraFeed); realtime
    and replay pass their own (wall-clock pose feed, clip playback). Everything a flight owns lives here, so
    nothing is left behind once it is closed.
    """

    def __init__(self, pmap: PlantationMap, camera: Camera, *, seed: int = 0, out_dir: str | os.PathLike | None = None,
                 options: dict | None = None, progress: Progress | None = None, stop_after_landing: bool = True):
        self.options = check_options(options)
        self.pmap, self.camera, self.seed, self.progress = pmap, camera, seed, progress
        self.out_dir = Path(out_dir) if out_dir is not None else None
        self.rig = FlightRig(pmap, camera, seed, self.options)
        try:
            self.crtp = open_crtp(self.rig.cf, self.options)  # before the tlog: a port in use writes nothing
        except BaseException:
            self.rig.close()
            raise
        try:
            tlog = open_tlog(self.out_dir, self.options)
        except BaseException:
            if self.crtp is not None:
                self.crtp.close()
            self.rig.close()
            raise
        self.record = FlightRecord(pmap, self.rig, tlog)
        self.hide = HideFault(pmap, self.rig, self.options)
        self.feed = CameraFeed(camera, self.rig, self.hide, self.options, seed)
        self.monitor = Monitor(self.rig, self.record, self.hide, progress, stop_after_landing=stop_after_landing)
        self.camera_killed_ms = None  # set by realtime's --kill-camera-at (the plot marks it)
        self.cpu_s = 0.0

    # what the plot and the summary read
    reached = property(lambda self: self.record.reached)
    trajectory = property(lambda self: self.record.trajectory)
    detections = property(lambda self: self.record.detections)
    app_trees = property(lambda self: self.record.app_trees)

    def run(self, world_task: Iterator | None = None, stop: Callable[[], bool] | None = None) -> None:
        """Run the flight to its end (the monitor stops it after landing) or its time limit; with ``stop``,
        also until ``stop()`` says so (asked every STOP_CHECK_MS of simulated time: a served drone's signals)."""
        cf = self.rig.cf
        cf.x_task_create(world_task if world_task is not None else self.feed.task(), "HARNESS_CAMERA",
                         WORLD_TASK_PRI)
        self.rig.app.start()
        cf.x_task_create(self.monitor.task(), "HARNESS_MONITOR", MONITOR_TASK_PRI)
        if self.options["profile"]:
            cf.scheduler.profile()
        if self.crtp is not None:
            self.crtp.start()  # the last task: it adds nothing the others see unless a client speaks
        cpu0 = time.process_time()
        end = int(float(self.options["max_time_s"]) * 1000) + 1
        if stop is None:
            cf.run_until(end)
        else:
            while (cf.x_task_get_tick_count() < end and not stop()
                   and cf.run_until(min(end, cf.x_task_get_tick_count() + STOP_CHECK_MS))):
                pass
        self.cpu_s = time.process_time() - cpu0

    def wait_wall(self, seconds: float) -> None:
        """Let ``seconds`` of wall time pass (the realtime pacer): serving CRTP requests meanwhile."""
        if self.crtp is not None:
            self.crtp.serve_for(seconds)
        else:
            time.sleep(seconds)

    def close(self, keep: bool = True) -> None:
        if self.crtp is not None:
            self.crtp.close()
        self.rig.close()
        self.record.close(keep=keep)

    def summary(self) -> dict:
        return summarize(self)

    def write_outputs(self, summary: dict) -> None:
        """flight.tlog is already there; add the camera's detections.csv and summary.json, then trajectory.png
        last: the record of the flight is on disk before the slowest output is drawn (and whatever the plot does)."""
        from host_tools.flight.plot import plot_trajectory  # matplotlib: loaded only by a flight that draws

        summary["tlog"] = str(self.out_dir / "flight.tlog")
        summary["plot"] = str(self.out_dir / "trajectory.png")
        summary["summary"] = str(self.out_dir / "summary.json")
        if hasattr(self.camera, "frames_csv"):
            summary["detections_csv"] = str(self.out_dir / "detections.csv")
            fileio.write_text(summary["detections_csv"], self.camera.frames_csv())
        fileio.write_json(summary["summary"], {k: v for k, v in summary.items() if k != "cpu_s"})
        plot_trajectory(self, summary["plot"])


def run_flight(pmap: PlantationMap, camera: Camera, *, seed: int = 0, out_dir: str | os.PathLike | None = None,
               options: dict | None = None, progress: Progress | None = None) -> dict:
    """Fly ``pmap`` with the app against ``camera``; return the summary dict (see module docstring).

    With ``out_dir``, writes flight.tlog, trajectory.png and summary.json there and adds their paths.
    """
    flight = Flight(pmap, camera, seed=seed, out_dir=out_dir, options=options, progress=progress)
    try:
        flight.run()
    except BaseException:
        flight.close(keep=False)
        raise
    flight.close(keep=True)
    summary = flight.summary()
    if hasattr(camera, "report"):  # a camera that scores its own detections (vision_camera): per-frame figures
        summary["vision"] = camera.report()
    summary["cpu_s"] = round(flight.cpu_s, 2)  # not part of the reproducible record
    if flight.options["profile"]:
        summary["stage_cpu_s"] = stage_split(flight.rig.cf.scheduler.task_cpu_s, getattr(camera, "stage_cpu_s", None))
    if flight.out_dir is not None:
        flight.write_outputs(summary)
    return summary


def fly(map_data: dict, *, camera: str = "oracle", camera_kwargs: dict | None = None, app: str = "python",
        options: dict | None = None, seed: int = 0) -> dict:
    """The harness as a function: (map, camera, app, options, seed) -> summary, from plain data only.

    ``map_data`` is a map JSON object (host_tools.maps), ``camera`` a registered camera name built with
    ``camera_kwargs``, ``app`` a registered app name. Picklable (a Dask task ships it by reference and its
    arguments by value); every object of the flight is built here and dropped on return, so a worker can
    fly thousands in a row. Same arguments, same summary (apart from ``cpu_s``).
    """
    pmap = map_from_dict(map_data, source=map_data.get("name", "<map>"))
    try:
        cam = camera_factory(camera)(pmap, seed=seed, **(camera_kwargs or {}))
    except ValueError as err:
        raise ForaNavError("camera: %s" % err)
    merged = dict(options or {})
    merged["app"] = app
    try:
        return run_flight(pmap, cam, seed=seed, options=merged)
    finally:
        close = getattr(cam, "close", None)
        if close is not None:
            close()
