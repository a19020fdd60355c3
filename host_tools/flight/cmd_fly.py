"""Fly a map with the Crazyflie navigation app on the emulated firmware.

The app (crazyflie_app/app/navigation.py) runs on the firmware emulation; a camera on the other end of a real
pseudo-terminal sends it JeVois serial lines. --camera sim (the default) renders each frame from the MAV's
true pose with the plantation simulator and runs the unchanged JeVois module on it (~9 FPS with one frame
of latency, as in the paper; --fps and --latency-ms change that); --camera oracle is an ideal detector
reading the map's ground truth (pixel noise, dropout and latency configurable).

Lockstep (default): one simulated clock, deterministic (same map and seed = same summary and tlog bytes).
--realtime: the camera and the flight run as two processes sharing nothing but the pty, on the wall clock
times --speed; --kill-camera-at S kills the camera process at S simulated seconds (the app holds, then lands).

--plant firmware flies the real Crazyflie firmware's commander, supervisor, PID controller and Kalman
estimator (built from the firmware source by `make firmware-sil`) over a rigid-body quadrotor; the app reads
the Kalman filter's estimate, never the truth. --plant reduced (the default) is the reduced MAV model.

--crtp [HOST:]PORT: the emulated Crazyflie serves CRTP on udp://HOST:PORT (host 127.0.0.1 unless given), so
cflib and cfclient connect to the flight as to a Crazyflie: log and param TOCs, log blocks, params, console,
arming (docs/crtp.md). Lockstep without a client: the same summary and tlog bytes as without --crtp.

Prints the flight summary (a short table, or the JSON object with --json) and writes flight.tlog (MAVLink 2),
trajectory.png and summary.json into --out (default runs/fly-<map>-seed<N>/). Exit status 0 when the flight
completed, 1 when it did not (crash (CRASHED: tumbled or hit the ground faster than 2.5 m/s), watchdog lock, time
limit, camera never heard so never took off, camera link lost in flight, or a camera that reported no tree in a whole
flight over a map with targets: it flew blind), 2 on bad input.

Examples:
  foranav fly --map map1
  foranav fly --map map1 --realtime --speed 4
  foranav fly --map map1 --silence 40:2 --garbage-rate 0.2
  foranav fly --map map1 --camera oracle
  foranav fly --map map1 --app c
  foranav fly --map map1 --plant firmware --positioning flow
  foranav fly --map map2 --camera oracle --dropout 0.3 --json
  foranav fly --map map3 --camera oracle --hide-tree 6 --hide-s 5 --mavlink udpout:127.0.0.1:14550
  foranav fly --map map1 --realtime --crtp 19850     (then connect cfclient to udp://127.0.0.1:19850)
  foranav fly --map map1 --crowns ../shared/data/real/oilpalm_gearth_detectree2/boxes.csv --model real.npz
"""
import argparse
import json
import math
import sys
import time
from pathlib import Path
from typing import TextIO

from crazyflie_app.app.navigation_core import NavigationParams
from host_tools import argtypes, fileio
from host_tools.errors import ForaNavError
from host_tools.flight import camera_factory, run_flight
from host_tools.flight.components import check_crtp_endpoint
from host_tools.flight.realtime import run_realtime
from host_tools.flight.registry import (FLOW_BIAS_RANGE_COUNTS, FLOW_SCALE_RANGE, FPS_RANGE, GROUND_TEXTURE_RANGE,
                                       PIXEL_NOISE_RANGE_PX, PLANTS, POSITIONINGS, WIND_RANGE_MPS2, check_options,
                                       plant_model_options)
from host_tools.flight.vision_camera import model_option
from host_tools.maps import load_map, path_length_m
from host_tools.sim.cli_args import (add_appearance_arguments, appearance_from_args, appearance_spec_from_args,
                                     refuse_appearance_on_photo_map)

CAMERA_CHOICES = ("oracle", "sim")
APP_CHOICES = ("python", "c")
PROGRESS_EVERY_S = 5.0  # wall-clock seconds between progress lines on stderr
LATENCY_MAX_MS = 5000  # app.camLatency is a uint16 and a latency of seconds already means a broken camera


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--map", required=True, help="built-in map name (map1, map2, map3) or map file")
    parser.add_argument("--camera", choices=CAMERA_CHOICES, default="sim",
                        help="sim (default): rendered frames + the JeVois module; oracle: ground-truth detector")
    parser.add_argument("--seed", type=argtypes.seed, default=0, help="seed of every random choice (default 0)")
    parser.add_argument("--out", help="output folder (default runs/fly-<map>-seed<N>/)")
    parser.add_argument("--json", action="store_true", help="print the summary as one JSON object")
    parser.add_argument("--dropout", type=argtypes.probability, default=0.0,
                        help="probability that a detection is lost on the way (default 0)")
    parser.add_argument("--hide-tree", type=int, help="hide this tree id from the camera ...")
    parser.add_argument("--hide-s", type=argtypes.nonnegative, default=5.0,
                        help="... for this many seconds from when the app first approaches it (default 5)")
    parser.add_argument("--pixel-noise", type=argtypes.float_range(*PIXEL_NOISE_RANGE_PX), default=None,
                        help="detection centre noise std (px; default oracle 1.5, sim 0 on top of sensor noise)")
    parser.add_argument("--latency-ms", type=argtypes.int_range(0, LATENCY_MAX_MS), default=None,
                        help="camera latency (ms; default sim: one frame, oracle: 50)")
    parser.add_argument("--fps", type=argtypes.float_range(*FPS_RANGE), default=None,
                        help="camera frame rate, %g-%g (default sim 9, the paper; oracle 10)" % FPS_RANGE)
    parser.add_argument("--silence", action="append", default=[], metavar="START:DURATION",
                        help="fault: nothing reaches the wire from START for DURATION seconds (repeatable)")
    parser.add_argument("--garbage-rate", type=argtypes.probability, default=0.0,
                        help="fault: probability per frame of a garbage line on the wire")
    parser.add_argument("--partial-rate", type=argtypes.probability, default=0.0,
                        help="fault: probability per frame that its bytes arrive in two pieces")
    parser.add_argument("--realtime", action="store_true",
                        help="camera and flight as two processes sharing only the pty, on the wall clock")
    parser.add_argument("--speed", type=argtypes.float_range(0.01, 100.0), default=1.0,
                        help="--realtime: wall-clock speed-up (default 1)")
    parser.add_argument("--kill-camera-at", type=argtypes.nonnegative, default=None, metavar="S",
                        help="--realtime fault: kill the camera process at S simulated seconds")
    parser.add_argument("--cam-offset", type=argtypes.float_range(-1.0, 1.0), nargs=2, metavar=("FWD", "LEFT"),
                        default=None, action=argtypes.Once,
                        help="camera mount offset from the MAV centre, body frame (m); sets the oracle's mount "
                             "and the app's app.camOffsetX/Y")
    parser.add_argument("--positioning", "--estimator", dest="positioning", choices=POSITIONINGS, default="uwb",
                        help="uwb (default): Loco deck + Flow deck; flow: Flow deck alone (the estimate drifts). "
                             "Reduced plant: the estimate's error model; firmware plant: the decks the Kalman "
                             "filter fuses (--estimator is the older name)")
    parser.add_argument("--wind", type=argtypes.float_range(*WIND_RANGE_MPS2), default=0.0,
                        help="wind gust acceleration std (m/s^2)")
    parser.add_argument("--flow-scale", type=argtypes.float_range(*FLOW_SCALE_RANGE), default=None, metavar="K",
                        help="firmware plant: the Flow deck reports K counts per count of motion (1.05: 5 %% long)")
    parser.add_argument("--flow-bias", type=argtypes.float_range(*FLOW_BIAS_RANGE_COUNTS), default=None, metavar="COUNTS",
                        help="firmware plant: counts added to each 10 ms flow frame, x and y")
    parser.add_argument("--ground-texture", type=argtypes.float_range(*GROUND_TEXTURE_RANGE), default=None, metavar="Q",
                        help="firmware plant: ground texture for the Flow deck (1 textured .. 0 featureless; "
                             "below 0.5 counts under-read, below 0.35 frames are lost)")
    parser.add_argument("--mavlink", type=argtypes.mavlink_url, help="also stream the telemetry live, e.g. udpout:127.0.0.1:14550")
    parser.add_argument("--crtp", type=argtypes.udp_endpoint, metavar="[HOST:]PORT", default=None,
                        help="serve CRTP on udp://HOST:PORT for cflib/cfclient (host 127.0.0.1 unless given; "
                             "cflib scans 19850-19859; docs/crtp.md)")
    parser.add_argument("--model", metavar="M", default=None,
                        help="sim: the module runs with this model file (.npz), as the camera does with its "
                             "species parameter set to a model file (default: the map's target species model)")
    add_appearance_arguments(parser)
    parser.add_argument("--app", choices=APP_CHOICES, default="python",
                        help="flight app: python (default) or c (the C core of crazyflie_app/bolt, as on the Bolt)")
    add_plant_argument(parser)


def add_plant_argument(parser: argparse.ArgumentParser) -> None:
    """--plant, as fly, paper-tests, sweep and demo take it."""
    parser.add_argument("--plant", choices=PLANTS, default="reduced",
                        help="reduced (default): the reduced MAV model with a noisy estimate; firmware: the real "
                             "Crazyflie firmware (commander, supervisor, PID controller, Kalman estimator) over a "
                             "rigid-body quadrotor with IMU, flow, ToF and UWB sensors (build it: make firmware-sil)")


def flight_options(args: argparse.Namespace) -> dict:
    """The harness options of parsed fly arguments (ranges are the argument types'; sweeps build their flights
    with it)."""
    options = {"dropout": args.dropout, "model": plant_model_options(args.plant, args.positioning, args.wind),
               "plant": args.plant,
               "silence": [_window(text) for text in args.silence], "garbage_rate": args.garbage_rate,
               "partial_rate": args.partial_rate, "app": args.app}
    if args.hide_tree is not None:
        options.update(hide_tree=args.hide_tree, hide_s=args.hide_s)
    if args.mavlink:
        options["mavlink"] = args.mavlink
    if args.crtp:
        options["crtp"] = args.crtp
    if args.cam_offset is not None:
        options["params"] = {"app.camOffsetX": args.cam_offset[0], "app.camOffsetY": args.cam_offset[1]}
    for option, field_name in FLOW_DRIFT_OPTIONS:
        value = getattr(args, option)
        if value is None:
            continue
        if args.plant != "firmware":
            raise ForaNavError("--%s: models the firmware plant's Flow deck; add --plant firmware"
                               % option.replace("_", "-"))
        options["model"][field_name] = value
    return options


# fly options of the firmware plant's Flow deck drift (the sweeps' drift conditions): (option, config field)
FLOW_DRIFT_OPTIONS = (("flow_scale", "flow_scale"), ("flow_bias", "flow_bias_counts"),
                      ("ground_texture", "ground_texture"))


def _window(text: str) -> tuple[float, float]:
    try:
        start, duration = (float(part) for part in text.split(":"))
    except ValueError:
        raise ForaNavError("--silence: expected START:DURATION in seconds, got %r" % text)
    if not (math.isfinite(start) and math.isfinite(duration)) or start < 0 or duration <= 0:
        raise ForaNavError("--silence: START must be >= 0 and DURATION > 0, got %r" % text)
    return (start, duration)


def camera_kwargs(args: argparse.Namespace) -> dict:
    """The camera factory's keyword arguments of parsed fly arguments, photo crowns and model included (sweeps
    build their flights with it; the species check against one map is run()'s)."""
    kwargs = {}
    if args.fps is not None:
        kwargs["frame_period_ms"] = int(round(1000.0 / args.fps))
    if args.pixel_noise is not None:
        kwargs["pixel_noise_px"] = args.pixel_noise
    if args.latency_ms is not None:
        kwargs["latency_ms"] = args.latency_ms
    if args.cam_offset is not None:
        kwargs["mount_offset"] = tuple(args.cam_offset)
    spec = appearance_spec_from_args(args)
    if not spec.default:
        kwargs["appearance"] = spec.to_dict()
    if args.model is not None:
        kwargs["model"] = model_option(args.model)
    return kwargs


def print_table(summary: dict, out: TextIO | None = None) -> None:
    out = out or sys.stdout
    mean = summary["mean_deviation_m"]
    ci = summary["ci95_m"]
    print("map %s, seed %d: %s" % (summary["map"], summary["seed"],
                                   "SUCCESS" if summary["success"] else
                                   ("completed" if summary["completed"] else
                                    "NOT STARTED: camera never heard, did not take off"
                                    if summary.get("camera_never_heard") else
                                    "NOT COMPLETED: the camera reported no tree in the whole flight"
                                    if summary.get("camera_blind") else "NOT COMPLETED")), file=out)
    print("  %-6s %-14s %s" % ("tree", "deviation (m)", "t (s)"), file=out)
    for r in summary["reached"]:
        print("  %-6s %-14.3f %.1f" % (r["id"] if r["id"] is not None else "-", r["deviation_m"], r["t_s"]),
              file=out)
    print("  targets %s; missed %s; non-targets visited %s" % (
        summary["targets"], summary["missed_targets"] or "none", summary["non_targets_visited"] or "none"),
        file=out)
    print("  mean deviation %s m (95%% CI +/- %s); mission %.1f s; recoveries %d; watchdog events %d" % (
        "-" if mean is None else "%.3f" % mean, "-" if ci is None else "%.3f" % ci, summary["mission_time_s"],
        summary["recoveries"], summary["watchdog_events"]), file=out)
    error = summary.get("estimate_error")
    if error:
        print("  %s plant: estimate error position %.3f / %.3f / %.3f m, yaw %.2f / %.2f / %.2f deg "
              "(mean / p95 / max)" % ((summary["plant"],) + tuple(error["position_m"].values())
                                      + tuple(error["yaw_deg"].values())), file=out)
    if summary.get("crashed"):
        print("  CRASHED: %s" % summary["crash"], file=out)
    vision = summary.get("vision")
    if vision:
        fps = vision.get("effective_fps", vision["fps"])  # realtime: the frames that actually arrived
        print("  camera %.1f fps: %s detections per frame; %d true, %d false, %d missed (recall %s, precision %s)"
              % (fps, vision["detections_per_frame"], vision["true_positives"], vision["false_positives"],
                 vision["missed"], vision["recall"], vision["precision"]), file=out)
        if vision.get("photo_species"):
            print("  crowns from photos: %s" % ", ".join(vision["photo_species"]), file=out)
    if summary.get("link_losses") or summary.get("link_aborted"):
        print("  camera link lost %d time(s)%s" % (summary["link_losses"], "; LANDED: link dead"
                                                    if summary["link_aborted"] else ""), file=out)
    if summary.get("tlog"):
        print("  tlog %s\n  plot %s" % (summary["tlog"], summary["plot"]), file=out)


def _check_flyable(pmap, max_time_s):
    """Refuse a map whose path alone takes longer than a flight may last (it could only end unfinished)."""
    path_s = path_length_m(pmap.waypoints) / NavigationParams.cruise_speed
    if path_s > max_time_s:
        raise ForaNavError("%s: waypoints: the path F is %.0f m long, %.0f s at the app's cruise speed %g m/s; "
                           "a flight ends at %.0f s" % (pmap.source, path_length_m(pmap.waypoints), path_s,
                                                         NavigationParams.cruise_speed, max_time_s))


def run(args: argparse.Namespace) -> int:
    factory = camera_factory(args.camera)
    options = flight_options(args)
    if args.kill_camera_at is not None and not args.realtime:
        raise ForaNavError("--kill-camera-at: only with --realtime (the camera is a process there)")
    if args.realtime and args.camera != "sim":
        raise ForaNavError("--realtime: only with --camera sim")
    out = Path(args.out) if args.out else Path("runs") / ("fly-%s-seed%d" % (Path(args.map).stem, args.seed))
    fileio.check_output_dir(out, "--out")
    if args.crtp:
        check_crtp_endpoint(args.crtp)
    pmap = load_map(args.map)
    _check_flyable(pmap, check_options(options)["max_time_s"])
    if args.hide_tree is not None and args.hide_tree not in {tree.id for tree in pmap.trees}:
        raise ForaNavError("--hide-tree: map %s has no tree %d (its trees: %s)" % (
            args.map, args.hide_tree, ", ".join(str(tree.id) for tree in pmap.trees)))
    if args.hide_tree is not None and pmap.photo is not None:
        raise ForaNavError("--hide-tree: map %s is a photo map: a photographed crown cannot be taken away "
                           "(there is no ground under it)" % args.map)
    spec, _ = appearance_from_args(args, {t.species for t in pmap.trees}, "map %s" % args.map)
    refuse_appearance_on_photo_map(spec, pmap, args.map)
    if (not spec.default or args.model is not None) and args.camera != "sim":
        raise ForaNavError("--crowns/--ground/--model: only with --camera sim (the oracle sees no pixels)")
    kwargs = camera_kwargs(args)
    if args.realtime:
        camera = None
    else:
        try:
            camera = factory(pmap, seed=args.seed, **kwargs)
        except ValueError as err:
            raise ForaNavError("camera: %s" % err)

    if args.crtp:
        print("  CRTP: the Crazyflie answers on udp://%s (cflib, cfclient)" % args.crtp, file=sys.stderr)
    last_print = [time.monotonic()]

    def progress(t_s, phase):
        # only slow flights (a camera in the loop) need a sign of life; an oracle flight takes ~1 s
        if not args.json and time.monotonic() - last_print[0] >= PROGRESS_EVERY_S:
            last_print[0] = time.monotonic()
            print("  t = %5.0f s  %s" % (t_s, phase), file=sys.stderr)

    if args.realtime:
        summary = run_realtime(pmap, seed=args.seed, speed=args.speed, out_dir=out, options=options,
                               kill_camera_at_s=args.kill_camera_at, camera_kwargs=kwargs, progress=progress)
    else:
        summary = run_flight(pmap, camera, seed=args.seed, out_dir=out, options=options, progress=progress)
    cpu = summary.pop("cpu_s", None)
    if args.json:
        print(json.dumps(summary, indent=2))
    else:
        print_table(summary)
        if cpu is not None:
            print("  cpu %.2f s" % cpu)
    return 0 if summary["completed"] else 1
